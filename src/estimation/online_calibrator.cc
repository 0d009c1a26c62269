#include "kincal/estimation/online_calibrator.h"

#include <cmath>
#include <stdexcept>

#include "kincal/angles.h"

namespace kincal {

bool ProcessNoiseOptions::IsValid(int num_controls, std::string* error) const {
  if (!control_psd.empty() && static_cast<int>(control_psd.size()) != num_controls) {
    *error = "control_psd has " + std::to_string(control_psd.size()) + " entries, model has " +
             std::to_string(num_controls) + " controls";
    return false;
  }
  for (double q : control_psd) {
    if (!(q >= 0.0) || !std::isfinite(q)) {
      *error = "control_psd entries must be finite and >= 0";
      return false;
    }
  }
  if (!(effect_state_psd >= 0.0) || !std::isfinite(effect_state_psd)) {
    *error = "effect_state_psd must be finite and >= 0";
    return false;
  }
  if (!(pose_psd.array() >= 0.0).all() || !pose_psd.allFinite()) {
    *error = "pose_psd entries must be finite and >= 0";
    return false;
  }
  return true;
}

bool OnlineCalibratorOptions::IsValid(const System& sys, std::string* error) const {
  if (FilterRegistry::Instance().Create(filter) == nullptr) {
    *error = "unknown filter '" + filter + "'";
    return false;
  }
  return noise.IsValid(sys.num_controls(), error);
}

void SystemProcess::Eval(const double* x, const double* v, double* out) const {
  sys_.Propagate(x, out, t0_, t1_, u_, v);
}

void SystemProcess::Jacobians(const StateVec& x, StateMat* F, StateNoiseMat* G) const {
  const int n = sys_.state_dim();
  const int nv = sys_.noise_dim();
  Jet xj[kMaxState], vj[kMaxNoise], out[kMaxState];
  for (int i = 0; i < n; ++i) xj[i] = Jet(x[i], i);
  for (int k = 0; k < nv; ++k) vj[k] = Jet(0.0, n + k);
  sys_.Propagate(xj, out, t0_, t1_, u_, vj);
  F->resize(n, n);
  G->resize(n, nv);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) (*F)(i, j) = out[i].v[j];
    for (int k = 0; k < nv; ++k) (*G)(i, k) = out[i].v[n + k];
  }
}

void SystemPoseMeasurement::Jacobian(const StateVec& x, MeasStateMat* H) const {
  const int n = sys_.state_dim();
  Jet xj[kMaxState], z[3];
  for (int i = 0; i < n; ++i) xj[i] = Jet(x[i], i);
  sys_.Measure(xj, z);
  H->resize(3, n);
  for (int i = 0; i < kPoseDim; ++i) {
    for (int j = 0; j < n; ++j) (*H)(i, j) = z[i].v[j];
  }
}

NoiseMat ProcessNoiseSqrt(const System& sys, const ProcessNoiseOptions& noise, double dt_s) {
  const int nc = sys.num_controls();
  NoiseMat Sv = NoiseMat::Zero(sys.noise_dim(), sys.noise_dim());
  if (dt_s <= 0.0) return Sv;
  for (int c = 0; c < nc && c < static_cast<int>(noise.control_psd.size()); ++c) {
    // A white noise of PSD q averaged over dt has variance q / dt.
    Sv(c, c) = std::sqrt(noise.control_psd[static_cast<size_t>(c)] / dt_s);
  }
  for (int i = 0; i < kPoseDim; ++i) Sv(nc + i, nc + i) = std::sqrt(noise.pose_psd[i] * dt_s);
  for (int i = nc + 3; i < sys.noise_dim(); ++i)
    Sv(i, i) = std::sqrt(noise.effect_state_psd * dt_s);
  return Sv;
}

OnlineCalibrator::OnlineCalibrator(const System& sys, OnlineCalibratorOptions options,
                                   TimeNs time_origin_ns)
    : sys_(sys),
      options_(std::move(options)),
      controls_(sys.num_controls(), time_origin_ns),
      meas_(sys) {
  std::string error;
  if (!options_.IsValid(sys_, &error)) throw std::invalid_argument("OnlineCalibrator: " + error);
  filter_ = MakeFilter(options_.filter).value();
  noise_ = options_.noise;
}

void OnlineCalibrator::set_extra_pose_psd(const Eigen::Vector3d& psd) {
  noise_.pose_psd = options_.noise.pose_psd + psd;
}

void OnlineCalibrator::Initialize(TimeNs t_ns, const StateVec& x0, const StateMat& P0) {
  filter_->Initialize(x0, P0, 1u << 2);
  t_ns_ = t_ns;
  initialized_ = true;
  updates_ = 0;
}

void OnlineCalibrator::Initialize(TimeNs t_ns, const Eigen::Vector3d& pose,
                                  const Eigen::Matrix3d& pose_cov, const VecN<kMaxState>& params,
                                  const StateMat& params_cov) {
  const int n = sys_.state_dim();
  const int np = sys_.num_params();
  StateVec x =
      sys_.MakeState(pose.x(), pose.y(), pose.z(), params, controls_, controls_.ToSeconds(t_ns));
  WarmUpEffectStates(t_ns, &x);
  StateMat P = StateMat::Zero(n, n);
  P.topLeftCorner(3, 3) = pose_cov;  // replaced by ResetPose below
  P.block(3, 3, np, np) = params_cov;
  // Effect states: a small variance so that the filter may correct them.
  for (int i = sys_.state_offset(); i < n; ++i) P(i, i) = 1e-6;
  filter_->Initialize(x, P, 1u << 2);
  initialized_ = true;
  updates_ = 0;
  ResetPose(t_ns, pose, pose_cov);
}

