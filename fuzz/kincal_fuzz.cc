// libFuzzer harnesses for every decoder of outside data, in one program (a lean build):
//
//   kincal_fuzz --target=NAME [libFuzzer options] [CORPUS_DIR...]
//
// NAME: lcm_log (a kincald LCM log through the recording reader and the replay source),
// controls (one kincal.controls_t as the daemon's handler sees it), lcm_messages (params_t
// as `kincal export` reads it, frame_t and pose_t), csv (kincal's CSV recording reader),
// mrclam (the MR.CLAM reader), yaml (daemon config, scenario, target layout), checkpoint
// (JSON checkpoints, validated: extreme values, bad covariances), frame (pixel decoding:
// raw, YUYV, packed colour, MJPEG, PNG), lists (--init and --effects text).
// libFuzzer ignores flags starting with "--"; the harness reads --target itself.
// Expected failures (the readers' documented exceptions) are fine; crashes, sanitizer
// reports, leaks and hangs are not.
#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <kincal/frame_t.hpp>
#include <kincal/params_t.hpp>
#include <kincal/pose_t.hpp>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "daemon/control_input.h"
#include "daemon/sources.h"
#include "kincal/analysis/option_lists.h"
#include "kincal/daemon/config.h"
#include "kincal/daemon/frame.h"
#include "kincal/io/checkpoint.h"
#include "kincal/io/lcm_guard.h"
#include "kincal/io/recording.h"
#include "kincal/model.h"
#include "kincal/sim/scenario.h"
#include "kincal/system.h"
#include "kincal/vision/setup_files.h"

