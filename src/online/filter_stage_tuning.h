// The filter stage's fixed choices (filter_stage*.cc): when it re-fits, restarts, calls a
// parameter converged or the model inadequate, and follows a batch calibration. Private to
// the online layer.
#pragma once

#include <cstddef>

namespace kincal::filter_stage_tuning {

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

}  // namespace kincal::filter_stage_tuning
