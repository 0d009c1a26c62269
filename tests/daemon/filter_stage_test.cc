#include "daemon/filter_stage.h"

#include <gtest/gtest.h>

#include "daemon/filter_stage_harness.h"

namespace kincal::daemon {
namespace {

using test_util::DefaultStageOptions;
using test_util::RunStage;
using test_util::StageScenario;

StageScenario CleanDiffDrive() {
  StageScenario sc;
  sc.truth = {{"r_l", 0.0310}, {"r_r", 0.0313}, {"d", 0.148}};
  sc.guess = {{"r_l", 0.034}, {"r_r", 0.029}, {"d", 0.160}};
  return sc;
}

TEST(FilterStage, ConvergesToTheTruthOnAModelThatFits) {
  const StageScenario sc = CleanDiffDrive();
  const auto run = RunStage(sc, DefaultStageOptions());
  ASSERT_FALSE(run.params.empty());
  for (const auto& [name, truth] : sc.truth) {
    EXPECT_NEAR(run.Final(name), truth, 3 * run.FinalSigma(name)) << name;
    EXPECT_NEAR(run.Final(name), truth, 0.005 * truth) << name;
  }
  EXPECT_EQ(run.counters.filter_resets, 0);
  EXPECT_EQ(run.counters.run_resets, 0);
  EXPECT_LT(run.counters.poses_gated, 10);  // 99.9 % gate: ~0.1 % of 1800 poses
  EXPECT_GT(run.counters.updates, 1750);
  EXPECT_EQ(int{run.params.back().status}, int{kincal::params_t::STATUS_CONVERGED});
  EXPECT_EQ(run.params.back().update_count, run.counters.updates);
}

TEST(FilterStage, GatesAnIsolatedOutlierAndIsNotMovedByIt) {
  StageScenario sc = CleanDiffDrive();
  const auto clean = RunStage(sc, DefaultStageOptions());
  sc.outliers = {600, 1200};
  const auto run = RunStage(sc, DefaultStageOptions());
  EXPECT_EQ(run.counters.poses_gated, clean.counters.poses_gated + 2);
  EXPECT_EQ(run.counters.filter_resets, 0);
  for (const auto& [name, truth] : sc.truth) {
    EXPECT_NEAR(run.Final(name), clean.Final(name), 0.1 * clean.FinalSigma(name)) << name;
  }
}

TEST(FilterStage, PublishesAtTheConfiguredRates) {
  FilterStageOptions o = DefaultStageOptions();
  o.filter.params_rate_hz = 5.0;
  o.model_check_every_s = 2.0;
  const auto run = RunStage(CleanDiffDrive(), o);  // 60 s of poses
  EXPECT_NEAR(static_cast<double>(run.params.size()), 60 * 5.0, 3.0);
  EXPECT_NEAR(static_cast<double>(run.checks.size()), 60 / 2.0, 1.0);
}

}  // namespace
}  // namespace kincal::daemon
