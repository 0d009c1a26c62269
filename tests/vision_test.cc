// Vision: camera model, synthetic camera, sub-pixel marker centres, target
// identification, Lowe pose (against finite differences and cv::solvePnP), ground-plane
// pose, end to end through rendered images.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "kincal/vision/camera.h"
#include "kincal/vision/markers.h"
#include "kincal/vision/opencv_baseline.h"
#include "kincal/vision/pose.h"
#include "kincal/vision/target.h"

namespace kincal::vision {
namespace {

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

CameraModel TestCamera() {
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
FloorExtrinsics Overhead() {
  FloorExtrinsics f;
  f.R_cf = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix() *
           Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()).toRotationMatrix();
  f.t_cf = Eigen::Vector3d(0.02, -0.03, 1.2);
  return f;
}

Pose3 TargetPose(const FloorExtrinsics& f, const Eigen::Vector3d& q, double height) {
  Pose3 p;
  const Eigen::Matrix3d Rz = Eigen::AngleAxisd(q.z(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  p.R = f.R_cf * Rz;
  p.t = f.R_cf * Eigen::Vector3d(q.x(), q.y(), height) + f.t_cf;
  return p;
}

TEST(Camera, UndistortInvertsDistort) {
  const CameraModel c = TestCamera();
  for (double u = 0; u <= 640; u += 40) {
    for (double v = 0; v <= 480; v += 40) {
      const Eigen::Vector2d px(u, v);
      EXPECT_LT((c.NormalizedToPixel(c.PixelToNormalized(px)) - px).norm(), 1e-9) << u << "," << v;
    }
  }
}

TEST(Camera, OpenCvYamlRoundTripAndErrors) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string path = (dir / "kincal_cam_test.yaml").string();
  WriteCameraYaml(TestCamera(), path);
  const CameraModel c = ReadCameraYaml(path);
  EXPECT_EQ(c.width, 640);
  EXPECT_DOUBLE_EQ(c.fx, 820);
  EXPECT_DOUBLE_EQ(c.p2, -0.0004);
  // The same numbers as OpenCV's own projection.
  std::vector<cv::Point3d> obj = {{0.1, -0.05, 1.0}};
  std::vector<cv::Point2d> img;
  const cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  const cv::Mat D = (cv::Mat_<double>(5, 1) << c.k1, c.k2, c.p1, c.p2, c.k3);
  cv::projectPoints(obj, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D, img);
  const Eigen::Vector2d ours = c.Project(Eigen::Vector3d(0.1, -0.05, 1.0));
  EXPECT_NEAR(ours.x(), img[0].x, 1e-9);
  EXPECT_NEAR(ours.y(), img[0].y, 1e-9);
  const std::string bad = (dir / "kincal_cam_bad.yaml").string();
  std::ofstream(bad) << "%YAML:1.0\n---\nimage_width: 640\n";
  try {
    ReadCameraYaml(bad);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("kincal_cam_bad.yaml: missing key 'camera_matrix'"),
              std::string::npos)
        << e.what();
  }
}

TEST(Lowe, JacobianMatchesFiniteDifferences) {
  const Pose3 pose = TargetPose(Overhead(), Eigen::Vector3d(0.1, 0.2, 0.7), 0.1);
  const Eigen::Vector3d p(0.045, -0.025, 0.0);
  const auto J = LoweJacobian(p, pose);
  auto proj = [&](const Pose3& q) {
    const Eigen::Vector3d c = q.R * p + q.t;
    return Eigen::Vector2d(c.x() / c.z(), c.y() / c.z());
  };
  for (int k = 0; k < 6; ++k) {
    const double h = 1e-7;
    Pose3 a = pose, b = pose;
    if (k < 3) {
      a.t[k] += h;
      b.t[k] -= h;
    } else {
      Eigen::Vector3d w = Eigen::Vector3d::Zero();
      w[k - 3] = h;
      a.R = Eigen::AngleAxisd(h, w.normalized()).toRotationMatrix() * pose.R;
      b.R = Eigen::AngleAxisd(-h, w.normalized()).toRotationMatrix() * pose.R;
    }
    const Eigen::Vector2d fd = (proj(a) - proj(b)) / (2 * h);
    EXPECT_LT((fd - J.col(k)).norm(), 1e-6 * std::max(1.0, fd.norm())) << "column " << k;
  }
}

TEST(Lowe, RecoversPoseAndAgreesWithSolvePnP) {
  const CameraModel cam = TestCamera();
  const TargetLayout layout = TargetLayout::Thesis();
  std::mt19937_64 rng(1);
  std::normal_distribution<double> g(0.0, 0.05);  // px
  std::vector<Eigen::Vector3d> obj;
  for (const auto& m : layout.markers) obj.emplace_back(m.x(), m.y(), 0.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Pose3 truth =
        TargetPose(Overhead(), Eigen::Vector3d(0.2 * g(rng) / 0.05, 0.1, trial * 0.3), 0.1);
    std::vector<Eigen::Vector2d> norm;
    std::vector<cv::Point3d> cobj;
    std::vector<cv::Point2d> cimg;
    for (const auto& p : obj) {
      const Eigen::Vector2d px = cam.Project(truth.R * p + truth.t) + Draw2(g, rng);
      norm.push_back(cam.PixelToNormalized(px));
      cobj.emplace_back(p.x(), p.y(), p.z());
      cimg.emplace_back(norm.back().x(), norm.back().y());
    }
    Pose3 init;
    ASSERT_TRUE(PlanarInitialPose(obj, norm, &init));
    const LoweResult r = LowePose(obj, norm, init, cam.fx, 0.05);
    ASSERT_TRUE(r.ok);
    // Pose error against the truth within 4 sigma of its own covariance (position).
    const Eigen::Vector3d dt = r.pose.t - truth.t;
    const Eigen::Matrix3d Ct = r.covariance.topLeftCorner<3, 3>();
    EXPECT_LT(dt.dot(Ct.ldlt().solve(dt)), 25.0) << trial;
    // solvePnP (ITERATIVE) minimises the same reprojection error: same answer.
    cv::Mat rvec, tvec;
    cv::solvePnP(cobj, cimg, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, false,
                 cv::SOLVEPNP_ITERATIVE);
    EXPECT_LT(
        (r.pose.t - Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)))
            .norm(),
        1e-6);
  }
}

