// lateral_slip: sideways velocity -c_slip * v * omega (outward in a turn).
#include <gtest/gtest.h>

#include <cmath>

#include "core/kinematics_test_util.h"

namespace kincal {
namespace {

using testing::ArcPose;
using testing::PoseAfter;

TEST(LateralSlip, TurningSlidesOutwards) {
  const System sys = MakeSystem("unicycle", {"lateral_slip"}).value();
  // 1 m/s at 0.5 rad/s with c_slip 0.01 s: 5 mm/s to the right, out of the left turn.
  const Eigen::Vector3d pose = PoseAfter(sys, {1.0, 1.0, 0.01}, {1.0, 0.5}, 2.0);
  EXPECT_LT((pose - ArcPose(1.0, -0.005, 0.5, 2.0)).norm(), 1e-12);
  const Eigen::Vector3d straight = PoseAfter(sys, {1.0, 1.0, 0.01}, {1.0, 0.0}, 2.0);
  EXPECT_NEAR(straight[1], 0.0, 1e-15);
}

}  // namespace
}  // namespace kincal
