// Detection + pose per frame against the OpenCV baselines, and pose solvers against
// cv::solvePnP, on synthetic frames measured in the same run.
#include <benchmark/benchmark.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "kincal/vision/markers.h"
#include "kincal/vision/pose.h"

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
  s.cam.width = width;
  s.cam.height = height;
  s.cam.fx = s.cam.fy = 820.0 * width / 640.0;
  s.cam.cx = 0.5 * (width - 1);
  s.cam.cy = 0.5 * (height - 1);
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
  const cv::Mat K = (cv::Mat_<double>(3, 3) << s.cam.fx, 0, s.cam.cx, 0, s.cam.fy, s.cam.cy, 0, 0, 1);
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

void BM_Lowe(benchmark::State& state) {
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
    benchmark::DoNotOptimize(GroundPlanePose(floor, 0.1, s.obj, s.norm, Eigen::Vector3d(0.04, -0.02, 0.55), s.cam.fx, 0.02));
  }
}

void BM_SolvePnP(benchmark::State& state) {
  const Scene s = MakeScene(640, 480);
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  for (size_t i = 0; i < s.obj.size(); ++i) {
    obj.emplace_back(s.obj[i].x(), s.obj[i].y(), 0.0);
    img.emplace_back(s.norm[i].x(), s.norm[i].y());
  }
  const int method = static_cast<int>(state.range(0));
  const cv::Mat K = cv::Mat::eye(3, 3, CV_64F);
  for (auto _ : state) {
    cv::Mat rvec, tvec;
    cv::solvePnP(obj, img, K, cv::Mat(), rvec, tvec, false, method);
    benchmark::DoNotOptimize(tvec);
  }
}

#define RESOLUTIONS ->Args({640, 480})->Args({1280, 720})->Args({1920, 1080})
BENCHMARK(BM_KincalFullFrame) RESOLUTIONS;
BENCHMARK(BM_KincalTracked) RESOLUTIONS;
BENCHMARK(BM_OpenCvThresholdComponents) RESOLUTIONS;
BENCHMARK(BM_OpenCvBlobDetectorSolvePnP)->Args({640, 480})->Args({1280, 720});
BENCHMARK(BM_Lowe);
BENCHMARK(BM_GroundPlane);
BENCHMARK(BM_SolvePnP)->Arg(cv::SOLVEPNP_ITERATIVE)->Arg(cv::SOLVEPNP_IPPE);

}  // namespace
}  // namespace kincal::vision
