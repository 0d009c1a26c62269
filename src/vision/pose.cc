#include "kincal/vision/pose.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace kincal::vision {
namespace {

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}

Eigen::Matrix3d Exp(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a < 1e-12) return Eigen::Matrix3d::Identity() + Skew(w);
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

// d(normalised projection)/d(D, w) at the rotated point xr = R p and camera point c = xr + D.
Eigen::Matrix<double, 2, 6> LoweJacobianAt(const Eigen::Vector3d& xr, const Eigen::Vector3d& c) {
  const double iz = 1.0 / c.z();
  Eigen::Matrix<double, 2, 3> dproj;
  dproj << iz, 0, -c.x() * iz * iz, 0, iz, -c.y() * iz * iz;
  Eigen::Matrix<double, 2, 6> J;
  J.leftCols<3>() = dproj;
  J.rightCols<3>() = -dproj * Skew(xr);
  return J;
}

}  // namespace

Eigen::Matrix<double, 2, 6> LoweJacobian(const Eigen::Vector3d& p, const Pose3& pose) {
  const Eigen::Vector3d xr = pose.R * p;
  return LoweJacobianAt(xr, xr + pose.t);
}

LoweResult LowePose(std::span<const Eigen::Vector3d> object,
                    std::span<const Eigen::Vector2d> normalized, const Pose3& initial, double fx,
                    double sigma_px, int max_iterations) {
  LoweResult r;
  const size_t n = object.size();
  if (n < 3 || normalized.size() != n) return r;
  Eigen::Matrix3d R = initial.R;
  Eigen::Vector3d D = initial.t;
  Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
  for (int it = 0; it < max_iterations; ++it) {
    H.setZero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    double sse = 0;
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d xr = R * object[i];
      const Eigen::Vector3d c = xr + D;
      if (c.z() <= 0) return r;
      const double iz = 1.0 / c.z();
      const Eigen::Vector2d e = normalized[i] - Eigen::Vector2d(c.x() * iz, c.y() * iz);
      const Eigen::Matrix<double, 2, 6> J = LoweJacobianAt(xr, c);
      H.noalias() += J.transpose() * J;
      g.noalias() += J.transpose() * e;
      sse += e.squaredNorm();
    }
    const Eigen::Matrix<double, 6, 1> step = H.ldlt().solve(g);
    D += step.head<3>();
    R = Exp(step.tail<3>()) * R;
    r.iterations = it + 1;
    r.rms_px = std::sqrt(sse / static_cast<double>(n)) * fx;
    if (step.squaredNorm() < 1e-20) break;  // 0.1 nm / 0.1 nrad: far below any noise
  }
  // Orthonormalise (rounding over iterations; R stays within 1e-15 of a rotation).
  R = Eigen::Quaterniond(R).normalized().toRotationMatrix();
  r.pose.R = R;
  r.pose.t = D;
  const double s = sigma_px / fx;  // centre noise in normalised units
  r.covariance = H.inverse() * s * s;
  r.ok = r.covariance.allFinite();
  return r;
}

