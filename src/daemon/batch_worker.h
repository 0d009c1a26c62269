// The batch tier's worker thread: `kincal analyze` (the same code, Analyze) on a snapshot
// of the run, so that neither capture nor the filter thread ever waits for it (except a
// lossless replay, which waits at a fixed point in data time so that its decisions are
// bit-identical run to run). The thread runs below the pipeline (background_thread.h):
// on a loaded machine the batch finishes later, the frames do not, and it never starves.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "kincal/online/batch_calibration.h"

namespace kincal::daemon {

// kincald's BatchRunner: one worker thread.
class BatchWorker final : public BatchRunner {
 public:
  // `background`: below the pipeline (live). A lossless replay waits for its batches, so
  // there the worker keeps the pipeline's priority.
  explicit BatchWorker(bool background = true);
  ~BatchWorker();
  BatchWorker(const BatchWorker&) = delete;
  BatchWorker& operator=(const BatchWorker&) = delete;

  // Starts a batch (false if one is running).
  bool Start(int sequence, Recording data, AnalyzeOptions options) override;
  bool running() const override;
  // The result once the batch is done (and forgets it); nothing while it runs.
  std::optional<BatchCalibration> Poll() override;
  // Waits for the running batch (an empty failed result when none was started).
  BatchCalibration Wait() override;
  // Thread-safe: the running batch (if any) ends at Analyze's next stage with a result
  // marked `cancelled`. The next Start runs normally. (kincald stopping: the last batch
  // over everything replaces it.)
  void CancelRunning() override;
  // As Wait, but nothing (the batch still running) once CancelRunning was called: a
  // pipeline that is stopping does not wait here (kincald's Finish waits instead).
  std::optional<BatchCalibration> WaitUnlessCancelled() override;

 private:
  void Loop(bool background);

  std::atomic<bool> cancel_{false}, cancel_running_{false};
  mutable std::mutex mu_;
  std::condition_variable cv_;
  bool stop_ = false, pending_ = false, busy_ = false;
  int sequence_ = 0;
  Recording data_;
  AnalyzeOptions options_;
  std::optional<BatchCalibration> result_;
  std::thread thread_;
};

}  // namespace kincal::daemon
