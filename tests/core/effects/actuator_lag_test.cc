// actuator_lag: a first-order response with time constant tau_s, integrated exactly.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "kincal/system.h"

namespace kincal {
namespace {

TEST(ActuatorLag, FollowsFirstOrderResponseExactly) {
  const System sys = MakeSystem("unicycle", {"actuator_lag[v]"}).value();
  ControlSignal u(2, 0);
  const std::array<double, 2> go = {1.0, 0.0};
  u.Append(SecondsToNs(1.0), go);
  VecN<kMaxState> p(3);
  const double tau = 0.25, kv = 0.9;
  p << kv, 1.0, tau;
  StateVec x = sys.MakeState(0, 0, 0, p, u, 0.0);
  EXPECT_EQ(x[6], 0.0);  // lag state at rest before the command
  for (double t : {1.1, 1.25, 2.0}) {
    StateVec out(x.size());
    sys.Propagate(x.data(), out.data(), 0.0, t, u, static_cast<const double*>(nullptr));
    const double s = t - 1.0;
    EXPECT_NEAR(out[0], kv * (s - tau * (1.0 - std::exp(-s / tau))), 1e-12) << t;
    EXPECT_NEAR(out[6], 1.0 - std::exp(-s / tau), 1e-12) << t;
  }
}

}  // namespace
}  // namespace kincal
