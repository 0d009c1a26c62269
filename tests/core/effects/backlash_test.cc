// backlash: play in the steering linkage; the wheel follows only beyond half the play.
#include <gtest/gtest.h>

#include <cmath>

#include "core/kinematics_test_util.h"

namespace kincal {
namespace {

using testing::ArcPose;
using testing::PoseAfter;

TEST(Backlash, TheWheelLagsTheCommandByHalfThePlayAndHoldsInsideIt) {
  const System sys = MakeSystem("ackermann", {"backlash"}).value();
  // r_b 0.05 m, l 0.3 m, no steering offset, 0.04 rad of play; 10 rad/s.
  ControlSignal u(2, 0);
  const std::vector<double> c1 = {10.0, 0.2}, c2 = {10.0, 0.19}, c3 = {10.0, 0.1};
  u.Append(0, c1);
  u.Append(SecondsToNs(1.0), c2);
  u.Append(SecondsToNs(2.0), c3);
  VecN<kMaxState> p(4);
  p << 0.05, 0.3, 0.0, 0.04;
  const StateVec x = sys.MakeState(0, 0, 0, p, u, -1.0);
  const int s = sys.state_offset();
  EXPECT_EQ(x[s], 0.0);  // at rest with zero steering before t = 0
  StateVec out(x.size());
  sys.Propagate(x.data(), out.data(), 0.0, 0.9, u, static_cast<const double*>(nullptr));
  EXPECT_NEAR(out[s], 0.18, 1e-12);  // pushed to 0.2 against the play
  sys.Propagate(x.data(), out.data(), 0.0, 1.9, u, static_cast<const double*>(nullptr));
  EXPECT_NEAR(out[s], 0.18, 1e-12);  // 0.19 lies inside the play: the wheel stays
  sys.Propagate(x.data(), out.data(), 0.0, 2.9, u, static_cast<const double*>(nullptr));
  EXPECT_NEAR(out[s], 0.12, 1e-12);  // pulled back to 0.1 from the other side
  // The heading turns at the realised angle.
  StateVec a(x.size()), b(x.size());
  sys.Propagate(x.data(), a.data(), 0.0, 1.5, u, static_cast<const double*>(nullptr));
  sys.Propagate(x.data(), b.data(), 0.0, 1.9, u, static_cast<const double*>(nullptr));
  EXPECT_NEAR(b[2] - a[2], 0.4 * 0.5 * std::tan(0.18) / 0.3, 1e-9);
}

}  // namespace
}  // namespace kincal