bool PlanarInitialPose(std::span<const Eigen::Vector3d> object,
                       std::span<const Eigen::Vector2d> normalized, Pose3* pose) {
  const size_t n = object.size();
  if (n < 4 || normalized.size() != n) return false;
  // DLT for H with normalised image ~ H [X Y 1]^T, with h33 = 1 (h33 is the target's depth
  // along the optical axis up to scale: positive for any target in front of the camera).
  // Points are centred and scaled first (Hartley) and the 8 x 8 normal equations are
  // accumulated point by point: fixed-size, no allocation, no SVD of the 2n x 9 system.
  Eigen::Vector2d mo = Eigen::Vector2d::Zero(), mi = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < n; ++i) {
    mo += object[i].head<2>();
    mi += normalized[i];
  }
  mo /= static_cast<double>(n);
  mi /= static_cast<double>(n);
  double so = 0, si = 0;
  for (size_t i = 0; i < n; ++i) {
    so += (object[i].head<2>() - mo).norm();
    si += (normalized[i] - mi).norm();
  }
  if (!(so > 0) || !(si > 0)) return false;
  so = static_cast<double>(n) / so;  // mean distance from the centroid becomes 1
  si = static_cast<double>(n) / si;
  Eigen::Matrix<double, 8, 8> N = Eigen::Matrix<double, 8, 8>::Zero();
  Eigen::Matrix<double, 8, 1> rhs = Eigen::Matrix<double, 8, 1>::Zero();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d o = so * (object[i].head<2>() - mo), m = si * (normalized[i] - mi);
    const double X = o.x(), Y = o.y(), u = m.x(), v = m.y();
    Eigen::Matrix<double, 8, 1> a;
    a << X, Y, 1, 0, 0, 0, -u * X, -u * Y;
    N.selfadjointView<Eigen::Lower>().rankUpdate(a);
    rhs += a * u;
    a << 0, 0, 0, X, Y, 1, -v * X, -v * Y;
    N.selfadjointView<Eigen::Lower>().rankUpdate(a);
    rhs += a * v;
  }
  const Eigen::LDLT<Eigen::Matrix<double, 8, 8>, Eigen::Lower> ldlt(N);
  if (ldlt.info() != Eigen::Success) return false;
  const Eigen::Matrix<double, 8, 1> h = ldlt.solve(rhs);
  if (!h.allFinite()) return false;
  Eigen::Matrix3d Hn;
  Hn << h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], 1.0;
  // Undo the normalisations: H = Ti^-1 Hn To.
  Eigen::Matrix3d To, Ti_inv;
  To << so, 0, -so * mo.x(), 0, so, -so * mo.y(), 0, 0, 1;
  Ti_inv << 1 / si, 0, mi.x(), 0, 1 / si, mi.y(), 0, 0, 1;
  const Eigen::Matrix3d Hm = Ti_inv * Hn * To;
  double lambda = 1.0 / Hm.col(0).norm();
  if (Hm(2, 2) * lambda < 0) lambda = -lambda;  // target in front of the camera
  Eigen::Vector3d r1 = lambda * Hm.col(0), r2 = lambda * Hm.col(1);
  const Eigen::Vector3d t = lambda * Hm.col(2);
  Eigen::Matrix3d R;
  R.col(0) = r1;
  R.col(1) = r2;
  R.col(2) = r1.cross(r2);
  Eigen::JacobiSVD<Eigen::Matrix3d> s2(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  R = s2.matrixU() * s2.matrixV().transpose();
  if (R.determinant() < 0) return false;
  pose->R = R;
  pose->t = t;
  return t.z() > 0;
}

PlanarPose GroundPlanePose(const FloorExtrinsics& floor, double target_height_m,
                           std::span<const Eigen::Vector3d> object,
                           std::span<const Eigen::Vector2d> normalized,
                           const Eigen::Vector3d& initial, double fx, double sigma_px,
                           int max_iterations) {
  PlanarPose r;
  const size_t n = object.size();
  if (n < 2 || normalized.size() != n) return r;
  Eigen::Vector3d q = initial;
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (int it = 0; it < max_iterations; ++it) {
    H.setZero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    double sse = 0;
    const double c = std::cos(q.z()), s = std::sin(q.z());
    for (size_t i = 0; i < n; ++i) {
      const double px = object[i].x(), py = object[i].y();
      const Eigen::Vector3d Xf(q.x() + c * px - s * py, q.y() + s * px + c * py,
                               target_height_m + object[i].z());
      const Eigen::Vector3d Xc = floor.R_cf * Xf + floor.t_cf;
      if (Xc.z() <= 0) return r;
      const double iz = 1.0 / Xc.z();
      const Eigen::Vector2d e = normalized[i] - Eigen::Vector2d(Xc.x() * iz, Xc.y() * iz);
      Eigen::Matrix<double, 2, 3> dproj;
      dproj << iz, 0, -Xc.x() * iz * iz, 0, iz, -Xc.y() * iz * iz;
      Eigen::Matrix3d dXf;
      dXf << 1, 0, -s * px - c * py, 0, 1, c * px - s * py, 0, 0, 0;
      const Eigen::Matrix<double, 2, 3> J = dproj * floor.R_cf * dXf;
      H += J.transpose() * J;
      g += J.transpose() * e;
      sse += e.squaredNorm();
    }
    const Eigen::Vector3d step = H.ldlt().solve(g);
    q += step;
    r.iterations = it + 1;
    r.rms_px = std::sqrt(sse / static_cast<double>(n)) * fx;
    if (step.squaredNorm() < 1e-24) break;
  }
  r.xytheta = q;
  const double sn = sigma_px / fx;
  r.covariance = H.inverse() * sn * sn;
  r.ok = r.covariance.allFinite();
  return r;
}

namespace {

// A tilted solution is taken over a level one only when it fits the centres better by
// this many sigma^2 (the residual has 2 degrees of freedom for 4 markers: chance alone
// makes 9 sigma^2 in one frame of a hundred).
constexpr double kClearlyBetter = 25.0;

// Angle between the target's plane and the floor.
double TiltFromFloor(const FloorExtrinsics& floor, const Pose3& pose) {
  const double c = (floor.R_cf.transpose() * pose.R)(2, 2);
  return std::acos(std::clamp(c, -1.0, 1.0));
}

}  // namespace

