// Kinematic models and effects: derivatives against finite differences, exact
// integration against fine Euler, and the sign and timing conventions.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "kincal/estimation/online_calibrator.h"
#include "kincal/model.h"
#include "kincal/system.h"
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
    if (MakeModel(sc.model)->has_steering()) effects.push_back("backlash");
  }
  const System sys = MakeSystem(sc.model, effects);
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

TEST_P(BareModelTest, ExactIntegrationMatchesFineEuler) {
  const auto sc = AllModelScenarios()[static_cast<size_t>(GetParam())];
  const System sys = MakeSystem(sc.model);
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
                         ::testing::Combine(::testing::Range(0, 4), ::testing::Range(0, 3)),
                         ModelTestName);
INSTANTIATE_TEST_SUITE_P(AllModels, BareModelTest, ::testing::Range(0, 4),
                         [](const ::testing::TestParamInfo<int>& info) {
                           return AllModelScenarios()[static_cast<size_t>(info.param)].model;
                         });

Twist<double> TwistOf(const char* model, std::vector<double> p, std::vector<double> u) {
  return MakeModel(model)->BodyTwist(p.data(), u.data());
}

TEST(Conventions, PositiveSteeringAndFasterRightWheelTurnLeft) {
  EXPECT_GT(TwistOf("diffdrive", {0.03, 0.03, 0.15}, {10.0, 12.0}).omega, 0.0);
  EXPECT_NEAR(TwistOf("diffdrive", {0.03, 0.03, 0.15}, {10.0, 12.0}).omega, 0.03 * 2.0 / 0.15,
              1e-12);
  EXPECT_GT(TwistOf("ackermann", {0.05, 0.3, 0.0}, {10.0, 0.2}).omega, 0.0);
  EXPECT_GT(TwistOf("tricycle", {0.001, 0.0, 1e-4, 0.5}, {200.0, 5000.0}).omega, 0.0);
  // Ackermann with a driven rear wheel: forward speed is R_B * omega, no cos(phi).
  EXPECT_NEAR(TwistOf("ackermann", {0.05, 0.3, 0.0}, {10.0, 0.4}).vx, 0.5, 1e-12);
  // Tricycle: the front wheel drives, the rear-axle midpoint moves at v_f cos(phi).
  EXPECT_NEAR(TwistOf("tricycle", {0.001, 0.0, 1e-4, 0.5}, {400.0, 5000.0}).vx, 0.5 * std::cos(0.4),
              1e-12);
}

TEST(Effects, TimeOffsetDelaysTheMotion) {
  const System sys = MakeSystem("unicycle", {"time_offset"});
  ControlSignal u(2, 0);
  const std::array<double, 2> go = {1.0, 0.0};
  u.Append(SecondsToNs(1.0), go);
  VecN<kMaxState> p(3);
  p << 0.8, 1.0, 0.2;  // k_v, k_omega, delay_s
  StateVec x = sys.MakeState(0, 0, 0, p, u, 0.0);
  StateVec out(x.size());
  sys.Propagate(x.data(), out.data(), 0.0, 1.15, u, static_cast<const double*>(nullptr));
  EXPECT_EQ(out[0], 0.0);
  sys.Propagate(x.data(), out.data(), 0.0, 1.5, u, static_cast<const double*>(nullptr));
  EXPECT_NEAR(out[0], 0.8 * 0.3, 1e-12);
}

TEST(Effects, ActuatorLagFollowsFirstOrderResponseExactly) {
  const System sys = MakeSystem("unicycle", {"actuator_lag[v]"});
  ControlSignal u(2, 0);
  const std::array<double, 2> go = {1.0, 0.0};
  u.Append(SecondsToNs(1.0), go);
  VecN<kMaxState> p(3);
  const double tau = 0.25, kv = 0.9;
  p << kv, 1.0, tau;
  StateVec x = sys.MakeState(0, 0, 0, p, u, 0.0);
  EXPECT_EQ(x[6], 0.0);  // lag state at rest before the command
  for (double t : {1.1, 1.25, 2.0}) {
    StateVec out(x.size());
    sys.Propagate(x.data(), out.data(), 0.0, t, u, static_cast<const double*>(nullptr));
    const double s = t - 1.0;
    EXPECT_NEAR(out[0], kv * (s - tau * (1.0 - std::exp(-s / tau))), 1e-12) << t;
    EXPECT_NEAR(out[6], 1.0 - std::exp(-s / tau), 1e-12) << t;
  }
}

TEST(Effects, LeverArmMovesTheMeasuredPoint) {
  const System sys = MakeSystem("unicycle", {"lever_arm"});
  StateVec x(sys.state_dim());
  x << 1.0, 2.0, M_PI / 2, 1.0, 1.0, 0.1, 0.02, 0.05;
  double z[3];
  sys.Measure(x.data(), z);
  EXPECT_NEAR(z[0], 1.0 - 0.02, 1e-12);
  EXPECT_NEAR(z[1], 2.0 + 0.1, 1e-12);
  EXPECT_NEAR(z[2], M_PI / 2 + 0.05, 1e-12);
  StateVec back = x;
  back.head(3).setZero();
  sys.SetPoseFromMeasurement(z, back.data());
  EXPECT_NEAR((back - x).norm(), 0.0, 1e-12);
}

TEST(Effects, BadSpecsGetClearErrors) {
  EXPECT_THROW(
      {
        try {
          MakeSystem("unicycle", {"actuator_lag[wheel]"});
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find("has no control 'wheel'"), std::string::npos);
          throw;
        }
      },
      std::invalid_argument);
  EXPECT_THROW(MakeSystem("unicycle", {"warp_drive"}), std::invalid_argument);
  EXPECT_THROW(MakeSystem("hovercraft"), std::invalid_argument);
  EXPECT_THROW(MakeSystem("unicycle", {"lever_arm", "lever_arm"}), std::invalid_argument);
}

}  // namespace
}  // namespace kincal
