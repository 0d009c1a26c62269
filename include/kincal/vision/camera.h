// Pinhole camera with radial (k1, k2, k3) and tangential (p1, p2) distortion, in OpenCV's
// parameter order and conventions, so calibrations move both ways (FileStorage YAML with
// the keys of OpenCV's calibration sample).
//
// Frames: camera frame x right, y down, z forward (optical axis), metres. Pixels: u right,
// v down, origin at the centre of the top-left pixel.
#pragma once

#include <Eigen/Dense>
#include <string>

#include "kincal/status.h"

namespace kincal::vision {

// The largest image side a camera may have, px (the frame and the buffers it needs are
// sized from the camera's file).
inline constexpr int kMaxCameraSide = 16384;

struct CameraModel {
  int width = 0, height = 0;              // px
  double fx = 0, fy = 0, cx = 0, cy = 0;  // px
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;

  // Normalised undistorted (x/z, y/z) -> pixel.
  Eigen::Vector2d NormalizedToPixel(const Eigen::Vector2d& n) const;
  // Camera-frame point -> pixel (z > 0 expected).
  Eigen::Vector2d Project(const Eigen::Vector3d& p) const {
    return NormalizedToPixel(p.head<2>() / p.z());
  }
  // Pixel -> normalised undistorted coordinates (iterative inversion of the distortion).
  Eigen::Vector2d PixelToNormalized(const Eigen::Vector2d& px) const;
  // Image size 1..kMaxCameraSide a side, focal lengths > 0, every number finite.
  bool IsValid(std::string* error) const;
  // No distortion, square pixels of `focal_px`, the principal point at the image's centre
  // ((width - 1) / 2, (height - 1) / 2): the default and the simulated cameras.
  static CameraModel Centred(int width, int height, double focal_px);
};

// OpenCV FileStorage YAML: camera_matrix, distortion_coefficients, image_width,
// image_height; ROS camera_info YAML (camera_calibration_parsers' format, plumb_bob) is
// read too. An error names the file and the missing or bad key.
StatusOr<CameraModel> ReadCameraYaml(const std::string& path);
// Written whole or not at all (kincal/io/output_file.h); an error names the file.
Status WriteCameraYaml(const CameraModel& cam, const std::string& path);
// ROS camera_info YAML (camera_calibration_parsers' format): plumb_bob distortion, identity
// rectification, projection [K | 0]. Whole or not at all.
Status WriteCameraInfoYaml(const CameraModel& cam, const std::string& camera_name,
                           const std::string& path);

}  // namespace kincal::vision