TEST(Markers, SubPixelCentresOnSyntheticImages) {
  // Markers about 14 px across at 1 grey level of noise: centre error RMS <= 0.02 px.
  const CameraModel cam = TestCamera();
  const TargetLayout layout = TargetLayout::Thesis();
  const FloorExtrinsics floor = Overhead();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(-0.2, 0.2);
  RenderOptions ro;
  DetectorOptions dopt;
  double sq = 0;
  int n = 0;
  for (int f = 0; f < 30; ++f) {
    const Pose3 pose = TargetPose(floor, Draw3(U, rng, 10), 0.1);
    const RenderedFrame fr = RenderTarget(cam, pose, layout, ro, rng);
    auto markers = DetectMarkers(fr.image, dopt);
    ASSERT_EQ(markers.size(), 4u) << "frame " << f;
    ASSERT_TRUE(IdentifyTarget(cam, layout, &markers)) << "frame " << f;
    for (const auto& m : markers) {
      EXPECT_GT(m.diameter_px, 10.0);
      sq += (m.centre_px - fr.centres[static_cast<size_t>(m.id)]).squaredNorm() / 2.0;
      ++n;
    }
  }
  const double rms = std::sqrt(sq / n);
  RecordProperty("centre_rms_px", std::to_string(rms));
  EXPECT_LE(rms, 0.02) << "centre RMS per axis " << rms << " px";
}

