#include "kincal/plan/design_information.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "kincal/angles.h"

namespace kincal {
namespace {

// Central-difference steps: 1e-5 of a parameter's size (its value, or its prior sigma
// when the value is near zero, as a delay's is); 10 um and 10 urad for the pose.
constexpr double kRelativeStep = 1e-5;
constexpr double kPoseStep = 1e-5;

// Information of the parameters with the pose (first three rows) profiled out.
Eigen::MatrixXd Profiled(const Eigen::MatrixXd& info) {
  const Eigen::Index n = info.rows() - 3;
  const Eigen::Matrix3d a = info.topLeftCorner<3, 3>();
  if (!(a.trace() > 0.0)) return Eigen::MatrixXd::Zero(n, n);
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(a);
  const Eigen::MatrixXd b = info.topRightCorner(3, n);
  return info.bottomRightCorner(n, n) - b.transpose() * ldlt.solve(b);
}

}  // namespace

bool DesignInformationOptions::IsValid(std::string* error) const {
  if (!(pose_sigma.minCoeff() > 0.0) || !pose_sigma.allFinite()) {
    *error = "pose_sigma: three positive values (m, m, rad) expected";
    return false;
  }
  if (!(pose_rate_hz > 0.0 && pose_rate_hz <= kMaxDesignPoseRateHz)) {
    std::ostringstream why;
    why << "pose_rate_hz: in (0, " << kMaxDesignPoseRateHz << "] Hz expected, not " << pose_rate_hz;
    *error = why.str();
    return false;
  }
  return true;
}

DesignInformation::DesignInformation(const System& sys, const Eigen::VectorXd& params,
                                     const Eigen::MatrixXd& prior_cov,
                                     const DesignInformationOptions& options)
    : sys_(&sys), opt_(options), params_(params) {
  std::string error;
  if (!options.IsValid(&error)) throw std::invalid_argument("DesignInformation: " + error);
  const int n = sys.num_params();
  if (params.size() != n || prior_cov.rows() != n || prior_cov.cols() != n) {
    throw std::invalid_argument("DesignInformation: params and prior_cov must match the system");
  }
  prior_info_ = prior_cov.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
  steps_.resize(3 + n);
  steps_.head<3>().setConstant(kPoseStep);
  for (int i = 0; i < n; ++i) {
    const double size = std::max({std::abs(params[i]), std::sqrt(prior_cov(i, i)), 1e-6});
    steps_[3 + i] = kRelativeStep * size;
  }
  done_info_ = Eigen::MatrixXd::Zero(n, n);
  seg_info_ = Eigen::MatrixXd::Zero(3 + n, 3 + n);
  states_.resize(static_cast<size_t>(1 + 2 * (3 + n)));
}

void DesignInformation::StartSegment(const Eigen::Vector3d& pose, double t_s,
                                     const ControlSignal& controls) {
  if (started_) {
    done_info_ += Profiled(seg_info_);
    seg_info_.setZero();
  }
  started_ = true;
  t_s_ = t_s;
  next_measure_s_ = t_s;
  const int m = static_cast<int>(steps_.size());
  const ControlSignal at_rest(controls.num_channels(), controls.origin_ns());
  for (int k = 0; k <= 2 * m; ++k) {
    Eigen::Vector3d p0 = pose;
    VecN<kMaxState> p = params_;
    if (k > 0) {
      const int i = (k - 1) / 2;
      const double h = (k % 2 == 1 ? 1.0 : -1.0) * steps_[i];
      if (i < 3) {
        p0[i] += h;
      } else {
        p[i - 3] += h;
      }
    }
    // At rest: effect states (a lag's realised controls) at zero whatever the controls in
    // force at t_s would give (with a delay, those depend on the delay itself, and
    // differentiating that choice would invent information).
    states_[static_cast<size_t>(k)] = sys_->MakeState(p0.x(), p0.y(), p0.z(), p, at_rest, t_s);
  }
}

void DesignInformation::Advance(double t1_s, const ControlSignal& controls) {
  if (!started_) throw std::logic_error("DesignInformation: StartSegment first");
  while (next_measure_s_ <= t1_s + 1e-12) {
    for (auto& x : states_) {
      sys_->Propagate(x.data(), x.data(), t_s_, next_measure_s_, controls,
                      static_cast<const double*>(nullptr));
    }
    t_s_ = next_measure_s_;
    Measure();
    next_measure_s_ += 1.0 / opt_.pose_rate_hz;
  }
  if (t1_s > t_s_) {
    for (auto& x : states_) {
      sys_->Propagate(x.data(), x.data(), t_s_, t1_s, controls,
                      static_cast<const double*>(nullptr));
    }
    t_s_ = t1_s;
  }
}

Eigen::Vector3d DesignInformation::MeasuredPose() const {
  Eigen::Vector3d z;
  sys_->Measure(states_[0].data(), z.data());
  return z;
}

void DesignInformation::Measure() {
  const int m = static_cast<int>(steps_.size());
  Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, m);
  for (int i = 0; i < m; ++i) {
    Eigen::Vector3d zp, zm;
    sys_->Measure(states_[static_cast<size_t>(1 + 2 * i)].data(), zp.data());
    sys_->Measure(states_[static_cast<size_t>(2 + 2 * i)].data(), zm.data());
    Eigen::Vector3d d = zp - zm;
    d.z() = WrapAngle(d.z());
    J.col(i) = d / (2.0 * steps_[i]);
  }
  const Eigen::Vector3d w = opt_.pose_sigma.cwiseInverse().cwiseAbs2();
  seg_info_.noalias() += J.transpose() * w.asDiagonal() * J;
  ++measurements_;
}

Eigen::MatrixXd DesignInformation::ParamInformation() const {
  return done_info_ + Profiled(seg_info_);
}

Eigen::MatrixXd DesignInformation::Covariance() const {
  const Eigen::MatrixXd info = prior_info_ + ParamInformation();
  return info.ldlt().solve(Eigen::MatrixXd::Identity(info.rows(), info.cols()));
}

}  // namespace kincal