namespace {

std::string g_target;
std::string g_dir;

// Writes the input to a scratch file (the readers take paths, as users give them).
std::string WriteFile(const std::string& name, const uint8_t* data, size_t size) {
  const std::string path = g_dir + "/" + name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

template <typename F>
void Expect(F&& f) {
  try {
    f();
  } catch (const std::runtime_error&) {
  } catch (const std::invalid_argument&) {
  } catch (const std::out_of_range&) {
  }
}

const kincal::KinematicModel& Diffdrive() {
  static const auto model = kincal::MakeModel("diffdrive").value();
  return *model;
}

void FuzzLcmLog(const uint8_t* data, size_t size) {
  const std::string path = WriteFile("log.lcm", data, size);
  Expect([&] { (void)kincal::ReadLcmLog(path, Diffdrive()); });
  kincal::daemon::DaemonConfig c;
  c.source = kincal::daemon::SourceKind::kReplay;
  c.replay.path = path;
  c.replay.speed = 0;
  Expect([&] {
    kincal::ControlSample s;
    std::string why;
    auto src =
        kincal::daemon::MakeReplaySource(c.replay, c.lcm, [&](const void* d, size_t n, int64_t t) {
          kincal::daemon::DecodeControls(d, n, Diffdrive(), false, t, &s, &why);
        });
    if (!src->Start().ok()) return;
    kincal::daemon::Frame f;
    cv::Mat grey;
    std::string error;
    for (int i = 0; i < 64; ++i) {
      const auto st = src->Next(&f, 0, &error);
      if (st != kincal::daemon::SourceStatus::kFrame) break;
      Expect([&] { (void)kincal::daemon::ToGrey(f, &grey); });
    }
  });
}

void FuzzControls(const uint8_t* data, size_t size) {
  kincal::ControlSample s;
  std::string why;
  kincal::daemon::DecodeControls(data, size, Diffdrive(), false, 1, &s, &why);
  kincal::daemon::DecodeControls(data, size, Diffdrive(), true, 1, &s, &why);
}

void FuzzLcmMessages(const uint8_t* data, size_t size) {
  std::string why;
  if (kincal::PlausibleParams(data, size, 1000, &why)) {
    kincal::params_t m;
    m.decode(data, 0, static_cast<int>(size));
  }
  if (kincal::PlausibleFrame(data, size, &why)) {
    kincal::frame_t m;
    m.decode(data, 0, static_cast<int>(size));
  }
  kincal::pose_t p;  // fixed size: no length fields to check
  p.decode(data, 0, static_cast<int>(size));
}

void FuzzCsv(const uint8_t* data, size_t size) {
  // The first byte splits the input into a controls file and a poses file.
  const size_t cut = size == 0 ? 0 : std::min<size_t>(size, 1 + data[0] * size / 256);
  const std::string c = WriteFile("controls.csv", data, cut);
  const std::string p = WriteFile("poses.csv", data + cut, size - cut);
  static const auto unicycle = kincal::MakeModel("unicycle").value();
  Expect([&] { (void)kincal::ReadCsvRecording(c, p, *unicycle); });
}

void FuzzMrclam(const uint8_t* data, size_t size) {
  const size_t cut = size == 0 ? 0 : std::min<size_t>(size, 1 + data[0] * size / 256);
  WriteFile("Robot1_Odometry.dat", data, cut);
  WriteFile("Robot1_Groundtruth.dat", data + cut, size - cut);
  Expect([&] { (void)kincal::ReadMrclam(g_dir, 1); });
}

void FuzzYaml(const uint8_t* data, size_t size) {
  const std::string path = WriteFile("config.yaml", data, size);
  Expect([&] {
    const auto c = kincal::daemon::ReadDaemonConfig(path);
    std::string error;
    if (c.ok()) (void)c->IsValid(&error);
  });
  Expect([&] { (void)kincal::LoadScenario(path); });
  Expect([&] { (void)kincal::vision::ReadTargetLayoutYaml(path); });
}

void FuzzCheckpoint(const uint8_t* data, size_t size) {
  const std::string path = WriteFile("checkpoint.json", data, size);
  (void)kincal::ReadCheckpoint(path);  // a Status, never an exception
}

void FuzzLists(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::map<std::string, double> init;
  std::vector<std::string> effects;
  (void)kincal::ParseInitList(text, &init);
  if (kincal::ParseEffectList(text, &effects).ok()) {
    // Every spec the list accepts is one ParseEffectSpec accepts: try binding it.
    for (const auto& e : effects) {
      std::unique_ptr<kincal::System> sys;
      (void)kincal::MakeSystem("diffdrive", {e}, {}, &sys);
    }
  }
}

void FuzzFrame(const uint8_t* data, size_t size) {
  if (size < 6) return;
  kincal::daemon::Frame f;
  f.format = static_cast<kincal::daemon::PixelFormat>(data[0] % 6);
  f.width = data[1] + 1;
  f.height = data[2] + 1;
  f.stride = f.width * (data[3] % 4) + data[4] % 8;
  f.data.assign(data + 5, data + size);
  cv::Mat grey;
  Expect([&] { (void)kincal::daemon::ToGrey(f, &grey); });
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  for (int i = 1; i < *argc; ++i) {
    if (std::strncmp((*argv)[i], "--target=", 9) == 0) g_target = (*argv)[i] + 9;
  }
  if (g_target.empty()) {
    std::fprintf(stderr,
                 "kincal_fuzz: give "
                 "--target=lcm_log|controls|lcm_messages|csv|mrclam|yaml|checkpoint|frame|lists\n");
    std::exit(2);
  }
  // The library's warnings (e.g. replay naming each damaged stretch) would flood the
  // output at thousands of executions per second.
  spdlog::set_level(spdlog::level::off);
  // Scratch files in memory when possible: every execution writes its input to a file.
  std::string tmpl =
      (::access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp") + std::string("/kincal_fuzz_XXXXXX");
  const char* dir = ::mkdtemp(tmpl.data());
  if (dir == nullptr) std::exit(2);
  g_dir = dir;
  std::atexit([] { std::filesystem::remove_all(g_dir); });
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (g_target == "lcm_log")
    FuzzLcmLog(data, size);
  else if (g_target == "controls")
    FuzzControls(data, size);
  else if (g_target == "lcm_messages")
    FuzzLcmMessages(data, size);
  else if (g_target == "csv")
    FuzzCsv(data, size);
  else if (g_target == "mrclam")
    FuzzMrclam(data, size);
  else if (g_target == "yaml")
    FuzzYaml(data, size);
  else if (g_target == "checkpoint")
    FuzzCheckpoint(data, size);
  else if (g_target == "frame")
    FuzzFrame(data, size);
  else if (g_target == "lists")
    FuzzLists(data, size);
  else {
    std::fprintf(stderr, "kincal_fuzz: unknown target '%s'\n", g_target.c_str());
    std::exit(2);
  }
  return 0;
}
