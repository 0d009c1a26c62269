// Camera calibration: intrinsics within 3 sigma of the truth and equal to OpenCV's,
// degenerate and bad input named, a 3-D rig through the DLT.
#include "kincal/vision/calibration.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "kincal/vision/camera.h"
#include "kincal/vision/markers.h"
#include "kincal/vision/opencv_baseline.h"
#include "kincal/vision/pose.h"
#include "kincal/vision/synthetic.h"
#include "kincal/vision/target.h"
#include "vision/vision_test_util.h"
#include "windows_text.h"

namespace kincal::vision {
namespace {

using namespace test_util;

TEST(Calibration, RecoversIntrinsicsWithin3SigmaAndMatchesOpenCv) {
  const CameraModel truth = TestCamera();
  std::mt19937_64 rng(21);
  const auto views = SyntheticBoardViews(truth, 15, 0.1, rng);
  CalibrationOptions opt;
  opt.width = truth.width;
  opt.height = truth.height;
  const CalibrationResult r = CalibrateCamera(views, opt).value();
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
    const StatusOr<CalibrationResult> r = CalibrateCamera(v, o);
    return r.ok() ? std::string("no error") : r.status().message();
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

// Issue 34: a points file saved by a Windows tool (CRLF, a UTF-8 byte-order mark) read the
// previous release and failed with "got '237.257'" (the carriage return invisible).
TEST(Calibration, PointsFileWithCrlfAndByteOrderMark) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string plain = (dir / "kincal_points_lf.csv").string();
  const std::string windows = (dir / "kincal_points_crlf.csv").string();
  const std::string rows =
      "view,X,Y,Z,u,v\n0,0,0,0,100.5,237.257\n0,0.1,0,0,180,237.5\n"
      "1,0,0,0,101,238\n";
  std::ofstream(plain, std::ios::binary) << rows;
  const auto a = ReadCalibrationPoints(plain).value();
  ASSERT_EQ(a.size(), 2u);
  for (const auto& [system, text] : ::kincal::testing::OtherSystemsText(rows)) {
    std::ofstream(windows, std::ios::binary) << text;
    const auto read = ReadCalibrationPoints(windows);
    ASSERT_TRUE(read.ok()) << system << ": " << read.status().message();
    const std::vector<CalibrationView>& b = read.value();
    ASSERT_EQ(b.size(), a.size()) << system;
    for (size_t k = 0; k < a.size(); ++k) {
      EXPECT_EQ(b[k].name, a[k].name);
      ASSERT_EQ(b[k].image.size(), a[k].image.size()) << system;
      for (size_t i = 0; i < a[k].image.size(); ++i) {
        EXPECT_EQ(b[k].image[i], a[k].image[i]) << system;
        EXPECT_EQ(b[k].object[i], a[k].object[i]) << system;
      }
    }
  }
  EXPECT_EQ(a[0].image[0].y(), 237.257);
  // An invisible character left inside a value (a spreadsheet's no-break space) is shown,
  // escaped.
  std::ofstream(windows, std::ios::binary) << "view,X,Y,Z,u,v\n0,0,0,0,100\xC2\xA0,237\n";
  const auto refused = ReadCalibrationPoints(windows);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find(":2: column 5: expected a number, got '100\\xC2\\xA0'"),
            std::string::npos)
      << refused.status().message();
  // Issue 34's sweep: `kincal camcal --points /dev/zero` read one endless line (11.8 GB in
  // 30 s); a folder said "empty file (no header)".
  EXPECT_EQ(ReadCalibrationPoints("/dev/zero").status().message(),
            "/dev/zero:1: line longer than 65536 bytes: not a text file of this kind");
  EXPECT_EQ(ReadCalibrationPoints(dir.string()).status().message(),
            dir.string() + ": cannot open points file: Is a directory");
}

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
  const StatusOr<CalibrationResult> r = CalibrateCamera(views, opt);
  if (r.ok()) {
    // If the solver happens to return, its uncertainty must say it knows nothing.
    EXPECT_TRUE(!r->sigma_ok || r->sigma[0] > 1.0) << "fx sigma " << r->sigma[0];
  } else {
    EXPECT_NE(r.status().message().find("degenerate views"), std::string::npos)
        << r.status().message();
  }
}

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
  const CalibrationResult r = CalibrateCamera(views, opt).value();
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
