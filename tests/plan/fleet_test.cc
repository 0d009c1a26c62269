// The prior's fleet and the two stay-in rules (src/plan/fleet.cc).
#include "plan/fleet.h"

#include <gtest/gtest.h>

namespace kincal::plan_internal {
namespace {

// A unicycle whose speed scale is known to 10 % (1 sigma), at the centre of a 2 x 2 m
// arena heading +x, driven at 0.25 m/s for 3 s: the design point ends 0.75 m out, the
// +3 sigma robot 0.975 m (inside), and the ellipsoid's extreme pose, a fifth beyond the
// axis robots' spread, 0.75 + 1.2 x 0.225 = 1.02 m (outside).
struct FleetCase {
  System sys = MakeSystem("unicycle").value();
  Eigen::VectorXd p = Eigen::Vector2d(1.0, 1.0);
  Eigen::MatrixXd prior = Eigen::Vector2d(0.01, 0.01).asDiagonal();
  PlanOptions o;
  std::unique_ptr<Workspace> ws = MakeArena(-1.0, -1.0, 1.0, 1.0);
  ControlSignal Drive(double v, double seconds) const {
    ControlSignal u(2, 0);
    u.Append(0, std::array<double, 2>{v, 0.0});
    u.Append(SecondsToNs(seconds), std::array<double, 2>{0.0, 0.0});
    return u;
  }
};

TEST(Fleet, TheRulesAgreeAtRestAndWhenEveryRobotLeaves) {
  const FleetCase c;
  const ControlSignal rest = c.Drive(0.0, 3.0);
  EXPECT_TRUE(FleetStaysInside(c.sys, c.p, c.prior, *c.ws, c.o, rest));
  EXPECT_TRUE(FleetStaysInside(c.sys, c.p, c.prior, *c.ws, c.o, rest, CornersInside));
  const ControlSignal out = c.Drive(0.5, 3.0);  // the design point alone ends 1.5 m out
  EXPECT_FALSE(FleetStaysInside(c.sys, c.p, c.prior, *c.ws, c.o, out));
  EXPECT_FALSE(FleetStaysInside(c.sys, c.p, c.prior, *c.ws, c.o, out, CornersInside));
}

TEST(Fleet, ThePlannersRuleKeepsTheEllipsoidNotOnlyItsCorners) {
  const FleetCase c;
  const ControlSignal u = c.Drive(0.25, 3.0);
  EXPECT_TRUE(FleetStaysInside(c.sys, c.p, c.prior, *c.ws, c.o, u, CornersInside));
  EXPECT_TRUE(EveryRobotStaysIn(c.sys, c.p, c.prior, *c.ws, c.o, u));
  EXPECT_FALSE(FleetStaysInside(c.sys, c.p, c.prior, *c.ws, c.o, u));
  // A shorter drive keeps the ellipsoid in too (0.6 + 1.2 x 0.18 = 0.82 m).
  EXPECT_TRUE(FleetStaysInside(c.sys, c.p, c.prior, *c.ws, c.o, c.Drive(0.2, 3.0)));
}

// The fleet: the design point and the robots at +-3 sigma along each axis of the prior.
TEST(Fleet, AtTheStartItIsTheDesignPointAndTheAxisRobots) {
  const FleetCase c;
  const Fleet f = FleetAtStart(c.sys, c.p, c.prior, Eigen::Vector3d::Zero(), c.o, c.Drive(0, 1));
  ASSERT_EQ(f.x.size(), 5u);
  EXPECT_EQ(f.t_s, 0.0);
}

}  // namespace
}  // namespace kincal::plan_internal
