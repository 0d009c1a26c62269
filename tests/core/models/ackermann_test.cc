// ackermann: a driven rear wheel, a steered front axle with an offset.
#include <gtest/gtest.h>

#include <cmath>

#include "core/kinematics_test_util.h"

namespace kincal {
namespace {

using testing::TwistOf;

TEST(Ackermann, RearWheelSpeedAndBicycleTurnRate) {
  // r_b 0.05 m, l 0.3 m, steer_offset 0.02 rad; omega 10 rad/s, phi 0.2 rad.
  const Twist<double> tw = TwistOf("ackermann", {0.05, 0.3, 0.02}, {10.0, 0.2});
  EXPECT_NEAR(tw.vx, 0.5, 1e-12);  // R_B * omega, no cos(phi): the rear wheel drives
  EXPECT_NEAR(tw.omega, 0.5 * std::tan(0.22) / 0.3, 1e-12);
  EXPECT_GT(tw.omega, 0.0);  // positive steering turns left
}

TEST(Ackermann, SteeringOffsetAloneMakesItCurve) {
  const Twist<double> tw = TwistOf("ackermann", {0.05, 0.3, -0.03}, {10.0, 0.0});
  EXPECT_NEAR(tw.omega, 0.5 * std::tan(-0.03) / 0.3, 1e-12);
}

}  // namespace
}  // namespace kincal