TEST(Markers, IdentifiesTheTargetAmongDistractorsAndRejectsNonCircles) {
  const CameraModel cam = TestCamera();
  const TargetLayout layout = TargetLayout::Thesis();
  std::mt19937_64 rng(3);
  const Pose3 pose = TargetPose(Overhead(), Eigen::Vector3d(0.05, -0.1, 2.0), 0.1);
  RenderedFrame fr = RenderTarget(cam, pose, layout, RenderOptions{}, rng);
  cv::rectangle(fr.image, cv::Rect(30, 30, 40, 8), cv::Scalar(40), cv::FILLED);  // a stripe
  std::vector<Rejected> rejected;
  auto markers = DetectMarkers(fr.image, DetectorOptions{}, {}, &rejected);
  ASSERT_EQ(markers.size(), 4u);
  ASSERT_FALSE(rejected.empty());
  EXPECT_NE(rejected[0].reason.find("circularity"), std::string::npos) << rejected[0].reason;
  std::shuffle(markers.begin(), markers.end(), rng);
  ASSERT_TRUE(IdentifyTarget(cam, layout, &markers));
  for (const auto& m : markers) {
    EXPECT_LT((m.centre_px - fr.centres[static_cast<size_t>(m.id)]).norm(), 0.1);
  }
}

TEST(GroundPlane, PoseFromRenderedImagesWithinItsCovariance) {
  const CameraModel cam = TestCamera();
  const TargetLayout layout = TargetLayout::Thesis();
  const FloorExtrinsics floor = Overhead();
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(-0.25, 0.25);
  std::vector<Eigen::Vector3d> obj;
  for (const auto& m : layout.markers) obj.emplace_back(m.x(), m.y(), 0.0);
  int inside = 0;
  const int frames = 20;
  for (int f = 0; f < frames; ++f) {
    const Eigen::Vector3d q = Draw3(U, rng, 12);
    const RenderedFrame fr =
        RenderTarget(cam, TargetPose(floor, q, 0.1), layout, RenderOptions{}, rng);
    std::vector<Rejected> rejected;
    auto markers = DetectMarkers(fr.image, DetectorOptions{}, {}, &rejected);
    ASSERT_TRUE(IdentifyTarget(cam, layout, &markers))
        << "frame " << f << ": " << markers.size() << " markers, " << rejected.size() << " rejected"
        << (rejected.empty() ? "" : ": " + rejected[0].reason);
    std::vector<Eigen::Vector2d> norm(4);
    for (const auto& m : markers)
      norm[static_cast<size_t>(m.id)] = cam.PixelToNormalized(m.centre_px);
    const PlanarPose p =
        GroundPlanePose(floor, 0.1, obj, norm, Eigen::Vector3d(0, 0, q.z() + 0.3), cam.fx, 0.02);
    ASSERT_TRUE(p.ok);
    Eigen::Vector3d e = p.xytheta - q;
    e.z() = std::remainder(e.z(), 2 * M_PI);
    EXPECT_LT(e.head<2>().norm(), 1e-3) << f;
    if (e.dot(p.covariance.ldlt().solve(e)) < 14.2) ++inside;  // chi2(3) 99.7 %
  }
  EXPECT_GE(inside, frames * 8 / 10);
}

}  // namespace
}  // namespace kincal::vision

#include "kincal/vision/calibration.h"
#include "kincal/vision/synthetic.h"

