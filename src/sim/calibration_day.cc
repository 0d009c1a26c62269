#include "sim/calibration_day.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "kincal/vision/calibration.h"

namespace kincal {
namespace {

// The board's marker centres in its own frame (z = 0), centred on its middle.
std::vector<Eigen::Vector3d> BoardPoints(const CameraCalibrationErrors& o) {
  std::vector<Eigen::Vector3d> p;
  for (int r = 0; r < o.board_rows; ++r) {
    for (int c = 0; c < o.board_cols; ++c) {
      p.emplace_back((c - 0.5 * (o.board_cols - 1)) * o.board_pitch_m,
                     (r - 0.5 * (o.board_rows - 1)) * o.board_pitch_m, 0.0);
    }
  }
  return p;
}

// The board -> camera poses of the five views: flat on the floor at the origin (board
// axes the floor's), then tilted about its x and its y axis each way, its middle raised by
// what keeps the tilted edge off the floor.
std::vector<vision::Pose3> BoardPoses(const ThesisVision& truth, const CameraCalibrationErrors& o) {
  const double half_x = 0.5 * (o.board_cols - 1) * o.board_pitch_m;
  const double half_y = 0.5 * (o.board_rows - 1) * o.board_pitch_m;
  std::vector<vision::Pose3> poses;
  poses.push_back({truth.floor.R_cf, truth.floor.t_cf});
  for (const auto& [axis, sign] : {std::pair{0, 1.0}, {0, -1.0}, {1, 1.0}, {1, -1.0}}) {
    const Eigen::Vector3d a = axis == 0 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(sign * o.tilt_rad, a).toRotationMatrix();
    const double lift = (axis == 0 ? half_y : half_x) * std::sin(o.tilt_rad);
    const Eigen::Vector3d middle(0.0, 0.0, lift);  // in the floor frame
    poses.push_back({truth.floor.R_cf * tilt, truth.floor.R_cf * middle + truth.floor.t_cf});
  }
  return poses;
}

// The views of `board` at `poses` through `camera`, their centres given noise of `sigma_px`.
std::vector<vision::CalibrationView> Views(const vision::CameraModel& camera,
                                           const std::vector<vision::Pose3>& poses,
                                           const std::vector<Eigen::Vector3d>& board,
                                           double sigma_px, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, sigma_px);
  std::vector<vision::CalibrationView> views;
  for (const vision::Pose3& pose : poses) {
    vision::CalibrationView v;
    v.name = "calibration view " + std::to_string(views.size() + 1);
    for (const Eigen::Vector3d& q : board) {
      const Eigen::Vector2d px = camera.Project(pose.R * q + pose.t);
      const double du = noise(rng);  // drawn in sequence: argument order is unspecified
      const double dv = noise(rng);
      v.object.push_back(q);
      v.image.push_back(px + Eigen::Vector2d(du, dv));
    }
    views.push_back(std::move(v));
  }
  return views;
}

// The camera and floor the views calibrate to (the first view's board is the floor).
StatusOr<ThesisVision> Calibrate(const ThesisVision& base,
                                 const std::vector<vision::CalibrationView>& views,
                                 vision::CalibrationResult* result) {
  vision::CalibrationOptions co;
  co.width = base.camera.width;
  co.height = base.camera.height;
  auto cal = vision::CalibrateCamera(views, co);
  if (!cal.ok()) return Status::Error("the day's camera calibration: " + cal.status().message());
  *result = std::move(cal).value();
  ThesisVision day = base;
  day.camera = result->camera;
  day.floor.R_cf = result->board_poses.front().R;
  day.floor.t_cf = result->board_poses.front().t;
  return day;
}

constexpr int kBootstrapDraws = 16;

}  // namespace

StatusOr<CalibratedDay> CalibrateDay(const ThesisVision& truth, const CameraCalibrationErrors& o,
                                     double centroid_sigma_px, std::mt19937_64& rng) {
  const std::vector<Eigen::Vector3d> board = BoardPoints(o);
  vision::CalibrationResult cal;
  StatusOr<ThesisVision> first = Calibrate(
      truth, Views(truth.camera, BoardPoses(truth, o), board, centroid_sigma_px, rng), &cal);
  if (!first.ok()) return first.status();
  CalibratedDay day;
  day.vision = std::move(first).value();
  // The noise the residuals show, per axis (rms_px is over both axes; dof corrected).
  const int params = 8 + 6 * static_cast<int>(cal.board_poses.size());
  const double sigma =
      cal.rms_px * std::sqrt(static_cast<double>(cal.points) / (2.0 * cal.points - params));
  // Robustly (1.4826 x the median absolute scale): a redo that lands in another minimum
  // would otherwise make the sigma of all.
  std::vector<double> scales;
  for (int k = 0; k < kBootstrapDraws; ++k) {
    vision::CalibrationResult again;
    const StatusOr<ThesisVision> redo =
        Calibrate(truth, Views(day.vision.camera, cal.board_poses, board, sigma, rng), &again);
    if (!redo.ok()) return Status::Error(redo.status().message() + " (its bootstrap)");
    scales.push_back(std::abs(CompareFloorMaps(day.vision, redo.value()).scale));
  }
  std::nth_element(scales.begin(), scales.begin() + kBootstrapDraws / 2, scales.end());
  day.scale_sigma = 1.4826 * scales[kBootstrapDraws / 2];
  return day;
}

