// unicycle: commanded speed and turn rate scaled by k_v and k_omega.
#include <gtest/gtest.h>

#include "core/kinematics_test_util.h"

namespace kincal {
namespace {

using testing::TwistOf;

TEST(Unicycle, GainsScaleTheCommandedSpeedAndTurnRate) {
  const Twist<double> tw = TwistOf("unicycle", {0.9, 0.85}, {0.5, -1.2});
  EXPECT_NEAR(tw.vx, 0.45, 1e-12);
  EXPECT_EQ(tw.vy, 0.0);
  EXPECT_NEAR(tw.omega, -1.02, 1e-12);  // negative command: clockwise
}

TEST(Unicycle, PropagationFollowsTheArc) {
  const System sys = MakeSystem("unicycle").value();
  const Eigen::Vector3d pose = testing::PoseAfter(sys, {0.9, 0.85}, {0.5, 0.4}, 2.0);
  EXPECT_LT((pose - testing::ArcPose(0.45, 0.0, 0.34, 2.0)).norm(), 1e-12);
}

}  // namespace
}  // namespace kincal
