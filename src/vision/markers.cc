#include "kincal/vision/markers.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numeric>
#include <opencv2/imgproc.hpp>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

namespace kincal::vision {

bool DetectorOptions::IsValid(std::string* error) const {
  if (threshold > 255 || min_area_px < 1 || max_area_px < min_area_px || !(min_circularity > 0) ||
      min_circularity > 1 || !(min_fill > 0) || min_fill > 1 || min_contrast < 0 ||
      min_contrast > 255 || background_tile_px < 8) {
    *error =
        "detector: threshold <= 255, 1 <= min_area <= max_area, circularity and fill in (0, 1], "
        "min_contrast in [0, 255], background_tile_px >= 8";
    return false;
  }
  return true;
}

namespace {

// The Otsu histogram samples every kOtsuStride-th pixel of every kOtsuStride-th row.
constexpr int kOtsuStride = 2;
// Blobs smaller than this are noise, dropped without a rejection note.
constexpr int64_t kMinReportedArea = 4;
// The centroid window: the blob's box grown by this many pixels, which holds the edge
// blur; the background is the median of its border.
constexpr int kCentroidMarginPx = 2;
// The marker level: this quantile of the foreground pixels (the darkest quarter's edge).
constexpr size_t kForegroundQuantileDivisor = 4;
// Moment floors, and the variance a pixel adds to a pixelated disk's moments (1/12 per
// axis).
constexpr double kMomentFloor = 1e-12;
constexpr double kPixelVariance = 1.0 / 12.0;
// A target seen more obliquely than about 78 deg (singular value ratio below this) is not
// identified.
constexpr double kMinAffineSingularRatio = 0.2;

// One connected component, accumulated from its horizontal runs.
struct Blob {
  int parent;
  int64_t area = 0;
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
};

int Find(std::vector<Blob>& b, int i) {
  while (b[static_cast<size_t>(i)].parent != i) {
    b[static_cast<size_t>(i)].parent =
        b[static_cast<size_t>(b[static_cast<size_t>(i)].parent)].parent;
    i = b[static_cast<size_t>(i)].parent;
  }
  return i;
}

struct Run {
  int x0, x1, blob;
};

// Regions at least this large (pixels) are flattened (DetectorOptions::flatten_background).
constexpr int kFlattenMinArea = 320 * 240;
// The floor's level in a tile: this quantile of its (sampled) pixels, from the bright end
// for dark markers.
constexpr double kBackgroundQuantile = 0.9;
// After flattening, the floor sits at this grey level (headroom for bright markers).
constexpr double kFlatLevel = 200.0;

// The floor's brightness, interpolated over the view from per-tile quantiles, divided out:
// out = kFlatLevel * view / background (dark markers) or, for bright markers on a dark
// floor, view - background + a fixed offset (a dark floor's level is mostly offset).
void FlattenBackground(const cv::Mat& view, bool dark_on_light, int tile, cv::Mat* out) {
  const int tx = (view.cols + tile - 1) / tile, ty = (view.rows + tile - 1) / tile;
  thread_local cv::Mat levels, spread, background;
  thread_local std::vector<uint8_t> samples;
  levels.create(ty, tx, CV_32F);
  for (int j = 0; j < ty; ++j) {
    for (int i = 0; i < tx; ++i) {
      samples.clear();
      const int y1 = std::min(view.rows, (j + 1) * tile), x1 = std::min(view.cols, (i + 1) * tile);
      for (int y = j * tile; y < y1; y += 2) {
        const uint8_t* row = view.ptr<uint8_t>(y);
        for (int x = i * tile; x < x1; x += 2) samples.push_back(row[x]);
      }
      const double q = dark_on_light ? kBackgroundQuantile : 1.0 - kBackgroundQuantile;
      const auto k =
          samples.begin() + static_cast<long>(q * static_cast<double>(samples.size() - 1));
      std::nth_element(samples.begin(), k, samples.end());
      levels.at<float>(j, i) = static_cast<float>(*k);
    }
  }
  // A marker (or a plate) filling a tile: the brightest (darkest) neighbour is the floor.
  if (dark_on_light) {
    cv::dilate(levels, spread, cv::Mat());
  } else {
    cv::erode(levels, spread, cv::Mat());
  }
  cv::resize(spread, background, view.size(), 0, 0, cv::INTER_LINEAR);
  out->create(view.size(), CV_8UC1);
  for (int y = 0; y < view.rows; ++y) {
    const uint8_t* in = view.ptr<uint8_t>(y);
    const float* b = background.ptr<float>(y);
    uint8_t* o = out->ptr<uint8_t>(y);
    for (int x = 0; x < view.cols; ++x) {
      o[x] = dark_on_light ? cv::saturate_cast<uint8_t>(kFlatLevel * in[x] / std::max(b[x], 1.0f))
                           : cv::saturate_cast<uint8_t>(in[x] - b[x] + (255.0 - kFlatLevel));
    }
  }
}

// The threshold of a flattened view: half way between the floor (the median) and the
// darkest (brightest) kMarkerFraction of the pixels; -1 when they differ by less than twice
// `min_contrast` (nothing but floor in view). Otsu would split the floor's own noise here:
// markers are a tiny fraction of a whole frame.
constexpr double kMarkerFraction = 1e-4;
int FlatThreshold(const cv::Mat& flat, bool dark_on_light, int min_contrast) {
  std::array<int64_t, 256> hist{};
  int64_t n = 0;
  for (int y = 0; y < flat.rows; y += kOtsuStride) {
    const uint8_t* row = flat.ptr<uint8_t>(y);
    for (int x = 0; x < flat.cols; x += kOtsuStride) {
      ++hist[row[x]];
      ++n;
    }
  }
  auto quantile = [&](double q) {
    const auto target = static_cast<int64_t>(q * static_cast<double>(n));
    int64_t c = 0;
    for (int v = 0; v < 256; ++v) {
      c += hist[static_cast<size_t>(v)];
      if (c > target) return v;
    }
    return 255;
  };
  const int floor = quantile(0.5);
  const int marker = quantile(dark_on_light ? kMarkerFraction : 1.0 - kMarkerFraction);
  if (std::abs(floor - marker) < 2 * min_contrast) return -1;
  return (floor + marker) / 2;
}

// Otsu threshold from a histogram of every other pixel of every other row; -1 when the
// two classes it separates differ by less than `min_contrast` grey levels (an empty,
// noisy view: thresholding it would only produce noise blobs).
int OtsuThreshold(const cv::Mat& view, int min_contrast) {
  std::array<int64_t, 256> hist{};
  int64_t n = 0;
  for (int y = 0; y < view.rows; y += kOtsuStride) {
    const uint8_t* row = view.ptr<uint8_t>(y);
    for (int x = 0; x < view.cols; x += kOtsuStride) {
      ++hist[row[x]];
      ++n;
    }
  }
  double sum = 0;
  for (int i = 0; i < 256; ++i)
    sum += static_cast<double>(i) * static_cast<double>(hist[static_cast<size_t>(i)]);
  double sum_b = 0, best = -1;
  int64_t w_b = 0;
  int thr = 128;
  double contrast = 0.0;
  for (int t = 0; t < 256; ++t) {
    w_b += hist[static_cast<size_t>(t)];
    if (w_b == 0) continue;
    const int64_t w_f = n - w_b;
    if (w_f == 0) break;
    sum_b += static_cast<double>(t) * static_cast<double>(hist[static_cast<size_t>(t)]);
    const double m_b = sum_b / static_cast<double>(w_b),
                 m_f = (sum - sum_b) / static_cast<double>(w_f);
    const double between =
        static_cast<double>(w_b) * static_cast<double>(w_f) * (m_b - m_f) * (m_b - m_f);
    if (between > best) {
      best = between;
      thr = t;
      contrast = m_f - m_b;
    }
  }
  return contrast >= min_contrast ? thr : -1;
}

// Foreground test: dark-on-light markers are p <= thr, light-on-dark p > thr.
template <bool kDark>
inline bool Fg(uint8_t p, int thr) {
  return kDark ? p <= thr : p > thr;
}

// First x >= x in [x, w) that is foreground (w if none); skips 16 background pixels at a
// time with SSE2 where available.
template <bool kDark>
inline int NextFg(const uint8_t* row, int x, int w, int thr) {
#ifdef __SSE2__
  const __m128i t = _mm_set1_epi8(static_cast<char>(kDark ? thr : std::min(thr + 1, 255)));
  while (x + 16 <= w) {
    const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
    const __m128i hit =
        kDark ? _mm_cmpeq_epi8(_mm_min_epu8(v, t), v) : _mm_cmpeq_epi8(_mm_max_epu8(v, t), v);
    if (_mm_movemask_epi8(hit) != 0) break;
    x += 16;
  }
#endif
  while (x < w && !Fg<kDark>(row[x], thr)) ++x;
  return x;
}

template <bool kDark>
void LabelRuns(const cv::Mat& view, int thr, std::vector<Blob>* blobs) {
  std::vector<Run> prev, cur;
  for (int y = 0; y < view.rows; ++y) {
    const uint8_t* row = view.ptr<uint8_t>(y);
    cur.clear();
    int x = 0;
    const int w = view.cols;
    size_t j = 0;  // first run of the previous row that may touch
    while ((x = NextFg<kDark>(row, x, w, thr)) < w) {
      const int x0 = x;
      while (x < w && Fg<kDark>(row[x], thr)) ++x;
      const int x1 = x - 1;
      int blob = -1;
      while (j < prev.size() && prev[j].x1 < x0 - 1) ++j;
      for (size_t k = j; k < prev.size() && prev[k].x0 <= x1 + 1; ++k) {
        const int r = Find(*blobs, prev[k].blob);
        if (blob < 0) {
          blob = r;
        } else if (r != blob) {
          (*blobs)[static_cast<size_t>(r)].parent = blob;
        }
      }
      if (blob < 0) {
        blob = static_cast<int>(blobs->size());
        blobs->push_back(Blob{blob});
      }
      Blob& b = (*blobs)[static_cast<size_t>(blob)];
      const double n = x1 - x0 + 1;
      const double s1 = n * (x0 + x1) * 0.5;
      auto s2 = [](double k) { return k * (k + 1) * (2 * k + 1) / 6.0; };
      b.area += x1 - x0 + 1;
      b.sx += s1;
      b.sy += n * y;
      b.sxx += s2(x1) - s2(x0 - 1);
      b.syy += n * y * y;
      b.sxy += s1 * y;
      b.x0 = std::min(b.x0, x0);
      b.x1 = std::max(b.x1, x1);
      b.y0 = std::min(b.y0, y);
      b.y1 = std::max(b.y1, y);
      cur.push_back({x0, x1, blob});
    }
    std::swap(prev, cur);
  }
  // Merge the statistics of every blob into its root.
  for (size_t i = 0; i < blobs->size(); ++i) {
    const int r = Find(*blobs, static_cast<int>(i));
    if (r == static_cast<int>(i)) continue;
    Blob& a = (*blobs)[static_cast<size_t>(r)];
    Blob& b = (*blobs)[i];
    a.area += b.area;
    a.sx += b.sx;
    a.sy += b.sy;
    a.sxx += b.sxx;
    a.syy += b.syy;
    a.sxy += b.sxy;
    a.x0 = std::min(a.x0, b.x0);
    a.x1 = std::max(a.x1, b.x1);
    a.y0 = std::min(a.y0, b.y0);
    a.y1 = std::max(a.y1, b.y1);
    b.area = 0;
  }
}

// Intensity-weighted centre of blob `b` over its box grown by kCentroidMarginPx. The
// marker level is the darkest (brightest) quarter of the foreground pixels inside the
// box; the background level is the median of the window's border. A pixel's weight is its depth
// below the background in units of the contrast, capped at 1 but not floored at 0: noise on the
// background pixels then averages out, where clipping it at 0 would pull the centre
// towards the middle of the window, by up to a fifth of the noise's own scatter
// (Markers.HeavyNoiseScattersTheCentreWithoutBiasingIt). False without contrast.
bool WeightedCentre(const cv::Mat& view, const Blob& b, int thr, bool dark_on_light,
                    Eigen::Vector2d* centre, double* weight) {
  const int g = kCentroidMarginPx;
  const int x0 = std::max(0, b.x0 - g), y0 = std::max(0, b.y0 - g);
  const int x1 = std::min(view.cols - 1, b.x1 + g), y1 = std::min(view.rows - 1, b.y1 + g);
  thread_local std::vector<double> border, inner;
  border.clear();
  inner.clear();
  for (int x = x0; x <= x1; ++x) {
    border.push_back(view.at<uint8_t>(y0, x));
    border.push_back(view.at<uint8_t>(y1, x));
  }
  for (int y = y0 + 1; y < y1; ++y) {
    border.push_back(view.at<uint8_t>(y, x0));
    border.push_back(view.at<uint8_t>(y, x1));
  }
  const auto mid = border.begin() + static_cast<long>(border.size() / 2);
  std::nth_element(border.begin(), mid, border.end());
  const double bg = *mid;
  for (int y = b.y0; y <= b.y1; ++y) {
    const uint8_t* row = view.ptr<uint8_t>(y);
    for (int x = b.x0; x <= b.x1; ++x) {
      if (dark_on_light ? row[x] <= thr : row[x] > thr) inner.push_back(row[x]);
    }
  }
  if (inner.empty()) return false;
  const auto q = inner.begin() + static_cast<long>(inner.size() / kForegroundQuantileDivisor);
  if (dark_on_light) {
    std::nth_element(inner.begin(), q, inner.end());
  } else {
    std::nth_element(inner.begin(), q, inner.end(), std::greater<double>());
  }
  const double span = bg - *q;
  if (std::abs(span) < 1e-9 || (dark_on_light ? span < 0 : span > 0)) return false;
  double sw = 0, su = 0, sv = 0;
  const double inv = 1.0 / span;
  for (int y = y0; y <= y1; ++y) {
    const uint8_t* row = view.ptr<uint8_t>(y);
    for (int x = x0; x <= x1; ++x) {
      const double w = std::min((bg - row[x]) * inv, 1.0);
      sw += w;
      su += w * x;
      sv += w * y;
    }
  }
  if (!(sw > 0.0)) return false;
  *centre = Eigen::Vector2d(su / sw, sv / sw);
  *weight = sw;
  return true;
}

}  // namespace

std::vector<Marker> DetectMarkers(const cv::Mat& grey, const DetectorOptions& opt, cv::Rect roi,
                                  std::vector<Rejected>* rejected) {
  CV_Assert(grey.type() == CV_8UC1);
  if (roi.area() == 0) roi = cv::Rect(0, 0, grey.cols, grey.rows);
  roi &= cv::Rect(0, 0, grey.cols, grey.rows);
  std::vector<Marker> out;
  if (roi.area() == 0) return out;
  cv::Mat view = grey(roi);
  int thr = opt.threshold;
  if (opt.flatten_background && opt.threshold < 0 && roi.area() >= kFlattenMinArea) {
    thread_local cv::Mat flat;
    FlattenBackground(view, opt.dark_on_light, opt.background_tile_px, &flat);
    view = flat;
    thr = FlatThreshold(view, opt.dark_on_light, opt.min_contrast);
  } else if (thr < 0) {
    thr = OtsuThreshold(view, opt.min_contrast);
  }
  if (thr < 0) return out;
  thread_local std::vector<Blob> blobs;
  blobs.clear();
  if (opt.dark_on_light) {
    LabelRuns<true>(view, thr, &blobs);
  } else {
    LabelRuns<false>(view, thr, &blobs);
  }
  for (size_t k = 0; k < blobs.size(); ++k) {
    const Blob& b = blobs[k];
    if (b.parent != static_cast<int>(k) || b.area == 0) continue;
    const double area = static_cast<double>(b.area);
    const double mx = b.sx / area, my = b.sy / area;
    const Eigen::Vector2d c0(mx + roi.x, my + roi.y);
    auto reject = [&](const std::string& why) {
      if (rejected != nullptr) rejected->push_back({c0, why});
    };
    if (b.area < opt.min_area_px) {
      if (b.area >= kMinReportedArea)
        reject("area " + std::to_string(b.area) + " < " + std::to_string(opt.min_area_px));
      continue;
    }
    if (b.area > opt.max_area_px) {
      reject("area " + std::to_string(b.area) + " > " + std::to_string(opt.max_area_px));
      continue;
    }
    const int bx = b.x0, by = b.y0, bw = b.x1 - b.x0 + 1, bh = b.y1 - b.y0 + 1;
    if (bx == 0 || by == 0 || bx + bw >= view.cols || by + bh >= view.rows) {
      reject("touches the search border");
      continue;
    }
    // Second moments of the binary blob: ellipse axes.
    const double sxx = b.sxx / area - mx * mx, syy = b.syy / area - my * my,
                 sxy = b.sxy / area - mx * my;
    const double tr = sxx + syy, det = sxx * syy - sxy * sxy;
    const double disc = std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
    const double l1 = std::max(0.5 * tr + disc, kMomentFloor);
    const double l2 = std::max(0.5 * tr - disc, kMomentFloor);
    const double circ = std::sqrt(l2 / l1);
    // A pixelated disk's moments include each pixel's own spread (1/12 per axis).
    const double ellipse_area = 4.0 * M_PI *
                                std::sqrt(std::max(l1 - kPixelVariance, kMomentFloor) *
                                          std::max(l2 - kPixelVariance, kMomentFloor));
    const double fill = area / ellipse_area;
    if (circ < opt.min_circularity) {
      reject("circularity " + std::to_string(circ).substr(0, 4));
      continue;
    }
    if (fill < opt.min_fill || fill > 1.0 / opt.min_fill) {
      reject("fill ratio " + std::to_string(fill).substr(0, 4));
      continue;
    }
    Eigen::Vector2d centre;
    double weight = 0.0;
    if (!WeightedCentre(view, b, thr, opt.dark_on_light, &centre, &weight)) {
      reject("no contrast");
      continue;
    }
    Marker m;
    m.centre_px = centre + Eigen::Vector2d(roi.x, roi.y);
    m.area_px = weight;
    m.diameter_px = 2.0 * std::sqrt(weight / M_PI);
    out.push_back(m);
  }
  return out;
}

bool IdentifyTarget(const CameraModel& cam, const TargetLayout& layout,
                    std::vector<Marker>* markers, double max_rms) {
  const size_t m = layout.markers.size();
  const size_t n = markers->size();
  if (n < m || n > 12) return false;
  std::vector<Eigen::Vector2d> norm;
  for (const auto& mk : *markers) norm.push_back(cam.PixelToNormalized(mk.centre_px));
  // Layout centred, for the similarity fit.
  Eigen::Vector2d lc = Eigen::Vector2d::Zero();
  for (const auto& p : layout.markers) lc += p;
  lc /= static_cast<double>(m);
  double best = 1e300;
  std::vector<size_t> best_assign;
  std::vector<size_t> idx(n);
  std::iota(idx.begin(), idx.end(), 0);
  // Every ordered choice of m detections (n <= 12, m = 4: at most 11880 candidates).
  std::vector<size_t> choice(m);
  std::vector<bool> used(n, false);
  std::function<void(size_t)> rec = [&](size_t depth) {
    if (depth == m) {
      // Affine least squares z = A w + b from the mirrored layout (the camera sees the
      // plate from its marked +z side, which mirrors the plate's (x, y) into the image's
      // (right, down) axes). Affine absorbs foreshortening of oblique views; det(A) > 0
      // keeps the handedness, which makes the asymmetric layout unambiguous.
      Eigen::Vector2d ic = Eigen::Vector2d::Zero();
      for (size_t i = 0; i < m; ++i) ic += norm[choice[i]];
      ic /= static_cast<double>(m);
      Eigen::Matrix2d WW = Eigen::Matrix2d::Zero(), ZW = Eigen::Matrix2d::Zero();
      for (size_t i = 0; i < m; ++i) {
        const Eigen::Vector2d w(layout.markers[i].x() - lc.x(), -(layout.markers[i].y() - lc.y()));
        const Eigen::Vector2d z = norm[choice[i]] - ic;
        WW += w * w.transpose();
        ZW += z * w.transpose();
      }
      const Eigen::Matrix2d A = ZW * WW.inverse();
      if (A.determinant() <= 0) return;
      Eigen::JacobiSVD<Eigen::Matrix2d> svd(A);
      if (svd.singularValues()[1] < kMinAffineSingularRatio * svd.singularValues()[0]) return;
      double res = 0, scale = 0;
      for (size_t i = 0; i < m; ++i) {
        const Eigen::Vector2d w(layout.markers[i].x() - lc.x(), -(layout.markers[i].y() - lc.y()));
        const Eigen::Vector2d z = norm[choice[i]] - ic;
        res += (z - A * w).squaredNorm();
        scale += z.squaredNorm();
      }
      const double rel = std::sqrt(res / std::max(scale, 1e-300));
      if (rel < best) {
        best = rel;
        best_assign = choice;
      }
      return;
    }
    for (size_t j = 0; j < n; ++j) {
      if (used[j]) continue;
      used[j] = true;
      choice[depth] = j;
      rec(depth + 1);
      used[j] = false;
    }
  };
  rec(0);
  if (best > max_rms) return false;
  for (auto& mk : *markers) mk.id = -1;
  for (size_t i = 0; i < m; ++i) (*markers)[best_assign[i]].id = static_cast<int>(i);
  return true;
}

std::vector<std::vector<Marker>> IdentifyTargets(const CameraModel& cam,
                                                 const std::vector<TargetLayout>& layouts,
                                                 const std::vector<Marker>& detections,
                                                 double max_rms) {
  std::vector<std::vector<Marker>> out(layouts.size());
  std::vector<Marker> pool = detections;
  // Layouts with more markers first: they are the most constrained.
  std::vector<size_t> order(layouts.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return layouts[a].markers.size() > layouts[b].markers.size();
  });
  for (size_t li : order) {
    std::vector<Marker> trial = pool;
    if (!IdentifyTarget(cam, layouts[li], &trial, max_rms)) continue;
    std::vector<Marker> rest;
    for (const auto& m : trial) {
      if (m.id >= 0) {
        out[li].push_back(m);
      } else {
        rest.push_back(m);
      }
    }
    std::sort(out[li].begin(), out[li].end(),
              [](const Marker& a, const Marker& b) { return a.id < b.id; });
    pool = rest;
  }
  return out;
}

