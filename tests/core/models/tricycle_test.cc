// tricycle: a driven, steered front wheel in encoder ticks.
#include <gtest/gtest.h>

#include <cmath>

#include "core/kinematics_test_util.h"

namespace kincal {
namespace {

using testing::TwistOf;

TEST(Tricycle, FrontWheelDrivesTheRearAxleMidpoint) {
  // k_steer 0.001 rad/tick, steer_offset 0.01 rad, k_drive 1e-4 m/tick, wheelbase 0.5 m.
  const Twist<double> tw = TwistOf("tricycle", {0.001, 0.01, 1e-4, 0.5}, {390.0, 5000.0});
  const double phi = 0.4, vf = 0.5;
  EXPECT_NEAR(tw.vx, vf * std::cos(phi), 1e-12);
  EXPECT_EQ(tw.vy, 0.0);
  EXPECT_NEAR(tw.omega, vf * std::sin(phi) / 0.5, 1e-12);
  EXPECT_GT(tw.omega, 0.0);  // positive steering turns left
}

}  // namespace
}  // namespace kincal
