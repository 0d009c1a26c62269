#include "kincal/online/filter_stage.h"

#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <kincal/model_check_t.hpp>
#include <limits>
#include <map>

#include "kincal/check.h"
#include "kincal/estimation/batch.h"
#include "kincal/online/estimate_messages.h"
#include "kincal/plan/planner.h"
#include "kincal/sim/scenario.h"
#include "online/filter_stage_tuning.h"

namespace kincal {

using namespace filter_stage_tuning;  // the stage's constants (filter_stage_tuning.h)
namespace {

PoseNoiseAdaptationOptions AdaptationOptions(const FilterOptions& f) {
  PoseNoiseAdaptationOptions o;
  o.enabled = f.adaptive_noise;
  return o;
}

BatchTierOptions BatchTierOptionsFor(const FilterStageOptions& o) {
  BatchTierOptions b = o.calibration;
  b.auto_effects = o.auto_effects;
  b.fixed = o.fixed;
  b.lossless = o.lossless;
  return b;
}

// The prior's values by name: the batch starts where `kincal analyze --init` would.
std::map<std::string, double> GuessByName(const System& sys, const FilterPrior& prior) {
  std::map<std::string, double> guess;
  for (int i = 0; i < sys.num_params(); ++i) {
    guess[sys.params()[static_cast<size_t>(i)].name] = prior.mean[i];
  }
  return guess;
}

}  // namespace

bool FilterStageOptions::IsValid(std::string* error) const {
  if (!filter.IsValid(error)) return false;
  if (!(model_check_every_s > 0) || !(checkpoint_every_s > 0)) {
    *error = "the model check and checkpoint periods must be > 0";
    return false;
  }
  return calibration.IsValid(error);
}

FilterStage::FilterStage(const System& sys, FilterStageOptions options, FilterPrior prior,
                         std::function<bool(ControlSample*)> next_control, FilterOutputs outputs,
                         OnlineCounters* counters, std::unique_ptr<BatchRunner> batch_runner)
    : sys_(std::make_shared<System>(sys)),
      effects_(options.effects),
      opt_(std::move(options)),
      prior_(std::move(prior)),
      prior_sigma_(prior_.covariance.diagonal().cwiseSqrt()),
      next_control_(std::move(next_control)),
      out_(std::move(outputs)),
      counters_(*counters),
      max_gap_ns_(SecondsToNs(opt_.filter.max_pose_gap_s)),
      params_every_ns_(
          opt_.filter.params_rate_hz > 0 ? SecondsToNs(1.0 / opt_.filter.params_rate_hz) : 0),
      check_every_ns_(SecondsToNs(opt_.model_check_every_s)),
      checkpoint_every_ns_(SecondsToNs(opt_.checkpoint_every_s)),
      batch_window_ns_(SecondsToNs(opt_.filter.batch_window_s)),
      time_base_(max_gap_ns_),
      recent_(kRecentPoses),
      adapter_(AdaptationOptions(opt_.filter)),
      batch_(BatchTierOptionsFor(opt_), std::string(sys.model().name()), opt_.effects,
             GuessByName(sys, prior_), sys.num_controls(), std::move(batch_runner)) {
  std::string invalid;
  KINCAL_CHECK(opt_.IsValid(&invalid), invalid.c_str());  // the daemon's config was validated
  const FilterOptions& f = opt_.filter;
  calibrator_options_.filter = f.type;
  calibrator_options_.noise.control_psd =
      f.control_psd.empty() ? std::vector<double>(static_cast<size_t>(sys.num_controls()), 0.0)
                            : f.control_psd;
  calibrator_options_.noise.pose_psd = Eigen::Vector3d(f.pose_psd[0], f.pose_psd[1], f.pose_psd[2]);
  for (const auto& [name, value] : opt_.fixed) held_.push_back(name);
}

FilterStage::~FilterStage() = default;

// ---- controls -------------------------------------------------------------------------

void FilterStage::DrainControls(TimeNs now_mono_ns) {
  ControlSample c;
  while (!time_base_.holding() && next_control_(&c)) {
    const TimeNs t = UtimeToPipelineNs(c.utime);
    if (time_base_.FromOldBase(t, TimeBase::Stream::kControls)) {
      counters_.discarded_at_reset.fetch_add(1);
      continue;
    }
    if (time_base_.IsControlJump(t)) {
      time_base_.Hold(c, now_mono_ns);
      break;
    }
    AddControlSample(c);
  }
}

void FilterStage::AddControlSample(const ControlSample& c) {
  const TimeNs t = UtimeToPipelineNs(c.utime);
  if (!cal_) {
    cal_ = std::make_unique<OnlineCalibrator>(*sys_, calibrator_options_, t);
    check_ = std::make_unique<ModelCheck>(*sys_);
  }
  if (cal_->initialized() && t < cal_->time_ns()) counters_.controls_late.fetch_add(1);
  const std::span<const double> values(c.values.data(), static_cast<size_t>(sys_->num_controls()));
  if (!cal_->AddControl(t, values)) {
    counters_.controls_out_of_order.fetch_add(1);
    return;
  }
  batch_.AddControl(t, values);
  time_base_.ControlUsed(t);
}

// ---- time base --------------------------------------------------------------------------

// A clock jumped back: start a new time base. Parameters and their covariance carry over as
// the prior; the control history and the pose are dropped.
void FilterStage::StartNewBase(const char* what, TimeNs t, TimeBase::Stream by) {
  const int np = sys_->num_params();
  if (cal_ && cal_->initialized()) {
    prior_.mean.head(np) = cal_->params().head(np);
    prior_.covariance = cal_->params_covariance();
  }
  cal_.reset();
  check_.reset();
  recent_.clear();
  adapter_.Reset();
  high_noise_since_ = TimeBase::kNever;
  consecutive_gated_ = 0;
  last_update_ns_ = TimeBase::kNever;
  batch_.NewBase();
  time_base_.StartNew(t, by);
  counters_.time_resets.fetch_add(1);
  spdlog::warn("{} jumped back by more than filter.max_pose_gap_s: new time base, parameters kept",
               what);
}

// Starts the new time base at a jump (seen in the poses at t, or in the controls), with the
// held control and the ones queued behind it.
void FilterStage::TakeJump(const char* what, TimeNs t, TimeBase::Stream by, TimeNs now_mono_ns) {
  StartNewBase(what, t, by);
  if (time_base_.holding()) AddControlSample(time_base_.ReleaseHeld());
  DrainControls(now_mono_ns);
}

void FilterStage::TakeControlJump(TimeNs now_mono_ns) {
  if (!time_base_.holding()) return;
  TakeJump("the control clock", UtimeToPipelineNs(time_base_.held().utime),
           TimeBase::Stream::kControls, now_mono_ns);
}

// ---- poses ------------------------------------------------------------------------------

void FilterStage::AddPose(const PoseSample& p, TimeNs now_mono_ns) {
  if (!p.valid) return;
  const TimeNs t = UtimeToPipelineNs(p.utime);
  if (time_base_.FromOldBase(t, TimeBase::Stream::kPoses)) {
    counters_.discarded_at_reset.fetch_add(1);
    return;
  }
  if (time_base_.IsPoseJump(t)) {
    TakeJump(time_base_.holding() ? "the camera and control clocks" : "the camera clock", t,
             TimeBase::Stream::kPoses, now_mono_ns);
  }
  if (!cal_ || !time_base_.has_controls()) return;  // nothing to propagate with yet
  bool used = true;
  if (!cal_->initialized()) {
    // Start only where the controls in force are known (not before the first sample).
    if (cal_->controls().empty() || cal_->controls().ToNs(cal_->controls().TimeAt(0)) > t) return;
    cal_->Initialize(t, p.xytheta, p.covariance, prior_.mean, prior_.covariance);
  } else if (t <= time_base_.last_pose_ns() || t <= cal_->time_ns()) {
    counters_.frames_out_of_order.fetch_add(1);  // repeated or earlier than the last: not used
    return;
  } else if (t - time_base_.last_pose_ns() > max_gap_ns_) {
    cal_->ResetPose(t, p.xytheta, p.covariance);
    counters_.run_resets.fetch_add(1);
    consecutive_gated_ = 0;
  } else {
    used = Update(p, t);
  }
  last_pose_ = p;
  // The batch sees the poses the filter used: an isolated pose beyond the gate (a
  // reflection, a wrong match) is left out of both.
  if (used) batch_.AddPose(t, p.xytheta);
  if (auto done = batch_.OnPose(t)) ApplyBatch(*done, p, t);
  time_base_.PoseSeen(t);
  if (recent_.full()) recent_.pop();
  recent_.push(p);
  cal_->controls().DiscardBefore(cal_->controls().ToSeconds(t) - opt_.filter.control_history_s);
  PublishParams(t, false);
  if (t - last_check_ns_ >= check_every_ns_) PublishModelCheck(t);
  if (!opt_.checkpoint_path.empty() && t - last_checkpoint_ns_ >= checkpoint_every_ns_) {
    last_checkpoint_ns_ = t;
    out_.checkpoint_due();
  }
}

bool FilterStage::Update(const PoseSample& p, TimeNs t) {
  const double dt_s = NsToSeconds(t - cal_->time_ns());
  const Eigen::Vector3d extra = adapter_.ExtraPsd();
  cal_->set_extra_pose_psd(extra);
  const UpdateResult r = cal_->AddPose(t, p.xytheta, p.covariance, opt_.filter.gate_nis);
  if (!r.ok && !r.gated) return true;  // not positive definite: nothing learnt
  adapter_.Add(r.innovation.head<3>(), r.innovation_cov.topLeftCorner<3, 3>(), p.covariance,
               extra * dt_s, dt_s);
  check_->Add(t, r, cal_->state(), cal_->controls());  // gated innovations are evidence too
  if (r.gated) {
    accepted_in_row_ = 0;
    ++consecutive_gated_;
    if (consecutive_gated_ >= opt_.filter.divergence_gated && restart_armed_) {
      counters_.poses_gated.fetch_add(1);
      Recover(p, t, /*diverged=*/true);
      return true;
    }
    if (consecutive_gated_ < kRobustAfterGated) {  // an isolated outlier: not used
      counters_.poses_gated.fetch_add(1);
      return false;
    }
    // Persistent: the model, not the pose, is off. Use the pose with its covariance
    // widened to bring it to the gate (a robust update), so the filter never stalls.
    const UpdateResult robust =
        cal_->AddPose(t, p.xytheta, p.covariance * (r.nis / opt_.filter.gate_nis), 0.0);
    if (!robust.ok) return true;
    counters_.poses_downweighted.fetch_add(1);
  } else {
    consecutive_gated_ = 0;
  }
  last_update_ns_ = t;
  counters_.updates.fetch_add(1);
  ++accepted_in_row_;
  TrackEpisode(p, t);
  return true;
}

// ---- outputs ----------------------------------------------------------------------------

// ---- the batch tier ----------------------------------------------------------------------

// At shutdown: the last batch over the whole run, then the final parameters. With a batch
// calibration the last params_t carries it (source SOURCE_BATCH): what a user reads at the
// end of a run is what the data say, not the filter's recent opinion.
void FilterStage::Finish() {
  if (!cal_ || !cal_->initialized()) return;
  const TimeNs t = time_base_.last_pose_ns();
  const auto began = std::chrono::steady_clock::now();
  for (const BatchCalibration& r : batch_.Finish(t)) ApplyBatch(r, last_pose_, t);
  counters_.batch_shutdown_ms.fetch_add(std::chrono::duration_cast<std::chrono::milliseconds>(
                                            std::chrono::steady_clock::now() - began)
                                            .count());
  PublishParams(t, true);
  if (calibration_) PublishFinalCalibration(t);
  if (!opt_.checkpoint_path.empty()) out_.checkpoint_due();
}

}  // namespace kincal
