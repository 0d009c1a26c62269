// The frame sources kincald can run from, and the vision set-up they share.
#pragma once

#include <functional>
#include <memory>

#include "daemon/frame_source.h"
#include "kincal/daemon/config.h"
#include "kincal/vision/camera.h"
#include "kincal/vision/pose.h"
#include "kincal/vision/target.h"

namespace kincal::daemon {

// Camera intrinsics, floor extrinsics and target layout from a config (defaults: a
// 640x480 f = 500 px camera looking straight down). Throws naming the file at fault.
struct VisionSetup {
  vision::CameraModel camera;
  vision::FloorExtrinsics floor;
  vision::TargetLayout layout;
  double target_height_m = 0.0;  // the target plane above the floor
};
// The camera, floor and target files the config names (defaults where it names none); an
// error names the file.
StatusOr<VisionSetup> LoadVisionSetup(const DaemonConfig& c);

// Sources that also carry the robot's controls (simulation, replay) hand each message
// over as the raw kincal.controls_t bytes with the host time it was received.
using ControlIntake = std::function<void(const void* data, size_t n, int64_t receive_utime)>;
// A log without frames hands each logged measurement over as the raw kincal.pose_t bytes;
// `utime_shift` is to be added to its stamps (a looped replay's later passes).
using PoseIntake = std::function<void(const void* data, size_t n, int64_t utime_shift)>;
// Publishes raw bytes on the network, and into the recording when `log_utime` is not
// kNetworkOnly (the simulated robot's controls go to the network only: they are recorded
// where they are received; its truth goes to both).
inline constexpr int64_t kNetworkOnly = -1;
using NetworkPublish =
    std::function<void(const std::string& channel, const void* data, size_t n, int64_t log_utime)>;

// The simulated camera: renders the scenario's robot (true parameters, hidden effects)
// carrying the target, and publishes the robot's commands like a robot would, and with
// every frame the truth (kincal.truth_t on truth_channel, network and recording). A run
// ends when the target nears the image edge; the robot is then carried back to the
// centre (no target in view for sim.carry_s) and starts a new run. The robot drives the
// scenario's random controls, or with `drive` (guidance.drive) legs planned from the
// running estimate (daemon/drive_link.h), each followed by drive_pause_s at rest.
struct SimSourceOptions {
  SimOptions sim;
  std::string robot_model;                     // the config's robot.model: must be the scenario's
  std::string controls_channel;                // where the simulated robot publishes its commands
  std::string truth_channel = "KINCAL_TRUTH";  // lcm.truth_channel
  std::string config_file;                     // named in errors
  double drive_pause_s = 0.5;                  // guidance.drive_pause_s
};
class DriveLink;
// An error names the scenario file and what does not fit the config.
StatusOr<std::unique_ptr<FrameSource>> MakeSimSource(const SimSourceOptions& o,
                                                     const VisionSetup& v, ControlIntake controls,
                                                     NetworkPublish publish,
                                                     DriveLink* drive = nullptr);
// An LCM log written by `kincald --record`: frames on lcm.frame_channel, controls on
// lcm.controls_channel (other channels are skipped and counted). A log with no frames
// (motion capture from `kincal import`, a recording made without them) is replayed from
// its poses on lcm.pose_channel instead, each handed to `poses` in log order with the
// controls; Start() says which, and a log with neither is an error naming it.
std::unique_ptr<FrameSource> MakeReplaySource(const ReplayOptions& replay, const LcmOptions& lcm,
                                              ControlIntake controls, PoseIntake poses = nullptr);
// Video4Linux2 capture device, mmap streaming.
std::unique_ptr<FrameSource> MakeV4l2Source(const V4l2Options& o);
// libcamera camera.
std::unique_ptr<FrameSource> MakeLibcameraSource(const LibcameraOptions& o);

// The source the config names (source: sim | v4l2 | libcamera | replay). `controls` and
// `publish` are used by the sources that carry the robot's controls (sim, replay), `drive`
// by the simulated camera (guidance.drive; null: the scenario's controls), `poses` by the
// replay of a log without frames. Devices and files are opened by Start(); the simulated
// camera's scenario is read here.
StatusOr<std::unique_ptr<FrameSource>> MakeSource(const DaemonConfig& c, const VisionSetup& v,
                                                  ControlIntake controls, NetworkPublish publish,
                                                  DriveLink* drive = nullptr,
                                                  PoseIntake poses = nullptr);

// The clocks (kincal/time.h):
//   host realtime   CLOCK_REALTIME now, in us; it steps with NTP (health messages only);
//   monotonic       CLOCK_MONOTONIC in ns (latency, pacing, timeouts);
//   pipeline utime  CLOCK_MONOTONIC mapped onto the realtime epoch by an offset measured
//                   once per process, in us: frame and receive stamps. It reads as
//                   realtime, but an NTP step does not move it against the frames.
int64_t RealtimeUtime();
TimeNs MonotonicNs();
int64_t PipelineUtime(TimeNs mono_ns);

}  // namespace kincal::daemon