namespace kincal::vision {
namespace {

TEST(Calibration, RecoversIntrinsicsWithin3SigmaAndMatchesOpenCv) {
  const CameraModel truth = TestCamera();
  std::mt19937_64 rng(21);
  const auto views = SyntheticBoardViews(truth, 15, 0.1, rng);
  CalibrationOptions opt;
  opt.width = truth.width;
  opt.height = truth.height;
  const CalibrationResult r = CalibrateCamera(views, opt);
  ASSERT_TRUE(r.sigma_ok);
  const double t[8] = {truth.fx, truth.fy, truth.cx, truth.cy,
                       truth.k1, truth.k2, truth.p1, truth.p2};
  const double e[8] = {r.camera.fx, r.camera.fy, r.camera.cx, r.camera.cy,
                       r.camera.k1, r.camera.k2, r.camera.p1, r.camera.p2};
  for (int i = 0; i < 8; ++i)
    EXPECT_LE(std::abs(e[i] - t[i]), 3.0 * r.sigma[i]) << "parameter " << i;
  EXPECT_NEAR(r.rms_px, 0.1 * std::sqrt(2.0), 0.015);  // OpenCV rms: both axes per point
  // cv::calibrateCamera on the same points (k3 fixed, as ours): the same optimum.
  const OpenCvCalibration cv_r = CalibrateWithOpenCv(views, opt, CameraModel{});
  EXPECT_NEAR(cv_r.rms_px, r.rms_px, 1e-3);
  EXPECT_NEAR(cv_r.camera.fx, r.camera.fx, 3.0 * r.sigma[0]);
  EXPECT_NEAR(cv_r.camera.cx, r.camera.cx, 3.0 * r.sigma[2]);
}

TEST(Calibration, BadInputNamesTheProblem) {
  const CameraModel truth = TestCamera();
  std::mt19937_64 rng(2);
  auto views = SyntheticBoardViews(truth, 4, 0.1, rng);
  CalibrationOptions opt;
  opt.width = truth.width;
  opt.height = truth.height;
  auto message = [&](std::vector<CalibrationView> v, CalibrationOptions o) {
    try {
      CalibrateCamera(v, o);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({views[0], views[1]}, opt).find("at least 3 views"), std::string::npos);
  auto small = opt;
  small.width = 320;
  EXPECT_NE(message(views, small).find("lies outside the 320x480 image"), std::string::npos);
  auto few = views;
  few[1].object.resize(3);
  few[1].image.resize(3);
  EXPECT_NE(message(few, opt).find("view 1: at least 6 point pairs"), std::string::npos);
}

}  // namespace
}  // namespace kincal::vision

namespace kincal::vision {
namespace {

TEST(Markers, PerspectiveBiasCorrectionOnAnObliqueView) {
  // A camera looking at the floor 45 degrees off the vertical: the image of a marker's
  // centre is off the centre of its image by a measurable amount; the correction removes it.
  CameraModel cam = TestCamera();
  FloorExtrinsics floor;
  floor.R_cf = Eigen::AngleAxisd(M_PI - 0.8, Eigen::Vector3d::UnitX()).toRotationMatrix();
  floor.t_cf = Eigen::Vector3d(0.0, 0.0, 0.55);
  const TargetLayout layout = TargetLayout::Thesis();
  std::mt19937_64 rng(5);
  RenderOptions ro;
  ro.noise_sigma = 0.0;
  const Pose3 pose = TargetPose(floor, Eigen::Vector3d(0.0, 0.0, 0.4), 0.0);
  const RenderedFrame fr = RenderTarget(cam, pose, layout, ro, rng);
  auto markers = DetectMarkers(fr.image, DetectorOptions{});
  ASSERT_TRUE(IdentifyTarget(cam, layout, &markers));
  double before = 0, after = 0;
  for (const auto& m : markers)
    before = std::max(before, (m.centre_px - fr.centres[static_cast<size_t>(m.id)]).norm());
  const double largest = CorrectPerspectiveBias(cam, pose, layout, &markers);
  for (const auto& m : markers)
    after = std::max(after, (m.centre_px - fr.centres[static_cast<size_t>(m.id)]).norm());
  EXPECT_GT(largest, 0.02);
  EXPECT_GT(before, 0.02);
  EXPECT_LT(after, 0.4 * before) << "before " << before << " after " << after;
}

TEST(Markers, TrackerSearchesNearTheLastTargetAndFallsBack) {
  const CameraModel cam = TestCamera();
  const TargetLayout layout = TargetLayout::Thesis();
  std::mt19937_64 rng(9);
  MarkerTracker tracker(cam, layout, DetectorOptions{});
  const FloorExtrinsics floor = Overhead();
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector3d q =
        k < 9 ? Eigen::Vector3d(0.01 * k, 0.0, 0.05 * k) : Eigen::Vector3d(-0.2, 0.2, 1.0);
    const RenderedFrame fr =
        RenderTarget(cam, TargetPose(floor, q, 0.1), layout, RenderOptions{}, rng);
    const auto markers = tracker.Track(fr.image);
    ASSERT_EQ(markers.size(), 4u) << k;
    for (const auto& m : markers)
      EXPECT_LT((m.centre_px - fr.centres[static_cast<size_t>(m.id)]).norm(), 0.1);
    if (k > 0 && k < 9) {
      EXPECT_FALSE(tracker.last_was_full_frame()) << k;
    }
  }
  EXPECT_EQ(tracker.full_frame_searches(), 2);  // the first frame and the jump
}

}  // namespace
}  // namespace kincal::vision