LoweResult LevelLowePose(const FloorExtrinsics& floor, std::span<const Eigen::Vector3d> object,
                         std::span<const Eigen::Vector2d> normalized, const Pose3& initial,
                         double fx, double sigma_px) {
  const LoweResult a = LowePose(object, normalized, initial, fx, sigma_px);
  Pose3 level = initial;
  const Eigen::Vector3d xyt = FloorPoseOf(floor, initial);
  level.R = floor.R_cf * Eigen::AngleAxisd(xyt.z(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const LoweResult b = LowePose(object, normalized, level, fx, sigma_px);
  if (!a.ok) return b;
  if (!b.ok) return a;
  const double n = static_cast<double>(object.size());
  const double rss_a = a.rms_px * a.rms_px * n, rss_b = b.rms_px * b.rms_px * n;
  const bool a_level = TiltFromFloor(floor, a.pose) <= TiltFromFloor(floor, b.pose);
  const LoweResult& more = a_level ? a : b;
  const LoweResult& less = a_level ? b : a;
  const double rss_more = a_level ? rss_a : rss_b, rss_less = a_level ? rss_b : rss_a;
  return rss_more - rss_less > kClearlyBetter * sigma_px * sigma_px ? less : more;
}

Eigen::Vector3d FloorPoseOf(const FloorExtrinsics& floor, const Pose3& pose) {
  const Eigen::Matrix3d Rft = floor.R_cf.transpose() * pose.R;
  const Eigen::Vector3d o = floor.R_cf.transpose() * (pose.t - floor.t_cf);
  return {o.x(), o.y(), std::atan2(Rft(1, 0), Rft(0, 0))};
}

namespace {

// A Lowe solve on the floor at `xy`, whose derivative with respect to the solved
// translation is `dxy_dt`; the heading moves with the floor-z component of the rotation.
PlanarPose OnFloor(const FloorExtrinsics& floor, const LoweResult& lowe, const Eigen::Vector2d& xy,
                   const Eigen::Matrix<double, 2, 3>& dxy_dt) {
  PlanarPose out;
  out.xytheta = FloorPoseOf(floor, lowe.pose);
  out.xytheta.head<2>() = xy;
  Eigen::Matrix<double, 3, 6> J = Eigen::Matrix<double, 3, 6>::Zero();
  J.block<2, 3>(0, 0) = dxy_dt;
  J.block<1, 3>(2, 3) = floor.R_cf.col(2).transpose();
  out.covariance = J * lowe.covariance * J.transpose();
  out.rms_px = lowe.rms_px;
  out.iterations = lowe.iterations;
  out.ok = lowe.ok;
  return out;
}

}  // namespace

PlanarPose FloorPoseFromLowe(const FloorExtrinsics& floor, const LoweResult& lowe) {
  const Eigen::Matrix3d Rfc = floor.R_cf.transpose();
  return OnFloor(floor, lowe, (Rfc * (lowe.pose.t - floor.t_cf)).head<2>(), Rfc.topRows<2>());
}

PlanarPose FloorPoseFromLoweAtHeight(const FloorExtrinsics& floor, const LoweResult& lowe,
                                     double target_height_m) {
  const Eigen::Matrix3d Rfc = floor.R_cf.transpose();
  const Eigen::Vector3d centre = -Rfc * floor.t_cf;  // the camera in floor coordinates
  const Eigen::Vector3d d = Rfc * lowe.pose.t;       // line of sight to the target's origin
  const double drop = target_height_m - centre.z();
  if (!(d.z() < 0.0 && drop < 0.0)) {
    PlanarPose out = FloorPoseFromLowe(floor, lowe);
    out.ok = false;
    return out;
  }
  const double s = drop / d.z();
  // d(xy)/d(d) = s [I | -d_xy / d_z]; d(d)/d(t) = Rfc.
  Eigen::Matrix<double, 2, 3> dxy_dd;
  dxy_dd << s, 0.0, -s * d.x() / d.z(), 0.0, s, -s * d.y() / d.z();
  return OnFloor(floor, lowe, centre.head<2>() + s * d.head<2>(), dxy_dd * Rfc);
}

Pose3 CameraPoseOnFloor(const FloorExtrinsics& floor, const Eigen::Vector3d& xytheta,
                        double target_height_m) {
  Pose3 p;
  p.R = floor.R_cf * Eigen::AngleAxisd(xytheta.z(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.t = floor.R_cf * Eigen::Vector3d(xytheta.x(), xytheta.y(), target_height_m) + floor.t_cf;
  return p;
}

}  // namespace kincal::vision
