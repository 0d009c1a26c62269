// Shared by the vision unit tests: the test camera, an overhead floor, target poses and
// random draws in a fixed order.
#pragma once

#include <Eigen/Core>
#include <random>

#include "kincal/vision/camera.h"
#include "kincal/vision/pose.h"

namespace kincal::vision::test_util {

// Random vectors drawn component by component in a fixed order, last component first (the
// order in which a constructor's arguments are evaluated is unspecified and differs
// between compilers; GCC's, last first, is kept so the seeds give the same scenes).
template <typename D, typename R>
Eigen::Vector2d Draw2(D& d, R& rng) {
  const double b = d(rng);
  return {d(rng), b};
}
template <typename D, typename R>
Eigen::Vector3d Draw3(D& d, R& rng, double scale_z = 1.0) {
  const double c = d(rng), b = d(rng);
  return {d(rng), b, scale_z * c};
}

inline CameraModel TestCamera() {
  CameraModel c;
  c.width = 640;
  c.height = 480;
  c.fx = 820;
  c.fy = 820;
  c.cx = 321.3;
  c.cy = 238.7;
  c.k1 = -0.12;
  c.k2 = 0.05;
  c.p1 = 0.0007;
  c.p2 = -0.0004;
  return c;
}

// Camera 1.2 m above the floor looking down; a robot-mounted target 0.1 m above the floor.
inline FloorExtrinsics Overhead() {
  FloorExtrinsics f;
  f.R_cf = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix() *
           Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()).toRotationMatrix();
  f.t_cf = Eigen::Vector3d(0.02, -0.03, 1.2);
  return f;
}

inline Pose3 TargetPose(const FloorExtrinsics& f, const Eigen::Vector3d& q, double height) {
  Pose3 p;
  const Eigen::Matrix3d Rz = Eigen::AngleAxisd(q.z(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.R = f.R_cf * Rz;
  p.t = f.R_cf * Eigen::Vector3d(q.x(), q.y(), height) + f.t_cf;
  return p;
}

}  // namespace kincal::vision::test_util
