// kincald: the kincal daemon. Captures frames (V4L2, libcamera, simulated camera or a
// recorded log), finds the target, calibrates the robot online and publishes over LCM.
// Thin front end over kincal::daemon::Daemon; see `kincald --help` and docs/daemon.md.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <thread>

#include "kincal/analysis/option_lists.h"
#include "kincal/daemon/daemon.h"

#ifndef KINCAL_INSTALL_DATADIR
#define KINCAL_INSTALL_DATADIR ""
#endif
#ifndef KINCAL_SOURCE_DIR
#define KINCAL_SOURCE_DIR ""
#endif

namespace {

// Without --config: the simulated robot (config/kincald_sim.yaml) beside the executable
// (PREFIX/bin -> PREFIX/share/kincal), in the configured install prefix, or in the source tree.
std::string DefaultConfig() {
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  const std::string beside =
      ec ? std::string() : (exe.parent_path().parent_path() / "share/kincal/config").string();
  for (const std::string& dir : {beside, std::string(KINCAL_INSTALL_DATADIR) + "/config",
                                 std::string(KINCAL_SOURCE_DIR) + "/config"}) {
    if (dir.empty()) continue;
    const auto p = std::filesystem::path(dir) / "kincald_sim.yaml";
    if (std::filesystem::exists(p)) return p.string();
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "kincald: online kinematic calibration daemon (capture -> markers -> pose -> SR-DD2 -> LCM)"};
  std::string config, device, libcamera, replay, record, lcm_url, resume, checkpoint;
  double speed = 1.0, duration = 0.0;
  int loops = 1;
  bool fast = false, record_png = false, publish_frames = false, quiet = false,
       resume_if_present = false;
  app.add_option("-c,--config", config,
                 "YAML config (default: the simulated robot, config/kincald_sim.yaml)");
  auto* dev = app.add_option("--device", device, "V4L2 device, e.g. /dev/video0 (source: v4l2)");
  auto* lc = app.add_option("--libcamera", libcamera,
                            "libcamera camera id, or 'first' (source: libcamera)");
  auto* rp =
      app.add_option("--replay", replay, "replay an LCM log recorded by kincald (source: replay)");
  dev->excludes(lc)->excludes(rp);
  lc->excludes(rp);
  auto* sp = app.add_option("--speed", speed, "replay/simulation speed factor (1: real time)");
  auto* fa = app.add_flag("--fast", fast, "as fast as possible, nothing dropped, deterministic");
  sp->excludes(fa);
  app.add_option("--loop", loops, "replay the log N times, each later by its span (soak tests)")
      ->check(CLI::PositiveNumber);
  app.add_option("--record", record,
                 "write everything (frames, controls, outputs) to this LCM log");
  app.add_flag("--record-png", record_png, "store recorded frames as PNG instead of raw");
  app.add_flag("--publish-frames", publish_frames,
               "also publish frames on LCM (default: log only)");
  app.add_option("--lcm-url", lcm_url,
                 "LCM provider URL, e.g. udpm://239.255.76.67:7667?ttl=0 or memq://");
  app.add_option("--resume", resume, "start from this checkpoint (JSON)");
  app.add_option("--checkpoint", checkpoint,
                 "write checkpoints (and the final estimate) to this file");
  app.add_flag("--resume-if-present", resume_if_present,
               "resume from the --checkpoint file when it exists (services)");
  auto* dur = app.add_option("--duration", duration, "simulation length in seconds (source: sim)");
  std::string effects;
  app.add_option("--effects", effects,
                 "robot effects: 'auto' (found and added online), 'none', or specs separated by "
                 "commas, e.g. time_offset,auto");
  app.add_flag("-q,--quiet", quiet, "log warnings and errors only");
  CLI11_PARSE(app, argc, argv);
  if (quiet) spdlog::set_level(spdlog::level::warn);

  // SIGINT/SIGTERM go to one thread that asks the daemon to stop (drain, final estimate,
  // checkpoint, close the log). A second signal exits at once.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  try {
    if (config.empty()) config = DefaultConfig();
    kincal::daemon::DaemonConfig cfg =
        config.empty() ? kincal::daemon::DaemonConfig{} : kincal::daemon::LoadDaemonConfig(config);
    if (!device.empty()) {
      cfg.source = kincal::daemon::SourceKind::kV4l2;
      cfg.v4l2.device = device;
    } else if (!libcamera.empty()) {
      cfg.source = kincal::daemon::SourceKind::kLibcamera;
      cfg.libcamera.camera = libcamera == "first" ? "" : libcamera;
    } else if (!replay.empty()) {
      cfg.source = kincal::daemon::SourceKind::kReplay;
      cfg.replay.path = replay;
    }
    if (cfg.source == kincal::daemon::SourceKind::kReplay)
      cfg.replay.speed = fast ? 0.0 : (sp->count() ? speed : cfg.replay.speed);
    if (cfg.source == kincal::daemon::SourceKind::kSim)
      cfg.sim.speed = fast ? 0.0 : (sp->count() ? speed : cfg.sim.speed);
    if (dur->count()) {
      if (!(duration > 0 && duration <= kincal::daemon::kMaxSimDurationS)) {
        throw std::runtime_error(
            "--duration: expected seconds > 0 and at most " +
            std::to_string(static_cast<int64_t>(kincal::daemon::kMaxSimDurationS)) + " (30 days)");
      }
      cfg.sim.duration_s = duration;
    }
    if (!effects.empty()) {
      cfg.robot.effects.clear();
      cfg.robot.auto_effects = false;
      std::vector<std::string> list;
      if (const kincal::Status s = kincal::ParseEffectList(effects == "none" ? "" : effects, &list);
          !s.ok()) {
        throw std::runtime_error(s.message());
      }
      for (const std::string& e : list) {
        if (e == "auto") {
          cfg.robot.auto_effects = true;
        } else {
          cfg.robot.effects.push_back(e);
        }
      }
    }
    if (loops > 1) cfg.replay.loops = loops;
    if (!record.empty()) cfg.record.path = record;
    if (record_png) cfg.record.frame_encoding = kincal::daemon::FrameEncoding::kPng;
    if (publish_frames) cfg.lcm.publish_frames = true;
    if (!lcm_url.empty()) cfg.lcm.url = lcm_url;
    if (!resume.empty()) cfg.checkpoint.resume = resume;
    if (!checkpoint.empty()) cfg.checkpoint.path = checkpoint;
    if (resume_if_present && !cfg.checkpoint.path.empty() &&
        std::filesystem::exists(cfg.checkpoint.path)) {
      cfg.checkpoint.resume = cfg.checkpoint.path;
    }

    kincal::daemon::Daemon daemon(std::move(cfg));
    std::thread signal_thread([&daemon, signals] {
      int sig = 0;
      if (sigwait(&signals, &sig) != 0) return;
      if (sig == 0) return;
      spdlog::info("kincald: {} received", sig == SIGINT ? "SIGINT" : "SIGTERM");
      daemon.Stop();
      if (sigwait(&signals, &sig) == 0 && sig != 0) std::_Exit(128 + sig);
    });
    signal_thread.detach();
    const int rc = daemon.Run();
    const auto est = daemon.Estimate();
    if (!est.names.empty()) {
      if (est.source == "batch") {
        std::cout << "final estimate: the batch calibration (batch " << est.batch_sequence
                  << " over " << est.batch_poses << " poses of the run; the filter made "
                  << est.update_count << " updates):\n";
      } else {
        std::cout << "final estimate: the filter's, no batch calibration yet (" << est.update_count
                  << " updates, " << est.filter << "):\n";
      }
      for (size_t i = 0; i < est.names.size(); ++i) {
        std::cout << "  " << est.names[i] << " = " << est.values[i] << " +- "
                  << std::sqrt(
                         std::max(0.0, est.covariance(static_cast<int>(i), static_cast<int>(i))))
                  << " " << est.units[i] << "\n";
      }
    }
    std::cout << "shutdown: " << daemon.counters().batch_shutdown_ms
              << " ms in the last batch calibration\n";
    return rc;
  } catch (const std::exception& e) {
    std::cerr << "kincald: error: " << e.what() << "\n";
    return 1;
  }
}
