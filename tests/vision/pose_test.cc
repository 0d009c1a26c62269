// Pose from markers: the Lowe Jacobian against finite differences, Lowe against
// cv::solvePnP, and the ground-plane pose through rendered images within its covariance.
#include "kincal/vision/pose.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "kincal/angles.h"
#include "kincal/sim/thesis_vision.h"
#include "kincal/vision/calibration.h"
#include "kincal/vision/camera.h"
#include "kincal/vision/markers.h"
#include "kincal/vision/opencv_baseline.h"
#include "kincal/vision/synthetic.h"
#include "kincal/vision/target.h"
#include "vision/vision_test_util.h"

namespace kincal::vision {
namespace {

using namespace test_util;

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
  double nees_sum = 0.0;
  constexpr int kTrials = 100;
  for (int trial = 0; trial < kTrials; ++trial) {
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
    // Position error against the truth by its own covariance: each trial's NEES below
    // chi2(3)'s 99.99 % point (21.1; 1 % over the 100 trials), and their mean below.
    const Eigen::Vector3d dt = r.pose.t - truth.t;
    const Eigen::Matrix3d Ct = r.covariance.topLeftCorner<3, 3>();
    const double e = dt.dot(Ct.ldlt().solve(dt));
    EXPECT_LT(e, 21.1) << trial;
    nees_sum += e;
    // solvePnP (ITERATIVE) minimises the same reprojection error: same answer.
    cv::Mat rvec, tvec;
    cv::solvePnP(cobj, cimg, cv::Mat::eye(3, 3, CV_64F), cv::Mat(), rvec, tvec, false,
                 cv::SOLVEPNP_ITERATIVE);
    EXPECT_LT(
        (r.pose.t - Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)))
            .norm(),
        1e-6);
  }
  // 100 x the mean NEES is chi2(300) when the covariance is right: its 99.9 % interval,
  // [226, 387] (Wilson-Hilferty), divided by 100. A covariance 35 % off either way
  // (mean 2.2 or 4.6) leaves it.
  const double mean = nees_sum / kTrials;
  std::cout << "Lowe position NEES, mean of " << kTrials << ": " << mean << "\n";
  EXPECT_GT(mean, 2.26);
  EXPECT_LT(mean, 3.87);
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

namespace {}  // namespace

}  // namespace
}  // namespace kincal::vision

namespace kincal::vision {
namespace {

// Reproduces the mirrored-tilt ambiguity first: through the thesis's camera at 0.14 px,
// Lowe started from the homography lands on the mirrored solution (target tilted by tens
// of degrees, heading off by up to 0.5 rad) in a good share of frames; started also from
// the levelled pose (LevelLowePose) it does not.
TEST(LevelLowePose, AvoidsTheMirroredTiltOfAPlanarTarget) {
  const ThesisVision v = ThesisTable63Vision();
  std::mt19937_64 rng(9);
  MarkerTracker tracker(v.camera, v.layout, DetectorOptions{});
  RenderOptions ro;
  ro.supersample = 4;
  ro.blur_sigma_px = 0.8;
  ro.noise_sigma = 28.0;  // centres scatter about 0.14 px (PixelPoseMeter)
  std::uniform_real_distribution<double> pos(-0.4, 0.4), ang(-std::numbers::pi, std::numbers::pi);
  int n = 0, plain_off = 0, level_off = 0;
  while (n < 300) {
    const Eigen::Vector3d truth(pos(rng), pos(rng), ang(rng));
    if (!PlateInView(v, truth, 6.0)) continue;
    const auto frame = RenderTarget(v.camera, CameraPoseOnFloor(v.floor, truth, v.target_height_m),
                                    v.layout, ro, rng);
    const auto markers = tracker.Track(frame.image);
    if (markers.size() != 4) continue;
    std::vector<Eigen::Vector3d> obj;
    std::vector<Eigen::Vector2d> norm;
    for (const auto& m : markers) {
      const auto& q = v.layout.markers[static_cast<size_t>(m.id)];
      obj.emplace_back(q.x(), q.y(), 0.0);
      norm.push_back(v.camera.PixelToNormalized(m.centre_px));
    }
    Pose3 init;
    if (!PlanarInitialPose(obj, norm, &init)) continue;
    const LoweResult plain = LowePose(obj, norm, init, v.camera.fx, 0.1414);
    const LoweResult level = LevelLowePose(v.floor, obj, norm, init, v.camera.fx, 0.1414);
    ASSERT_TRUE(level.ok);
    auto heading_error = [&](const LoweResult& r) {
      return std::abs(WrapAngle(FloorPoseOf(v.floor, r.pose).z() - truth.z()));
    };
    plain_off += heading_error(plain) > 0.05 ? 1 : 0;
    level_off += heading_error(level) > 0.05 ? 1 : 0;
    ++n;
  }
  std::cout << "headings off by > 50 mrad: from the homography " << plain_off << " of " << n
            << ", levelled " << level_off << "\n";
  EXPECT_GT(plain_off, n / 20);
  EXPECT_LE(level_off, 1);
}

}  // namespace
}  // namespace kincal::vision

