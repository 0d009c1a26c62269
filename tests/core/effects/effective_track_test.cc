// effective_track: turn rate divided by (1 + c_track |omega|).
#include <gtest/gtest.h>

#include <cmath>

#include "core/kinematics_test_util.h"

namespace kincal {
namespace {

using testing::ArcPose;
using testing::PoseAfter;

TEST(EffectiveTrack, FastTurnsAreSlowed) {
  const System sys = MakeSystem("unicycle", {"effective_track"}).value();
  const Eigen::Vector3d pose = PoseAfter(sys, {1.0, 1.0, 0.4}, {1.0, 0.5}, 2.0);
  EXPECT_LT((pose - ArcPose(1.0, 0.0, 0.5 / 1.2, 2.0)).norm(), 1e-12);
  const Eigen::Vector3d in_place = PoseAfter(sys, {1.0, 1.0, 0.4}, {0.0, -2.0}, 1.0);
  EXPECT_NEAR(in_place[2], -2.0 / 1.8, 1e-12);
}

}  // namespace
}  // namespace kincal
