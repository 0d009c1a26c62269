// Greedy sequential design (src/plan/greedy.cc): up to the targets and no further, from a
// seed motion, and the largest sigma over its target.
#include "plan/greedy.h"

#include <gtest/gtest.h>

#include <cmath>

#include "plan/plan_cases.h"

namespace kincal::plan_internal {
namespace {

// A unicycle with a lag, planned for 20 s.
struct GreedyCase : plan_testing::UnicycleWithALag {
  GreedyCase() : UnicycleWithALag(20.0) {}
};

TEST(Greedy, WorstTargetRatioIsTheLargestScaledSigma) {
  PlanOptions o;
  o.targets = Eigen::Vector3d(1.0, 2.0, 0.0);  // the third has no target
  const Eigen::Matrix3d cov = Eigen::Vector3d(0.25, 9.0, 100.0).asDiagonal();
  EXPECT_DOUBLE_EQ(WorstTargetRatio(cov, o), 1.5);
  o.care = {0};
  EXPECT_DOUBLE_EQ(WorstTargetRatio(cov, o), 0.5);
  o.targets = Eigen::VectorXd();
  EXPECT_TRUE(std::isinf(WorstTargetRatio(cov, o)));
}

// Until the targets: segments are added while some sigma is above its target and not after;
// the design's information is that of its controls.
TEST(Greedy, DesignsUpToTheTargetsAndNoFurther) {
  const GreedyCase c;
  const std::vector<Values> grid = CandidateControls(c.sys, c.p, c.o);
  const Eigen::VectorXd prior_sigma = c.prior.diagonal().cwiseSqrt();
  Design d = DesignAtStart(c.sys, c.p, c.prior, *c.ws, c.o);
  ASSERT_TRUE(DesignSegments(c.sys, *c.ws, c.o, grid, prior_sigma, 40, true, &d));
  ASSERT_GT(d.chosen.size(), 1u);
  ASSERT_LT(d.chosen.size(), 40u);
  EXPECT_NEAR(d.t_s, static_cast<double>(d.chosen.size()) * c.o.segment_s, 1e-9);
  EXPECT_LE(WorstTargetRatio(d.info.Covariance(), c.o), 1.0);
  // One segment less had not reached them.
  Design shorter = DesignAtStart(c.sys, c.p, c.prior, *c.ws, c.o);
  ASSERT_TRUE(DesignSegments(c.sys, *c.ws, c.o, grid, prior_sigma,
                             static_cast<int>(d.chosen.size()) - 1, false, &shorter));
  EXPECT_GT(WorstTargetRatio(shorter.info.Covariance(), c.o), 1.0);
  EXPECT_EQ(shorter.chosen,
            std::vector<Values>(d.chosen.begin(), d.chosen.end() - 1));  // greedy: a prefix
  // Every robot within the prior inside along the design and a stop after it.
  ControlSignal u = d.u;
  Values now = d.now;
  AppendStopAndRest(&u, d.t_s, c.o.duration_s, c.o, &now);
  EXPECT_TRUE(EveryRobotStaysIn(c.sys, c.p, c.prior, *c.ws, c.o, u));
}

// From a seed: its controls driven to the seed's time, the design's information and values
// those of the seed there; a seed that takes a robot within the prior out is refused.
TEST(Greedy, DesignsOnFromASeedThatKeepsEveryRobotInside) {
  const GreedyCase c;
  ControlSignal seed(2, 0);
  Values now{};
  AppendSlewed(&seed, 0.0, 3.0, Values{0.3, 1.0}, c.o, &now);
  Design d = DesignAtStart(c.sys, c.p, c.prior, *c.ws, c.o);
  ASSERT_TRUE(DesignFromSeed(c.sys, *c.ws, c.o, seed, 2.0, &d));
  EXPECT_EQ(d.t_s, 2.0);
  EXPECT_EQ(d.now, seed.At(2.0));
  DesignInformation direct(c.sys, c.p, c.prior, c.o.info);
  direct.StartSegment(StartPose(*c.ws, c.o), 0.0, seed);
  direct.Advance(2.0, seed);
  EXPECT_TRUE(d.info.Covariance().isApprox(direct.Covariance(), 1e-9));
  // Straight on at full speed for 2.6 s and a stop, from the centre of a 3 m arena: 1.3 m
  // at the design point (inside), 1.7 m for the robot at 3 sigma of the speed scale.
  ControlSignal away(2, 0);
  now = Values{};
  AppendSlewed(&away, 0.0, 2.6, Values{0.5, 0.0}, c.o, &now);
  Motion driven;
  driven.controls = away;
  driven.segment_starts_s = {0.0};
  AppendStopAndRest(&driven.controls, 2.6, c.o.duration_s, c.o, &now);
  EvaluateMotion(c.sys, c.p, c.prior, *c.ws, c.o, kCurveStepS, &driven);
  EXPECT_TRUE(driven.stays_in);
  Design e = DesignAtStart(c.sys, c.p, c.prior, *c.ws, c.o);
  EXPECT_FALSE(DesignFromSeed(c.sys, *c.ws, c.o, away, 2.6, &e));
}

}  // namespace
}  // namespace kincal::plan_internal
