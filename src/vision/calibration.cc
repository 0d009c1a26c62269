#include "kincal/vision/calibration.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Dense>
#include <cmath>
#include <map>
#include <stdexcept>

#include "kincal/csv.h"
#include "kincal/estimation/ceres_logging.h"
#include "kincal/text.h"

namespace kincal::vision {
namespace {

// Points or views that cannot be calibrated; caught by this file's public functions, never outside
// it.
class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace
namespace {

// Pixel residual of one board point. Intrinsics: fx fy cx cy k1 k2 p1 p2 k3.
struct Reprojection {
  Reprojection(const Eigen::Vector3d& X, const Eigen::Vector2d& uv) : X_(X), uv_(uv) {}
  template <typename T>
  bool operator()(const T* intr, const T* pose, T* r) const {
    const T p[3] = {T(X_.x()), T(X_.y()), T(X_.z())};
    T c[3];
    ceres::AngleAxisRotatePoint(pose, p, c);
    c[0] += pose[3];
    c[1] += pose[4];
    c[2] += pose[5];
    const T x = c[0] / c[2], y = c[1] / c[2];
    const T r2 = x * x + y * y;
    const T radial = 1.0 + r2 * (intr[4] + r2 * (intr[5] + r2 * intr[8]));
    const T xd = x * radial + 2.0 * intr[6] * x * y + intr[7] * (r2 + 2.0 * x * x);
    const T yd = y * radial + intr[6] * (r2 + 2.0 * y * y) + 2.0 * intr[7] * x * y;
    r[0] = intr[0] * xd + intr[2] - uv_.x();
    r[1] = intr[1] * yd + intr[3] - uv_.y();
    return true;
  }
  Eigen::Vector3d X_;
  Eigen::Vector2d uv_;
};

Eigen::Matrix3d Homography(const CalibrationView& v) {
  const size_t n = v.object.size();
  // Hartley normalisation of both point sets.
  auto normaliser = [](const std::vector<Eigen::Vector2d>& pts) {
    Eigen::Vector2d m = Eigen::Vector2d::Zero();
    for (const auto& p : pts) m += p;
    m /= static_cast<double>(pts.size());
    double s = 0;
    for (const auto& p : pts) s += (p - m).norm();
    s = std::sqrt(2.0) * static_cast<double>(pts.size()) / std::max(s, 1e-12);
    Eigen::Matrix3d T;
    T << s, 0, -s * m.x(), 0, s, -s * m.y(), 0, 0, 1;
    return T;
  };
  std::vector<Eigen::Vector2d> obj, img;
  for (size_t i = 0; i < n; ++i) {
    obj.push_back(v.object[i].head<2>());
    img.push_back(v.image[i]);
  }
  const Eigen::Matrix3d To = normaliser(obj), Ti = normaliser(img);
  Eigen::MatrixXd A(2 * n, 9);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d o = To * obj[i].homogeneous();
    const Eigen::Vector3d p = Ti * img[i].homogeneous();
    const double X = o.x(), Y = o.y(), u = p.x(), w = p.y();
    A.row(static_cast<long>(2 * i)) << X, Y, 1, 0, 0, 0, -u * X, -u * Y, -u;
    A.row(static_cast<long>(2 * i + 1)) << 0, 0, 0, X, Y, 1, -w * X, -w * Y, -w;
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::VectorXd h = svd.matrixV().col(8);
  Eigen::Matrix3d H;
  H << h[0], h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8];
  return Ti.inverse() * H * To;
}

// Board pose (angle-axis, translation) from its homography and the intrinsics.
std::array<double, 6> PoseFromHomography(const Eigen::Matrix3d& K, const Eigen::Matrix3d& H) {
  const Eigen::Matrix3d M = K.inverse() * H;
  double l = 1.0 / M.col(0).norm();
  if (M(2, 2) * l < 0) l = -l;
  Eigen::Matrix3d R;
  R.col(0) = l * M.col(0);
  R.col(1) = l * M.col(1);
  R.col(2) = R.col(0).cross(R.col(1));
  Eigen::JacobiSVD<Eigen::Matrix3d> s(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  R = s.matrixU() * s.matrixV().transpose();
  const Eigen::AngleAxisd aa(R);
  const Eigen::Vector3d w = aa.angle() * aa.axis();
  const Eigen::Vector3d t = l * M.col(2);
  return {w.x(), w.y(), w.z(), t.x(), t.y(), t.z()};
}

Eigen::Matrix<double, 6, 1> Vij(const Eigen::Matrix3d& H, int i, int j) {
  const Eigen::Vector3d a = H.col(i), b = H.col(j);
  Eigen::Matrix<double, 6, 1> v;
  v << a[0] * b[0], a[0] * b[1] + a[1] * b[0], a[1] * b[1], a[2] * b[0] + a[0] * b[2],
      a[2] * b[1] + a[1] * b[2], a[2] * b[2];
  return v;
}

// DLT of a 3x4 projection from >= 6 non-coplanar points, decomposed into K (upper
// triangular, K(2,2) = 1, positive diagonal), R and t with x ~ K (R X + t).
bool DltView(const CalibrationView& v, Eigen::Matrix3d* K, Eigen::Matrix3d* R, Eigen::Vector3d* t) {
  const size_t n = v.object.size();
  Eigen::MatrixXd A(2 * n, 12);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector4d X = v.object[i].homogeneous();
    const double u = v.image[i].x(), w = v.image[i].y();
    A.row(static_cast<long>(2 * i)) << X.transpose(), Eigen::RowVector4d::Zero(),
        -u * X.transpose();
    A.row(static_cast<long>(2 * i + 1)) << Eigen::RowVector4d::Zero(), X.transpose(),
        -w * X.transpose();
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::VectorXd p = svd.matrixV().col(11);
  Eigen::Matrix<double, 3, 4> P;
  P << p.segment<4>(0).transpose(), p.segment<4>(4).transpose(), p.segment<4>(8).transpose();
  // RQ of M = P(:, 0:3) by QR of the flipped transpose.
  Eigen::Matrix3d F;
  F << 0, 0, 1, 0, 1, 0, 1, 0, 0;
  const Eigen::Matrix3d M = P.leftCols<3>();
  Eigen::HouseholderQR<Eigen::Matrix3d> qr((F * M).transpose());
  const Eigen::Matrix3d Qp = qr.householderQ();
  const Eigen::Matrix3d Rp = qr.matrixQR().triangularView<Eigen::Upper>();
  Eigen::Matrix3d k = F * Rp.transpose() * F;
  Eigen::Matrix3d r = F * Qp.transpose();
  for (int i = 0; i < 3; ++i) {
    if (k(i, i) < 0) {
      k.col(i) *= -1.0;
      r.row(i) *= -1.0;
    }
  }
  // P = s K [R | t]: fix scale and the sign so that points are in front of the camera.
  double scale = k(2, 2);
  Eigen::Vector3d tt = k.inverse() * P.col(3);
  if (r.determinant() < 0) {
    r = -r;
    tt = -tt;
  }
  k /= scale;
  if (!k.allFinite() || !r.allFinite()) return false;
  *K = k;
  *R = r;
  *t = tt;
  // Points in front: flip the whole solution if the mean depth is negative.
  double z = 0;
  for (const auto& X : v.object) z += (r * X + tt).z();
  if (z < 0) return false;
  return true;
}

}  // namespace

namespace {

std::vector<CalibrationView> ReadCalibrationPointsOrThrow(const std::string& path) {
  TextLines lines(path, "points file");
  std::string line;
  std::map<std::string, CalibrationView> views;
  std::vector<std::string> order;
  bool header = false;
  while (lines.Next(&line)) {
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> cols = SplitCsvFields(line);
    const std::string where = path + ":" + std::to_string(lines.line_number());
    if (!header) {
      if (cols.size() != 6 || cols[0] != "view" || cols[1] != "X" || cols[5].substr(0, 1) != "v") {
        throw CalibrationError(where + ": expected header 'view,X,Y,Z,u,v', got '" + Escaped(line) +
                               "'");
      }
      header = true;
      continue;
    }
    if (cols.size() != 6)
      throw CalibrationError(where + ": expected 6 values, found " + std::to_string(cols.size()));
    double v[5];
    for (int k = 0; k < 5; ++k) {
      const std::string& tok = cols[static_cast<size_t>(k + 1)];
      if (!ParseFiniteNumber(tok, &v[k])) {
        throw CalibrationError(where + ": column " + std::to_string(k + 2) +
                               ": expected a number, got '" + Escaped(tok) + "'");
      }
    }
    if (!views.count(cols[0])) {
      order.push_back(cols[0]);
      views[cols[0]].name = "view " + cols[0];
    }
    views[cols[0]].object.emplace_back(v[0], v[1], v[2]);
    views[cols[0]].image.emplace_back(v[3], v[4]);
  }
  if (!lines.status().ok()) throw CalibrationError(lines.status().message());
  if (!header) throw CalibrationError(path + ": empty file (no header)");
  std::vector<CalibrationView> out;
  for (const auto& k : order) out.push_back(views[k]);
  return out;
}

}  // namespace

StatusOr<std::vector<CalibrationView>> ReadCalibrationPoints(const std::string& path) {
  try {
    return ReadCalibrationPointsOrThrow(path);
  } catch (const CalibrationError& e) {
    return Status::Error(e.what());
  } catch (const cv::Exception& e) {
    return Status::Error(std::string("calibration: ") + e.what());
  }
}

namespace {

CalibrationResult Refine(const std::vector<CalibrationView>& views, const CalibrationOptions& o,
                         double* intr, std::vector<std::array<double, 6>>& poses) {
  RouteCeresLogging();
  ceres::Problem problem;
  int points = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    for (size_t k = 0; k < views[i].object.size(); ++k) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Reprojection, 2, 9, 6>(
                                   new Reprojection(views[i].object[k], views[i].image[k])),
                               nullptr, intr, poses[i].data());
      ++points;
    }
  }
  if (!o.use_k3) problem.SetManifold(intr, new ceres::SubsetManifold(9, {8}));
  ceres::Solver::Options sopt;
  sopt.max_num_iterations = o.max_iterations;
  sopt.linear_solver_type = ceres::DENSE_SCHUR;
  sopt.function_tolerance = 1e-14;
  sopt.parameter_tolerance = 1e-14;
  sopt.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(sopt, &problem, &summary);

