// guidance.drive: the link plans a leg from the first estimate made while the robot rested,
// from where the robot stands, keeping the target in view, and says why when it cannot;
// closed loop, kincald's simulated robot driving by the guidance reaches the targets in a
// fraction of the data time its random driving needs, never loses the target, is the same
// on every run, and its log replays to the same estimate.
#include "daemon/drive_link.h"

#include <gtest/gtest.h>

#include <cmath>
#include <kincal/model_check_t.hpp>
#include <kincal/params_t.hpp>
#include <limits>

#include "daemon/daemon_test_util.h"
#include "kincal/daemon/daemon.h"
#include "kincal/io/lcm_log_reader.h"
#include "kincal/system.h"

namespace kincal::daemon {
namespace {

using namespace std::chrono_literals;

GuidanceOptions DriveOptions() {
  GuidanceOptions g;
  g.enabled = true;
  g.drive = true;
  g.horizon_s = 2.0;
  g.limits = {{"omega_l", 20.0}, {"omega_r", 20.0}, {"accel", 40.0}};
  g.targets = {{"r_l", 3e-5}, {"r_r", 3e-5}, {"d", 1.5e-4}};
  return g;
}

Checkpoint DriveEstimate(int64_t utime) {
  Checkpoint c;
  c.model = "diffdrive";
  c.utime = utime;
  c.names = {"r_l", "r_r", "d"};
  c.values = {0.031, 0.031, 0.15};
  c.covariance = Eigen::Vector3d(1e-8, 1e-8, 1e-6).asDiagonal();
  return c;
}

std::unique_ptr<Workspace> Floor() { return MakeArena(-1.0, -1.0, 1.0, 1.0); }

TEST(DriveLink, PlansTheLegFromTheFirstEstimateMadeAtRest) {
  DriveLink link(DriveOptions(), Floor());
  Checkpoint wrong = DriveEstimate(0);
  wrong.values.pop_back();         // would fail the plan if it were the one used
  link.Offer(DriveEstimate(500));  // before any leg is expected: ignored
  link.Expect(1'000);
  wrong.utime = 900;
  link.Offer(wrong);  // before the rest began
  link.Offer(DriveEstimate(1'000));
  wrong.utime = 1'100;
  link.Offer(wrong);  // after the one kept
  ControlSignal leg;
  const Status s = link.NextLeg(Eigen::Vector3d(0.2, -0.1, 0.5), 50.0, 1s, &leg);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(link.legs(), 1);
  EXPECT_EQ(link.legs_failed(), 0);
  // Horizon, then a stop at 40 rad/s^2 from at most 20 rad/s, then a sample at rest.
  ASSERT_GT(leg.size(), 2u);
  EXPECT_NEAR(leg.TimeAt(0), 0.0, 1e-12);
  const double end = leg.TimeAt(static_cast<int>(leg.size()) - 1);
  EXPECT_GE(end, 2.0);
  EXPECT_LE(end, 2.0 + 0.5 + 0.02 + 1e-9);
  const auto& last = leg.ValuesAt(static_cast<int>(leg.size()) - 1);
  EXPECT_EQ(last[0], 0.0);
  EXPECT_EQ(last[1], 0.0);
  for (int i = 1; i < static_cast<int>(leg.size()); ++i) {
    for (int c = 0; c < 2; ++c) {
      const double rate = std::abs(leg.ValuesAt(i)[static_cast<size_t>(c)] -
                                   leg.ValuesAt(i - 1)[static_cast<size_t>(c)]) /
                          (leg.TimeAt(i) - leg.TimeAt(i - 1));
      EXPECT_LE(rate, 40.0 + 1e-6) << "at " << leg.TimeAt(i) << " s";
    }
  }
}

// From a pose near the edge, heading out: the leg keeps the target inside.
TEST(DriveLink, TheLegKeepsTheTargetInViewFromWhereTheRobotStands) {
  DriveLink link(DriveOptions(), Floor());
  link.Expect(1'000);
  link.Offer(DriveEstimate(1'000));
  const Eigen::Vector3d pose(0.75, 0.0, 0.0);  // 25 cm from the edge, heading at it
  ControlSignal leg;
  ASSERT_TRUE(link.NextLeg(pose, 50.0, 1s, &leg).ok());
  const System sys = MakeSystem("diffdrive", {}).value();
  const Checkpoint e = DriveEstimate(0);
  StateVec x = sys.MakeState(pose.x(), pose.y(), pose.z(),
                             Eigen::Map<const Eigen::VectorXd>(e.values.data(), 3), leg, 0.0);
  const auto arena = Floor();
  double moved = 0.0;
  for (double t = 0.0; t < leg.TimeAt(static_cast<int>(leg.size()) - 1) + 1.0; t += 0.02) {
    sys.Propagate(x.data(), x.data(), t, t + 0.02, leg, static_cast<const double*>(nullptr));
    Eigen::Vector3d z;
    sys.Measure(x.data(), z.data());
    ASSERT_TRUE(arena->Contains(z)) << "left at " << t << " s: " << z.transpose();
    moved = std::max(moved, (z.head<2>() - pose.head<2>()).norm());
  }
  EXPECT_GT(moved, 0.05);  // it does drive
}

TEST(DriveLink, NoEstimateIsAnErrorAfterTheWaitAndCancelWakesAWait) {
  DriveLink link(DriveOptions(), Floor());
  link.Expect(1'000);
  link.Offer(DriveEstimate(999));
  ControlSignal leg;
  Status s = link.NextLeg(Eigen::Vector3d::Zero(), 50.0, 50ms, &leg);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("no estimate came while the robot rested"), std::string::npos)
      << s.message();
  std::thread canceller([&] {
    std::this_thread::sleep_for(50ms);
    link.Cancel();
  });
  s = link.NextLeg(Eigen::Vector3d::Zero(), 50.0, 60s, &leg);  // would wait a minute
  canceller.join();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("stopped"), std::string::npos) << s.message();
  EXPECT_EQ(link.legs_failed(), 2);
}

TEST(DriveConfig, DriveNeedsGuidanceTheSimulatorAndAnEstimateWhileResting) {
  DaemonConfig c = test_util::SimConfig(5);
  c.guidance = DriveOptions();
  std::string error;
  EXPECT_TRUE(c.IsValid(&error)) << error;
  c.source = SourceKind::kReplay;
  c.replay.path = "run.lcm";
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_NE(error.find("guidance.drive needs source: sim"), std::string::npos) << error;
  c = test_util::SimConfig(5);
  c.guidance = DriveOptions();
  c.guidance.drive_pause_s = 0.1;  // params_t at 10 Hz: one period
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_NE(error.find("guidance.drive_pause_s must be at least two"), std::string::npos) << error;
  c.guidance = DriveOptions();
  c.guidance.enabled = false;
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_NE(error.find("guidance.drive needs guidance.enabled"), std::string::npos) << error;
}

// Data time of the first params_t whose sigmas all meet the targets (+inf: never).
double TimeToTargets(const std::string& log_path, const DaemonConfig& c) {
  const std::unique_ptr<LcmLogReader> log = test_util::OpenLog(log_path);
  if (!log) return std::numeric_limits<double>::infinity();
  LcmLogEvent ev;
  int64_t first_utime = -1;
  while (log->Next(&ev)) {
    if (ev.channel != c.lcm.params_channel) continue;
    kincal::params_t m;
    if (m.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())) < 0) continue;
    if (first_utime < 0) first_utime = m.utime;
    bool met = true;
    for (const auto& [name, target] : c.guidance.targets) {
      for (int i = 0; i < m.num_params; ++i) {
        if (m.names[static_cast<size_t>(i)] == name) met = met && m.sigmas[i] <= target;
      }
    }
    if (met) return static_cast<double>(m.utime - first_utime) * 1e-6;
  }
  return std::numeric_limits<double>::infinity();
}

struct DriveRun {
  Checkpoint estimate;
  DaemonCounters counters;
  double time_to_targets_s = 0.0;
};

DriveRun RunDaemon(DaemonConfig c, const std::string& name) {
  c.record.path = test_util::TempPath(name + ".lcm");
  const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
  Daemon& d = *d_owner;
  EXPECT_EQ(d.Run(), 0);
  return {d.Estimate(), d.counters(), TimeToTargets(c.record.path, c)};
}

// The shipped closed loop (config/kincald_sim_drive.yaml): a diffdrive with the actuator
// lag it has declared, poses at 30 Hz from a camera 2 m up, targets 0.1 % and 3 ms.
TEST(DriveDaemon, TheSimulatedRobotFollowsThePlanToTheTargetsAndReplaysTheSame) {
  DaemonConfig c = ReadDaemonConfig(test_util::kConfigDir + "/kincald_sim_drive.yaml").value();
  c.lcm.url = "memq://";
  c.sim.speed = 0;
  c.sim.duration_s = 30;
  const DriveRun driven = RunDaemon(c, "drive");
  DaemonConfig random = c;
  random.guidance.drive = false;
  const DriveRun wandered = RunDaemon(random, "random");
  std::cout << "time to the targets: driven by the guidance " << driven.time_to_targets_s << " s ("
            << driven.counters.drive_legs << " legs), the scenario's random controls "
            << wandered.time_to_targets_s << " s\n";
  for (size_t i = 0; i < driven.estimate.names.size(); ++i) {
    const int k = static_cast<int>(i);
    std::cout << "  " << driven.estimate.names[i] << ": driven " << driven.estimate.values[i]
              << " +- " << std::sqrt(driven.estimate.covariance(k, k)) << ", random "
              << wandered.estimate.values[i] << " +- "
              << std::sqrt(wandered.estimate.covariance(k, k)) << "\n";
  }
  // Every leg planned and driven, the target never out of view (one run, a pose per frame).
  EXPECT_GE(driven.counters.drive_legs, 5);
  EXPECT_EQ(driven.counters.drive_legs_failed, 0);
  EXPECT_EQ(driven.counters.run_resets, 0);
  EXPECT_EQ(driven.counters.poses_invalid, 0);
  EXPECT_EQ(driven.counters.poses_valid, driven.counters.frames_captured);
  test_util::ExpectWithin3Sigma(driven.estimate, test_util::Truth(c));
  ASSERT_TRUE(std::isfinite(driven.time_to_targets_s));
  EXPECT_LT(1.5 * driven.time_to_targets_s, wandered.time_to_targets_s);

  // The same on a second run, and its log replays (drive off: the log has the controls)
  // to the same estimate.
  const DriveRun again = RunDaemon(c, "drive_again");
  EXPECT_EQ(again.estimate.values, driven.estimate.values);
  DaemonConfig replay = c;
  replay.source = SourceKind::kReplay;
  replay.replay.path = test_util::TempPath("drive.lcm");
  replay.replay.speed = 0;
  replay.guidance.drive = false;
  const DriveRun replayed = RunDaemon(replay, "drive_replay");
  ASSERT_EQ(replayed.estimate.values.size(), driven.estimate.values.size());
  for (size_t i = 0; i < driven.estimate.values.size(); ++i) {
    EXPECT_NEAR(replayed.estimate.values[i], driven.estimate.values[i],
                1e-9 * std::abs(driven.estimate.values[i]))
        << driven.estimate.names[i];
  }
}

// Issue 34 item 2: under guidance.drive, a run whose declared lag was estimated correctly
// reported MODEL_INADEQUATE from 2 s to 19 s: the model check's window still held the
// innovations from before the estimate converged. Every params_t whose estimate lies
// within 3 sigma of the truth must not say MODEL_INADEQUATE; and the same robot with its
// lag hidden (not declared) is still named within 30 s.
TEST(DriveDaemon, StatusIsHonestOnceTheEstimateIsRightAndAHiddenLagIsStillNamed) {
  DaemonConfig c = ReadDaemonConfig(test_util::kConfigDir + "/kincald_sim_drive.yaml").value();
  c.lcm.url = "memq://";
  c.sim.speed = 0;
  c.sim.duration_s = 30;
  RunDaemon(c, "honest");
  const std::map<std::string, double> truth = test_util::Truth(c);
  const std::unique_ptr<LcmLogReader> log = test_util::OpenLog(test_util::TempPath("honest.lcm"));
  ASSERT_NE(log, nullptr);
  LcmLogEvent ev;
  int64_t first = -1;
  int right = 0, inadequate_while_right = 0;
  double first_bad_s = -1;
  while (log->Next(&ev)) {
    if (ev.channel != c.lcm.params_channel) continue;
    kincal::params_t m;
    ASSERT_GE(m.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())), 0);
    if (first < 0) first = m.utime;
    bool inside = true;
    for (int i = 0; i < m.num_params; ++i) {
      const auto it = truth.find(m.names[static_cast<size_t>(i)]);
      if (it == truth.end()) continue;
      inside = inside && std::abs(m.values[static_cast<size_t>(i)] - it->second) <=
                             3 * m.sigmas[static_cast<size_t>(i)];
    }
    if (!inside) continue;
    ++right;
    if (m.status == kincal::params_t::STATUS_MODEL_INADEQUATE) {
      if (inadequate_while_right++ == 0) first_bad_s = static_cast<double>(m.utime - first) * 1e-6;
    }
  }
  EXPECT_GT(right, 100);  // the estimate is right for most of the run
  EXPECT_EQ(inadequate_while_right, 0) << "first at " << first_bad_s << " s";

  // The lag hidden: the check names it (or time_offset, which shares its signature).
  DaemonConfig hidden = c;
  hidden.robot.effects.clear();
  hidden.guidance.enabled = false;
  hidden.guidance.drive = false;
  hidden.guidance.targets.erase("tau_s");
  RunDaemon(hidden, "hidden_lag");
  const std::unique_ptr<LcmLogReader> hidden_log =
      test_util::OpenLog(test_util::TempPath("hidden_lag.lcm"));
  ASSERT_NE(hidden_log, nullptr);
  double named_s = -1;
  first = -1;
  while (hidden_log->Next(&ev) && named_s < 0) {
    if (ev.channel != c.lcm.model_check_channel) continue;
    kincal::model_check_t m;
    ASSERT_GE(m.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())), 0);
    if (first < 0) first = m.utime;
    if (m.suspected_effect == "actuator_lag" || m.suspected_effect == "time_offset")
      named_s = static_cast<double>(m.utime - first) * 1e-6;
  }
  std::cout << "estimate right in " << right << " params_t; hidden lag named after " << named_s
            << " s\n";
  EXPECT_GE(named_s, 0) << "the hidden lag was never named";
  EXPECT_LE(named_s, 30.0);
}

TEST(DriveLink, KincaldMakesOneOnlyForGuidanceDrive) {
  DaemonConfig c;
  const VisionSetup v = LoadVisionSetup(c).value();
  EXPECT_EQ(MakeDriveLink(c, v), nullptr);
  c.guidance.enabled = true;
  c.guidance.drive = true;
  EXPECT_NE(MakeDriveLink(c, v), nullptr);
}

}  // namespace
}  // namespace kincal::daemon
