// OnlineCalibrator's own contract, on a simulated unicycle with a known truth: it
// converges to the truth within its sigma on clean data, refuses poses from the past,
// gates an outlier without moving, keeps the parameters through a pose reset, predicts
// without a measurement, widens with the extra pose noise, and names bad options.
#include "kincal/estimation/online_calibrator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>

#include "test_util.h"

namespace kincal {
namespace {

using testing::Simulate;
using testing::ToVec;

struct SimulatedUnicycle {
  System sys = MakeSystem("unicycle").value();
  VecN<kMaxState> truth = ToVec({1.06, 0.93});
  testing::SimData data;
  SimulatedUnicycle() {
    std::mt19937_64 rng(11);
    const double lo[] = {-0.3, -1.5}, hi[] = {1.0, 1.5};
    data = Simulate(sys, truth, lo, hi, 40.0, 20.0, Eigen::Vector3d(0.002, 0.002, 0.005), rng);
  }
  // A calibrator started at the first pose from a guess 10 % off with a 20 % sigma.
  OnlineCalibrator Start() const {
    OnlineCalibrator cal(sys, {}, 0);
    cal.controls() = data.controls;
    const auto& m0 = data.meas.front();
    StateMat P = StateMat::Zero(sys.num_params(), sys.num_params());
    P.diagonal().setConstant(0.2 * 0.2);
    cal.Initialize(m0.t_ns, m0.z, m0.R, ToVec({1.0 / 1.1 * 1.06, 1.1 * 0.93}), P);
    return cal;
  }
  // The poses [1, end) into the calibrator.
  void Feed(OnlineCalibrator* cal, size_t end) const {
    for (size_t k = 1; k < end; ++k) {
      const auto& m = data.meas[k];
      cal->AddPose(m.t_ns, m.z, m.R);
    }
  }
};

TEST(OnlineCalibrator, ConvergesToTheTruthWithinItsSigma) {
  const SimulatedUnicycle run;
  OnlineCalibrator cal = run.Start();
  for (size_t k = 1; k < run.data.meas.size(); ++k) {
    const auto& m = run.data.meas[k];
    ASSERT_TRUE(cal.AddPose(m.t_ns, m.z, m.R).ok) << k;
  }
  EXPECT_EQ(cal.update_count(), static_cast<int64_t>(run.data.meas.size()) - 1);
  const auto p = cal.params();
  const StateMat C = cal.params_covariance();
  for (int i = 0; i < 2; ++i) {
    const double s = std::sqrt(C(i, i));
    EXPECT_LT(std::abs(p[i] - run.truth[i]), 3.0 * s) << run.sys.params()[i].name;
    EXPECT_LT(s, 0.005) << "40 s of motion should pin " << run.sys.params()[i].name;
  }
}

TEST(OnlineCalibrator, APoseFromThePastIsRefusedAndChangesNothing) {
  const SimulatedUnicycle run;
  OnlineCalibrator cal = run.Start();
  const auto& m = run.data.meas[10];
  ASSERT_TRUE(cal.AddPose(m.t_ns, m.z, m.R).ok);
  const StateVec before = cal.state();
  const auto& old = run.data.meas[5];
  EXPECT_FALSE(cal.AddPose(old.t_ns, old.z, old.R).ok);
  EXPECT_EQ(cal.time_ns(), m.t_ns);
  EXPECT_EQ((cal.state() - before).norm(), 0.0);
  EXPECT_EQ(cal.update_count(), 1);
}

TEST(OnlineCalibrator, AnOutlierFailsTheGateAndIsNotUsed) {
  const SimulatedUnicycle run;
  OnlineCalibrator cal = run.Start();
  run.Feed(&cal, 100);
  const VecN<kMaxState> params = cal.params();
  const auto& m = run.data.meas[100];
  const Eigen::Vector3d far = m.z + Eigen::Vector3d(0.5, 0.0, 0.0);  // 50 cm off
  const UpdateResult r = cal.AddPose(m.t_ns, far, m.R, /*gate_nis=*/16.0);
  EXPECT_TRUE(r.gated);
  EXPECT_FALSE(r.ok);
  EXPECT_GT(r.nis, 1000.0);
  EXPECT_EQ((cal.params() - params).norm(), 0.0) << "a gated pose must not move the estimate";
  // The true pose at the next frame is used again.
  const auto& next = run.data.meas[101];
  EXPECT_TRUE(cal.AddPose(next.t_ns, next.z, next.R, 16.0).ok);
}

TEST(OnlineCalibrator, APoseResetKeepsTheParametersAndTheirCovariance) {
  const SimulatedUnicycle run;
  OnlineCalibrator cal = run.Start();
  run.Feed(&cal, 200);
  const VecN<kMaxState> params = cal.params();
  const StateMat C = cal.params_covariance();
  const auto& m = run.data.meas[250];
  const Eigen::Vector3d elsewhere(2.0, -1.0, 0.4);
  cal.ResetPose(m.t_ns, elsewhere, m.R);
  EXPECT_EQ(cal.time_ns(), m.t_ns);
  EXPECT_LT((cal.state().head<3>() - elsewhere).norm(), 1e-12);
  EXPECT_LT((cal.params() - params).norm(), 1e-12);
  EXPECT_LT((cal.params_covariance() - C).norm(), 1e-12 * C.norm());
}

TEST(OnlineCalibrator, PredictionMovesTheTimeAndGrowsThePoseUncertainty) {
  const SimulatedUnicycle run;
  OnlineCalibrator cal = run.Start();
  const double var0 = cal.covariance()(0, 0);
  const TimeNs t1 = run.data.meas.front().t_ns + SecondsToNs(1.0);
  cal.PredictTo(t1);
  EXPECT_EQ(cal.time_ns(), t1);
  EXPECT_GT(cal.covariance()(0, 0), var0);
  // Extra pose noise: the same prediction from the same start spreads further.
  OnlineCalibrator noisy = run.Start();
  noisy.set_extra_pose_psd(Eigen::Vector3d(1e-3, 1e-3, 1e-3));
  noisy.PredictTo(t1);
  EXPECT_GT(noisy.covariance()(0, 0), cal.covariance()(0, 0) + 0.5e-3);
}

TEST(OnlineCalibrator, BadOptionsAreNamed) {
  const System sys = MakeSystem("unicycle").value();
  OnlineCalibratorOptions o;
  o.filter = "kalman9";
  std::string error;
  EXPECT_FALSE(o.IsValid(sys, &error));
  EXPECT_NE(error.find("kalman9"), std::string::npos) << error;
  EXPECT_THROW(OnlineCalibrator(sys, o, 0), std::invalid_argument);
  o.filter = "dd2";
  o.noise.control_psd = {1e-4};  // the unicycle has two controls
  EXPECT_FALSE(o.IsValid(sys, &error));
  EXPECT_NE(error.find("2 controls"), std::string::npos) << error;
  o.noise.control_psd = {1e-4, -1.0};
  EXPECT_FALSE(o.IsValid(sys, &error));
  o.noise.control_psd = {};
  o.noise.pose_psd = Eigen::Vector3d(0, std::nan(""), 0);
  EXPECT_FALSE(o.IsValid(sys, &error));
  EXPECT_NE(error.find("pose_psd"), std::string::npos) << error;
}

}  // namespace
}  // namespace kincal
