#include "kincal/vision/floor_pose_solver.h"

#include <cmath>

namespace kincal::vision {

bool FloorPoseSolverOptions::IsValid(std::string* error) const {
  if (!(sigma_px > 0.0) || !std::isfinite(sigma_px)) {
    *error = "pose solver: sigma_px must be > 0 and finite";
    return false;
  }
  if (!(max_rms_px > 0.0) || !(max_chi2 > 0.0)) {
    *error = "pose solver: max_rms_px and max_chi2 must be > 0 (infinity: no limit)";
    return false;
  }
  return true;
}

FloorPoseSolver::FloorPoseSolver(const CameraModel& camera, const FloorExtrinsics& floor,
                                 const TargetLayout& layout, double target_height_m,
                                 const FloorPoseSolverOptions& options)
    : camera_(camera),
      floor_(floor),
      layout_(layout),
      height_m_(target_height_m),
      options_(options) {}

bool FloorPoseSolver::Solve(std::span<const Marker> markers, const Eigen::Vector3d* previous,
                            PlanarPose* out) {
  *out = PlanarPose{};
  const size_t n = markers.size();
  if (n > static_cast<size_t>(kMaxMarkers)) return false;
  for (size_t i = 0; i < n; ++i) {
    const Marker& m = markers[i];
    if (m.id < 0 || static_cast<size_t>(m.id) >= layout_.markers.size()) return false;
    const Eigen::Vector2d& q = layout_.markers[static_cast<size_t>(m.id)];
    object_[i] = Eigen::Vector3d(q.x(), q.y(), 0.0);
    normalized_[i] = camera_.PixelToNormalized(m.centre_px);
  }
  const std::span<const Eigen::Vector3d> o(object_.data(), n);
  const std::span<const Eigen::Vector2d> u(normalized_.data(), n);
  const bool ground = options_.method == FloorPoseMethod::kGroundPlane;
  Pose3 pose3;
  Eigen::Vector3d init = previous != nullptr ? *previous : Eigen::Vector3d::Zero();
  if (previous == nullptr || !ground) {
    if (!PlanarInitialPose(o, u, &pose3)) return false;
    init = FloorPoseOf(floor_, pose3);
  }
  PlanarPose r;
  double rms = 0.0;  // of the solve itself (Lowe's, before it is put on the floor)
  if (ground) {
    r = GroundPlanePose(floor_, height_m_, o, u, init, camera_.fx, options_.sigma_px);
    rms = r.rms_px;
  } else {
    const LoweResult lowe = LevelLowePose(floor_, o, u, pose3, camera_.fx, options_.sigma_px);
    if (!lowe.ok) return false;
    rms = lowe.rms_px;
    r = FloorPoseFromLoweAtHeight(floor_, lowe, height_m_);
  }
  const double dof = 2.0 * static_cast<double>(n) - (ground ? 3.0 : 6.0);
  const double rss = rms * rms * static_cast<double>(n);
  const double chi2_limit = options_.max_chi2 * options_.sigma_px * options_.sigma_px;
  if (!r.ok || !(rms <= options_.max_rms_px) || (dof > 0.0 && rss > chi2_limit) ||
      !r.xytheta.allFinite()) {
    return false;
  }
  *out = r;
  return true;
}

}  // namespace kincal::vision