namespace kincal::vision {
namespace {

// Reproduces the depth's bias first: Lowe's depth of a small target is nonlinear in its
// centres, so with noisy centres its mean lies off the truth, and a floor position taken
// at the solved depth moves along the line of sight: a scale of every position about the
// camera's nadir (seen as a common scale error of all lengths in the thesis scenario).
// Cut with the target's known plane instead (FloorPoseFromLoweAtHeight) the mean stays
// on the truth and the propagated covariance describes the scatter.
TEST(FloorPoseFromLoweAtHeight, RemovesTheDepthsScaleBias) {
  const ThesisVision v = ThesisTable63Vision();
  const Eigen::Vector3d truth(0.25, -0.15, 0.7);
  const Pose3 p = CameraPoseOnFloor(v.floor, truth, v.target_height_m);
  const Eigen::Matrix3d Rfc = v.floor.R_cf.transpose();
  const Eigen::Vector3d nadir = -Rfc * v.floor.t_cf;
  const Eigen::Vector2d out = (truth.head<2>() - nadir.head<2>()).normalized();
  constexpr double kSigmaPx = 0.3;
  std::mt19937_64 rng(21);
  std::normal_distribution<double> noise(0.0, kSigmaPx);
  std::vector<Eigen::Vector3d> obj;
  for (const auto& q : v.layout.markers) obj.emplace_back(q.x(), q.y(), 0.0);
  double sum_depth = 0.0, sum_sq_depth = 0.0, sum_height = 0.0, sum_sq_height = 0.0;
  double nees = 0.0;
  int n = 0;
  for (int k = 0; k < 20000; ++k) {
    std::vector<Eigen::Vector2d> norm;
    for (const auto& o : obj) {
      const Eigen::Vector2d px = v.camera.Project(p.R * o + p.t);
      norm.push_back(v.camera.PixelToNormalized(px + Eigen::Vector2d(noise(rng), noise(rng))));
    }
    Pose3 init;
    if (!PlanarInitialPose(obj, norm, &init)) continue;
    const LoweResult lowe = LevelLowePose(v.floor, obj, norm, init, v.camera.fx, kSigmaPx);
    const PlanarPose depth = FloorPoseFromLowe(v.floor, lowe);
    const PlanarPose height = FloorPoseFromLoweAtHeight(v.floor, lowe, v.target_height_m);
    ASSERT_TRUE(depth.ok && height.ok);
    const double a = out.dot(depth.xytheta.head<2>() - truth.head<2>());
    const double b = out.dot(height.xytheta.head<2>() - truth.head<2>());
    sum_depth += a;
    sum_sq_depth += a * a;
    sum_height += b;
    sum_sq_height += b * b;
    Eigen::Vector3d e = height.xytheta - truth;
    e.z() = WrapAngle(e.z());
    nees += e.dot(height.covariance.ldlt().solve(e));
    ++n;
  }
  ASSERT_GT(n, 19000);
  const double mean_depth = sum_depth / n, se_depth = std::sqrt(sum_sq_depth / n) / std::sqrt(n);
  const double mean_height = sum_height / n,
               se_height = std::sqrt(sum_sq_height / n) / std::sqrt(n);
  std::cout << "radial bias: at the solved depth " << mean_depth * 1e3 << " mm (se "
            << se_depth * 1e3 << "), at the known height " << mean_height * 1e3 << " mm (se "
            << se_height * 1e3 << "); NEES " << nees / n << "\n";
  EXPECT_GT(std::abs(mean_depth), 5.0 * se_depth);
  EXPECT_LT(std::abs(mean_height), 3.0 * se_height);
  EXPECT_LT(std::sqrt(sum_sq_height / n), 0.5 * std::sqrt(sum_sq_depth / n));
  EXPECT_NEAR(nees / n, 3.0, 0.3);
}

}  // namespace
}  // namespace kincal::vision
