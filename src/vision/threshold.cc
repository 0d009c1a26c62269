#include "vision/threshold.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>
#ifdef __SSE2__
#include <emmintrin.h>
#endif

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

#ifdef __SSE2__
// Eight pixels of FlattenRow at once, with the scalar loop's arithmetic to the bit: the
// same operations in the same precision (double, the float subtraction of the bright
// case in float), rounded to nearest even as cvRound does (cvtpd_epi32 under the default
// rounding mode) and saturated to 0..255 as saturate_cast does (the two packs).
__m128i ToInt4(__m128d lo, __m128d hi) {
  return _mm_unpacklo_epi64(_mm_cvtpd_epi32(lo), _mm_cvtpd_epi32(hi));
}

void Store8(__m128i first4, __m128i last4, uint8_t* out) {
  const __m128i words = _mm_packs_epi32(first4, last4);
  _mm_storel_epi64(reinterpret_cast<__m128i*>(out), _mm_packus_epi16(words, words));
}

// The eight pixels as two vectors of four 32-bit integers.
void Load8(const uint8_t* in, __m128i* first4, __m128i* last4) {
  const __m128i zero = _mm_setzero_si128();
  const __m128i words =
      _mm_unpacklo_epi8(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(in)), zero);
  *first4 = _mm_unpacklo_epi16(words, zero);
  *last4 = _mm_unpackhi_epi16(words, zero);
}

// kFlatLevel * in / max(b, 1).
__m128i FlattenDark4(__m128i in4, const float* b) {
  const __m128 level = _mm_max_ps(_mm_loadu_ps(b), _mm_set1_ps(1.0f));
  const __m128d scale = _mm_set1_pd(kFlatLevel);
  const __m128d lo = _mm_div_pd(_mm_mul_pd(scale, _mm_cvtepi32_pd(in4)), _mm_cvtps_pd(level));
  const __m128d hi = _mm_div_pd(_mm_mul_pd(scale, _mm_cvtepi32_pd(_mm_unpackhi_epi64(in4, in4))),
                                _mm_cvtps_pd(_mm_movehl_ps(level, level)));
  return ToInt4(lo, hi);
}

// (in - b, in float) + (255 - kFlatLevel).
__m128i FlattenBright4(__m128i in4, const float* b) {
  const __m128 diff = _mm_sub_ps(_mm_cvtepi32_ps(in4), _mm_loadu_ps(b));
  const __m128d offset = _mm_set1_pd(255.0 - kFlatLevel);
  return ToInt4(_mm_add_pd(_mm_cvtps_pd(diff), offset),
                _mm_add_pd(_mm_cvtps_pd(_mm_movehl_ps(diff, diff)), offset));
}

void FlattenDark8(const uint8_t* in, const float* b, uint8_t* out) {
  __m128i first4, last4;
  Load8(in, &first4, &last4);
  Store8(FlattenDark4(first4, b), FlattenDark4(last4, b + 4), out);
}

void FlattenBright8(const uint8_t* in, const float* b, uint8_t* out) {
  __m128i first4, last4;
  Load8(in, &first4, &last4);
  Store8(FlattenBright4(first4, b), FlattenBright4(last4, b + 4), out);
}
#endif

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
    FlattenRow(view.ptr<uint8_t>(y), background.ptr<float>(y), view.cols, dark_on_light,
               out->ptr<uint8_t>(y));
  }
}

void FlattenRow(const uint8_t* in, const float* b, int n, bool dark_on_light, uint8_t* out) {
  int x = 0;
#ifdef __SSE2__
  if (dark_on_light) {
    for (; x + 8 <= n; x += 8) FlattenDark8(in + x, b + x, out + x);
  } else {
    for (; x + 8 <= n; x += 8) FlattenBright8(in + x, b + x, out + x);
  }
#endif
  for (; x < n; ++x) {
    out[x] = dark_on_light ? cv::saturate_cast<uint8_t>(kFlatLevel * in[x] / std::max(b[x], 1.0f))
                           : cv::saturate_cast<uint8_t>(in[x] - b[x] + (255.0 - kFlatLevel));
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
