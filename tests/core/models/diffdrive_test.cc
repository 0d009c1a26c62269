// diffdrive: wheel rates to body twist, and a faster right wheel turns left.
#include <gtest/gtest.h>

#include "core/kinematics_test_util.h"

namespace kincal {
namespace {

using testing::TwistOf;

TEST(DiffDrive, WheelRatesGiveTheMeanSpeedAndTheTurnRateOverTheTrack) {
  // r_l 0.030, r_r 0.032, d 0.15 m; omega_l 10, omega_r 12 rad/s.
  const Twist<double> tw = TwistOf("diffdrive", {0.030, 0.032, 0.15}, {10.0, 12.0});
  EXPECT_NEAR(tw.vx, (0.30 + 0.384) / 2.0, 1e-12);
  EXPECT_EQ(tw.vy, 0.0);
  EXPECT_NEAR(tw.omega, (0.384 - 0.30) / 0.15, 1e-12);
  EXPECT_GT(tw.omega, 0.0);  // counter-clockwise
}

TEST(DiffDrive, OppositeWheelsTurnInPlace) {
  const Twist<double> tw = TwistOf("diffdrive", {0.03, 0.03, 0.15}, {-5.0, 5.0});
  EXPECT_NEAR(tw.vx, 0.0, 1e-15);
  EXPECT_NEAR(tw.omega, 2.0 * 0.15 / 0.15, 1e-12);
}

}  // namespace
}  // namespace kincal
