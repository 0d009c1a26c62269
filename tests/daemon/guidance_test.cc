// kincald's guidance: the worker advises on an estimate (the least determined parameter,
// a motion, the time to the targets) off the filter thread, at most every every_s of data
// time, survives an estimate it cannot use; the config section is checked against the
// robot; a simulated run publishes KINCAL_GUIDANCE into its log, and the advice gets
// easier as the estimate converges.
#include "daemon/guidance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <mutex>

#include "daemon/daemon_test_util.h"
#include "kincal/daemon/daemon.h"

namespace kincal::daemon {
namespace {

GuidanceOptions GuidanceTestOptions() {
  GuidanceOptions g;
  g.enabled = true;
  g.every_s = 2.0;
  g.limits = {{"omega_l", 20.0}, {"omega_r", 20.0}, {"accel", 40.0}};
  g.targets = {{"r_l", 3e-5}, {"r_r", 3e-5}, {"d", 3e-4}, {"tau_s", 3e-3}};
  return g;
}

Checkpoint GuidanceEstimate(int64_t utime, double tau_sigma) {
  Checkpoint c;
  c.model = "diffdrive";
  c.effects = {"actuator_lag"};
  c.utime = utime;
  c.names = {"r_l", "r_r", "d", "tau_s"};
  c.values = {0.03, 0.03, 0.3, 0.1};
  c.covariance = Eigen::Vector4d(1e-12, 1e-12, 1e-10, tau_sigma * tau_sigma).asDiagonal();
  return c;
}

TEST(Guidance, AdvisesOnTheLeastDeterminedParameterAtMostEveryPeriod) {
  std::mutex mu;
  std::vector<kincal::guidance_t> got;
  Guidance g(GuidanceTestOptions(), [&](int64_t, const kincal::guidance_t& m) {
    std::lock_guard lock(mu);
    got.push_back(m);
  });
  g.Offer(GuidanceEstimate(1'000'000, 0.05));
  g.Drain();
  g.Offer(GuidanceEstimate(2'000'000, 0.05));  // 1 s later: not yet
  g.Drain();
  g.Offer(GuidanceEstimate(3'500'000, 0.05));  // 2.5 s after the first
  g.Drain();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(g.advised(), 2);
  const kincal::guidance_t& m = got[0];
  EXPECT_EQ(m.model, "diffdrive+actuator_lag");
  EXPECT_EQ(m.parameter, "tau_s");
  EXPECT_NEAR(m.sigma, 0.05, 1e-12);
  EXPECT_NEAR(m.target, 3e-3, 1e-12);
  EXPECT_LT(m.sigma_after, 0.2 * m.sigma);
  EXPECT_FALSE(m.motion.empty());
  EXPECT_EQ(m.num_controls, 2);
  EXPECT_EQ(m.control_names[0], "omega_l");
  EXPECT_GT(m.time_to_target_s, 0.0);
  EXPECT_LT(m.time_to_target_s, 60.0);
  EXPECT_EQ(m.num_params, 4);
  EXPECT_EQ(m.utime, 1'000'000);
  // The path the motion drives, from the target where it stands, every 0.1 s.
  EXPECT_EQ(m.num_path, static_cast<int>(std::lround(GuidanceTestOptions().horizon_s / 0.1)) + 1);
  ASSERT_EQ(m.path_x.size(), static_cast<size_t>(m.num_path));
  EXPECT_EQ(m.path_x[0], 0.0);
  EXPECT_EQ(m.path_y[0], 0.0);
  // Here a turn in place: the target (no lever arm) stays where it is.
  ASSERT_NE(m.motion.find("turn in place"), std::string::npos) << m.motion;
  for (int k = 0; k < m.num_path; ++k) {
    EXPECT_LT(std::hypot(m.path_x[static_cast<size_t>(k)], m.path_y[static_cast<size_t>(k)]), 1e-9);
  }
  std::cout << "advice: " << m.parameter << " " << m.sigma << " -> " << m.sigma_after << ": "
            << m.motion << "; " << m.time_to_target_s << " s to the targets\n";
}

TEST(Guidance, AnEstimateItCannotUseIsAnErrorNotACrash) {
  int published = 0;
  Guidance g(GuidanceTestOptions(), [&](int64_t, const kincal::guidance_t&) { ++published; });
  Checkpoint bad = GuidanceEstimate(1'000'000, 0.05);
  bad.values.pop_back();
  g.Offer(bad);
  g.Drain();
  EXPECT_EQ(published, 0);
  EXPECT_NE(g.last_error().find("does not match"), std::string::npos) << g.last_error();
}

TEST(GuidanceConfig, LimitsAndTargetsMustNameTheRobots) {
  DaemonConfig c = test_util::SimConfig(5);
  c.guidance = GuidanceTestOptions();
  c.guidance.targets = {{"r_l", 3e-5}};
  std::string error;
  EXPECT_TRUE(c.IsValid(&error)) << error;
  c.guidance.limits.erase("omega_r");
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_NE(error.find("guidance.limits: omega_r=.. missing"), std::string::npos) << error;
  c.guidance = GuidanceTestOptions();
  c.guidance.targets = {{"wheelbase", 1e-3}};
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_NE(error.find("guidance.targets: 'wheelbase'"), std::string::npos) << error;
  c.guidance = GuidanceTestOptions();
  c.guidance.horizon_s = 0;
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_NE(error.find("guidance.horizon_s"), std::string::npos) << error;
}

// The shipped simulated robot with guidance on: advice lands in the log every few seconds
// of data, and the time it predicts to the targets falls as the estimate converges.
TEST(GuidanceDaemon, ASimulatedRunPublishesAdviceThatGetsEasier) {
  DaemonConfig c = test_util::SimConfig(30);
  c.guidance = GuidanceTestOptions();
  c.guidance.every_s = 5.0;
  c.guidance.targets = {{"r_l", 3e-5}, {"r_r", 3e-5}, {"d", 3e-4}};
  c.guidance.limits = {{"omega_l", 25.0}, {"omega_r", 25.0}, {"accel", 50.0}};
  c.record.path = test_util::TempPath("guidance.lcm");
  const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
  Daemon& d = *d_owner;
  ASSERT_EQ(d.Run(), 0);
  lcm::LogFile log(c.record.path, "r");
  std::vector<kincal::guidance_t> advice;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel != c.lcm.guidance_channel) continue;
    kincal::guidance_t m;
    ASSERT_GT(m.decode(ev->data, 0, ev->datalen), 0);
    advice.push_back(m);
  }
  ASSERT_GE(advice.size(), 2u);
  for (const auto& m : advice) {
    std::cout << m.utime / 1e6 << " s: " << m.parameter << " sigma " << m.sigma << ", " << m.motion
              << ", " << m.time_to_target_s << " s to go\n";
    EXPECT_EQ(m.num_params, 3);
  }
  EXPECT_LT(advice.back().sigma, advice.front().sigma);
  EXPECT_LE(advice.back().time_to_target_s, advice.front().time_to_target_s);
}

}  // namespace
}  // namespace kincal::daemon
