// Camera calibration from views of a planar board (Zhang's linear initialisation:
// homographies -> intrinsics -> per-view extrinsics) or of a 3-D rig (a DLT per view,
// decomposed into K, R, t; K averaged), then Levenberg-Marquardt with Ceres
// over the intrinsics, distortion and every view's pose; 1-sigma from ceres::Covariance
// scaled by the residual variance. rms_px is OpenCV's: sqrt(sum(du^2 + dv^2) / points).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "kincal/status.h"
#include "kincal/vision/camera.h"
#include "kincal/vision/target.h"

namespace kincal::vision {

struct CalibrationView {
  std::string name;                     // e.g. the image file, for error messages
  std::vector<Eigen::Vector3d> object;  // board or rig points, m
  std::vector<Eigen::Vector2d> image;   // px
};

struct CalibrationOptions {
  int width = 0, height = 0;  // image size, px
  bool use_k3 = false;
  int max_iterations = 200;
};

struct CalibrationResult {
  CameraModel camera;
  // 1-sigma of fx, fy, cx, cy, k1, k2, p1, p2, k3 (k3 = 0 when not used).
  Eigen::Matrix<double, 9, 1> sigma = Eigen::Matrix<double, 9, 1>::Zero();
  std::vector<Pose3> board_poses;  // board -> camera, per view
  double rms_px = 0.0;
  int points = 0;
  bool sigma_ok = false;
};

// An error names the view and the problem (too few points, a degenerate view, points
// outside the image).
StatusOr<CalibrationResult> CalibrateCamera(const std::vector<CalibrationView>& views,
                                            const CalibrationOptions& options);

// Reads a points file with header "view,X,Y,Z,u,v" (object m, image px) into views.
StatusOr<std::vector<CalibrationView>> ReadCalibrationPoints(const std::string& path);

}  // namespace kincal::vision
