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
  std::vector<int> fixed;                 // model parameters held (--fix), System indices
};

// Cuts the recording into windows; throws AnalysisError naming the recording when it is too
// short or its controls and poses do not overlap enough. Pose sigmas are estimated from
// second differences unless the options give them.
Dataset Prepare(const Recording& rec, const AnalyzeOptions& o, std::vector<std::string>* warnings);

}  // namespace kincal::analysis
