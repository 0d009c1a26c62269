#include "kincal/vision/camera.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <cmath>
#include <iomanip>
#include <opencv2/core.hpp>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "kincal/io/output_file.h"
#include "kincal/text.h"
#include "kincal/yaml_file.h"
#include "vision/opencv_file.h"

namespace kincal::vision {
namespace {

// A camera file that cannot be read; caught by this file's public functions, never outside it.
class CameraFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace

Eigen::Vector2d CameraModel::NormalizedToPixel(const Eigen::Vector2d& n) const {
  const double x = n.x(), y = n.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  const double xd = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
  const double yd = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
  return {fx * xd + cx, fy * yd + cy};
}

Eigen::Vector2d CameraModel::PixelToNormalized(const Eigen::Vector2d& px) const {
  const Eigen::Vector2d d((px.x() - cx) / fx, (px.y() - cy) / fy);
  // Newton on the distortion map (a few iterations reach machine precision for lenses
  // that are invertible over the image).
  Eigen::Vector2d n = d;
  for (int it = 0; it < 20; ++it) {
    const double x = n.x(), y = n.y();
    const double r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dradial = k1 + 2.0 * r2 * k2 + 3.0 * r2 * r2 * k3;  // d radial / d r2
    const Eigen::Vector2d f(x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) - d.x(),
                            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y - d.y());
    // The 2x2 Jacobian (symmetric) solved in closed form: this runs for every pixel the
    // simulated camera renders.
    const double a = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
    const double b = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
    const double c = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
    const double det = a * c - b * b;
    if (!(std::abs(det) > 1e-300)) break;
    const Eigen::Vector2d step((c * f.x() - b * f.y()) / det, (a * f.y() - b * f.x()) / det);
    n -= step;
    if (step.squaredNorm() < 1e-30) break;
  }
  return n;
}

CameraModel CameraModel::Centred(int width, int height, double focal_px) {
  CameraModel c;
  c.width = width;
  c.height = height;
  c.fx = c.fy = focal_px;
  c.cx = 0.5 * (width - 1);
  c.cy = 0.5 * (height - 1);
  return c;
}

bool CameraModel::IsValid(std::string* error) const {
  if (width <= 0 || height <= 0 || !(fx > 0) || !(fy > 0)) {
    *error = "camera needs positive image size and focal lengths";
    return false;
  }
  if (width > kMaxCameraSide || height > kMaxCameraSide) {
    *error = "camera image size " + std::to_string(width) + "x" + std::to_string(height) +
             " is over " + std::to_string(kMaxCameraSide) + " px a side";
    return false;
  }
  for (const double v : {fx, fy, cx, cy, k1, k2, p1, p2, k3}) {
    if (!std::isfinite(v)) {
      *error = "camera intrinsics and distortion must be finite numbers";
      return false;
    }
  }
  return true;
}

namespace {

// ROS camera_info YAML (camera_calibration_parsers' keys), through yaml-cpp: it carries no
// %YAML directive, without which OpenCV's reader refuses a file.
CameraModel ReadRosCameraInfo(const std::string& path) {
  StatusOr<YAML::Node> loaded = LoadYamlFile(path, "camera intrinsics");
  if (!loaded.ok()) throw CameraFileError(loaded.status().message());
  const YAML::Node n = std::move(loaded).value();
  auto need = [&](const char* key) {
    if (!n.IsMap() || !n[key]) throw CameraFileError(path + ": missing key '" + key + "'");
    return n[key];
  };
  auto data = [&](const char* key, size_t at_least) {
    std::vector<double> v;
    try {
      v = need(key)["data"].as<std::vector<double>>();
    } catch (const YAML::Exception&) {
      throw CameraFileError(path + ": " + key + ".data: expected a list of numbers");
    }
    if (v.size() < at_least) {
      throw CameraFileError(path + ": " + key + ".data: expected at least " +
                            std::to_string(at_least) + " numbers");
    }
    return v;
  };
  if (n.IsMap() && n["distortion_model"]) {
    const auto model = n["distortion_model"].as<std::string>("");
    if (model != "plumb_bob" && model != "rational_polynomial") {
      throw CameraFileError(path + ": distortion_model '" + model +
                            "': expected plumb_bob (or rational_polynomial)");
    }
  }
  const std::vector<double> k = data("camera_matrix", 9), d = data("distortion_coefficients", 4);
  CameraModel c;
  try {
    c.width = need("image_width").as<int>();
    c.height = need("image_height").as<int>();
  } catch (const YAML::Exception&) {
    throw CameraFileError(path + ": image_width and image_height: expected integers");
  }
  c.fx = k[0];
  c.cx = k[2];
  c.fy = k[4];
  c.cy = k[5];
  c.k1 = d[0];
  c.k2 = d[1];
  c.p1 = d[2];
  c.p2 = d[3];
  c.k3 = d.size() > 4 ? d[4] : 0.0;
  std::string error;
  if (!c.IsValid(&error)) throw CameraFileError(path + ": " + error);
  return c;
}

// OpenCV's YAML files open with a %YAML directive; camera_info files do not.
bool IsRosCameraInfo(const std::string& path) {
  TextLines lines(path, "camera intrinsics");
  std::string first;
  if (!lines.Next(&first)) return false;  // the reader below names what is wrong
  return first.rfind("%YAML", 0) != 0 && first.rfind("<?xml", 0) != 0 && first.rfind("{", 0) != 0;
}

}  // namespace

namespace {

CameraModel ReadCameraYamlOrThrow(const std::string& path) {
  if (IsRosCameraInfo(path)) return ReadRosCameraInfo(path);
  cv::FileStorage fs;
  if (const Status s = OpenOpenCvFile(path, "camera intrinsics", &fs); !s.ok())
    throw CameraFileError(s.message());
  auto need = [&](const char* key) {
    cv::FileNode n = fs[key];
    if (n.empty()) throw CameraFileError(path + ": missing key '" + key + "'");
    return n;
  };
  cv::Mat K, D;
  need("camera_matrix") >> K;
  need("distortion_coefficients") >> D;
  CameraModel c;
  c.width = static_cast<int>(need("image_width"));
  c.height = static_cast<int>(need("image_height"));
  if (K.rows != 3 || K.cols != 3) throw CameraFileError(path + ": camera_matrix must be 3x3");
  K.convertTo(K, CV_64F);
  D.convertTo(D, CV_64F);
  c.fx = K.at<double>(0, 0);
  c.fy = K.at<double>(1, 1);
  c.cx = K.at<double>(0, 2);
  c.cy = K.at<double>(1, 2);
  const int nd = static_cast<int>(D.total());
  if (nd < 4) throw CameraFileError(path + ": distortion_coefficients needs at least 4 values");
  const double* d = D.ptr<double>();
  c.k1 = d[0];
  c.k2 = d[1];
  c.p1 = d[2];
  c.p2 = d[3];
  c.k3 = nd > 4 ? d[4] : 0.0;
  std::string error;
  if (!c.IsValid(&error)) throw CameraFileError(path + ": " + error);
  return c;
}

}  // namespace

StatusOr<CameraModel> ReadCameraYaml(const std::string& path) {
  try {
    return ReadCameraYamlOrThrow(path);
  } catch (const CameraFileError& e) {
    return Status::Error(e.what());
  } catch (const cv::Exception& e) {
    return Status::Error(path + ": " + e.what());
  }
}

Status WriteCameraYaml(const CameraModel& c, const std::string& path) {
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  const cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  const cv::Mat D = (cv::Mat_<double>(5, 1) << c.k1, c.k2, c.p1, c.p2, c.k3);
  fs << "image_width" << c.width << "image_height" << c.height << "camera_matrix" << K
     << "distortion_coefficients" << D;
  return WriteFileAtomically(path, fs.releaseAndGetString(), "camera calibration");
}

Status WriteCameraInfoYaml(const CameraModel& c, const std::string& camera_name,
                           const std::string& path) {
  std::ostringstream o;
  o << std::setprecision(12);
  auto row = [&o](std::initializer_list<double> v) {
    o << "  data: [";
    const char* sep = "";
    for (double x : v) {
      o << sep << x;
      sep = ", ";
    }
    o << "]\n";
  };
  o << "image_width: " << c.width << "\nimage_height: " << c.height
    << "\ncamera_name: " << camera_name << "\ncamera_matrix:\n  rows: 3\n  cols: 3\n";
  row({c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1});
  o << "distortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n";
  row({c.k1, c.k2, c.p1, c.p2, c.k3});
  o << "rectification_matrix:\n  rows: 3\n  cols: 3\n";
  row({1, 0, 0, 0, 1, 0, 0, 0, 1});
  o << "projection_matrix:\n  rows: 3\n  cols: 4\n";
  row({c.fx, 0, c.cx, 0, 0, c.fy, c.cy, 0, 0, 0, 1, 0});
  return WriteFileAtomically(path, o.str(), "camera_info");
}

}  // namespace kincal::vision
