// The online diagnosis: a simulated robot with a hidden 0.1 s delay yields a time_offset
// verdict; a clean one yields none.
#include "kincal/analysis/model_check.h"

#include <gtest/gtest.h>

#include <kincal/model_check_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <random>

#include "daemon/messages.h"
#include "kincal/estimation/online_calibrator.h"
#include "kincal/simulator.h"

namespace kincal {
namespace {

ModelCheckVerdict RunOnline(double hidden_delay_s, uint64_t seed) {
  const System truth = MakeSystem("unicycle", {"time_offset"});
  const System model = MakeSystem("unicycle");
  std::mt19937_64 rng(seed);
  ControlSignal u(2, 0);
  const std::vector<double> lo = {-0.2, -1.0}, hi = {0.8, 1.0};
  AppendPiecewiseRandom(&u, 0, SecondsToNs(60.0), lo, hi, 0.7, 2.0, rng);
  FrameTimingOptions cam{30.0, 0.0, 0.0, 0.0};
  const auto times = FrameTimes(0, SecondsToNs(60.0), cam, rng);
  VecN<kMaxState> p(3);
  p << 0.9, 0.95, hidden_delay_s;
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

TEST(ModelCheck, HiddenDelayIsNamed) {
  const ModelCheckVerdict v = RunOnline(0.1, 3);
  EXPECT_FALSE(v.consistent) << v.evidence;
  EXPECT_EQ(v.suspected_effect, "time_offset") << v.evidence;
  EXPECT_GT(v.confidence, 0.5);
}

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
  const model_check_t msg = daemon::ModelCheckMessage(RunOnline(0.1, 3), "unicycle", 123);
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
  }
}

}  // namespace
}  // namespace kincal
