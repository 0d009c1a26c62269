// SyntheticBoardViews: the views it promises (a 9 x 6 grid at 25 mm, every point inside the
// image, in front of the camera at about 0.7 m), the same for the same seed, and noise of the
// asked size on top of the exact projections.
#include "kincal/vision/synthetic.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "vision/vision_test_util.h"

namespace kincal::vision {
namespace {

using namespace test_util;

TEST(Synthetic, ViewsAreWholeGridsInsideTheImage) {
  const CameraModel cam = TestCamera();
  std::mt19937_64 rng(3);
  const auto views = SyntheticBoardViews(cam, 10, 0.2, rng);
  ASSERT_EQ(views.size(), 10u);
  std::set<std::string> names;
  for (const auto& v : views) {
    names.insert(v.name);
    ASSERT_EQ(v.object.size(), 54u);
    ASSERT_EQ(v.image.size(), 54u);
    EXPECT_EQ(v.object[0], Eigen::Vector3d(0, 0, 0));
    EXPECT_NEAR(v.object[53].x(), 0.2, 1e-15);  // 8 x 25 mm
    EXPECT_NEAR(v.object[53].y(), 0.125, 1e-15);
    for (const auto& px : v.image) {
      EXPECT_GT(px.x(), 0.0);
      EXPECT_GT(px.y(), 0.0);
      EXPECT_LT(px.x(), cam.width - 1.0);
      EXPECT_LT(px.y(), cam.height - 1.0);
    }
  }
  EXPECT_EQ(names.size(), views.size()) << "each view is named apart";
}

TEST(Synthetic, TheSameSeedGivesTheSameViews) {
  const CameraModel cam = TestCamera();
  std::mt19937_64 a(8), b(8), c(9);
  const auto va = SyntheticBoardViews(cam, 3, 0.3, a);
  const auto vb = SyntheticBoardViews(cam, 3, 0.3, b);
  const auto vc = SyntheticBoardViews(cam, 3, 0.3, c);
  for (size_t i = 0; i < va.size(); ++i) {
    for (size_t k = 0; k < va[i].image.size(); ++k) EXPECT_EQ(va[i].image[k], vb[i].image[k]);
  }
  EXPECT_GT((va[0].image[0] - vc[0].image[0]).norm(), 1.0) << "another seed, another view";
}

// The noise draws are taken whatever their size, so the same seed with and without noise
// gives the same poses: the difference is the noise alone.
TEST(Synthetic, PixelNoiseHasTheAskedSigma) {
  const CameraModel cam = TestCamera();
  std::mt19937_64 a(5), b(5);
  const auto exact = SyntheticBoardViews(cam, 20, 0.0, a);
  const auto noisy = SyntheticBoardViews(cam, 20, 0.5, b);
  double sum = 0, sum2 = 0;
  int n = 0;
  for (size_t i = 0; i < exact.size(); ++i) {
    ASSERT_EQ(exact[i].object, noisy[i].object);
    for (size_t k = 0; k < exact[i].image.size(); ++k) {
      const Eigen::Vector2d d = noisy[i].image[k] - exact[i].image[k];
      ASSERT_LT(d.norm(), 5.0) << "view " << i << " was redrawn differently";
      sum += d.x() + d.y();
      sum2 += d.squaredNorm();
      n += 2;
    }
  }
  const double mean = sum / n, sigma = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 4.0 * 0.5 / std::sqrt(n));
  EXPECT_NEAR(sigma, 0.5, 0.05);  // 2160 draws: the sigma's own sigma is 0.008
}

}  // namespace
}  // namespace kincal::vision
