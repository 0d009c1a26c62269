// The filter stage when the filter diverges: an episode of innovations beyond their
// prediction, a re-fit over the recent poses, and the restart (filter_stage.h: Recover).
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "kincal/estimation/batch.h"
#include "kincal/online/estimate_messages.h"
#include "kincal/online/filter_stage.h"
#include "online/filter_stage_tuning.h"

namespace kincal {

using namespace filter_stage_tuning;  // the stage's constants (filter_stage_tuning.h)

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

}  // namespace kincal
