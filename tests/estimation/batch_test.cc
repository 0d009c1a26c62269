// The batch fit and its Cramer-Rao bound: a constant-control run is rank deficient (and a
// prior makes the Bayesian bound exist); the spread of 40 Monte-Carlo fits matches the
// bound; the fit recovers the truth within 3 sigma from a start 5 % off.
#include "kincal/estimation/batch.h"

#include <gtest/gtest.h>

#include <random>

#include "test_util.h"

namespace kincal {
namespace {

using testing::AllModelScenarios;

TEST(Bound, OneConstantControlRunCannotSeparateRadiiAndTrack) {
  const System sys = MakeSystem("diffdrive");
  ControlSignal u(2, 0);
  const std::array<double, 2> w = {10.0, 20.0};
  AppendConstant(&u, 0, SecondsToNs(10.0), w);
  std::mt19937_64 rng(1);
  const VecN<kMaxState> truth = testing::ToVec({0.031, 0.0313, 0.148});
  std::vector<TimeNs> times;
  for (int k = 0; k < 60; ++k) times.push_back(SecondsToNs(k / 6.0));
  const auto traj = SimulateTruth(sys, sys.MakeState(0, 0, 0, truth, u, 0), u, times);
  const auto meas = MeasurePoses(traj, Eigen::Matrix3d::Identity() * 1e-8, 0, rng);
  const Eigen::Vector3d start = traj.front().x.head(3);
  const BatchResult one = BoundAt(sys, u, meas, truth.cast<double>(), {start}, {});
  EXPECT_FALSE(one.covariance_ok) << "a single constant-control run must be rank deficient";
  // With a prior, the Bayesian bound exists.
  BatchOptions with_prior;
  with_prior.prior = ParamPrior{truth.cast<double>(), Eigen::Matrix3d::Identity() * 1e-6};
  EXPECT_TRUE(BoundAt(sys, u, meas, truth.cast<double>(), {start}, with_prior).covariance_ok);
}

TEST(Bound, BatchSpreadMatchesCramerRao) {
  // 40 Monte-Carlo repetitions of one design: the empirical variance of the batch
  // estimates must agree with the bound (within the sampling error of 40 samples).
  const System sys = MakeSystem("diffdrive");
  const auto sc = AllModelScenarios()[0];
  const VecN<kMaxState> truth = testing::ToVec(sc.truth);
  std::mt19937_64 rng(9);
  const Eigen::Vector3d sigma(0.002, 0.002, 0.01);
  const auto d = testing::Simulate(sys, truth, sc.lo, sc.hi, 20.0, 10.0, sigma, rng);
  const Eigen::Vector3d start = d.truth.front().x.head(3);
  const BatchResult bound = BoundAt(sys, d.controls, d.meas, truth.cast<double>(), {start}, {});
  ASSERT_TRUE(bound.covariance_ok);
  Eigen::Vector3d sq = Eigen::Vector3d::Zero();
  const int trials = 40;
  for (int t = 0; t < trials; ++t) {
    std::vector<TrajectoryPoint> tr = d.truth;
    const auto meas = MeasurePoses(tr, sigma.array().square().matrix().asDiagonal(), 0, rng);
    const BatchResult b = FitBatch(sys, d.controls, meas, truth.cast<double>() * 1.05, {});
    sq += (b.params - truth.cast<double>()).array().square().matrix();
  }
  for (int i = 0; i < 3; ++i) {
    const double ratio = sq[i] / trials / bound.covariance(i, i);
    EXPECT_GT(ratio, 0.5) << i;
    EXPECT_LT(ratio, 1.6) << i;
  }
}

TEST(Batch, RecoversTheTruthWithin3SigmaFromAStart5PercentOff) {
  const System sys = MakeSystem("diffdrive");
  const auto sc = AllModelScenarios()[0];
  const VecN<kMaxState> truth = testing::ToVec(sc.truth);
  std::mt19937_64 rng(21);
  const Eigen::Vector3d sigma(0.002, 0.002, 0.01);
  const auto d = testing::Simulate(sys, truth, sc.lo, sc.hi, 20.0, 10.0, sigma, rng);
  const BatchResult b = FitBatch(sys, d.controls, d.meas, truth.cast<double>() * 1.05, {});
  ASSERT_TRUE(b.covariance_ok);
  for (int i = 0; i < 3; ++i) {
    const double err = b.params[i] - truth[i];
    const double s = std::sqrt(b.covariance(i, i));
    EXPECT_LT(std::abs(err), 3.0 * s) << sys.params()[static_cast<size_t>(i)].name;
    // A real calibration, not a loose one: each parameter to better than 1 %.
    EXPECT_LT(s, 0.01 * std::abs(truth[i])) << sys.params()[static_cast<size_t>(i)].name;
  }
}

// Bad data is a status naming the problem, never an exception (callers used to catch any
// std::exception as "the fit failed").
TEST(Batch, BadInputsAreStatusesThatSayWhatIsWrong) {
  const System sys = MakeSystem("diffdrive");
  const auto sc = AllModelScenarios()[0];
  const VecN<kMaxState> truth = testing::ToVec(sc.truth);
  std::mt19937_64 rng(3);
  const auto d = testing::Simulate(sys, truth, sc.lo, sc.hi, 5.0, 10.0,
                                   Eigen::Vector3d(0.002, 0.002, 0.01), rng);
  const Eigen::VectorXd guess = truth.cast<double>();
  auto fit = [&](std::vector<PoseMeasurement> meas, const Eigen::VectorXd& p0) {
    BatchResult r;
    EXPECT_NO_THROW(r = FitBatch(sys, d.controls, meas, p0, {}));
    EXPECT_FALSE(r.status.ok());
    return r.status.message();
  };
  EXPECT_EQ(fit({}, guess), "batch: no pose measurements");
  auto backwards = d.meas;
  std::swap(backwards[3].t_ns, backwards[4].t_ns);
  backwards[3].segment = backwards[4].segment = 0;
  for (auto& m : backwards) m.segment = 0;
  EXPECT_EQ(fit(backwards, guess), "batch: measurement times go backwards within segment 0");
  auto singular = d.meas;
  singular[2].R = Eigen::Matrix3d::Zero();
  EXPECT_EQ(fit(singular, guess), "batch: measurement 2: covariance is not positive definite");
  EXPECT_EQ(fit(d.meas, guess.head(2)),
            "batch: the initial guess has 2 parameters, the system 3, all finite expected");
  // The same data, well formed, fits.
  EXPECT_TRUE(FitBatch(sys, d.controls, d.meas, guess, {}).status.ok());
}

}  // namespace
}  // namespace kincal
