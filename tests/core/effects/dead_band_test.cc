// dead_band: commands inside +-band_<channel> give no motion; larger ones lose the band.
#include <gtest/gtest.h>

#include <cmath>

#include "core/kinematics_test_util.h"

namespace kincal {
namespace {

using testing::ArcPose;
using testing::PoseAfter;

TEST(DeadBand, SmallCommandsGiveNoMotionAndLargeOnesLoseTheBand) {
  const System sys = MakeSystem("unicycle", {"dead_band[v]"}).value();
  const std::vector<double> p = {1.0, 1.0, 0.1};
  EXPECT_EQ(PoseAfter(sys, p, {0.05, 0.0}, 2.0)[0], 0.0);
  EXPECT_NEAR(PoseAfter(sys, p, {0.3, 0.0}, 2.0)[0], 0.4, 1e-12);
  EXPECT_NEAR(PoseAfter(sys, p, {-0.3, 0.0}, 2.0)[0], -0.4, 1e-12);
}

}  // namespace
}  // namespace kincal
