// time_offset: the robot acts on the command delay_s seconds late.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "kincal/system.h"

namespace kincal {
namespace {

TEST(TimeOffset, DelaysTheMotion) {
  const System sys = MakeSystem("unicycle", {"time_offset"}).value();
  ControlSignal u(2, 0);
  const std::array<double, 2> go = {1.0, 0.0};
  u.Append(SecondsToNs(1.0), go);
  VecN<kMaxState> p(3);
  p << 0.8, 1.0, 0.2;  // k_v, k_omega, delay_s
  StateVec x = sys.MakeState(0, 0, 0, p, u, 0.0);
  StateVec out(x.size());
  sys.Propagate(x.data(), out.data(), 0.0, 1.15, u, static_cast<const double*>(nullptr));
  EXPECT_EQ(out[0], 0.0);
  sys.Propagate(x.data(), out.data(), 0.0, 1.5, u, static_cast<const double*>(nullptr));
  EXPECT_NEAR(out[0], 0.8 * 0.3, 1e-12);
}

}  // namespace
}  // namespace kincal
