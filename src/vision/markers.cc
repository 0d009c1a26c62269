#include "kincal/vision/markers.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numeric>
#include <opencv2/imgproc.hpp>

namespace kincal::vision {

bool DetectorOptions::IsValid(std::string* error) const {
  if (threshold > 255 || min_area_px < 1 || max_area_px < min_area_px || !(min_circularity > 0) ||
      min_circularity > 1 || !(min_fill > 0) || min_fill > 1) {
    *error = "detector: threshold <= 255, 1 <= min_area <= max_area, circularity and fill in (0, 1]";
    return false;
  }
  return true;
}

std::vector<Marker> DetectMarkers(const cv::Mat& grey, const DetectorOptions& opt, cv::Rect roi,
                                  std::vector<Rejected>* rejected) {
  CV_Assert(grey.type() == CV_8UC1);
  if (roi.area() == 0) roi = cv::Rect(0, 0, grey.cols, grey.rows);
  roi &= cv::Rect(0, 0, grey.cols, grey.rows);
  std::vector<Marker> out;
  if (roi.area() == 0) return out;
  const cv::Mat view = grey(roi);
  cv::Mat bin;
  const int type = opt.dark_on_light ? cv::THRESH_BINARY_INV : cv::THRESH_BINARY;
  const double thr = opt.threshold >= 0
                         ? cv::threshold(view, bin, opt.threshold, 255, type)
                         : cv::threshold(view, bin, 0, 255, type | cv::THRESH_OTSU);
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(bin, labels, stats, centroids, 8, CV_32S);
  for (int k = 1; k < n; ++k) {
    const int area = stats.at<int>(k, cv::CC_STAT_AREA);
    const Eigen::Vector2d c0(centroids.at<double>(k, 0) + roi.x, centroids.at<double>(k, 1) + roi.y);
    auto reject = [&](const std::string& why) {
      if (rejected != nullptr) rejected->push_back({c0, why});
    };
    if (area < opt.min_area_px) {
      reject("area " + std::to_string(area) + " < " + std::to_string(opt.min_area_px));
      continue;
    }
    if (area > opt.max_area_px) {
      reject("area " + std::to_string(area) + " > " + std::to_string(opt.max_area_px));
      continue;
    }
    const int bx = stats.at<int>(k, cv::CC_STAT_LEFT), by = stats.at<int>(k, cv::CC_STAT_TOP);
    const int bw = stats.at<int>(k, cv::CC_STAT_WIDTH), bh = stats.at<int>(k, cv::CC_STAT_HEIGHT);
    if (bx == 0 || by == 0 || bx + bw >= view.cols || by + bh >= view.rows) {
      reject("touches the search border");
      continue;
    }
    // Second moments of the binary blob: ellipse axes.
    double sxx = 0, syy = 0, sxy = 0;
    const double mx = centroids.at<double>(k, 0), my = centroids.at<double>(k, 1);
    for (int y = by; y < by + bh; ++y) {
      const int* lab = labels.ptr<int>(y);
      for (int x = bx; x < bx + bw; ++x) {
        if (lab[x] != k) continue;
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
        sxy += (x - mx) * (y - my);
      }
    }
    sxx /= area;
    syy /= area;
    sxy /= area;
    const double tr = sxx + syy, det = sxx * syy - sxy * sxy;
    const double disc = std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
    const double l1 = 0.5 * tr + disc, l2 = std::max(0.5 * tr - disc, 1e-12);
    const double circ = std::sqrt(l2 / l1);
    const double ellipse_area = 4.0 * M_PI * std::sqrt(l1 * l2);
    const double fill = area / ellipse_area;
    if (circ < opt.min_circularity) {
      reject("circularity " + std::to_string(circ).substr(0, 4));
      continue;
    }
    if (fill < opt.min_fill || fill > 1.0 / opt.min_fill) {
      reject("fill ratio " + std::to_string(fill).substr(0, 4));
      continue;
    }
    // Intensity-weighted centre over the blob's box grown by 2 px: background level from
    // the box border, marker level from the blob's darkest (brightest) quarter.
    const int x0 = std::max(0, bx - 2), y0 = std::max(0, by - 2);
    const int x1 = std::min(view.cols - 1, bx + bw + 1), y1 = std::min(view.rows - 1, by + bh + 1);
    std::vector<double> border;
    for (int x = x0; x <= x1; ++x) {
      border.push_back(view.at<uint8_t>(y0, x));
      border.push_back(view.at<uint8_t>(y1, x));
    }
    for (int y = y0 + 1; y < y1; ++y) {
      border.push_back(view.at<uint8_t>(y, x0));
      border.push_back(view.at<uint8_t>(y, x1));
    }
    std::nth_element(border.begin(), border.begin() + static_cast<long>(border.size() / 2), border.end());
    const double bg = border[border.size() / 2];
    std::vector<double> inner;
    for (int y = by; y < by + bh; ++y) {
      for (int x = bx; x < bx + bw; ++x) {
        if (labels.at<int>(y, x) == k) inner.push_back(view.at<uint8_t>(y, x));
      }
    }
    const size_t q = inner.size() / 4;
    if (opt.dark_on_light) {
      std::nth_element(inner.begin(), inner.begin() + static_cast<long>(q), inner.end());
    } else {
      std::nth_element(inner.begin(), inner.begin() + static_cast<long>(q), inner.end(), std::greater<double>());
    }
    const double fg = inner[q];
    const double span = bg - fg;
    if (std::abs(span) < 1e-9 || (opt.dark_on_light ? span < 0 : span > 0)) {
      reject("no contrast");
      continue;
    }
    double sw = 0, su = 0, sv = 0;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        const double w = std::clamp((bg - view.at<uint8_t>(y, x)) / span, 0.0, 1.0);
        sw += w;
        su += w * x;
        sv += w * y;
      }
    }
    Marker m;
    m.centre_px = Eigen::Vector2d(su / sw + roi.x, sv / sw + roi.y);
    m.area_px = sw;
    m.diameter_px = 2.0 * std::sqrt(sw / M_PI);
    out.push_back(m);
    (void)thr;
  }
  return out;
}

