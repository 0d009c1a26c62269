// The detection/pose stage of kincald, one frame at a time: decode to grey, find and
// identify the target's markers (tracking a region of interest, falling back to the whole
// frame), and solve the target's planar pose on the floor (ground-plane solver, or the
// fully projective Lowe pose brought onto the floor). Used by the daemon's detection
// thread and directly by tests that feed frames from a real driver.
#pragma once

#include <array>
#include <string>

#include "daemon/sources.h"
#include "kincal/daemon/config.h"
#include "kincal/daemon/frame.h"
#include "kincal/online/samples.h"
#include "kincal/vision/floor_pose_solver.h"
#include "kincal/vision/markers.h"

namespace kincal::daemon {

class PoseStage {
 public:
  PoseStage(const PoseOptions& pose, const vision::DetectorOptions& detector, const VisionSetup& v);
  // Fills *out (times and sequence from the frame). Returns false with *error set when the
  // frame cannot be decoded or has the wrong size; a frame without the target gives a
  // pose with valid = false and returns true.
  bool Process(const Frame& f, PoseSample* out, std::string* error);
  // The last frame processed, decoded to grey (the preview's source).
  const cv::Mat& grey() const { return grey_; }

 private:
  void Solve(const std::vector<vision::Marker>& markers, PoseSample* p);
  void CalibrateCovariance(int num_markers, PoseSample* p);

  const PoseOptions opt_;
  const VisionSetup& vis_;
  vision::MarkerTracker tracker_;
  cv::Mat grey_;
  vision::FloorPoseSolver solver_;
  Eigen::Vector3d last_pose_ = Eigen::Vector3d::Zero();
  bool have_last_ = false;
  // The marker centres' noise as the poses' own residuals show it (px^2, running mean):
  // the published covariance is scaled to it from the configured pose.sigma_px.
  double centre_variance_;
  int centre_samples_ = 0;
};

}  // namespace kincal::daemon
