#include "daemon/filter_stage.h"

#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <kincal/model_check_t.hpp>
#include <limits>
#include <map>

#include "daemon/messages.h"
#include "kincal/check.h"
#include "kincal/estimation/batch.h"
#include "kincal/plan/planner.h"
#include "kincal/sim/scenario.h"

namespace kincal::daemon {
namespace {

// Recent poses kept for a divergence re-fit (the re-fit uses filter.batch_window_s of them).
constexpr size_t kRecentPoses = 4096;
// The divergence re-fit: a robust (Huber) loss at this many sigma, a bounded solve, and its
// covariance inflated by this factor (the window is short and had outliers).
constexpr double kRefitHuberSigmas = 2.0;
constexpr int kRefitMaxIterations = 50;
constexpr double kRefitCovarianceInflation = 4.0;
constexpr size_t kRefitMinPoses = 10;
// A parameter has converged when its sigma is below this fraction of its prior sigma.
constexpr double kConvergedSigmaFraction = 0.05;
// A verdict against the model is judged again on fresh innovations when a parameter's sigma
// has fallen this much since the check's window began (RejudgeOnSettledInnovations).
constexpr double kCheckForgetFactor = 2.0;
// The innovations after the model check's window restarted before the pose noise's level
// may call the model inadequate (the check's own least for a verdict,
// ModelCheckOptions::min_samples).
constexpr int kSettledInnovations = 100;
// A re-fit replaces the running estimate only if every parameter's re-fit sigma is within
// this factor of the running one (its window excites the parameters) ...
constexpr double kRefitMaxSigmaRatio = 3.0;
// ... and its cost on the window is below this fraction of the running estimate's: the
// running parameters are wrong, not just the model (which would leave both fits poor).
constexpr double kRefitMaxCostFraction = 0.25;
// Beyond the gate this many times in a row, poses are used with a widened covariance
// (robust update) instead of being dropped: the innovations are persistent, not outliers.
constexpr int kRobustAfterGated = 2;
// Status DIVERGED: beyond the gate this many times filter.divergence_gated poses in a row.
constexpr int kDivergedStreakFactor = 3;
// The filter is re-centred on a batch calibration it is further from than this many
// combined sigmas (of any parameter); "converged" needs it within.
constexpr double kRecentreSigmas = 3.0;
// Without an accepted re-fit, the running estimate restarts with its covariance times this.
constexpr double kRestartCovarianceInflation = 4.0;
// After a restart, this many accepted updates in a row end the divergence episode.
constexpr int kEpisodeEndUpdates = 100;
// Adaptive noise above this level (measurement variances per frame interval) means the
// model misses something; "converged" needs it below kAdequateNoiseLevel.
constexpr double kInadequateNoiseLevel = 0.3;
constexpr double kAdequateNoiseLevel = 0.05;

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

FilterPrior ConfiguredPrior(const System& sys, const RobotOptions& robot, const std::string& file) {
  const int np = sys.num_params();
  // robot.guess names only parameters of the model (DaemonConfig::IsValid): an error is a bug.
  FilterPrior p{ParamsFrom(sys, robot.guess, file + ": robot.guess").value(),
                StateMat::Zero(np, np)};
  for (int i = 0; i < np; ++i) {
    const double s =
        robot.guess_sigma_fraction *
        std::max(std::abs(p.mean[i]), sys.params()[static_cast<size_t>(i)].default_sigma);
    p.covariance(i, i) = s * s;
  }
  HoldFixed(sys, robot.fixed, &p.mean, &p.covariance);
  return p;
}

void HoldFixed(const System& sys, const std::map<std::string, double>& fixed, VecN<kMaxState>* mean,
               StateMat* covariance) {
  for (const auto& [name, v] : fixed) {
    const int i = sys.model().ParamIndex(name);  // validated with the config
    if (i < 0) continue;
    (*mean)[i] = v;
    covariance->row(i).setZero();
    covariance->col(i).setZero();
    const double s = kHeldSigmaFraction * sys.params()[static_cast<size_t>(i)].default_sigma;
    (*covariance)(i, i) = s * s;
  }
}

int ResumeFrom(const System& sys, const Checkpoint& ck, FilterPrior* prior) {
  const auto held = [&ck](const std::string& name) {
    return std::find(ck.held.begin(), ck.held.end(), name) != ck.held.end();
  };
  int matched = 0;
  for (size_t i = 0; i < ck.names.size(); ++i) {
    const int a = sys.ParamIndex(ck.names[i]);
    if (a < 0) continue;
    ++matched;
    prior->mean[a] = ck.values[i];
    // Held in the earlier run: its value, with this run's prior spread (zero would freeze
    // it; this run's robot.fixed holds it again when it is still held).
    if (held(ck.names[i])) continue;
    for (size_t k = 0; k < ck.names.size(); ++k) {
      const int b = sys.ParamIndex(ck.names[k]);
      if (b >= 0 && !held(ck.names[k])) {
        prior->covariance(a, b) = ck.covariance(static_cast<int>(i), static_cast<int>(k));
      }
    }
  }
  return matched;
}

FilterStageOptions FilterStageOptionsFrom(const DaemonConfig& c) {
  FilterStageOptions o;
  o.filter = c.filter;
  o.effects = c.robot.effects;
  o.fixed = c.robot.fixed;
  o.model_check_every_s = 1.0 / c.health_rate_hz;
  o.checkpoint_path = c.checkpoint.path;
  o.checkpoint_every_s = c.checkpoint.every_s;
  o.auto_effects = c.robot.auto_effects;
  o.calibration.enabled = c.calibration.enabled;
  o.calibration.every_s = c.calibration.every_s;
  o.calibration.first_s = c.calibration.first_s;
  o.calibration.growth = c.calibration.growth;
  o.calibration.threads = c.calibration.threads;
  o.calibration.max_effects = c.calibration.max_effects;
  o.calibration.store.max_poses = c.calibration.max_poses;
  o.calibration.store.max_controls = c.calibration.max_controls;
  o.calibration.store.block_s = c.calibration.block_s;
  return o;
}

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
                         CounterSet* counters)
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
             GuessByName(sys, prior_), sys.num_controls()) {
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

// The innovations have run far beyond the prediction (the adaptive noise is high) for a
// whole re-fit window: either the parameters are wrong (an overconfident prior, a changed
// robot) or the model misses an effect. A re-fit tells them apart (RefitIsBetter); it is
// tried once per episode, which ends when the noise is back to normal.
void FilterStage::TrackEpisode(const PoseSample& p, TimeNs t) {
  if (adapter_.level() > kInadequateNoiseLevel) {
    if (high_noise_since_ == TimeBase::kNever) high_noise_since_ = t;
  } else if (adapter_.level() < kAdequateNoiseLevel) {
    high_noise_since_ = TimeBase::kNever;
    if (accepted_in_row_ >= kEpisodeEndUpdates) restart_armed_ = true;
  }
  if (restart_armed_ && high_noise_since_ != TimeBase::kNever &&
      t - high_noise_since_ >= batch_window_ns_) {
    Recover(p, t, /*diverged=*/false);
  }
}

std::vector<PoseMeasurement> FilterStage::RecentMeasurements(TimeNs t) const {
  std::vector<PoseMeasurement> meas;
  int segment = 0;
  TimeNs prev = TimeBase::kNever;
  for (size_t k = 0; k < recent_.size(); ++k) {
    const PoseSample& r = recent_.at(k);
    const TimeNs rt = UtimeToPipelineNs(r.utime);
    if (rt < t - batch_window_ns_) continue;
    if (prev != TimeBase::kNever && rt - prev > max_gap_ns_) ++segment;
    prev = rt;
    meas.push_back({rt, r.xytheta, r.covariance, segment});
  }
  return meas;
}

// A re-fit replaces the running estimate only when its window informs every parameter about
// as well as the filter does, and it explains the window's poses clearly better than the
// running estimate (whose cost there is the fit's initial cost: it starts from it).
bool FilterStage::RefitIsBetter(const BatchResult& refit, const std::vector<PoseMeasurement>& meas,
                                std::string* why) const {
  const int np = sys_->num_params();
  if (!refit.status.ok() || !refit.params.allFinite() || refit.covariance.rows() != np ||
      !refit.covariance.allFinite()) {
    *why = refit.status.ok() ? "no usable covariance" : refit.status.message();
    return false;
  }
  const StateMat running = cal_->params_covariance();
  for (int i = 0; i < np; ++i) {
    const double ratio = std::sqrt(refit.covariance(i, i) / running(i, i));
    if (!(ratio <= kRefitMaxSigmaRatio)) {
      *why = "its " + std::to_string(meas.size()) + " poses do not excite " +
             sys_->params()[static_cast<size_t>(i)].name;
      return false;
    }
  }
  if (!(refit.final_cost < kRefitMaxCostFraction * refit.initial_cost)) {
    *why = "it explains the last poses little better than the running estimate (cost " +
           std::to_string(refit.final_cost) + " against " + std::to_string(refit.initial_cost) +
           ")";
    return false;
  }
  return true;
}

// Divergence: the filter has rejected divergence_gated poses in a row although its process
// noise adapts. Re-fit the parameters by batch (robust loss) over the recent poses and
// controls, starting from the running estimate; restart the filter from the re-fit if it
// is better (RefitIsBetter), else from the running estimate with a wider covariance. Never
// from the configured prior: the data so far are worth more.
void FilterStage::Recover(const PoseSample& p, TimeNs t, bool diverged) {
  const int np = sys_->num_params();
  const std::vector<PoseMeasurement> meas = RecentMeasurements(t);
  VecN<kMaxState> start = cal_->params();
  StateMat start_cov = kRestartCovarianceInflation * cal_->params_covariance();
  std::string how = "the running estimate (no re-fit: too few poses)";
  std::string fallback = "the running estimate";
  if (calibration_ && calibration_->unique && calibration_->effects == effects_) {
    // The whole run's calibration is a better place to restart from than the filter's
    // recent opinion (which is what diverged).
    SetFromCalibration(*calibration_, kRestartCovarianceInflation, &start, &start_cov);
    fallback = "batch calibration " + std::to_string(calibration_->sequence);
    how = fallback + " (no re-fit: too few poses)";
  }
  if (meas.size() >= kRefitMinPoses) {
    BatchOptions bo;
    bo.huber_scale = kRefitHuberSigmas;
    bo.max_iterations = kRefitMaxIterations;
    bo.warmup_s = 0.0;
    const BatchResult br = FitBatch(*sys_, cal_->controls(), meas, start.head(np), bo);
    std::string why;
    if (RefitIsBetter(br, meas, &why)) {
      start.head(np) = br.params;
      start_cov = kRefitCovarianceInflation * br.covariance;
      how = "a batch fit over " + std::to_string(meas.size()) + " poses";
    } else if (!diverged) {
      restart_armed_ = false;  // model error: the filter goes on, and says so
      spdlog::info(
          "innovations beyond the model for {:.1f} s; a re-fit does not explain them ({}): "
          "the model misses an effect",
          NsToSeconds(t - high_noise_since_), why);
      return;
    } else {
      how = fallback + " (re-fit not used: " + why + ")";
    }
  } else if (!diverged) {
    restart_armed_ = false;
    return;
  }
  auto fresh =
      std::make_unique<OnlineCalibrator>(*sys_, calibrator_options_, cal_->controls().origin_ns());
  fresh->controls() = cal_->controls();
  fresh->Initialize(t, p.xytheta, p.covariance, start, start_cov);
  cal_ = std::move(fresh);
  adapter_.Reset();
  consecutive_gated_ = 0;
  restart_armed_ = false;  // until kEpisodeEndUpdates updates in a row end the episode
  counters_.filter_resets.fetch_add(1);
  high_noise_since_ = TimeBase::kNever;
  if (diverged) {
    spdlog::warn(
        "filter diverged ({} poses in a row failed the innovation gate): restarted from {}",
        opt_.filter.divergence_gated, how);
  } else {
    spdlog::warn("the running parameters did not explain the last poses: restarted from {}", how);
  }
}

bool FilterStage::RejudgeOnSettledInnovations(const kincal::params_t& m,
                                              const ModelCheckVerdict& verdict) {
  const int np = static_cast<int>(m.sigmas.size());
  if (check_sigma_peak_.size() != np) check_sigma_peak_ = VecN<kMaxState>::Zero(np);
  bool fell = false;
  for (int i = 0; i < np; ++i) {
    const double s = m.sigmas[static_cast<size_t>(i)];
    check_sigma_peak_[i] = std::max(check_sigma_peak_[i], s);
    fell = fell || kCheckForgetFactor * s < check_sigma_peak_[i];
  }
  if (!fell || !ModelInadequate(verdict)) return false;
  check_->Reset();
  for (int i = 0; i < np; ++i) check_sigma_peak_[i] = m.sigmas[static_cast<size_t>(i)];
  return true;
}

// ---- outputs ----------------------------------------------------------------------------

// A named effect, or pose noise the model cannot explain; the noise only once the check's
// window holds kSettledInnovations innovations from after its last restart (before that,
// the adaptive noise still answers the innovations of an estimate that had not settled).
bool FilterStage::ModelInadequate(const ModelCheckVerdict& v) const {
  return !v.suspected_effect.empty() ||
         (v.window >= kSettledInnovations && adapter_.level() > kInadequateNoiseLevel);
}

// The status the parameters are published with; health reports the same.
int FilterStage::ParamsStatus(bool sigmas_small, const ModelCheckVerdict& verdict, TimeNs t) const {
  // Robust updates that have not brought the innovations back within the gate for this
  // long: the filter has lost the robot. Shorter streaks are the model's error.
  if (consecutive_gated_ >= kDivergedStreakFactor * opt_.filter.divergence_gated) {
    return kincal::params_t::STATUS_DIVERGED;
  }
  if (ModelInadequate(verdict) || consecutive_gated_ >= opt_.filter.divergence_gated) {
    return kincal::params_t::STATUS_MODEL_INADEQUATE;
  }
  const bool updated_recently =
      last_update_ns_ != TimeBase::kNever && t - last_update_ns_ <= max_gap_ns_;
  // Converged: the filter has settled, the model check finds nothing, and the filter agrees
  // with the whole run's batch calibration (none yet: not converged).
  if (sigmas_small && updated_recently && consecutive_gated_ == 0 && verdict.consistent &&
      adapter_.level() < kAdequateNoiseLevel && DisagreementSigmas(nullptr) <= kRecentreSigmas) {
    return kincal::params_t::STATUS_CONVERGED;
  }
  return kincal::params_t::STATUS_CONVERGING;
}

void FilterStage::PublishParams(TimeNs t, bool force) {
  if (!cal_ || !cal_->initialized()) return;
  if (!force && t - last_params_ns_ < params_every_ns_) return;
  last_params_ns_ = t;
  kincal::params_t& m = params_msg_;
  FillParamsMessage(*sys_, cal_->params(), cal_->params_covariance(), cal_->filter_name(),
                    counters_.updates.load(), PipelineNsToUtime(t), &m);
  bool sigmas_small = true;
  for (size_t i = 0; i < m.sigmas.size(); ++i) {
    if (i < sys_->params().size() && opt_.fixed.count(sys_->params()[i].name)) continue;  // held
    sigmas_small =
        sigmas_small && m.sigmas[i] < kConvergedSigmaFraction * prior_sigma_[static_cast<int>(i)];
  }
  ModelCheckVerdict verdict = check_->Verdict();
  if (RejudgeOnSettledInnovations(m, verdict)) verdict = check_->Verdict();
  m.status = static_cast<int8_t>(ParamsStatus(sigmas_small, verdict, t));
  status_.store(m.status);
  out_.params(m.utime, m);
  FillCheckpoint(m, effects_, &estimate_);
  MarkHeld(held_, &estimate_);  // the filter's negligible sigma: zero, as the batch's
  out_.estimate(estimate_);
}

void FilterStage::PublishModelCheck(TimeNs t) {
  last_check_ns_ = t;
  const int64_t utime = PipelineNsToUtime(t);
  const ModelCheckVerdict verdict = check_->Verdict();
  kincal::model_check_t m =
      ModelCheckMessage(verdict, ModelLabel(sys_->model().name(), effects_), utime);
  m.adaptive_noise = adapter_.level();
  if (verdict.suspected_effect.empty() && adapter_.level() > kInadequateNoiseLevel) {
    m.evidence = fmt::format(
        "innovations beyond the model: the filter adds {:.3g} measurement "
        "variances of pose noise per frame; {}",
        adapter_.level(), verdict.evidence);
  }
  m.num_added = static_cast<int32_t>(added_.size());
  for (const auto& a : added_) {
    m.effects_added.push_back(a.name);
    m.added_utime.push_back(a.utime);
    m.heldout_before_m.push_back(a.heldout_before_m);
    m.heldout_after_m.push_back(a.heldout_after_m);
  }
  out_.model_check(utime, m);
}

// ---- the batch tier ----------------------------------------------------------------------

// The filter starts again on `sys` from (mean, cov) at pose p, keeping the control history.
void FilterStage::StartFilterAt(const std::shared_ptr<const System>& sys,
                                const VecN<kMaxState>& mean, const StateMat& cov,
                                const PoseSample& p, TimeNs t) {
  auto cal =
      std::make_unique<OnlineCalibrator>(*sys, calibrator_options_, cal_->controls().origin_ns());
  cal->controls() = cal_->controls();
  cal->Initialize(t, p.xytheta, p.covariance, mean, cov);
  cal_ = std::move(cal);
  if (sys != sys_) {
    check_ = std::make_unique<ModelCheck>(*sys);
    check_sigma_peak_.resize(0);
  }
  sys_ = sys;
  adapter_.Reset();
  consecutive_gated_ = 0;
  high_noise_since_ = TimeBase::kNever;
}

double FilterStage::DisagreementSigmas(std::string* worst) const {
  if (!calibration_ || !calibration_->unique || !cal_ || !cal_->initialized() ||
      calibration_->effects != effects_) {
    return std::numeric_limits<double>::infinity();
  }
  const VecN<kMaxState> f = cal_->params();
  const StateMat fc = cal_->params_covariance();
  double most = 0.0;
  for (size_t i = 0; i < calibration_->params.size(); ++i) {
    const ParamEstimate& b = calibration_->params[i];
    const int k = sys_->ParamIndex(b.name);
    if (k < 0) return std::numeric_limits<double>::infinity();
    if (opt_.fixed.count(b.name)) continue;  // held by both
    const double z = std::abs(f[k] - b.value) / std::sqrt(fc(k, k) + b.sigma * b.sigma);
    if (!(z <= most)) {
      most = z;
      if (worst != nullptr) *worst = b.name;
    }
  }
  return most;
}

void FilterStage::PublishCalibration(const BatchCalibration& r, TimeNs t) {
  const BatchCalibration* good = calibration_ ? &*calibration_ : nullptr;
  FillCalibrationMessage(r, good, std::string(sys_->model().name()), batch_.store().poses_thinned(),
                         &calibration_msg_);
  if (good != nullptr) {
    kincal::params_t m;
    FillParamsFromCalibration(*good, std::string(sys_->model().name()), counters_.updates.load(),
                              PipelineNsToUtime(t), &m);
    FillCheckpoint(m, good->effects, &calibration_checkpoint_);
    MarkHeld(held_, &calibration_checkpoint_);
    calibration_checkpoint_.batch_sequence = good->sequence;
    calibration_checkpoint_.batch_poses = good->num_poses;
  }
  if (out_.calibration) {
    out_.calibration(calibration_msg_.utime, calibration_msg_,
                     good != nullptr ? &calibration_checkpoint_ : nullptr);
  }
}

// A batch calibration: published; then the filter follows it when they differ (its model,
// or its values beyond kRecentreSigmas of their combined sigmas). A failed batch leaves the
// last good calibration in place and says why.
void FilterStage::ApplyBatch(const BatchCalibration& r, const PoseSample& p, TimeNs t) {
  counters_.batch_runs.fetch_add(1);
  if (!r.ok) {
    counters_.batch_failed.fetch_add(1);
    spdlog::warn("batch calibration {} failed ({}); {}", r.sequence, r.error,
                 calibration_ ? "the calibration of batch " +
                                    std::to_string(calibration_->sequence) + " stays"
                              : std::string("no calibration yet"));
    PublishCalibration(r, t);
    return;
  }
  calibration_ = r;
  if (opt_.resumed) {
    std::string why;
    calibration_ = FusedWithResumed(r, *opt_.resumed, &why);
    if (calibration_->prior.empty()) {
      spdlog::info("batch calibration {} is this run's alone: {}", r.sequence, why);
    }
  }
  PublishCalibration(r, t);
  spdlog::info(
      "batch calibration {}: {} poses in {:.1f} s; held-out error {:.2f} mm -> {:.2f} mm{}",
      r.sequence, r.num_poses, r.compute_s, 1e3 * r.heldout_before_m, 1e3 * r.heldout_after_m,
      r.accepted.empty() ? std::string() : fmt::format(" with {}", fmt::join(r.accepted, ", ")));
  if (!cal_ || !cal_->initialized()) return;
  if (!r.unique) {  // published as analyze reports it; the filter does not follow it
    spdlog::warn("batch calibration {} is not unique: {}", r.sequence, r.warnings);
    return;
  }
  if (r.effects != effects_) {
    Rebuild(*calibration_, p, t);
    return;
  }
  std::string worst;
  const double z = DisagreementSigmas(&worst);
  if (z > kRecentreSigmas) {
    spdlog::info("the filter's {} is {:.1f} sigma from batch calibration {}: re-centred on it",
                 worst, z, r.sequence);
    Recentre(*calibration_, p, t);
  }
}

// A batch calibration's values and covariance (times cov_scale) into the running model's
// parameter mean and covariance, by name (the calibration's model is the filter's).
void FilterStage::SetFromCalibration(const BatchCalibration& r, double cov_scale,
                                     VecN<kMaxState>* mean, StateMat* cov) const {
  for (size_t i = 0; i < r.params.size(); ++i) {
    const int a = sys_->ParamIndex(r.params[i].name);
    (*mean)[a] = r.params[i].value;
    for (size_t k = 0; k < r.params.size(); ++k) {
      (*cov)(a, sys_->ParamIndex(r.params[k].name)) =
          cov_scale * r.covariance(static_cast<int>(i), static_cast<int>(k));
    }
  }
  HoldFixed(*sys_, opt_.fixed, mean, cov);  // the batch's zero variance, as the filter holds it
}

void FilterStage::Recentre(const BatchCalibration& r, const PoseSample& p, TimeNs t) {
  const int np = sys_->num_params();
  VecN<kMaxState> mean = cal_->params();
  StateMat cov = StateMat::Zero(np, np);
  SetFromCalibration(r, 1.0, &mean, &cov);
  StartFilterAt(sys_, mean, cov, p, t);
  counters_.filter_recentres.fetch_add(1);
}

// The batch's model differs from the filter's (effects accepted or no longer supported):
// the filter starts again on the batch's model from its calibration, keeping the control
// history.
void FilterStage::Rebuild(const BatchCalibration& r, const PoseSample& p, TimeNs t) {
  std::unique_ptr<System> made;
  if (const Status s = MakeSystem(sys_->model().name(), r.effects, {}, &made); !s.ok()) {
    spdlog::warn("batch calibration {}: its model cannot run: {}", r.sequence, s.message());
    return;
  }
  const std::shared_ptr<const System> sys = std::move(made);
  const int np = sys->num_params();
  VecN<kMaxState> mean = VecN<kMaxState>::Zero(np);
  StateMat cov = StateMat::Zero(np, np);
  Eigen::VectorXd prior_sigma(np);
  for (int i = 0; i < np; ++i) {
    const ParamInfo& info = sys->params()[static_cast<size_t>(i)];
    mean[i] = r.params[static_cast<size_t>(i)].value;
    for (int k = 0; k < np; ++k) cov(i, k) = r.covariance(i, k);
    const int old = sys_->ParamIndex(info.name);
    prior_sigma[i] = old >= 0 ? prior_sigma_[old] : info.default_sigma;
  }
  const std::vector<std::string> before = effects_;
  StartFilterAt(sys, mean, cov, p, t);
  effects_ = r.effects;
  prior_sigma_ = prior_sigma;
  restart_armed_ = true;
  std::vector<AddedEffect> added;
  for (const auto& name : r.accepted) {
    AddedEffect a{name, PipelineNsToUtime(t), r.heldout_before_m, r.heldout_after_m};
    for (const auto& old : added_) {
      if (old.name == name) a = old;  // added before: keeps when and what it changed then
    }
    if (std::find(before.begin(), before.end(), name) == before.end()) {
      counters_.effects_added.fetch_add(1);
      spdlog::info("added {}: held-out error {:.4f} m -> {:.4f} m; filter restarted on the model",
                   name, r.heldout_before_m, r.heldout_after_m);
    }
    added.push_back(a);
  }
  for (const auto& name : before) {
    if (std::find(r.effects.begin(), r.effects.end(), name) != r.effects.end()) continue;
    counters_.effects_removed.fetch_add(1);
    spdlog::info("removed {}: batch calibration {} no longer supports it", name, r.sequence);
  }
  added_ = std::move(added);
}

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

void FilterStage::PublishFinalCalibration(TimeNs t) {
  kincal::params_t& m = params_msg_;
  FillParamsFromCalibration(*calibration_, std::string(sys_->model().name()),
                            counters_.updates.load(), PipelineNsToUtime(t), &m);
  m.status = static_cast<int8_t>(status_.load());
  out_.params(m.utime, m);
}

}  // namespace kincal::daemon
