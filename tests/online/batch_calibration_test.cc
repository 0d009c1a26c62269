// A batch calibration is kincal analyze on the run (RunBatchCalibration, here through the
// thread-free InlineBatchRunner). On data with a hidden delay (effects: auto) it accepts
// time_offset with its value, evidence and the held-out gain, and its covariance is the one
// analyze reports; on clean data it accepts nothing; too little data and a fit that
// explains nothing are errors, not crashes; one batch at a time; a cancel ends it.
#include "kincal/online/batch_calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "analysis/analysis_test_util.h"

namespace kincal {
namespace {

TEST(BatchCalibration, FindsAHiddenDelayWithItsEvidenceAndAnalyzesCovariance) {
  InlineBatchRunner worker;
  const Recording rec = testing::UnicycleRecording(60.0, {"time_offset"}, {{"delay_s", 0.2}}, 3);
  ASSERT_TRUE(worker.Start(7, rec, testing::AutoUnicycleOptions()));
  EXPECT_FALSE(worker.Start(8, rec, testing::AutoUnicycleOptions()));  // one at a time
  const BatchCalibration r = worker.Wait();
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.sequence, 7);
  ASSERT_EQ(r.accepted, std::vector<std::string>{"time_offset"}) << r.evidence;
  EXPECT_EQ(r.effects, std::vector<std::string>{"time_offset"});
  ASSERT_EQ(r.accepted_evidence.size(), 1u);
  EXPECT_NE(r.accepted_evidence[0].find("held-out gain"), std::string::npos);
  EXPECT_EQ(r.num_poses, static_cast<int>(rec.poses.size()));
  EXPECT_GT(r.compute_s, 0.0);
  const AnalyzeResult offline = Analyze(rec, testing::AutoUnicycleOptions()).value();
  ASSERT_EQ(r.params.size(), offline.after.params.size());
  ASSERT_EQ(r.covariance.rows(), static_cast<int>(r.params.size()));
  for (size_t i = 0; i < r.params.size(); ++i) {
    EXPECT_EQ(r.params[i].value, offline.after.params[i].value) << r.params[i].name;
    const int k = static_cast<int>(i);
    EXPECT_DOUBLE_EQ(std::sqrt(r.covariance(k, k)), r.params[i].sigma) << r.params[i].name;
    if (r.params[i].name == "delay_s") {
      EXPECT_NEAR(r.params[i].value, 0.2, std::max(0.01, 3 * r.params[i].sigma));
    }
  }
  EXPECT_LT(r.heldout_after_m, 0.5 * r.heldout_before_m);
  EXPECT_FALSE(worker.running());
  EXPECT_FALSE(worker.Poll().has_value());  // the result was handed over once
}

TEST(BatchCalibration, CleanDataAcceptsNothing) {
  InlineBatchRunner worker;
  ASSERT_TRUE(
      worker.Start(1, testing::UnicycleRecording(60.0, {}, {}, 4), testing::AutoUnicycleOptions()));
  const BatchCalibration r = worker.Wait();
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_TRUE(r.accepted.empty()) << r.evidence;
  EXPECT_NEAR(r.params[0].value, 0.9, 3 * r.params[0].sigma);
  EXPECT_NEAR(r.params[1].value, 0.8, 3 * r.params[1].sigma);
}

TEST(BatchCalibration, TooLittleDataIsAnErrorNotACrash) {
  InlineBatchRunner worker;
  ASSERT_TRUE(
      worker.Start(1, testing::UnicycleRecording(1.0, {}, {}, 5), testing::AutoUnicycleOptions()));
  const BatchCalibration r = worker.Wait();
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("at least"), std::string::npos) << r.error;
}

// A robot lifted onto a stand: the wheels follow the commands, the body does not move. The
// model explains nothing there: the batch keeps analyze's fit, flagged as not unique.
TEST(BatchCalibration, AFitThatExplainsNothingIsFlagged) {
  Recording rec = testing::UnicycleRecording(60.0, {}, {}, 6);
  std::srand(6);  // Eigen's Random()
  for (auto& p : rec.poses) p.z = rec.poses.front().z + 1e-3 * Eigen::Vector3d::Random();
  InlineBatchRunner worker;
  AnalyzeOptions o = testing::AutoUnicycleOptions();
  o.effects_mode = "none";
  ASSERT_TRUE(worker.Start(1, rec, o));
  const BatchCalibration r = worker.Wait();
  EXPECT_TRUE(r.ok) << r.error;
  EXPECT_FALSE(r.unique);
  EXPECT_NE(r.warnings.find("explains nothing"), std::string::npos) << r.warnings;
}

TEST(BatchCalibration, ACancelledBatchSaysSoAndTheNextRunsInFull) {
  InlineBatchRunner runner;
  ASSERT_TRUE(
      runner.Start(1, testing::UnicycleRecording(60.0, {}, {}, 4), testing::AutoUnicycleOptions()));
  runner.CancelRunning();
  EXPECT_FALSE(runner.WaitUnlessCancelled().has_value());  // stopping: nothing waits
  const BatchCalibration r = runner.Wait();
  EXPECT_TRUE(r.cancelled);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("stopping"), std::string::npos) << r.error;
  ASSERT_TRUE(
      runner.Start(2, testing::UnicycleRecording(60.0, {}, {}, 4), testing::AutoUnicycleOptions()));
  const std::optional<BatchCalibration> next = runner.Poll();
  ASSERT_TRUE(next.has_value());
  EXPECT_FALSE(next->cancelled);
  EXPECT_TRUE(next->ok) << next->error;
  EXPECT_EQ(next->sequence, 2);
  EXPECT_EQ(runner.Wait().error, "no batch was running");
}

TEST(BatchCalibration, ACovarianceThatIsNotFiniteIsAFailure) {
  AnalyzeResult a;
  a.after.params = {{"k_v", "1", 0.9, 0.01, 0}};
  a.after.covariance = Eigen::MatrixXd::Constant(1, 1, std::nan(""));
  a.after.unique = true;
  const BatchCalibration c = CalibrationFrom(a, {});
  EXPECT_FALSE(c.ok);
  EXPECT_EQ(c.error, "the fit gave no usable covariance");
  a.after.covariance(0, 0) = 1e-4;
  EXPECT_TRUE(CalibrationFrom(a, {}).ok);
}

}  // namespace
}  // namespace kincal
