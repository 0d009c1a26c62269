// The usual motions are what their names say: the square closes on itself with a lag in
// the robot (its corners are driven from a stop), the circles turn both ways and stay in,
// the thesis's runs are 99 segments.
#include <gtest/gtest.h>

#include <iostream>
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

// A family's sizes start at the robot's own scale, not at a fraction of the workspace: on a
// floor of 100 x 100 m the best figure-eight is as small and nearly as fast as on 3 x 2 m
// (it was a fraction of the floor's size, and needed 32 s where 6.75 s will do).
TEST(UsualMotions, SizesStartAtTheRobotsScaleOnALargeFloor) {
  const System sys = MakeSystem("diffdrive", {"actuator_lag", "time_offset", "lever_arm"}).value();
  const Eigen::VectorXd p =
      (Eigen::VectorXd(8) << 0.03, 0.03, 0.3, 0.1, 0.0, 0.0, 0.0, 0.0).finished();
  const Eigen::MatrixXd prior =
      (Eigen::VectorXd(8) << 0.003, 0.003, 0.03, 0.1, 0.1, 0.05, 0.05, 0.05)
          .finished()
          .cwiseAbs2()
          .asDiagonal();
  PlanOptions o;
  o.duration_s = 20.0;
  o.max_abs = {20.0, 20.0};
  o.max_accel = {40.0, 40.0};
  o.targets = (Eigen::VectorXd(8) << 3e-5, 3e-5, 3e-4, 3e-3, 3e-3, 2e-3, 2e-3, 0.0).finished();
  o.care = {0, 1, 2, 3, 4, 5, 6};
  auto eight = [&](const Workspace& ws) {
    for (const Motion& m : UsualMotions(sys, p, prior, ws, o)) {
      if (m.name.rfind("figure-eight (", 0) == 0) return m.curve.time_to_target_s;
    }
    return 1e9;
  };
  const double small = eight(*MakeArena(-1.5, -1.0, 1.5, 1.0));
  const double large = eight(*MakeArena(-50.0, -50.0, 50.0, 50.0));
  std::cout << "best figure-eight: " << small << " s on 3 x 2 m, " << large
            << " s on 100 x 100 m\n";
  EXPECT_LE(small, 7.0);
  EXPECT_LE(large, 1.2 * small);
}

// Wheel limits of 10^9 rad/s (a typo, or a unit mixed up) once had loops a micrometre
// across drawn as pieces shorter than a control period: tens of millions of samples,
// 17 GB and minutes. Every motion now has about the samples its duration holds (a piece's
// or a run's edges add one each: the thesis's 99 runs, 298 for 200 periods).
TEST(UsualMotions, AbsurdLimitsGiveNoMoreSamplesThanTheDurationHolds) {
  const System sys = MakeSystem("diffdrive").value();
  const Eigen::Vector3d p(0.033, 0.033, 0.3);
  const Eigen::Matrix3d prior = Eigen::Vector3d(3e-6, 3e-6, 1e-4).asDiagonal();
  PlanOptions o;
  o.duration_s = 10.0;
  o.max_abs = {1e9, 1e9};
  const auto ws = MakeArena(-1.0, -1.0, 1.0, 1.0);
  const std::vector<Motion> all = UsualMotions(sys, p, prior, *ws, o);
  EXPECT_FALSE(all.empty());
  const double most = 2.0 * o.duration_s * o.control_rate_hz;
  for (const Motion& m : all) EXPECT_LE(static_cast<double>(m.controls.size()), most) << m.name;
}

}  // namespace
}  // namespace kincal
