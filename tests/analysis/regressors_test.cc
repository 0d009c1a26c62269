// Regressors: the commanded motion of each evaluation window, in the numbers the effects'
// signatures name; and the lag of the measured motion behind the commands.
#include "analysis/regressors.h"

#include <gtest/gtest.h>

#include "analysis/analysis_test_util.h"

namespace kincal::analysis {
namespace {

Dataset Prepared(const Recording& rec) {
  AnalyzeOptions o;
  o.model = "unicycle";
  std::vector<std::string> warnings;
  return Prepare(rec, o, &warnings).value();
}

TEST(Regressors, ConstantCommandGivesItsTwist) {
  Recording rec = testing::UnicycleRecording(30.0, {}, {}, 1);
  rec.controls = ControlSignal(2, 0);
  const std::array<double, 2> cmd = {0.5, -0.25};
  AppendConstant(&rec.controls, 0, SecondsToNs(40.0), cmd);
  Dataset d = Prepared(rec);
  Eigen::VectorXd p(2);
  p << 0.9, 0.8;
  ComputeFeatures(&d, MakeSystem("unicycle").value(), p);
  ASSERT_EQ(d.features.size(), d.eval.size());
  const RegressorValues& f = d.features[d.features.size() / 2];
  EXPECT_NEAR(f[Regressor::kSpeed], 0.45, 1e-9);
  EXPECT_NEAR(f[Regressor::kAbsSpeed], 0.45, 1e-9);
  EXPECT_NEAR(f[Regressor::kTurnRate], -0.2, 1e-9);
  EXPECT_NEAR(f[Regressor::kAbsTurnRate], 0.2, 1e-9);
  EXPECT_NEAR(f[Regressor::kLatAccel], -0.09, 1e-9);
  EXPECT_NEAR(f[Regressor::kTurnRateSq], -0.04, 1e-9);
  EXPECT_NEAR(f[Regressor::kAccel], 0.0, 1e-12);
  EXPECT_NEAR(f[Regressor::kYawAccel], 0.0, 1e-12);
  EXPECT_NEAR(f[Regressor::kMoving], 1.0, 1e-12);
}

TEST(Regressors, CommandLagFindsAClockOffset) {
  const Recording rec = testing::UnicycleRecording(120.0, {"time_offset"}, {{"delay_s", 0.7}}, 2);
  const Dataset d = Prepared(rec);
  Eigen::VectorXd p(2);
  p << 0.9, 0.8;
  EXPECT_NEAR(EstimateCommandLag(d, MakeSystem("unicycle").value(), p), 0.7, 0.06);
  const Recording prompt = testing::UnicycleRecording(120.0, {}, {}, 2);
  EXPECT_NEAR(EstimateCommandLag(Prepared(prompt), MakeSystem("unicycle").value(), p), 0.0, 0.06);
}

}  // namespace
}  // namespace kincal::analysis
