// asymmetric_gain: a channel's gain is 1 + asym for positive commands, 1 - asym for negative.
#include <gtest/gtest.h>

#include <cmath>

#include "core/kinematics_test_util.h"

namespace kincal {
namespace {

using testing::ArcPose;
using testing::PoseAfter;

TEST(AsymmetricGain, ForwardAndBackwardGainsDiffer) {
  const System sys = MakeSystem("unicycle", {"asymmetric_gain[v]"}).value();
  const std::vector<double> p = {0.9, 0.85, 0.04};
  EXPECT_NEAR(PoseAfter(sys, p, {0.5, 0.0}, 1.0)[0], 0.9 * 0.5 * 1.04, 1e-12);
  EXPECT_NEAR(PoseAfter(sys, p, {-0.5, 0.0}, 1.0)[0], -0.9 * 0.5 * 0.96, 1e-12);
  // The turn channel is not listed: its gain is symmetric.
  EXPECT_NEAR(PoseAfter(sys, p, {0.0, -1.0}, 1.0)[2], -0.85, 1e-12);
}

}  // namespace
}  // namespace kincal
