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
  const std::vector<Motion> all = UsualMotions(sys, p, prior, *ws, o);
  // Each family's best that keeps every robot within the prior inside (and, when better,
  // its best at the design point only), then the thesis's runs.
  auto family = [&](const std::string& name) {
    const Motion* kept = nullptr;
    for (const auto& x : all) {
      if (x.name.rfind(name + " (", 0) == 0 && x.every_robot_stays_in) kept = &x;
    }
    EXPECT_NE(kept, nullptr) << name;
    return kept;
  };
  const Motion* square = family("square");
  const Motion* circles = family("circle each way");
  ASSERT_NE(family("figure-eight"), nullptr);
  ASSERT_NE(square, nullptr);
  ASSERT_NE(circles, nullptr);
  EXPECT_LE(all.size(), 7u);
  EXPECT_EQ(all.back().name, "thesis 99 runs");
  EXPECT_EQ(all.back().segment_starts_s.size(), 99u);
  for (const auto& x : all) {
    EXPECT_TRUE(x.stays_in) << x.name << " left at " << x.left_at_s;
    if (x.every_robot_stays_in && x.segment_starts_s.size() == 1) {
      EXPECT_TRUE(EveryRobotStaysIn(sys, p, prior, *ws, o, x.controls)) << x.name;
    }
    // At rest by the duration: the last sample at it, zero.
    const int last = static_cast<int>(x.controls.size()) - 1;
    EXPECT_NEAR(x.controls.TimeAt(last), o.duration_s, 1e-9) << x.name;
    for (double u : x.controls.ValuesAt(last)) EXPECT_EQ(u, 0.0) << x.name;
  }
  const std::vector<Motion> m = {*square, *circles};
  // The square: back near its start after every lap, heading a multiple of 2 pi.
  double closest = 1e9;
  for (size_t k = 8; k < m[0].path.size(); ++k) {
    const Eigen::Vector3d& q = m[0].path[k];
    if (std::abs(WrapAngle(q.z())) < 0.02) closest = std::min(closest, q.head<2>().norm());
  }
  EXPECT_LT(closest, 0.03);
  // The circles: the heading turns both ways, at least a full turn each (less the few
  // hundredths of a turn the lag and the ramps take from a single lap): up by a turn, and
  // somewhere down by a turn from the highest heading before.
  double most = 0.0, fall = 0.0;
  double unwrapped = 0.0;
  for (size_t k = 1; k < m[1].path.size(); ++k) {
    unwrapped += WrapAngle(m[1].path[k].z() - m[1].path[k - 1].z());
    most = std::max(most, unwrapped);
    fall = std::max(fall, most - unwrapped);
  }
  const double turn = 0.95 * 2.0 * std::numbers::pi;
  EXPECT_GT(most, turn);
  EXPECT_GT(fall, turn);
}

}  // namespace
}  // namespace kincal
