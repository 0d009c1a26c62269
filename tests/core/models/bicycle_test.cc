// bicycle: a car commanded by speed (m/s) and steering angle (rad), rear-axle reference.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "core/kinematics_test_util.h"
#include "kincal/effect.h"

namespace kincal {
namespace {

using testing::ArcPose;
using testing::PoseAfter;
using testing::TwistOf;

TEST(Bicycle, SpeedGainAndSteeringThroughGainAndOffset) {
  // k_v 0.9, k_steer 0.6, steer_offset 0.02 rad, wheelbase 0.33 m; v 2 m/s, steer 0.3 rad.
  const Twist<double> tw = TwistOf("bicycle", {0.9, 0.6, 0.02, 0.33}, {2.0, 0.3});
  const double v = 1.8, phi = 0.6 * 0.3 + 0.02;
  EXPECT_NEAR(tw.vx, v, 1e-12);  // the rear axle moves straight ahead: no cos(phi)
  EXPECT_EQ(tw.vy, 0.0);
  EXPECT_NEAR(tw.omega, v * std::tan(phi) / 0.33, 1e-12);
  EXPECT_GT(tw.omega, 0.0);  // positive steering turns left
}

TEST(Bicycle, OffsetAloneCurvesAndReversingTurnsTheOtherWay) {
  const Twist<double> fwd = TwistOf("bicycle", {1.0, 1.0, -0.03, 0.5}, {1.0, 0.0});
  EXPECT_NEAR(fwd.omega, std::tan(-0.03) / 0.5, 1e-12);
  const Twist<double> back = TwistOf("bicycle", {1.0, 1.0, -0.03, 0.5}, {-1.0, 0.0});
  EXPECT_NEAR(back.omega, -fwd.omega, 1e-15);
}

// A held command is a circle: the integrated pose is the closed-form arc (exact
// integration, not a small-step approximation).
TEST(Bicycle, HeldCommandIntegratesToTheClosedFormArc) {
  const System sys = MakeSystem("bicycle").value();
  const std::vector<double> p = {1.1, 0.8, 0.01, 0.33};
  const double v = 1.1 * 1.5, omega = v * std::tan(0.8 * 0.25 + 0.01) / 0.33;
  for (double t : {0.1, 1.0, 4.0}) {
    const Eigen::Vector3d got = PoseAfter(sys, p, {1.5, 0.25}, t);
    const Eigen::Vector3d want = ArcPose(v, 0.0, omega, t);
    EXPECT_NEAR(got.x(), want.x(), 1e-9) << t;
    EXPECT_NEAR(got.y(), want.y(), 1e-9) << t;
    EXPECT_NEAR(got.z(), want.z(), 1e-9) << t;
  }
}

// Every effect applies to it: the steering ones (backlash, dead band, a lag of the
// steering servo) as well as timing, slip, lever arm, gains and turn losses.
TEST(Bicycle, EveryEffectCombinesWithIt) {
  for (const std::string& e : EffectRegistry::Instance().Names()) {
    std::unique_ptr<System> sys;
    const Status s = MakeSystem("bicycle", {e}, {}, &sys);
    EXPECT_TRUE(s.ok()) << e << ": " << s.message();
  }
  std::unique_ptr<System> sys;
  ASSERT_TRUE(MakeSystem("bicycle", {"actuator_lag[steer]", "backlash"}, {}, &sys).ok());
  EXPECT_EQ(sys->num_params(), 4 + 2);
}

}  // namespace
}  // namespace kincal
