// kincald configuration files.
#include "kincal/daemon/config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "kincal/estimation/filter.h"
#include "kincal/model.h"
#include "kincal/system.h"

namespace kincal::daemon {
namespace {

template <typename E>
struct Named {
  std::string_view name;
  E value;
};
constexpr std::array<Named<SourceKind>, 4> kSourceNames{{{"sim", SourceKind::kSim},
                                                         {"v4l2", SourceKind::kV4l2},
                                                         {"libcamera", SourceKind::kLibcamera},
                                                         {"replay", SourceKind::kReplay}}};
constexpr std::array<Named<PoseMethod>, 2> kPoseMethodNames{
    {{"ground_plane", PoseMethod::kGroundPlane}, {"lowe", PoseMethod::kLowe}}};
constexpr std::array<Named<ControlStamp>, 3> kControlStampNames{
    {{"receive", ControlStamp::kReceive},
     {"sender", ControlStamp::kSender},
     {"mapped", ControlStamp::kMapped}}};
constexpr std::array<Named<FrameEncoding>, 2> kFrameEncodingNames{
    {{"raw", FrameEncoding::kRaw}, {"png", FrameEncoding::kPng}}};
// Pixel formats a camera can be asked for (PNG is only a recorded frame's encoding).
constexpr std::array<Named<PixelFormat>, 5> kCameraFormatNames{{{"GREY", PixelFormat::kGrey},
                                                                {"YUYV", PixelFormat::kYuyv},
                                                                {"MJPG", PixelFormat::kMjpeg},
                                                                {"BGR3", PixelFormat::kBgr24},
                                                                {"RGB3", PixelFormat::kRgb24}}};

template <typename E, size_t N>
std::string_view NameOf(const std::array<Named<E>, N>& table, E value) {
  for (const auto& n : table) {
    if (n.value == value) return n.name;
  }
  return "?";
}

template <typename E, size_t N>
std::string NameList(const std::array<Named<E>, N>& table) {
  std::string list;
  for (size_t i = 0; i < N; ++i) {
    list += (i == 0 ? "" : (i + 1 == N ? " or " : ", ")) + std::string(table[i].name);
  }
  return list;
}

// One YAML map: typed reads that name file:line on error, and a check that every key in
// the file was one we know.
class Section {
 public:
  Section(YAML::Node node, std::string file, std::string prefix)
      : node_(std::move(node)), file_(std::move(file)), prefix_(std::move(prefix)) {
    if (node_ && !node_.IsMap())
      throw std::runtime_error(Where(node_) + ": '" + prefix_ + "' must be a map");
  }
  template <typename T>
  void Get(const std::string& key, T* out) {
    known_.insert(key);
    if (!node_ || !node_[key] || node_[key].IsNull()) return;
    try {
      *out = node_[key].as<T>();
    } catch (const YAML::Exception& e) {
      throw std::runtime_error(Where(node_[key]) + ": key '" + prefix_ + key + "': " + e.msg);
    }
  }
  // One of a fixed set of names, turned into its enum value here, once.
  template <typename E, size_t N>
  void Choice(const std::string& key, E* out, const std::array<Named<E>, N>& table) {
    std::string name;
    Get(key, &name);
    if (name.empty()) return;
    for (const auto& n : table) {
      if (n.name == name) {
        *out = n.value;
        return;
      }
    }
    throw std::runtime_error(Where(node_[key]) + ": key '" + prefix_ + key + "': expected " +
                             NameList(table) + ", got '" + name + "'");
  }
  void Path(const std::string& key, std::string* out, const std::string& base_dir) {
    Get(key, out);
    if (!out->empty() && std::filesystem::path(*out).is_relative() && node_ && node_[key]) {
      *out = (std::filesystem::path(base_dir) / *out).lexically_normal().string();
    }
  }
  // A list of effect specs, or "auto", or a list with "auto" among the specs: the declared
  // effects, and whether the daemon may add more online.
  void Effects(const std::string& key, std::vector<std::string>* list, bool* automatic) {
    known_.insert(key);
    if (!node_ || !node_[key] || node_[key].IsNull()) return;
    const YAML::Node n = node_[key];
    if (n.IsScalar() && n.as<std::string>() == "auto") {
      *automatic = true;
      return;
    }
    Get(key, list);
    const auto a = std::find(list->begin(), list->end(), "auto");
    if (a != list->end()) {
      *automatic = true;
      list->erase(a);
    }
  }
  Section Sub(const std::string& key) {
    known_.insert(key);
    return Section(node_ ? node_[key] : YAML::Node(), file_, prefix_ + key + ".");
  }
  void CheckUnknown() const {
    if (!node_) return;
    for (const auto& kv : node_) {
      const auto key = kv.first.as<std::string>();
      if (!known_.count(key)) {
        std::string list;
        for (const auto& k : known_) list += (list.empty() ? "" : ", ") + k;
        throw std::runtime_error(Where(kv.first) + ": unknown key '" + prefix_ + key +
                                 "' (expected one of: " + list + ")");
      }
    }
  }

