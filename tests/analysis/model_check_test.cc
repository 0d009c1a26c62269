// The online diagnosis: a simulated robot with a hidden 0.1 s delay yields a time_offset
// verdict; a clean one yields none.
#include "kincal/analysis/model_check.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <kincal/model_check_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <random>

#include "kincal/estimation/online_calibrator.h"
#include "kincal/online/estimate_messages.h"
#include "kincal/sim/simulator.h"

namespace kincal {
namespace {

// A unicycle with one hidden effect (its parameter at `value`), filtered with the bare model
// for 60 s at 30 Hz; the check sees every innovation.
ModelCheckVerdict RunOnline(const std::string& hidden, const std::string& param, double value,
                            uint64_t seed) {
  const System truth = MakeSystem("unicycle", {hidden}).value();
  const System model = MakeSystem("unicycle").value();
  std::mt19937_64 rng(seed);
  ControlSignal u(2, 0);
  const std::vector<double> lo = {-0.2, -1.0}, hi = {0.8, 1.0};
  AppendPiecewiseRandom(&u, 0, SecondsToNs(60.0), lo, hi, 0.7, 2.0, rng);
  FrameTimingOptions cam{30.0, 0.0, 0.0, 0.0};
  const auto times = FrameTimes(0, SecondsToNs(60.0), cam, rng);
  VecN<kMaxState> p = VecN<kMaxState>::Zero(truth.num_params());
  p[0] = 0.9;
  p[1] = 0.95;
  p[truth.ParamIndex(param)] = value;
  const auto traj = SimulateTruth(truth, truth.MakeState(0, 0, 0, p, u, 0), u, times);
  const Eigen::Matrix3d R = Eigen::Vector3d(1e-6, 1e-6, 1e-5).asDiagonal();
  const auto meas = MeasurePoses(traj, R, 0, rng);
  OnlineCalibratorOptions opt;
  opt.noise.pose_psd = Eigen::Vector3d(1e-6, 1e-6, 1e-5);
  OnlineCalibrator cal(model, opt, 0);
  cal.controls() = u;
  VecN<kMaxState> guess(2);
  guess << 1.0, 1.0;
  cal.Initialize(meas[0].t_ns, meas[0].z, R, guess, StateMat::Identity(2, 2) * 0.04);
  ModelCheck check(model);
  for (size_t k = 1; k < meas.size(); ++k) {
    const UpdateResult r = cal.AddPose(meas[k].t_ns, meas[k].z, R);
    check.Add(meas[k].t_ns, r, cal.state(), cal.controls());
  }
  return check.Verdict();
}

ModelCheckVerdict RunOnline(double hidden_delay_s, uint64_t seed) {
  return RunOnline("time_offset", "delay_s", hidden_delay_s, seed);
}

TEST(ModelCheck, HiddenDelayIsNamed) {
  const ModelCheckVerdict v = RunOnline(0.1, 3);
  EXPECT_FALSE(v.consistent) << v.evidence;
  EXPECT_EQ(v.suspected_effect, "time_offset") << v.evidence;
  EXPECT_GT(v.confidence, 0.5);
}

// Every effect whose signature is defined is among the candidates the check names when it
// is hidden: the check reads the registered signatures, so this covers their vocabulary.
struct HiddenCase {
  const char* spec;
  const char* param;
  double value;
};

class ModelCheckNames : public ::testing::TestWithParam<HiddenCase> {};

TEST_P(ModelCheckNames, HiddenEffectIsACandidate) {
  const HiddenCase c = GetParam();
  const ModelCheckVerdict v = RunOnline(c.spec, c.param, c.value, 3);
  EXPECT_FALSE(v.consistent) << v.evidence;
  const std::string name = std::string(c.spec).substr(0, std::string(c.spec).find('['));
  EXPECT_NE(std::find(v.candidates.begin(), v.candidates.end(), name), v.candidates.end())
      << name << " not among the candidates: " << v.evidence;
  // A delay and a lag share their signature terms: the check names both (the effect
  // search tells them apart); every other effect is the first suspect by its own term.
  if (name != "actuator_lag") {
    EXPECT_EQ(v.suspected_effect, name) << v.evidence;
  }
}

INSTANTIATE_TEST_SUITE_P(EverySignature, ModelCheckNames,
                         ::testing::Values(HiddenCase{"time_offset", "delay_s", 0.1},
                                           HiddenCase{"actuator_lag", "tau_s", 0.15},
                                           HiddenCase{"turn_slowdown", "c_slow", 0.5},
                                           HiddenCase{"lever_arm", "dx", 0.05},
                                           HiddenCase{"yaw_rate_bias", "bias_rad_s", 0.05},
                                           HiddenCase{"asymmetric_gain[v]", "asym_v", 0.15},
                                           HiddenCase{"lateral_slip", "c_slip", 0.05},
                                           HiddenCase{"effective_track", "c_track", 0.3}),
                         [](const ::testing::TestParamInfo<HiddenCase>& info) {
                           std::string n = info.param.spec;
                           return n.substr(0, n.find('['));
                         });

TEST(ModelCheck, VerdictTravelsAsAnLcmMessage) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  struct Sink {
    std::vector<model_check_t> got;
    void On(const lcm::ReceiveBuffer*, const std::string&, const model_check_t* m) {
      got.push_back(*m);
    }
  } sink;
  lcm.subscribe("KINCAL_MODEL_CHECK", &Sink::On, &sink);
  const model_check_t msg = ModelCheckMessage(RunOnline(0.1, 3), "unicycle", 123);
  ASSERT_EQ(lcm.publish("KINCAL_MODEL_CHECK", &msg), 0);
  ASSERT_GE(lcm.handleTimeout(100), 0);
  ASSERT_EQ(sink.got.size(), 1u);
  EXPECT_EQ(sink.got[0].suspected_effect, "time_offset");
  EXPECT_EQ(sink.got[0].consistent, 0);
  EXPECT_EQ(sink.got[0].model, "unicycle");
}

TEST(ModelCheck, CleanRobotYieldsNoVerdict) {
  for (uint64_t seed : {3, 4, 5}) {
    const ModelCheckVerdict v = RunOnline(0.0, seed);
    EXPECT_TRUE(v.suspected_effect.empty()) << v.suspected_effect << ": " << v.evidence;
    EXPECT_TRUE(v.consistent) << v.evidence;
    // Said in words, not a bare "; window ..." (seen on kincal view's page).
    EXPECT_EQ(v.evidence, "no signature, innovations as expected; window " +
                              std::to_string(ModelCheck::kWindow) + " innovations");
  }
}

}  // namespace
}  // namespace kincal
