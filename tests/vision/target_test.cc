// Targets and the synthetic camera: the thesis layout is valid and asymmetric, bad layouts
// are named, and a rendered target's ground-truth centres are the camera's projections
// with the markers where they were drawn.
#include "kincal/vision/target.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "vision/vision_test_util.h"

namespace kincal::vision {
namespace {

using test_util::Overhead;
using test_util::TargetPose;
using test_util::TestCamera;

TEST(TargetLayout, ThesisPlateIsValidAndHasNoSymmetry) {
  const TargetLayout t = TargetLayout::Thesis();
  std::string error;
  ASSERT_TRUE(t.IsValid(&error)) << error;
  ASSERT_EQ(t.markers.size(), 4u);
  // A half turn of the plate must not map the markers onto themselves.
  int coincide = 0;
  for (const auto& a : t.markers) {
    for (const auto& b : t.markers) coincide += (a + b).norm() < 1e-6;
  }
  EXPECT_LT(coincide, 4);
}

TEST(TargetLayout, TooFewOrOverlappingMarkersAreNamed) {
  TargetLayout t = TargetLayout::Thesis();
  t.markers.resize(2);
  std::string error;
  EXPECT_FALSE(t.IsValid(&error));
  EXPECT_FALSE(error.empty());
  t = TargetLayout::Thesis();
  t.markers[1] = t.markers[0];
  error.clear();
  EXPECT_FALSE(t.IsValid(&error));
  EXPECT_FALSE(error.empty());
  // A marker at infinity, and a plate of no size (a layout file with .inf, or 0): named.
  t = TargetLayout::Thesis();
  t.markers[2].x() = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(t.IsValid(&error));
  EXPECT_EQ(error, "marker 3: its position must be finite");
  t = TargetLayout::Thesis();
  t.plate_size_m.x() = 0.0;
  EXPECT_FALSE(t.IsValid(&error));
  EXPECT_EQ(error, "plate_size_m must be two finite sizes > 0");
}

TEST(RenderTarget, CentresAreTheProjectionsAndTheMarkersAreDark) {
  const CameraModel cam = TestCamera();
  const TargetLayout layout = TargetLayout::Thesis();
  const Pose3 pose = TargetPose(Overhead(), Eigen::Vector3d(0.05, -0.02, 0.4), 0.1);
  RenderOptions o;
  o.noise_sigma = 0.0;
  std::mt19937_64 rng(1);
  const RenderedFrame f = RenderTarget(cam, pose, layout, o, rng);
  ASSERT_EQ(f.image.type(), CV_8UC1);
  ASSERT_EQ(f.centres.size(), layout.markers.size());
  for (size_t k = 0; k < layout.markers.size(); ++k) {
    const Eigen::Vector3d X(layout.markers[k].x(), layout.markers[k].y(), 0.0);
    const Eigen::Vector2d uv = cam.Project(pose.R * X + pose.t);
    EXPECT_LT((uv - f.centres[k]).norm(), 1e-9) << k;
    const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
    EXPECT_LT(f.image.at<uint8_t>(v, u), 0.5 * (o.background + o.foreground)) << k;
  }
}

}  // namespace
}  // namespace kincal::vision
