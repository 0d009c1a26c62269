// The weighted centre (src/vision/centroid.h): a supersampled disk's centre to 0.02 px
// wherever it sits on the grid, dark on light and light on dark; no contrast is
// no centre.
#include "vision/centroid.h"

#include <gtest/gtest.h>

#include <cmath>

namespace kincal::vision {
namespace {

// A disk of radius r centred at (cx, cy), area-sampled 16 x 16 per pixel: level `in`
// inside, `out` outside.
cv::Mat Disk(double cx, double cy, double r, double in, double out) {
  cv::Mat img(32, 32, CV_8UC1);
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      int hits = 0;
      for (int j = 0; j < 16; ++j) {
        for (int i = 0; i < 16; ++i) {
          const double u = x - 0.5 + (i + 0.5) / 16, v = y - 0.5 + (j + 0.5) / 16;
          hits += (u - cx) * (u - cx) + (v - cy) * (v - cy) <= r * r;
        }
      }
      img.at<uint8_t>(y, x) = cv::saturate_cast<uint8_t>(out + (in - out) * hits / 256.0);
    }
  }
  return img;
}

// The blob LabelRuns gives for the disk (its one component).
Blob Component(const cv::Mat& img, int thr, bool dark) {
  std::vector<Blob> blobs;
  LabelRuns(img, thr, dark, &blobs);
  for (size_t k = 0; k < blobs.size(); ++k) {
    if (blobs[k].parent == static_cast<int>(k) && blobs[k].area > 0) return blobs[k];
  }
  return Blob{-1};
}

TEST(Centroid, ADiskAnywhereOnTheGridToTwoHundredthsOfAPixel) {
  for (const double dx : {0.0, 0.13, 0.5, 0.77}) {
    for (const bool dark : {true, false}) {
      const double cx = 15.0 + dx, cy = 16.0 - dx / 2;
      const cv::Mat img = dark ? Disk(cx, cy, 5.0, 30, 190) : Disk(cx, cy, 5.0, 220, 40);
      const int thr = dark ? 110 : 130;
      Eigen::Vector2d c;
      double weight = 0;
      ASSERT_TRUE(WeightedCentre(img, Component(img, thr, dark), thr, dark, &c, &weight));
      EXPECT_NEAR(c.x(), cx, 0.02) << dx << " dark " << dark;
      EXPECT_NEAR(c.y(), cy, 0.02) << dx << " dark " << dark;
      EXPECT_NEAR(weight, M_PI * 25.0, 0.05 * M_PI * 25.0);  // the disk's area in pixels
    }
  }
}

TEST(Centroid, NoContrastIsNoCentre) {
  const cv::Mat img(32, 32, CV_8UC1, cv::Scalar(100));
  Blob b{0};
  b.area = 9;
  b.x0 = b.y0 = 10;
  b.x1 = b.y1 = 12;
  Eigen::Vector2d c;
  double weight = 0;
  EXPECT_FALSE(WeightedCentre(img, b, 100, true, &c, &weight));
}

}  // namespace
}  // namespace kincal::vision
