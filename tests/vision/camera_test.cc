// The camera model: distortion inverted, OpenCV YAML read and written.
#include "kincal/vision/camera.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <regex>

#include "kincal/vision/calibration.h"
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
  ASSERT_TRUE(WriteCameraYaml(TestCamera(), path).ok());
  const CameraModel c = ReadCameraYaml(path).value();
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
  const StatusOr<CameraModel> refused = ReadCameraYaml(bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("kincal_cam_bad.yaml: missing key 'camera_matrix'"),
            std::string::npos)
      << refused.status().message();
}

// The default camera of kincald and `kincal render`: the principal point at the centre of
// the pixel grid (pixel centres at integers: 319.5 of 0..639).
TEST(Camera, CentredHasItsPrincipalPointAtTheImageCentre) {
  const CameraModel c = CameraModel::Centred(640, 480, 500.0);
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_EQ(c.fx, 500.0);
  EXPECT_EQ(c.fy, 500.0);
  EXPECT_EQ(c.cx, 319.5);
  EXPECT_EQ(c.cy, 239.5);
  EXPECT_EQ(c.k1, 0.0);
  const Eigen::Vector2d centre = c.Project(Eigen::Vector3d(0.0, 0.0, 2.0));
  EXPECT_EQ(centre, Eigen::Vector2d(319.5, 239.5));
  std::string error;
  EXPECT_TRUE(c.IsValid(&error)) << error;
}

// A camera whose numbers cannot be projected with, or whose frame could not be allocated: an
// infinite distortion once rendered centres at (-inf, -inf), and a width of 99999999 px
// asked OpenCV for 192 GB.
TEST(Camera, NonFiniteNumbersAndHugeImagesAreRefused) {
  std::string error;
  CameraModel c = TestCamera();
  EXPECT_TRUE(c.IsValid(&error)) << error;
  c.k1 = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_EQ(error, "camera intrinsics and distortion must be finite numbers");
  c = TestCamera();
  c.cy = std::nan("");
  EXPECT_FALSE(c.IsValid(&error));
  c = TestCamera();
  c.width = 99999999;
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_EQ(error, "camera image size 99999999x480 is over 16384 px a side");
}

// Issue 34: both camera files as Windows tools save them (CRLF, a UTF-8 byte-order mark),
// with a lone CR (classic Mac) and in UTF-16, read as their LF twins.
TEST(Camera, CrlfAndByteOrderMarkReadAsPlainText) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string opencv = (dir / "kincal_cam_crlf_cv.yaml").string();
  const std::string ros = (dir / "kincal_cam_crlf_ros.yaml").string();
  ASSERT_TRUE(WriteCameraYaml(TestCamera(), opencv).ok());
  ASSERT_TRUE(WriteCameraInfoYaml(TestCamera(), "overhead", ros).ok());
  for (const std::string& path : {opencv, ros}) {
    std::ifstream in(path);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (const auto& [system, other] : ::kincal::testing::OtherSystemsText(text)) {
      const std::string crlf = path + ".other.yaml";
      std::ofstream(crlf, std::ios::binary) << other;
      const StatusOr<CameraModel> c = ReadCameraYaml(crlf);
      ASSERT_TRUE(c.ok()) << path << ", " << system << ": " << c.status().message();
      EXPECT_EQ(c->width, TestCamera().width) << path << ", " << system;
      EXPECT_DOUBLE_EQ(c->fx, TestCamera().fx) << path << ", " << system;
      EXPECT_DOUBLE_EQ(c->k3, TestCamera().k3) << path << ", " << system;
    }
  }
}

// ROS camera_info YAML (camera_calibration_parsers' keys), read back by the same reader.
TEST(Camera, RosCameraInfoYamlRoundTrip) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string path = (dir / "kincal_camera_info_test.yaml").string();
  ASSERT_TRUE(WriteCameraInfoYaml(TestCamera(), "overhead", path).ok());
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* key : {"camera_name: overhead", "distortion_model: plumb_bob",
                          "rectification_matrix:", "projection_matrix:\n  rows: 3\n  cols: 4"}) {
    EXPECT_NE(text.find(key), std::string::npos) << key << "\n" << text;
  }
  const CameraModel c = ReadCameraYaml(path).value();
  const CameraModel t = TestCamera();
  EXPECT_EQ(c.width, t.width);
  EXPECT_EQ(c.height, t.height);
  for (const auto& [a, b] : {std::pair{c.fx, t.fx},
                             {c.fy, t.fy},
                             {c.cx, t.cx},
                             {c.cy, t.cy},
                             {c.k1, t.k1},
                             {c.k2, t.k2},
                             {c.p1, t.p1},
                             {c.p2, t.p2},
                             {c.k3, t.k3}}) {
    EXPECT_DOUBLE_EQ(a, b);
  }
  const std::string fisheye = (dir / "kincal_camera_info_fisheye.yaml").string();
  std::ofstream(fisheye) << std::regex_replace(text, std::regex("plumb_bob"), "equidistant");
  const StatusOr<CameraModel> refused = ReadCameraYaml(fisheye);
  ASSERT_FALSE(refused.ok());
  EXPECT_NE(refused.status().message().find("distortion_model 'equidistant'"), std::string::npos)
      << refused.status().message();
}

}  // namespace
}  // namespace kincal::vision
