// Designing on for the robots within the prior (src/plan/judged_design.cc): once the
// design point is at its targets, the robots short of theirs reach them sooner than by
// the greedy design for the design point, every robot within the prior kept inside.
#include "plan/judged_design.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "plan/plan_cases.h"

namespace kincal::plan_internal {
namespace {

struct JudgedCase : plan_testing::Issue34Command {
  std::vector<Values> grid = CandidateControls(sys, p, o);
  Eigen::VectorXd prior_sigma = prior.diagonal().cwiseSqrt();
  std::vector<Judge> judges = RobotsToJudge(sys, p, prior, o);

  // The greedy design up to the design point's targets.
  Design AtTargets() const {
    Design d = DesignAtStart(sys, p, prior, *ws, o);
    EXPECT_TRUE(DesignSegments(sys, *ws, o, grid, prior_sigma, 60, true, &d));
    EXPECT_LE(WorstTargetRatio(d.info.Covariance(), o), 1.0);
    return d;
  }

  // d's controls, then a stop and rest to the duration.
  ControlSignal Stopped(const Design& d) const {
    ControlSignal u = d.u;
    Values now = d.now;
    AppendStopAndRest(&u, d.t_s, o.duration_s, o, &now);
    return u;
  }

  // When judge j reaches the targets along d's controls then a stop (the test's own
  // evaluation: the sigma curve at j), or infinity.
  double ReachedBy(const Design& d, const Judge& j) const {
    Motion m;
    m.controls = Stopped(d);
    m.segment_starts_s = {0.0};
    EvaluateMotion(sys, j.params, prior, *ws, o, kCurveStepS, &m);
    return ReachedAt(m);
  }
};

// Issue 34's command: the greedy design to the targets (without the look-ahead and the
// seeds) leaves some robots at 3 sigma short of them; designed on for them, the slowest
// gets there far sooner than designed on for the design point alone, and every one of them
// is at its targets where the judged design stops. Measured: the slowest at 8.5 s against
// the greedy's 11.5 s (the left wheel's -3 sigma, 0.74x); with the candidates judged on
// their own segment only (no horizon), 10 s (0.87x), which the bound refuses.
TEST(JudgedDesign, TheRobotsShortOfTheTargetsReachThemSooner) {
  const JudgedCase c;
  ASSERT_EQ(c.judges.size(), 16u);
  const Design start = c.AtTargets();
  Design judged = start, greedy = start;
  const int designed = DesignForJudges(c.sys, c.prior, *c.ws, c.o, c.grid, c.judges, 40, &judged);
  ASSERT_GT(designed, 0);
  ASSERT_LT(designed, 40) << "the judges never all reached the targets";
  EXPECT_EQ(judged.chosen.size(), start.chosen.size() + static_cast<size_t>(designed));
  EXPECT_NEAR(judged.t_s, start.t_s + designed * c.o.segment_s, 1e-9);
  ASSERT_TRUE(DesignSegments(c.sys, *c.ws, c.o, c.grid, c.prior_sigma, 40, false, &greedy));
  double slowest_judged = 0.0, slowest_greedy = 0.0;
  for (const Judge& j : c.judges) {
    const double tj = c.ReachedBy(judged, j), tg = c.ReachedBy(greedy, j);
    std::cout << j.name << ": designed for the judges " << tj << " s, greedy " << tg << " s\n";
    EXPECT_LE(tj, judged.t_s + 1e-9) << j.name << " is not at the targets where it stops";
    slowest_judged = std::max(slowest_judged, tj);
    slowest_greedy = std::max(slowest_greedy, tg);
  }
  EXPECT_LT(slowest_judged, 0.8 * slowest_greedy);
  // The planner's rule holds along the judged segments and a stop after them.
  EXPECT_TRUE(EveryRobotStaysIn(c.sys, c.p, c.prior, *c.ws, c.o, c.Stopped(judged)));
}

// Nothing is designed before the design point's targets, without judges or without targets.
TEST(JudgedDesign, DesignsNothingBeforeTheTargetsOrWithoutJudges) {
  const JudgedCase c;
  Design d = DesignAtStart(c.sys, c.p, c.prior, *c.ws, c.o);
  EXPECT_EQ(DesignForJudges(c.sys, c.prior, *c.ws, c.o, c.grid, c.judges, 10, &d), 0);
  EXPECT_TRUE(d.chosen.empty());
  Design at = c.AtTargets();
  const size_t segments = at.chosen.size();
  EXPECT_EQ(DesignForJudges(c.sys, c.prior, *c.ws, c.o, c.grid, {}, 10, &at), 0);
  PlanOptions none = c.o;
  none.targets = Eigen::VectorXd();
  EXPECT_EQ(DesignForJudges(c.sys, c.prior, *c.ws, none, c.grid, c.judges, 10, &at), 0);
  EXPECT_EQ(at.chosen.size(), segments);
}

}  // namespace
}  // namespace kincal::plan_internal
