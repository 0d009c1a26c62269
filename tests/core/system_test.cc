// System (a model with its effects): autodiff derivatives of the propagation and the
// measurement against finite differences for every registered model with every effect,
// and the exact arc integration against fine Euler.
#include "kincal/system.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "kincal/estimation/online_calibrator.h"
#include "kincal/model.h"
#include "test_util.h"

namespace kincal {
namespace {

using testing::AllModelScenarios;

ControlSignal RandomControls(int nc, std::span<const double> lo, std::span<const double> hi,
                             uint64_t seed) {
  std::mt19937_64 rng(seed);
  ControlSignal u(nc, 0);
  AppendSmoothRandom(&u, 0, SecondsToNs(3.0), lo, hi, 0.5, 50.0, rng);
  return u;
}

// Full state for a system: truth params of the model, small non-zero effect params.
StateVec TestState(const System& sys, const std::vector<double>& model_params,
                   const ControlSignal& u) {
  VecN<kMaxState> p(sys.num_params());
  for (int i = 0; i < sys.num_params(); ++i) {
    p[i] = i < static_cast<int>(model_params.size()) ? model_params[static_cast<size_t>(i)] : 0.0;
  }
  auto set = [&](const char* name, double v) {
    const int i = sys.ParamIndex(name);
    if (i >= 0) p[i] = v;
  };
  set("delay_s", 0.05);
  set("tau_s", 0.08);
  set("dx", 0.05);
  set("dy", -0.02);
  set("dtheta", 0.03);
  set("c_slip", 0.01);
  set("bias_rad_s", 0.02);
  set("c_track", 0.05);
  set("backlash", 0.01);
  for (const auto& c : sys.model().controls()) {
    set(("asym_" + c.name).c_str(), 0.04);
    set(("band_" + c.name).c_str(), 0.001);
  }
  return sys.MakeState(0.3, -0.1, 0.4, p, u, 1.003);
}

class ModelTest : public ::testing::TestWithParam<std::tuple<int, int>> {};

TEST_P(ModelTest, AutodiffJacobiansMatchFiniteDifferences) {
  const auto sc = AllModelScenarios()[static_cast<size_t>(std::get<0>(GetParam()))];
  std::vector<std::string> effects;
  if (std::get<1>(GetParam()) == 1) {
    effects = {"time_offset", "actuator_lag", "lever_arm", "lateral_slip", "yaw_rate_bias"};
  } else if (std::get<1>(GetParam()) == 2) {
    effects = {"asymmetric_gain", "dead_band", "effective_track"};
    if (MakeModel(sc.model).value()->has_steering()) effects.push_back("backlash");
  }
  const System sys = MakeSystem(sc.model, effects).value();
  const ControlSignal u = RandomControls(sys.num_controls(), sc.lo, sc.hi, 3);
  const StateVec x = TestState(sys, sc.truth, u);
  // Interval chosen away from the (delay-shifted) 20 ms control breakpoints.
  SystemProcess f(sys, u, 1.003, 1.707);
  StateMat F_ad, F_fd;
  StateNoiseMat G_ad, G_fd;
  f.Jacobians(x, &F_ad, &G_ad);
  f.ProcessFunction::Jacobians(x, &F_fd, &G_fd);
  for (int i = 0; i < sys.state_dim(); ++i) {
    for (int j = 0; j < sys.state_dim(); ++j) {
      EXPECT_NEAR(F_ad(i, j), F_fd(i, j), 2e-5 * std::max(1.0, std::abs(F_fd(i, j))))
          << sc.model << " dF(" << sys.StateName(i) << ")/d(" << sys.StateName(j) << ")";
    }
    for (int j = 0; j < sys.noise_dim(); ++j) {
      EXPECT_NEAR(G_ad(i, j), G_fd(i, j), 2e-5 * std::max(1.0, std::abs(G_fd(i, j))))
          << sc.model << " dF(" << sys.StateName(i) << ")/dv" << j;
    }
  }
  SystemPoseMeasurement h(sys);
  MeasStateMat H_ad, H_fd;
  h.Jacobian(x, &H_ad);
  h.MeasurementFunction::Jacobian(x, &H_fd);
  EXPECT_LT((H_ad - H_fd).cwiseAbs().maxCoeff(), 1e-7) << sc.model;
}

class BareModelTest : public ::testing::TestWithParam<int> {};
// The state-only walk (warm-ups) moves the effect states as Propagate does, in one step per
// command interval instead of 5 ms sub-steps, and leaves the pose where it was.
TEST_P(BareModelTest, EffectStatesAloneFollowPropagate) {
  const auto sc = AllModelScenarios()[static_cast<size_t>(GetParam())];
  std::vector<std::string> effects = {"time_offset", "actuator_lag"};
  if (MakeModel(sc.model).value()->has_steering()) effects.push_back("backlash");
  const System sys = MakeSystem(sc.model, effects).value();
  ASSERT_GT(sys.num_states(), 0);
  const ControlSignal u = RandomControls(sys.num_controls(), sc.lo, sc.hi, 7);
  const StateVec x0 = TestState(sys, sc.truth, u);
  StateVec full(x0.size()), alone = x0;
  sys.Propagate(x0.data(), full.data(), 0.31, 2.77, u, static_cast<const double*>(nullptr));
  sys.AdvanceEffectStates(alone.data(), 0.31, 2.77, u);
  const int off = sys.state_offset();
  double moved = 0.0;
  for (int i = off; i < sys.state_dim(); ++i) {
    EXPECT_NEAR(alone[i], full[i], 1e-12 * std::max(1.0, std::abs(full[i])))
        << sc.model << " " << sys.StateName(i);
    moved = std::max(moved, std::abs(full[i] - x0[i]));
  }
  EXPECT_GT(moved, 1e-3) << "the controls should move the states";
  for (int i = 0; i < off; ++i) EXPECT_EQ(alone[i], x0[i]) << sys.StateName(i);
}

TEST_P(BareModelTest, ExactIntegrationMatchesFineEuler) {
  const auto sc = AllModelScenarios()[static_cast<size_t>(GetParam())];
  const System sys = MakeSystem(sc.model).value();
  const ControlSignal u = RandomControls(sys.num_controls(), sc.lo, sc.hi, 5);
  StateVec x = TestState(sys, sc.truth, u);
  StateVec exact(x.size());
  sys.Propagate(x.data(), exact.data(), 0.5, 2.5, u, static_cast<const double*>(nullptr));
  // Forward Euler, 1e-5 s steps, directly from the model's body twist.
  double px = x[0], py = x[1], th = x[2];
  const double dt = 1e-5;
  for (double t = 0.5; t < 2.5 - 0.5 * dt; t += dt) {
    const auto& c = u.At(t);
    const Twist<double> tw = sys.model().BodyTwist(x.data() + 3, c.data());
    px += (std::cos(th) * tw.vx - std::sin(th) * tw.vy) * dt;
    py += (std::sin(th) * tw.vx + std::cos(th) * tw.vy) * dt;
    th += tw.omega * dt;
  }
  EXPECT_NEAR(exact[0], px, 2e-4) << sc.model;
  EXPECT_NEAR(exact[1], py, 2e-4) << sc.model;
  EXPECT_NEAR(exact[2], th, 2e-4) << sc.model;
}

std::string ModelTestName(const ::testing::TestParamInfo<std::tuple<int, int>>& info) {
  static const char* kSets[] = {"", "_timing_lag_lever_slip_bias", "_asym_deadband_track_backlash"};
  return AllModelScenarios()[static_cast<size_t>(std::get<0>(info.param))].model +
         std::string(kSets[std::get<1>(info.param)]);
}

INSTANTIATE_TEST_SUITE_P(AllModels, ModelTest,
                         ::testing::Combine(::testing::Range(0, 5), ::testing::Range(0, 3)),
                         ModelTestName);
INSTANTIATE_TEST_SUITE_P(AllModels, BareModelTest, ::testing::Range(0, 5),
                         [](const ::testing::TestParamInfo<int>& info) {
                           return AllModelScenarios()[static_cast<size_t>(info.param)].model;
                         });

TEST(Model, ParamNamesListsTheParametersForMessages) {
  EXPECT_EQ(ParamNames(MakeModel("bicycle").value()->params()),
            "k_v, k_steer, steer_offset, wheelbase");
  EXPECT_EQ(ParamNames({}), "");
}

TEST(ModelRegistry, AnUnknownNameIsAnErrorNamingTheKnownModels) {
  const auto made = MakeModel("hovercraft");
  ASSERT_FALSE(made.ok());
  EXPECT_NE(made.status().message().find("diffdrive"), std::string::npos)
      << made.status().message();
  EXPECT_EQ(MakeModel("bicycle").value()->name(), "bicycle");
}

}  // namespace
}  // namespace kincal
