// Marker targets and the synthetic camera.
//
// A target is a plate carrying circular markers at known positions in its own frame
// (x forward, y left, z up, metres, origin at the plate's reference point). The synthetic
// camera renders it at a known pose with anti-aliasing, blur, noise, vignetting and lens
// distortion, and returns the exact projected marker centres as ground truth.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "kincal/vision/camera.h"

namespace kincal::vision {

struct TargetLayout {
  std::string name = "thesis";
  std::vector<Eigen::Vector2d> markers;  // centres in the target frame, m (plane z = 0)
  double marker_radius_m = 0.008;
  Eigen::Vector2d plate_size_m{0.12, 0.08};  // printed plate, centred on the target origin
  bool dark_on_light = true;
  // The thesis plate: 80 x 120 mm, four markers in an asymmetric layout (one corner
  // marker moved inwards) so that correspondences and heading are unambiguous.
  static TargetLayout Thesis();
  bool IsValid(std::string* error) const;
};

// Rigid transform target -> camera: X_cam = R X_target + t.
struct Pose3 {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
};

struct RenderOptions {
  int supersample = 8;         // sub-samples per pixel and axis on marker edges
  double background = 200.0;   // grey level of the plate / floor
  double foreground = 40.0;    // grey level of a marker
  double blur_sigma_px = 0.6;  // optical blur
  double noise_sigma = 1.0;    // additive Gaussian noise, grey levels
  double vignetting = 0.0;     // relative brightness loss at the image corner
};

struct RenderedFrame {
  cv::Mat image;                         // CV_8UC1
  std::vector<Eigen::Vector2d> centres;  // projected marker centres (ground truth), px
};

RenderedFrame RenderTarget(const CameraModel& cam, const Pose3& pose, const TargetLayout& layout,
                           const RenderOptions& opt, std::mt19937_64& rng);

// A chessboard of (cols + 1) x (rows + 1) squares of side `pitch` (m) whose inner corner
// (0, 0) is the board origin; `centres` returns the projected inner corners, row-major.
RenderedFrame RenderChessboard(const CameraModel& cam, const Pose3& pose, int cols, int rows,
                               double pitch, const RenderOptions& opt, std::mt19937_64& rng);

}  // namespace kincal::vision
