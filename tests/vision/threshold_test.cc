// Thresholding (src/vision/threshold.h): Otsu's threshold splits markers from the floor and
// refuses a view of noise alone; flattening takes an uneven floor to one level, and the
// flattened view's threshold lies between that level and the markers'.
#include "vision/threshold.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>
#include <vector>

namespace kincal::vision {
namespace {

// A floor of `floor` grey with Gaussian noise and dark disks of `marker` grey.
cv::Mat ThresholdScene(int w, int h, double floor, double marker, double noise, uint64_t seed) {
  cv::Mat img(h, w, CV_8UC1);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, noise);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) img.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(floor + g(rng));
  }
  for (int k = 0; k < 4; ++k) {
    cv::circle(img, cv::Point(w / 5 * (k + 1), h / 2), 8, cv::Scalar(marker), cv::FILLED);
  }
  return img;
}

TEST(Threshold, OtsuSplitsMarkersFromTheFloor) {
  const cv::Mat img = ThresholdScene(160, 120, 180, 40, 2.0, 1);
  // Foreground is p <= thr: every marker pixel (40) in, every floor pixel (180 +- 3 sigma)
  // out.
  const int thr = OtsuThreshold(img, 10);
  EXPECT_GE(thr, 40);
  EXPECT_LT(thr, 174);
  // Light markers on a dark floor (foreground p > thr): the same split.
  cv::Mat inverted;
  cv::bitwise_not(img, inverted);
  const int inv = OtsuThreshold(inverted, 10);
  EXPECT_GE(inv, 75 + 6);
  EXPECT_LT(inv, 215);
}

TEST(Threshold, NoiseAloneHasNoThreshold) {
  const cv::Mat img = ThresholdScene(160, 120, 128, 128, 2.0, 2);  // "markers" at the floor's level
  EXPECT_EQ(OtsuThreshold(img, 10), -1);
  EXPECT_EQ(FlatThreshold(img, true, 10), -1);
}

// The row division's vector path gives the scalar formula's bytes exactly (the golden
// replay depends on them): every length up to 40 (the tail after the last eight), random
// levels, levels below 1, and exact halves that round to even.
TEST(Threshold, FlattenRowIsTheScalarFormulaToTheBit) {
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<int> grey(0, 255);
  std::uniform_real_distribution<float> level(0.0f, 300.0f);
  auto reference = [](uint8_t in, float b, bool dark) {
    // FlattenBackground's formula, written out: 200 in / max(b, 1), or in - b + 55.
    const double v = dark ? 200.0 * in / static_cast<double>(std::max(b, 1.0f))
                          : static_cast<double>(static_cast<float>(in) - b) + 55.0;
    return static_cast<uint8_t>(std::clamp(static_cast<int>(std::nearbyint(v)), 0, 255));
  };
  int halves = 0;
  for (bool dark : {true, false}) {
    for (int n = 0; n <= 40; ++n) {
      for (int trial = 0; trial < 50; ++trial) {
        std::vector<uint8_t> in(static_cast<size_t>(n)), out(static_cast<size_t>(n) + 1, 7);
        std::vector<float> b(static_cast<size_t>(n));
        for (int x = 0; x < n; ++x) {
          const auto i = static_cast<size_t>(x);
          in[i] = static_cast<uint8_t>(grey(rng));
          switch (trial % 4) {
            case 0:
              b[i] = level(rng);
              break;
            case 1:
              b[i] = level(rng) / 300.0f;
              break;  // below 1: the guard
            case 2:
              b[i] = dark ? 80.0f : 0.5f;
              break;  // 200 in / 80 and in - 0.5: halves
            default:
              b[i] = static_cast<float>(grey(rng));
              break;
          }
          const double v = dark ? 200.0 * in[i] / std::max(b[i], 1.0f) : in[i] - b[i] + 55.0;
          halves += v - std::floor(v) == 0.5 ? 1 : 0;
        }
        FlattenRow(in.data(), b.data(), n, dark, out.data());
        for (int x = 0; x < n; ++x) {
          const auto i = static_cast<size_t>(x);
          ASSERT_EQ(int{out[i]}, int{reference(in[i], b[i], dark)})
              << (dark ? "dark" : "bright") << " n " << n << " x " << x << " in " << int{in[i]}
              << " b " << b[i];
        }
        EXPECT_EQ(out[static_cast<size_t>(n)], 7) << "wrote past the row";
      }
    }
  }
  EXPECT_GT(halves, 1000) << "the exact halves were not exercised";
}

TEST(Threshold, FlatteningLevelsAnUnevenFloor) {
  // 640 x 480, the floor from 90 (left) to 230 (right): no single threshold splits it, and
  // the disks on the dark side are lighter than the floor on the bright side.
  cv::Mat img(480, 640, CV_8UC1);
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x)
      img.at<uint8_t>(y, x) = static_cast<uint8_t>(90 + x * 140 / 639);
  }
  for (int k = 0; k < 4; ++k) {
    const int x = 80 + 160 * k;
    const double floor = 90 + x * 140.0 / 639;
    cv::circle(img, cv::Point(x, 240), 8, cv::Scalar(0.35 * floor), cv::FILLED);
  }
  ASSERT_GE(img.rows * img.cols, kFlattenMinArea);
  cv::Mat flat;
  FlattenBackground(img, true, 64, &flat);
  // The floor near its flat level everywhere (the tiles' upper quantile, spread to their
  // neighbours, sits a little above a sloping floor): within 40 levels, where it spanned
  // 140 before;
  // the disks well below.
  int lo = 255, hi = 0;
  for (int x : {20, 170, 320, 470, 620}) {
    lo = std::min<int>(lo, flat.at<uint8_t>(100, x));
    hi = std::max<int>(hi, flat.at<uint8_t>(100, x));
  }
  EXPECT_GE(lo, 160);
  EXPECT_LE(hi, 205);
  EXPECT_LE(hi - lo, 40);
  for (int k = 0; k < 4; ++k) EXPECT_LT(flat.at<uint8_t>(240, 80 + 160 * k), 90) << k;
  const int thr = FlatThreshold(flat, true, 10);
  EXPECT_GT(thr, 90);
  EXPECT_LT(thr, 190);
}

}  // namespace
}  // namespace kincal::vision
