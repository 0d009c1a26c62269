// The online estimator (kincald's filter stage): poses and controls in, parameter estimates
// out, as kincal's messages (estimate_messages.h). It owns the
// online calibrator, the model check, the time base and the divergence recovery; the
// filter thread only decides when a pose may be taken (its controls are in) and hands it
// over. Single-threaded; times are the pipeline's (ns), converted from the samples' utime
// once, on entry. Without threads: kincald's filter thread drives it, a test drives it
// directly (tests/online/filter_stage_harness.h); only its batches may run elsewhere (the
// BatchRunner it is given).
//
//   AddControl  a control sample (time base rules, held jumps, late and reordered ones)
//   AddPose     a pose: initialise, new run, update or gate, recovery, publish
//   Recover     after filter.divergence_gated gated poses in a row (real divergence, at most
//               once per episode): batch re-fit if its window informs every parameter and
//               explains the recent poses better, else the batch calibration (or the
//               running estimate before there is one); restart
//   ApplyBatch  a batch calibration (batch_tier.h: the whole run as `kincal analyze` fits
//               it): published; the filter re-centred on it when the two disagree beyond
//               their sigmas, re-initialised on its model when its effects differ
//   Finish      a last batch over the whole run, then the final estimate (the batch
//               calibration) and checkpoint
#pragma once

#include <atomic>
#include <functional>
#include <kincal/calibration_t.hpp>
#include <kincal/params_t.hpp>
#include <memory>
#include <optional>
#include <string>

#include "kincal/analysis/model_check.h"
#include "kincal/estimation/batch.h"
#include "kincal/estimation/noise_adaptation.h"
#include "kincal/estimation/online_calibrator.h"
#include "kincal/io/checkpoint.h"
#include "kincal/online/batch_tier.h"
#include "kincal/online/counters.h"
#include "kincal/online/filter_options.h"
#include "kincal/online/filter_prior.h"
#include "kincal/online/pose_ring.h"
#include "kincal/online/samples.h"
#include "kincal/online/time_base.h"
#include "kincal/system.h"

namespace kincal {
class model_check_t;

// What the filter stage is configured with (kincald: from the config's filter, robot,
// checkpoint and calibration sections and the health rate, daemon/filter_setup.h).
struct FilterStageOptions {
  FilterOptions filter;
  std::vector<std::string> effects;  // declared (for the estimate and checkpoints)
  double model_check_every_s = 1.0;  // a model_check_t this often (the health rate)
  std::string checkpoint_path;       // empty: no checkpoints
  double checkpoint_every_s = 10.0;
  bool auto_effects = false;            // robot.effects: auto (the batch tier's selection)
  std::map<std::string, double> fixed;  // robot.fixed: held by the filter and the batch
  BatchTierOptions calibration;         // the batch tier (batch_tier.h)
  // --resume: the checkpoint resumed from. Each batch calibration (of this run's data) is
  // fused with it when both describe the same parameters (FusedWithResumed).
  std::optional<Checkpoint> resumed;
  bool lossless = false;  // a replay with --fast: online decisions at fixed data times
  bool IsValid(std::string* error) const;
};

// Where the stage's results go (called on the filter thread).
struct FilterOutputs {
  std::function<void(int64_t utime, const kincal::params_t&)> params;
  std::function<void(int64_t utime, const kincal::model_check_t&)> model_check;
  std::function<void(const Checkpoint&)> estimate;  // after every params publication
  // After every batch: its message, and the calibration in force (the last good batch) as
  // a checkpoint, null while there is none.
  std::function<void(int64_t utime, const kincal::calibration_t&, const Checkpoint* in_force)>
      calibration;
  std::function<void()> checkpoint_due;  // every checkpoint.every_s (if a path is set)
};

class FilterStage {
 public:
  // `next_control` pops the next queued control (false when none is waiting); the stage
  // drains it itself, because a clock jump must take exactly the controls queued behind it.
  FilterStage(const System& sys, FilterStageOptions options, FilterPrior prior,
              std::function<bool(ControlSample*)> next_control, FilterOutputs outputs,
              OnlineCounters* counters, std::unique_ptr<BatchRunner> batch_runner);
  ~FilterStage();

  // Takes every queued control until one starts a clock jump (held, see TimeBase).
  void DrainControls(TimeNs now_mono_ns);
  // One pose (in time order; invalid poses are ignored).
  void AddPose(const PoseSample& p, TimeNs now_mono_ns);
  // The controls jumped back and the poses did not follow: the held control starts the new
  // base by itself.
  void TakeControlJump(TimeNs now_mono_ns);
  // Publishes the final estimate (and writes the checkpoint) if the filter has started.
  void Finish();
  // Thread-safe: kincald is stopping; a running batch ends early (Finish fits everything).
  void CancelBatch() { batch_.CancelRunning(); }