bool IdentifyTarget(const CameraModel& cam, const TargetLayout& layout, std::vector<Marker>* markers,
                    double max_rms) {
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
      if (svd.singularValues()[1] < 0.2 * svd.singularValues()[0]) return;  // beyond ~78 deg
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

double CorrectPerspectiveBias(const CameraModel& cam, const Pose3& pose, const TargetLayout& layout,
                              std::vector<Marker>* markers) {
  double largest = 0.0;
  for (auto& m : *markers) {
    if (m.id < 0 || m.id >= static_cast<int>(layout.markers.size())) continue;
    const Eigen::Vector2d c = layout.markers[static_cast<size_t>(m.id)];
    const Eigen::Vector2d centre = cam.Project(pose.R * Eigen::Vector3d(c.x(), c.y(), 0.0) + pose.t);
    // Area centroid of the projected boundary polygon.
    constexpr int kN = 96;
    std::array<Eigen::Vector2d, kN> b;
    for (int k = 0; k < kN; ++k) {
      const double a = 2.0 * M_PI * k / kN;
      const Eigen::Vector3d p(c.x() + layout.marker_radius_m * std::cos(a), c.y() + layout.marker_radius_m * std::sin(a), 0.0);
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
  roi_ = cv::Rect(static_cast<int>(u0) - margin_, static_cast<int>(v0) - margin_,
                  static_cast<int>(u1 - u0) + 2 * margin_, static_cast<int>(v1 - v0) + 2 * margin_) &
         cv::Rect(0, 0, grey.cols, grey.rows);
  std::sort(target.begin(), target.end(), [](const Marker& a, const Marker& b) { return a.id < b.id; });
  return target;
}

}  // namespace kincal::vision
