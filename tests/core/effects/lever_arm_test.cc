// lever_arm: the target sits at (dx, dy, dtheta) in the robot frame.
#include <gtest/gtest.h>

#include <array>
#include <cmath>

#include "kincal/system.h"

namespace kincal {
namespace {

TEST(LeverArm, MovesTheMeasuredPoint) {
  const System sys = MakeSystem("unicycle", {"lever_arm"}).value();
  StateVec x(sys.state_dim());
  x << 1.0, 2.0, M_PI / 2, 1.0, 1.0, 0.1, 0.02, 0.05;
  double z[3];
  sys.Measure(x.data(), z);
  EXPECT_NEAR(z[0], 1.0 - 0.02, 1e-12);
  EXPECT_NEAR(z[1], 2.0 + 0.1, 1e-12);
  EXPECT_NEAR(z[2], M_PI / 2 + 0.05, 1e-12);
  StateVec back = x;
  back.head(3).setZero();
  sys.SetPoseFromMeasurement(z, back.data());
  EXPECT_NEAR((back - x).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace kincal
