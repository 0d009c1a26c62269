// Target pose from marker centres.
//
// LowePose: the fully projective formulation of Lowe's algorithm (Araujo, Carceroni and
// Brown 1998; thesis 4.5) on undistorted normalised coordinates. The pose is
// reparameterised by D = the target origin in the camera frame and a rotation R, so that
// a point p projects as u = (x' + Dx) / (z' + Dz), v = (y' + Dy) / (z' + Dz) with
// (x', y', z') = R p. Gauss-Newton with the corrected Jacobians
//   du/dDx = 1/(z'+Dz)   du/dDz = -(x'+Dx)/(z'+Dz)^2   dv/dDy = 1/(z'+Dz)
//   dv/dDz = -(y'+Dy)/(z'+Dz)^2
// and rotation increments w applied on the left (R <- exp([w]x) R, d(Rp)/dw = -[Rp]x).
//
// GroundPlanePose: the thesis's own future work: the target moves on a calibrated floor,
// so only (x, y, theta) on the floor are estimated (3 parameters instead of 6).
//
// Both return a covariance from the Jacobian and the centre noise sigma (pixels).
#pragma once

#include <Eigen/Core>
#include <span>

#include "kincal/vision/camera.h"
#include "kincal/vision/target.h"

namespace kincal::vision {

struct LoweResult {
  Pose3 pose;                              // target -> camera
  Eigen::Matrix<double, 6, 6> covariance;  // over (D, rotation increment)
  double rms_px = 0.0;
  int iterations = 0;
  bool ok = false;
};

// Jacobian of the normalised projection of target point p at `pose` with respect to
// (D, rotation increment w), the parameters Gauss-Newton updates.
Eigen::Matrix<double, 2, 6> LoweJacobian(const Eigen::Vector3d& p, const Pose3& pose);

// `normalized` are undistorted normalised image points of `object` (target frame, m).
// `fx` converts normalised units to pixels for the residual and covariance.
LoweResult LowePose(std::span<const Eigen::Vector3d> object,
                    std::span<const Eigen::Vector2d> normalized, const Pose3& initial, double fx,
                    double sigma_px, int max_iterations = 20);

// Initial pose of a planar target from a homography (4+ points, target plane z = 0).
bool PlanarInitialPose(std::span<const Eigen::Vector3d> object,
                       std::span<const Eigen::Vector2d> normalized, Pose3* pose);

// Floor extrinsics: X_cam = R_cf X_floor + t_cf (floor: z up, metres).
struct FloorExtrinsics {
  Eigen::Matrix3d R_cf = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t_cf = Eigen::Vector3d::Zero();
};

struct PlanarPose {
  Eigen::Vector3d xytheta = Eigen::Vector3d::Zero();  // on the floor (m, m, rad)
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  double rms_px = 0.0;
  int iterations = 0;
  bool ok = false;
};

// The fully projective Lowe pose of a target that rides level on the floor. A planar
// target seen from afar has two poses that image almost alike, mirrored in tilt about the
// line of sight; with noisy centres the solve started from a homography lands on the wrong
// one often (15 % of frames of the thesis's camera at 0.14 px, headings off by up to
// 0.5 rad). Solves from `initial` and from `initial` levelled (its plane turned parallel
// to the floor, heading kept), and returns the more level solution unless the other fits
// the centres clearly better (residual sum of squares lower by more than 25 sigma^2). All
// six degrees of freedom stay free.
LoweResult LevelLowePose(const FloorExtrinsics& floor, std::span<const Eigen::Vector3d> object,
                         std::span<const Eigen::Vector2d> normalized, const Pose3& initial,
                         double fx, double sigma_px);

// A 6-DOF pose brought onto the floor: the target origin's floor (x, y) and the heading
// of its x axis, with the covariance propagated from the Lowe solve ((x, y) are linear in
// D; theta moves with the floor-z component of the rotation increment). ok and rms_px
// are copied from the solve.
PlanarPose FloorPoseFromLowe(const FloorExtrinsics& floor, const LoweResult& lowe);
// The same, with the target's position taken where the line of sight to its solved
// origin meets the plane `target_height_m` above the floor, instead of at its solved
// depth: a known height replaces the least certain coordinate of a small target's pose,
// and with it the depth's bias (a scale of every position about the camera's nadir).
// Not ok when the line of sight does not descend to that plane.
PlanarPose FloorPoseFromLoweAtHeight(const FloorExtrinsics& floor, const LoweResult& lowe,
                                     double target_height_m);
// The floor (x, y, theta) of a target pose alone.
Eigen::Vector3d FloorPoseOf(const FloorExtrinsics& floor, const Pose3& pose);

// The target's camera pose for a floor pose (x, y, theta) with the target plane
// `target_height_m` above the floor and parallel to it.
Pose3 CameraPoseOnFloor(const FloorExtrinsics& floor, const Eigen::Vector3d& xytheta,
                        double target_height_m);

// Target frame = robot frame raised by `target_height_m` above the floor.
PlanarPose GroundPlanePose(const FloorExtrinsics& floor, double target_height_m,
                           std::span<const Eigen::Vector3d> object,
                           std::span<const Eigen::Vector2d> normalized,
                           const Eigen::Vector3d& initial, double fx, double sigma_px,
                           int max_iterations = 10);

}  // namespace kincal::vision
