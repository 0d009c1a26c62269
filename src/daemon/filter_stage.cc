#include "daemon/filter_stage.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <kincal/model_check_t.hpp>

#include "daemon/messages.h"
#include "kincal/check.h"
#include "kincal/estimation/batch.h"
#include "kincal/scenario.h"

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
// The model check calls the filter diverged when, over at least this many innovations,
// the mean NIS exceeds its expectation this many times.
constexpr int kDivergedMinWindow = 100;
constexpr double kDivergedNisRatio = 10.0;

}  // namespace

FilterPrior ConfiguredPrior(const System& sys, const RobotOptions& robot, const std::string& file) {
  const int np = sys.num_params();
  FilterPrior p{ParamsFrom(sys, robot.guess, file + ": robot.guess"), StateMat::Zero(np, np)};
  for (int i = 0; i < np; ++i) {
    const double s =
        robot.guess_sigma_fraction *
        std::max(std::abs(p.mean[i]), sys.params()[static_cast<size_t>(i)].default_sigma);
    p.covariance(i, i) = s * s;
  }
  return p;
}

int ResumeFrom(const System& sys, const Checkpoint& ck, FilterPrior* prior) {
  int matched = 0;
  for (size_t i = 0; i < ck.names.size(); ++i) {
    const int a = sys.ParamIndex(ck.names[i]);
    if (a < 0) continue;
    ++matched;
    prior->mean[a] = ck.values[i];
    for (size_t k = 0; k < ck.names.size(); ++k) {
      const int b = sys.ParamIndex(ck.names[k]);
      if (b >= 0) prior->covariance(a, b) = ck.covariance(static_cast<int>(i), static_cast<int>(k));
    }
  }
  return matched;
}

FilterStageOptions FilterStageOptionsFrom(const DaemonConfig& c) {
  FilterStageOptions o;
  o.filter = c.filter;
  o.effects = c.robot.effects;
  o.model_check_every_s = 1.0 / c.health_rate_hz;
  o.checkpoint_path = c.checkpoint.path;
  o.checkpoint_every_s = c.checkpoint.every_s;
  return o;
}

bool FilterStageOptions::IsValid(std::string* error) const {
  if (!filter.IsValid(error)) return false;
  if (!(model_check_every_s > 0) || !(checkpoint_every_s > 0)) {
    *error = "the model check and checkpoint periods must be > 0";
    return false;
  }
  return true;
}

FilterStage::FilterStage(const System& sys, FilterStageOptions options, FilterPrior prior,
                         std::function<bool(ControlSample*)> next_control, FilterOutputs outputs,
                         CounterSet* counters)
    : sys_(sys),
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
      recent_(kRecentPoses) {
  std::string invalid;
  KINCAL_CHECK(opt_.IsValid(&invalid), invalid.c_str());  // the daemon's config was validated
  const FilterOptions& f = opt_.filter;
  calibrator_options_.filter = f.type;
  calibrator_options_.noise.control_psd =
      f.control_psd.empty() ? std::vector<double>(static_cast<size_t>(sys.num_controls()), 0.0)
                            : f.control_psd;
  calibrator_options_.noise.pose_psd = Eigen::Vector3d(f.pose_psd[0], f.pose_psd[1], f.pose_psd[2]);
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
    cal_ = std::make_unique<OnlineCalibrator>(sys_, calibrator_options_, t);
    check_ = std::make_unique<ModelCheck>(sys_);
  }
  if (cal_->initialized() && t < cal_->time_ns()) counters_.controls_late.fetch_add(1);
  const std::span<const double> values(c.values.data(), static_cast<size_t>(sys_.num_controls()));
  if (!cal_->AddControl(t, values)) {
    counters_.controls_out_of_order.fetch_add(1);
    return;
  }
  time_base_.ControlUsed(t);
}

// ---- time base --------------------------------------------------------------------------

// A clock jumped back: start a new time base. Parameters and their covariance carry over as
// the prior; the control history and the pose are dropped.
void FilterStage::StartNewBase(const char* what, TimeNs t, TimeBase::Stream by) {
  const int np = sys_.num_params();
  if (cal_ && cal_->initialized()) {
    prior_.mean.head(np) = cal_->params().head(np);
    prior_.covariance = cal_->params_covariance();
  }
  cal_.reset();
  check_.reset();
  recent_.clear();
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
    Update(p, t);
  }
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

