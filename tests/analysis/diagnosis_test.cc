#include "kincal/analysis/diagnosis.h"

#include <gtest/gtest.h>

#include <random>

namespace kincal {
namespace {

// 600 windows, one per 0.1 s, horizon 1 s: 60 effective windows. The along-track error is
// 0.02 * accel plus noise; the heading has a bias of 3 mrad while moving; cross is noise.
struct Synthetic {
  std::vector<ResidualPoint> points;
  std::vector<RegressorValues> regressors;
};

Synthetic Make(double along_gain, double heading_bias, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  Synthetic s;
  for (int k = 0; k < 600; ++k) {
    RegressorValues r;
    const double accel = n(rng), w = n(rng);
    r.Set(Regressor::kAccel, accel);
    r.Set(Regressor::kTurnRate, w);
    r.Set(Regressor::kConst, 1.0);
    ResidualPoint p{0.1 * k, k >= 480, along_gain * accel + 0.005 * n(rng), 0.005 * n(rng),
                    heading_bias + 0.002 * n(rng)};
    s.points.push_back(p);
    s.regressors.push_back(r);
  }
  return s;
}

TEST(Diagnosis, NamesTheTermThatCarriesTheError) {
  const Synthetic s = Make(0.02, 0.003, 3);
  const auto terms = Diagnose(s.points, s.regressors, 1.0);
  ASSERT_EQ(terms.size(), 9u);  // 3 components x 3 regressors present
  EXPECT_EQ(terms[0].component_id, ResidualComponent::kAlong);
  EXPECT_EQ(terms[0].regressor_id, Regressor::kAccel);
  // r = 0.02 / sqrt(0.02^2 + 0.005^2) = 0.97; z = r * sqrt(48 s / 1 s).
  EXPECT_NEAR(terms[0].r, 0.97, 0.02);
  EXPECT_NEAR(terms[0].z, 0.97 * std::sqrt(47.9), 0.3);
  // The heading bias: mean over RMS = 3 / sqrt(3^2 + 2^2) = 0.83.
  for (const auto& t : terms) {
    if (t.component_id == ResidualComponent::kHeading && t.regressor_id == Regressor::kConst) {
      EXPECT_NEAR(t.r, 0.83, 0.03);
    }
    if (t.component_id == ResidualComponent::kCross) {
      EXPECT_LT(std::abs(t.z), 3.0) << t.regressor;
    }
  }
}

TEST(Diagnosis, SignatureZIsItsStrongestMeasuredTerm) {
  const auto terms = Diagnose(Make(0.02, 0.0, 4).points, Make(0.02, 0.0, 4).regressors, 1.0);
  const double along_accel = terms[0].z;
  EXPECT_DOUBLE_EQ(SignatureZ({{ResidualComponent::kAlong, Regressor::kAccel},
                               {ResidualComponent::kCross, Regressor::kTurnRate}},
                              terms),
                   std::abs(along_accel));
  EXPECT_DOUBLE_EQ(SignatureZ({{ResidualComponent::kHeading, Regressor::kYawAccel}}, terms), 0.0);
}

TEST(Diagnosis, TooFewWindowsGiveNothing) {
  Synthetic s = Make(0.02, 0.0, 5);
  s.points.resize(9);
  s.regressors.resize(9);
  EXPECT_TRUE(Diagnose(s.points, s.regressors, 1.0).empty());
}

}  // namespace
}  // namespace kincal