namespace kincal::vision {
namespace {

TEST(Markers, TwoRobotsToldApartByTheirLayouts) {
  const CameraModel cam = TestCamera();
  TargetLayout a = TargetLayout::Thesis();
  TargetLayout b;
  b.name = "second";
  b.markers = {{0.04, 0.03}, {0.04, -0.03}, {-0.04, 0.0}, {0.0, -0.03}};  // a different shape
  std::mt19937_64 rng(4);
  const FloorExtrinsics floor = Overhead();
  RenderOptions ro;
  const RenderedFrame fa =
      RenderTarget(cam, TargetPose(floor, Eigen::Vector3d(-0.12, 0.05, 0.4), 0.1), a, ro, rng);
  const RenderedFrame fb =
      RenderTarget(cam, TargetPose(floor, Eigen::Vector3d(0.13, -0.06, 2.2), 0.1), b, ro, rng);
  cv::Mat both;
  cv::min(fa.image, fb.image, both);  // dark markers of both robots in one frame
  const auto detections = DetectMarkers(both, DetectorOptions{});
  ASSERT_EQ(detections.size(), 8u);
  const auto targets = IdentifyTargets(cam, {a, b}, detections);
  ASSERT_EQ(targets[0].size(), 4u);
  ASSERT_EQ(targets[1].size(), 4u);
  for (const auto& m : targets[0])
    EXPECT_LT((m.centre_px - fa.centres[static_cast<size_t>(m.id)]).norm(), 0.1);
  for (const auto& m : targets[1])
    EXPECT_LT((m.centre_px - fb.centres[static_cast<size_t>(m.id)]).norm(), 0.1);
}

}  // namespace
}  // namespace kincal::vision

#include <opencv2/features2d.hpp>

namespace kincal::vision {
namespace {

TEST(Markers, LightOnDarkAndMoreAccurateThanSimpleBlobDetector) {
  const CameraModel cam = TestCamera();
  TargetLayout layout = TargetLayout::Thesis();
  layout.dark_on_light = false;
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> U(-0.2, 0.2);
  DetectorOptions dopt;
  dopt.dark_on_light = false;
  cv::SimpleBlobDetector::Params bp;
  bp.blobColor = 255;
  bp.minArea = 10;
  auto blob = cv::SimpleBlobDetector::create(bp);
  double ours = 0, theirs = 0;
  int n = 0, m_theirs = 0;
  for (int f = 0; f < 10; ++f) {
    const RenderedFrame fr = RenderTarget(cam, TargetPose(Overhead(), Draw3(U, rng, 10), 0.1),
                                          layout, RenderOptions{}, rng);
    auto markers = DetectMarkers(fr.image, dopt);
    ASSERT_EQ(markers.size(), 4u);
    ASSERT_TRUE(IdentifyTarget(cam, layout, &markers));
    for (const auto& mk : markers) {
      ours += (mk.centre_px - fr.centres[static_cast<size_t>(mk.id)]).squaredNorm();
      ++n;
    }
    std::vector<cv::KeyPoint> kp;
    blob->detect(fr.image, kp);
    for (const auto& c : fr.centres) {
      double best = 1e9;
      for (const auto& k : kp)
        best = std::min(best, (Eigen::Vector2d(k.pt.x, k.pt.y) - c).squaredNorm());
      if (best < 4.0) {
        theirs += best;
        ++m_theirs;
      }
    }
  }
  ASSERT_GT(m_theirs, 0);
  const double rms_ours = std::sqrt(ours / n), rms_theirs = std::sqrt(theirs / m_theirs);
  RecordProperty("rms_ours_px", std::to_string(rms_ours));
  RecordProperty("rms_simpleblob_px", std::to_string(rms_theirs));
  EXPECT_LT(rms_ours, 0.03);
  EXPECT_LT(rms_ours, rms_theirs) << "ours " << rms_ours << " SimpleBlobDetector " << rms_theirs;
}

}  // namespace
}  // namespace kincal::vision