void FilterStage::Update(const PoseSample& p, TimeNs t) {
  const UpdateResult r = cal_->AddPose(t, p.xytheta, p.covariance, opt_.filter.gate_nis);
  if (r.gated) {
    counters_.poses_gated.fetch_add(1);
    if (++consecutive_gated_ >= opt_.filter.divergence_gated) Recover(p, t);
  } else if (r.ok) {
    consecutive_gated_ = 0;
    counters_.updates.fetch_add(1);
    check_->Add(t, r, cal_->state(), cal_->controls());
  }
}

// Divergence: the filter has rejected divergence_gated poses in a row. Re-fit the parameters
// by batch (robust loss) over the recent poses and controls, and start the filter again from
// that estimate (or from the prior if the fit fails).
void FilterStage::Recover(const PoseSample& p, TimeNs t) {
  const int np = sys_.num_params();
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
  VecN<kMaxState> start = prior_.mean;
  StateMat start_cov = prior_.covariance;
  std::string how = "the configured prior";
  if (meas.size() >= kRefitMinPoses) {
    BatchOptions bo;
    bo.huber_scale = kRefitHuberSigmas;
    bo.max_iterations = kRefitMaxIterations;
    bo.warmup_s = 0.0;
    const BatchResult br = FitBatch(sys_, cal_->controls(), meas, prior_.mean.head(np), bo);
    if (!br.status.ok()) {
      spdlog::warn("batch re-fit failed: {}", br.status.message());
    } else if (br.params.allFinite() && br.covariance.rows() == np && br.covariance.allFinite()) {
      start = cal_->params();
      start.head(np) = br.params;
      start_cov = kRefitCovarianceInflation * br.covariance;
      how = "a batch fit over " + std::to_string(meas.size()) + " poses";
    }
  }
  auto fresh =
      std::make_unique<OnlineCalibrator>(sys_, calibrator_options_, cal_->controls().origin_ns());
  fresh->controls() = cal_->controls();
  fresh->Initialize(t, p.xytheta, p.covariance, start, start_cov);
  cal_ = std::move(fresh);
  check_->Reset();
  consecutive_gated_ = 0;
  counters_.filter_resets.fetch_add(1);
  spdlog::warn("filter diverged ({} poses in a row failed the innovation gate): restarted from {}",
               opt_.filter.divergence_gated, how);
}

// ---- outputs ----------------------------------------------------------------------------

int FilterStage::ParamsStatus(bool converged) const {
  const ModelCheckVerdict verdict = check_->Verdict();
  const bool nis_far_off = verdict.window >= kDivergedMinWindow &&
                           verdict.nis_mean > kDivergedNisRatio * verdict.nis_expected;
  if (consecutive_gated_ > 0 && consecutive_gated_ < opt_.filter.divergence_gated) {
    return kincal::params_t::STATUS_CONVERGING;
  }
  if (nis_far_off || consecutive_gated_ > 0) return kincal::params_t::STATUS_DIVERGED;
  return converged ? kincal::params_t::STATUS_CONVERGED : kincal::params_t::STATUS_CONVERGING;
}

void FilterStage::PublishParams(TimeNs t, bool force) {
  if (!cal_ || !cal_->initialized()) return;
  if (!force && t - last_params_ns_ < params_every_ns_) return;
  last_params_ns_ = t;
  kincal::params_t& m = params_msg_;
  FillParamsMessage(sys_, cal_->params(), cal_->params_covariance(), cal_->filter_name(),
                    cal_->update_count(), PipelineNsToUtime(t), &m);
  bool converged = true;
  for (size_t i = 0; i < m.sigmas.size(); ++i) {
    converged =
        converged && m.sigmas[i] < kConvergedSigmaFraction * prior_sigma_[static_cast<int>(i)];
  }
  m.status = static_cast<int8_t>(ParamsStatus(converged));
  out_.params(m.utime, m);
  FillCheckpoint(m, opt_.effects, &estimate_);
  out_.estimate(estimate_);
}

void FilterStage::PublishModelCheck(TimeNs t) {
  last_check_ns_ = t;
  const int64_t utime = PipelineNsToUtime(t);
  out_.model_check(utime,
                   ModelCheckMessage(check_->Verdict(), std::string(sys_.model().name()), utime));
}

void FilterStage::Finish() {
  if (!cal_ || !cal_->initialized()) return;
  PublishParams(time_base_.last_pose_ns(), true);
  if (!opt_.checkpoint_path.empty()) out_.checkpoint_due();
}

}  // namespace kincal::daemon
