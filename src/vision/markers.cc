// Marker detection: threshold (threshold.h), connected components (labels.h), a shape test
// on each component's moments, and the sub-pixel centre of each that passes
// (centroid.h). Identification and tracking: identification.cc, tracking.cc.
#include "kincal/vision/markers.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "vision/centroid.h"
#include "vision/labels.h"
#include "vision/threshold.h"

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

// Blobs smaller than this are noise, dropped without a rejection note.
constexpr int64_t kMinReportedArea = 4;
// Moment floors, and the variance a pixel adds to a pixelated disk's moments (1/12 per
// axis).
constexpr double kMomentFloor = 1e-12;
constexpr double kPixelVariance = 1.0 / 12.0;

// Why blob `b` of a view of `cols` x `rows` is not a marker ("" when its size, position
// and shape fit one); `mx`, `my` its centroid.
std::string ShapeRejection(const Blob& b, double mx, double my, int cols, int rows,
                           const DetectorOptions& opt) {
  if (b.area < opt.min_area_px) {
    return b.area >= kMinReportedArea
               ? "area " + std::to_string(b.area) + " < " + std::to_string(opt.min_area_px)
               : std::string("-");  // noise: dropped silently
  }
  if (b.area > opt.max_area_px) {
    return "area " + std::to_string(b.area) + " > " + std::to_string(opt.max_area_px);
  }
  if (b.x0 == 0 || b.y0 == 0 || b.x1 + 1 >= cols || b.y1 + 1 >= rows) {
    return "touches the search border";
  }
  // Second moments of the binary blob: ellipse axes.
  const double area = static_cast<double>(b.area);
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
  if (circ < opt.min_circularity) return "circularity " + std::to_string(circ).substr(0, 4);
  if (fill < opt.min_fill || fill > 1.0 / opt.min_fill) {
    return "fill ratio " + std::to_string(fill).substr(0, 4);
  }
  return "";
}

// The view to label (flattened when large) and its threshold; -1: nothing to find.
int Threshold(const DetectorOptions& opt, cv::Mat* view) {
  if (opt.flatten_background && opt.threshold < 0 && view->rows * view->cols >= kFlattenMinArea) {
    thread_local cv::Mat flat;
    FlattenBackground(*view, opt.dark_on_light, opt.background_tile_px, &flat);
    *view = flat;
    return FlatThreshold(*view, opt.dark_on_light, opt.min_contrast);
  }
  return opt.threshold >= 0 ? opt.threshold : OtsuThreshold(*view, opt.min_contrast);
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
  const int thr = Threshold(opt, &view);
  if (thr < 0) return out;
  thread_local std::vector<Blob> blobs;
  LabelRuns(view, thr, opt.dark_on_light, &blobs);
  for (size_t k = 0; k < blobs.size(); ++k) {
    const Blob& b = blobs[k];
    if (b.parent != static_cast<int>(k) || b.area == 0) continue;
    const double mx = b.sx / static_cast<double>(b.area), my = b.sy / static_cast<double>(b.area);
    const Eigen::Vector2d c0(mx + roi.x, my + roi.y);
    std::string why = ShapeRejection(b, mx, my, view.cols, view.rows, opt);
    Eigen::Vector2d centre;
    double weight = 0.0;
    if (why.empty() && !WeightedCentre(view, b, thr, opt.dark_on_light, &centre, &weight)) {
      why = "no contrast";
    }
    if (!why.empty()) {
      if (rejected != nullptr && why != "-") rejected->push_back({c0, why});
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

}  // namespace kincal::vision
