// kincald's libcamera source (and its V4L2 source) against a real media-controller
// pipeline: vimc (Sensor B -> Debayer B -> Scaler -> RGB/YUV Capture), inside the QEMU VM
// that tests/vm/run_in_vm.sh boots with the module tests/vm/build_vimc.sh builds for its
// kernel (ctest vm.libcamera_vimc). Not discovered on the host. The tests run in this
// order: the first meets the pipeline as the driver left it, the last reloads the driver.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/videodev2.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <kincal/pose_t.hpp>
#include <map>
#include <thread>
#include <vector>

#include "daemon/sources.h"
#include "kincal/daemon/daemon.h"
#include "kincal/daemon/frame.h"
#include "kincal/io/lcm_log_reader.h"
#include "kincal/vision/setup_files.h"
#include "source_dir.h"

namespace kincal::daemon {
namespace {

namespace fs = std::filesystem;

std::string Tmp(const std::string& name) {
  const char* t = std::getenv("TMPDIR");
  return std::string(t ? t : "/tmp") + "/" + name;
}

// /dev/videoN whose sysfs name is `name`.
std::string FindVimcNode(const std::string& name) {
  for (const auto& e : fs::directory_iterator("/sys/class/video4linux")) {
    std::ifstream in(e.path() / "name");
    std::string n;
    std::getline(in, n);
    if (n == name) return "/dev/" + e.path().filename().string();
  }
  return "";
}

// Intrinsics for what vimc delivers when asked for 640x480 (libcamera adjusts to 636x480).
std::string WriteIntrinsics(int width, int height) {
  vision::CameraModel cam;
  cam.width = width;
  cam.height = height;
  cam.fx = cam.fy = 500;
  cam.cx = width / 2.0;
  cam.cy = height / 2.0;
  const std::string path = Tmp("vimc_cam_" + std::to_string(width) + ".yaml");
  EXPECT_TRUE(vision::WriteCameraYaml(cam, path).ok());
  return path;
}

void RequireVm() {
  ASSERT_NE(std::getenv("KINCAL_IN_VM"), nullptr)
      << "runs inside the VM: ctest -R vm.libcamera_vimc";
  ASSERT_STREQ(std::getenv("KINCAL_VM_DRIVER"), "vimc");
}

std::vector<Frame> Capture(FrameSource* src, int n, std::string* error) {
  std::vector<Frame> frames;
  Frame f;
  for (int tries = 0; static_cast<int>(frames.size()) < n && tries < 4 * n; ++tries) {
    const SourceStatus st = src->Next(&f, 2000, error);
    if (st == SourceStatus::kError || st == SourceStatus::kEnd) break;
    if (st == SourceStatus::kFrame) frames.push_back(f);
  }
  return frames;
}

// A started libcamera source and its first `n` frames (fewer, with a failure, when it
// cannot start or deliver them).
std::vector<Frame> StartAndCapture(const LibcameraOptions& o, int n,
                                   std::unique_ptr<FrameSource>* src) {
  *src = MakeLibcameraSource(o);
  if (const Status s = (*src)->Start(); !s.ok()) {
    ADD_FAILURE() << s.message();
    return {};
  }
  std::string error;
  std::vector<Frame> frames = Capture(src->get(), n, &error);
  if (static_cast<int>(frames.size()) != n) {
    ADD_FAILURE() << frames.size() << " of " << n << " frames: " << error;
  }
  return frames;
}

// Media-controller V4L2 before anything configured the pipeline: the capture node's
// format does not match what the scaler sends, and the error says what is missing.
TEST(VmVimc, V4l2OnAnUnconfiguredPipelineSaysWhatIsMissing) {
  RequireVm();
  V4l2Options o;
  o.device = FindVimcNode("RGB/YUV Capture");
  ASSERT_FALSE(o.device.empty());
  o.pixel_format = PixelFormat::kBgr24;
  auto src = MakeV4l2Source(o);
  const Status s = src->Start();
  std::cout << "v4l2 on vimc, unconfigured: " << (s.ok() ? "streams" : s.message()) << "\n";
  ASSERT_FALSE(s.ok()) << "vimc's default pipeline does not produce 640x480 BGR3";
  EXPECT_NE(s.message().find("VIDIOC_STREAMON: Broken pipe: the device is one node of a "
                             "media-controller pipeline"),
            std::string::npos)
      << s.message();
}

TEST(VmVimc, LibcameraStreamsWithSensorTimestampsAndSequenceNumbers) {
  RequireVm();
  std::unique_ptr<FrameSource> src;
  const std::vector<Frame> frames = StartAndCapture(LibcameraOptions{}, 40, &src);
  ASSERT_EQ(frames.size(), 40u);
  for (size_t i = 1; i < frames.size(); ++i) {
    const Frame &a = frames[i - 1], &b = frames[i];
    EXPECT_GT(b.sequence, a.sequence);
    EXPECT_GT(b.device_utime, a.device_utime) << "sensor timestamps must increase";
    // The sensor stamp (CLOCK_MONOTONIC) comes before the frame reached us, by less than
    // a second even under TCG, and is what the pipeline clock was mapped from.
    EXPECT_LE(b.device_utime * 1000, b.arrival_mono_ns);
    EXPECT_GT(b.device_utime * 1000, b.arrival_mono_ns - kNsPerSecond);
    EXPECT_EQ(b.utime, PipelineUtime(b.device_utime * 1000));
  }
  const double span_s =
      static_cast<double>(frames.back().device_utime - frames.front().device_utime) / 1e6;
  const int64_t gaps = frames.back().sequence - frames.front().sequence - 39;
  EXPECT_EQ(src->device_drops(), gaps) << "sequence gaps are counted as device drops";
  std::cout << "libcamera on vimc: " << src->name() << "; " << 39 / span_s << " fps, " << gaps
            << " sequence gaps\n";
  src->Stop();
}

// vimc's sensor shows 75 % colour bars (white, yellow, cyan, green, magenta, red, blue,
// black). Whatever RGB order the camera negotiates, the red bar's grey is 0.299 x 191 and
// the blue bar's 0.114 x 191 (BT.601): swapped channels would exchange them.
TEST(VmVimc, TheNegotiatedFormatIsConvertedToGreyCorrectly) {
  RequireVm();
  for (const PixelFormat want : {PixelFormat::kGrey, PixelFormat::kBgr24, PixelFormat::kRgb24}) {
    LibcameraOptions o;
    o.pixel_format = want;
    std::unique_ptr<FrameSource> src;
    const std::vector<Frame> frames = StartAndCapture(o, 3, &src);
    ASSERT_EQ(frames.size(), 3u);
    const Frame& f = frames.back();
    cv::Mat grey;
    ASSERT_TRUE(ToGrey(f, &grey).ok());
    auto bar = [&](int b) {
      return static_cast<int>(grey.at<uint8_t>(f.height / 2, (2 * b + 1) * f.width / 16));
    };
    std::cout << "asked " << PixelFormatName(want) << ", got " << PixelFormatName(f.format)
              << ": bars white " << bar(0) << " red " << bar(5) << " blue " << bar(6) << " black "
              << bar(7) << "\n";
    EXPECT_NEAR(bar(0), 191, 2);
    EXPECT_NEAR(bar(5), 57, 2) << "red bar";
    EXPECT_NEAR(bar(6), 22, 2) << "blue bar";
    EXPECT_NEAR(bar(7), 0, 2);
    if (want != PixelFormat::kGrey) {
      EXPECT_EQ(f.format, want) << "vimc offers both RGB orders";
    }
    src->Stop();
  }
}

// 640x480 is adjusted to 636x480 by the pipeline (its scaler's alignment): taken, and said.
// A rate the camera cannot set is said too; one it can is honoured.
TEST(VmVimc, SizeAndRateAreHonouredOrReportedAsAdjusted) {
  RequireVm();
  LibcameraOptions o;
  o.fps = 10;
  std::unique_ptr<FrameSource> src;
  const std::vector<Frame> frames = StartAndCapture(o, 12, &src);
  ASSERT_EQ(frames.size(), 12u);
  EXPECT_EQ(frames.back().height, 480);
  const std::string name = src->name();
  if (frames.back().width != 640) {
    EXPECT_NE(name.find(std::to_string(frames.back().width) +
                        "x480, adjusted by the camera from GREY 640x480"),
              std::string::npos)
        << name;
  }
  const double fps =
      11e6 / static_cast<double>(frames.back().device_utime - frames[1].device_utime);
  std::cout << "asked 640x480 at 10 fps: " << name << "; measured " << fps << " fps\n";
  if (name.find("no frame-rate control") == std::string::npos) {
    EXPECT_NEAR(fps, 10.0, 1.0);
  }
  src->Stop();
}

// After libcamera configured the links and subdevice formats, the plain V4L2 source
// streams from the capture node at the pipeline's format.
TEST(VmVimc, V4l2StreamsOnceThePipelineIsConfigured) {
  RequireVm();
  V4l2Options o;
  o.device = FindVimcNode("RGB/YUV Capture");
  v4l2_format fmt{};
  {
    const int fd = open(o.device.c_str(), O_RDWR);
    ASSERT_GE(fd, 0);
    fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    ASSERT_EQ(ioctl(fd, VIDIOC_G_FMT, &fmt), 0);
    close(fd);
  }
  o.width = static_cast<int>(fmt.fmt.pix.width);
  o.height = static_cast<int>(fmt.fmt.pix.height);
  o.pixel_format =
      fmt.fmt.pix.pixelformat == V4L2_PIX_FMT_RGB24 ? PixelFormat::kRgb24 : PixelFormat::kBgr24;
  auto src = MakeV4l2Source(o);
  const Status s = src->Start();
  ASSERT_TRUE(s.ok()) << s.message();
  std::string error;
  const std::vector<Frame> frames = Capture(src.get(), 10, &error);
  EXPECT_EQ(frames.size(), 10u) << error;
  std::cout << "v4l2 on the configured vimc pipeline: " << frames.size() << " frames " << o.width
            << "x" << o.height << " " << PixelFormatName(o.pixel_format) << "\n";
}

std::string Kincald() {
  return (fs::read_symlink("/proc/self/exe").parent_path() / "kincald").string();
}

// The shipped config, with intrinsics for what vimc delivers and no floor file (nadir).
std::string VimcDaemonConfig() {
  const std::string src = ::kincal::testing::SourceDir() + "/config";
  std::ifstream in(src + "/kincald_libcamera.yaml");
  std::ostringstream out;
  for (std::string line; std::getline(in, line);) {
    if (line.find("intrinsics:") != std::string::npos) {
      line = "  intrinsics: " + WriteIntrinsics(636, 480);
    } else if (line.find("floor:") != std::string::npos) {
      line = "  floor: \"\"";
    } else if (line.find("layout:") != std::string::npos) {
      line = "  layout: " + src + "/target_thesis.yaml";
    } else if (line.find("  url:") != std::string::npos) {
      line = "  url: memq://";
    } else if (line.find("  path: kincal_checkpoint.json") != std::string::npos) {
      line = "  path: \"\"";
    }
    out << line << "\n";
  }
  const std::string path = Tmp("kincald_vimc.yaml");
  std::ofstream(path) << out.str();
  return path;
}

std::vector<std::pair<std::string, std::vector<uint8_t>>> Events(const std::string& path,
                                                                 const std::string& channel) {
  std::vector<std::pair<std::string, std::vector<uint8_t>>> out;
  std::unique_ptr<LcmLogReader> r;
  const Status s = LcmLogReader::Open(path, &r);
  EXPECT_TRUE(s.ok()) << s.message();
  if (!s.ok()) return out;
  LcmLogEvent ev;
  while (r->Next(&ev)) {
    if (ev.channel == channel) out.emplace_back(ev.channel, ev.data);
  }
  return out;
}

int WaitForExit(int pid, double seconds) {
  for (int i = 0; i < static_cast<int>(seconds * 10); ++i) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return -2;
}

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// True once the log kincald records at `path` holds `frames` frames of 636x480 RGB (the
// recorder flushes every record.flush_every_s), false at the deadline.
bool WaitForFrames(const std::string& path, int frames, double seconds) {
  const std::uintmax_t bytes = static_cast<std::uintmax_t>(frames) * 636 * 480 * 3;
  for (int i = 0; i < static_cast<int>(seconds * 10); ++i) {
    std::error_code ec;
    if (fs::file_size(path, ec) >= bytes && !ec) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return false;
}

// kincald with `args` (after the executable), its output to `log`; the child's pid.
pid_t StartKincald(const std::vector<std::string>& args, const std::string& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    const std::string exe = Kincald();
    std::vector<char*> argv{const_cast<char*>(exe.c_str())};
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    execv(exe.c_str(), argv.data());
    _exit(127);
  }
  return pid;
}

// `kincald --config config/kincald_libcamera.yaml --record` on vimc, then `--replay --fast`
// of that log recording again: the frames read back bit-identically and give bit-identical
// poses.
TEST(VmVimc, DaemonRecordsALogThatReplaysBitIdentically) {
  RequireVm();
  const std::string cfg = VimcDaemonConfig(), live = Tmp("vimc_live.lcm"),
                    again = Tmp("vimc_replayed.lcm");
  // Live until 15 frames are on disk (a condition, not a time: a loaded machine starts
  // slower), then SIGINT.
  const pid_t pid = StartKincald({"--config", cfg, "--record", live}, Tmp("live.txt"));
  EXPECT_TRUE(WaitForFrames(live, 15, 60)) << Slurp(Tmp("live.txt"));
  kill(pid, SIGINT);
  EXPECT_EQ(WaitForExit(pid, 60), 0) << Slurp(Tmp("live.txt"));
  const std::string replay = Kincald() + " --config " + cfg + " --replay " + live +
                             " --fast --record " + again + " -q > " + Tmp("replay.txt") + " 2>&1";
  EXPECT_EQ(std::system(replay.c_str()), 0) << replay;
  const auto frames = Events(live, "KINCAL_FRAME"), replayed = Events(again, "KINCAL_FRAME");
  EXPECT_GT(frames.size(), 10u);
  ASSERT_EQ(frames.size(), replayed.size());
  for (size_t i = 0; i < frames.size(); ++i) ASSERT_EQ(frames[i].second, replayed[i].second) << i;
  // Live, a frame may be dropped by the full frame queue after it was recorded (counted);
  // replay is lossless. Every live pose is in the replay, bit-identical.
  auto by_time = [](const auto& events) {
    std::map<int64_t, std::vector<uint8_t>> m;
    for (const auto& [channel, data] : events) {
      kincal::pose_t p;
      if (p.decode(data.data(), 0, static_cast<int>(data.size())) > 0) m[p.utime] = data;
    }
    return m;
  };
  const auto live_poses = by_time(Events(live, "KINCAL_POSE"));
  const auto replay_poses = by_time(Events(again, "KINCAL_POSE"));
  EXPECT_EQ(replay_poses.size(), frames.size()) << "a pose for every frame in replay";
  // Live, the frames the full queue dropped (its policy under load) are counted in the
  // summary line ("N frames (... D by the queue ..."); every other frame gave a pose.
  const std::string summary = Slurp(Tmp("live.txt"));
  const size_t line = summary.rfind(" frames (");
  ASSERT_NE(line, std::string::npos) << summary;
  const size_t by_queue = summary.find(" by the queue", line);
  ASSERT_NE(by_queue, std::string::npos) << summary;
  const size_t num = summary.rfind(' ', by_queue - 1);
  const size_t dropped = std::stoul(summary.substr(num + 1, by_queue - num - 1));
  EXPECT_GE(live_poses.size() + dropped, frames.size()) << summary;
  EXPECT_GT(live_poses.size(), 0u);
  for (const auto& [utime, data] : live_poses) {
    ASSERT_TRUE(replay_poses.count(utime)) << utime;
    EXPECT_EQ(replay_poses.at(utime), data) << utime;
  }
  std::cout << frames.size() << " frames and " << live_poses.size()
            << " live poses read back bit-identically\n";
}

// Another process streaming from the camera: kincald's source fails at start with a
// message that says the camera is taken.
TEST(VmVimc, ASecondProcessHoldingTheCameraGetsAClearError) {
  RequireVm();
  const std::string cmd = "sh -c '" + Kincald() + " --config " + VimcDaemonConfig() + " -q > " +
                          Tmp("holder.txt") + " 2>&1 & echo $!'";
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  int pid = 0;
  ASSERT_EQ(fscanf(p, "%d", &pid), 1);
  pclose(p);
  // Streaming once it has the capture node open.
  const std::string node = FindVimcNode("RGB/YUV Capture");
  bool holding = false;
  for (int i = 0; i < 200 && !holding; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    std::error_code ec;
    for (const auto& e : fs::directory_iterator("/proc/" + std::to_string(pid) + "/fd", ec)) {
      if (fs::read_symlink(e.path(), ec).string() == node) holding = true;
    }
  }
  ASSERT_TRUE(holding) << "the first kincald never opened " << node;
  auto src = MakeLibcameraSource(LibcameraOptions{});
  const Status s = src->Start();
  kill(pid, SIGINT);
  for (int i = 0; i < 100 && kill(pid, 0) == 0; ++i) {  // gone before the next test
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  std::cout << "second process: " << s.message() << "\n";
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("in use by another process"), std::string::npos) << s.message();
}

// The driver is unbound mid-stream (as when a camera is pulled): kincald reports it and,
// as libcamera cannot release a vanished camera, ends with the error (rc 1; its final
// checkpoint is written when it has an estimate: none here, without controls), and lets go
// of the device so the module unloads. When the module is back, kincald restarted as its
// supervisor would (--resume-if-present) captures again.
TEST(VmVimc, TheDriverIsUnboundAndTheCameraComesBack) {
  RequireVm();
  const char* modules = std::getenv("KINCAL_VM_MODULES");
  ASSERT_NE(modules, nullptr);
  const std::string cfg = VimcDaemonConfig(), ck = Tmp("vimc_ck.json"), log1 = Tmp("run1.txt");
  // Each run records its frames: a condition to wait for (frames on disk), not a time.
  auto start = [&](const std::string& log, const std::string& record) {
    return StartKincald(
        {"--config", cfg, "--checkpoint", ck, "--resume-if-present", "--record", record}, log);
  };
  const pid_t first = start(log1, Tmp("run1.lcm"));
  ASSERT_TRUE(WaitForFrames(Tmp("run1.lcm"), 12, 60)) << Slurp(log1);
  {
    std::ofstream unbind("/sys/bus/platform/drivers/vimc/unbind");
    unbind << "vimc.0";
    ASSERT_TRUE(unbind.good()) << "cannot unbind vimc.0";
  }
  const int rc = WaitForExit(first, 60);
  const std::string out1 = Slurp(log1);
  EXPECT_EQ(rc, 1) << out1;
  EXPECT_NE(out1.find("the camera's device vanished"), std::string::npos) << out1;
  EXPECT_EQ(std::system("/usr/sbin/rmmod vimc"), 0) << "kincald let go of the device";
  const std::string insmod = std::string("/usr/sbin/insmod ") + modules + "/vimc.ko";
  ASSERT_EQ(std::system(insmod.c_str()), 0) << insmod;
  ASSERT_EQ(std::system("udevadm settle --timeout=20"), 0);
  const std::string log2 = Tmp("run2.txt");
  const pid_t second = start(log2, Tmp("run2.lcm"));
  EXPECT_TRUE(WaitForFrames(Tmp("run2.lcm"), 12, 60)) << Slurp(log2);
  kill(second, SIGINT);
  EXPECT_EQ(WaitForExit(second, 60), 0);
  const std::string out2 = Slurp(log2);
  int frames = 0;
  const size_t summary = out2.rfind(" frames (");
  if (summary != std::string::npos) {
    size_t b = out2.rfind(' ', summary - 1);
    frames = std::atoi(out2.substr(b + 1, summary - b - 1).c_str());
  }
  EXPECT_GT(frames, 10) << out2;
  std::cout << "camera lost: kincald ended with rc " << rc << "; restarted after the module came "
            << "back: " << frames << " frames\n";
}

}  // namespace
}  // namespace kincal::daemon