namespace {

// Floor point (x, y) on the plane at the plate's height as `calibrated` sees it where
// `reference` images it; none outside the image or where either camera's distortion
// folds (a calibrated polynomial far outside the points it was fitted to can image a
// point from outside the view into it: the inversion then finds another ray).
std::optional<Eigen::Vector2d> MapPoint(const ThesisVision& reference,
                                        const ThesisVision& calibrated, const Eigen::Vector2d& xy) {
  const double h = reference.target_height_m;
  const Eigen::Vector3d pc =
      reference.floor.R_cf * Eigen::Vector3d(xy.x(), xy.y(), h) + reference.floor.t_cf;
  if (!(pc.z() > 0.0)) return std::nullopt;
  const Eigen::Vector2d px = reference.camera.Project(pc);
  if (px.x() < 0 || px.y() < 0 || px.x() > reference.camera.width - 1 ||
      px.y() > reference.camera.height - 1)
    return std::nullopt;
  const Eigen::Vector2d n = calibrated.camera.PixelToNormalized(px);
  if ((reference.camera.PixelToNormalized(px) - pc.head<2>() / pc.z()).norm() > 1e-6 ||
      (calibrated.camera.NormalizedToPixel(n) - px).norm() > 1e-3)
    return std::nullopt;
  // The pixel's ray through the calibration, met with the plane z = h of its floor.
  const Eigen::Matrix3d Rt = calibrated.floor.R_cf.transpose();
  const Eigen::Vector3d origin = -Rt * calibrated.floor.t_cf;
  const Eigen::Vector3d dir = Rt * Eigen::Vector3d(n.x(), n.y(), 1.0);
  const double s = (h - origin.z()) / dir.z();
  return (origin + s * dir).head<2>();
}

}  // namespace

Eigen::Vector3d MapPose(const ThesisVision& reference, const ThesisVision& calibrated,
                        const Eigen::Vector3d& pose) {
  constexpr double kAlong = 0.1;
  const Eigen::Vector2d at = pose.head<2>();
  const Eigen::Vector2d ahead =
      at + kAlong * Eigen::Vector2d(std::cos(pose.z()), std::sin(pose.z()));
  const auto a = MapPoint(reference, calibrated, at), b = MapPoint(reference, calibrated, ahead);
  if (!a || !b) return pose;
  const Eigen::Vector2d d = *b - *a;
  return Eigen::Vector3d(a->x(), a->y(), std::atan2(d.y(), d.x()));
}

FloorMapError CompareFloorMaps(const ThesisVision& reference, const ThesisVision& calibrated) {
  std::vector<std::pair<Eigen::Vector2d, Eigen::Vector2d>> pairs;  // (reference, calibrated)
  for (double x = -1.0; x <= 1.0 + 1e-9; x += 0.05) {
    for (double y = -1.0; y <= 1.0 + 1e-9; y += 0.05) {
      // Where the robot's plate can be measured (the whole plate in view): the workspace.
      if (!PlateInView(reference, Eigen::Vector3d(x, y, 0.0), 0.0)) continue;
      if (const auto c = MapPoint(reference, calibrated, {x, y})) pairs.push_back({{x, y}, *c});
    }
  }
  FloorMapError e;
  e.points = static_cast<int>(pairs.size());
  if (pairs.size() < 3) return e;
  // The least-squares similarity c = k Q t + b (Umeyama, in the plane).
  Eigen::Vector2d mt = Eigen::Vector2d::Zero(), mc = Eigen::Vector2d::Zero();
  for (const auto& [t, c] : pairs) {
    mt += t;
    mc += c;
  }
  mt /= static_cast<double>(pairs.size());
  mc /= static_cast<double>(pairs.size());
  double a = 0.0, b = 0.0, var = 0.0;  // sum of dot and cross products, and |t|^2
  for (const auto& [t, c] : pairs) {
    const Eigen::Vector2d dt = t - mt, dc = c - mc;
    a += dt.dot(dc);
    b += dt.x() * dc.y() - dt.y() * dc.x();
    var += dt.squaredNorm();
  }
  const double k = std::hypot(a, b) / var;
  const double phi = std::atan2(b, a);
  const Eigen::Matrix2d Q = Eigen::Rotation2Dd(phi).toRotationMatrix();
  double ss = 0.0;
  for (const auto& [t, c] : pairs) ss += (c - mc - k * Q * (t - mt)).squaredNorm();
  e.scale = k - 1.0;
  e.rms_m = std::sqrt(ss / static_cast<double>(pairs.size()));
  return e;
}

}  // namespace kincal