  CalibrationResult r;
  r.camera.width = o.width;
  r.camera.height = o.height;
  r.camera.fx = intr[0];
  r.camera.fy = intr[1];
  r.camera.cx = intr[2];
  r.camera.cy = intr[3];
  r.camera.k1 = intr[4];
  r.camera.k2 = intr[5];
  r.camera.p1 = intr[6];
  r.camera.p2 = intr[7];
  r.camera.k3 = intr[8];
  r.points = points;
  r.rms_px = std::sqrt(2.0 * summary.final_cost / points);
  for (const auto& p : poses) {
    Pose3 q;
    const Eigen::Vector3d w(p[0], p[1], p[2]);
    q.R = w.norm() > 0 ? Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix()
                       : Eigen::Matrix3d::Identity();
    q.t = Eigen::Vector3d(p[3], p[4], p[5]);
    r.board_poses.push_back(q);
  }
  ceres::Covariance::Options copt;
  copt.algorithm_type = ceres::DENSE_SVD;
  copt.null_space_rank = -1;
  ceres::Covariance cov(copt);
  std::vector<std::pair<const double*, const double*>> blocks = {{intr, intr}};
  if (cov.Compute(blocks, &problem)) {
    double C[81];
    cov.GetCovarianceBlock(intr, intr, C);
    const int dof = 2 * points - (o.use_k3 ? 9 : 8) - 6 * static_cast<int>(views.size());
    const double s2 = dof > 0 ? 2.0 * summary.final_cost / dof : 1.0;
    for (int i = 0; i < 9; ++i) r.sigma[i] = std::sqrt(std::max(0.0, C[i * 9 + i] * s2));
    r.sigma_ok = true;
  }
  return r;
}

