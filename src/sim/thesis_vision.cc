#include "kincal/sim/thesis_vision.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "kincal/vision/floor_pose_solver.h"
#include "sim/calibration_day.h"

namespace kincal {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
// Table 6-3.
constexpr double kHeightM = 1.58911;
constexpr double kTiltDeg = 19.30;              // phi
constexpr double kRollDeg = 180.0 - 178.01;     // psi's deviation from looking down
constexpr double kAboutAxisDeg = 90.0 - 89.32;  // theta's deviation from the floor axes
constexpr double kFocalMm = 6.8313;
constexpr double kFocalPx = 500.0;  // chosen: see the header
// 99.9 % point of chi-square with 2 degrees of freedom (four markers, six unknowns).
constexpr double kMaxFitChi2 = 13.8;
// Grey-level noise of the first calibration pass.
constexpr double kTrialNoiseGrey = 3.0;
// The centres must scatter as asked to this fraction after the image noise is scaled
// (sampling error of the scatter: about 4 % with 64 frames of 4 markers).
constexpr double kCalibrationTolerance = 0.15;
// Calibration frames: a centre this many robust sigmas off is a misdetection; more than
// this fraction of such frames means the noise breaks the detection.
constexpr double kGrossSigmas = 8.0;
constexpr double kMaxGrossFraction = 0.1;

vision::FloorExtrinsics Table63Floor() {
  // Rows of R_cf are the camera axes in floor coordinates. Looking straight down with image
  // x along floor x, then tilted about the camera's x axis, rolled about its y axis and
  // turned about its optical axis.
  Eigen::Matrix3d down;
  down << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  const Eigen::Matrix3d turn = (Eigen::AngleAxisd(kAboutAxisDeg * kDeg, Eigen::Vector3d::UnitZ()) *
                                Eigen::AngleAxisd(kRollDeg * kDeg, Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(-kTiltDeg * kDeg, Eigen::Vector3d::UnitX()))
                                   .toRotationMatrix();
  vision::FloorExtrinsics f;
  f.R_cf = turn * down;
  // The optical axis meets the floor at the origin: centre C = -s z_c with C.z = height.
  const Eigen::Vector3d z_c = f.R_cf.row(2).transpose();
  const Eigen::Vector3d centre = -z_c * (kHeightM / -z_c.z());
  f.t_cf = -f.R_cf * centre;
  return f;
}

// 4 x 4 sub-samples on marker edges: the anti-aliased centre is then good to a few
// hundredths of a pixel, well inside the 0.14 px noise, at a quarter of the default's cost.
vision::RenderOptions RenderOptionsFor(const PixelPoseOptions& o, double noise_grey) {
  vision::RenderOptions r;
  r.supersample = o.supersample;
  r.blur_sigma_px = o.blur_sigma_px;
  r.noise_sigma = noise_grey;
  return r;
}

}  // namespace

ThesisVision ThesisTable63Vision() {
  ThesisVision v;
  vision::CameraModel& c = v.camera;
  c.width = 320;
  c.height = 240;
  c.fx = c.fy = kFocalPx;
  c.cx = 151.51;
  c.cy = 119.88;
  const double f = kFocalMm;
  c.k1 = -6.522413e-3 * f * f;
  c.k2 = 2.643364e-4 * f * f * f * f;
  c.p1 = -1.713880e-4 * f;
  c.p2 = 1.428032e-3 * f;
  v.floor = Table63Floor();
  v.layout = vision::TargetLayout::Thesis();
  v.layout.marker_radius_m = 0.010;
  v.target_height_m = 0.10;
  return v;
}

bool PlateInView(const ThesisVision& v, const Eigen::Vector3d& pose, double margin_px) {
  const vision::Pose3 p = vision::CameraPoseOnFloor(v.floor, pose, v.target_height_m);
  const Eigen::Vector2d half = 0.5 * v.layout.plate_size_m;
  for (const double sx : {-1.0, 1.0}) {
    for (const double sy : {-1.0, 1.0}) {
      const Eigen::Vector3d q = p.R * Eigen::Vector3d(sx * half.x(), sy * half.y(), 0.0) + p.t;
      if (!(q.z() > 0.0)) return false;
      const Eigen::Vector2d px = v.camera.Project(q);
      if (!(px.x() >= margin_px && px.y() >= margin_px &&
            px.x() <= v.camera.width - 1 - margin_px && px.y() <= v.camera.height - 1 - margin_px))
        return false;
    }
  }
  return true;
}

bool CameraCalibrationErrors::IsValid(std::string* error) const {
  if (runs_per_day < 1 || board_cols < 3 || board_rows < 3 || !(board_pitch_m > 0.0) ||
      !(tilt_rad > 0.0 && tilt_rad < 1.2)) {
    *error =
        "pixel.calibration: runs_per_day >= 1, a board of at least 3 x 3 markers, a positive "
        "pitch and tilt_rad in (0, 1.2) expected";
    return false;
  }
  return true;
}

bool PixelPoseOptions::IsValid(std::string* error) const {
  if (!calibration.IsValid(error)) return false;
  if (!(centroid_sigma_px > 0.0 && centroid_sigma_px < 2.0) ||
      !(blur_sigma_px >= 0.0 && blur_sigma_px < 5.0) || calibration_frames < 8 || supersample < 1 ||
      supersample > 16) {
    *error =
        "pixel: centroid_sigma_px in (0, 2), blur_sigma_px in [0, 5), calibration_frames "
        ">= 8 and supersample in [1, 16] expected";
    return false;
  }
  return true;
}

PixelPoseMeter::PixelPoseMeter(ThesisVision vision, const PixelPoseOptions& options)
    : vision_(std::move(vision)),
      calibrated_(vision_),
      options_(options),
      day_rng_(options.calibration.seed),
      tracker_(vision_.camera, vision_.layout, vision::DetectorOptions{}) {}

StatusOr<std::unique_ptr<PixelPoseMeter>> PixelPoseMeter::Make(ThesisVision vision,
                                                               const PixelPoseOptions& options,
                                                               std::mt19937_64& rng) {
  std::string error;
  if (!options.IsValid(&error)) return Status::Error(error);
  std::unique_ptr<PixelPoseMeter> meter(new PixelPoseMeter(std::move(vision), options));
  const Status noise = meter->SetNoise(rng);
  if (!noise.ok()) return noise;
  return meter;
}

Status PixelPoseMeter::SetNoise(std::mt19937_64& rng) {
  noise_grey_ = kTrialNoiseGrey;
  for (int pass = 0; pass < 2; ++pass) {
    const double s = CentreScatter(noise_grey_, rng);
    if (!(s > 0.0)) return Status::Error("pixel: the calibration target was not detected");
    noise_grey_ *= options_.centroid_sigma_px / s;
  }
  measured_sigma_ = CentreScatter(noise_grey_, rng);
  // Noise that breaks the detection (misplaced centres) makes the scatter jump instead:
  // then the scaling does not converge, and the scatter asked for cannot be had.
  if (!(std::abs(measured_sigma_ / options_.centroid_sigma_px - 1.0) <= kCalibrationTolerance)) {
    return Status::Error("pixel: detected centres cannot be made to scatter by " +
                         std::to_string(options_.centroid_sigma_px) +
                         " px with this camera and target (" + std::to_string(measured_sigma_) +
                         " px at " + std::to_string(noise_grey_) +
                         " grey levels of image noise; more breaks the detection): ask for less");
  }
  return {};
}

// Scatter (px per axis) of each marker's detected centre about its own median over frames
// of a still target at the workspace origin. A frame with a centre beyond kGrossSigmas
// robust sigmas (1.4826 x the median absolute deviation) is a misdetection, not scatter,
// and is left out; when more than one frame in kMaxGrossFraction^-1 is, the noise breaks
// the detection, and the scatter of all frames (which jumps) is returned.
double PixelPoseMeter::CentreScatter(double noise_grey, std::mt19937_64& rng) {
  const Eigen::Vector3d at(0.0, 0.0, 0.3);
  const vision::Pose3 pose = vision::CameraPoseOnFloor(vision_.floor, at, vision_.target_height_m);
  vision::RenderOptions r = RenderOptionsFor(options_, noise_grey);
  const size_t n = vision_.layout.markers.size();
  vision::MarkerTracker tracker(vision_.camera, vision_.layout, vision::DetectorOptions{});
  std::vector<std::vector<Eigen::Vector2d>> frames;  // [frame][marker id]
  for (int k = 0; k < options_.calibration_frames; ++k) {
    const auto frame = vision::RenderTarget(vision_.camera, pose, vision_.layout, r, rng);
    const auto markers = tracker.Track(frame.image);
    if (markers.size() != n) continue;
    std::vector<Eigen::Vector2d> centres(n);
    for (const auto& m : markers) centres[static_cast<size_t>(m.id)] = m.centre_px;
    frames.push_back(std::move(centres));
  }
  if (frames.size() < 4) return 0.0;
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  // Each marker's median centre, then every per-axis deviation from it.
  std::vector<Eigen::Vector2d> centre(n);
  std::vector<double> abs_dev;
  for (size_t i = 0; i < n; ++i) {
    for (int axis = 0; axis < 2; ++axis) {
      std::vector<double> v;
      for (const auto& f : frames) v.push_back(f[i][axis]);
      centre[i][axis] = median(v);
      for (const double x : v) abs_dev.push_back(std::abs(x - centre[i][axis]));
    }
  }
  const double limit = kGrossSigmas * 1.4826 * median(abs_dev);
  auto gross = [&](const std::vector<Eigen::Vector2d>& f) {
    for (size_t i = 0; i < n; ++i) {
      if ((f[i] - centre[i]).cwiseAbs().maxCoeff() > limit) return true;
    }
    return false;
  };
  std::vector<char> keep(frames.size());
  size_t bad = 0;
  for (size_t k = 0; k < frames.size(); ++k) {
    keep[k] = !gross(frames[k]);
    bad += keep[k] ? 0 : 1;
  }
  if (static_cast<double>(bad) > kMaxGrossFraction * static_cast<double>(frames.size())) {
    std::fill(keep.begin(), keep.end(), 1);  // broken: the scatter of every frame
  }
  double ss = 0.0;
  int dof = 0;
  for (size_t i = 0; i < n; ++i) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    int count = 0;
    for (size_t k = 0; k < frames.size(); ++k) {
      if (keep[k]) {
        mean += frames[k][i];
        ++count;
      }
    }
    mean /= static_cast<double>(count);
    for (size_t k = 0; k < frames.size(); ++k) {
      if (keep[k]) ss += (frames[k][i] - mean).squaredNorm();
    }
    dof += 2 * (count - 1);
  }
  return dof > 0 ? std::sqrt(ss / dof) : 0.0;
}

