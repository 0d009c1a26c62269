// Extended Kalman filter: first-order linearisation of f and h at the estimate
// (Jacobians from the function objects: autodiff for kinematic systems), Joseph-form
// covariance update. The comparison baseline for DD2.
#include <cmath>

#include "filter_util.h"
#include "kincal/estimation/filter.h"

namespace kincal {
namespace {

class Ekf final : public Filter {
 public:
  std::string_view name() const override { return "ekf"; }

  void Initialize(const StateVec& x, const StateMat& P, uint32_t angle_mask) override {
    x_ = x;
    P_ = P;
    mask_ = angle_mask;
  }

  void Predict(const ProcessFunction& f, const NoiseMat& Sv) override {
    const int n = static_cast<int>(x_.size());
    StateMat F;
    StateNoiseMat G;
    f.Jacobians(x_, &F, &G);
    NoiseVec v0 = NoiseVec::Zero(f.noise_dim());
    StateVec next(n);
    f.Eval(x_.data(), v0.data(), next.data());
    x_ = next;
    const StateNoiseMat GS = G * Sv;
    P_ = F * P_ * F.transpose() + GS * GS.transpose();
    P_ = 0.5 * (P_ + P_.transpose()).eval();
  }

  UpdateResult Update(const MeasurementFunction& hf, const MeasVec& z, const MeasMat& Sw) override {
    const int n = static_cast<int>(x_.size());
    const int m = hf.meas_dim();
    const uint32_t zmask = internal::MeasAngleMask(hf);
    MeasVec zpred(m);
    hf.Eval(x_.data(), zpred.data());
    MeasStateMat H;
    hf.Jacobian(x_, &H);
    const MeasMat R = Sw * Sw.transpose();
    UpdateResult r;
    r.innovation = internal::WrappedDiff(z, zpred, zmask);
    r.innovation_cov = H * P_ * H.transpose() + R;
    Eigen::LLT<MeasMat> llt(r.innovation_cov);
    if (llt.info() != Eigen::Success) {
      r.ok = false;
      return r;
    }
    const StateMeasMat PHt = P_ * H.transpose();
    const StateMeasMat K = llt.solve(PHt.transpose()).transpose();
    r.nis = r.innovation.dot(llt.solve(r.innovation));
    x_ += K * r.innovation;
    internal::WrapAngles(&x_, mask_);
    const StateMat IKH = StateMat::Identity(n, n) - K * H;
    P_ = IKH * P_ * IKH.transpose() + K * R * K.transpose();
    P_ = 0.5 * (P_ + P_.transpose()).eval();
    return r;
  }

  const StateVec& mean() const override { return x_; }
  StateMat covariance() const override { return P_; }

 private:
  StateVec x_;
  StateMat P_;
  uint32_t mask_ = 0;
};

}  // namespace

KINCAL_FILTER_FACTORY(Ekf)

}  // namespace kincal
