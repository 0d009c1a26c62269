#include "kincal/vision/synthetic.h"

#include <Eigen/Geometry>
#include <cmath>
#include <string>

namespace kincal::vision {

std::vector<CalibrationView> SyntheticBoardViews(const CameraModel& cam, int n_views,
                                                 double noise_px, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, noise_px);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  // Draws are named and sequenced explicitly: the order of evaluation of function
  // arguments differs between compilers, the results must not.
  auto uniform3 = [&] {
    const double c = U(rng), b = U(rng);
    return Eigen::Vector3d(U(rng), b, c);
  };
  std::vector<CalibrationView> views;
  while (static_cast<int>(views.size()) < n_views) {
    CalibrationView v;
    v.name = "view " + std::to_string(views.size());
    const double ax = U(rng), ay = U(rng), az = U(rng);
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(M_PI + 0.5 * az, Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(0.5 * ay, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(0.3 * ax, Eigen::Vector3d::UnitZ()))
                                  .toRotationMatrix();
    const Eigen::Vector3d t = Eigen::Vector3d(-0.1, 0.06, 0.7) +
                              uniform3().cwiseProduct(Eigen::Vector3d(0.08, 0.05, 0.2));
    bool inside = true;
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 9; ++c) {
        const Eigen::Vector3d X(0.025 * c, 0.025 * r, 0.0);
        const Eigen::Vector3d Xc = R * X + t;
        const double nv = noise(rng), nu = noise(rng);
        const Eigen::Vector2d px = cam.Project(Xc) + Eigen::Vector2d(nu, nv);
        inside = inside && Xc.z() > 0 && px.x() > 0 && px.y() > 0 && px.x() < cam.width - 1 &&
                 px.y() < cam.height - 1;
        v.object.push_back(X);
        v.image.push_back(px);
      }
    }
    if (inside) views.push_back(v);
  }
  return views;
}

}  // namespace kincal::vision