// Effect states (a lag's realised control, ...) from the controls before t: steady state at
// the start of the warm-up, then propagated, so that a filter started in mid-motion does not
// begin with the realised controls equal to the commands.
void OnlineCalibrator::WarmUpEffectStates(TimeNs t_ns, StateVec* x) const {
  if (sys_.num_states() == 0 || controls_.empty()) return;
  const double t1 = controls_.ToSeconds(t_ns);
  const double t0 = std::max(controls_.TimeAt(0), t1 - kEffectWarmUpS);
  if (!(t1 > t0)) return;
  StateVec w = *x;
  sys_.InitEffectStates(w.data(), controls_, t0);
  sys_.Propagate(w.data(), w.data(), t0, t1, controls_, static_cast<const double*>(nullptr));
  const int n = sys_.num_states();
  x->segment(sys_.state_offset(), n) = w.segment(sys_.state_offset(), n);
}

void OnlineCalibrator::PredictTo(TimeNs t_ns) {
  if (t_ns <= t_ns_) return;
  const double t0 = controls_.ToSeconds(t_ns_);
  const double t1 = controls_.ToSeconds(t_ns);
  SystemProcess f(sys_, controls_, t0, t1);
  filter_->Predict(f, ProcessNoiseSqrt(sys_, noise_, t1 - t0));
  t_ns_ = t_ns;
}

UpdateResult OnlineCalibrator::AddPose(TimeNs t_ns, const Eigen::Vector3d& z,
                                       const Eigen::Matrix3d& R, double gate_nis) {
  if (!initialized_ || t_ns < t_ns_) {
    UpdateResult r;
    r.ok = false;
    return r;
  }
  PredictTo(t_ns);
  if (gate_nis > 0.0) {
    const StateVec& x = filter_->mean();
    MeasVec zp(kPoseDim);
    meas_.Eval(x.data(), zp.data());
    MeasVec nu = z - zp;
    nu[2] = WrapAngle(nu[2]);
    MeasStateMat H;
    meas_.Jacobian(x, &H);
    const Eigen::Matrix3d S = (H * filter_->covariance() * H.transpose()).topLeftCorner<3, 3>() + R;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(S);
    const double nis = nu.head<3>().dot(ldlt.solve(Eigen::Vector3d(nu.head<3>())));
    if (!(nis <= gate_nis)) {
      UpdateResult r;
      r.ok = false;
      r.gated = true;
      r.nis = nis;
      r.innovation = nu;
      r.innovation_cov = MeasMat::Zero(kPoseDim, kPoseDim);
      r.innovation_cov.topLeftCorner<3, 3>() = S;
      return r;
    }
  }
  Eigen::LLT<Eigen::Matrix3d> llt(R);
  const MeasMat Sw = llt.matrixL().toDenseMatrix();
  const MeasVec zv = z;
  UpdateResult r = filter_->Update(meas_, zv, Sw);
  if (r.ok) ++updates_;
  return r;
}

void OnlineCalibrator::ResetPose(TimeNs t_ns, const Eigen::Vector3d& z, const Eigen::Matrix3d& R) {
  // The camera measures the target pose; the state holds the reference pose. Invert the
  // measurement map at the current parameters, x_pose = g(z, p), and propagate the
  // covariance through its Jacobians: the pose inherits the uncertainty of a lever arm
  // and stays correlated with it.
  const int n = sys_.state_dim();
  StateVec x = filter_->mean();
  sys_.ResetEffectStates(&x, controls_, controls_.ToSeconds(t_ns));
  WarmUpEffectStates(t_ns, &x);
  auto g = [&](const StateVec& xs, const Eigen::Vector3d& zs) {
    StateVec out = xs;
    sys_.SetPoseFromMeasurement(zs.data(), out.data());
    return Eigen::Vector3d(out.head(kPoseDim));
  };
  const Eigen::Vector3d pose = g(x, z);
  // J = d(new state)/d(old state): identity except the pose rows; Gz = d pose / d z.
  StateMat J = StateMat::Identity(n, n);
  J.topLeftCorner(3, 3).setZero();
  Eigen::Matrix3d Gz;
  for (int j = 3; j < n; ++j) {
    const double h = 1e-6 * std::max(1.0, std::abs(x[j]));
    StateVec xp = x, xm = x;
    xp[j] += h;
    xm[j] -= h;
    Eigen::Vector3d d = g(xp, z) - g(xm, z);
    d.z() = WrapAngle(d.z());
    J.block(0, j, 3, 1) = d / (2.0 * h);
  }
  for (int j = 0; j < kPoseDim; ++j) {
    Eigen::Vector3d zp = z, zm = z;
    zp[j] += 1e-6;
    zm[j] -= 1e-6;
    Eigen::Vector3d d = g(x, zp) - g(x, zm);
    d.z() = WrapAngle(d.z());
    Gz.col(j) = d / 2e-6;
  }
  StateMat P = J * filter_->covariance() * J.transpose();
  P.topLeftCorner(3, 3) += Gz * R * Gz.transpose();
  x.head(kPoseDim) = pose;
  x[2] = WrapAngle(x[2]);
  filter_->Initialize(x, P, 1u << 2);
  t_ns_ = t_ns;
}

VecN<kMaxState> OnlineCalibrator::params() const {
  return filter_->mean().segment(sys_.param_offset(), sys_.num_params());
}

StateMat OnlineCalibrator::params_covariance() const {
  const int np = sys_.num_params();
  return filter_->covariance().block(sys_.param_offset(), sys_.param_offset(), np, np);
}

}  // namespace kincal