  // The controls up to the pose's time are in, or will never come (a jump is held).
  bool ControlsCover(const PoseSample& p) const {
    return time_base_.newest_control_ns() >= UtimeToPipelineNs(p.utime) || time_base_.holding();
  }
  bool holding_jump() const { return time_base_.holding(); }
  // The status of the last parameters published (params_t::STATUS_*), for health.
  int status() const { return status_.load(); }
  // The model as it runs now (with the effects added online).
  const System& system() const { return *sys_; }
  // The batch tier (its store, the batches started).
  const BatchTier& batch() const { return batch_; }
  TimeNs held_since_mono_ns() const { return time_base_.held_since_mono_ns(); }

 private:
  void AddControlSample(const ControlSample& c);
  void TakeJump(const char* what, TimeNs t, TimeBase::Stream by, TimeNs now_mono_ns);
  void StartNewBase(const char* what, TimeNs t, TimeBase::Stream by);
  // False when the pose was an isolated outlier (gated, not used).
  bool Update(const PoseSample& p, TimeNs t);
  void TrackEpisode(const PoseSample& p, TimeNs t);
  void Recover(const PoseSample& p, TimeNs t, bool diverged);
  std::vector<PoseMeasurement> RecentMeasurements(TimeNs t) const;
  bool RefitIsBetter(const BatchResult& refit, const std::vector<PoseMeasurement>& meas,
                     std::string* why) const;
  void PublishParams(TimeNs t, bool force);
  void PublishFinalCalibration(TimeNs t);
  void PublishModelCheck(TimeNs t);
  int ParamsStatus(bool sigmas_small, const ModelCheckVerdict& verdict, TimeNs t) const;
  // A verdict against the model reached while the estimate was still moving is judged again
  // on fresh innovations: when it calls the model inadequate and a parameter's sigma has
  // fallen by kCheckForgetFactor since the check's window began, the window restarts (issue
  // 34: a declared lag, estimated right, was called inadequate for 17 s by the innovations
  // of the first seconds). True when it restarted.
  bool RejudgeOnSettledInnovations(const kincal::params_t& m, const ModelCheckVerdict& verdict);
  bool ModelInadequate(const ModelCheckVerdict& v) const;
  void ApplyBatch(const BatchCalibration& r, const PoseSample& p, TimeNs t);
  void PublishCalibration(const BatchCalibration& r, TimeNs t);
  void Rebuild(const BatchCalibration& r, const PoseSample& p, TimeNs t);
  void Recentre(const BatchCalibration& r, const PoseSample& p, TimeNs t);
  void SetFromCalibration(const BatchCalibration& r, double cov_scale, VecN<kMaxState>* mean,
                          StateMat* cov) const;
  // The largest |filter - batch| over their combined sigma, parameter by parameter
  // (infinity when the models differ or there is no batch calibration).
  double DisagreementSigmas(std::string* worst) const;
  void StartFilterAt(const std::shared_ptr<const System>& sys, const VecN<kMaxState>& mean,
                     const StateMat& cov, const PoseSample& p, TimeNs t);

  std::shared_ptr<const System> sys_;  // replaced when an effect is added online
  std::vector<std::string> effects_;   // declared, then those added online
  const FilterStageOptions opt_;
  FilterPrior prior_;
  Eigen::VectorXd prior_sigma_;  // of the configured or resumed prior (convergence test)
  OnlineCalibratorOptions calibrator_options_;
  std::function<bool(ControlSample*)> next_control_;
  FilterOutputs out_;
  OnlineCounters& counters_;

  TimeNs max_gap_ns_, params_every_ns_, check_every_ns_, checkpoint_every_ns_, batch_window_ns_;
  TimeBase time_base_;
  std::unique_ptr<OnlineCalibrator> cal_;
  std::unique_ptr<ModelCheck> check_;
  VecN<kMaxState> check_sigma_peak_;  // each parameter's largest sigma in the check's window
  PoseRing recent_;                   // poses the filter used, for a batch re-fit when it diverges
  PoseNoiseAdapter adapter_;
  BatchTier batch_;
  std::optional<BatchCalibration> calibration_;  // the last good batch
  Checkpoint calibration_checkpoint_;            // the same, as a checkpoint
  std::vector<std::string> held_;                // robot.fixed's names (checkpoints)
  kincal::calibration_t calibration_msg_{};
  PoseSample last_pose_;  // the newest pose the filter took (a restart's starting pose)
  std::vector<AddedEffect> added_;
  int consecutive_gated_ = 0;
  bool restart_armed_ = true;  // one restart per divergence episode
  int accepted_in_row_ = 0;    // updates since the last gated pose (re-arms the restart)
  TimeNs last_update_ns_ = TimeBase::kNever;
  TimeNs high_noise_since_ = TimeBase::kNever;  // adaptive noise above kInadequateNoiseLevel
  TimeNs last_params_ns_ = TimeBase::kNever, last_check_ns_ = TimeBase::kNever;
  TimeNs last_checkpoint_ns_ = 0;
  kincal::params_t params_msg_{};
  std::atomic<int> status_{0};  // params_t::STATUS_INITIALIZING
  Checkpoint estimate_;
};

}  // namespace kincal