CalibrationResult CalibrateFromDlt(const std::vector<CalibrationView>& views,
                                   const std::vector<int>& dlt_views, const CalibrationOptions& o) {
  Eigen::Matrix3d Ksum = Eigen::Matrix3d::Zero();
  int used = 0;
  std::vector<std::array<double, 6>> poses(views.size());
  std::vector<bool> have(views.size(), false);
  for (int i : dlt_views) {
    Eigen::Matrix3d K, R;
    Eigen::Vector3d t;
    if (!DltView(views[static_cast<size_t>(i)], &K, &R, &t)) {
      throw CalibrationError(views[static_cast<size_t>(i)].name +
                             ": degenerate view (the DLT found no camera in front of the points)");
    }
    Ksum += K;
    ++used;
    const Eigen::AngleAxisd aa(R);
    const Eigen::Vector3d w = aa.angle() * aa.axis();
    poses[static_cast<size_t>(i)] = {w.x(), w.y(), w.z(), t.x(), t.y(), t.z()};
    have[static_cast<size_t>(i)] = true;
  }
  const Eigen::Matrix3d K = Ksum / used;
  double intr[9] = {K(0, 0), K(1, 1), K(0, 2), K(1, 2), 0, 0, 0, 0, 0};
  // Planar views among them: extrinsics from their homography and this K.
  for (size_t i = 0; i < views.size(); ++i) {
    if (have[i]) continue;
    poses[i] = PoseFromHomography(K, Homography(views[i]));
  }
  return Refine(views, o, intr, poses);
}

