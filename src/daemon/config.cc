// kincald configuration files.
#include "kincal/daemon/config.h"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <set>
#include <stdexcept>

#include "kincal/estimation/filter.h"
#include "kincal/model.h"
#include "kincal/system.h"

namespace kincal::daemon {
namespace {

// One YAML map: typed reads that name file:line on error, and a check that every key in
// the file was one we know.
class Section {
 public:
  Section(YAML::Node node, std::string file, std::string prefix)
      : node_(std::move(node)), file_(std::move(file)), prefix_(std::move(prefix)) {
    if (node_ && !node_.IsMap()) throw std::runtime_error(Where(node_) + ": '" + prefix_ + "' must be a map");
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
  void Path(const std::string& key, std::string* out, const std::string& base_dir) {
    Get(key, out);
    if (!out->empty() && std::filesystem::path(*out).is_relative() && node_ && node_[key]) {
      *out = (std::filesystem::path(base_dir) / *out).lexically_normal().string();
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
        throw std::runtime_error(Where(kv.first) + ": unknown key '" + prefix_ + key + "' (expected one of: " + list + ")");
      }
    }
  }

 private:
  std::string Where(const YAML::Node& n) const { return file_ + ":" + std::to_string(n.Mark().line + 1); }
  YAML::Node node_;
  std::string file_, prefix_;
  std::set<std::string> known_;
};

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::runtime_error("config: " + what);
}

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
  top.Get("source", &c.source);
  top.Get("health_rate_hz", &c.health_rate_hz);
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
    s.Get("pixel_format", &c.v4l2.pixel_format);
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
    s.Get("pixel_format", &c.libcamera.pixel_format);
    s.Get("buffers", &c.libcamera.buffers);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("sim");
    s.Path("scenario", &c.sim.scenario, dir);
    s.Get("speed", &c.sim.speed);
    s.Get("duration_s", &c.sim.duration_s);
    s.Get("margin_px", &c.sim.margin_px);
    s.Get("carry_s", &c.sim.carry_s);
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
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("pose");
    s.Get("method", &c.pose.method);
    s.Get("sigma_px", &c.pose.sigma_px);
    s.Get("max_rms_px", &c.pose.max_rms_px);
    s.CheckUnknown();
  }
  {
    auto s = top.Sub("robot");
    s.Get("model", &c.robot.model);
    s.Get("effects", &c.robot.effects);
    s.Get("guess", &c.robot.guess);
    s.Get("guess_sigma_fraction", &c.robot.guess_sigma_fraction);
    s.Get("control_stamp", &c.robot.control_stamp);
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
      if (psd.size() != 3) throw std::runtime_error(path + ": filter.pose_psd needs 3 values (m^2/s, m^2/s, rad^2/s)");
      c.filter.pose_psd = {psd[0], psd[1], psd[2]};
    }
    s.Get("max_pose_gap_s", &c.filter.max_pose_gap_s);
    s.Get("params_rate_hz", &c.filter.params_rate_hz);
    s.Get("control_history_s", &c.filter.control_history_s);
    s.Get("gate_nis", &c.filter.gate_nis);
    s.Get("divergence_gated", &c.filter.divergence_gated);
    s.Get("batch_window_s", &c.filter.batch_window_s);
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
    s.Get("frame_encoding", &c.record.frame_encoding);
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

