// The one floor-pose solver: both methods recover rendered poses, a misplaced centre or an
// unidentified marker is refused, and bad options are named.
#include "kincal/vision/floor_pose_solver.h"

#include <gtest/gtest.h>

#include <random>

#include "kincal/angles.h"
#include "kincal/vision/markers.h"
#include "kincal/vision/target.h"
#include "vision/vision_test_util.h"

namespace kincal::vision {
namespace {

using namespace test_util;

constexpr double kHeight = 0.1;

// Identified markers of the thesis target rendered at q (noise as the renderer's default).
std::vector<Marker> Rendered(const CameraModel& cam, const TargetLayout& layout,
                             const FloorExtrinsics& floor, const Eigen::Vector3d& q,
                             std::mt19937_64& rng) {
  const RenderedFrame fr = RenderTarget(cam, TargetPose(floor, q, kHeight), layout, {}, rng);
  MarkerTracker tracker(cam, layout, DetectorOptions{});
  return tracker.Track(fr.image);
}

class FloorPoseSolverTest : public ::testing::TestWithParam<FloorPoseMethod> {};

TEST_P(FloorPoseSolverTest, RecoversRenderedPosesWithinTheirCovariance) {
  const CameraModel cam = TestCamera();
  const TargetLayout layout = TargetLayout::Thesis();
  const FloorExtrinsics floor = Overhead();
  FloorPoseSolverOptions o;
  o.method = GetParam();
  o.sigma_px = 0.05;
  o.max_rms_px = 1.0;
  FloorPoseSolver solver(cam, floor, layout, kHeight, o);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> U(-0.25, 0.25);
  Eigen::Vector3d previous;
  bool have_previous = false;
  for (int f = 0; f < 12; ++f) {
    const Eigen::Vector3d q = Draw3(U, rng, 12);
    const auto markers = Rendered(cam, layout, floor, q, rng);
    ASSERT_EQ(markers.size(), layout.markers.size()) << "frame " << f;
    PlanarPose p;
    ASSERT_TRUE(solver.Solve(markers, have_previous ? &previous : nullptr, &p)) << "frame " << f;
    Eigen::Vector3d e = p.xytheta - q;
    e.z() = WrapAngle(e.z());
    EXPECT_LT(e.head<2>().norm(), 1e-3) << "frame " << f;
    EXPECT_LT(std::abs(e.z()), 5e-3) << "frame " << f;
    EXPECT_LT(p.rms_px, 0.5);
    EXPECT_TRUE(p.covariance.allFinite());
    previous = p.xytheta;
    have_previous = true;
  }
}

TEST_P(FloorPoseSolverTest, RefusesAMisplacedCentreAndAnUnidentifiedMarker) {
  const CameraModel cam = TestCamera();
  const TargetLayout layout = TargetLayout::Thesis();
  const FloorExtrinsics floor = Overhead();
  std::mt19937_64 rng(4);
  auto markers = Rendered(cam, layout, floor, Eigen::Vector3d(0.05, -0.03, 0.4), rng);
  ASSERT_EQ(markers.size(), 4u);
  FloorPoseSolverOptions by_rms;
  by_rms.method = GetParam();
  by_rms.max_rms_px = 1.0;
  FloorPoseSolverOptions by_chi2 = by_rms;
  by_chi2.max_rms_px = std::numeric_limits<double>::infinity();
  by_chi2.sigma_px = 0.1;
  by_chi2.max_chi2 = 13.8;
  PlanarPose p;
  for (const auto& o : {by_rms, by_chi2}) {
    FloorPoseSolver solver(cam, floor, layout, kHeight, o);
    EXPECT_TRUE(solver.Solve(markers, nullptr, &p));
    auto moved = markers;
    moved[1].centre_px += Eigen::Vector2d(6.0, -4.0);  // a blob taken for the marker
    EXPECT_FALSE(solver.Solve(moved, nullptr, &p));
    auto unknown = markers;
    unknown[2].id = -1;
    EXPECT_FALSE(solver.Solve(unknown, nullptr, &p));
    unknown[2].id = 7;  // beyond the layout
    EXPECT_FALSE(solver.Solve(unknown, nullptr, &p));
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, FloorPoseSolverTest,
                         ::testing::Values(FloorPoseMethod::kLowe, FloorPoseMethod::kGroundPlane),
                         [](const auto& info) {
                           return info.param == FloorPoseMethod::kLowe ? "Lowe" : "GroundPlane";
                         });

TEST(FloorPoseSolverOptions, BadValuesAreNamed) {
  std::string error;
  FloorPoseSolverOptions o;
  EXPECT_TRUE(o.IsValid(&error)) << error;
  o.sigma_px = 0.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("sigma_px"), std::string::npos) << error;
  o = FloorPoseSolverOptions{};
  o.max_chi2 = -1.0;
  EXPECT_FALSE(o.IsValid(&error));
  EXPECT_NE(error.find("max_chi2"), std::string::npos) << error;
}

}  // namespace
}  // namespace kincal::vision
