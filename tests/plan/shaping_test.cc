// Control shaping: the controls for a wanted twist, for every model, and channels that
// slew together at their acceleration limits.
#include "plan/shaping.h"

#include <gtest/gtest.h>

namespace kincal::plan_internal {
namespace {

TEST(Shaping, TwistToControlsForEveryModel) {
  struct Case {
    const char* model;
    std::vector<double> p, max_abs;
  };
  const std::vector<Case> cases = {
      {"diffdrive", {0.03, 0.031, 0.3}, {30.0, 30.0}},
      {"unicycle", {1.1, 0.9}, {1.0, 3.0}},
      {"tricycle", {0.001, 0.02, 1e-4, 0.5}, {1000.0, 8000.0}},
  };
  for (const auto& c : cases) {
    const System sys = MakeSystem(c.model).value();
    const Eigen::VectorXd p = Eigen::Map<const Eigen::VectorXd>(c.p.data(), c.p.size());
    PlanOptions o;
    o.max_abs = c.max_abs;
    for (const auto& [v, w] :
         std::vector<std::pair<double, double>>{{0.3, 0.0}, {0.2, 0.4}, {-0.2, 0.3}}) {
      Values u{};
      ASSERT_TRUE(TwistToControls(sys, p, v, w, o, &u)) << c.model << " " << v << " " << w;
      const Eigen::Vector2d tw = TwistOf(sys, p, u);
      EXPECT_NEAR(tw.x(), v, 1e-6) << c.model;
      EXPECT_NEAR(tw.y(), w, 1e-6) << c.model;
    }
  }
  // Beyond the limits: the nearest the box allows, and false.
  const System dd = MakeSystem("diffdrive").value();
  PlanOptions o;
  o.max_abs = {10.0, 10.0};
  Values u{};
  EXPECT_FALSE(TwistToControls(dd, Eigen::Vector3d(0.03, 0.03, 0.3), 1.0, 0.0, o, &u));
  EXPECT_NEAR(u[0], 10.0, 1e-6);
  EXPECT_NEAR(u[1], 10.0, 1e-6);
}

// No channel steps by more than its acceleration limit allows between samples.
void ExpectSlewWithin(const ControlSignal& s, const PlanOptions& o) {
  for (int i = 1; i < static_cast<int>(s.size()); ++i) {
    const double dt = s.TimeAt(i) - s.TimeAt(i - 1);
    for (size_t c = 0; c < o.max_accel.size(); ++c) {
      EXPECT_LE(std::abs(s.ValuesAt(i)[c] - s.ValuesAt(i - 1)[c]), o.max_accel[c] * dt + 1e-9)
          << "channel " << c << " at " << s.TimeAt(i) << " s";
    }
  }
}

TEST(Shaping, ChannelsSlewTogetherAtTheirLimits) {
  PlanOptions o;
  o.control_rate_hz = 100.0;
  o.max_abs = {10.0, 10.0};
  o.max_accel = {20.0, 40.0};
  ControlSignal s(2, 0);
  Values u{};
  const Values to = {10.0, -10.0};
  AppendSlewed(&s, 0.0, 2.0, to, o, &u);
  // The slowest channel needs 0.5 s (10 at 20/s); the other moves 20 in the same 0.5 s.
  EXPECT_NEAR(s.At(0.25)[0], 5.0, 0.25);
  EXPECT_NEAR(s.At(0.25)[1], -5.0, 0.25);
  EXPECT_NEAR(s.At(0.6)[0], 10.0, 1e-9);
  EXPECT_NEAR(s.At(0.6)[1], -10.0, 1e-9);
  ExpectSlewWithin(s, o);
}

// A plan ends with a stop every channel can follow, not a step to zero: from (10, -5) at
// 20 and 40 per second, 0.5 s of ramp, then a sample at rest.
TEST(Shaping, AStopRampsEveryChannelToRestAtItsLimit) {
  PlanOptions o;
  o.control_rate_hz = 100.0;
  o.max_abs = {10.0, 10.0};
  o.max_accel = {20.0, 40.0};
  ControlSignal s(2, 0);
  Values u = {10.0, -5.0};
  s.Append(0, std::span<const double>(u.data(), 2));
  const double rest = AppendStop(&s, 1.0, o, &u);
  EXPECT_NEAR(rest, 1.5, 1e-9);
  EXPECT_EQ(u[0], 0.0);
  EXPECT_EQ(u[1], 0.0);
  EXPECT_NEAR(s.At(1.25)[0], 5.0, 0.25);
  EXPECT_EQ(s.At(rest)[0], 0.0);
  EXPECT_EQ(s.At(rest)[1], 0.0);
  ExpectSlewWithin(s, o);
}

// The longest stop is from the speed limits, the slowest channel's, rounded up to the
// control rate: 20 / 40 s and 2 / 3 s at 20 Hz: 0.7 s (0.667 rounded up); no acceleration
// limits, no ramp.
TEST(Shaping, TheLongestStopIsFromTheLimits) {
  PlanOptions o;
  o.control_rate_hz = 20.0;
  o.max_abs = {20.0, 2.0};
  o.max_accel = {40.0, 3.0};
  EXPECT_NEAR(LongestStopSeconds(o, 2), 0.7, 1e-12);
  o.max_accel = {40.0, 0.0};
  EXPECT_NEAR(LongestStopSeconds(o, 2), 0.5, 1e-12);
  o.max_accel.clear();
  EXPECT_EQ(LongestStopSeconds(o, 2), 0.0);
  // What AppendStop takes from the limits is never longer.
  o.max_accel = {40.0, 3.0};
  ControlSignal s(2, 0);
  Values u{};
  u[0] = 20.0;
  u[1] = -2.0;
  EXPECT_LE(AppendStop(&s, 0.0, o, &u), LongestStopSeconds(o, 2) + 1e-12);
}

}  // namespace
}  // namespace kincal::plan_internal
