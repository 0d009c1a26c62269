// kincald end to end: replay throughput in --fast mode and frame-to-publish latency at
// --speed 1, on a recorded raw 640x480 GREY 30 fps log of the simulated robot.
#include <benchmark/benchmark.h>
#include <spawn.h>
#include <spdlog/spdlog.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "kincal/daemon/config.h"
#include "kincal/daemon/daemon.h"
#include "kincal/io/recording.h"
#include "kincal/online/batch_tier.h"
#include "kincal/vision/camera.h"

namespace kincal::daemon {
namespace {

DaemonConfig Base() {
  DaemonConfig c =
      ReadDaemonConfig(std::string(KINCAL_SOURCE_DIR) + "/config/kincald_sim.yaml").value();
  c.lcm.url = "memq://";
  return c;
}

// A 20 s recording (600 frames), made once per process.
const std::string& Log() {
  static const std::string path = [] {
    spdlog::set_level(spdlog::level::warn);
    const auto p = std::filesystem::temp_directory_path() /
                   ("kincal_bench_" + std::to_string(::getpid()) + ".lcm");
    DaemonConfig c = Base();
    c.sim.speed = 0;
    c.sim.duration_s = 20;
    c.record.path = p.string();
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
    Daemon& d = *d_owner;
    d.Run();
    return p.string();
  }();
  return path;
}

double PeakRssMb(const std::string& status = "/proc/self/status") {
  std::ifstream in(status);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return 0.0;
}

// A replay's wall time, split: the frames through the pipeline (from Run() to the last
// frame's pose through the filter) and the batch calibration at shutdown, which does not
// depend on the frames' size or format.
struct ReplayTiming {
  double frames_per_s = 0;                                    // frames over the pipeline's time
  double pipeline_ms = 0, shutdown_batch_ms = 0, run_ms = 0;  // per replay
};

// Replays `c` (a replay configuration, --fast) once per benchmark iteration.
ReplayTiming TimeReplay(benchmark::State& state, const DaemonConfig& c) {
  int64_t frames = 0, runs = 0;
  double run_s = 0, batch_s = 0;
  for (auto _ : state) {
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
    Daemon& d = *d_owner;
    const auto t0 = std::chrono::steady_clock::now();
    d.Run();
    run_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const DaemonCounters k = d.counters();
    frames += k.frames_captured;
    batch_s += 1e-3 * static_cast<double>(k.batch_shutdown_ms);
    ++runs;
  }
  ReplayTiming t;
  const double n = static_cast<double>(std::max<int64_t>(runs, 1));
  t.run_ms = 1e3 * run_s / n;
  t.shutdown_batch_ms = 1e3 * batch_s / n;
  t.pipeline_ms = t.run_ms - t.shutdown_batch_ms;
  t.frames_per_s = static_cast<double>(frames) / std::max(run_s - batch_s, 1e-9);
  return t;
}

void ReportReplay(benchmark::State& state, const ReplayTiming& t) {
  state.counters["frames_per_s"] = t.frames_per_s;
  state.counters["pipeline_ms"] = t.pipeline_ms;
  state.counters["shutdown_batch_ms"] = t.shutdown_batch_ms;
  state.counters["run_ms"] = t.run_ms;
}

DaemonConfig FastReplayOf(const std::string& log) {
  DaemonConfig c = Base();
  c.source = SourceKind::kReplay;
  c.replay.path = log;
  c.replay.speed = 0;
  return c;
}

void BM_DaemonReplayFast(benchmark::State& state) {
  const ReplayTiming t = TimeReplay(state, FastReplayOf(Log()));
  ReportReplay(state, t);
  state.counters["x_realtime"] = t.frames_per_s / 30.0;
  state.counters["peak_rss_mb"] = PeakRssMb();
}
BENCHMARK(BM_DaemonReplayFast)->Unit(benchmark::kMillisecond)->Iterations(3);

// A 10 s recording of the simulated robot at width x height with frames stored as
// `encoding` (raw GREY, PNG, or JPEG replayed as MJPG), made once per case, and the camera
// file it was rendered with (empty: the default 640x480 camera).
struct FormatRecording {
  std::string log, intrinsics;
};

FormatRecording RecordFormat(int width, int height, FrameEncoding encoding) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string stem = "kincal_bench_" + std::to_string(::getpid()) + "_" +
                           std::to_string(width) + "_" + std::string(FrameEncodingName(encoding));
  DaemonConfig c = Base();
  if (width != 640 || height != 480) {
    const vision::CameraModel cam =
        vision::CameraModel::Centred(width, height, 500.0 * width / 640.0);
    c.camera.intrinsics = (dir / (stem + ".yaml")).string();
    if (!vision::WriteCameraYaml(cam, c.camera.intrinsics).ok()) return {};
  }
  c.sim.speed = 0;
  c.sim.duration_s = 10;
  c.record.path = (dir / (stem + ".lcm")).string();
  c.record.frame_encoding = encoding;
  const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
  Daemon& d = *d_owner;
  d.Run();
  return {c.record.path, c.camera.intrinsics};
}

// Replay throughput (--fast) by frame format and size. frames_per_s is over the pipeline's
// time only: the batch calibration at shutdown (shutdown_batch_ms, the same 40-60 ms for
// every format and size, a quarter of a raw replay's wall time) blurred the difference the
// frame size makes (raw 640x480 and 1280x720 read alike; issue 34). The detector tracks the
// target in a window around its last position, so a frame's size costs its copies
// (reading the log, the queue), and its format the decoding.
void BM_DaemonReplayFormat(benchmark::State& state) {
  const int width = static_cast<int>(state.range(0)), height = static_cast<int>(state.range(1));
  const auto encoding = static_cast<FrameEncoding>(state.range(2));
  const FormatRecording rec = RecordFormat(width, height, encoding);
  if (rec.log.empty()) {
    state.SkipWithError("could not write the camera file");
    return;
  }
  DaemonConfig c = FastReplayOf(rec.log);
  c.camera.intrinsics = rec.intrinsics;
  ReportReplay(state, TimeReplay(state, c));
  state.counters["log_mb"] = static_cast<double>(std::filesystem::file_size(rec.log)) / 1e6;
  state.SetLabel(std::string(FrameEncodingName(encoding)));
  std::filesystem::remove(rec.log);
  if (!rec.intrinsics.empty()) std::filesystem::remove(rec.intrinsics);
}
BENCHMARK(BM_DaemonReplayFormat)
    ->Args({640, 480, static_cast<int>(FrameEncoding::kRaw)})
    ->Args({640, 480, static_cast<int>(FrameEncoding::kPng)})
    ->Args({640, 480, static_cast<int>(FrameEncoding::kJpeg)})
    ->Args({1280, 720, static_cast<int>(FrameEncoding::kRaw)})
    ->Args({1280, 720, static_cast<int>(FrameEncoding::kPng)})
    ->Args({1280, 720, static_cast<int>(FrameEncoding::kJpeg)})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(3);

void ReportLatency(benchmark::State& state, const DaemonCounters& c) {
  state.counters["latency_p50_ms"] = c.latency_p50_ms;
  state.counters["latency_p99_ms"] = c.latency_p99_ms;
  state.counters["latency_max_ms"] = c.latency_max_ms;
  state.counters["frames_dropped"] = static_cast<double>(c.frames_dropped_queue);
}

// The frame-to-publish latency while batch calibrations run in the background: the
// simulated robot with a hidden lag (config/kincald_sim_lag.yaml, robot.effects: auto) at
// --speed 1 for 100 s, during which the batch tier runs at 30 and 90 s of data (analyze's
// selection, which adds the lag) and once more at shutdown.
void BM_DaemonLatencyDuringBatch(benchmark::State& state) {
  DaemonCounters c{};
  for (auto _ : state) {
    DaemonConfig cfg =
        ReadDaemonConfig(std::string(KINCAL_SOURCE_DIR) + "/config/kincald_sim_lag.yaml").value();
    cfg.lcm.url = "memq://";
    cfg.sim.duration_s = 100;
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(cfg).value();
    Daemon& d = *d_owner;
    d.Run();
    c = d.counters();
  }
  ReportLatency(state, c);
  state.counters["effects_added"] = static_cast<double>(c.effects_added);
  state.counters["batch_runs"] = static_cast<double>(c.batch_runs);
}
BENCHMARK(BM_DaemonLatencyDuringBatch)->Unit(benchmark::kMillisecond)->Iterations(1);

// One batch of the daemon's batch tier, with its options (analyze's; threads as given: the
// daemon's default, 0, is one per core; 1 for comparison),
// over the first 10 minutes of a real robot's motion (MR.CLAM dataset 6, motion capture
// thinned to 10 Hz poses, its odometry commands as the controls): through the store, as
// kincald runs it at shutdown (inline: the fit's own time). Args: robot, robot.effects: auto (1) or
// nothing (0), threads.
void BM_DaemonBatchMrclam10Min(benchmark::State& state) {
  const std::string dir = std::string(KINCAL_SOURCE_DIR) + "/../shared/data/mrclam/dataset6";
  if (!std::filesystem::is_directory(dir)) {
    state.SkipWithError(("no MR.CLAM data at " + dir).c_str());
    return;
  }
  spdlog::set_level(spdlog::level::warn);
  const Recording rec = ReadMrclam(dir, static_cast<int>(state.range(0))).value();
  BatchCalibration last;
  for (auto _ : state) {
    BatchTierOptions o;
    o.auto_effects = state.range(1) != 0;
    o.threads = static_cast<int>(state.range(2));
    BatchTier tier(o, "unicycle", {}, {}, 2, std::make_unique<InlineBatchRunner>());
    const TimeNs t0 = rec.poses.front().t_ns, end = t0 + SecondsToNs(600.0);
    TimeNs next_pose = t0;
    size_t c = 0;
    for (const auto& p : rec.poses) {
      if (p.t_ns > end) break;
      for (; c < rec.controls.size() &&
             rec.controls.ToNs(rec.controls.TimeAt(static_cast<int>(c))) <= p.t_ns;
           ++c) {
        const auto& v = rec.controls.ValuesAt(static_cast<int>(c));
        tier.AddControl(rec.controls.ToNs(rec.controls.TimeAt(static_cast<int>(c))),
                        std::span<const double>(v.data(), 2));
      }
      if (p.t_ns < next_pose) continue;
      next_pose = p.t_ns + 100'000'000;  // 10 Hz
      tier.AddPose(p.t_ns, p.z);
    }
    const auto results = tier.Finish(end);
    if (!results.empty()) last = results.back();
  }
  state.SetLabel(last.ok ? (last.accepted.empty() ? "none" : last.accepted.front() + "...")
                         : "failed: " + last.error);
  state.counters["batch_s"] = last.compute_s;
  state.counters["poses"] = last.num_poses;
  state.counters["effects_accepted"] = static_cast<double>(last.accepted.size());
  state.counters["heldout_mm_before"] = 1e3 * last.heldout_before_m;
  state.counters["heldout_mm_after"] = 1e3 * last.heldout_after_m;
}
BENCHMARK(BM_DaemonBatchMrclam10Min)
    ->Args({1, 0, 0})
    ->Args({1, 1, 0})
    ->Args({5, 0, 0})
    ->Args({5, 1, 0})
    ->Args({1, 1, 1})
    ->Args({5, 1, 1})
    ->Unit(benchmark::kSecond)
    ->Iterations(1)
    ->UseRealTime();

void BM_DaemonLatencySpeed1(benchmark::State& state) {
  const std::string& log = Log();
  DaemonCounters c{};
  for (auto _ : state) {
    DaemonConfig cfg = FastReplayOf(log);
    cfg.replay.speed = 1;
    const std::unique_ptr<Daemon> d_owner = Daemon::Create(cfg).value();
    Daemon& d = *d_owner;
    d.Run();
    c = d.counters();
  }
  ReportLatency(state, c);
  state.counters["peak_rss_mb"] = PeakRssMb();
}
BENCHMARK(BM_DaemonLatencySpeed1)->Unit(benchmark::kMillisecond)->Iterations(1);

// Resident memory of kincald itself: the binary beside this benchmark replays the log five
// times (3000 frames) in --fast mode. Peak RSS is the child's VmHWM, polled every 2 ms
// while it runs (it is a high-water mark, so the last reading holds the peak to within the
// last 2 ms). wait4's ru_maxrss would include this benchmark's own memory, which the child
// shares between posix_spawn's clone and its exec.
void BM_KincaldPeakResidentMemory(benchmark::State& state) {
  const std::string& log = Log();
  const std::string exe =
      (std::filesystem::read_symlink("/proc/self/exe").parent_path() / "kincald").string();
  if (!std::filesystem::exists(exe)) {
    state.SkipWithError("kincald is not built beside kincal_bench");
    return;
  }
  double peak_mb = 0, seconds = 0;
  for (auto _ : state) {
    std::vector<std::string> args = {exe, "--replay",  log,       "--fast", "--loop",
                                     "5", "--lcm-url", "memq://", "-q"};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    const auto t0 = std::chrono::steady_clock::now();
    pid_t pid = 0;
    if (posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv.data(), environ) != 0) {
      state.SkipWithError("cannot start kincald");
      return;
    }
    const std::string proc_status = "/proc/" + std::to_string(pid) + "/status";
    int status = 0;
    while (waitpid(pid, &status, WNOHANG) == 0) {
      const double mb = PeakRssMb(proc_status);
      if (mb > 0) peak_mb = mb;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
      state.SkipWithError("kincald failed");
      return;
    }
  }
  state.counters["kincald_peak_rss_mb"] = peak_mb;
  state.counters["frames_per_s"] = 3000.0 * static_cast<double>(state.iterations()) / seconds;
}
BENCHMARK(BM_KincaldPeakResidentMemory)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->UseRealTime();

}  // namespace
}  // namespace kincal::daemon
