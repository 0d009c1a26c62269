// Filter consistency: the normalised estimation error squared (NEES) of the augmented
// state at the end of a run must fall inside the two-sided 95 % chi-square band in at
// least 90 % of Monte-Carlo runs, for every model.
#include <gtest/gtest.h>

#include <map>
#include <random>

#include "kincal/angles.h"
#include "kincal/estimation/online_calibrator.h"
#include "test_util.h"

namespace kincal {
namespace {

using testing::AllModelScenarios;

// Two-sided 95 % chi-square quantiles (2.5 %, 97.5 %) by degrees of freedom.
std::pair<double, double> Chi2Band(int dof) {
  static const std::map<int, std::pair<double, double>> kBand = {
      {5, {0.8312, 12.8325}}, {6, {1.2373, 14.4494}}, {7, {1.6899, 16.0128}},
      {8, {2.1797, 17.5345}}, {9, {2.7004, 19.0228}}, {10, {3.2470, 20.4832}}};
  return kBand.at(dof);
}

struct ConsistencyCase {
  int model;
  bool control_noise;
  std::vector<std::string> effects;
  std::vector<std::pair<std::string, double>> effect_truth;
};

class Consistency : public ::testing::TestWithParam<ConsistencyCase> {};

TEST_P(Consistency, NeesInside95PercentBand) {
  const ConsistencyCase c = GetParam();
  auto sc = AllModelScenarios()[static_cast<size_t>(c.model)];
  const bool control_noise = c.control_noise;
  const System sys = MakeSystem(sc.model, c.effects).value();
  for (const auto& e : c.effect_truth) sc.truth.push_back(e.second);
  const int n = sys.state_dim();
  // Effect states (a lag's realised controls) are deterministic functions of the
  // parameters and the command history when the truth has no control noise: they add
  // no degrees of freedom to the error.
  const auto band = Chi2Band(control_noise ? n : n - sys.num_states());
  const int runs = 50;
  int inside = 0;
  std::mt19937_64 rng(100 + static_cast<uint64_t>(c.model));
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Vector3d sigma(0.002, 0.002, 0.01);
  const Eigen::Matrix3d R = sigma.array().square().matrix().asDiagonal();
  for (int run = 0; run < runs; ++run) {
    testing::SimData d =
        testing::Simulate(sys, testing::ToVec(sc.truth), sc.lo, sc.hi, 20.0, 15.0, sigma, rng);
    OnlineCalibratorOptions opt;
    ControlSignal realised = d.controls;
    if (control_noise) {
      // Realised controls: commands + white noise (std 2 % of range, per 20 ms sample);
      // the filter is told the matching PSD.
      std::vector<double> sd, psd;
      for (size_t c = 0; c < sc.lo.size(); ++c) {
        sd.push_back(0.02 * (sc.hi[c] - sc.lo[c]));
        psd.push_back(sd.back() * sd.back() * 0.02);
      }
      realised = PerturbControls(d.controls, sd, rng);
      opt.noise.control_psd = psd;
      std::vector<TimeNs> times;
      for (const auto& p : d.truth) times.push_back(p.t_ns);
      d.truth = SimulateTruth(sys, d.truth.front().x, realised, times);
      d.meas = MeasurePoses(d.truth, R, 0, rng);
    }
    // Prior: guess drawn from the prior itself, so that the prior is consistent.
    const int np = sys.num_params();
    VecN<kMaxState> guess(np);
    StateMat P = StateMat::Zero(np, np);
    for (int i = 0; i < np; ++i) {
      const double s = std::max(0.05 * std::abs(sc.truth[static_cast<size_t>(i)]),
                                0.1 * sys.params()[static_cast<size_t>(i)].default_sigma);
      guess[i] = sc.truth[static_cast<size_t>(i)] + s * g(rng);
      P(i, i) = s * s;
    }
    OnlineCalibrator cal(sys, opt, 0);
    cal.controls() = d.controls;
    cal.Initialize(d.meas.front().t_ns, d.meas.front().z, R, guess, P);
    for (size_t k = 1; k < d.meas.size(); ++k) cal.AddPose(d.meas[k].t_ns, d.meas[k].z, R);
    StateVec err = cal.state() - d.truth.back().x;
    err[2] = WrapAngle(err[2]);
    const double nees = err.dot(cal.covariance().ldlt().solve(err));
    if (nees >= band.first && nees <= band.second) ++inside;
  }
  EXPECT_GE(inside, static_cast<int>(0.9 * runs)) << sc.model;
}

std::string ConsistencyCaseName(const ::testing::TestParamInfo<ConsistencyCase>& info) {
  std::string name = AllModelScenarios()[static_cast<size_t>(info.param.model)].model;
  if (info.param.control_noise) name += "_control_noise";
  for (const auto& e : info.param.effects) name += "_" + e;
  return name;
}

INSTANTIATE_TEST_SUITE_P(
    AllModels, Consistency,
    ::testing::Values(
        ConsistencyCase{0, false, {}, {}}, ConsistencyCase{1, false, {}, {}},
        ConsistencyCase{2, false, {}, {}}, ConsistencyCase{3, false, {}, {}},
        ConsistencyCase{0, true, {}, {}}, ConsistencyCase{1, true, {}, {}},
        ConsistencyCase{2, true, {}, {}}, ConsistencyCase{3, true, {}, {}},
        ConsistencyCase{1,
                        false,
                        {"time_offset", "lever_arm"},
                        {{"delay_s", 0.15}, {"dx", 0.1}, {"dy", -0.03}, {"dtheta", 0.05}}},
        ConsistencyCase{0, false, {"actuator_lag"}, {{"tau_s", 0.12}}},
        ConsistencyCase{
            2, false, {"lateral_slip", "yaw_rate_bias"}, {{"c_slip", 0.02}, {"bias_rad_s", 0.03}}}),
    ConsistencyCaseName);

}  // namespace
}  // namespace kincal
