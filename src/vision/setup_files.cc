// Target layout and floor extrinsics files.
#include "kincal/vision/setup_files.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string_view>

#include "kincal/yaml_file.h"
#include "vision/opencv_file.h"

namespace kincal::vision {
namespace {

// A target or floor file that cannot be read; caught by this file's public functions, never outside
// it.
class SetupFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace

// Target layout YAML (config/target_*.yaml) -> TargetLayout; errors name file and line.
namespace {

// Refuses a layout that is not a map, or a key it does not know (a misspelt key would be
// ignored and its default used).
void CheckLayoutKeys(const YAML::Node& n, const std::string& path) {
  if (!n.IsMap() && !n.IsNull()) throw SetupFileError(path + ": a target layout is a map of keys");
  constexpr std::array<std::string_view, 5> kKeys = {"name", "marker_radius_m", "dark_on_light",
                                                     "plate_size_m", "markers"};
  for (const auto& kv : n) {
    const auto key = kv.first.as<std::string>();
    if (std::find(kKeys.begin(), kKeys.end(), key) != kKeys.end()) continue;
    std::string known;
    for (const std::string_view k : kKeys) known += (known.empty() ? "" : ", ") + std::string(k);
    throw SetupFileError(path + ":" + std::to_string(kv.first.Mark().line + 1) + ": unknown key '" +
                         key + "' (known: " + known + ")");
  }
}

TargetLayout ReadTargetLayoutYamlOrThrow(const std::string& path) {
  if (path.empty()) return TargetLayout::Thesis();
  StatusOr<YAML::Node> loaded = LoadYamlFile(path, "target layout");
  if (!loaded.ok()) throw SetupFileError(loaded.status().message());
  const YAML::Node n = std::move(loaded).value();
  CheckLayoutKeys(n, path);
  TargetLayout t;
  try {
    t.name = n["name"] ? n["name"].as<std::string>() : path;
    if (n["marker_radius_m"]) t.marker_radius_m = n["marker_radius_m"].as<double>();
    if (n["dark_on_light"]) t.dark_on_light = n["dark_on_light"].as<bool>();
    if (n["plate_size_m"]) {
      const auto v = n["plate_size_m"].as<std::vector<double>>();
      if (v.size() != 2) throw SetupFileError(path + ": plate_size_m needs [width, height]");
      t.plate_size_m = Eigen::Vector2d(v[0], v[1]);
    }
    if (!n["markers"]) throw SetupFileError(path + ": missing key 'markers'");
    t.markers.clear();
    for (const auto& m : n["markers"]) {
      const auto v = m.as<std::vector<double>>();
      if (v.size() != 2) {
        throw SetupFileError(path + ":" + std::to_string(m.Mark().line + 1) +
                             ": a marker is [x, y] in metres");
      }
      t.markers.emplace_back(v[0], v[1]);
    }
  } catch (const YAML::Exception& e) {
    throw SetupFileError(path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  std::string error;
  if (!t.IsValid(&error)) throw SetupFileError(path + ": " + error);
  return t;
}

}  // namespace

StatusOr<TargetLayout> ReadTargetLayoutYaml(const std::string& path) {
  try {
    return ReadTargetLayoutYamlOrThrow(path);
  } catch (const SetupFileError& e) {
    return Status::Error(e.what());
  } catch (const cv::Exception& e) {
    return Status::Error(path + ": " + e.what());
  }
}

namespace {

FloorExtrinsics ReadFloorYamlOrThrow(const std::string& path) {
  cv::FileStorage fs;
  if (const Status s = OpenOpenCvFile(path, "floor extrinsics", &fs); !s.ok())
    throw SetupFileError(s.message());
  cv::Mat R, t;
  fs["R_cf"] >> R;
  fs["t_cf"] >> t;
  if (R.rows != 3 || R.cols != 3 || R.type() != CV_64F) {
    throw SetupFileError(path + ": expected a 3x3 double matrix 'R_cf' (from kincal floorcal)");
  }
  if (t.total() != 3 || t.type() != CV_64F)
    throw SetupFileError(path + ": expected a 3-vector 't_cf'");
  FloorExtrinsics f;
  for (int i = 0; i < 3; ++i) {
    f.t_cf[i] = t.at<double>(i);
    for (int j = 0; j < 3; ++j) f.R_cf(i, j) = R.at<double>(i, j);
  }
  if (!f.t_cf.allFinite()) throw SetupFileError(path + ": t_cf must be three finite numbers");
  if (!f.R_cf.allFinite() ||
      (f.R_cf.transpose() * f.R_cf - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
      f.R_cf.determinant() < 0) {
    throw SetupFileError(path + ": R_cf is not a rotation");
  }
  return f;
}

}  // namespace

StatusOr<FloorExtrinsics> ReadFloorYaml(const std::string& path) {
  try {
    return ReadFloorYamlOrThrow(path);
  } catch (const SetupFileError& e) {
    return Status::Error(e.what());
  } catch (const cv::Exception& e) {
    return Status::Error(path + ": " + e.what());
  }
}

FloorExtrinsics NadirFloor(double height_m) {
  FloorExtrinsics f;
  f.R_cf = Eigen::Vector3d(1, -1, -1).asDiagonal();
  f.t_cf = Eigen::Vector3d(0, 0, height_m);
  return f;
}

}  // namespace kincal::vision
