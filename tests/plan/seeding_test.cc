// The greedy design seeded with the usual motions (src/plan/seeding.cc).
#include "plan/seeding.h"

#include <gtest/gtest.h>

#include <cmath>

#include "plan/plan_cases.h"

namespace kincal::plan_internal {
namespace {

struct SeedCase : plan_testing::UnicycleWithALag {
  SeedCase() : UnicycleWithALag(20.0) {}
};

// A plan that never reaches the targets (the robot at rest) is replaced by a usual motion's
// start designed on: it reaches them no later than the best usual motion every robot within
// the prior survives, keeps every robot inside and is at rest by the duration; a plan no
// seed beats is kept; without targets nothing is done.
TEST(Seeding, AUsualMotionsStartDesignedOnBeatsAPoorPlan) {
  const SeedCase c;
  const std::vector<Values> grid = CandidateControls(c.sys, c.p, c.o);
  const std::vector<Motion> usual = UsualMotions(c.sys, c.p, c.prior, *c.ws, c.o);
  double admissible = 1e9;
  for (const Motion& m : usual) {
    if (m.every_robot_stays_in && m.segment_starts_s.size() == 1 && !m.curve.extrapolated) {
      admissible = std::min(admissible, m.curve.time_to_target_s);
    }
  }
  ASSERT_LT(admissible, 1e9);
  Motion rest;
  rest.name = "plan";
  rest.controls = ControlSignal(2, 0);
  rest.segment_starts_s = {0.0};
  AppendRest(&rest.controls, c.o.duration_s);
  EvaluateMotion(c.sys, c.p, c.prior, *c.ws, c.o, kCurveStepS, &rest);
  Motion plan = rest;
  ASSERT_TRUE(SeedWithUsual(c.sys, c.p, c.prior, *c.ws, c.o, grid, usual, {}, &plan));
  std::cout << plan.name << ": " << plan.curve.time_to_target_s << " s (best admissible usual "
            << admissible << " s)\n";
  EXPECT_NE(plan.name.find("then designed"), std::string::npos) << plan.name;
  EXPECT_FALSE(plan.curve.extrapolated);
  EXPECT_LE(plan.curve.time_to_target_s, admissible);
  EXPECT_TRUE(EveryRobotStaysIn(c.sys, c.p, c.prior, *c.ws, c.o, plan.controls));
  const int last = static_cast<int>(plan.controls.size()) - 1;
  EXPECT_NEAR(plan.controls.TimeAt(last), c.o.duration_s, 1e-9);
  EXPECT_EQ(plan.controls.ValuesAt(last), (Values{}));
  // Now nothing beats it: kept.
  Motion again = plan;
  EXPECT_FALSE(SeedWithUsual(c.sys, c.p, c.prior, *c.ws, c.o, grid, usual, {}, &again));
  EXPECT_EQ(again.name, plan.name);
  PlanOptions none = c.o;
  none.targets = Eigen::VectorXd();
  Motion same = rest;
  EXPECT_FALSE(SeedWithUsual(c.sys, c.p, c.prior, *c.ws, none, grid, usual, {}, &same));
}

}  // namespace
}  // namespace kincal::plan_internal