 private:
  std::string Where(const YAML::Node& n) const {
    return file_ + ":" + std::to_string(n.Mark().line + 1);
  }
  YAML::Node node_;
  std::string file_, prefix_;
  std::set<std::string> known_;
};

}  // namespace

DaemonConfig LoadDaemonConfig(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw std::runtime_error(path + ": cannot open config file");
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (!root || root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
  const std::string dir = std::filesystem::path(path).parent_path().string();
  DaemonConfig c;
  c.file = path;
  Section top(root, path, "");
  top.Choice("source", &c.source, kSourceNames);
  top.Get("health_rate_hz", &c.health_rate_hz);
  top.Get("no_target_warn_s", &c.no_target_warn_s);
  {
    auto s = top.Sub("lcm");
    s.Get("url", &c.lcm.url);
    s.Get("controls_channel", &c.lcm.controls_channel);
    s.Get("pose_channel", &c.lcm.pose_channel);
    s.Get("params_channel", &c.lcm.params_channel);
    s.Get("health_channel", &c.lcm.health_channel);
    s.Get("model_check_channel", &c.lcm.model_check_channel);
    s.Get("markers_channel", &c.lcm.markers_channel);
    s.Get("frame_channel", &c.lcm.frame_channel);
    s.Get("publish_frames", &c.lcm.publish_frames);
    s.Get("publish_markers", &c.lcm.publish_markers);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("v4l2");
    s.Get("device", &c.v4l2.device);
    s.Get("width", &c.v4l2.width);
    s.Get("height", &c.v4l2.height);
    s.Choice("pixel_format", &c.v4l2.pixel_format, kCameraFormatNames);
    s.Get("fps", &c.v4l2.fps);
    s.Get("buffers", &c.v4l2.buffers);
    s.Get("controls", &c.v4l2.controls);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("libcamera");
    s.Get("camera", &c.libcamera.camera);
    s.Get("width", &c.libcamera.width);
    s.Get("height", &c.libcamera.height);
    s.Choice("pixel_format", &c.libcamera.pixel_format, kCameraFormatNames);
    s.Get("buffers", &c.libcamera.buffers);
    s.Get("fps", &c.libcamera.fps);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("sim");
    s.Path("scenario", &c.sim.scenario, dir);
    s.Get("speed", &c.sim.speed);
    s.Get("duration_s", &c.sim.duration_s);
    s.Get("margin_px", &c.sim.margin_px);
    s.Get("carry_s", &c.sim.carry_s);
    s.Get("chunk_s", &c.sim.chunk_s);
    s.Get("noise_grey", &c.sim.noise_grey);
    s.Get("controls_via_lcm", &c.sim.controls_via_lcm);
    s.Get("reflection_prob", &c.sim.reflection_prob);
    s.Get("occlusion_prob", &c.sim.occlusion_prob);
    s.Get("seed", &c.sim.seed);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("replay");
    s.Path("path", &c.replay.path, dir);
    s.Get("speed", &c.replay.speed);
    s.Get("loops", &c.replay.loops);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("camera");
    s.Path("intrinsics", &c.camera.intrinsics, dir);
    s.Path("floor", &c.camera.floor, dir);
    s.Get("nadir_height_m", &c.camera.nadir_height_m);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("target");
    s.Path("layout", &c.target.layout, dir);
    s.Get("height_m", &c.target.height_m);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("detector");
    s.Get("dark_on_light", &c.detector.dark_on_light);
    s.Get("threshold", &c.detector.threshold);
    s.Get("min_area_px", &c.detector.min_area_px);
    s.Get("max_area_px", &c.detector.max_area_px);
    s.Get("min_circularity", &c.detector.min_circularity);
    s.Get("min_fill", &c.detector.min_fill);
    s.Get("min_contrast", &c.detector.min_contrast);
    s.Get("flatten_background", &c.detector.flatten_background);
    s.Get("background_tile_px", &c.detector.background_tile_px);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("pose");
    s.Choice("method", &c.pose.method, kPoseMethodNames);
    s.Get("sigma_px", &c.pose.sigma_px);
    s.Get("max_rms_px", &c.pose.max_rms_px);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("robot");
    s.Get("model", &c.robot.model);
    s.Effects("effects", &c.robot.effects, &c.robot.auto_effects);
    s.Get("guess", &c.robot.guess);
    s.Get("guess_sigma_fraction", &c.robot.guess_sigma_fraction);
    s.Choice("control_stamp", &c.robot.control_stamp, kControlStampNames);
    s.Get("max_control_delay_s", &c.robot.max_control_delay_s);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("filter");
    s.Get("type", &c.filter.type);
    s.Get("control_psd", &c.filter.control_psd);
    std::vector<double> psd;
    s.Get("pose_psd", &psd);
    if (!psd.empty()) {
      if (psd.size() != kPoseDim)
        throw std::runtime_error(path + ": filter.pose_psd needs 3 values (m^2/s, m^2/s, rad^2/s)");
      c.filter.pose_psd = {psd[0], psd[1], psd[2]};
    }
    s.Get("max_pose_gap_s", &c.filter.max_pose_gap_s);
    s.Get("params_rate_hz", &c.filter.params_rate_hz);
    s.Get("control_history_s", &c.filter.control_history_s);
    s.Get("gate_nis", &c.filter.gate_nis);
    s.Get("divergence_gated", &c.filter.divergence_gated);
    s.Get("batch_window_s", &c.filter.batch_window_s);
    s.Get("adaptive_noise", &c.filter.adaptive_noise);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("queues");
    s.Get("frames", &c.queues.frames);
    s.Get("poses", &c.queues.poses);
    s.Get("controls", &c.queues.controls);
    s.Get("recorder", &c.queues.recorder);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("record");
    s.Get("path", &c.record.path);
    s.Choice("frame_encoding", &c.record.frame_encoding, kFrameEncodingNames);
    s.Get("flush_every_s", &c.record.flush_every_s);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("checkpoint");
    s.Get("path", &c.checkpoint.path);
    s.Get("every_s", &c.checkpoint.every_s);
    s.Get("resume", &c.checkpoint.resume);
    s.CheckUnknown();
  }
  top.CheckUnknown();
  return c;
}

std::string_view SourceName(SourceKind k) { return NameOf(kSourceNames, k); }
std::string_view PoseMethodName(PoseMethod m) { return NameOf(kPoseMethodNames, m); }
std::string_view ControlStampName(ControlStamp s) { return NameOf(kControlStampNames, s); }
std::string_view FrameEncodingName(FrameEncoding e) { return NameOf(kFrameEncodingNames, e); }

namespace {

// Sets *error to `what` and returns false when !ok (for chains of checks).
bool Expect(bool ok, const std::string& what, std::string* error) {
  if (!ok) *error = what;
  return ok;
}

}  // namespace

bool LcmOptions::IsValid(std::string* error) const {
  for (const auto* ch : {&controls_channel, &pose_channel, &params_channel, &health_channel,
                         &model_check_channel, &markers_channel, &frame_channel}) {
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
         Expect(reflection_prob >= 0 && reflection_prob <= 1 && occlusion_prob >= 0 &&
                    occlusion_prob <= 1,
                "sim.reflection_prob and occlusion_prob must be in [0, 1]", error);
}

bool ReplayOptions::IsValid(std::string* error) const {
  return Expect(!path.empty(), "replay.path (or --replay FILE) must name an LCM log", error) &&
         Expect(speed >= 0, "replay.speed must be >= 0 (0: --fast)", error) &&
         Expect(loops >= 1, "replay.loops must be >= 1", error);
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
  for (const auto& [name, v] : guess) {
    if (!Expect(
            sys->ParamIndex(name) >= 0,
            "robot.guess: model '" + model + "' with its effects has no parameter '" + name + "'",
            error)) {
      return false;
    }
  }
  return true;
}

bool FilterOptions::IsValid(std::string* error) const {
  if (!FilterRegistry::Instance().Has(type)) {
    *error = "filter.type: unknown filter '" + type +
             "' (known: " + FilterRegistry::Instance().KnownList() + ")";
    return false;
  }
  for (double v : control_psd) {
    if (!Expect(v >= 0, "filter.control_psd must be >= 0", error)) return false;
  }
  for (double v : pose_psd) {
    if (!Expect(v >= 0, "filter.pose_psd must be >= 0", error)) return false;
  }
  return Expect(max_pose_gap_s > 0 && params_rate_hz >= 0 && control_history_s > 0,
                "filter.max_pose_gap_s, control_history_s must be > 0, params_rate_hz >= 0",
                error) &&
         Expect(gate_nis >= 0 && divergence_gated >= 1,
                "filter.gate_nis >= 0, divergence_gated >= 1", error) &&
         Expect(batch_window_s > 0 && batch_window_s <= control_history_s,
                "filter.batch_window_s must be in (0, control_history_s]", error);
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

bool DaemonConfig::IsValid(std::string* error) const {
  if (!Expect(health_rate_hz > 0, "health_rate_hz must be > 0", error) ||
      !Expect(no_target_warn_s > 0, "no_target_warn_s must be > 0", error) || !lcm.IsValid(error)) {
    return false;
  }
  switch (source) {
    case SourceKind::kV4l2:
      if (!v4l2.IsValid(error)) return false;
      break;
    case SourceKind::kLibcamera:
      if (!libcamera.IsValid(error)) return false;
      break;
    case SourceKind::kSim:
      if (!sim.IsValid(error)) return false;
      break;
    case SourceKind::kReplay:
      if (!replay.IsValid(error)) return false;
      break;
  }
  if (source == SourceKind::kSim && sim.controls_via_lcm && sim.speed != 1.0 &&
      robot.control_stamp != ControlStamp::kSender) {
    *error =
        "sim.controls_via_lcm at sim.speed != 1: receive stamps are wall-clock times, the "
        "simulation's are not; set robot.control_stamp: sender";
    return false;
  }
  if (!camera.IsValid(error) || !target.IsValid(error)) return false;
  if (!Expect(target.height_m < camera.nadir_height_m || !camera.floor.empty(),
              "target.height_m must be >= 0 and below the camera", error)) {
    return false;
  }
  std::string detector_error;
  if (!detector.IsValid(&detector_error)) {
    *error = "detector: " + detector_error;
    return false;
  }
  if (!pose.IsValid(error) || !robot.IsValid(error) || !filter.IsValid(error)) return false;
  if (!filter.control_psd.empty()) {
    const int controls = MakeModel(robot.model)->num_controls();  // robot.IsValid: it exists
    if (!Expect(static_cast<int>(filter.control_psd.size()) == controls,
                "filter.control_psd needs " + std::to_string(controls) + " values for model " +
                    robot.model,
                error)) {
      return false;
    }
  }
  return queues.IsValid(error) && record.IsValid(error) && checkpoint.IsValid(error);
}

void Validate(const DaemonConfig& c) {
  std::string error;
  if (!c.IsValid(&error)) throw std::runtime_error("config: " + error);
}

}  // namespace kincal::daemon
