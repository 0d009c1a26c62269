// Shared pieces of the frame sources: clocks and the vision set-up.
#include "daemon/sources.h"

#include <time.h>

#include <stdexcept>

#include "kincal/online/samples.h"
#include "kincal/vision/setup_files.h"

namespace kincal::daemon {

int64_t RealtimeUtime() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
}

TimeNs MonotonicNs() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<TimeNs>(ts.tv_sec) * kNsPerSecond + ts.tv_nsec;
}

int64_t PipelineUtime(TimeNs mono_ns) {
  // Offset realtime - monotonic, measured once (the tightest of a few readings). Later
  // steps of the realtime clock (NTP) do not move the pipeline's time base.
  static const int64_t offset_ns = [] {
    int64_t best = 0, best_span = INT64_MAX;
    for (int i = 0; i < 5; ++i) {
      const TimeNs a = MonotonicNs();
      timespec rt{};
      clock_gettime(CLOCK_REALTIME, &rt);
      const TimeNs b = MonotonicNs();
      const int64_t rt_ns = static_cast<int64_t>(rt.tv_sec) * kNsPerSecond + rt.tv_nsec;
      if (b - a < best_span) {
        best_span = b - a;
        best = rt_ns - (a + (b - a) / 2);
      }
    }
    return best;
  }();
  return (mono_ns + offset_ns) / 1000;
}

StatusOr<std::unique_ptr<FrameSource>> MakeSource(const DaemonConfig& c, const VisionSetup& v,
                                                  ControlIntake controls, NetworkPublish publish,
                                                  DriveLink* drive, PoseIntake poses) {
  switch (c.source) {
    case SourceKind::kSim:
      return MakeSimSource(
          {c.sim, c.robot.model,
           c.sim.controls_channel.empty() ? c.lcm.controls_channel : c.sim.controls_channel,
           c.lcm.truth_channel, c.file, c.guidance.drive_pause_s},
          v, std::move(controls), std::move(publish), drive);
    case SourceKind::kReplay:
      return MakeReplaySource(c.replay, c.lcm, std::move(controls), std::move(poses));
    case SourceKind::kV4l2:
      return MakeV4l2Source(c.v4l2);
    case SourceKind::kLibcamera:
      return MakeLibcameraSource(c.libcamera);
  }
  return Status::Error("unknown source kind");  // unreachable: each is handled above
}

StatusOr<VisionSetup> LoadVisionSetup(const DaemonConfig& c) {
  VisionSetup v;
  if (c.camera.intrinsics.empty()) {
    v.camera = vision::CameraModel::Centred(640, 480, 500.0);
  } else {
    StatusOr<vision::CameraModel> camera = vision::ReadCameraYaml(c.camera.intrinsics);
    if (!camera.ok()) return camera.status();
    v.camera = std::move(camera).value();
  }
  if (c.camera.floor.empty()) {
    v.floor = vision::NadirFloor(c.camera.nadir_height_m);
  } else {
    StatusOr<vision::FloorExtrinsics> floor = vision::ReadFloorYaml(c.camera.floor);
    if (!floor.ok()) return floor.status();
    v.floor = std::move(floor).value();
  }
  StatusOr<vision::TargetLayout> layout = vision::ReadTargetLayoutYaml(c.target.layout);
  if (!layout.ok()) return layout.status();
  v.layout = std::move(layout).value();
  v.target_height_m = c.target.height_m;
  if (static_cast<int>(v.layout.markers.size()) > kMaxMarkers) {
    return Status::Error(c.target.layout + ": at most " + std::to_string(kMaxMarkers) +
                         " markers per target");
  }
  return v;
}

}  // namespace kincal::daemon
