// kincald configuration: one struct per YAML section, mapped one to one (config/kincald_*.yaml
// are the documented examples). ReadDaemonConfig rejects unknown keys and wrong types
// naming the file and line; IsValid() checks values and cross-section consistency.
// Relative paths in a config file are relative to that file's directory.
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include "kincal/daemon/frame.h"
#include "kincal/online/filter_options.h"
#include "kincal/status.h"
#include "kincal/vision/markers.h"

namespace kincal::daemon {

// The choices a config makes, parsed once from their names (the names are what the YAML
// files and messages use: SourceName(kV4l2) is "v4l2").
enum class SourceKind { kSim, kV4l2, kLibcamera, kReplay };
enum class PoseMethod { kGroundPlane, kLowe };  // ground_plane | lowe
// receive | sender | mapped (the sender's stamps mapped onto the receive clock, see
// src/daemon/control_clock.h; the receive stamp for a message without sender_utime)
enum class ControlStamp { kReceive, kSender, kMapped };
// raw | png | jpeg (grey frames recorded as PNG, lossless, or JPEG, quality 95, which
// replays as MJPG; frames the camera delivered in another format are recorded raw)
enum class FrameEncoding { kRaw, kPng, kJpeg };
std::string_view SourceName(SourceKind k);
std::string_view PoseMethodName(PoseMethod m);
std::string_view ControlStampName(ControlStamp s);
std::string_view FrameEncodingName(FrameEncoding e);

struct LcmOptions {
  std::string url;  // empty: LCM's default (LCM_DEFAULT_URL or udpm://239.255.76.67:7667?ttl=0)
  std::string controls_channel = "KINCAL_CONTROLS";
  std::string pose_channel = "KINCAL_POSE";
  std::string params_channel = "KINCAL_PARAMS";
  std::string health_channel = "KINCAL_HEALTH";
  std::string model_check_channel = "KINCAL_MODEL_CHECK";
  std::string guidance_channel = "KINCAL_GUIDANCE";
  std::string calibration_channel = "KINCAL_CALIBRATION";  // the batch tier's calibration_t
  std::string markers_channel = "KINCAL_MARKERS";
  std::string frame_channel = "KINCAL_FRAME";
  std::string preview_channel = "KINCAL_PREVIEW";  // preview.enabled: downscaled JPEG frames
  std::string truth_channel = "KINCAL_TRUTH";      // source sim: the simulated robot's truth
  bool publish_frames = false;  // frames go to the log; on the network only if asked
  bool publish_markers = true;
  bool IsValid(std::string* error) const;
};

struct V4l2Options {
  std::string device = "/dev/video0";
  int width = 640, height = 480;
  PixelFormat pixel_format = PixelFormat::kGrey;  // GREY, YUYV, MJPG
  double fps = 30.0;
  int buffers = 4;
  std::map<std::string, long long>
      controls;  // V4L2 control name (lower case, '_' for ' ') -> value
  bool IsValid(std::string* error) const;
};

struct LibcameraOptions {
  std::string camera;  // id; empty: the first camera
  int width = 640, height = 480;
  // GREY (R8), YUYV, MJPG, BGR3 (RGB888), RGB3 (BGR888)
  PixelFormat pixel_format = PixelFormat::kGrey;
  int buffers = 4;
  // Frames per second asked of the camera (its FrameDurationLimits control); 0: the
  // camera's own. A camera without the control runs at its own rate, and says so.
  double fps = 0.0;
  bool IsValid(std::string* error) const;
};

// The longest simulated run (s): 30 days. The run is simulated in chunks, so its length
// does not bound memory; the limit keeps times well inside int64 nanoseconds and double
// seconds (sub-nanosecond resolution).
inline constexpr double kMaxSimDurationS = 30.0 * 86400.0;

struct SimOptions {
  std::string scenario = "sim_diffdrive.yaml";  // robot, truth, controls (as `kincal simulate`)
  double speed = 1.0;       // simulated seconds per wall-clock second; <= 0: as fast as possible
  double duration_s = 0.0;  // 0: the scenario's
  // The run is simulated this many seconds at a time: memory holds one chunk of commands
  // and frame times (rates x chunk_s), whatever the duration. A run no longer than one
  // chunk is drawn exactly as a whole.
  double chunk_s = 300.0;
  double margin_px = 40.0;  // a run ends when the target comes this close to the image edge
  double carry_s = 1.0;     // the robot is carried back to the centre (no target in view)
  double noise_grey = 2.0;  // image noise, grey levels
  // false: the simulated robot hands its controls to the filter directly (and publishes
  // them); true: they reach the filter only through LCM, like a real robot's.
  bool controls_via_lcm = false;
  // Where the simulated robot publishes its commands; empty: lcm.controls_channel. Another
  // channel stands for a robot whose driver forwards them to kincald (a bridge such as
  // scripts/kincal_controls.py; tests of that path).
  std::string controls_channel;
  // Measurement faults, per frame: a marker-like reflection near the target, one marker
  // hidden (a wrong marker count).
  double reflection_prob = 0.0;
  double occlusion_prob = 0.0;
  uint64_t seed = 0;  // 0: the scenario's seed
  bool IsValid(std::string* error) const;
};

struct ReplayOptions {
  std::string path;
  double speed = 1.0;  // 0: --fast (as fast as possible, nothing dropped, deterministic)
  int loops = 1;       // play the log this many times, each later by the log's span (soak tests)
  // A log without frames (motion capture imported by `kincal import`, or a recording made
  // without them) is replayed from its poses. A logged pose whose covariance is not
  // positive definite (PoseStamped has none: imported as zeros) is given this one-sigma
  // noise (m, m, rad) instead.
  std::array<double, 3> pose_sigma{0.002, 0.002, 0.01};
  bool IsValid(std::string* error) const;
};

struct CameraOptions {
  std::string intrinsics;       // OpenCV camera YAML; empty: 640x480, f = 500 px (simulation)
  std::string floor;            // floor extrinsics from `kincal floorcal`; empty: nadir camera
  double nadir_height_m = 2.0;  // used when `floor` is empty
  bool IsValid(std::string* error) const;
};

struct TargetOptions {
  std::string layout;      // target YAML; empty: the thesis plate
  double height_m = 0.05;  // target plane above the floor
  bool IsValid(std::string* error) const;
};

struct PoseOptions {
  // ground_plane (x, y, theta) | lowe (6-DoF, then onto the floor)
  PoseMethod method = PoseMethod::kGroundPlane;
  double sigma_px = 0.05;   // marker centre noise, px
  double max_rms_px = 2.0;  // poses fitting worse are published invalid
  bool IsValid(std::string* error) const;
};

struct RobotOptions {
  std::string model = "diffdrive";
  std::vector<std::string> effects;     // declared
  bool auto_effects = false;            // "auto": add effects online when the check is decisive
  std::map<std::string, double> guess;  // initial parameter values (default: model defaults)
  // Model parameters held at a known value (a measured dimension): not estimated by the
  // filter or the batch tier (kincal analyze --fix).
  std::map<std::string, double> fixed;
  double guess_sigma_fraction = 0.2;
  ControlStamp control_stamp = ControlStamp::kMapped;
  double max_control_delay_s = 0.1;  // a pose waits this long for the controls up to its time
  bool IsValid(std::string* error) const;
};

struct QueueOptions {
  int frames = 4;       // capture -> detection (live: drop oldest; --fast: block)
  int poses = 64;       // detection -> filter (live: drop oldest; --fast: block)
  int controls = 1024;  // LCM -> filter (live: drop oldest; --fast: block)
  int recorder = 4096;  // everything -> log writer (live: drop newest, counted as lost)
  bool IsValid(std::string* error) const;
};

struct RecordOptions {
  std::string path;  // empty: no recording
  FrameEncoding frame_encoding = FrameEncoding::kRaw;
  double flush_every_s = 1.0;
  bool IsValid(std::string* error) const;
};

struct CheckpointOptions {
  std::string path;  // empty: none
  double every_s = 10.0;
  std::string resume;  // checkpoint to start from (--resume)
  bool IsValid(std::string* error) const;
};

// The batch tier (the daemon's calibration): every every_s of data time (the first once
// the run spans first_s, and once more at shutdown) the run's poses and controls are fitted
// as `kincal analyze` fits them, on a worker thread, and published as kincal.calibration_t
// on lcm.calibration_channel. The store keeps max_poses / max_controls at most (thinned
// evenly over the run in blocks of block_s when full): memory is bounded by these.
struct CalibrationOptions {
  bool enabled = true;
  double every_s = 60.0;
  double first_s = 30.0;
  // A batch refits everything, so batches are spaced by at least this fraction of the
  // span already fitted: a run of length T costs O(log T) batches, not O(T) (a --fast
  // replay of hours waits for each). 0: every every_s regardless.
  double growth = 0.25;
  // The fit's threads, 0: one per core (they run below the pipeline's priority, so the
  // frames keep theirs); the result does not depend on it.
  int threads = 0;
  int max_effects = 4;         // robot.effects: auto: effects the selection may accept
  int max_poses = 108'000;     // 1 h at 30 Hz
  int max_controls = 432'000;  // 1 h at 120 Hz
  double block_s = 4.0;
  bool IsValid(std::string* error) const;
};

// What the camera sees, for people (kincal view, Foxglove): every 1/rate_hz of frame time
// the detection thread's grey image, downscaled by the smallest whole factor that fits
// `width` and JPEG-encoded at `quality` on a worker thread, as a kincal.preview_t on
// lcm.preview_channel and in the recording. Off by default. The defaults (320 px: a
// 1280x960 or 640x480 camera gives 320x240) cost about 2 % of the pose stage's CPU at
// 1280x960 and 30 Hz; 480 (426 px) 3.6 %, 640 4.8 % (bench/RESULTS.md).
struct PreviewOptions {
  bool enabled = false;
  double rate_hz = 5.0;
  int width = 320;
  int quality = 80;
  bool IsValid(std::string* error) const;
};

// Online guidance: every every_s of data time the running estimate is handed to a worker
// thread that answers what `kincal plan --advise` answers (kincal/plan/advice.h) and
// publishes it as kincal.guidance_t on lcm.guidance_channel.
struct GuidanceOptions {
  bool enabled = false;
  double every_s = 5.0;    // data time between pieces of advice
  double horizon_s = 3.0;  // how long the advised motion is held
  // <control>: max |command|, accel / accel_<control>: per second, curvature: 1/m (as
  // `kincal plan --limits`); every control needs one when enabled.
  std::map<std::string, double> limits;
  // <parameter>: target sigma (as `kincal plan --targets`); empty: every parameter, scored
  // against its current sigma, and no time to target.
  std::map<std::string, double> targets;
  std::vector<double> pose_sigma = {0.002, 0.002, 0.005};  // m, m, rad
  double pose_rate_hz = 15.0;
  // With source: sim, the simulated robot drives legs planned from the running estimate
  // (horizon_s each, kept in the camera's view with sim.margin_px), resting
  // drive_pause_s after each; the next leg is planned from an estimate made at rest.
  bool drive = false;
  double drive_pause_s = 0.5;
  bool IsValid(std::string* error) const;
};

struct DaemonConfig {
  std::string file;  // where it was read from ("" for defaults)
  SourceKind source = SourceKind::kSim;
  LcmOptions lcm;
  V4l2Options v4l2;
  LibcameraOptions libcamera;
  SimOptions sim;
  ReplayOptions replay;
  CameraOptions camera;
  TargetOptions target;
  vision::DetectorOptions detector;
  PoseOptions pose;
  RobotOptions robot;
  FilterOptions filter;
  QueueOptions queues;
  RecordOptions record;
  CheckpointOptions checkpoint;
  CalibrationOptions calibration;
  GuidanceOptions guidance;
  PreviewOptions preview;
  double health_rate_hz = 1.0;
  double no_target_warn_s = 5.0;  // health is not ok after this long (frame time) without target
  // Every section, then what ties sections together; false with *error naming the
  // section.key and what is expected. Only the sections the source uses are checked.
  bool IsValid(std::string* error) const;
};

// The config file, or an error naming file:line and the offending key. Values and
// cross-section consistency are DaemonConfig::IsValid's (Daemon::Create checks them).
StatusOr<DaemonConfig> ReadDaemonConfig(const std::string& path);

// Every key a config file may hold ("section.key"), in the loaders' order, with its default
// as YAML writes it (a choice lists its names): what `kincald --config-keys` prints and
// docs/config_keys.md holds. The loaders are the one list of the keys.
struct ConfigKey {
  std::string key;
  std::string default_value;
};
std::vector<ConfigKey> DaemonConfigKeys();

}  // namespace kincal::daemon
