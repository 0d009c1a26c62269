// A batch calibration: the whole run fitted as `kincal analyze` fits it (Analyze, the same
// code), and what runs it. The fit itself has no threads (RunBatchCalibration); a
// BatchRunner decides where it runs: kincald's BatchWorker on a thread below the pipeline
// (src/daemon/batch_worker.h), InlineBatchRunner on the caller's thread (tests and tools
// without threads, and every lossless replay decides the same on either).
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "kincal/analysis/analyze.h"
#include "kincal/io/recording.h"
#include "kincal/time.h"

namespace kincal {

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

// The fit of one batch: Analyze on `data`, as a BatchCalibration with its sequence, data
// span, sizes and wall time. `cancelled` is asked at each of Analyze's stages: a reason
// (not null) ends the fit there, and the result is marked `cancelled` with it as its error.
BatchCalibration RunBatchCalibration(int sequence, const Recording& data,
                                     const AnalyzeOptions& options,
                                     const std::function<const char*()>& cancelled = {});

// Where batches run. One at a time: Start refuses while one is pending or running.
class BatchRunner {
 public:
  virtual ~BatchRunner() = default;
  // Starts a batch (false if one is running).
  virtual bool Start(int sequence, Recording data, AnalyzeOptions options) = 0;
  virtual bool running() const = 0;
  // The result once the batch is done (and forgets it); nothing while it runs.
  virtual std::optional<BatchCalibration> Poll() = 0;
  // Waits for the batch (an empty failed result when none was started).
  virtual BatchCalibration Wait() = 0;
  // Thread-safe: the running batch (if any) ends at Analyze's next stage with a result
  // marked `cancelled`. The next Start runs normally.
  virtual void CancelRunning() = 0;
  // As Wait, but nothing (the batch still running) once CancelRunning was called: a
  // pipeline that is stopping does not wait here.
  virtual std::optional<BatchCalibration> WaitUnlessCancelled() = 0;
};

// Runs each batch on the caller's thread when its result is asked for (Poll or Wait): a
// pipeline without threads. A lossless replay's decisions are the same as on a worker
// thread (the result is taken at the same data time); live, Poll blocks for the fit.
class InlineBatchRunner final : public BatchRunner {
 public:
  bool Start(int sequence, Recording data, AnalyzeOptions options) override;
  bool running() const override { return pending_; }
  std::optional<BatchCalibration> Poll() override;
  BatchCalibration Wait() override;
  void CancelRunning() override { cancel_running_.store(true); }
  std::optional<BatchCalibration> WaitUnlessCancelled() override;

 private:
  std::atomic<bool> cancel_running_{false};
  bool pending_ = false;
  int sequence_ = 0;
  Recording data_;
  AnalyzeOptions options_;
};

}  // namespace kincal
