// The filter stage's outputs: the parameters with their status, the model check (its window
// restarted once the estimate settles), and the final calibration at shutdown.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "kincal/online/estimate_messages.h"
#include "kincal/online/filter_stage.h"
#include "online/filter_stage_tuning.h"

namespace kincal {

using namespace filter_stage_tuning;  // the stage's constants (filter_stage_tuning.h)

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

void FilterStage::PublishFinalCalibration(TimeNs t) {
  kincal::params_t& m = params_msg_;
  FillParamsFromCalibration(*calibration_, std::string(sys_->model().name()),
                            counters_.updates.load(), PipelineNsToUtime(t), &m);
  m.status = static_cast<int8_t>(status_.load());
  out_.params(m.utime, m);
}

}  // namespace kincal
