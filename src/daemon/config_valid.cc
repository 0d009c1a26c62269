// kincald configuration: the checks of every options struct and of the whole config
// (loading is in config.cc).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "kincal/daemon/config.h"
#include "kincal/estimation/filter.h"
#include "kincal/model.h"
#include "kincal/plan/planner.h"
#include "kincal/system.h"

namespace kincal::daemon {

namespace {

// Sets *error to `what` and returns false when !ok (for chains of checks).
bool Expect(bool ok, const std::string& what, std::string* error) {
  if (!ok) *error = what;
  return ok;
}

// guidance.limits and guidance.targets name the robot's controls and parameters.
bool GuidanceFitsTheRobot(const DaemonConfig& c, std::string* error) {
  if (!c.guidance.enabled) {
    return Expect(!c.guidance.drive, "guidance.drive needs guidance.enabled: true", error);
  }
  if (c.guidance.drive && c.source != SourceKind::kSim) {
    *error =
        "guidance.drive needs source: sim (only the simulated robot can follow the plan; a "
        "replayed drive run is replayed with drive: false and gives the same estimates)";
    return false;
  }
  // An estimate must come while the robot rests: two params_t periods at least.
  if (c.guidance.drive && c.filter.params_rate_hz > 0 &&
      c.guidance.drive_pause_s < 2.0 / c.filter.params_rate_hz) {
    *error = "guidance.drive_pause_s must be at least two filter.params_rate_hz periods (" +
             std::to_string(2.0 / c.filter.params_rate_hz) + " s)";
    return false;
  }
  std::unique_ptr<System> sys;
  if (!MakeSystem(c.robot.model, c.robot.effects, {}, &sys).ok()) return true;  // robot's error
  PlanOptions o;
  if (const Status s = PlanLimitsFrom(*sys, c.guidance.limits, c.guidance.targets, &o); !s.ok()) {
    *error = "guidance." + s.message();
    return false;
  }
  return true;
}

}  // namespace

bool LcmOptions::IsValid(std::string* error) const {
  for (const auto* ch : {&controls_channel, &pose_channel, &params_channel, &health_channel,
                         &model_check_channel, &markers_channel, &frame_channel, &guidance_channel,
                         &calibration_channel, &preview_channel, &truth_channel}) {
    if (!Expect(!ch->empty() && ch->size() < 64, "lcm channel names must be 1..63 characters",
                error)) {
      return false;
    }
  }
  return true;
}

bool V4l2Options::IsValid(std::string* error) const {
  return Expect(width > 0 && height > 0, "v4l2.width/height must be > 0", error) &&
         Expect(fps > 0, "v4l2.fps must be > 0", error) &&
         Expect(buffers >= 4 && buffers <= 32, "v4l2.buffers must be 4..32", error) &&
         Expect(pixel_format != PixelFormat::kPng,
                "v4l2.pixel_format must be GREY, YUYV, MJPG, BGR3 or RGB3 (got '" +
                    std::string(PixelFormatName(pixel_format)) + "')",
                error);
}

bool LibcameraOptions::IsValid(std::string* error) const {
  return Expect(width > 0 && height > 0, "libcamera.width/height must be > 0", error) &&
         Expect(buffers >= 2 && buffers <= 32, "libcamera.buffers must be 2..32", error) &&
         Expect(fps >= 0 && fps <= 1000, "libcamera.fps must be in [0, 1000] (0: the camera's)",
                error) &&
         Expect(pixel_format != PixelFormat::kPng,
                "libcamera.pixel_format must be GREY, YUYV, MJPG, BGR3 or RGB3", error);
}

bool SimOptions::IsValid(std::string* error) const {
  return Expect(!scenario.empty(), "sim.scenario must name a scenario file", error) &&
         Expect(duration_s >= 0 && margin_px >= 0 && carry_s >= 0 && noise_grey >= 0,
                "sim.duration_s, margin_px, carry_s, noise_grey must be >= 0", error) &&
         Expect(duration_s <= kMaxSimDurationS,
                "sim.duration_s must be at most " +
                    std::to_string(static_cast<int64_t>(kMaxSimDurationS)) +
                    " s (30 days); 0 takes the scenario's",
                error) &&
         Expect(chunk_s >= 1.0 && chunk_s <= 3600.0, "sim.chunk_s must be in [1, 3600] s", error) &&
         Expect(speed >= 0, "sim.speed (or --speed) must be >= 0 (0: --fast)", error) &&
         Expect(reflection_prob >= 0 && reflection_prob <= 1 && occlusion_prob >= 0 &&
                    occlusion_prob <= 1,
                "sim.reflection_prob and occlusion_prob must be in [0, 1]", error) &&
         Expect(controls_channel.size() < 64,
                "sim.controls_channel must be at most 63 characters (empty: "
                "lcm.controls_channel)",
                error);
}

bool ReplayOptions::IsValid(std::string* error) const {
  return Expect(!path.empty(), "replay.path (or --replay FILE) must name an LCM log", error) &&
         Expect(speed >= 0, "replay.speed (or --speed) must be >= 0 (0: --fast)", error) &&
         Expect(loops >= 1, "replay.loops must be >= 1", error) &&
         Expect(std::all_of(pose_sigma.begin(), pose_sigma.end(),
                            [](double v) { return std::isfinite(v) && v > 0; }),
                "replay.pose_sigma must be 3 finite values > 0 (m, m, rad)", error);
}

bool CameraOptions::IsValid(std::string* error) const {
  return Expect(nadir_height_m > 0, "camera.nadir_height_m must be > 0", error);
}

bool TargetOptions::IsValid(std::string* error) const {
  return Expect(height_m >= 0, "target.height_m must be >= 0 and below the camera", error);
}

bool PoseOptions::IsValid(std::string* error) const {
  return Expect(sigma_px > 0 && max_rms_px > 0, "pose.sigma_px and max_rms_px must be > 0", error);
}

bool RobotOptions::IsValid(std::string* error) const {
  if (!Expect(max_control_delay_s >= 0, "robot.max_control_delay_s must be >= 0", error) ||
      !Expect(guess_sigma_fraction > 0, "robot.guess_sigma_fraction must be > 0", error)) {
    return false;
  }
  std::unique_ptr<System> sys;
  if (const Status s = MakeSystem(model, effects, {}, &sys); !s.ok()) {
    *error = "robot: " + s.message();
    return false;
  }
  const std::string known = ParamNames(sys->model().params());
  for (const auto& [name, v] : fixed) {
    const int i = sys->model().ParamIndex(name);
    if (!Expect(i >= 0,
                "robot.fixed: '" + name + "' is not a parameter of model '" + model +
                    "' (its parameters: " + known + ")",
                error)) {
      return false;
    }
    const std::string problem = ParamValueProblem(sys->model().params()[static_cast<size_t>(i)], v);
    if (!Expect(problem.empty(), "robot.fixed: " + problem, error)) return false;
  }
  if (!Expect(fixed.empty() || static_cast<int>(fixed.size()) < sys->model().num_params(),
              "robot.fixed holds every parameter of model '" + model + "' (" + known +
                  "): nothing is left to calibrate",
              error)) {
    return false;
  }
  for (const auto& [name, v] : guess) {
    const int i = sys->ParamIndex(name);
    if (!Expect(
            i >= 0,
            "robot.guess: model '" + model + "' with its effects has no parameter '" + name + "'",
            error)) {
      return false;
    }
    const std::string problem = ParamValueProblem(sys->params()[static_cast<size_t>(i)], v);
    if (!Expect(problem.empty(), "robot.guess: " + problem, error)) return false;
  }
  return true;
}

bool QueueOptions::IsValid(std::string* error) const {
  // Upper bounds keep memory bounded by the configuration: a frame slot holds a whole
  // image, the others a sample or a log event each.
  return Expect(frames >= 2 && poses >= 2 && controls >= 2 && recorder >= 16,
                "queues: frames, poses, controls >= 2, recorder >= 16", error) &&
         Expect(frames <= 256 && poses <= 65536 && controls <= 65536 && recorder <= 1 << 20,
                "queues: frames <= 256 (each holds a whole image), poses and controls <= 65536, "
                "recorder <= 1048576",
                error);
}

bool RecordOptions::IsValid(std::string* error) const {
  return Expect(flush_every_s > 0, "record.flush_every_s must be > 0", error);
}

bool CheckpointOptions::IsValid(std::string* error) const {
  return Expect(every_s > 0, "checkpoint.every_s must be > 0", error);
}

bool CalibrationOptions::IsValid(std::string* error) const {
  return Expect(every_s >= 1 && every_s <= 86400, "calibration.every_s must be in [1, 86400] s",
                error) &&
         Expect(first_s >= 1 && first_s <= 86400, "calibration.first_s must be in [1, 86400] s",
                error) &&
         Expect(growth >= 0 && growth <= 10, "calibration.growth must be in [0, 10]", error) &&
         Expect(threads >= 0 && threads <= 64, "calibration.threads must be 0..64", error) &&
         Expect(max_effects >= 0 && max_effects <= 8, "calibration.max_effects must be 0..8",
                error) &&
         Expect(max_poses >= 1000 && max_poses <= 10'000'000,
                "calibration.max_poses must be 1000..10000000", error) &&
         Expect(max_controls >= 1000 && max_controls <= 40'000'000,
                "calibration.max_controls must be 1000..40000000", error) &&
         Expect(block_s >= 0.5 && block_s <= 600, "calibration.block_s must be in [0.5, 600] s",
                error);
}

bool GuidanceOptions::IsValid(std::string* error) const {
  if (!enabled) return true;
  if (!Expect(every_s > 0 && horizon_s > 0 && horizon_s <= 60,
              "guidance.every_s must be > 0 and guidance.horizon_s in (0, 60]", error) ||
      !Expect(pose_sigma.size() == 3 && pose_sigma[0] > 0 && pose_sigma[1] > 0 && pose_sigma[2] > 0,
              "guidance.pose_sigma needs 3 positive values (m, m, rad)", error) ||
      !Expect(pose_rate_hz > 0 && pose_rate_hz <= 1000,
              "guidance.pose_rate_hz must be in (0, 1000]", error) ||
      !Expect(drive_pause_s >= 0.1 && drive_pause_s <= 60,
              "guidance.drive_pause_s must be in [0.1, 60] s", error)) {
    return false;
  }
  return true;
}

namespace {

// DaemonConfig::IsValid by part: the source, the camera and the target, the estimator.
bool ValidSource(const DaemonConfig& c, std::string* error) {
  switch (c.source) {
    case SourceKind::kV4l2:
      if (!c.v4l2.IsValid(error)) return false;
      break;
    case SourceKind::kLibcamera:
      if (!c.libcamera.IsValid(error)) return false;
      break;
    case SourceKind::kSim:
      if (!c.sim.IsValid(error)) return false;
      break;
    case SourceKind::kReplay:
      if (!c.replay.IsValid(error)) return false;
      break;
  }
  if (c.source == SourceKind::kSim && c.sim.controls_via_lcm && c.sim.speed != 1.0 &&
      c.robot.control_stamp != ControlStamp::kSender) {
    *error =
        "sim.controls_via_lcm at sim.speed != 1: receive stamps are wall-clock times, the "
        "simulation's are not; set robot.control_stamp: sender";
    return false;
  }
  return true;
}

bool ValidVision(const DaemonConfig& c, std::string* error) {
  if (!c.camera.IsValid(error) || !c.target.IsValid(error)) return false;
  if (!Expect(c.target.height_m < c.camera.nadir_height_m || !c.camera.floor.empty(),
              "target.height_m must be >= 0 and below the camera", error)) {
    return false;
  }
  std::string detector_error;
  if (!c.detector.IsValid(&detector_error)) {
    *error = "detector: " + detector_error;
    return false;
  }
  return c.pose.IsValid(error);
}

bool ValidEstimator(const DaemonConfig& c, std::string* error) {
  if (!c.robot.IsValid(error) || !c.filter.IsValid(error)) return false;
  if (!c.filter.control_psd.empty()) {
    const int controls =
        MakeModel(c.robot.model).value()->num_controls();  // robot.IsValid: it exists
    if (!Expect(static_cast<int>(c.filter.control_psd.size()) == controls,
                "filter.control_psd needs " + std::to_string(controls) + " values for model " +
                    c.robot.model,
                error)) {
      return false;
    }
  }
  return true;
}

}  // namespace

bool PreviewOptions::IsValid(std::string* error) const {
  return Expect(rate_hz > 0 && rate_hz <= 30, "preview.rate_hz must be in (0, 30]", error) &&
         Expect(width >= 32 && width <= 4096, "preview.width must be 32..4096 px", error) &&
         Expect(quality >= 10 && quality <= 100, "preview.quality must be 10..100", error);
}

bool DaemonConfig::IsValid(std::string* error) const {
  if (!Expect(health_rate_hz > 0, "health_rate_hz must be > 0", error) ||
      !Expect(no_target_warn_s > 0, "no_target_warn_s must be > 0", error) || !lcm.IsValid(error)) {
    return false;
  }
  if (!ValidSource(*this, error) || !ValidVision(*this, error) || !ValidEstimator(*this, error)) {
    return false;
  }
  if (!queues.IsValid(error) || !record.IsValid(error) || !checkpoint.IsValid(error) ||
      !calibration.IsValid(error) || !guidance.IsValid(error) || !preview.IsValid(error)) {
    return false;
  }
  return GuidanceFitsTheRobot(*this, error);
}

}  // namespace kincal::daemon
