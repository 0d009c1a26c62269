// kincald on a robot with an effect nobody declared, through the whole pipeline: the
// simulated camera renders it, the run is recorded, and the log is replayed with --fast
// (the path a user's recording takes). The filter must keep running (at most one restart),
// the model check must name the family, and health must agree with params at every message.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <kincal/calibration_t.hpp>
#include <kincal/health_t.hpp>
#include <kincal/model_check_t.hpp>
#include <kincal/params_t.hpp>
#include <map>
#include <set>

#include "daemon/daemon_test_util.h"
#include "kincal/analysis/analyze.h"
#include "kincal/daemon/daemon.h"
#include "kincal/io/lcm_log_reader.h"
#include "kincal/io/recording.h"

namespace kincal::daemon {
namespace {

using test_util::TempPath;

// The shipped simulated robot with a hidden effect, recorded, then replayed; the replay's
// own recording.
struct Replayed {
  std::string log;  // the (last) replay's recording
  std::vector<kincal::params_t> params;
  std::vector<kincal::model_check_t> checks;
  std::vector<kincal::calibration_t> calibrations;
  std::vector<kincal::health_t> health;
  std::vector<std::pair<char, size_t>> order;  // 'p', 'c', 'h' and the index, in log order
  DaemonCounters counters;
};

// The shipped diff-drive scenario with extra truth lines and a hidden_effects line
// ("  tau_s: 0.15|hidden_effects: [actuator_lag]").
std::string DiffDriveScenario(const std::string& hidden_yaml) {
  std::ifstream in(test_util::kConfigDir + "/sim_daemon.yaml");
  std::string text, line;
  while (std::getline(in, line)) {
    if (line.rfind("hidden_effects:", 0) == 0) continue;
    text += line + "\n";
    if (line.rfind("truth:", 0) == 0) text += hidden_yaml.substr(0, hidden_yaml.find('|')) + "\n";
  }
  return text + hidden_yaml.substr(hidden_yaml.find('|') + 1) + "\n";
}

// Records the simulated robot of `scenario_yaml` through the camera, then replays the log
// `replays` times with --fast. `robot` adjusts the robot section (model, guess).
Replayed SimulateAndReplayScenario(const std::string& name, const std::string& scenario_yaml,
                                   double duration_s, bool auto_effects, int replays,
                                   const std::function<void(DaemonConfig*)>& robot) {
  const std::string scenario = TempPath(name + "_scenario.yaml");
  std::ofstream(scenario) << scenario_yaml;
  DaemonConfig sim = test_util::SimConfig(duration_s);
  if (robot) robot(&sim);
  sim.sim.scenario = scenario;
  sim.record.path = TempPath(name + "_sim.lcm");
  if (!std::filesystem::exists(sim.record.path)) {  // a second replay of one run reuses it
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(sim).value();
    Daemon& d = *d_owner;
    EXPECT_EQ(d.Run(), 0);
  }
  DaemonConfig replay = sim;
  replay.source = SourceKind::kReplay;
  replay.replay.path = sim.record.path;
  replay.replay.speed = 0;
  replay.robot.auto_effects = auto_effects;
  Replayed r;
  std::vector<std::vector<uint8_t>> first_params;
  std::vector<kincal::calibration_t> first_calibrations;
  for (int k = 0; k < replays; ++k) {
    replay.record.path = TempPath(name + (auto_effects ? "_auto" : "_declared") + "_replay" +
                                  std::to_string(k) + ".lcm");
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(replay).value();
    Daemon& d = *d_owner;
    EXPECT_EQ(d.Run(), 0);
    r.counters = d.counters();
    // Every replay publishes the very same parameters (bytes).
    const std::unique_ptr<LcmLogReader> log = test_util::OpenLog(replay.record.path);
    if (!log) return r;
    LcmLogEvent ev;
    std::vector<std::vector<uint8_t>> params;
    std::vector<kincal::calibration_t> calibrations;
    while (log->Next(&ev)) {
      if (ev.channel == replay.lcm.params_channel) params.push_back(ev.data);
      if (ev.channel == replay.lcm.calibration_channel) {
        calibrations.emplace_back().decode(ev.data.data(), 0, static_cast<int>(ev.data.size()));
        calibrations.back().compute_s = 0;  // wall time: not part of the result
      }
    }
    if (k == 0) first_params = params, first_calibrations = calibrations;
    EXPECT_TRUE(params == first_params) << "replay " << k << " differs from the first";
    // The batch results, bit for bit (the encoded messages, less the wall time they took).
    EXPECT_EQ(calibrations.size(), first_calibrations.size()) << "replay " << k;
    for (size_t i = 0; i < std::min(calibrations.size(), first_calibrations.size()); ++i) {
      std::vector<uint8_t> a(static_cast<size_t>(calibrations[i].getEncodedSize()));
      std::vector<uint8_t> b(static_cast<size_t>(first_calibrations[i].getEncodedSize()));
      calibrations[i].encode(a.data(), 0, static_cast<int>(a.size()));
      first_calibrations[i].encode(b.data(), 0, static_cast<int>(b.size()));
      EXPECT_TRUE(a == b) << "replay " << k << ": batch " << i << " differs from the first";
    }
  }
  r.log = replay.record.path;
  const std::unique_ptr<LcmLogReader> log = test_util::OpenLog(replay.record.path);
  if (!log) return r;
  LcmLogEvent ev;
  const int n = 0;
  while (log->Next(&ev)) {
    const int size = static_cast<int>(ev.data.size());
    if (ev.channel == replay.lcm.params_channel) {
      r.params.emplace_back().decode(ev.data.data(), n, size);
      r.order.emplace_back('p', r.params.size() - 1);
    } else if (ev.channel == replay.lcm.model_check_channel) {
      r.checks.emplace_back().decode(ev.data.data(), n, size);
      r.order.emplace_back('c', r.checks.size() - 1);
    } else if (ev.channel == replay.lcm.calibration_channel) {
      r.calibrations.emplace_back().decode(ev.data.data(), n, size);
    } else if (ev.channel == replay.lcm.health_channel) {
      r.health.emplace_back().decode(ev.data.data(), n, size);
      r.order.emplace_back('h', r.health.size() - 1);
    }
  }
  return r;
}

Replayed SimulateAndReplay(const std::string& name, const std::string& hidden_yaml,
                           double duration_s, bool auto_effects = false, int replays = 1) {
  return SimulateAndReplayScenario(name, DiffDriveScenario(hidden_yaml), duration_s, auto_effects,
                                   replays, nullptr);
}

// Health reports the status of the params_t published last, at every message.
void ExpectHealthAgreesWithParams(const Replayed& r) {
  int last_status = kincal::params_t::STATUS_INITIALIZING;
  for (const auto& [kind, i] : r.order) {
    if (kind == 'p') last_status = r.params[i].status;
    if (kind == 'h') {
      EXPECT_EQ(int{r.health[i].filter_status}, last_status) << "health message " << i;
      const bool bad = last_status == kincal::params_t::STATUS_DIVERGED ||
                       last_status == kincal::params_t::STATUS_MODEL_INADEQUATE;
      if (bad) {
        EXPECT_EQ(r.health[i].ok, 0) << "health message " << i;
      }
    }
  }
}

// Seconds of data until the first model check that names `effect` among its candidates.
double SecondsUntilNamed(const Replayed& r, const std::string& effect) {
  for (const auto& c : r.checks) {
    for (const auto& name : c.candidates) {
      if (name == effect) return 1e-6 * static_cast<double>(c.utime - r.checks.front().utime);
    }
  }
  return -1;
}

TEST(DaemonModelError, HiddenLagThroughTheCameraAndReplay) {
  const Replayed r = SimulateAndReplay("lag", "  tau_s: 0.15|hidden_effects: [actuator_lag]", 60);
  ASSERT_GT(r.params.size(), 100u);
  EXPECT_LE(r.counters.filter_resets, 1);
  EXPECT_LT(r.counters.poses_gated, r.counters.updates / 20);
  const double named_s = SecondsUntilNamed(r, "actuator_lag");
  EXPECT_GE(named_s, 0.0);
  EXPECT_LE(named_s, 30.0);
  EXPECT_EQ(int{r.params.back().status}, int{kincal::params_t::STATUS_MODEL_INADEQUATE});
  EXPECT_EQ(r.params.back().update_count, r.counters.updates);
  ExpectHealthAgreesWithParams(r);
}

TEST(DaemonModelError, HiddenDelayThroughTheCameraAndReplay) {
  const Replayed r =
      SimulateAndReplay("delay", "  delay_s: 0.10|hidden_effects: [time_offset]", 60);
  ASSERT_GT(r.params.size(), 100u);
  EXPECT_LE(r.counters.filter_resets, 1);
  EXPECT_LT(r.counters.poses_gated, r.counters.updates / 20);
  const double named_s = SecondsUntilNamed(r, "time_offset");
  EXPECT_GE(named_s, 0.0);
  EXPECT_LE(named_s, 30.0);
  EXPECT_EQ(int{r.params.back().status}, int{kincal::params_t::STATUS_MODEL_INADEQUATE});
  ExpectHealthAgreesWithParams(r);
}

TEST(DaemonModelError, CleanRobotConvergesAndHealthAgrees) {
  const Replayed r = SimulateAndReplay("clean", "|hidden_effects: []", 40);
  ASSERT_GT(r.params.size(), 100u);
  EXPECT_EQ(r.counters.filter_resets, 0);
  EXPECT_EQ(int{r.params.back().status}, int{kincal::params_t::STATUS_CONVERGED});
  for (const auto& c : r.checks) EXPECT_EQ(c.num_candidates, 0) << c.evidence;
  ExpectHealthAgreesWithParams(r);
}

// robot.effects: auto through the camera and a --fast replay, twice: the lag is found and
// estimated, and both replays decide and publish bit-identically.
TEST(DaemonModelError, AutoEffectsFindTheLagAndReplayBitIdentically) {
  const Replayed r = SimulateAndReplay("lag_auto", "  tau_s: 0.15|hidden_effects: [actuator_lag]",
                                       90, /*auto_effects=*/true, /*replays=*/2);
  ASSERT_FALSE(r.checks.empty());
  const auto& last = r.checks.back();
  ASSERT_EQ(last.num_added, 1) << last.evidence;
  EXPECT_EQ(last.effects_added[0], "actuator_lag");
  EXPECT_LT(last.heldout_after_m[0], 0.5 * last.heldout_before_m[0]);
  const auto& p = r.params.back();
  const std::map<std::string, double> truth = {
      {"r_l", 0.0310}, {"r_r", 0.0313}, {"d", 0.148}, {"tau_s", 0.15}};
  ASSERT_EQ(p.num_params, 4);
  for (int i = 0; i < p.num_params; ++i) {
    EXPECT_NEAR(p.values[i], truth.at(p.names[i]), 3 * p.sigmas[i]) << p.names[i];
  }
  EXPECT_NEAR(p.values[3], 0.15, 0.015);
  EXPECT_LE(r.counters.filter_resets, 1);
  ExpectHealthAgreesWithParams(r);
}

// The last calibration a replay published is `kincal analyze` on the poses and controls
// the same replay recorded, within 1 sigma, parameter by parameter.
void ExpectCalibrationIsAnalyzeOfTheLog(const Replayed& r, const std::string& effects_mode) {
  ASSERT_FALSE(r.calibrations.empty());
  const kincal::calibration_t& c = r.calibrations.back();
  ASSERT_EQ(c.ok, 1) << c.error;
  AnalyzeOptions o;
  o.model = "unicycle";
  o.effects_mode = effects_mode;
  o.init = {{"k_v", 1.0}, {"k_omega", 1.0}};
  const AnalyzeResult offline =
      Analyze(ReadLcmLog(r.log, *MakeModel("unicycle").value()).value(), o).value();
  ASSERT_EQ(c.num_params, static_cast<int>(offline.after.params.size())) << c.model;
  EXPECT_EQ(c.effects, offline.after.effects);
  for (int i = 0; i < c.num_params; ++i) {
    const ParamEstimate& e = offline.after.params[static_cast<size_t>(i)];
    EXPECT_EQ(c.names[static_cast<size_t>(i)], e.name);
    EXPECT_NEAR(c.values[static_cast<size_t>(i)], e.value, e.sigma)
        << e.name << ": kincald " << c.values[static_cast<size_t>(i)] << ", analyze " << e.value;
  }
  // The run's last params_t carries the calibration, and says so.
  EXPECT_EQ(int{r.params.back().source}, int{kincal::params_t::SOURCE_BATCH});
  for (int i = 0; i < c.num_params; ++i) {
    EXPECT_EQ(r.params.back().values[static_cast<size_t>(i)], c.values[static_cast<size_t>(i)]);
  }
}

// The MR.CLAM pattern through the camera: a unicycle that acts 0.2 s late and loses speed
// in turns, nothing declared. With robot.effects: auto both effects are found and
// estimated; with or without, the daemon's calibration is what `kincal analyze` finds on
// the same recorded poses, and two --fast replays give the same batch results bit for bit.
TEST(DaemonModelError, AutoEffectsFindTheDelayAndTheTurnSlowdownOfAUnicycle) {
  const std::string scenario = R"(model: unicycle
truth: {k_v: 0.9, k_omega: 0.85, delay_s: 0.2, c_slow: 0.3}
hidden_effects: [time_offset, turn_slowdown]
estimator_effects: []
duration_s: 240
seed: 8
controls: {profile: piecewise, low: [-0.1, -1.0], high: [0.3, 1.0], min_period_s: 1.0, rate_hz: 50}
camera: {rate_hz: 30, jitter_max_s: 0.0, jitter_prob: 0.0, dropout_prob: 0.0}
)";
  const auto unicycle = [](DaemonConfig* c) {
    c->robot.model = "unicycle";
    c->robot.guess = {{"k_v", 1.0}, {"k_omega", 1.0}};
    c->filter.control_psd = {0.0, 0.0};
  };
  const Replayed r =
      SimulateAndReplayScenario("mrclam_auto", scenario, 240, /*auto_effects=*/true, 2, unicycle);
  ASSERT_FALSE(r.checks.empty());
  const auto& last = r.checks.back();
  std::set<std::string> added(last.effects_added.begin(), last.effects_added.end());
  EXPECT_EQ(added, (std::set<std::string>{"time_offset", "turn_slowdown"})) << last.evidence;
  const std::map<std::string, double> truth = {
      {"k_v", 0.9}, {"k_omega", 0.85}, {"delay_s", 0.2}, {"c_slow", 0.3}};
  const auto& p = r.params.back();
  ASSERT_EQ(p.num_params, 4);
  for (int i = 0; i < p.num_params; ++i) {
    EXPECT_NEAR(p.values[i], truth.at(p.names[i]), 3 * p.sigmas[i]) << p.names[i];
    if (p.names[i] == "delay_s" || p.names[i] == "c_slow") {
      EXPECT_NEAR(p.values[i], truth.at(p.names[i]), 0.1 * truth.at(p.names[i])) << p.names[i];
    }
  }
  EXPECT_LE(r.counters.filter_resets, 1);
  ExpectHealthAgreesWithParams(r);
  ExpectCalibrationIsAnalyzeOfTheLog(r, "auto");

  // The same recorded run, replayed without auto.
  const Replayed bare = SimulateAndReplayScenario("mrclam_auto", scenario, 240,
                                                  /*auto_effects=*/false, 1, unicycle);
  ExpectCalibrationIsAnalyzeOfTheLog(bare, "none");
  EXPECT_LE(bare.counters.filter_resets, 1);
  EXPECT_NE(int{bare.params.back().status}, int{kincal::params_t::STATUS_CONVERGED});
}

}  // namespace
}  // namespace kincal::daemon
