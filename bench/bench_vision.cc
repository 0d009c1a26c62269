// Detection + pose per frame against the OpenCV baselines, and pose solvers against
// cv::solvePnP, on synthetic frames measured in the same run.
#include <benchmark/benchmark.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "kincal/vision/calibration.h"
#include "kincal/vision/markers.h"
#include "kincal/vision/opencv_baseline.h"
#include "kincal/vision/pose.h"
#include "kincal/vision/synthetic.h"

namespace kincal::vision {
namespace {

struct Scene {
  CameraModel cam;
  TargetLayout layout = TargetLayout::Thesis();
  RenderedFrame frame;
  std::vector<Eigen::Vector3d> obj;
  std::vector<Eigen::Vector2d> norm;
  Pose3 truth;
};

Scene MakeScene(int width, int height) {
  Scene s;
  s.cam = CameraModel::Centred(width, height, 820.0 * width / 640.0);
  s.cam.k1 = -0.1;
  const Eigen::Matrix3d R_cf = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  s.truth.R = R_cf * Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  s.truth.t = R_cf * Eigen::Vector3d(0.05, -0.03, 0.1) + Eigen::Vector3d(0, 0, 1.2);
  std::mt19937_64 rng(1);
  s.frame = RenderTarget(s.cam, s.truth, s.layout, RenderOptions{}, rng);
  for (size_t i = 0; i < s.layout.markers.size(); ++i) {
    s.obj.emplace_back(s.layout.markers[i].x(), s.layout.markers[i].y(), 0.0);
    s.norm.push_back(s.cam.PixelToNormalized(s.frame.centres[i]));
  }
  return s;
}

void DetectAndPose(const Scene& s, std::vector<Marker>& markers, benchmark::State& state) {
  if (!IdentifyTarget(s.cam, s.layout, &markers)) {
    state.SkipWithError("target not found");
    return;
  }
  std::vector<Eigen::Vector3d> obj;
  std::vector<Eigen::Vector2d> norm;
  for (const auto& m : markers) {
    if (m.id < 0) continue;
    obj.push_back(s.obj[static_cast<size_t>(m.id)]);
    norm.push_back(s.cam.PixelToNormalized(m.centre_px));
  }
  Pose3 init;
  PlanarInitialPose(obj, norm, &init);
  benchmark::DoNotOptimize(LowePose(obj, norm, init, s.cam.fx, 0.02));
}

void BM_KincalFullFrame(benchmark::State& state) {
  const Scene s = MakeScene(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  for (auto _ : state) {
    auto markers = DetectMarkers(s.frame.image, DetectorOptions{});
    DetectAndPose(s, markers, state);
  }
}

void BM_KincalTracked(benchmark::State& state) {
  const Scene s = MakeScene(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  MarkerTracker tracker(s.cam, s.layout, DetectorOptions{});
  tracker.Track(s.frame.image);
  for (auto _ : state) {
    auto markers = tracker.Track(s.frame.image);
    DetectAndPose(s, markers, state);
  }
}

void BM_OpenCvThresholdComponents(benchmark::State& state) {
  const Scene s = MakeScene(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  cv::Mat bin, labels, stats, centroids;
  for (auto _ : state) {
    cv::threshold(s.frame.image, bin, 0, 255, cv::THRESH_BINARY_INV | cv::THRESH_OTSU);
    benchmark::DoNotOptimize(cv::connectedComponentsWithStats(bin, labels, stats, centroids));
  }
}

void BM_OpenCvBlobDetectorSolvePnP(benchmark::State& state) {
  const Scene s = MakeScene(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  cv::SimpleBlobDetector::Params p;
  p.filterByColor = true;
  p.blobColor = 0;
  p.minArea = 10;
  auto det = cv::SimpleBlobDetector::create(p);
  std::vector<cv::Point3d> obj;
  for (const auto& o : s.obj) obj.emplace_back(o.x(), o.y(), 0);
  const cv::Mat K =
      (cv::Mat_<double>(3, 3) << s.cam.fx, 0, s.cam.cx, 0, s.cam.fy, s.cam.cy, 0, 0, 1);
  const cv::Mat D = (cv::Mat_<double>(5, 1) << s.cam.k1, 0, 0, 0, 0);
  for (auto _ : state) {
    std::vector<cv::KeyPoint> kp;
    det->detect(s.frame.image, kp);
    if (kp.size() < 4) {
      state.SkipWithError("blobs not found");
      return;
    }
    // Correspondences taken from the ground truth order (the baseline gets them for free).
    std::vector<cv::Point2d> img;
    for (const auto& c : s.frame.centres) img.emplace_back(c.x(), c.y());
    cv::Mat rvec, tvec;
    cv::solvePnP(obj, img, K, D, rvec, tvec, false, cv::SOLVEPNP_IPPE);
    benchmark::DoNotOptimize(tvec);
  }
}

// Pose problems with known truth: the thesis target seen by a 640x480 camera (fx 820 px)
// from random poses 0.6-1.5 m away, tilted up to 45 deg, anywhere in the view; marker
// centres perturbed by 0.1 px (1 sigma). Every solver gets the same problems.
struct PoseProblem {
  std::vector<Eigen::Vector3d> obj;
  std::vector<Eigen::Vector2d> norm;
  Pose3 truth;
};

const std::vector<PoseProblem>& PoseProblems() {
  static const std::vector<PoseProblem> problems = [] {
    constexpr double kFx = 820.0, kNoisePx = 0.1, kHalfW = 320.0 / kFx, kHalfH = 240.0 / kFx;
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    std::normal_distribution<double> noise(0.0, kNoisePx / kFx);
    const TargetLayout layout = TargetLayout::Thesis();
    std::vector<PoseProblem> out;
    while (out.size() < 512) {
      PoseProblem p;
      const double depth = 0.6 + 0.9 * U(rng), tilt = 0.785 * U(rng), tilt_dir = 2 * M_PI * U(rng);
      const double yaw = 2 * M_PI * U(rng), ux = 2 * U(rng) - 1, uy = 2 * U(rng) - 1;
      p.truth.R =
          Eigen::AngleAxisd(tilt, Eigen::Vector3d(std::cos(tilt_dir), std::sin(tilt_dir), 0))
              .toRotationMatrix() *
          Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix() *
          Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      p.truth.t = Eigen::Vector3d(0.8 * kHalfW * ux * depth, 0.8 * kHalfH * uy * depth, depth);
      bool inside = true;
      for (const auto& m : layout.markers) {
        const Eigen::Vector3d X(m.x(), m.y(), 0.0);
        const Eigen::Vector3d Xc = p.truth.R * X + p.truth.t;
        const double nv = noise(rng), nu = noise(rng);
        const Eigen::Vector2d n = Xc.head<2>() / Xc.z() + Eigen::Vector2d(nu, nv);
        inside = inside && Xc.z() > 0.1 && std::abs(n.x()) < kHalfW && std::abs(n.y()) < kHalfH;
        p.obj.push_back(X);
        p.norm.push_back(n);
      }
      if (inside) out.push_back(std::move(p));
    }
    return out;
  }();
  return problems;
}

using PoseSolver = bool (*)(const PoseProblem&, Pose3*);

bool SolveLowe(const PoseProblem& p, Pose3* pose) {
  Pose3 init;  // from the homography, as the daemon does on a first sighting
  if (!PlanarInitialPose(p.obj, p.norm, &init)) return false;
  const LoweResult r = LowePose(p.obj, p.norm, init, 820.0, 0.1);
  *pose = r.pose;
  return r.ok;
}

template <int kMethod>
bool SolveOpenCv(const PoseProblem& p, Pose3* pose) {
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  for (size_t i = 0; i < p.obj.size(); ++i) {
    obj.emplace_back(p.obj[i].x(), p.obj[i].y(), 0.0);
    img.emplace_back(p.norm[i].x(), p.norm[i].y());
  }
  cv::Mat rvec, tvec, R;
  if (!cv::solvePnP(obj, img, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, false, kMethod))
    return false;
  cv::Rodrigues(rvec, R);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) pose->R(r, c) = R.at<double>(r, c);
    pose->t(r) = tvec.at<double>(r);
  }
  return true;
}

// Time per pose over the problem set, then (untimed) the error of every solution.
void PoseBenchmark(benchmark::State& state, PoseSolver solve) {
  const auto& problems = PoseProblems();
  size_t i = 0;
  Pose3 pose;
  for (auto _ : state) {
    benchmark::DoNotOptimize(solve(problems[i], &pose));
    i = (i + 1) % problems.size();
  }
  double pos2 = 0, rot2 = 0;
  int failed = 0;
  for (const auto& p : problems) {
    if (!solve(p, &pose)) {
      ++failed;
      continue;
    }
    const double rot = Eigen::AngleAxisd(pose.R * p.truth.R.transpose()).angle();
    const double pos = (pose.t - p.truth.t).norm();
    if (pos > 0.05 || rot > 0.2) {  // a wrong solution (e.g. the mirrored planar pose)
      ++failed;
      continue;
    }
    pos2 += pos * pos;
    rot2 += rot * rot;
  }
  const double ok = static_cast<double>(problems.size()) - failed;
  state.counters["pos_rms_mm"] = 1e3 * std::sqrt(pos2 / ok);
  state.counters["rot_rms_mrad"] = 1e3 * std::sqrt(rot2 / ok);
  state.counters["failed_pct"] = 100.0 * failed / static_cast<double>(problems.size());
}

void BM_PoseLowe(benchmark::State& state) { PoseBenchmark(state, SolveLowe); }
void BM_PoseSolvePnPIterative(benchmark::State& state) {
  PoseBenchmark(state, SolveOpenCv<cv::SOLVEPNP_ITERATIVE>);
}
void BM_PoseSolvePnPIppe(benchmark::State& state) {
  PoseBenchmark(state, SolveOpenCv<cv::SOLVEPNP_IPPE>);
}

// Lowe refining from the previous frame's pose (the tracking case): no homography.
void BM_LoweFromPreviousPose(benchmark::State& state) {
  const Scene s = MakeScene(640, 480);
  Pose3 init;
  PlanarInitialPose(s.obj, s.norm, &init);
  init.t += Eigen::Vector3d(0.002, -0.001, 0.003);
  for (auto _ : state) benchmark::DoNotOptimize(LowePose(s.obj, s.norm, init, s.cam.fx, 0.02));
}

void BM_GroundPlane(benchmark::State& state) {
  const Scene s = MakeScene(640, 480);
  FloorExtrinsics floor;
  floor.R_cf = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  floor.t_cf = Eigen::Vector3d(0, 0, 1.2);
  for (auto _ : state) {
    benchmark::DoNotOptimize(GroundPlanePose(floor, 0.1, s.obj, s.norm,
                                             Eigen::Vector3d(0.04, -0.02, 0.55), s.cam.fx, 0.02));
  }
}

// Detection cost against the number of markers: a 1280x720 frame with k dark discs
// (radius 6 px, anti-aliased, blurred, noisy) on a light floor.
void BM_DetectVsMarkers(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0));
  cv::Mat img(720, 1280, CV_8UC1, cv::Scalar(200));
  const int cols = static_cast<int>(std::ceil(std::sqrt(k * 16.0 / 9.0)));
  for (int i = 0; i < k; ++i) {
    const int r = i / cols, c = i % cols;
    const double step = 1240.0 / cols;
    cv::circle(img,
               cv::Point(static_cast<int>(20 + step * (c + 0.5)) * 16,
                         static_cast<int>(20 + step * (r + 0.5)) * 16),
               6 * 16, cv::Scalar(40), cv::FILLED, cv::LINE_AA, 4);
  }
  cv::GaussianBlur(img, img, cv::Size(0, 0), 0.6);
  cv::Mat n(img.size(), CV_16SC1);
  cv::theRNG().state = 1;
  cv::randn(n, 0, 1.0);
  cv::add(img, n, img, cv::noArray(), CV_8UC1);
  size_t found = 0;
  for (auto _ : state) {
    auto markers = DetectMarkers(img, DetectorOptions{});
    found = markers.size();
    benchmark::DoNotOptimize(markers.data());
  }
  state.counters["markers"] = k;
  state.counters["found"] = static_cast<double>(found);
}

// Camera calibration: ours against cv::calibrateCamera on the same 15 synthetic views
// (9 x 6 board, 0.1 px noise, k1 k2 p1 p2 free, k3 fixed), time and intrinsic error.
void CalibrationBenchmark(benchmark::State& state, bool opencv) {
  CameraModel truth;
  truth.width = 640;
  truth.height = 480;
  truth.fx = truth.fy = 820;
  truth.cx = 321.3;
  truth.cy = 238.7;
  truth.k1 = -0.12;
  truth.k2 = 0.05;
  truth.p1 = 0.0007;
  truth.p2 = -0.0004;
  std::mt19937_64 rng(21);
  const auto views = SyntheticBoardViews(truth, 15, 0.1, rng);
  CalibrationOptions opt;
  opt.width = truth.width;
  opt.height = truth.height;
  CameraModel est;
  double rms = 0;
  for (auto _ : state) {
    if (opencv) {
      const OpenCvCalibration r = CalibrateWithOpenCv(views, opt, CameraModel{});
      est = r.camera;
      rms = r.rms_px;
    } else {
      const CalibrationResult r = CalibrateCamera(views, opt).value();
      est = r.camera;
      rms = r.rms_px;
    }
  }
  state.counters["fx_err_px"] = std::abs(est.fx - truth.fx);
  state.counters["fy_err_px"] = std::abs(est.fy - truth.fy);
  state.counters["cx_err_px"] = std::abs(est.cx - truth.cx);
  state.counters["cy_err_px"] = std::abs(est.cy - truth.cy);
  state.counters["k1_err"] = std::abs(est.k1 - truth.k1);
  state.counters["rms_px"] = rms;
}
void BM_CalibrateKincal(benchmark::State& state) { CalibrationBenchmark(state, false); }
void BM_CalibrateOpenCv(benchmark::State& state) { CalibrationBenchmark(state, true); }

#define RESOLUTIONS ->Args({640, 480})->Args({1280, 720})->Args({1920, 1080})
BENCHMARK(BM_KincalFullFrame) RESOLUTIONS;
BENCHMARK(BM_KincalTracked) RESOLUTIONS;
BENCHMARK(BM_OpenCvThresholdComponents) RESOLUTIONS;
BENCHMARK(BM_OpenCvBlobDetectorSolvePnP) RESOLUTIONS;
BENCHMARK(BM_PoseLowe);
BENCHMARK(BM_PoseSolvePnPIterative);
BENCHMARK(BM_PoseSolvePnPIppe);
BENCHMARK(BM_LoweFromPreviousPose);
BENCHMARK(BM_GroundPlane);
BENCHMARK(BM_DetectVsMarkers)->Arg(4)->Arg(16)->Arg(64)->Arg(256);
BENCHMARK(BM_CalibrateKincal)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CalibrateOpenCv)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace kincal::vision