// The views as the fit takes them: each checked (6+ point pairs, image points inside the
// image), a planar board's plane shifted to Z = 0. Throws naming the view.
std::vector<CalibrationView> CheckedViews(const std::vector<CalibrationView>& views_in,
                                          const CalibrationOptions& o) {
  std::vector<CalibrationView> views = views_in;
  for (auto& v : views) {
    if (v.object.size() < 6 || v.object.size() != v.image.size()) {
      throw CalibrationError(v.name + ": at least 6 point pairs are needed, got " +
                             std::to_string(v.object.size()));
    }
    const double z0 = v.object.front().z();
    bool planar = true;
    for (const auto& p : v.object) planar = planar && std::abs(p.z() - z0) < 1e-9;
    if (planar) {
      for (auto& p : v.object) p.z() = 0.0;
    }
    for (const auto& p : v.image) {
      if (p.x() < -0.5 || p.y() < -0.5 || p.x() > o.width - 0.5 || p.y() > o.height - 0.5) {
        std::ostringstream m;
        m << v.name << ": image point (" << p.x() << ", " << p.y() << ") lies outside the "
          << o.width << "x" << o.height << " image";
        throw CalibrationError(m.str());
      }
    }
  }
  return views;
}

// Zhang's closed form for planar views: V b = 0 for B = K^-T K^-1 (zero skew), then each
// view's pose from its homography; refined by Refine.
CalibrationResult CalibrateFromHomographies(const std::vector<CalibrationView>& views,
                                            const CalibrationOptions& o) {
  std::vector<Eigen::Matrix3d> Hs;
  Eigen::MatrixXd V(2 * views.size() + 1, 6);
  for (size_t i = 0; i < views.size(); ++i) {
    Hs.push_back(Homography(views[i]));
    V.row(static_cast<long>(2 * i)) = Vij(Hs[i], 0, 1).transpose();
    V.row(static_cast<long>(2 * i + 1)) = (Vij(Hs[i], 0, 0) - Vij(Hs[i], 1, 1)).transpose();
  }
  V.row(static_cast<long>(2 * views.size())) << 0, 1, 0, 0, 0, 0;  // zero skew
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(V, Eigen::ComputeFullV);
  Eigen::Matrix<double, 6, 1> b = svd.matrixV().col(5);
  if (b[0] < 0) b = -b;
  const double B11 = b[0], B12 = b[1], B22 = b[2], B13 = b[3], B23 = b[4], B33 = b[5];
  const double v0 = (B12 * B13 - B11 * B23) / (B11 * B22 - B12 * B12);
  const double lambda = B33 - (B13 * B13 + v0 * (B12 * B13 - B11 * B23)) / B11;
  const double alpha = std::sqrt(lambda / B11);
  const double beta = std::sqrt(lambda * B11 / (B11 * B22 - B12 * B12));
  const double u0 = -B13 * alpha * alpha / lambda;
  if (!std::isfinite(alpha) || !std::isfinite(beta) || !std::isfinite(u0) || !std::isfinite(v0)) {
    throw CalibrationError(
        "calibration: degenerate views (all boards parallel, or too few orientations); tilt the "
        "board differently in each view");
  }
  Eigen::Matrix3d K;
  K << alpha, 0, u0, 0, beta, v0, 0, 0, 1;
  double intr[9] = {alpha, beta, u0, v0, 0, 0, 0, 0, 0};
  std::vector<std::array<double, 6>> poses(views.size());
  for (size_t i = 0; i < views.size(); ++i) {
    poses[i] = PoseFromHomography(K, Hs[i]);
  }
  return Refine(views, o, intr, poses);
}

}  // namespace

namespace {

CalibrationResult CalibrateCameraOrThrow(const std::vector<CalibrationView>& views_in,
                                         const CalibrationOptions& o) {
  if (o.width <= 0 || o.height <= 0)
    throw CalibrationError("calibration: image size must be given (WxH)");
  if (views_in.size() < 3)
    throw CalibrationError("calibration: at least 3 views are needed, got " +
                           std::to_string(views_in.size()));
  const std::vector<CalibrationView> views = CheckedViews(views_in, o);
  // Non-planar views (3-D rigs): DLT per view gives K, R, t directly; K is their mean.
  auto is_planar = [](const CalibrationView& v) {
    for (const auto& p : v.object) {
      if (p.z() != 0.0) return false;
    }
    return true;
  };
  std::vector<int> dlt_views;
  for (size_t i = 0; i < views.size(); ++i) {
    if (!is_planar(views[i])) dlt_views.push_back(static_cast<int>(i));
  }
  if (!dlt_views.empty()) return CalibrateFromDlt(views, dlt_views, o);
  return CalibrateFromHomographies(views, o);
}

}  // namespace

StatusOr<CalibrationResult> CalibrateCamera(const std::vector<CalibrationView>& views_in,
                                            const CalibrationOptions& options) {
  try {
    return CalibrateCameraOrThrow(views_in, options);
  } catch (const CalibrationError& e) {
    return Status::Error(e.what());
  } catch (const cv::Exception& e) {
    return Status::Error(std::string("calibration: ") + e.what());
  }
}

}  // namespace kincal::vision
