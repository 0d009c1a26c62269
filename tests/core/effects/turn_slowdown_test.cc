// turn_slowdown: forward speed divided by (1 + c_slow |omega|).
#include <gtest/gtest.h>

#include <cmath>

#include "core/kinematics_test_util.h"

namespace kincal {
namespace {

using testing::ArcPose;
using testing::PoseAfter;

TEST(TurnSlowdown, TurningDividesTheForwardSpeed) {
  const System sys = MakeSystem("unicycle", {"turn_slowdown"}).value();
  // k_v 1, k_omega 1, c_slow 0.4 s/rad; 1 m/s while turning at 0.5 rad/s.
  const Eigen::Vector3d pose = PoseAfter(sys, {1.0, 1.0, 0.4}, {1.0, 0.5}, 2.0);
  EXPECT_LT((pose - ArcPose(1.0 / 1.2, 0.0, 0.5, 2.0)).norm(), 1e-12);
  // Left and right turns lose the same speed.
  const Eigen::Vector3d right = PoseAfter(sys, {1.0, 1.0, 0.4}, {1.0, -0.5}, 2.0);
  EXPECT_LT((right - ArcPose(1.0 / 1.2, 0.0, -0.5, 2.0)).norm(), 1e-12);
}

TEST(TurnSlowdown, StraightDrivingIsUnchanged) {
  const System sys = MakeSystem("unicycle", {"turn_slowdown"}).value();
  EXPECT_NEAR(PoseAfter(sys, {0.9, 1.0, 0.4}, {1.0, 0.0}, 2.0)[0], 1.8, 1e-12);
}

}  // namespace
}  // namespace kincal
