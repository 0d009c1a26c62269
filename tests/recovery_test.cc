// Parameter recovery on simulated data, every model, recursive and batch; effects known
// to the estimator are recovered too; the batch covariance matches the Monte-Carlo spread
// and the Cramer-Rao bound.
#include <gtest/gtest.h>

#include <random>

#include "kincal/estimation/batch.h"
#include "kincal/estimation/online_calibrator.h"
#include "test_util.h"

namespace kincal {
namespace {

using testing::AllModelScenarios;

struct Case {
  int model;
  std::vector<std::string> effects;
  std::vector<std::pair<std::string, double>> effect_truth;
};

VecN<kMaxState> TruthParams(const System& sys, const testing::ModelScenario& sc, const Case& c) {
  VecN<kMaxState> p(sys.num_params());
  for (int i = 0; i < sys.num_params(); ++i) {
    p[i] = i < static_cast<int>(sc.truth.size()) ? sc.truth[static_cast<size_t>(i)] : 0.0;
  }
  for (const auto& [name, v] : c.effect_truth) p[sys.ParamIndex(name)] = v;
  return p;
}

// Initial guess: 10 % off plus 0.3 of the parameter's generic prior sigma.
VecN<kMaxState> Guess(const System& sys, const VecN<kMaxState>& truth) {
  VecN<kMaxState> g = truth;
  for (int i = 0; i < g.size(); ++i) {
    g[i] = 1.1 * truth[i] + 0.3 * sys.params()[static_cast<size_t>(i)].default_sigma;
  }
  return g;
}

class Recovery : public ::testing::TestWithParam<Case> {};

TEST_P(Recovery, FilterAndBatchRecoverTruthWithin3Sigma) {
  const Case c = GetParam();
  const auto sc = AllModelScenarios()[static_cast<size_t>(c.model)];
  const System sys = MakeSystem(sc.model, c.effects);
  const VecN<kMaxState> truth = TruthParams(sys, sc, c);
  std::mt19937_64 rng(42 + static_cast<uint64_t>(c.model));
  const Eigen::Vector3d sigma(0.001, 0.001, 0.005);
  const auto d = testing::Simulate(sys, truth, sc.lo, sc.hi, 60.0, 20.0, sigma, rng);
  const int np = sys.num_params();
  const VecN<kMaxState> guess = Guess(sys, truth);
  StateMat P = StateMat::Zero(np, np);
  for (int i = 0; i < np; ++i) {
    const double s =
        std::max(0.2 * std::abs(guess[i]), sys.params()[static_cast<size_t>(i)].default_sigma);
    P(i, i) = s * s;
  }
  // Recursive DD2.
  OnlineCalibrator cal(sys, {}, 0);
  cal.controls() = d.controls;
  cal.Initialize(d.meas.front().t_ns, d.meas.front().z, d.meas.front().R, guess, P);
  for (size_t k = 1; k < d.meas.size(); ++k) cal.AddPose(d.meas[k].t_ns, d.meas[k].z, d.meas[k].R);
  const auto est = cal.params();
  const auto cov = cal.params_covariance();
  for (int i = 0; i < np; ++i) {
    const double s = std::sqrt(cov(i, i));
    EXPECT_LE(std::abs(est[i] - truth[i]), 3.0 * s)
        << sc.model << " dd2 " << sys.params()[static_cast<size_t>(i)].name << " est " << est[i]
        << " truth " << truth[i] << " sigma " << s;
    EXPECT_LT(s, 0.01 * std::max(std::abs(truth[i]), 0.05)) << "not informative";
  }
  // Batch, multiple shooting over 10 s segments, no prior.
  std::vector<PoseMeasurement> meas = d.meas;
  for (auto& m : meas) m.segment = static_cast<int>(NsToSeconds(m.t_ns) / 10.0);
  const BatchResult b = FitBatch(sys, d.controls, meas, guess.cast<double>(), {});
  ASSERT_TRUE(b.covariance_ok) << b.message;
  for (int i = 0; i < np; ++i) {
    const double s = std::sqrt(b.covariance(i, i));
    EXPECT_LE(std::abs(b.params[i] - truth[i]), 3.0 * s)
        << sc.model << " batch " << sys.params()[static_cast<size_t>(i)].name;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Models, Recovery,
    ::testing::Values(
        Case{0, {}, {}}, Case{1, {}, {}}, Case{2, {}, {}}, Case{3, {}, {}},
        Case{1,
             {"time_offset", "lever_arm"},
             {{"delay_s", 0.15}, {"dx", 0.1}, {"dy", -0.03}, {"dtheta", 0.05}}},
        Case{0, {"actuator_lag"}, {{"tau_s", 0.12}}},
        Case{2, {"lateral_slip", "yaw_rate_bias"}, {{"c_slip", 0.02}, {"bias_rad_s", 0.03}}}),
    [](const ::testing::TestParamInfo<Case>& info) {
      std::string name = AllModelScenarios()[static_cast<size_t>(info.param.model)].model;
      for (const auto& e : info.param.effects) name += "_" + e;
      return name;
    });

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

}  // namespace
}  // namespace kincal
