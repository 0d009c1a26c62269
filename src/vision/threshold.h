// Thresholding a grey view for marker detection (markers.cc): the floor's brightness
// flattened out of a large view, and the threshold of a flattened view or, for a small one,
// Otsu's. Private to the vision layer.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>

namespace kincal::vision {

// Regions at least this large (pixels) are flattened (DetectorOptions::flatten_background).
inline constexpr int kFlattenMinArea = 320 * 240;

// The floor's brightness, interpolated over the view from per-tile (`tile` px) quantiles,
// divided out: out = 200 * view / background for dark markers, or view - background + 55
// for bright markers on a dark floor (a dark floor's level is mostly offset).
void FlattenBackground(const cv::Mat& view, bool dark_on_light, int tile, cv::Mat* out);

// One row of FlattenBackground's division (or subtraction): out[x] from in[x] and the
// background level b[x], for x < n. Eight pixels at a time with SSE2, to the same bits as
// the scalar formula above (rounded to nearest even, saturated).
void FlattenRow(const uint8_t* in, const float* b, int n, bool dark_on_light, uint8_t* out);

// The threshold of a flattened view: half way between the floor (the median) and the
// darkest (brightest) 10^-4 of the pixels; -1 when they differ by less than twice
// `min_contrast` (nothing but floor in view). Otsu would split the floor's own noise here:
// markers are a tiny fraction of a whole frame.
int FlatThreshold(const cv::Mat& flat, bool dark_on_light, int min_contrast);

// Otsu's threshold from a histogram of every other pixel of every other row; -1 when the
// two classes it separates differ by less than `min_contrast` grey levels (an empty, noisy
// view: thresholding it would only produce noise blobs).
int OtsuThreshold(const cv::Mat& view, int min_contrast);

}  // namespace kincal::vision
