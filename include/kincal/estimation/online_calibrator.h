// OnlineCalibrator: recursive calibration of a System from time-stamped poses and controls.
//
// Owns the control history and one Filter over the augmented state. Each pose
// measurement predicts the belief from the previous measurement time to the pose's time
// through the control history (zero-order hold, exact arcs, effects), then updates.
// Times are int64 ns on one time base shared by controls and poses.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>

#include "kincal/control_signal.h"
#include "kincal/estimation/filter.h"
#include "kincal/system.h"
#include "kincal/time.h"

namespace kincal {

// Process noise of the robot, as white-noise power spectral densities.
struct ProcessNoiseOptions {
  // Per control channel, (control unit)^2 * s: noise on the realised controls.
  std::vector<double> control_psd;
  // Additive pose noise (m^2/s, m^2/s, rad^2/s): unmodelled motion.
  Eigen::Vector3d pose_psd = Eigen::Vector3d::Zero();
  // Additive noise on every effect state ((state unit)^2/s). Effect states are functions
  // of parameters and the command history; without a little noise their covariance
  // collapses onto that function and rounding makes it indefinite.
  double effect_state_psd = 1e-9;
  bool IsValid(int num_controls, std::string* error) const;
};

struct OnlineCalibratorOptions {
  std::string filter = "dd2";  // "dd2", "ekf", "ukf"
  ProcessNoiseOptions noise;
  bool IsValid(const System& sys, std::string* error) const;
};

// f(x, v) of a System between two times, for the filters.
class SystemProcess final : public ProcessFunction {
 public:
  SystemProcess(const System& sys, const ControlSignal& u, double t0_s, double t1_s)
      : sys_(sys), u_(u), t0_(t0_s), t1_(t1_s) {}
  int state_dim() const override { return sys_.state_dim(); }
  int noise_dim() const override { return sys_.noise_dim(); }
  void Eval(const double* x, const double* v, double* out) const override;
  // Exact Jacobians by forward-mode autodiff.
  void Jacobians(const StateVec& x, StateMat* F, StateNoiseMat* G) const override;
  bool IsAngle(int i) const override { return sys_.IsAngle(i); }

 private:
  const System& sys_;
  const ControlSignal& u_;
  double t0_, t1_;
};

// h(x): measured target pose of a System state.
class SystemPoseMeasurement final : public MeasurementFunction {
 public:
  explicit SystemPoseMeasurement(const System& sys) : sys_(sys) {}
  int state_dim() const override { return sys_.state_dim(); }
  int meas_dim() const override { return 3; }
  void Eval(const double* x, double* z) const override { sys_.Measure(x, z); }
  void Jacobian(const StateVec& x, MeasStateMat* H) const override;
  bool IsAngle(int i) const override { return i == 2; }

 private:
  const System& sys_;
};

// Square-root process noise factor for a step of dt seconds.
NoiseMat ProcessNoiseSqrt(const System& sys, const ProcessNoiseOptions& noise, double dt_s);

class OnlineCalibrator {
 public:
  // Throws std::invalid_argument if the options are not valid for the system.
  OnlineCalibrator(const System& sys, OnlineCalibratorOptions options, TimeNs time_origin_ns = 0);

  const System& system() const { return sys_; }
  ControlSignal& controls() { return controls_; }
  const ControlSignal& controls() const { return controls_; }

  // Appends a control sample; false if it is older than the last one (ignored).
  bool AddControl(TimeNs t_ns, std::span<const double> values) {
    return controls_.Append(t_ns, values);
  }

  // Starts the belief at time t: full augmented mean and covariance.
  void Initialize(TimeNs t_ns, const StateVec& x0, const StateMat& P0);
  // Starts from a measured pose plus a parameter prior (mean, covariance over all params);
  // effect states at steady state.
  void Initialize(TimeNs t_ns, const Eigen::Vector3d& pose, const Eigen::Matrix3d& pose_cov,
                  const VecN<kMaxState>& params, const StateMat& params_cov);
  bool initialized() const { return initialized_; }

  // Predicts to t and updates with the measured target pose z (x, y, theta) of covariance R.
  // Poses older than the current belief are rejected (ok = false). With gate_nis > 0, a
  // pose whose normalised innovation squared before the update (linearised at the
  // predicted mean) exceeds gate_nis is not used: ok = false, gated = true, nis set.
  UpdateResult AddPose(TimeNs t_ns, const Eigen::Vector3d& z, const Eigen::Matrix3d& R,
                       double gate_nis = 0.0);
  // Pose process noise added to the configured pose_psd from now on (m^2/s, m^2/s,
  // rad^2/s): the adaptive noise that lets the filter follow a robot whose motion the model
  // does not fully explain (kincal/estimation/noise_adaptation.h).
  void set_extra_pose_psd(const Eigen::Vector3d& psd);
  // Predicts to t without a measurement.
  void PredictTo(TimeNs t_ns);
  // Starts a new run at time t: pose := z (cov R), parameters and their covariance kept.
  void ResetPose(TimeNs t_ns, const Eigen::Vector3d& z, const Eigen::Matrix3d& R);

  TimeNs time_ns() const { return t_ns_; }
  const StateVec& state() const { return filter_->mean(); }
  StateMat covariance() const { return filter_->covariance(); }
  VecN<kMaxState> params() const;
  StateMat params_covariance() const;
  int64_t update_count() const { return updates_; }
  std::string_view filter_name() const { return filter_->name(); }

 private:
  static constexpr double kEffectWarmUpS = 2.0;
  void WarmUpEffectStates(TimeNs t_ns, StateVec* x) const;

  const System& sys_;
  OnlineCalibratorOptions options_;
  ControlSignal controls_;
  std::unique_ptr<Filter> filter_;
  SystemPoseMeasurement meas_;
  TimeNs t_ns_ = 0;
  bool initialized_ = false;
  int64_t updates_ = 0;
  ProcessNoiseOptions noise_;  // options_.noise plus the extra pose noise
};

}  // namespace kincal
