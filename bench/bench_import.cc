// kincal import, as users run it: a ROS 2 mcap bag of a diff-drive robot (JointState at
// 50 Hz, motion-capture PoseStamped at 30 Hz, 300 s: 24,000 messages, written by rosbags'
// own writer from tests/ros/ros_bags.py) to a kincal LCM log, through the `kincal` beside
// this benchmark and the venv's Python.
#include <benchmark/benchmark.h>
#include <spawn.h>
#include <sys/wait.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

extern char** environ;

namespace {

namespace fs = std::filesystem;

constexpr double kBagSeconds = 300.0;
constexpr double kMessages = kBagSeconds * (50.0 + 30.0);

// The bag, written once per process; empty when Python or rosbags is missing.
const std::string& Bag() {
  static const std::string path = [] {
    const fs::path dir = fs::temp_directory_path() / "kincal_bench_import";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string bag = (dir / "robot_mcap").string();
    const std::string src = KINCAL_SOURCE_DIR;
    const std::string cmd =
        src + "/.venv/bin/python -c \"import sys; sys.path.insert(0, '" + src +
        "/tests/ros'); import ros_bags; ros_bags.write_diffdrive('" + bag +
        "', 'mcap', ros_bags.diffdrive(duration=" + std::to_string(kBagSeconds) + "))\"";
    return std::system(cmd.c_str()) == 0 ? bag : std::string();
  }();
  return path;
}

int Run(std::vector<std::string> args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

void BM_ImportBag(benchmark::State& state) {
  const std::string exe = (fs::read_symlink("/proc/self/exe").parent_path() / "kincal").string();
  if (!fs::exists(exe)) {
    state.SkipWithError("kincal is not built beside kincal_bench");
    return;
  }
  if (Bag().empty()) {
    state.SkipWithError("cannot write the bag (the venv's Python with rosbags)");
    return;
  }
  const std::string out = (fs::path(Bag()).parent_path() / "robot.lcm").string();
  double seconds = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const int rc = Run({exe, "import", Bag(), "--out", out, "--model", "diffdrive", "--controls",
                        "/joint_states", "--joints", "left_wheel_joint,right_wheel_joint",
                        "--poses", "/mocap/robot/pose"});
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (rc != 0) {
      state.SkipWithError("kincal import failed");
      return;
    }
  }
  state.counters["messages_per_s"] = kMessages * static_cast<double>(state.iterations()) / seconds;
}
BENCHMARK(BM_ImportBag)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

// Issue 33's car: thirty 4 s ROS 1 bags (AckermannDriveStamped at 20 Hz on the car's clock,
// motion capture at 60 Hz), written once per process; their folder, empty on failure.
const std::string& CarBags() {
  static const std::string path = [] {
    const fs::path dir = fs::temp_directory_path() / "kincal_bench_car";
    fs::remove_all(dir);
    fs::create_directories(dir / "bags");
    const std::string src = KINCAL_SOURCE_DIR;
    const std::string cmd =
        src + "/.venv/bin/python -c \"import sys; sys.path.insert(0, '" + src +
        "/tests/ros'); import numpy as np, ros_bags; g = np.random.default_rng(33); "
        "[ros_bags.write_car_run('" +
        (dir / "bags").string() +
        "/run_%02d.bag' % k, ros_bags.car_run(g), t0_s=10.0 * k) for k in range(30)]\"";
    return std::system(cmd.c_str()) == 0 ? (dir / "bags").string() : std::string();
  }();
  return path;
}

std::vector<std::string> ImportCar(const std::string& exe, const std::string& out) {
  return {exe,          "import", CarBags(), "--out",          out, "--model", "bicycle",
          "--controls", "/drive", "--poses", "/mocap/car/pose"};
}

// `kincal import` of the thirty bags into one log of thirty runs (issue 33: <= 5 s).
void BM_ImportCarBags(benchmark::State& state) {
  const std::string exe = (fs::read_symlink("/proc/self/exe").parent_path() / "kincal").string();
  if (!fs::exists(exe) || CarBags().empty()) {
    state.SkipWithError("kincal or the venv's Python with rosbags is missing");
    return;
  }
  const std::string out = (fs::path(CarBags()).parent_path() / "car.lcm").string();
  for (auto _ : state) {
    if (Run(ImportCar(exe, out)) != 0) {
      state.SkipWithError("kincal import failed");
      return;
    }
  }
}
BENCHMARK(BM_ImportCarBags)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

// `kincal analyze` of those thirty runs with the wheelbase held, default options (issue 33:
// <= 10 s on 2 cores).
void BM_AnalyzeCarRuns(benchmark::State& state) {
  const std::string exe = (fs::read_symlink("/proc/self/exe").parent_path() / "kincal").string();
  if (!fs::exists(exe) || CarBags().empty()) {
    state.SkipWithError("kincal or the venv's Python with rosbags is missing");
    return;
  }
  const fs::path dir = fs::path(CarBags()).parent_path();
  const std::string log = (dir / "car.lcm").string();
  if (Run(ImportCar(exe, log)) != 0) {
    state.SkipWithError("kincal import failed");
    return;
  }
  for (auto _ : state) {
    if (Run({exe, "analyze", "--log", log, "--model", "bicycle", "--fix", "wheelbase=0.33", "--out",
             (dir / "analysis").string()}) != 0) {
      state.SkipWithError("kincal analyze failed");
      return;
    }
  }
}
BENCHMARK(BM_AnalyzeCarRuns)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

}  // namespace
