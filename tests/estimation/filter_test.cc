// On a linear Gaussian model every filter must reproduce the Kalman filter.
#include "kincal/estimation/filter.h"

#include <gtest/gtest.h>

#include <random>

namespace kincal {
namespace {

// 2-D constant velocity: x = [px, py, vx, vy], acceleration noise v (2), dt = 0.1.
constexpr double kDt = 0.1;

Eigen::Matrix4d A() {
  Eigen::Matrix4d a = Eigen::Matrix4d::Identity();
  a(0, 2) = a(1, 3) = kDt;
  return a;
}
Eigen::Matrix<double, 4, 2> B() {
  Eigen::Matrix<double, 4, 2> b = Eigen::Matrix<double, 4, 2>::Zero();
  b(0, 0) = b(1, 1) = 0.5 * kDt * kDt;
  b(2, 0) = b(3, 1) = kDt;
  return b;
}
Eigen::Matrix<double, 2, 4> H() {
  Eigen::Matrix<double, 2, 4> h;
  h << 1, 0, 0, 0, 0.2, 1, 0, 0.1;  // a slightly mixed position sensor
  return h;
}

class LinearProcess final : public ProcessFunction {
 public:
  int state_dim() const override { return 4; }
  int noise_dim() const override { return 2; }
  void Eval(const double* x, const double* v, double* out) const override {
    Eigen::Map<Eigen::Vector4d> y(out);
    y = A() * Eigen::Map<const Eigen::Vector4d>(x) + B() * Eigen::Map<const Eigen::Vector2d>(v);
  }
};

class LinearMeasurement final : public MeasurementFunction {
 public:
  int state_dim() const override { return 4; }
  int meas_dim() const override { return 2; }
  void Eval(const double* x, double* z) const override {
    Eigen::Map<Eigen::Vector2d> y(z);
    y = H() * Eigen::Map<const Eigen::Vector4d>(x);
  }
};

TEST(LinearGaussian, EveryFilterEqualsTheKalmanFilter) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Vector2d sv(0.5, 0.3);
  Eigen::Vector2d sw(0.2, 0.1);
  Eigen::Vector4d x0(1.0, -2.0, 0.5, 0.2);
  Eigen::Matrix4d P0 = Eigen::Vector4d(1.0, 1.5, 0.3, 0.4).asDiagonal();
  P0(0, 2) = P0(2, 0) = 0.1;

  // Measurements from a simulated truth.
  std::vector<Eigen::Vector2d> zs;
  Eigen::Vector4d xt = x0;
  for (int k = 0; k < 60; ++k) {
    const double v1 = sv[1] * g(rng), v0 = sv[0] * g(rng);  // a fixed order on every compiler
    xt = A() * xt + B() * Eigen::Vector2d(v0, v1);
    const double w1 = sw[1] * g(rng), w0 = sw[0] * g(rng);
    zs.push_back(H() * xt + Eigen::Vector2d(w0, w1));
  }
  // Reference Kalman filter.
  Eigen::Vector4d xr = x0;
  Eigen::Matrix4d Pr = P0;
  const Eigen::Matrix2d Q = sv.array().square().matrix().asDiagonal();
  const Eigen::Matrix2d R = sw.array().square().matrix().asDiagonal();
  for (const auto& z : zs) {
    xr = A() * xr;
    Pr = A() * Pr * A().transpose() + B() * Q * B().transpose();
    const Eigen::Matrix2d S = H() * Pr * H().transpose() + R;
    const Eigen::Matrix<double, 4, 2> K = Pr * H().transpose() * S.inverse();
    xr += K * (z - H() * xr);
    Pr = (Eigen::Matrix4d::Identity() - K * H()) * Pr;
  }

  for (const char* name : {"dd2", "ekf", "ukf"}) {
    auto f = MakeFilter(name).value();
    f->Initialize(x0, StateMat(P0));
    const LinearProcess proc;
    const LinearMeasurement meas;
    NoiseMat Sv = NoiseMat::Zero(2, 2);
    Sv.diagonal() = sv;
    MeasMat Sw = MeasMat::Zero(2, 2);
    Sw.diagonal() = sw;
    for (const auto& z : zs) {
      f->Predict(proc, Sv);
      const auto r = f->Update(meas, MeasVec(z), Sw);
      ASSERT_TRUE(r.ok);
    }
    const double rel_x = (f->mean() - xr).norm() / xr.norm();
    const double rel_p = (f->covariance() - Pr).norm() / Pr.norm();
    EXPECT_LT(rel_x, 1e-8) << name;
    EXPECT_LT(rel_p, 1e-8) << name;
  }
}

TEST(FilterRegistry, AnUnknownNameIsAnErrorNamingTheKnownFilters) {
  const auto made = MakeFilter("kalman9000");
  ASSERT_FALSE(made.ok());
  EXPECT_NE(made.status().message().find("unknown filter 'kalman9000'"), std::string::npos);
  EXPECT_NE(made.status().message().find("ukf"), std::string::npos) << made.status().message();
  EXPECT_TRUE(MakeFilter("dd2").ok());
}

}  // namespace
}  // namespace kincal
