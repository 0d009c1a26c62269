// The greedy plan refined (src/plan/refine.cc).
#include "plan/refine.h"

#include <gtest/gtest.h>

#include "plan/plan_cases.h"

namespace kincal::plan_internal {
namespace {

struct RefineCase : plan_testing::UnicycleWithALag {
  RefineCase() : UnicycleWithALag(10.0) {}
};

double TimeOf(const RefineCase& c, const Workspace& ws, const ControlSignal& u) {
  Motion m;
  m.controls = u;
  m.segment_starts_s = {0.0};
  EvaluateMotion(c.sys, c.p, c.prior, ws, c.o, kCurveStepS, &m);
  return m.curve.time_to_target_s;
}

// The controls from segments' values: from rest, each value reached within its segment at
// the acceleration limits (these are in reach), then the stop, at rest at the duration.
TEST(Refine, SegmentsAreSlewedToAndTheMotionEndsAtRest) {
  RefineCase c;
  const std::vector<Values> segments = {{0.25, 0.0}, {0.5, 1.0}, {0.5, 0.0}};
  const ControlSignal u = ControlsOfSegments(segments, c.o, 2);
  EXPECT_LE(std::abs(u.ValuesAt(0)[0]), c.o.max_accel[0] / c.o.control_rate_hz + 1e-12);
  for (size_t k = 0; k < segments.size(); ++k) {
    const double end = static_cast<double>(k + 1) * c.o.segment_s;
    EXPECT_EQ(u.At(end - 1e-6), segments[k]) << "segment " << k;
  }
  const int last = static_cast<int>(u.size()) - 1;
  EXPECT_NEAR(u.TimeAt(last), c.o.duration_s, 1e-9);
  EXPECT_EQ(u.ValuesAt(last), (Values{}));
  for (int i = 1; i <= last; ++i) {  // never faster than the acceleration limits
    const double dt = u.TimeAt(i) - u.TimeAt(i - 1);
    for (size_t ch = 0; ch < 2; ++ch) {
      EXPECT_LE(std::abs(u.ValuesAt(i)[ch] - u.ValuesAt(i - 1)[ch]),
                c.o.max_accel[ch] * std::max(dt, 1.0 / c.o.control_rate_hz) + 1e-9);
    }
  }
}

// Refining never makes the plan slower, keeps every robot within the prior inside (the
// segments it returns, cut to those its last pass checked, and a stop), and here finds a
// faster one; without targets it does nothing.
TEST(Refine, NeverSlowerAlwaysInside) {
  RefineCase c;
  const auto ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  const std::vector<Values> grid = CandidateControls(c.sys, c.p, c.o);
  // A poor start that stays inside: slowly back and forth, turning a little.
  std::vector<Values> segments(15, Values{});
  for (size_t k = 0; k < segments.size(); ++k) segments[k] = {k % 4 < 2 ? 0.2 : -0.2, 0.5};
  ASSERT_TRUE(
      EveryRobotStaysIn(c.sys, c.p, c.prior, *ws, c.o, ControlsOfSegments(segments, c.o, 2)));
  const double before = TimeOf(c, *ws, ControlsOfSegments(segments, c.o, 2));
  const int kept = RefineSegments(c.sys, c.p, c.prior, *ws, c.o, grid, 3, &segments);
  const ControlSignal u = ControlsOfSegments(segments, c.o, 2);
  const double after = TimeOf(c, *ws, u);
  EXPECT_GT(kept, 0);
  EXPECT_TRUE(EveryRobotStaysIn(c.sys, c.p, c.prior, *ws, c.o, u));
  EXPECT_LT(after, 0.8 * before) << before << " s -> " << after << " s";
  std::cout << "refined: " << before << " s -> " << after << " s, " << kept << " changes\n";
  PlanOptions none = c.o;
  none.targets = Eigen::VectorXd();
  std::vector<Values> same = segments;
  EXPECT_EQ(RefineSegments(c.sys, c.p, c.prior, *ws, none, grid, 3, &same), 0);
  EXPECT_EQ(same, segments);
}

// A segment that adds nothing (the robot at rest before a greedy design) is dropped: what
// follows comes a segment sooner, and the targets are reached that much sooner. With no
// value to try, no segment's value is changed and the drop alone acts.
TEST(Refine, ASegmentThatAddsNothingIsDropped) {
  RefineCase c;
  const auto ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  const std::vector<Values> grid = CandidateControls(c.sys, c.p, c.o);
  Design d = DesignAtStart(c.sys, c.p, c.prior, *ws, c.o);
  ASSERT_TRUE(DesignSegments(c.sys, *ws, c.o, grid, c.prior.diagonal().cwiseSqrt(), 16, true, &d));
  std::vector<Values> segments = {Values{0.0, 0.0}};
  segments.insert(segments.end(), d.chosen.begin(), d.chosen.end());
  const double before = TimeOf(c, *ws, ControlsOfSegments(segments, c.o, 2));
  const double designed = TimeOf(c, *ws, ControlsOfSegments(d.chosen, c.o, 2));
  ASSERT_NEAR(before, designed + c.o.segment_s, kCurveStepS + 1e-9);
  EXPECT_EQ(RefineSegments(c.sys, c.p, c.prior, *ws, c.o, {}, 1, &segments), 1);
  EXPECT_EQ(segments, d.chosen);
  EXPECT_DOUBLE_EQ(TimeOf(c, *ws, ControlsOfSegments(segments, c.o, 2)), designed);
}

// The soonest of the greedy designs under each criterion, each refined: no later than any
// of them, and every robot within the prior inside along it and a stop after it.
TEST(Refine, DesignSoonestIsNoLaterThanAnyCriterionsDesign) {
  RefineCase c;
  const auto ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  const std::vector<Values> grid = CandidateControls(c.sys, c.p, c.o);
  const Eigen::VectorXd prior_sigma = c.prior.diagonal().cwiseSqrt();
  double each = 1e9;
  for (DesignCriterion k : {DesignCriterion::kTargets, DesignCriterion::kD, DesignCriterion::kA}) {
    PlanOptions o = c.o;
    o.criterion = k;
    Design d = DesignAtStart(c.sys, c.p, c.prior, *ws, o);
    ASSERT_TRUE(DesignSegments(c.sys, *ws, o, grid, prior_sigma, 19, true, &d));
    each = std::min(each, TimeOf(c, *ws, ControlsOfSegments(d.chosen, c.o, 2)));
  }
  Design d = DesignAtStart(c.sys, c.p, c.prior, *ws, c.o);
  ASSERT_TRUE(DesignSegments(c.sys, *ws, c.o, grid, prior_sigma, 19, true, &d));
  DesignSoonest(c.sys, c.p, c.prior, *ws, c.o, grid, &d);
  const ControlSignal u = ControlsOfSegments(d.chosen, c.o, 2);
  const double soonest = TimeOf(c, *ws, u);
  std::cout << "soonest " << soonest << " s, the best criterion's greedy " << each << " s\n";
  EXPECT_LE(soonest, each);
  EXPECT_NEAR(d.t_s, static_cast<double>(d.chosen.size()) * c.o.segment_s, 1e-9);
  EXPECT_TRUE(EveryRobotStaysIn(c.sys, c.p, c.prior, *ws, c.o, u));
}

}  // namespace
}  // namespace kincal::plan_internal