void Validate(const DaemonConfig& c) {
  static const std::set<std::string> kSources = {"sim", "v4l2", "libcamera", "replay"};
  Require(kSources.count(c.source) > 0, "source must be sim, v4l2, libcamera or replay (got '" + c.source + "')");
  Require(c.health_rate_hz > 0, "health_rate_hz must be > 0");
  for (const auto* ch : {&c.lcm.controls_channel, &c.lcm.pose_channel, &c.lcm.params_channel,
                         &c.lcm.health_channel, &c.lcm.model_check_channel, &c.lcm.markers_channel,
                         &c.lcm.frame_channel}) {
    Require(!ch->empty() && ch->size() < 64, "lcm channel names must be 1..63 characters");
  }
  if (c.source == "v4l2") {
    Require(c.v4l2.width > 0 && c.v4l2.height > 0, "v4l2.width/height must be > 0");
    Require(c.v4l2.fps > 0, "v4l2.fps must be > 0");
    Require(c.v4l2.buffers >= 4 && c.v4l2.buffers <= 32, "v4l2.buffers must be 4..32");
    Require(c.v4l2.pixel_format == "GREY" || c.v4l2.pixel_format == "YUYV" || c.v4l2.pixel_format == "MJPG",
            "v4l2.pixel_format must be GREY, YUYV or MJPG (got '" + c.v4l2.pixel_format + "')");
  }
  if (c.source == "libcamera") {
    Require(c.libcamera.width > 0 && c.libcamera.height > 0, "libcamera.width/height must be > 0");
    Require(c.libcamera.buffers >= 2 && c.libcamera.buffers <= 32, "libcamera.buffers must be 2..32");
    Require(c.libcamera.pixel_format == "GREY" || c.libcamera.pixel_format == "YUYV" ||
                c.libcamera.pixel_format == "MJPG" || c.libcamera.pixel_format == "BGR3" ||
                c.libcamera.pixel_format == "RGB3",
            "libcamera.pixel_format must be GREY, YUYV, MJPG, BGR3 or RGB3");
  }
  if (c.source == "sim") {
    Require(!c.sim.scenario.empty(), "sim.scenario must name a scenario file");
    Require(c.sim.duration_s >= 0 && c.sim.margin_px >= 0 && c.sim.carry_s >= 0 && c.sim.noise_grey >= 0,
            "sim.duration_s, margin_px, carry_s, noise_grey must be >= 0");
    Require(c.sim.reflection_prob >= 0 && c.sim.reflection_prob <= 1 && c.sim.occlusion_prob >= 0 &&
                c.sim.occlusion_prob <= 1,
            "sim.reflection_prob and occlusion_prob must be in [0, 1]");
  }
  if (c.source == "sim" && c.sim.controls_via_lcm && c.sim.speed != 1.0) {
    Require(c.robot.control_stamp == "sender",
            "sim.controls_via_lcm at sim.speed != 1: receive stamps are wall-clock times, the simulation's are "
            "not; set robot.control_stamp: sender");
  }
  if (c.source == "replay") {
    Require(!c.replay.path.empty(), "replay.path (or --replay FILE) must name an LCM log");
    Require(c.replay.speed >= 0, "replay.speed must be >= 0 (0: --fast)");
    Require(c.replay.loops >= 1, "replay.loops must be >= 1");
  }
  Require(c.camera.nadir_height_m > 0, "camera.nadir_height_m must be > 0");
  Require(c.target.height_m >= 0 && (c.target.height_m < c.camera.nadir_height_m || !c.camera.floor.empty()),
          "target.height_m must be >= 0 and below the camera");
  std::string error;
  Require(c.detector.IsValid(&error), "detector: " + error);
  Require(c.pose.method == "ground_plane" || c.pose.method == "lowe", "pose.method must be ground_plane or lowe");
  Require(c.pose.sigma_px > 0 && c.pose.max_rms_px > 0, "pose.sigma_px and max_rms_px must be > 0");
  Require(c.robot.control_stamp == "receive" || c.robot.control_stamp == "sender",
          "robot.control_stamp must be receive or sender");
  Require(c.robot.max_control_delay_s >= 0, "robot.max_control_delay_s must be >= 0");
  Require(c.robot.guess_sigma_fraction > 0, "robot.guess_sigma_fraction must be > 0");
  try {
    const System sys = MakeSystem(c.robot.model, c.robot.effects);
    for (const auto& [name, v] : c.robot.guess) {
      Require(sys.ParamIndex(name) >= 0, "robot.guess: model '" + c.robot.model + "' with its effects has no parameter '" + name + "'");
      (void)v;
    }
    Require(c.filter.control_psd.empty() || static_cast<int>(c.filter.control_psd.size()) == sys.num_controls(),
            "filter.control_psd needs " + std::to_string(sys.num_controls()) + " values for model " + c.robot.model);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("config: robot: ") + e.what());
  }
  try {
    (void)MakeFilter(c.filter.type);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(std::string("config: filter.type: ") + e.what());
  }
  for (double v : c.filter.control_psd) Require(v >= 0, "filter.control_psd must be >= 0");
  for (double v : c.filter.pose_psd) Require(v >= 0, "filter.pose_psd must be >= 0");
  Require(c.filter.max_pose_gap_s > 0 && c.filter.params_rate_hz >= 0 && c.filter.control_history_s > 0,
          "filter.max_pose_gap_s, control_history_s must be > 0, params_rate_hz >= 0");
  Require(c.filter.gate_nis >= 0 && c.filter.divergence_gated >= 1, "filter.gate_nis >= 0, divergence_gated >= 1");
  Require(c.filter.batch_window_s > 0 && c.filter.batch_window_s <= c.filter.control_history_s,
          "filter.batch_window_s must be in (0, control_history_s]");
  Require(c.queues.frames >= 2 && c.queues.poses >= 2 && c.queues.controls >= 2 && c.queues.recorder >= 16,
          "queues: frames, poses, controls >= 2, recorder >= 16");
  Require(c.record.frame_encoding == "raw" || c.record.frame_encoding == "png", "record.frame_encoding must be raw or png");
  Require(c.record.flush_every_s > 0, "record.flush_every_s must be > 0");
  Require(c.checkpoint.every_s > 0, "checkpoint.every_s must be > 0");
}

}  // namespace kincal::daemon
