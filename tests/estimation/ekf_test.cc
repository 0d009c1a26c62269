// The EKF (src/estimation/ekf.cc): the Kalman answer on a linear measurement, and exactly
// first order through a nonlinear process: mean f(mean), covariance F P F^T (which is
// why it misses the polar transform's bias that DD2 and the UKF capture).
#include <gtest/gtest.h>

#include "estimation/filter_unit_util.h"

namespace kincal {
namespace {

TEST(Ekf, KalmanOnALinearMeasurement) { testing::ExpectKalmanOnALinearMeasurement("ekf"); }

TEST(Ekf, FirstOrderThroughThePolarTransform) {
  auto f = MakeFilter("ekf").value();
  EXPECT_EQ(f->name(), "ekf");
  const double sr = 0.02, sb = 0.35;
  f->Initialize(Eigen::Vector2d(1.0, M_PI / 2),
                StateMat(Eigen::Vector2d(sr * sr, sb * sb).asDiagonal()));
  f->Predict(testing::PolarToCartesian(), NoiseMat::Zero(1, 1));
  // At (1, pi/2): F = [[0, -1], [1, 0]], so the mean is (0, 1) and P = diag(sb^2, sr^2).
  EXPECT_NEAR(f->mean()[0], 0.0, 1e-12);
  EXPECT_NEAR(f->mean()[1], 1.0, 1e-12);
  const StateMat P = f->covariance();
  EXPECT_NEAR(P(0, 0), sb * sb, 1e-6);
  EXPECT_NEAR(P(1, 1), sr * sr, 1e-6);
  EXPECT_NEAR(P(0, 1), 0.0, 1e-6);
  // The true mean of r sin b is exp(-sb^2 / 2) = 0.9405: the EKF's first order misses it.
  EXPECT_GT(f->mean()[1] - std::exp(-sb * sb / 2), 0.05);
}

}  // namespace
}  // namespace kincal
