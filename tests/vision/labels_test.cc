// Connected components (src/vision/labels.h): 8-connected, the branches of a U merged into
// one component, each component's area, moments and box exact.
#include "vision/labels.h"

#include <gtest/gtest.h>

#include <vector>

namespace kincal::vision {
namespace {

std::vector<Blob> Roots(const std::vector<Blob>& blobs) {
  std::vector<Blob> roots;
  for (size_t k = 0; k < blobs.size(); ++k) {
    if (blobs[k].parent == static_cast<int>(k) && blobs[k].area > 0) roots.push_back(blobs[k]);
  }
  return roots;
}

TEST(Labels, AUAndADiagonalPairAreOneComponentEachWithExactMoments) {
  cv::Mat img(12, 16, CV_8UC1, cv::Scalar(200));
  // A U: two columns joined only at the bottom row (labelled as two runs first).
  for (int y = 2; y <= 6; ++y) {
    img.at<uint8_t>(y, 2) = 20;
    img.at<uint8_t>(y, 5) = 20;
  }
  for (int x = 2; x <= 5; ++x) img.at<uint8_t>(7, x) = 20;
  // Two pixels touching at a corner only: 8-connected, one component.
  img.at<uint8_t>(3, 10) = 20;
  img.at<uint8_t>(4, 11) = 20;
  std::vector<Blob> blobs;
  LabelRuns(img, 100, /*dark_on_light=*/true, &blobs);
  const std::vector<Blob> roots = Roots(blobs);
  ASSERT_EQ(roots.size(), 2u);
  const Blob& u = roots[0].x0 == 2 ? roots[0] : roots[1];
  const Blob& pair = roots[0].x0 == 2 ? roots[1] : roots[0];
  // The U: 5 + 5 + 4 pixels; sums over its pixels by hand.
  EXPECT_EQ(u.area, 14);
  EXPECT_DOUBLE_EQ(u.sx, 5 * 2 + 5 * 5 + 3 + 4 + 2 + 5);
  EXPECT_DOUBLE_EQ(u.sy, 2 * (2 + 3 + 4 + 5 + 6) + 4 * 7);
  EXPECT_DOUBLE_EQ(u.sxx, 5 * 4 + 5 * 25 + 4 + 9 + 16 + 25);
  EXPECT_DOUBLE_EQ(u.sxy, (2 + 5) * (2 + 3 + 4 + 5 + 6) + 7 * (2 + 3 + 4 + 5));
  EXPECT_EQ(u.x0, 2);
  EXPECT_EQ(u.x1, 5);
  EXPECT_EQ(u.y0, 2);
  EXPECT_EQ(u.y1, 7);
  EXPECT_EQ(pair.area, 2);
  EXPECT_DOUBLE_EQ(pair.syy, 9 + 16);
}

TEST(Labels, LightOnDarkAndWideRunsAcrossTheVectorWidth) {
  // A run of 40 light pixels (longer than one 16-pixel SSE2 step) on a dark row.
  cv::Mat img(5, 64, CV_8UC1, cv::Scalar(10));
  for (int x = 17; x < 57; ++x) img.at<uint8_t>(2, x) = 250;
  std::vector<Blob> blobs(3);  // reused: cleared first
  LabelRuns(img, 128, /*dark_on_light=*/false, &blobs);
  const std::vector<Blob> roots = Roots(blobs);
  ASSERT_EQ(roots.size(), 1u);
  EXPECT_EQ(roots[0].area, 40);
  EXPECT_EQ(roots[0].x0, 17);
  EXPECT_EQ(roots[0].x1, 56);
  EXPECT_DOUBLE_EQ(roots[0].sx, (17 + 56) * 40 / 2.0);
  // Dark-on-light on the same view: the whole background is one component.
  LabelRuns(img, 128, /*dark_on_light=*/true, &blobs);
  ASSERT_EQ(Roots(blobs).size(), 1u);
  EXPECT_EQ(Roots(blobs)[0].area, 5 * 64 - 40);
}

}  // namespace
}  // namespace kincal::vision
