// Selection: the candidates are the registered effects that apply (per channel where an
// effect acts on one), and one candidate screened and confirmed on a recording with a
// hidden delay is accepted with its value and a held-out gain, while a wrong one gains
// nothing.
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
  const auto c = Candidates(*MakeModel("unicycle").value(), o);
  auto has = [&](const std::string& s) { return std::find(c.begin(), c.end(), s) != c.end(); };
  EXPECT_TRUE(has("time_offset"));
  EXPECT_TRUE(has("turn_slowdown"));
  EXPECT_FALSE(has("backlash"));  // no steering channel
  EXPECT_TRUE(has("dead_band[v]") || has("dead_band"));
  o.effects_mode = "none";
  EXPECT_TRUE(Candidates(*MakeModel("unicycle").value(), o).empty());
  o.effects_mode = "list";
  o.effects = {"lever_arm"};
  EXPECT_EQ(Candidates(*MakeModel("unicycle").value(), o), std::vector<std::string>{"lever_arm"});
}

// A candidate screened on the screening windows, then confirmed on all of them.
bool Try(const std::string& spec, const SelectionState& current, const Dataset& d,
         const std::shared_ptr<const KinematicModel>& model, double lag, Tried* out) {
  Screened s;
  if (!ScreenEffect(spec, current, d, model, lag, false, &s) || !s.ok) return false;
  ConfirmEffect(s, 1, current, d, out);
  return out->fit.ok;
}

// A second copy of an effect on a channel it already acts on is not a candidate; the same
// kind on another channel, or another kind, is.
TEST(Selection, AnEffectIsNotRepeatedOnItsChannel) {
  EXPECT_TRUE(Repeats("actuator_lag[omega]", "actuator_lag"));
  EXPECT_TRUE(Repeats("actuator_lag", "actuator_lag[v]"));
  EXPECT_TRUE(Repeats("actuator_lag[v]", "actuator_lag[v]"));
  EXPECT_TRUE(Repeats("dead_band[omega_l,omega_r]", "dead_band[omega_r]"));
  EXPECT_FALSE(Repeats("actuator_lag[omega]", "actuator_lag[v]"));
  EXPECT_FALSE(Repeats("time_offset", "actuator_lag"));
  EXPECT_FALSE(Repeats("not an effect[", "actuator_lag"));
}

TEST(Selection, TheHiddenEffectGainsAndAWrongOneDoesNot) {
  const Recording rec = testing::UnicycleRecording(90.0, {"time_offset"}, {{"delay_s", 0.25}}, 12);
  AnalyzeOptions o;
  o.model = "unicycle";
  std::vector<std::string> warnings;
  Dataset d = Prepare(rec, o, &warnings).value();
  const auto model = std::shared_ptr<const KinematicModel>(MakeModel("unicycle").value());
  const System bare(model, {});
  FitReport report;
  SelectionState current;
  current.fit = FitBaseline(bare, d, InitialParams(bare, {}).value(), o, &report).value();
  ComputeFeatures(&d, bare, current.fit.p);
  current.eval = Evaluate(bare, current.fit.p, d);
  const double lag = EstimateCommandLag(d, bare, current.fit.p);
  Tried delay, wrong;
  ASSERT_LT(d.screen_meas.size(), d.fit_meas.size());  // screened on a subsample
  ASSERT_TRUE(Try("time_offset", current, d, model, lag, &delay));
  ASSERT_TRUE(delay.ok);
  ASSERT_EQ(delay.trial.params.size(), 1u);
  EXPECT_NEAR(delay.trial.params[0].value, 0.25, std::max(0.01, 3 * delay.trial.params[0].sigma));
  EXPECT_GT(delay.trial.heldout_gain, 0.5);
  EXPECT_LT(delay.trial.delta_bic, 0.0);
  ASSERT_TRUE(Try("yaw_rate_bias", current, d, model, lag, &wrong));
  EXPECT_LT(wrong.trial.heldout_gain, 0.1);
  // A second round starts from the first round's estimate (warm start) and lands on the
  // same optimum.
  current.warm["time_offset"] = delay.fit.p.tail(1);
  Tried again;
  ASSERT_TRUE(Try("time_offset", current, d, model, lag, &again));
  EXPECT_NEAR(again.trial.params[0].value, delay.trial.params[0].value,
              0.1 * delay.trial.params[0].sigma);
}

}  // namespace
}  // namespace kincal::analysis