Status PixelPoseMeter::BeginDay() {
  if (!options_.calibration.enabled) return {};
  StatusOr<CalibratedDay> day =
      CalibrateDay(vision_, options_.calibration, options_.centroid_sigma_px, day_rng_);
  if (!day.ok()) return day.status();
  calibrated_ = std::move(day->vision);
  scale_sigma_ = day->scale_sigma;
  return {};
}

bool PixelPoseMeter::Solve(const std::vector<vision::Marker>& markers, vision::PlanarPose* out) {
  // On the floor through the plate's known height, not its solved depth: the depth of
  // four close markers seen from 1.7 m is biased at this noise (a scale of every
  // position, 2e-4 of all lengths in the joint estimate; docs/thesis.md). A solve whose
  // centres do not fit is refused at the 99.9 % point of its chi-square.
  vision::FloorPoseSolverOptions o;
  o.method = vision::FloorPoseMethod::kLowe;
  o.sigma_px = options_.centroid_sigma_px;
  o.max_chi2 = kMaxFitChi2;
  vision::FloorPoseSolver solver(calibrated_.camera, calibrated_.floor, calibrated_.layout,
                                 calibrated_.target_height_m, o);
  return solver.Solve(markers, nullptr, out);
}

bool PixelPoseMeter::Measure(const Eigen::Vector3d& pose, std::mt19937_64& rng, Eigen::Vector3d* z,
                             Eigen::Matrix3d* R) {
  const vision::RenderOptions r = RenderOptionsFor(options_, noise_grey_);
  const vision::Pose3 p = vision::CameraPoseOnFloor(vision_.floor, pose, vision_.target_height_m);
  const auto frame = vision::RenderTarget(vision_.camera, p, vision_.layout, r, rng);
  auto markers = tracker_.Track(frame.image);
  if (markers.size() != vision_.layout.markers.size()) return false;
  vision::PlanarPose solved;
  if (!Solve(markers, &solved)) return false;
  // The image of a marker's centre is not the centre of its image: correct at the solved
  // pose and solve again, as kincald's pose stage does.
  vision::CorrectPerspectiveBias(
      calibrated_.camera,
      vision::CameraPoseOnFloor(calibrated_.floor, solved.xytheta, calibrated_.target_height_m),
      calibrated_.layout, &markers);
  if (!Solve(markers, &solved)) return false;
  *z = solved.xytheta;
  *R = solved.covariance;
  return true;
}

}  // namespace kincal
