#include "kincal/estimation/noise_adaptation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace kincal {

bool PoseNoiseAdaptationOptions::IsValid(std::string* error) const {
  if (!(smoothing_updates >= 1) || !(outlier_cap > 1) || !(margin >= 0)) {
    *error = "pose noise adaptation: expected smoothing_updates >= 1, outlier_cap > 1, margin >= 0";
    return false;
  }
  return true;
}

PoseNoiseAdapter::PoseNoiseAdapter(PoseNoiseAdaptationOptions options) : options_(options) {
  std::string error;
  if (!options_.IsValid(&error)) throw std::invalid_argument(error);
}

void PoseNoiseAdapter::Add(const Eigen::Vector3d& innovation, const Eigen::Matrix3d& predicted,
                           const Eigen::Matrix3d& R, const Eigen::Vector3d& added_variance,
                           double dt_s) {
  if (!options_.enabled || !innovation.allFinite() || !predicted.allFinite() || !(dt_s > 0)) {
    return;
  }
  // Early on, plain means; then exponential with the configured time constant.
  const double w = 1.0 / std::min<double>(++count_, options_.smoothing_updates);
  for (int i = 0; i < 3; ++i) {
    const double s = std::max(predicted(i, i) - added_variance[i], R(i, i));
    const double nu2 = std::min(innovation[i] * innovation[i], options_.outlier_cap * s);
    squared_[i] += w * (nu2 - squared_[i]);
    predicted_[i] += w * (s - predicted_[i]);
    excess_[i] = std::max(0.0, squared_[i] - (1.0 + options_.margin) * predicted_[i]);
  }
  dt_s_ += w * (dt_s - dt_s_);
  level_ = 0.0;
  for (int i = 0; i < 3; ++i) level_ = std::max(level_, R(i, i) > 0 ? excess_[i] / R(i, i) : 0.0);
}

Eigen::Vector3d PoseNoiseAdapter::ExtraPsd() const {
  if (!options_.enabled || !(dt_s_ > 0)) return Eigen::Vector3d::Zero();
  return excess_ / dt_s_;
}

void PoseNoiseAdapter::Reset() {
  squared_.setZero();
  predicted_.setZero();
  excess_.setZero();
  dt_s_ = 0.0;
  level_ = 0.0;
  count_ = 0;
}

}  // namespace kincal
