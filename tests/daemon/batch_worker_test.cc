// BatchWorker: the batch runs on a worker thread (the fit itself is tested in
// tests/online/batch_calibration_test.cc): a running batch is cancelled at its next stage
// and the next runs in full; a pipeline waiting is released by the cancel; a wait without
// a batch says so.
#include "daemon/batch_worker.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <optional>
#include <thread>

#include "analysis/analysis_test_util.h"

namespace kincal::daemon {
namespace {

// kincald stopping: the running batch ends early, marked cancelled (not a failure); the
// next one runs in full.
TEST(BatchWorker, ARunningBatchCanBeCancelledAndTheNextRunsInFull) {
  BatchWorker worker(/*background=*/false);  // the fit, not the priority, under test
  const Recording slow = testing::UnicycleRecording(60.0, {"time_offset"}, {{"delay_s", 0.2}}, 3);
  ASSERT_TRUE(
      worker.Start(1, slow, testing::AutoUnicycleOptions()));  // a selection of ~20 s in full
  worker.CancelRunning();
  const BatchCalibration r = worker.Wait();
  EXPECT_TRUE(r.cancelled);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("stopping"), std::string::npos) << r.error;
  ASSERT_TRUE(
      worker.Start(2, testing::UnicycleRecording(60.0, {}, {}, 4), testing::AutoUnicycleOptions()));
  const BatchCalibration next = worker.Wait();
  EXPECT_FALSE(next.cancelled);
  ASSERT_TRUE(next.ok) << next.error;
  EXPECT_EQ(next.sequence, 2);
  // A pipeline blocked waiting (a lossless replay) is released by the cancel at once, the
  // batch still running until its next stage; Wait then collects it.
  ASSERT_TRUE(worker.Start(3, slow, testing::AutoUnicycleOptions()));
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