double CorrectPerspectiveBias(const CameraModel& cam, const Pose3& pose, const TargetLayout& layout,
                              std::vector<Marker>* markers) {
  double largest = 0.0;
  for (auto& m : *markers) {
    if (m.id < 0 || m.id >= static_cast<int>(layout.markers.size())) continue;
    const Eigen::Vector2d c = layout.markers[static_cast<size_t>(m.id)];
    const Eigen::Vector2d centre =
        cam.Project(pose.R * Eigen::Vector3d(c.x(), c.y(), 0.0) + pose.t);
    // Area centroid of the projected boundary polygon.
    constexpr int kN = 96;
    std::array<Eigen::Vector2d, kN> b;
    for (int k = 0; k < kN; ++k) {
      const double a = 2.0 * M_PI * k / kN;
      const Eigen::Vector3d p(c.x() + layout.marker_radius_m * std::cos(a),
                              c.y() + layout.marker_radius_m * std::sin(a), 0.0);
      b[static_cast<size_t>(k)] = cam.Project(pose.R * p + pose.t);
    }
    double area = 0;
    Eigen::Vector2d cen = Eigen::Vector2d::Zero();
    for (int k = 0; k < kN; ++k) {
      const auto& p0 = b[static_cast<size_t>(k)];
      const auto& p1 = b[static_cast<size_t>((k + 1) % kN)];
      const double cross = p0.x() * p1.y() - p1.x() * p0.y();
      area += cross;
      cen += (p0 + p1) * cross;
    }
    if (std::abs(area) < 1e-12) continue;
    cen /= 3.0 * area;
    const Eigen::Vector2d bias = cen - centre;
    m.centre_px -= bias;
    largest = std::max(largest, bias.norm());
  }
  return largest;
}

