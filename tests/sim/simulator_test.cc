// Simulator: frame timing statistics, command profiles, and truth integrated by the
// System; measurements scatter with the configured covariance.
#include "kincal/sim/simulator.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>

namespace kincal {
namespace {

TEST(FrameTimes, NominalRateStallsAndDropoutsHaveTheirConfiguredRates) {
  std::mt19937_64 rng(1);
  const FrameTimingOptions steady{25.0, 0.0, 0.0, 0.0};
  const auto t = FrameTimes(0, SecondsToNs(10.02), steady, rng);  // 0, 0.04, ... 10.0 s
  ASSERT_EQ(t.size(), 251u);
  for (size_t k = 1; k < t.size(); ++k) ASSERT_NEAR(t[k] - t[k - 1], 40'000'000, 1) << k;
  // Stalls of U(0, 0.4) s with p = 0.25: mean interval 1/6 + 0.05 s; 5 % dropped.
  const FrameTimingOptions thesis{6.0, 0.4, 0.25, 0.05};
  const auto s = FrameTimes(0, SecondsToNs(2000.0), thesis, rng);
  const double kept_mean_interval = 2000.0 / static_cast<double>(s.size());
  EXPECT_NEAR(kept_mean_interval, (1.0 / 6 + 0.25 * 0.2) / 0.95, 0.01);
  for (size_t k = 1; k < s.size(); ++k) ASSERT_GT(s[k], s[k - 1]);
  std::string error;
  EXPECT_FALSE((FrameTimingOptions{0.0, 0.0, 0.0, 0.0}).IsValid(&error));
  EXPECT_FALSE(error.empty());
}

TEST(Profiles, ConstantHoldsAndStopsAtTheEnd) {
  ControlSignal u(2, 0);
  const std::array<double, 2> go = {0.5, -0.2};
  AppendConstant(&u, 0, SecondsToNs(4.0), go);
  EXPECT_EQ(u.At(2.0)[0], 0.5);
  EXPECT_EQ(u.At(2.0)[1], -0.2);
  EXPECT_EQ(u.At(4.5)[0], 0.0);
}

TEST(Profiles, RandomCommandsStayInTheirRange) {
  std::mt19937_64 rng(2);
  const std::array<double, 2> lo = {-0.3, -1.5}, hi = {1.0, 1.5};
  ControlSignal smooth(2, 0), piecewise(2, 0);
  AppendSmoothRandom(&smooth, 0, SecondsToNs(60.0), lo, hi, 2.0, 50.0, rng);
  AppendPiecewiseRandom(&piecewise, 0, SecondsToNs(60.0), lo, hi, 0.5, 2.0, rng);
  for (double t = 0.0; t < 60.0; t += 0.01) {
    for (int c = 0; c < 2; ++c) {
      ASSERT_GE(smooth.At(t)[c], lo[c] - 1e-12) << t;
      ASSERT_LE(smooth.At(t)[c], hi[c] + 1e-12) << t;
      ASSERT_GE(piecewise.At(t)[c], lo[c] - 1e-12) << t;
      ASSERT_LE(piecewise.At(t)[c], hi[c] + 1e-12) << t;
    }
  }
}

TEST(Truth, FollowsTheArcAndMeasurementsScatterAsConfigured) {
  const System sys = MakeSystem("unicycle").value();
  ControlSignal u(2, 0);
  const std::array<double, 2> go = {0.5, 0.25};
  AppendConstant(&u, 0, SecondsToNs(100.0), go);
  VecN<kMaxState> p(2);
  p << 0.9, 0.8;
  const StateVec x0 = sys.MakeState(0, 0, 0, p, u, 0.0);
  std::vector<TimeNs> times;
  for (int k = 0; k < 2000; ++k) times.push_back(SecondsToNs(0.05 * k));
  const auto truth = SimulateTruth(sys, x0, u, times);
  const double t = 99.95, w = 0.2, r = 0.45 / w;
  EXPECT_NEAR(truth.back().target.x(), r * std::sin(w * t), 1e-9);
  EXPECT_NEAR(truth.back().target.y(), r * (1 - std::cos(w * t)), 1e-9);
  std::mt19937_64 rng(3);
  const Eigen::Matrix3d R = Eigen::Vector3d(1e-6, 4e-6, 1e-4).asDiagonal();
  const auto meas = MeasurePoses(truth, R, 0, rng);
  Eigen::Vector3d sum_sq = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < meas.size(); ++k) {
    Eigen::Vector3d e = meas[k].z - truth[k].target;
    e[2] = std::remainder(e[2], 2 * M_PI);
    sum_sq += e.cwiseAbs2();
  }
  const Eigen::Vector3d var = sum_sq / static_cast<double>(meas.size());
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(var[i] / R(i, i), 1.0, 0.1) << i;  // 2000 draws
}

}  // namespace
}  // namespace kincal
