#include "vision/threshold.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace kincal::vision {
namespace {

// The histograms sample every kOtsuStride-th pixel of every kOtsuStride-th row.
constexpr int kOtsuStride = 2;
// The floor's level in a tile: this quantile of its (sampled) pixels, from the bright end
// for dark markers.
constexpr double kBackgroundQuantile = 0.9;
// After flattening, the floor sits at this grey level (headroom for bright markers).
constexpr double kFlatLevel = 200.0;
// The marker level of a flattened view: this quantile from the dark (bright) end.
constexpr double kMarkerFraction = 1e-4;

// The grey-level histogram of every kOtsuStride-th pixel of every kOtsuStride-th row; *n
// the pixels counted.
std::array<int64_t, 256> SampledHistogram(const cv::Mat& view, int64_t* n) {
  std::array<int64_t, 256> hist{};
  for (int y = 0; y < view.rows; y += kOtsuStride) {
    const uint8_t* row = view.ptr<uint8_t>(y);
    for (int x = 0; x < view.cols; x += kOtsuStride) {
      ++hist[row[x]];
      ++*n;
    }
  }
  return hist;
}

}  // namespace

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

int FlatThreshold(const cv::Mat& flat, bool dark_on_light, int min_contrast) {
  int64_t n = 0;
  const std::array<int64_t, 256> hist = SampledHistogram(flat, &n);
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

int OtsuThreshold(const cv::Mat& view, int min_contrast) {
  int64_t n = 0;
  const std::array<int64_t, 256> hist = SampledHistogram(view, &n);
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

}  // namespace kincal::vision
