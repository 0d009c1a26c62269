// Selection: the candidates are the registered effects that apply (per channel where an
// effect acts on one), and one candidate tried on a recording with a hidden delay is
// accepted with its value and a held-out gain, while a wrong one gains nothing.
#include "analysis/selection.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "analysis/analysis_test_util.h"
#include "analysis/evaluation.h"
#include "analysis/regressors.h"

namespace kincal::analysis {
namespace {

TEST(Selection, CandidatesAreTheEffectsThatApply) {
  AnalyzeOptions o;
  o.model = "unicycle";
  const auto c = Candidates(*MakeModel("unicycle"), o);
  auto has = [&](const std::string& s) { return std::find(c.begin(), c.end(), s) != c.end(); };
  EXPECT_TRUE(has("time_offset"));
  EXPECT_TRUE(has("turn_slowdown"));
  EXPECT_FALSE(has("backlash"));  // no steering channel
  EXPECT_TRUE(has("dead_band[v]") || has("dead_band"));
  o.effects_mode = "none";
  EXPECT_TRUE(Candidates(*MakeModel("unicycle"), o).empty());
  o.effects_mode = "list";
  o.effects = {"lever_arm"};
  EXPECT_EQ(Candidates(*MakeModel("unicycle"), o), std::vector<std::string>{"lever_arm"});
}

TEST(Selection, TheHiddenEffectGainsAndAWrongOneDoesNot) {
  const Recording rec = testing::UnicycleRecording(90.0, {"time_offset"}, {{"delay_s", 0.25}}, 12);
  AnalyzeOptions o;
  o.model = "unicycle";
  std::vector<std::string> warnings;
  Dataset d = Prepare(rec, o, &warnings);
  const auto model = std::shared_ptr<const KinematicModel>(MakeModel("unicycle"));
  const System bare(model, {});
  FitReport report;
  SelectionState current;
  current.fit = FitBaseline(bare, d, InitialParams(bare, {}), o, &report);
  ComputeFeatures(&d, bare, current.fit.p);
  current.eval = Evaluate(bare, current.fit.p, d);
  const double lag = EstimateCommandLag(d, bare, current.fit.p);
  Tried delay, wrong;
  ASSERT_TRUE(TryEffect("time_offset", 1, current, d, model, lag, o, &delay));
  ASSERT_TRUE(delay.ok);
  ASSERT_EQ(delay.trial.params.size(), 1u);
  EXPECT_NEAR(delay.trial.params[0].value, 0.25, std::max(0.01, 3 * delay.trial.params[0].sigma));
  EXPECT_GT(delay.trial.heldout_gain, 0.5);
  EXPECT_LT(delay.trial.delta_bic, 0.0);
  ASSERT_TRUE(TryEffect("yaw_rate_bias", 1, current, d, model, lag, o, &wrong));
  EXPECT_LT(wrong.trial.heldout_gain, 0.1);
}

}  // namespace
}  // namespace kincal::analysis
