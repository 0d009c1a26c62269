#include "vision/centroid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

namespace kincal::vision {
namespace {

// The centroid window: the blob's box grown by this many pixels, which holds the edge
// blur; the background is the median of its border.
constexpr int kCentroidMarginPx = 2;
// The marker level: this quantile of the foreground pixels (the darkest quarter's edge).
constexpr size_t kForegroundQuantileDivisor = 4;

}  // namespace

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

}  // namespace kincal::vision
