// Workspaces: the arena's rectangle, and a camera's view checked against the thesis
// scenario's own in-view test on the same camera and plate.
#include "kincal/plan/workspace.h"

#include <gtest/gtest.h>

#include <random>

#include "kincal/sim/thesis_vision.h"

namespace kincal {
namespace {

TEST(Workspace, ArenaIsItsRectangle) {
  const auto a = MakeArena(-1.0, -0.5, 2.0, 1.5);
  EXPECT_TRUE(a->Contains(Eigen::Vector3d(0.0, 0.0, 3.0)));
  EXPECT_TRUE(a->Contains(Eigen::Vector3d(2.0, 1.5, 0.0)));
  EXPECT_FALSE(a->Contains(Eigen::Vector3d(2.01, 0.0, 0.0)));
  EXPECT_FALSE(a->Contains(Eigen::Vector3d(0.0, -0.51, 0.0)));
  EXPECT_TRUE(a->Centre().isApprox(Eigen::Vector2d(0.5, 0.5)));
  EXPECT_DOUBLE_EQ(a->Size(), 2.0);
}

// The thesis's tilted, distorted camera: the view agrees with PlateInView (which checks
// the plate's corners; the view checks the markers, which lie inside the plate) wherever
// the plate is in view, and the centre is in view.
TEST(Workspace, CameraViewAgreesWithTheThesisInViewTest) {
  const ThesisVision v = ThesisTable63Vision();
  const auto ws = MakeCameraView(v.camera, v.floor, v.layout, v.target_height_m, 6.0);
  const Eigen::Vector2d c = ws->Centre();
  EXPECT_TRUE(ws->Contains(Eigen::Vector3d(c.x(), c.y(), 0.0)));
  EXPECT_GT(ws->Size(), 0.3);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> pos(-1.5, 1.5), ang(-3.14, 3.14);
  int plate_in = 0, both = 0, view_in = 0;
  for (int k = 0; k < 4000; ++k) {
    const Eigen::Vector3d p(pos(rng), pos(rng), ang(rng));
    const bool plate = PlateInView(v, p, 6.0), view = ws->Contains(p);
    plate_in += plate ? 1 : 0;
    view_in += view ? 1 : 0;
    both += plate && view ? 1 : 0;
  }
  EXPECT_GT(plate_in, 100);
  EXPECT_EQ(both, plate_in) << "a plate in view has its markers in view";
  EXPECT_LT(view_in, plate_in * 3 / 2) << "and the markers' view is not much larger";
}

}  // namespace
}  // namespace kincal
