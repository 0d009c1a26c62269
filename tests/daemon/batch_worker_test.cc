// BatchWorker: kincal analyze in a worker thread. On data with a hidden delay (effects:
// auto) it accepts time_offset with its value, evidence and the held-out gain, and its
// covariance is the one analyze reports; on clean data it accepts nothing; too little
// data and a fit that explains nothing are errors, not crashes; one batch at a time.
#include "daemon/batch_worker.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <optional>
#include <thread>

#include "analysis/analysis_test_util.h"

namespace kincal::daemon {
namespace {

AnalyzeOptions AutoOptions() {
  AnalyzeOptions o;
  o.model = "unicycle";
  o.effects_mode = "auto";
  o.num_threads = 1;
  return o;
}

TEST(BatchWorker, FindsAHiddenDelayWithItsEvidenceAndAnalyzesCovariance) {
  BatchWorker worker(/*background=*/false);  // the fit, not the priority, under test
  const Recording rec = testing::UnicycleRecording(60.0, {"time_offset"}, {{"delay_s", 0.2}}, 3);
  ASSERT_TRUE(worker.Start(7, rec, AutoOptions()));
  EXPECT_FALSE(worker.Start(8, rec, AutoOptions()));  // one at a time
  const BatchCalibration r = worker.Wait();
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.sequence, 7);
  ASSERT_EQ(r.accepted, std::vector<std::string>{"time_offset"}) << r.evidence;
  EXPECT_EQ(r.effects, std::vector<std::string>{"time_offset"});
  ASSERT_EQ(r.accepted_evidence.size(), 1u);
  EXPECT_NE(r.accepted_evidence[0].find("held-out gain"), std::string::npos);
  EXPECT_EQ(r.num_poses, static_cast<int>(rec.poses.size()));
  EXPECT_GT(r.compute_s, 0.0);
  const AnalyzeResult offline = Analyze(rec, AutoOptions()).value();
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

TEST(BatchWorker, CleanDataAcceptsNothing) {
  BatchWorker worker(/*background=*/false);  // the fit, not the priority, under test
  ASSERT_TRUE(worker.Start(1, testing::UnicycleRecording(60.0, {}, {}, 4), AutoOptions()));
  const BatchCalibration r = worker.Wait();
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_TRUE(r.accepted.empty()) << r.evidence;
  EXPECT_NEAR(r.params[0].value, 0.9, 3 * r.params[0].sigma);
  EXPECT_NEAR(r.params[1].value, 0.8, 3 * r.params[1].sigma);
}

TEST(BatchWorker, TooLittleDataIsAnErrorNotACrash) {
  BatchWorker worker(/*background=*/false);  // the fit, not the priority, under test
  ASSERT_TRUE(worker.Start(1, testing::UnicycleRecording(1.0, {}, {}, 5), AutoOptions()));
  const BatchCalibration r = worker.Wait();
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("at least"), std::string::npos) << r.error;
}

// A robot lifted onto a stand: the wheels follow the commands, the body does not move. The
// model explains nothing there: the batch keeps analyze's fit, flagged as not unique.
TEST(BatchWorker, AFitThatExplainsNothingIsFlagged) {
  Recording rec = testing::UnicycleRecording(60.0, {}, {}, 6);
  std::srand(6);  // Eigen's Random()
  for (auto& p : rec.poses) p.z = rec.poses.front().z + 1e-3 * Eigen::Vector3d::Random();
  BatchWorker worker(/*background=*/false);  // the fit, not the priority, under test
  AnalyzeOptions o = AutoOptions();
  o.effects_mode = "none";
  ASSERT_TRUE(worker.Start(1, rec, o));
  const BatchCalibration r = worker.Wait();
  EXPECT_TRUE(r.ok) << r.error;
  EXPECT_FALSE(r.unique);
  EXPECT_NE(r.warnings.find("explains nothing"), std::string::npos) << r.warnings;
}

// kincald stopping: the running batch ends early, marked cancelled (not a failure); the
// next one runs in full.
TEST(BatchWorker, ARunningBatchCanBeCancelledAndTheNextRunsInFull) {
  BatchWorker worker(/*background=*/false);  // the fit, not the priority, under test
  const Recording slow = testing::UnicycleRecording(60.0, {"time_offset"}, {{"delay_s", 0.2}}, 3);
  ASSERT_TRUE(worker.Start(1, slow, AutoOptions()));  // a selection of ~20 s in full
  worker.CancelRunning();
  const BatchCalibration r = worker.Wait();
  EXPECT_TRUE(r.cancelled);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("stopping"), std::string::npos) << r.error;
  ASSERT_TRUE(worker.Start(2, testing::UnicycleRecording(60.0, {}, {}, 4), AutoOptions()));
  const BatchCalibration next = worker.Wait();
  EXPECT_FALSE(next.cancelled);
  ASSERT_TRUE(next.ok) << next.error;
  EXPECT_EQ(next.sequence, 2);
  // A pipeline blocked waiting (a lossless replay) is released by the cancel at once, the
  // batch still running until its next stage; Wait then collects it.
  ASSERT_TRUE(worker.Start(3, slow, AutoOptions()));
  std::thread stopper([&worker] {
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    worker.CancelRunning();
  });
  std::optional<BatchCalibration> w = worker.WaitUnlessCancelled();
  stopper.join();
  if (!w) w = worker.Wait();
  EXPECT_TRUE(w->cancelled);
  EXPECT_EQ(w->sequence, 3);
}

TEST(BatchWorker, WaitWithoutABatchSaysSo) {
  BatchWorker worker(/*background=*/false);  // the fit, not the priority, under test
  const BatchCalibration r = worker.Wait();
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.error.empty());
}

}  // namespace
}  // namespace kincal::daemon
