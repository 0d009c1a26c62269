// The UKF (src/estimation/ukf.cc): the Kalman answer on a linear measurement, and second
// order through the polar transform: its mean carries the bias E[r sin b] =
// exp(-sb^2 / 2) that a first-order EKF misses.
#include <gtest/gtest.h>

#include "estimation/filter_unit_util.h"

namespace kincal {
namespace {

TEST(Ukf, KalmanOnALinearMeasurement) { testing::ExpectKalmanOnALinearMeasurement("ukf"); }

TEST(Ukf, SecondOrderThroughThePolarTransform) {
  auto f = MakeFilter("ukf").value();
  EXPECT_EQ(f->name(), "ukf");
  const double sr = 0.02, sb = 0.35;
  f->Initialize(Eigen::Vector2d(1.0, M_PI / 2),
                StateMat(Eigen::Vector2d(sr * sr, sb * sb).asDiagonal()));
  f->Predict(testing::PolarToCartesian(), NoiseMat::Zero(1, 1));
  // Exact moments of (r cos b, r sin b) for independent Gaussian r, b at (1, pi/2).
  const double mean_y = std::exp(-sb * sb / 2);  // 0.9405
  EXPECT_NEAR(f->mean()[0], 0.0, 1e-9);          // symmetric: no bias across
  EXPECT_NEAR(f->mean()[1], mean_y, 3e-3);       // the EKF is 0.06 off
  const double var_x = (1 + sr * sr) * 0.5 * (1 - std::exp(-2 * sb * sb));
  const StateMat P = f->covariance();
  EXPECT_NEAR(P(0, 0), var_x, 0.1 * var_x);
  EXPECT_NEAR(P(0, 1), 0.0, 1e-9);
}

}  // namespace
}  // namespace kincal