std::vector<Marker> MarkerTracker::Track(const cv::Mat& grey) {
  std::vector<Marker> markers;
  if (roi_.area() > 0) {
    markers = DetectMarkers(grey, opt_, roi_);
    full_frame_ = false;
    if (!IdentifyTarget(cam_, layout_, &markers)) markers.clear();
  }
  if (markers.empty()) {
    full_frame_ = true;
    ++full_searches_;
    markers = DetectMarkers(grey, opt_);
    if (!IdentifyTarget(cam_, layout_, &markers)) {
      roi_ = {};
      return {};
    }
  }
  std::vector<Marker> target;
  double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
  for (const auto& m : markers) {
    if (m.id < 0) continue;
    target.push_back(m);
    u0 = std::min(u0, m.centre_px.x() - m.diameter_px);
    v0 = std::min(v0, m.centre_px.y() - m.diameter_px);
    u1 = std::max(u1, m.centre_px.x() + m.diameter_px);
    v1 = std::max(v1, m.centre_px.y() + m.diameter_px);
  }
  roi_ =
      cv::Rect(static_cast<int>(u0) - margin_, static_cast<int>(v0) - margin_,
               static_cast<int>(u1 - u0) + 2 * margin_, static_cast<int>(v1 - v0) + 2 * margin_) &
      cv::Rect(0, 0, grey.cols, grey.rows);
  std::sort(target.begin(), target.end(),
            [](const Marker& a, const Marker& b) { return a.id < b.id; });
  return target;
}

}  // namespace kincal::vision
