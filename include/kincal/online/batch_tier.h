// kincald's batch tier: the calibration the whole run supports, beside the filter's
// real-time estimate. The filter stage hands it every control and pose it takes (kept in a
// bounded CalibrationStore); every `every_s` of data time, or `growth` x the span already
// fitted when that is longer (the first once the run spans `first_s`) a snapshot of all of it goes
// to its runner (batch_calibration.h: kincald's worker thread, or inline), which fits it as `kincal
// analyze` does: the declared effects as the base, the configured guess as the start and, with
// robot.effects: auto, analyze's own effect selection on all the data (so an effect a later batch
// no longer supports is gone again).
//
// When a result is applied: live, at the first pose after it is ready; in a lossless
// replay, at the first pose `apply_after_s` of data time after the batch started (the
// filter thread waits for it there), so that a replay decides bit-identically every time.
// Data time here is the store's: the newest pose's time since the run's first sample.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "kincal/io/checkpoint.h"
#include "kincal/online/batch_calibration.h"
#include "kincal/online/calibration_store.h"
#include "kincal/time.h"

namespace kincal {

// One effect the batch tier added to the filter's model, for model_check_t.
struct AddedEffect {
  std::string name;
  int64_t utime = 0;
  double heldout_before_m = 0, heldout_after_m = 0;
};

struct BatchTierOptions {
  bool enabled = true;
  bool auto_effects = false;   // robot.effects: auto
  bool lossless = false;       // a replay with --fast: results applied at fixed data times
  double every_s = 60.0;       // data time between batches
  double first_s = 30.0;       // the first batch once the run spans this much
  double growth = 0.25;        // and at least growth x the span fitted between batches
  double apply_after_s = 5.0;  // lossless: results applied this long after the start
  // Analyze's threads, 0: one per core (the result does not depend on them). They run
  // below the pipeline (kincald's worker), so the frames keep their priority.
  int threads = 0;
  int max_effects = 4;                  // effects the selection may accept
  std::map<std::string, double> fixed;  // robot.fixed: held (kincal analyze --fix)
  CalibrationStoreOptions store;
  bool IsValid(std::string* error) const;
};

// A batch calibration fused with a resumed one (--resume: a calibration of earlier,
// independent data): information added, x = P (Pb^-1 xb + Pr^-1 xr), P = (Pb^-1 + Pr^-1)^-1.
// Only when both describe the same model, effects and parameters in the same order;
// otherwise the batch alone, with *why saying what differs. `r.prior` names what was fused.
// Parameters the batch holds (robot.fixed: zero variance) keep its value and are left out
// of the fusion; a parameter the resumed run held but this one estimates is a difference.
BatchCalibration FusedWithResumed(const BatchCalibration& r, const Checkpoint& resumed,
                                  std::string* why);

class BatchTier {
 public:
  // `model`, `declared` effects and the configured `guess` (by parameter name) are what
  // `kincal analyze --model M --init GUESS` would be given.
  // `runner` runs the batches (kincald: its worker thread; without threads: inline).
  BatchTier(BatchTierOptions options, std::string model, std::vector<std::string> declared,
            std::map<std::string, double> guess, int num_controls,
            std::unique_ptr<BatchRunner> runner);

  void AddControl(TimeNs t_ns, std::span<const double> values) {
    if (opt_.enabled) store_.AddControl(t_ns, values);
  }
  void AddPose(TimeNs t_ns, const Eigen::Vector3d& xytheta);
  // A new time base (a clock jumped back): the store goes on after what it holds.
  void NewBase() { store_.NewBase(); }

  // At each pose (after AddPose): a finished batch to apply now, if any; then a new batch
  // is started when one is due.
  std::optional<BatchCalibration> OnPose(TimeNs t_ns);
  // At shutdown: the running batch (if any), then one over everything stored, waited for.
  std::vector<BatchCalibration> Finish(TimeNs t_ns);
  // Thread-safe: a stop was asked for; the running batch (if any) ends early (at Analyze's
  // next stage) and is dropped, nothing waits for it before Finish (a lossless replay's
  // drain goes on), and Finish's batch over everything takes its place.
  void CancelRunning() {
    stopping_.store(true);
    runner_->CancelRunning();
  }

  bool running() const { return started_span_ns_ >= 0; }
  int started() const { return sequence_; }
  const CalibrationStore& store() const { return store_; }
  // The store's time of a batch result (BatchCalibration::data_*_ns) on the current time
  // base.
  TimeNs ToPipeline(TimeNs store_ns) const { return store_ns - store_.offset_ns(); }

 private:
  void StartBatch(TimeNs t_ns);
  BatchCalibration Finished(BatchCalibration r) const;
  AnalyzeOptions Options() const;

  BatchTierOptions opt_;
  std::string model_;
  std::vector<std::string> declared_;
  std::map<std::string, double> init_;
  CalibrationStore store_;
  std::unique_ptr<BatchRunner> runner_;
  int sequence_ = 0;
  TimeNs started_span_ns_ = -1;        // the running batch's start (store span), -1: none
  TimeNs last_span_ns_ = -1;           // the last batch's start (store span)
  std::atomic<bool> stopping_{false};  // CancelRunning: no new batch before Finish
  TimeNs next_due_span_ns_;
};

}  // namespace kincal
