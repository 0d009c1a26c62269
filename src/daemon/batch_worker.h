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

#include "kincal/analysis/analyze.h"
#include "kincal/io/recording.h"
#include "kincal/time.h"

namespace kincal::daemon {

// One batch's outcome (kincal.calibration_t carries it).
struct BatchCalibration {
  int sequence = 0;  // 1, 2, ... in the order batches were started
  bool ok = false;
  bool cancelled = false;             // stopped by CancelRunning (kincald stopping): not a failure
  std::string error;                  // why it failed (too little data, no unique fit)
  std::vector<std::string> effects;   // the model's: declared, then accepted
  std::vector<std::string> accepted;  // accepted by the selection beyond the declared
  std::vector<std::string> accepted_evidence;  // one line each
  std::vector<ParamEstimate> params;           // the model's, then the effects' (System order)
  Eigen::MatrixXd covariance;                  // cluster-robust, params' order
  double horizon_s = 0;
  double heldout_before_m = 0, heldout_after_m = 0;      // position RMS at the horizon
  double heldout_before_rad = 0, heldout_after_rad = 0;  // heading RMS at the horizon
  TimeNs data_begin_ns = 0, data_end_ns = 0;  // the store's time (pipeline time, current base)
  int num_poses = 0, num_controls = 0;
  bool unique = true;
  std::string warnings;  // one per line
  std::string evidence;  // every trial, "; " between them
  std::string prior;     // what the parameters were fused with (--resume), empty: nothing
  double compute_s = 0;  // wall time
};

// Analyze's result as a batch calibration: fails (ok = false, with why) when its
// covariance is not usable; a fit that is not unique is kept, flagged (unique = false, why
// in the warnings). `declared` are the options' base effects.
BatchCalibration CalibrationFrom(const AnalyzeResult& a, const std::vector<std::string>& declared);

class BatchWorker {
 public:
  // `background`: below the pipeline (live). A lossless replay waits for its batches, so
  // there the worker keeps the pipeline's priority.
  explicit BatchWorker(bool background = true);
  ~BatchWorker();
  BatchWorker(const BatchWorker&) = delete;
  BatchWorker& operator=(const BatchWorker&) = delete;

  // Starts a batch (false if one is running).
  bool Start(int sequence, Recording data, AnalyzeOptions options);
  bool running() const;
  // The result once the batch is done (and forgets it); nothing while it runs.
  std::optional<BatchCalibration> Poll();
  // Waits for the running batch (an empty failed result when none was started).
  BatchCalibration Wait();
  // Thread-safe: the running batch (if any) ends at Analyze's next stage with a result
  // marked `cancelled`. The next Start runs normally. (kincald stopping: the last batch
  // over everything replaces it.)
  void CancelRunning();
  // As Wait, but nothing (the batch still running) once CancelRunning was called: a
  // pipeline that is stopping does not wait here (kincald's Finish waits instead).
  std::optional<BatchCalibration> WaitUnlessCancelled();

 private:
  void Loop(bool background);
  static BatchCalibration Run(const Recording& data, const AnalyzeOptions& options);

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
