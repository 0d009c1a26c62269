// The target's pose on the floor from its identified markers: the one solver of kincald's
// pose stage and the simulator's pixel meter. Two methods: Lowe's fully projective pose,
// levelled to the floor and put at the plate's known height (FloorPoseFromLoweAtHeight),
// or the ground-plane solver (x, y, theta at the known height). A solve whose centres do
// not fit (a marker taken for another, a blob of noise) is refused by an RMS limit, a
// chi-square limit, or both.
#pragma once

#include <Eigen/Core>
#include <array>
#include <limits>
#include <span>
#include <string>

#include "kincal/vision/camera.h"
#include "kincal/vision/markers.h"
#include "kincal/vision/pose.h"
#include "kincal/vision/target.h"

namespace kincal::vision {

enum class FloorPoseMethod { kGroundPlane, kLowe };

struct FloorPoseSolverOptions {
  FloorPoseMethod method = FloorPoseMethod::kLowe;
  // Centre noise (px) the covariance is computed for.
  double sigma_px = 0.15;
  // Refused: an RMS residual above max_rms_px, or a residual sum of squares above
  // max_chi2 * sigma_px^2 when there are more residuals than unknowns.
  double max_rms_px = std::numeric_limits<double>::infinity();
  double max_chi2 = std::numeric_limits<double>::infinity();

  bool IsValid(std::string* error) const;
};

class FloorPoseSolver {
 public:
  static constexpr int kMaxMarkers = 16;

  // Keeps references to camera, floor and layout.
  FloorPoseSolver(const CameraModel& camera, const FloorExtrinsics& floor,
                  const TargetLayout& layout, double target_height_m,
                  const FloorPoseSolverOptions& options);

  // The pose from markers identified on the layout (every id set). `previous`: the last
  // pose, the ground-plane solver's start (nullptr: from the markers' homography; Lowe
  // always starts there). False when a marker is unidentified, there are more than
  // kMaxMarkers, or the solve fails or is refused. Allocates nothing.
  bool Solve(std::span<const Marker> markers, const Eigen::Vector3d* previous, PlanarPose* out);

  const FloorPoseSolverOptions& options() const { return options_; }

 private:
  const CameraModel& camera_;
  const FloorExtrinsics& floor_;
  const TargetLayout& layout_;
  const double height_m_;
  const FloorPoseSolverOptions options_;
  std::array<Eigen::Vector3d, kMaxMarkers> object_;
  std::array<Eigen::Vector2d, kMaxMarkers> normalized_;
};

}  // namespace kincal::vision
