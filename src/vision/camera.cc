#include "kincal/vision/camera.h"

#include <Eigen/Dense>
#include <cmath>
#include <opencv2/core.hpp>
#include <stdexcept>

#include "kincal/io/output_file.h"

namespace kincal::vision {

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
    Eigen::Matrix2d J;
    J(0, 0) = radial + 2.0 * x * x * dradial + 2.0 * p1 * y + 6.0 * p2 * x;
    J(0, 1) = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
    J(1, 0) = 2.0 * x * y * dradial + 2.0 * p1 * x + 2.0 * p2 * y;
    J(1, 1) = radial + 2.0 * y * y * dradial + 6.0 * p1 * y + 2.0 * p2 * x;
    const Eigen::Vector2d step = J.partialPivLu().solve(f);
    n -= step;
    if (step.squaredNorm() < 1e-30) break;
  }
  return n;
}

bool CameraModel::IsValid(std::string* error) const {
  if (width <= 0 || height <= 0 || !(fx > 0) || !(fy > 0)) {
    *error = "camera needs positive image size and focal lengths";
    return false;
  }
  return true;
}

CameraModel ReadCameraYaml(const std::string& path) {
  cv::FileStorage fs;
  try {
    fs.open(path, cv::FileStorage::READ);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(path + ": not a readable OpenCV FileStorage file (" + e.what() + ")");
  }
  if (!fs.isOpened()) throw std::runtime_error(path + ": cannot open");
  auto need = [&](const char* key) {
    cv::FileNode n = fs[key];
    if (n.empty()) throw std::runtime_error(path + ": missing key '" + key + "'");
    return n;
  };
  cv::Mat K, D;
  need("camera_matrix") >> K;
  need("distortion_coefficients") >> D;
  CameraModel c;
  c.width = static_cast<int>(need("image_width"));
  c.height = static_cast<int>(need("image_height"));
  if (K.rows != 3 || K.cols != 3) throw std::runtime_error(path + ": camera_matrix must be 3x3");
  K.convertTo(K, CV_64F);
  D.convertTo(D, CV_64F);
  c.fx = K.at<double>(0, 0);
  c.fy = K.at<double>(1, 1);
  c.cx = K.at<double>(0, 2);
  c.cy = K.at<double>(1, 2);
  const int nd = static_cast<int>(D.total());
  if (nd < 4) throw std::runtime_error(path + ": distortion_coefficients needs at least 4 values");
  const double* d = D.ptr<double>();
  c.k1 = d[0];
  c.k2 = d[1];
  c.p1 = d[2];
  c.p2 = d[3];
  c.k3 = nd > 4 ? d[4] : 0.0;
  std::string error;
  if (!c.IsValid(&error)) throw std::runtime_error(path + ": " + error);
  return c;
}

Status WriteCameraYaml(const CameraModel& c, const std::string& path) {
  cv::FileStorage fs(".yaml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  const cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  const cv::Mat D = (cv::Mat_<double>(5, 1) << c.k1, c.k2, c.p1, c.p2, c.k3);
  fs << "image_width" << c.width << "image_height" << c.height << "camera_matrix" << K
     << "distortion_coefficients" << D;
  return WriteFileAtomically(path, fs.releaseAndGetString(), "camera calibration");
}

}  // namespace kincal::vision
