// The thesis robot's look-up-table gains as nuisance parameters.
#include "sim/lookup_gain.h"

#include <gtest/gtest.h>

#include "kincal/system.h"

namespace kincal {
namespace {

TEST(LookupTableGain, ScalesEachWheelByItsSpeedBand) {
  const System bare = MakeSystem("diffdrive").value();
  const auto effect = MakeLookupTableGain(bare.model(), 3, 10.0);
  ASSERT_EQ(effect->num_params(), 6);
  EXPECT_EQ(effect->params()[0].name, "g_omega_l_0");
  EXPECT_EQ(effect->params()[5].name, "g_omega_r_2");
  const double p[6] = {0.01, 0.02, 0.03, -0.01, -0.02, -0.03};
  double u[2] = {5.0, -15.0};  // left band 0, right band 1 (by magnitude)
  effect->MapControls(p, u);
  EXPECT_DOUBLE_EQ(u[0], 5.0 * 1.01);
  EXPECT_DOUBLE_EQ(u[1], -15.0 * 0.98);
  double fast[2] = {45.0, 29.9};  // beyond the table: its last band
  effect->MapControls(p, fast);
  EXPECT_DOUBLE_EQ(fast[0], 45.0 * 1.03);
  EXPECT_DOUBLE_EQ(fast[1], 29.9 * 0.97);  // band 2
  EXPECT_THROW(MakeLookupTableGain(bare.model(), 0, 10.0), std::invalid_argument);
  EXPECT_THROW(MakeLookupTableGain(bare.model(), 2, 0.0), std::invalid_argument);
}

// Through System: the robot drives as the bare model with the band's gain on each wheel.
TEST(LookupTableGain, PropagatesAsScaledWheelRates) {
  const System bare = MakeSystem("diffdrive").value();
  const System with(bare.model_ptr(), {MakeLookupTableGain(bare.model(), 2, 10.0)});
  ControlSignal u(2, 0);
  const std::array<double, 2> c = {4.0, 12.0};
  u.Append(0, c);
  VecN<kMaxState> p(7);
  p << 0.031, 0.0313, 0.148, 0.02, 0.0, 0.0, -0.01;
  StateVec x = with.MakeState(0, 0, 0, p, u, 0.0);
  with.Propagate(x.data(), x.data(), 0.0, 2.0, u, static_cast<const double*>(nullptr));
  ControlSignal scaled(2, 0);
  const std::array<double, 2> s = {4.0 * 1.02, 12.0 * 0.99};
  scaled.Append(0, s);
  VecN<kMaxState> q(3);
  q << 0.031, 0.0313, 0.148;
  StateVec y = bare.MakeState(0, 0, 0, q, scaled, 0.0);
  bare.Propagate(y.data(), y.data(), 0.0, 2.0, scaled, static_cast<const double*>(nullptr));
  EXPECT_NEAR((x.head<3>() - y.head<3>()).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace kincal
