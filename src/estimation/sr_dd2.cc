// Square-root second-order divided-difference filter, DD2 (Norgaard, Poulsen & Ravn,
// Automatica 36, 2000; thesis 5.3 with its step-2 typo fixed: S_yx^(1), S_yw^(1),
// S_yx^(2), S_yw^(2)). Interval length h^2 = 3, optimal for Gaussian priors.
//
// Prediction, with sx_p / sv_p the columns of the square-root factors:
//   S_xx^(1)_p = [f(x + h sx_p) - f(x - h sx_p)] / 2h
//   S_xv^(1)_p = [f(v + h sv_p) - f(v - h sv_p)] / 2h
//   S_xx^(2)_p = sqrt(h^2-1)/2h^2 [f(x + h sx_p) + f(x - h sx_p) - 2 f(x)]   (same for v)
//   x-  = f(x) + 1/2h^2 sum_p [f(+) + f(-) - 2 f(x)]   over state and noise directions
//   S-  = triang([S_xx^(1) S_xv^(1) S_xx^(2) S_xv^(2)])
// Update with additive noise Sw (so S_yw^(1) = Sw, S_yw^(2) = 0):
//   S_y = triang([S_yx^(1) Sw S_yx^(2)]),  P_xy = S- S_yx^(1)^T,  K = P_xy (S_y S_y^T)^-1
//   S+  = triang([S- - K S_yx^(1),  K Sw,  K S_yx^(2)])
#include <cmath>

#include "filter_util.h"
#include "kincal/estimation/filter.h"

namespace kincal {
namespace {

constexpr double kH2 = 3.0;

class SrDd2 final : public Filter {
 public:
  std::string_view name() const override { return "dd2"; }

  void Initialize(const StateVec& x, const StateMat& P, uint32_t angle_mask) override {
    x_ = x;
    mask_ = angle_mask;
    Eigen::LLT<StateMat> llt(P);
    S_ = llt.matrixL();
  }

  void Predict(const ProcessFunction& f, const NoiseMat& Sv) override {
    const int n = static_cast<int>(x_.size());
    const int nv = f.noise_dim();
    const double h = std::sqrt(kH2);
    const double c2 = std::sqrt(kH2 - 1.0) / (2.0 * kH2);
    NoiseVec v0 = NoiseVec::Zero(nv);
    StateVec f0(n), fp(n), fm(n);
    f.Eval(x_.data(), v0.data(), f0.data());

    CompoundMat A = CompoundMat::Zero(n, 2 * (n + nv));
    StateVec sum = StateVec::Zero(n);
    for (int p = 0; p < n; ++p) {
      StateVec xp = x_ + h * S_.col(p);
      StateVec xm = x_ - h * S_.col(p);
      f.Eval(xp.data(), v0.data(), fp.data());
      f.Eval(xm.data(), v0.data(), fm.data());
      const StateVec dp = internal::WrappedDiff(fp, f0, mask_);
      const StateVec dm = internal::WrappedDiff(fm, f0, mask_);
      A.col(p) = (dp - dm) / (2.0 * h);
      A.col(n + nv + p) = c2 * (dp + dm);
      sum += dp + dm;
    }
    for (int q = 0; q < nv; ++q) {
      if (Sv.col(q).squaredNorm() == 0.0) continue;  // a noise input that is switched off
      NoiseVec vp = v0 + h * Sv.col(q);
      NoiseVec vm = v0 - h * Sv.col(q);
      f.Eval(x_.data(), vp.data(), fp.data());
      f.Eval(x_.data(), vm.data(), fm.data());
      const StateVec dp = internal::WrappedDiff(fp, f0, mask_);
      const StateVec dm = internal::WrappedDiff(fm, f0, mask_);
      A.col(n + q) = (dp - dm) / (2.0 * h);
      A.col(2 * n + nv + q) = c2 * (dp + dm);
      sum += dp + dm;
    }
    x_ = f0 + sum / (2.0 * kH2);
    Triangularize(A, &S_);
  }

  UpdateResult Update(const MeasurementFunction& hf, const MeasVec& z, const MeasMat& Sw) override {
    const int n = static_cast<int>(x_.size());
    const int m = hf.meas_dim();
    const uint32_t zmask = internal::MeasAngleMask(hf);
    const double h = std::sqrt(kH2);
    const double c2 = std::sqrt(kH2 - 1.0) / (2.0 * kH2);

    MeasVec z0(m), zp(m), zm(m);
    hf.Eval(x_.data(), z0.data());
    MatN<kMaxMeas, kMaxState> Syx1(m, n), Syx2(m, n);
    MeasVec sum = MeasVec::Zero(m);
    for (int p = 0; p < n; ++p) {
      StateVec xp = x_ + h * S_.col(p);
      StateVec xm = x_ - h * S_.col(p);
      hf.Eval(xp.data(), zp.data());
      hf.Eval(xm.data(), zm.data());
      const MeasVec dp = internal::WrappedDiff(zp, z0, zmask);
      const MeasVec dm = internal::WrappedDiff(zm, z0, zmask);
      Syx1.col(p) = (dp - dm) / (2.0 * h);
      Syx2.col(p) = c2 * (dp + dm);
      sum += dp + dm;
    }
    const MeasVec zpred = z0 + sum / (2.0 * kH2);

    CompoundMat Ay = CompoundMat::Zero(m, 2 * n + m);
    Ay.leftCols(n) = Syx1;
    Ay.middleCols(n, m) = Sw;
    Ay.rightCols(n) = Syx2;
    StateMat Sy;
    Triangularize(Ay, &Sy);

    UpdateResult r;
    r.innovation = internal::WrappedDiff(z, zpred, zmask);
    r.innovation_cov = Sy * Sy.transpose();
    for (int i = 0; i < m; ++i) {
      if (!(Sy(i, i) > 0.0)) {
        r.ok = false;
        return r;
      }
    }
    const auto SyL = Sy.triangularView<Eigen::Lower>();
    const auto SyU = Sy.transpose().triangularView<Eigen::Upper>();
    // K = P_xy (Sy Sy^T)^-1 with P_xy = S- Syx1^T, via two triangular solves.
    StateMeasMat Pxy = S_ * Syx1.transpose();
    MatN<kMaxMeas, kMaxState> Kt = Pxy.transpose();
    SyL.solveInPlace(Kt);
    SyU.solveInPlace(Kt);
    const StateMeasMat K = Kt.transpose();
    MeasVec white = r.innovation;
    SyL.solveInPlace(white);
    r.nis = white.squaredNorm();

    x_ += K * r.innovation;
    internal::WrapAngles(&x_, mask_);

    CompoundMat Ax = CompoundMat::Zero(n, 2 * n + m);
    Ax.leftCols(n) = S_ - K * Syx1;
    Ax.middleCols(n, m) = K * Sw;
    Ax.rightCols(n) = K * Syx2;
    Triangularize(Ax, &S_);
    return r;
  }

  const StateVec& mean() const override { return x_; }
  StateMat covariance() const override { return S_ * S_.transpose(); }

 private:
  StateVec x_;
  StateMat S_;  // lower-triangular, P = S S^T
  uint32_t mask_ = 0;
};

}  // namespace

KINCAL_FILTER_FACTORY(SrDd2)

}  // namespace kincal
