// The usual motions are what their names say: the square closes on itself with a lag in
// the robot (its corners are driven from a stop), the circles turn both ways and stay in,
// the thesis's runs are 99 segments.
#include <gtest/gtest.h>

#include <numbers>

#include "kincal/angles.h"
#include "kincal/plan/planner.h"

namespace kincal {
namespace {

TEST(UsualMotions, AreWhatTheirNamesSay) {
  const System sys = MakeSystem("diffdrive", {"actuator_lag"}).value();
  const Eigen::Vector4d p(0.03, 0.03, 0.3, 0.1);
  const Eigen::Matrix4d prior = Eigen::Vector4d(1e-6, 1e-6, 1e-4, 1e-2).asDiagonal();
  PlanOptions o;
  o.duration_s = 40.0;
  o.max_abs = {20.0, 20.0};
  o.max_accel = {40.0, 40.0};
  const auto ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  const std::vector<Motion> m = UsualMotions(sys, p, prior, *ws, o);
  ASSERT_EQ(m.size(), 4u);
  EXPECT_EQ(m[0].name, "square");
  EXPECT_EQ(m[3].name, "thesis 99 runs");
  EXPECT_EQ(m[3].segment_starts_s.size(), 99u);
  for (const auto& x : m) EXPECT_TRUE(x.stays_in) << x.name << " left at " << x.left_at_s;
  // The square: back near its start after every lap, heading a multiple of 2 pi.
  double closest = 1e9;
  for (size_t k = 8; k < m[0].path.size(); ++k) {
    const Eigen::Vector3d& q = m[0].path[k];
    if (std::abs(WrapAngle(q.z())) < 0.02) closest = std::min(closest, q.head<2>().norm());
  }
  EXPECT_LT(closest, 0.03);
  // The circles: the heading turns both ways.
  double most = 0.0, least = 0.0;
  double unwrapped = 0.0;
  for (size_t k = 1; k < m[1].path.size(); ++k) {
    unwrapped += WrapAngle(m[1].path[k].z() - m[1].path[k - 1].z());
    most = std::max(most, unwrapped);
    least = std::min(least, unwrapped);
  }
  EXPECT_GT(most, 2.0 * std::numbers::pi);
  EXPECT_LT(unwrapped, most - 2.0 * std::numbers::pi);
}

}  // namespace
}  // namespace kincal
