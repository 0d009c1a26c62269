// kincald configuration files: loading into typed options (their checks: config_valid.cc).
#include "kincal/daemon/config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <filesystem>
#include <set>
#include <stdexcept>

#include "daemon/config_names.h"
#include "kincal/finite.h"
#include "kincal/yaml_file.h"

namespace kincal::daemon {
namespace {

using namespace config_internal;  // NOLINT: the choices' names, kept beside this file

// A config file that cannot be read (file:line and the key); thrown by the loaders below
// and caught in ReadDaemonConfig, never outside this file.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One YAML map: typed reads that name file:line on error, and a check that every key in
// the file was one we know.
class Section {
 public:
  // `catalogue` (optional): every key read is listed there with the value it had before
  // (the default, when nothing was loaded): DaemonConfigKeys.
  Section(YAML::Node node, std::string file, std::string prefix,
          std::vector<ConfigKey>* catalogue = nullptr)
      : node_(std::move(node)),
        file_(std::move(file)),
        prefix_(std::move(prefix)),
        catalogue_(catalogue) {
    if (node_ && !node_.IsMap())
      throw ConfigError(Where(node_) + ": '" + prefix_ + "' must be a map");
  }
  template <typename T>
  void Get(const std::string& key, T* out) {
    List(key, Rendered(*out));
    if (!node_ || !node_[key] || node_[key].IsNull()) return;
    try {
      *out = node_[key].as<T>();
    } catch (const YAML::Exception& e) {
      throw ConfigError(Where(node_[key]) + ": key '" + prefix_ + key + "': " + e.msg);
    }
    if (!AllFinite(*out)) {
      throw ConfigError(Where(node_[key]) + ": key '" + prefix_ + key +
                        "': finite numbers expected");
    }
  }
  // One of a fixed set of names, turned into its enum value here, once.
  template <typename E, size_t N>
  void Choice(const std::string& key, E* out, const std::array<Named<E>, N>& table) {
    std::string name;
    List(key, std::string(NameOf(table, *out)) + " (" + NameList(table) + ")");
    Read(key, &name);
    if (name.empty()) return;
    for (const auto& n : table) {
      if (n.name == name) {
        *out = n.value;
        return;
      }
    }
    throw ConfigError(Where(node_[key]) + ": key '" + prefix_ + key + "': expected " +
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
    List(key, *automatic ? "auto" : Rendered(*list));
    if (!node_ || !node_[key] || node_[key].IsNull()) return;
    const YAML::Node n = node_[key];
    if (n.IsScalar() && n.as<std::string>() == "auto") {
      *automatic = true;
      return;
    }
    Read(key, list);
    const auto a = std::find(list->begin(), list->end(), "auto");
    if (a != list->end()) {
      *automatic = true;
      list->erase(a);
    }
  }
  Section Sub(const std::string& key) {
    known_.insert(key);
    return Section(node_ ? node_[key] : YAML::Node(), file_, prefix_ + key + ".", catalogue_);
  }
  void CheckUnknown() const {
    if (!node_) return;
    for (const auto& kv : node_) {
      const auto key = kv.first.as<std::string>();
      if (!known_.count(key)) {
        std::string list;
        for (const auto& k : known_) list += (list.empty() ? "" : ", ") + k;
        throw ConfigError(Where(kv.first) + ": unknown key '" + prefix_ + key +
                          "' (expected one of: " + list + ")");
      }
    }
  }

 private:
  std::string Where(const YAML::Node& n) const {
    return file_ + ":" + std::to_string(n.Mark().line + 1);
  }
  void List(const std::string& key, std::string default_value) {
    known_.insert(key);
    if (catalogue_ != nullptr) catalogue_->push_back({prefix_ + key, std::move(default_value)});
  }
  // A value as YAML would write it in flow style (a list in brackets; a number in the
  // fewest digits that read back to it).
  template <typename T>
  static std::string Rendered(const T& value) {
    YAML::Emitter e;
    e << YAML::Flow << YAML::Node(value);
    return e.c_str();
  }
  static std::string Rendered(double value) {
    char buf[32];
    const auto end = std::to_chars(buf, buf + sizeof buf, value).ptr;
    return std::string(buf, end);
  }
  static std::string Rendered(const std::vector<double>& values) {
    std::string out = "[";
    for (size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + Rendered(values[i]);
    return out + "]";
  }
  // Get without listing the key again (Choice and Effects list theirs).
  template <typename T>
  void Read(const std::string& key, T* out) {
    std::vector<ConfigKey>* catalogue = catalogue_;
    catalogue_ = nullptr;
    Get(key, out);
    catalogue_ = catalogue;
  }
  YAML::Node node_;
  std::string file_, prefix_;
  std::set<std::string> known_;
  std::vector<ConfigKey>* catalogue_;
};

// The sections of a config file, one loader each (LoadSections calls them in order). The
// loaders are the one list of the keys: reading, the unknown-key check and the reference
// (DaemonConfigKeys, docs/config_keys.md) all come from their calls.
void LoadLcm(Section s, DaemonConfig& c) {
  s.Get("url", &c.lcm.url);
  s.Get("controls_channel", &c.lcm.controls_channel);
  s.Get("pose_channel", &c.lcm.pose_channel);
  s.Get("params_channel", &c.lcm.params_channel);
  s.Get("health_channel", &c.lcm.health_channel);
  s.Get("model_check_channel", &c.lcm.model_check_channel);
  s.Get("guidance_channel", &c.lcm.guidance_channel);
  s.Get("calibration_channel", &c.lcm.calibration_channel);
  s.Get("markers_channel", &c.lcm.markers_channel);
  s.Get("preview_channel", &c.lcm.preview_channel);
  s.Get("truth_channel", &c.lcm.truth_channel);
  s.Get("frame_channel", &c.lcm.frame_channel);
  s.Get("publish_frames", &c.lcm.publish_frames);
  s.Get("publish_markers", &c.lcm.publish_markers);
  s.CheckUnknown();
}

void LoadV4l2(Section s, DaemonConfig& c) {
  s.Get("device", &c.v4l2.device);
  s.Get("width", &c.v4l2.width);
  s.Get("height", &c.v4l2.height);
  s.Choice("pixel_format", &c.v4l2.pixel_format, kCameraFormatNames);
  s.Get("fps", &c.v4l2.fps);
  s.Get("buffers", &c.v4l2.buffers);
  s.Get("controls", &c.v4l2.controls);
  s.CheckUnknown();
}

void LoadLibcamera(Section s, DaemonConfig& c) {
  s.Get("camera", &c.libcamera.camera);
  s.Get("width", &c.libcamera.width);
  s.Get("height", &c.libcamera.height);
  s.Choice("pixel_format", &c.libcamera.pixel_format, kCameraFormatNames);
  s.Get("buffers", &c.libcamera.buffers);
  s.Get("fps", &c.libcamera.fps);
  s.CheckUnknown();
}

void LoadSim(Section s, DaemonConfig& c, const std::string& dir) {
  s.Path("scenario", &c.sim.scenario, dir);
  s.Get("speed", &c.sim.speed);
  s.Get("duration_s", &c.sim.duration_s);
  s.Get("margin_px", &c.sim.margin_px);
  s.Get("carry_s", &c.sim.carry_s);
  s.Get("chunk_s", &c.sim.chunk_s);
  s.Get("noise_grey", &c.sim.noise_grey);
  s.Get("controls_via_lcm", &c.sim.controls_via_lcm);
  s.Get("controls_channel", &c.sim.controls_channel);
  s.Get("reflection_prob", &c.sim.reflection_prob);
  s.Get("occlusion_prob", &c.sim.occlusion_prob);
  s.Get("seed", &c.sim.seed);
  s.CheckUnknown();
}

void LoadReplay(Section s, DaemonConfig& c, const std::string& dir, const std::string& path) {
  s.Path("path", &c.replay.path, dir);
  s.Get("speed", &c.replay.speed);
  s.Get("loops", &c.replay.loops);
  std::vector<double> sigma(c.replay.pose_sigma.begin(), c.replay.pose_sigma.end());
  s.Get("pose_sigma", &sigma);
  if (sigma.size() != kPoseDim)
    throw ConfigError(path + ": replay.pose_sigma needs 3 values (m, m, rad)");
  c.replay.pose_sigma = {sigma[0], sigma[1], sigma[2]};
  s.CheckUnknown();
}

void LoadCamera(Section s, DaemonConfig& c, const std::string& dir) {
  s.Path("intrinsics", &c.camera.intrinsics, dir);
  s.Path("floor", &c.camera.floor, dir);
  s.Get("nadir_height_m", &c.camera.nadir_height_m);
  s.CheckUnknown();
}

void LoadTarget(Section s, DaemonConfig& c, const std::string& dir) {
  s.Path("layout", &c.target.layout, dir);
  s.Get("height_m", &c.target.height_m);
  s.CheckUnknown();
}

void LoadDetector(Section s, DaemonConfig& c) {
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

void LoadPose(Section s, DaemonConfig& c) {
  s.Choice("method", &c.pose.method, kPoseMethodNames);
  s.Get("sigma_px", &c.pose.sigma_px);
  s.Get("max_rms_px", &c.pose.max_rms_px);
  s.CheckUnknown();
}

void LoadRobot(Section s, DaemonConfig& c) {
  s.Get("model", &c.robot.model);
  s.Effects("effects", &c.robot.effects, &c.robot.auto_effects);
  s.Get("guess", &c.robot.guess);
  s.Get("fixed", &c.robot.fixed);
  s.Get("guess_sigma_fraction", &c.robot.guess_sigma_fraction);
  s.Choice("control_stamp", &c.robot.control_stamp, kControlStampNames);
  s.Get("max_control_delay_s", &c.robot.max_control_delay_s);
  s.CheckUnknown();
}

void LoadFilter(Section s, DaemonConfig& c, const std::string& path) {
  s.Get("type", &c.filter.type);
  s.Get("control_psd", &c.filter.control_psd);
  std::vector<double> psd(c.filter.pose_psd.begin(), c.filter.pose_psd.end());
  s.Get("pose_psd", &psd);
  if (psd.size() != kPoseDim)
    throw ConfigError(path + ": filter.pose_psd needs 3 values (m^2/s, m^2/s, rad^2/s)");
  c.filter.pose_psd = {psd[0], psd[1], psd[2]};
  s.Get("max_pose_gap_s", &c.filter.max_pose_gap_s);
  s.Get("params_rate_hz", &c.filter.params_rate_hz);
  s.Get("control_history_s", &c.filter.control_history_s);
  s.Get("gate_nis", &c.filter.gate_nis);
  s.Get("divergence_gated", &c.filter.divergence_gated);
  s.Get("batch_window_s", &c.filter.batch_window_s);
  s.Get("adaptive_noise", &c.filter.adaptive_noise);
  s.CheckUnknown();
}

void LoadQueues(Section s, DaemonConfig& c) {
  s.Get("frames", &c.queues.frames);
  s.Get("poses", &c.queues.poses);
  s.Get("controls", &c.queues.controls);
  s.Get("recorder", &c.queues.recorder);
  s.CheckUnknown();
}

void LoadRecord(Section s, DaemonConfig& c) {
  s.Get("path", &c.record.path);
  s.Choice("frame_encoding", &c.record.frame_encoding, kFrameEncodingNames);
  s.Get("flush_every_s", &c.record.flush_every_s);
  s.CheckUnknown();
}

void LoadCheckpoint(Section s, DaemonConfig& c) {
  s.Get("path", &c.checkpoint.path);
  s.Get("every_s", &c.checkpoint.every_s);
  s.Get("resume", &c.checkpoint.resume);
  s.CheckUnknown();
}

void LoadCalibration(Section s, DaemonConfig& c) {
  s.Get("enabled", &c.calibration.enabled);
  s.Get("every_s", &c.calibration.every_s);
  s.Get("first_s", &c.calibration.first_s);
  s.Get("growth", &c.calibration.growth);
  s.Get("threads", &c.calibration.threads);
  s.Get("max_effects", &c.calibration.max_effects);
  s.Get("max_poses", &c.calibration.max_poses);
  s.Get("max_controls", &c.calibration.max_controls);
  s.Get("block_s", &c.calibration.block_s);
  s.CheckUnknown();
}

void LoadPreview(Section s, DaemonConfig& c) {
  s.Get("enabled", &c.preview.enabled);
  s.Get("rate_hz", &c.preview.rate_hz);
  s.Get("width", &c.preview.width);
  s.Get("quality", &c.preview.quality);
  s.CheckUnknown();
}

void LoadGuidance(Section s, DaemonConfig& c) {
  s.Get("enabled", &c.guidance.enabled);
  s.Get("every_s", &c.guidance.every_s);
  s.Get("horizon_s", &c.guidance.horizon_s);
  s.Get("limits", &c.guidance.limits);
  s.Get("targets", &c.guidance.targets);
  s.Get("pose_sigma", &c.guidance.pose_sigma);
  s.Get("pose_rate_hz", &c.guidance.pose_rate_hz);
  s.Get("drive", &c.guidance.drive);
  s.Get("drive_pause_s", &c.guidance.drive_pause_s);
  s.CheckUnknown();
}

}  // namespace

namespace {

// Every section's loader, in order, on `root` (a catalogue, when given, lists each key).
void LoadSections(const YAML::Node& root, const std::string& path,
                  std::vector<ConfigKey>* catalogue, DaemonConfig& c) {
  const std::string dir = std::filesystem::path(path).parent_path().string();
  Section top(root, path, "", catalogue);
  top.Choice("source", &c.source, kSourceNames);
  top.Get("health_rate_hz", &c.health_rate_hz);
  top.Get("no_target_warn_s", &c.no_target_warn_s);
  LoadLcm(top.Sub("lcm"), c);
  LoadV4l2(top.Sub("v4l2"), c);
  LoadLibcamera(top.Sub("libcamera"), c);
  LoadSim(top.Sub("sim"), c, dir);
  LoadReplay(top.Sub("replay"), c, dir, path);
  LoadCamera(top.Sub("camera"), c, dir);
  LoadTarget(top.Sub("target"), c, dir);
  LoadDetector(top.Sub("detector"), c);
  LoadPose(top.Sub("pose"), c);
  LoadRobot(top.Sub("robot"), c);
  LoadFilter(top.Sub("filter"), c, path);
  LoadQueues(top.Sub("queues"), c);
  LoadRecord(top.Sub("record"), c);
  LoadCheckpoint(top.Sub("checkpoint"), c);
  LoadCalibration(top.Sub("calibration"), c);
  LoadGuidance(top.Sub("guidance"), c);
  LoadPreview(top.Sub("preview"), c);
  top.CheckUnknown();
}

DaemonConfig LoadDaemonConfig(const std::string& path) {
  StatusOr<YAML::Node> loaded = LoadYamlFile(path, "config file");
  if (!loaded.ok()) throw ConfigError(loaded.status().message());
  YAML::Node root = std::move(loaded).value();
  if (!root || root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
  DaemonConfig c;
  c.file = path;
  LoadSections(root, path, nullptr, c);
  return c;
}

}  // namespace

std::vector<ConfigKey> DaemonConfigKeys() {
  std::vector<ConfigKey> keys;
  DaemonConfig c;
  LoadSections(YAML::Node(YAML::NodeType::Map), "defaults", &keys, c);
  return keys;
}

StatusOr<DaemonConfig> ReadDaemonConfig(const std::string& path) {
  try {
    return LoadDaemonConfig(path);
  } catch (const ConfigError& e) {
    return Status::Error(e.what());
  } catch (const YAML::Exception& e) {
    return Status::Error(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

std::string_view SourceName(SourceKind k) { return NameOf(kSourceNames, k); }
std::string_view PoseMethodName(PoseMethod m) { return NameOf(kPoseMethodNames, m); }
std::string_view ControlStampName(ControlStamp s) { return NameOf(kControlStampNames, s); }
std::string_view FrameEncodingName(FrameEncoding e) { return NameOf(kFrameEncodingNames, e); }

}  // namespace kincal::daemon