namespace kincal::vision {
namespace {

TEST(Calibration, ParallelBoardsAreDegenerate) {
  // Three fronto-parallel views (the board only translated): Zhang's system has no unique
  // solution; the error says how to fix the views.
  const CameraModel cam = TestCamera();
  std::vector<CalibrationView> views;
  for (int v = 0; v < 3; ++v) {
    CalibrationView view;
    view.name = "view " + std::to_string(v);
    const Eigen::Vector3d t(-0.1 + 0.02 * v, -0.06, 0.8 + 0.05 * v);
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 9; ++c) {
        view.object.emplace_back(0.025 * c, 0.025 * r, 0.0);
        view.image.push_back(cam.Project(view.object.back() + t));
      }
    }
    views.push_back(view);
  }
  CalibrationOptions opt;
  opt.width = cam.width;
  opt.height = cam.height;
  try {
    const auto r = CalibrateCamera(views, opt);
    // If the solver happens to return, its uncertainty must say it knows nothing.
    EXPECT_TRUE(!r.sigma_ok || r.sigma[0] > 1.0) << "fx sigma " << r.sigma[0];
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("degenerate views"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace kincal::vision

namespace kincal::vision {
namespace {

TEST(Calibration, ThreeDimensionalRigThroughDlt) {
  // A rig of two perpendicular 6x5 grids (non-planar): DLT initialisation per view.
  const CameraModel truth = TestCamera();
  std::mt19937_64 rng(8);
  std::normal_distribution<double> g(0.0, 0.1);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::vector<CalibrationView> views;
  while (views.size() < 6) {
    CalibrationView v;
    v.name = "rig view " + std::to_string(views.size());
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(M_PI + 0.35 * U(rng), Eigen::Vector3d::UnitX()) *
                               Eigen::AngleAxisd(0.35 * U(rng), Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(M_PI / 4 + 0.3 * U(rng), Eigen::Vector3d::UnitZ()))
                                  .toRotationMatrix();
    const Eigen::Vector3d t =
        Eigen::Vector3d(0, 0, 0.75) + Draw3(U, rng).cwiseProduct(Eigen::Vector3d(0.02, 0.02, 0.1));
    bool inside = true;
    for (int a = 0; a < 6; ++a) {
      for (int b = 0; b < 5; ++b) {
        for (const Eigen::Vector3d& X : {Eigen::Vector3d(0.03 * a, 0.0, 0.03 * b),
                                         Eigen::Vector3d(0.0, 0.03 * a + 0.03, 0.03 * b)}) {
          const Eigen::Vector3d Xc = R * X + t;
          const Eigen::Vector2d px = truth.Project(Xc) + Draw2(g, rng);
          inside = inside && Xc.z() > 0 && px.x() > 0 && px.y() > 0 && px.x() < truth.width - 1 &&
                   px.y() < truth.height - 1;
          v.object.push_back(X);
          v.image.push_back(px);
        }
      }
    }
    if (inside) views.push_back(v);
  }
  CalibrationOptions opt;
  opt.width = truth.width;
  opt.height = truth.height;
  const CalibrationResult r = CalibrateCamera(views, opt);
  ASSERT_TRUE(r.sigma_ok);
  EXPECT_LE(std::abs(r.camera.fx - truth.fx), 3.0 * r.sigma[0]);
  EXPECT_LE(std::abs(r.camera.cx - truth.cx), 3.0 * r.sigma[2]);
  EXPECT_LE(std::abs(r.camera.k1 - truth.k1), 3.0 * r.sigma[4]);
  EXPECT_NEAR(r.rms_px, 0.1 * std::sqrt(2.0), 0.02);
  // OpenCV needs our result as its initial guess for a rig; it must agree with it.
  EXPECT_NEAR(CalibrateWithOpenCv(views, opt, r.camera).rms_px, r.rms_px, 1e-3);
}

}  // namespace
}  // namespace kincal::vision
