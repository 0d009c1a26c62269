// The plan judged at the robots within the prior (src/plan/within_prior.cc): which robots,
// the quickest usual motion's time at each, the plan's.
#include "plan/within_prior.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

#include "plan/plan_cases.h"
#include "plan/shaping.h"

namespace kincal::plan_internal {
namespace {

struct JudgeCase : plan_testing::UnicycleWithALag {
  std::vector<Motion> usual;
  JudgeCase() : UnicycleWithALag(20.0) { usual = UsualMotions(sys, p, prior, *ws, o); }
};

// The quickest admissible usual motion at robot q, each driven whole (the test's own
// reading of what a usual motion needs there).
double QuickestAt(const JudgeCase& c, const Eigen::VectorXd& q) {
  double best = std::numeric_limits<double>::infinity();
  for (const Motion& m : c.usual) {
    if (!m.every_robot_stays_in || !m.stays_in || m.segment_starts_s.size() != 1) continue;
    Motion at = m;
    if (!m.unstopped.empty()) at.controls = m.unstopped;
    EvaluateMotion(c.sys, q, c.prior, *c.ws, c.o, kCurveStepS, &at);
    if (!at.curve.extrapolated) best = std::min(best, at.curve.time_to_target_s);
  }
  return best;
}

// The robots within the prior of (p, prior, o), each timed with the case's usual motions.
std::vector<Judge> Judged(const JudgeCase& c, const Eigen::VectorXd& p,
                          const Eigen::MatrixXd& prior, const PlanOptions& o) {
  return JudgesWithinPrior(c.sys, RobotsToJudge(c.sys, p, prior, o), prior, *c.ws, o, c.usual);
}

std::set<std::string> Names(const std::vector<Judge>& judges) {
  std::set<std::string> out;
  for (const Judge& j : judges) out.insert(j.name);
  return out;
}

// The design point and the robots at +-3 sigma along each parameter, but the lag's -3
// sigma (-0.15 s: no robot); each with the quickest usual motion's time there.
TEST(WithinPrior, JudgesTheAxisRobotsWithinThePhysicalBounds) {
  const JudgeCase c;
  const std::vector<Judge> judges = Judged(c, c.p, c.prior, c.o);
  EXPECT_EQ(Names(judges),
            (std::set<std::string>{"the design point", "k_v +3 sigma", "k_v -3 sigma",
                                   "k_omega +3 sigma", "k_omega -3 sigma", "tau_s +3 sigma"}));
  // The same robots as RobotsToJudge's (every one is reached here), which leaves usual_s 0.
  const std::vector<Judge> robots = RobotsToJudge(c.sys, c.p, c.prior, c.o);
  EXPECT_EQ(Names(robots), Names(judges));
  for (const Judge& j : robots) EXPECT_EQ(j.usual_s, 0.0) << j.name;
  for (const Judge& j : judges) {
    const Eigen::VectorXd d = j.params - c.p;
    EXPECT_NEAR(d.norm(), j.name == "the design point" ? 0.0 : 0.3, 1e-12) << j.name;
    EXPECT_DOUBLE_EQ(j.usual_s, QuickestAt(c, j.params)) << j.name;
    EXPECT_GT(j.usual_s, 0.0) << j.name;
  }
  // The design point's is the quickest admissible usual motion's own time.
  double admissible = std::numeric_limits<double>::infinity();
  for (const Motion& m : c.usual) {
    if (m.every_robot_stays_in && m.segment_starts_s.size() == 1 && !m.curve.extrapolated) {
      admissible = std::min(admissible, m.curve.time_to_target_s);
    }
  }
  EXPECT_DOUBLE_EQ(judges[0].usual_s, admissible);
  PlanOptions none = c.o;
  none.targets = Eigen::VectorXd();
  EXPECT_TRUE(Judged(c, c.p, c.prior, none).empty());
}

// A parameter held (known) moves no robot; a correlated prior's axes are named as axes.
TEST(WithinPrior, HeldParametersMoveNoRobotAndCorrelatedAxesAreNamed) {
  const JudgeCase c;
  Eigen::VectorXd p = c.p;
  Eigen::MatrixXd prior = c.prior;
  PlanOptions o = c.o;
  ASSERT_TRUE(HoldParameters(c.sys, {{"k_omega", 1.0}}, &p, &prior, &o).ok());
  EXPECT_EQ(Names(Judged(c, p, prior, o)),
            (std::set<std::string>{"the design point", "k_v +3 sigma", "k_v -3 sigma",
                                   "tau_s +3 sigma"}));
  Eigen::MatrixXd correlated = c.prior;
  correlated(0, 1) = correlated(1, 0) = 0.008;
  const std::set<std::string> names = Names(Judged(c, c.p, correlated, c.o));
  EXPECT_EQ(names.count("tau_s +3 sigma"), 1u);
  EXPECT_EQ(names.count("k_v +3 sigma"), 0u);
  int axes = 0;
  for (const std::string& n : names) axes += n.starts_with("prior axis ");
  EXPECT_EQ(axes, 4);
}

// The plan driven by each judge: at the design point its own time; elsewhere what an
// evaluation at that robot gives; a plan that stays at rest reaches no target.
TEST(WithinPrior, JudgePlanDrivesThePlanByEachRobot) {
  const JudgeCase c;
  const std::vector<Judge> judges = Judged(c, c.p, c.prior, c.o);
  Motion plan;
  PlanOptions o = c.o;
  o.seed_with_usual = false;
  ASSERT_TRUE(PlanMotion(c.sys, c.p, c.prior, *c.ws, o, &plan).ok());
  EXPECT_TRUE(plan.within_prior.empty());
  JudgePlan(c.sys, c.prior, *c.ws, c.o, judges, &plan);
  ASSERT_EQ(plan.within_prior.size(), judges.size());
  for (size_t k = 0; k < judges.size(); ++k) {
    const PriorRobotTimes& t = plan.within_prior[k];
    EXPECT_EQ(t.robot, judges[k].name);
    EXPECT_EQ(t.usual_s, judges[k].usual_s);
    Motion at = plan;
    EvaluateMotion(c.sys, judges[k].params, c.prior, *c.ws, c.o, kCurveStepS, &at);
    EXPECT_DOUBLE_EQ(t.plan_s, at.curve.time_to_target_s) << t.robot;
    if (k == 0) {
      EXPECT_DOUBLE_EQ(t.plan_s, plan.curve.time_to_target_s);
    }
  }
  Motion rest;
  rest.controls = ControlSignal(2, 0);
  AppendRest(&rest.controls, c.o.duration_s);
  JudgePlan(c.sys, c.prior, *c.ws, c.o, judges, &rest);
  for (const PriorRobotTimes& t : rest.within_prior) EXPECT_TRUE(std::isinf(t.plan_s)) << t.robot;
}

}  // namespace
}  // namespace kincal::plan_internal
