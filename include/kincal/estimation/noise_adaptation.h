// PoseNoiseAdapter: adaptive process noise for a filter whose model may not fit.
//
// A model that lacks an effect (a delay, a lag, slip) makes the innovations larger than
// the filter predicts, and structured. With fixed process noise the filter then gates
// pose after pose and "diverges", and the evidence of what is missing is thrown away. The
// adapter matches covariances: from every pose, used or gated, it keeps a running mean of
// the squared innovation of each pose component and of the variance the filter predicted
// for it without the added noise. What the innovations show beyond the prediction is the
// model's error per frame; that much pose process noise is added, so the filter keeps
// tracking and keeps estimating. When the model fits, the excess is zero (within a
// margin for the running means' own noise) and nothing is added.
//
// The added noise is reported as a level: the excess variance per frame interval in units
// of the measurement variance (0: none). It measures how much the model misses.
#pragma once

#include <Eigen/Core>
#include <string>

namespace kincal {

struct PoseNoiseAdaptationOptions {
  bool enabled = true;
  double smoothing_updates = 30.0;  // running-mean time constant, in poses
  // Squared innovations are capped at this many predicted variances (a single outlier
  // moves the mean by at most cap / smoothing_updates of a variance).
  double outlier_cap = 16.0;
  // Excess counted only beyond this fraction of the predicted variance (the running
  // means' own scatter on a model that fits).
  double margin = 0.5;
  bool IsValid(std::string* error) const;
};

class PoseNoiseAdapter {
 public:
  explicit PoseNoiseAdapter(PoseNoiseAdaptationOptions options = {});
  // One pose, used or gated: its innovation (x, y, theta; theta wrapped), the innovation
  // covariance the filter predicted, the measurement covariance R, the pose variance the
  // adapter added for this step (ExtraPsd * dt) and the time since the previous pose.
  void Add(const Eigen::Vector3d& innovation, const Eigen::Matrix3d& predicted,
           const Eigen::Matrix3d& R, const Eigen::Vector3d& added_variance, double dt_s);
  // The pose process noise PSD to add now (m^2/s, m^2/s, rad^2/s).
  Eigen::Vector3d ExtraPsd() const;
  // Added noise in measurement variances per frame interval (0: none).
  double level() const { return level_; }
  void Reset();

 private:
  PoseNoiseAdaptationOptions options_;
  Eigen::Vector3d squared_ = Eigen::Vector3d::Zero();    // running mean of innovation^2
  Eigen::Vector3d predicted_ = Eigen::Vector3d::Zero();  // ... of its predicted variance
  Eigen::Vector3d excess_ = Eigen::Vector3d::Zero();     // variance per frame beyond it
  double dt_s_ = 0.0;                                    // running mean frame interval
  double level_ = 0.0;
  int count_ = 0;
};

}  // namespace kincal
