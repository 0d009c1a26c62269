#include "kincal/vision/floor_view.h"

#include <Eigen/Dense>
#include <cmath>

namespace kincal::vision {
namespace {

// The floor point seen at pixel `px` on the plane z = height_m; false above the horizon.
bool FloorPoint(const CameraModel& camera, const FloorExtrinsics& floor, double height_m,
                const Eigen::Vector2d& px, Eigen::Vector2d* out) {
  const Eigen::Vector2d n = camera.PixelToNormalized(px);
  const Eigen::Vector3d ray = floor.R_cf.transpose() * Eigen::Vector3d(n.x(), n.y(), 1.0);
  const Eigen::Vector3d centre = -floor.R_cf.transpose() * floor.t_cf;
  if (!(std::abs(ray.z()) > 1e-12)) return false;
  const double s = (height_m - centre.z()) / ray.z();
  if (!(s > 0.0)) return false;
  *out = (centre + s * ray).head<2>();
  return true;
}

}  // namespace

std::vector<Eigen::Vector2d> FloorSeen(const CameraModel& camera, const FloorExtrinsics& floor,
                                       double height_m, int per_side) {
  // Pixel corners: the top-left pixel's corner is (-0.5, -0.5).
  const double x0 = -0.5, y0 = -0.5, x1 = camera.width - 0.5, y1 = camera.height - 0.5;
  const Eigen::Vector2d corners[] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  std::vector<Eigen::Vector2d> out;
  for (int side = 0; side < 4; ++side) {
    const Eigen::Vector2d a = corners[side], b = corners[(side + 1) % 4];
    for (int k = 0; k < per_side; ++k) {
      Eigen::Vector2d p;
      if (FloorPoint(camera, floor, height_m, a + (b - a) * (static_cast<double>(k) / per_side),
                     &p)) {
        out.push_back(p);
      }
    }
  }
  return out;
}

bool TargetAxesInImage(const CameraModel& camera, const FloorExtrinsics& floor, double height_m,
                       const Eigen::Vector3d& xytheta, double length_m,
                       std::array<Eigen::Vector2d, 3>* px) {
  const double c = std::cos(xytheta.z()), s = std::sin(xytheta.z());
  const Eigen::Vector3d origin(xytheta.x(), xytheta.y(), height_m);
  const Eigen::Vector3d points[3] = {origin, origin + length_m * Eigen::Vector3d(c, s, 0.0),
                                     origin + length_m * Eigen::Vector3d(-s, c, 0.0)};
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d in_camera = floor.R_cf * points[k] + floor.t_cf;
    if (!(in_camera.z() > 1e-9)) return false;
    (*px)[static_cast<size_t>(k)] = camera.Project(in_camera);
  }
  return true;
}

}  // namespace kincal::vision
