// The Fisher information a motion gives about a system's parameters, accumulated as the
// motion is driven: the start of a planner's and of every "how long until calibrated"
// prediction.
//
// The system is propagated from a known state along a control signal; at each pose time
// the Jacobian of the measured target pose with respect to (start pose, parameters) is
// taken by central differences of the propagation itself (so every effect the system
// carries, delays and lags included, is differentiated as it is simulated), and adds
// J' R^-1 J to the information. A new segment (a robot put down again, as between the
// thesis's runs) starts with a free pose: what the finished segment knew of its pose is
// profiled out (Schur complement) and only its parameter information is kept.
//
// The predicted covariance is the Bayesian bound: (prior information + data information)^-1
// over the parameters. The state is kept between Advance calls, so a planner can try a
// candidate on a copy and keep the one it likes.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "kincal/control_signal.h"
#include "kincal/system.h"

namespace kincal {

// The fastest pose rate a design is predicted for.
inline constexpr double kMaxDesignPoseRateHz = 1000.0;

struct DesignInformationOptions {
  Eigen::Vector3d pose_sigma{0.002, 0.002, 0.005};  // pose measurement noise (m, m, rad)
  double pose_rate_hz = 15.0;  // pose measurements per second, (0, kMaxDesignPoseRateHz]
  bool IsValid(std::string* error) const;
};

class DesignInformation {
 public:
  // `params` are the system's parameters the design is evaluated at; `prior_cov` their
  // prior covariance (positive definite, num_params square). Throws std::invalid_argument
  // on sizes or options that do not fit (a bug in the caller: inputs are checked first).
  DesignInformation(const System& sys, const Eigen::VectorXd& params,
                    const Eigen::MatrixXd& prior_cov, const DesignInformationOptions& options);

  // Starts a segment at rest at `pose` at time `t_s` (seconds on the controls' origin).
  void StartSegment(const Eigen::Vector3d& pose, double t_s, const ControlSignal& controls);
  // Drives the controls from the current time to `t1_s`, measuring every pose period.
  void Advance(double t1_s, const ControlSignal& controls);

  double time_s() const { return t_s_; }
  // The current nominal target pose (x, y, theta) as measured.
  Eigen::Vector3d MeasuredPose() const;
  // Predicted posterior covariance of the parameters now.
  Eigen::MatrixXd Covariance() const;
  int num_measurements() const { return measurements_; }

 private:
  void Measure();
  Eigen::MatrixXd ParamInformation() const;  // finished segments + the current one, profiled

  const System* sys_;
  DesignInformationOptions opt_;
  Eigen::VectorXd params_;
  Eigen::VectorXd steps_;  // central-difference step of each of (pose, params)
  Eigen::MatrixXd prior_info_;
  Eigen::MatrixXd done_info_;     // parameter information of finished segments
  Eigen::MatrixXd seg_info_;      // (pose, params) information of the current segment
  std::vector<StateVec> states_;  // nominal, then + and - each of (pose, params)
  double t_s_ = 0.0;
  double next_measure_s_ = 0.0;
  bool started_ = false;
  int measurements_ = 0;
};

}  // namespace kincal
