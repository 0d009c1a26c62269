// kincald's preview against the pose stage it must not slow (issue 35: <= 3 % of the pose
// stage's CPU at 1280x960): one frame of a 1280x960 JPEG recording of the simulated robot
// through PoseStage::Process (decode, markers, pose), and one preview of the same frames
// (the copy the detection thread makes, the worker's downscale to preview.width and JPEG),
// both as process CPU per frame. bench_report.py turns them into the share at the default
// rates (30 Hz frames, preview.rate_hz previews).
#include <benchmark/benchmark.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <filesystem>
#include <kincal/frame_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

#include "daemon/pose_stage.h"
#include "daemon/preview.h"
#include "daemon/sources.h"
#include "kincal/daemon/config.h"
#include "kincal/daemon/daemon.h"
#include "kincal/vision/camera.h"

namespace kincal::daemon {
namespace {

struct Recorded {
  DaemonConfig config;
  std::vector<Frame> frames;
};

// 2 s of the simulated robot seen by a 1280x960 camera (f = 1000 px), frames as JPEG.
const Recorded& Recording1280() {
  static const Recorded r = [] {
    spdlog::set_level(spdlog::level::warn);
    const auto dir = std::filesystem::temp_directory_path();
    const std::string stem = "kincal_bench_preview_" + std::to_string(::getpid());
    Recorded out;
    DaemonConfig& c = out.config;
    c = ReadDaemonConfig(std::string(KINCAL_SOURCE_DIR) + "/config/kincald_sim.yaml").value();
    c.lcm.url = "memq://";
    const vision::CameraModel cam = vision::CameraModel::Centred(1280, 960, 1000.0);
    c.camera.intrinsics = (dir / (stem + ".yaml")).string();
    if (!vision::WriteCameraYaml(cam, c.camera.intrinsics).ok()) return out;
    c.sim.speed = 0;
    c.sim.duration_s = 2;
    c.record.path = (dir / (stem + ".lcm")).string();
    c.record.frame_encoding = FrameEncoding::kJpeg;
    {
      const std::unique_ptr<Daemon> d_owner = Daemon::Create(c).value();
      Daemon& d = *d_owner;
      d.Run();
    }
    lcm::LogFile log(c.record.path, "r");
    while (const lcm::LogEvent* ev = log.readNextEvent()) {
      kincal::frame_t m;
      if (ev->channel != c.lcm.frame_channel || m.decode(ev->data, 0, ev->datalen) < 0) continue;
      Frame f;
      f.data = m.data;
      f.width = m.width;
      f.height = m.height;
      f.stride = m.stride;
      f.format = ParsePixelFormat(m.pixel_format).value();
      f.utime = m.utime;
      f.sequence = m.sequence;
      out.frames.push_back(std::move(f));
    }
    std::filesystem::remove(c.record.path);
    c.record.path.clear();
    return out;
  }();
  return r;
}

void BM_PoseStageFrame1280(benchmark::State& state) {
  const Recorded& r = Recording1280();
  if (r.frames.empty()) {
    state.SkipWithError("no recording");
    return;
  }
  const VisionSetup vis = LoadVisionSetup(r.config).value();
  PoseStage stage(r.config.pose, r.config.detector, vis);
  PoseSample p;
  std::string error;
  size_t i = 0, valid = 0;
  for (auto _ : state) {
    if (stage.Process(r.frames[i % r.frames.size()], &p, &error) && p.valid) ++valid;
    ++i;
  }
  state.counters["valid_fraction"] = static_cast<double>(valid) / static_cast<double>(i);
}
BENCHMARK(BM_PoseStageFrame1280)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

void BM_PreviewFrame1280(benchmark::State& state) {
  const Recorded& r = Recording1280();
  if (r.frames.empty()) {
    state.SkipWithError("no recording");
    return;
  }
  std::vector<cv::Mat> grey(r.frames.size());
  for (size_t k = 0; k < grey.size(); ++k) (void)ToGrey(r.frames[k], &grey[k]);
  Publisher pub;
  LcmOptions lcm_opt;
  lcm_opt.url = "memq://";
  if (!pub.Open(lcm_opt, RecordOptions{}, 16, true).ok()) {
    state.SkipWithError("no LCM");
    return;
  }
  PreviewOptions o;  // the defaults but the width (the argument), every frame due
  o.rate_hz = 30;
  o.width = static_cast<int>(state.range(0));
  PreviewStage preview(o, "PREVIEW", &pub, /*lossless=*/true);
  int64_t i = 0;
  for (auto _ : state) {
    preview.Offer(grey[static_cast<size_t>(i) % grey.size()], 1'000'000 + i * 33'334, i);
    preview.Drain();
    while (pub.lcm()->handleTimeout(0) > 0) {  // memq keeps what nobody handled
    }
    ++i;
  }
  state.counters["published"] = static_cast<double>(preview.published());
  state.counters["default_rate_hz"] = PreviewOptions{}.rate_hz;
  state.counters["default_width"] = PreviewOptions{}.width;
}
BENCHMARK(BM_PreviewFrame1280)
    ->Arg(640)
    ->Arg(480)  // 426 px wide
    ->Arg(320)  // the default
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime();

}  // namespace
}  // namespace kincal::daemon
