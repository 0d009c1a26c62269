// Small systems with known answers for the filters' unit tests (sr_dd2, ekf, ukf).
#pragma once

#include <cmath>

#include "kincal/estimation/filter.h"

namespace kincal::testing {

// x = [r, bearing] -> [r cos b, r sin b]; no process noise.
class PolarToCartesian final : public ProcessFunction {
 public:
  int state_dim() const override { return 2; }
  int noise_dim() const override { return 1; }
  void Eval(const double* x, const double*, double* out) const override {
    out[0] = x[0] * std::cos(x[1]);
    out[1] = x[0] * std::sin(x[1]);
  }
};

// z = x0 + x1 (linear, one measurement).
class SumOfTwo final : public MeasurementFunction {
 public:
  int state_dim() const override { return 2; }
  int meas_dim() const override { return 1; }
  void Eval(const double* x, double* z) const override { z[0] = x[0] + x[1]; }
};

// Prior N(0, diag(1, 4)), z = x0 + x1 + w, w ~ N(0, 1), z = 3: by hand, S = 6,
// K = [1, 4] / 6, mean [0.5, 2], P = [[5/6, -2/3], [-2/3, 4/3]], NIS 1.5. Every filter
// must give the Kalman answer on a linear measurement.
inline void ExpectKalmanOnALinearMeasurement(const char* name) {
  auto f = MakeFilter(name).value();
  f->Initialize(Eigen::Vector2d::Zero(), StateMat(Eigen::Vector2d(1.0, 4.0).asDiagonal()));
  MeasVec z(1);
  z << 3.0;
  MeasMat sw(1, 1);
  sw << 1.0;
  const UpdateResult u = f->Update(SumOfTwo(), z, sw);
  ASSERT_TRUE(u.ok) << name;
  EXPECT_FALSE(u.gated) << name;
  EXPECT_NEAR(u.nis, 1.5, 1e-9) << name;
  EXPECT_NEAR(u.innovation[0], 3.0, 1e-12) << name;
  EXPECT_NEAR(u.innovation_cov(0, 0), 6.0, 1e-9) << name;
  EXPECT_NEAR(f->mean()[0], 0.5, 1e-9) << name;
  EXPECT_NEAR(f->mean()[1], 2.0, 1e-9) << name;
  const StateMat P = f->covariance();
  EXPECT_NEAR(P(0, 0), 5.0 / 6.0, 1e-9) << name;
  EXPECT_NEAR(P(0, 1), -2.0 / 3.0, 1e-9) << name;
  EXPECT_NEAR(P(1, 0), -2.0 / 3.0, 1e-9) << name;
  EXPECT_NEAR(P(1, 1), 4.0 / 3.0, 1e-9) << name;
}

}  // namespace kincal::testing
