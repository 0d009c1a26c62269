// Unscented Kalman filter (Julier & Uhlmann; scaled form of Wan & van der Merwe) with the
// process noise augmented into the sigma points, alpha = 1, beta = 2, kappa = 0:
// 2(n + nv) symmetric points of weight 1/(2(n + nv)), the centre point weighted only in
// the covariance (beta). Additive measurement noise.
#include <cmath>

#include "filter_util.h"
#include "kincal/estimation/filter.h"

namespace kincal {
namespace {

constexpr double kBeta = 2.0;

class Ukf final : public Filter {
 public:
  std::string_view name() const override { return "ukf"; }

  void Initialize(const StateVec& x, const StateMat& P, uint32_t angle_mask) override {
    x_ = x;
    P_ = P;
    mask_ = angle_mask;
  }

  void Predict(const ProcessFunction& f, const NoiseMat& Sv) override {
    const int n = static_cast<int>(x_.size());
    const int nv = f.noise_dim();
    const int na = n + nv;
    const double gamma = std::sqrt(static_cast<double>(na));
    const double w = 1.0 / (2.0 * na);
    Eigen::LLT<StateMat> llt(P_);
    const StateMat S = llt.matrixL();
    NoiseVec v0 = NoiseVec::Zero(nv);
    StateVec f0(n), fi(n);
    f.Eval(x_.data(), v0.data(), f0.data());
    // Sigma-point images, stored as deviations from f0 to keep angles continuous.
    MatN<kMaxState, 2 * (kMaxState + kMaxNoise)> D(n, 2 * na);
    for (int p = 0; p < na; ++p) {
      for (int sgn = 0; sgn < 2; ++sgn) {
        const double s = sgn == 0 ? gamma : -gamma;
        if (p < n) {
          StateVec xs = x_ + s * S.col(p);
          f.Eval(xs.data(), v0.data(), fi.data());
        } else {
          NoiseVec vs = v0 + s * Sv.col(p - n);
          f.Eval(x_.data(), vs.data(), fi.data());
        }
        D.col(2 * p + sgn) = internal::WrappedDiff(fi, f0, mask_);
      }
    }
    const StateVec mean_dev = w * D.rowwise().sum();
    x_ = f0 + mean_dev;
    // Centre point: deviation -mean_dev with covariance weight beta (W0m = 0).
    P_ = kBeta * mean_dev * mean_dev.transpose();
    for (int i = 0; i < 2 * na; ++i) {
      const StateVec d = D.col(i) - mean_dev;
      P_ += w * d * d.transpose();
    }
  }

  UpdateResult Update(const MeasurementFunction& hf, const MeasVec& z, const MeasMat& Sw) override {
    const int n = static_cast<int>(x_.size());
    const int m = hf.meas_dim();
    const uint32_t zmask = internal::MeasAngleMask(hf);
    const double gamma = std::sqrt(static_cast<double>(n));
    const double w = 1.0 / (2.0 * n);
    Eigen::LLT<StateMat> llt(P_);
    const StateMat S = llt.matrixL();
    MeasVec z0(m), zi(m);
    hf.Eval(x_.data(), z0.data());
    MatN<kMaxMeas, 2 * kMaxState> Dz(m, 2 * n);
    MatN<kMaxState, 2 * kMaxState> Dx(n, 2 * n);
    for (int p = 0; p < n; ++p) {
      for (int sgn = 0; sgn < 2; ++sgn) {
        const double s = sgn == 0 ? gamma : -gamma;
        StateVec xs = x_ + s * S.col(p);
        hf.Eval(xs.data(), zi.data());
        Dz.col(2 * p + sgn) = internal::WrappedDiff(zi, z0, zmask);
        Dx.col(2 * p + sgn) = s * S.col(p);
      }
    }
    const MeasVec zdev = w * Dz.rowwise().sum();
    const MeasVec zpred = z0 + zdev;
    MeasMat Pzz = kBeta * zdev * zdev.transpose() + Sw * Sw.transpose();
    StateMeasMat Pxz = StateMeasMat::Zero(n, m);
    for (int i = 0; i < 2 * n; ++i) {
      const MeasVec dz = Dz.col(i) - zdev;
      Pzz += w * dz * dz.transpose();
      Pxz += w * Dx.col(i) * dz.transpose();
    }
    UpdateResult r;
    r.innovation = internal::WrappedDiff(z, zpred, zmask);
    r.innovation_cov = Pzz;
    Eigen::LLT<MeasMat> lz(Pzz);
    if (lz.info() != Eigen::Success) {
      r.ok = false;
      return r;
    }
    const StateMeasMat K = lz.solve(Pxz.transpose()).transpose();
    r.nis = r.innovation.dot(lz.solve(r.innovation));
    x_ += K * r.innovation;
    internal::WrapAngles(&x_, mask_);
    P_ -= K * Pzz * K.transpose();
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

KINCAL_FILTER_FACTORY(Ukf)

}  // namespace kincal
