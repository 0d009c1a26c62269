// The windows `kincal analyze` predicts over: a recording cut into prediction windows of
// one horizon (evaluation windows at every strided pose, non-overlapping fit windows in
// the fit span, shorter ones for the multi-start stage), with the pose weights.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "kincal/analysis/analyze.h"
#include "kincal/estimation/batch.h"
#include "kincal/io/recording.h"
#include "kincal/signature.h"

namespace kincal::analysis {

// What every fit of one recording respects: parameters held at their value (--fix, System
// indices) and the runs' starts (no warm-up crosses one).
struct FitLimits {
  std::vector<int> fixed;
  std::vector<TimeNs> run_starts;
};

struct Window {
  int start;  // pose index
  int end;    // pose index of the horizon end
};

struct Dataset {
  const Recording* rec = nullptr;
  std::vector<double> t;      // pose times, s since origin
  std::vector<int> next_gap;  // per pose: the first pose after which a gap follows
  double t_ctrl0 = 0, t_ctrl1 = 0, t_split = 0;
  double horizon = 1.0;
  double pose_interval = 0.0;  // median interval between consecutive poses, s
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector2d sigma{1, 1};
  std::vector<Window> eval;           // every (strided) pose with a horizon end
  std::vector<Window> fit_windows;    // non-overlapping, in the fit span
  std::vector<Window> short_windows;  // shorter, for the multi-start stage
  std::vector<PoseMeasurement> fit_meas, short_meas;
  // Every screen_stride-th fit window: candidates are screened on these, then the leading
  // ones confirmed on all (the fit windows themselves when there are too few).
  std::vector<PoseMeasurement> screen_meas;
  std::vector<RegressorValues> features;  // per eval window (regressors.h)
  // Held parameters (--fix) and the runs' starts: what every fit of this data respects.
  FitLimits limits;
  // Runs: each pose's run, each run's start (s) and whether it is held out. With two or
  // more runs whole runs are held out (AnalyzeOptions::heldout_runs); otherwise the time
  // after t_split.
  std::vector<int> run;
  std::vector<double> run_start_s;
  std::vector<bool> run_heldout;
  bool by_runs = false;
  // Is time t (s) in the held-out part?
  bool HeldOutAt(double t_s) const;
};

// Cuts the recording into windows; an error names the recording when it is too short or its
// controls and poses do not overlap enough. Pose sigmas are estimated from second
// differences unless the options give them.
StatusOr<Dataset> Prepare(const Recording& rec, const AnalyzeOptions& o,
                          std::vector<std::string>* warnings);

}  // namespace kincal::analysis
