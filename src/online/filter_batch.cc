// The filter stage and the batch tier: a batch calibration published, and the filter
// re-centred on it or rebuilt on its model (effects added or removed online).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "kincal/online/estimate_messages.h"
#include "kincal/online/filter_stage.h"
#include "online/filter_stage_tuning.h"

namespace kincal {

using namespace filter_stage_tuning;  // the stage's constants (filter_stage_tuning.h)

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

}  // namespace kincal
