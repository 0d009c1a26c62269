// The floor a camera sees: a nadir camera's rectangle from its field of view by hand, the
// target plane's height shrinking it, and a camera looking above the horizon seeing less.
#include "kincal/vision/floor_view.h"

#include <gtest/gtest.h>

#include <cmath>

namespace kincal::vision {
namespace {

CameraModel Camera640() { return CameraModel::Centred(640, 480, 500.0); }

// Straight down from `h` m above the floor (camera x along floor x, y along -y).
FloorExtrinsics Nadir(double h) {
  FloorExtrinsics f;
  f.R_cf = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
  f.t_cf = Eigen::Vector3d(0.0, 0.0, h);
  return f;
}

TEST(FloorView, ANadirCameraSeesItsFieldOfViewTimesItsHeight) {
  const auto poly = FloorSeen(Camera640(), Nadir(2.0), 0.0, 4);
  ASSERT_EQ(poly.size(), 16u);
  // Top-left corner of the image: (-320 px, -240 px) from the centre at f = 500 px, 2 m.
  EXPECT_NEAR(poly[0].x(), -320.0 / 500.0 * 2.0, 1e-9);
  EXPECT_NEAR(poly[0].y(), 240.0 / 500.0 * 2.0, 1e-9);  // image up is floor +y
  double x_min = 1e9, x_max = -1e9;
  for (const auto& p : poly) {
    x_min = std::min(x_min, p.x());
    x_max = std::max(x_max, p.x());
  }
  EXPECT_NEAR(x_max - x_min, 640.0 / 500.0 * 2.0, 1e-9);
  // The plane of markers 0.5 m up: a quarter less.
  const auto up = FloorSeen(Camera640(), Nadir(2.0), 0.5, 4);
  EXPECT_NEAR(up[0].x(), -320.0 / 500.0 * 1.5, 1e-9);
}

TEST(FloorView, RaysAboveTheHorizonAreLeftOut) {
  // Tilted 80 degrees from the nadir about camera x: the image's top looks above the horizon.
  FloorExtrinsics f = Nadir(1.0);
  const double a = 80.0 * M_PI / 180.0;
  Eigen::Matrix3d tilt;
  tilt << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  f.R_cf = tilt * f.R_cf;
  f.t_cf = tilt * f.t_cf;
  const auto poly = FloorSeen(Camera640(), f, 0.0, 8);
  EXPECT_GT(poly.size(), 0u);
  EXPECT_LT(poly.size(), 32u);
  // Camera 1 m up looking above the horizon: nothing.
  FloorExtrinsics sky = Nadir(1.0);
  sky.R_cf = Eigen::Vector3d(1.0, 1.0, 1.0).asDiagonal();  // looking straight up
  sky.t_cf = Eigen::Vector3d(0.0, 0.0, -1.0);
  EXPECT_TRUE(FloorSeen(Camera640(), sky, 0.0, 8).empty());
}

// The target's axes by hand for a nadir camera 2 m up (depth 1.95 m to the target plane):
// the origin, the x axis along image +u at theta 0 and along image -v at theta pi/2, the y
// axis along image -v; a target above the camera is not in front of it.
TEST(FloorView, TheTargetsAxesProjectIntoTheImage) {
  const CameraModel c = Camera640();
  std::array<Eigen::Vector2d, 3> px;
  ASSERT_TRUE(TargetAxesInImage(c, Nadir(2.0), 0.05, Eigen::Vector3d(0.2, 0.1, 0.0), 0.1, &px));
  const double k = 500.0 / 1.95;
  EXPECT_NEAR(px[0].x(), 319.5 + 0.2 * k, 1e-9);
  EXPECT_NEAR(px[0].y(), 239.5 - 0.1 * k, 1e-9);
  EXPECT_NEAR(px[1].x() - px[0].x(), 0.1 * k, 1e-9);
  EXPECT_NEAR(px[1].y() - px[0].y(), 0.0, 1e-9);
  EXPECT_NEAR(px[2].x() - px[0].x(), 0.0, 1e-9);
  EXPECT_NEAR(px[2].y() - px[0].y(), -0.1 * k, 1e-9);
  ASSERT_TRUE(
      TargetAxesInImage(c, Nadir(2.0), 0.05, Eigen::Vector3d(0.2, 0.1, M_PI / 2), 0.1, &px));
  EXPECT_NEAR(px[1].x() - px[0].x(), 0.0, 1e-9);
  EXPECT_NEAR(px[1].y() - px[0].y(), -0.1 * k, 1e-9);
  EXPECT_NEAR(px[2].x() - px[0].x(), -0.1 * k, 1e-9);
  EXPECT_FALSE(TargetAxesInImage(c, Nadir(2.0), 2.5, Eigen::Vector3d::Zero(), 0.1, &px));
}

}  // namespace
}  // namespace kincal::vision
