// Connected components of a thresholded view in one pass over its horizontal runs
// (union-find), each with the moments and box marker detection needs (markers.cc).
// Private to the vision layer.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace kincal::vision {

// One connected component, accumulated from its horizontal runs. After LabelRuns, a root
// (parent == its own index) with area > 0 holds the whole component: its pixel count, the
// sums of x, y, x^2, y^2, xy over its pixels, and its inclusive bounding box.
struct Blob {
  int parent;
  int64_t area = 0;
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
};

// The 8-connected components of the foreground of `view` (dark_on_light: pixels <= thr;
// otherwise pixels > thr), into *blobs (cleared first; its capacity is kept, so a reused
// vector does not allocate once warm).
void LabelRuns(const cv::Mat& view, int thr, bool dark_on_light, std::vector<Blob>* blobs);

}  // namespace kincal::vision
