// Parameter recovery on simulated data, every model, recursive and batch; effects known
// to the estimator are recovered too. (The batch's own tests, the Cramer-Rao bound among
// them, are in estimation/batch_test.cc.)
#include <gtest/gtest.h>

#include <random>

#include "kincal/estimation/batch.h"
#include "kincal/estimation/online_calibrator.h"
#include "test_util.h"

namespace kincal {
namespace {

using testing::AllModelScenarios;

struct RecoveryCase {
  int model;
  std::vector<std::string> effects;
  std::vector<std::pair<std::string, double>> effect_truth;
};

VecN<kMaxState> TruthParams(const System& sys, const testing::ModelScenario& sc,
                            const RecoveryCase& c) {
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

class Recovery : public ::testing::TestWithParam<RecoveryCase> {};

TEST_P(Recovery, FilterAndBatchRecoverTruthWithin3Sigma) {
  const RecoveryCase c = GetParam();
  const auto sc = AllModelScenarios()[static_cast<size_t>(c.model)];
  const System sys = MakeSystem(sc.model, c.effects).value();
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
        RecoveryCase{0, {}, {}}, RecoveryCase{1, {}, {}}, RecoveryCase{2, {}, {}},
        RecoveryCase{3, {}, {}},
        RecoveryCase{1,
                     {"time_offset", "lever_arm"},
                     {{"delay_s", 0.15}, {"dx", 0.1}, {"dy", -0.03}, {"dtheta", 0.05}}},
        RecoveryCase{0, {"actuator_lag"}, {{"tau_s", 0.12}}},
        RecoveryCase{
            2, {"lateral_slip", "yaw_rate_bias"}, {{"c_slip", 0.02}, {"bias_rad_s", 0.03}}}),
    [](const ::testing::TestParamInfo<RecoveryCase>& info) {
      std::string name = AllModelScenarios()[static_cast<size_t>(info.param.model)].model;
      for (const auto& e : info.param.effects) name += "_" + e;
      return name;
    });

}  // namespace
}  // namespace kincal
