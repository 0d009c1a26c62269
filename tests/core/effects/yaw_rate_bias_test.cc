// yaw_rate_bias: a constant turn-rate offset while the robot moves.
#include <gtest/gtest.h>

#include <cmath>

#include "core/kinematics_test_util.h"

namespace kincal {
namespace {

using testing::ArcPose;
using testing::PoseAfter;

TEST(YawRateBias, MovingStraightCurvesByTheBias) {
  const System sys = MakeSystem("unicycle", {"yaw_rate_bias"}).value();
  const Eigen::Vector3d pose = PoseAfter(sys, {1.0, 1.0, 0.02}, {1.0, 0.0}, 2.0);
  EXPECT_LT((pose - ArcPose(1.0, 0.0, 0.02, 2.0)).norm(), 1e-12);
}

TEST(YawRateBias, StandingStillDoesNotTurn) {
  const System sys = MakeSystem("unicycle", {"yaw_rate_bias"}).value();
  EXPECT_EQ(PoseAfter(sys, {1.0, 1.0, 0.02}, {0.0, 0.0}, 2.0).norm(), 0.0);
}

}  // namespace
}  // namespace kincal
