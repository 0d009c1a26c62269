// MarkerTracker: detection near the last target, the whole frame when it is lost.
#include <algorithm>

#include "kincal/vision/markers.h"

namespace kincal::vision {

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
