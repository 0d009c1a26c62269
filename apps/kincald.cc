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

#include "kincal/daemon/command_line.h"
#include "kincal/daemon/daemon.h"
#include "options.h"

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

// The options, into `o`; config is the file given (or empty).
void AddOptions(CLI::App* app, std::string* config, kincal::daemon::CommandLineOptions* o,
                bool* quiet, bool* config_keys) {
  app->add_option("-c,--config", *config,
                  "YAML config (default: the simulated robot, config/kincald_sim.yaml)");
  auto* dev =
      app->add_option("--device", o->device, "V4L2 device, e.g. /dev/video0 (source: v4l2)");
  auto* lc = app->add_option("--libcamera", o->libcamera,
                             "libcamera camera id, or 'first' (source: libcamera)");
  auto* rp = app->add_option("--replay", o->replay,
                             "replay an LCM log recorded by kincald (source: replay)");
  dev->excludes(lc)->excludes(rp);
  lc->excludes(rp);
  auto* sp = app->add_option("--speed", o->speed, "replay/simulation speed factor (1: real time)");
  auto* fa =
      app->add_flag("--fast", o->fast, "as fast as possible, nothing dropped, deterministic");
  sp->excludes(fa);
  app->add_option("--loop", o->loops, "replay the log N times, each later by its span (soak tests)")
      ->check(kincal::app::AtLeastOne());
  app->add_option("--record", o->record,
                  "write everything (frames, controls, outputs) to this LCM log");
  app->add_flag("--record-png", o->record_png, "store recorded frames as PNG instead of raw");
  app->add_flag("--publish-frames", o->publish_frames,
                "also publish frames on LCM (default: log only)");
  app->add_flag("--preview", o->preview,
                "publish the camera's picture on KINCAL_PREVIEW (preview.*; for kincal view)");
  app->add_option("--lcm-url", o->lcm_url,
                  "LCM provider URL, e.g. udpm://239.255.76.67:7667?ttl=0 or memq://");
  app->add_option("--resume", o->resume, "start from this checkpoint (JSON)");
  app->add_option("--checkpoint", o->checkpoint,
                  "write checkpoints (and the final estimate) to this file");
  app->add_flag("--resume-if-present", o->resume_if_present,
                "resume from the --checkpoint file when it exists (services)");
  app->add_option("--duration", o->duration, "simulation length in seconds (source: sim)");
  app->add_option("--effects", o->effects,
                  "robot effects: 'auto' (found and added online), 'none', or specs separated by "
                  "commas, e.g. time_offset,auto");
  app->add_flag("-q,--quiet", *quiet, "log warnings and errors only");
  app->add_flag("--config-keys", *config_keys,
                "print every config key with its default (docs/config_keys.md) and exit");
}

// docs/config_keys.md: every key the loaders read, with its default.
void PrintConfigKeys() {
  std::cout << "# kincald's configuration keys\n\n"
               "Every key a kincald config file may hold, with its default, as `kincald "
               "--config-keys`\nprints them from the loaders themselves (a test keeps this "
               "file equal to that).\nWhat each means: the options structs in "
               "`include/kincal/daemon/config.h` and the\nsections of docs/daemon.md; the "
               "shipped configs in `config/` comment their keys.\n\n"
               "| key | default |\n|---|---|\n";
  for (const auto& k : kincal::daemon::DaemonConfigKeys()) {
    std::string value = k.default_value;
    for (size_t at = value.find('|'); at != std::string::npos; at = value.find('|', at + 2))
      value.replace(at, 1, "\\|");
    std::cout << "| `" << k.key << "` | " << (value.empty() ? "(empty)" : "`" + value + "`")
              << " |\n";
  }
}

// The configuration file (or the built-in defaults without one) with the command line
// applied, and the daemon made from it.
kincal::StatusOr<std::unique_ptr<kincal::daemon::Daemon>> MakeDaemon(
    std::string config, const kincal::daemon::CommandLineOptions& o) {
  if (config.empty()) config = DefaultConfig();
  kincal::StatusOr<kincal::daemon::DaemonConfig> cfg =
      config.empty() ? kincal::daemon::DaemonConfig{} : kincal::daemon::ReadDaemonConfig(config);
  if (!cfg.ok()) return cfg.status();
  if (kincal::Status s = kincal::daemon::ApplyCommandLine(o, &*cfg); !s.ok()) return s;
  return kincal::daemon::Daemon::Create(std::move(cfg).value());
}

void PrintFinalEstimate(const kincal::daemon::Daemon& daemon) {
  const auto est = daemon.Estimate();
  if (!est.names.empty()) {
    if (est.source == "batch") {
      const auto c = daemon.counters();
      const int64_t runs = c.run_resets + (c.updates > 0 ? 1 : 0);  // as the summary line counts
      std::cout << "final estimate: the batch calibration (batch " << est.batch_sequence << " over "
                << est.batch_poses << " poses of "
                << (runs > 1 ? "its " + std::to_string(runs) + " runs" : std::string("the run"))
                << "; the filter made " << est.update_count << " updates):\n";
    } else {
      std::cout << "final estimate: the filter's, no batch calibration yet (" << est.update_count
                << " updates, " << est.filter << "):\n";
    }
    for (size_t i = 0; i < est.names.size(); ++i) {
      const auto k = static_cast<Eigen::Index>(i);
      std::cout << "  " << est.names[i] << " = " << est.values[i] << " +- "
                << std::sqrt(std::max(0.0, est.covariance(k, k))) << " " << est.units[i] << "\n";
    }
  }
  std::cout << "shutdown: " << daemon.counters().batch_shutdown_ms
            << " ms in the last batch calibration\n";
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "kincald: online kinematic calibration daemon (capture -> markers -> pose -> SR-DD2 -> LCM)"};
  std::string config;
  kincal::daemon::CommandLineOptions options;
  bool quiet = false, config_keys = false;
  AddOptions(&app, &config, &options, &quiet, &config_keys);
  kincal::app::RefuseNonFiniteNumbers(app);
  CLI11_PARSE(app, argc, argv);
  if (config_keys) {
    PrintConfigKeys();
    return 0;
  }
  if (quiet) spdlog::set_level(spdlog::level::warn);

  // SIGINT/SIGTERM go to one thread that asks the daemon to stop (drain, final estimate,
  // checkpoint, close the log). A second signal exits at once.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  auto made = MakeDaemon(config, options);
  if (!made.ok()) {
    std::cerr << "kincald: error: " << made.status().message() << "\n";
    return 1;
  }
  kincal::daemon::Daemon& daemon = **made;
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
  PrintFinalEstimate(daemon);
  return rc;
}
