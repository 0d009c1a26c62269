// The vision set-up files: target layouts (YAML) and floor extrinsics (OpenCV FileStorage,
// as `kincal floorcal` writes them). The shipped layouts read back as written; a bad file
// is refused with its path, and the line where the YAML says one; a floor whose R_cf is
// not a rotation is refused; the nadir floor maps the floor's axes as documented.
#include "kincal/vision/setup_files.h"

#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/core.hpp>
#include <stdexcept>

#include "source_dir.h"
#include "temp_path.h"
#include "windows_text.h"

namespace kincal::vision {
namespace {

using kincal::testing::TempPath;

std::string Write(const std::string& name, const std::string& text) {
  const std::string path = TempPath(name);
  std::ofstream(path) << text;
  return path;
}

// The message of what `f` throws ("" when it does not).
template <typename T>
std::string ErrorOf(const StatusOr<T>& r) {
  return r.ok() ? "" : r.status().message();
}

TEST(SetupFiles, TheShippedLargeTargetReadsAsWritten) {
  const TargetLayout t =
      ReadTargetLayoutYaml(kincal::testing::SourceDir() + "/config/target_large.yaml").value();
  EXPECT_EQ(t.name, "large");
  EXPECT_DOUBLE_EQ(t.marker_radius_m, 0.024);
  EXPECT_DOUBLE_EQ(t.plate_size_m.x(), 0.36);
  EXPECT_DOUBLE_EQ(t.plate_size_m.y(), 0.24);
  ASSERT_EQ(t.markers.size(), 4u);
  EXPECT_DOUBLE_EQ(t.markers[3].x(), -0.060);
  EXPECT_DOUBLE_EQ(t.markers[3].y(), 0.075);
}

// Issue 34: the shipped layout as other systems save it (CRLF and a byte-order mark, a lone
// CR, UTF-16) reads as itself.
TEST(SetupFiles, OtherSystemsTextReadsAsItself) {
  const std::string shipped = kincal::testing::SourceDir() + "/config/target_large.yaml";
  const TargetLayout plain = ReadTargetLayoutYaml(shipped).value();
  std::ifstream in(shipped);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const auto& [system, other] : kincal::testing::OtherSystemsText(text)) {
    const std::string path = TempPath("target_other.yaml");
    std::ofstream(path, std::ios::binary) << other;
    const StatusOr<TargetLayout> t = ReadTargetLayoutYaml(path);
    ASSERT_TRUE(t.ok()) << system << ": " << t.status().message();
    EXPECT_EQ(t->name, plain.name) << system;
    EXPECT_EQ(t->marker_radius_m, plain.marker_radius_m) << system;
    EXPECT_EQ(t->plate_size_m, plain.plate_size_m) << system;
    EXPECT_EQ(t->markers, plain.markers) << system;
  }
}

TEST(SetupFiles, NoPathIsTheThesisPlate) {
  const TargetLayout t = ReadTargetLayoutYaml("").value();
  const TargetLayout thesis = TargetLayout::Thesis();
  ASSERT_EQ(t.markers.size(), thesis.markers.size());
  for (size_t i = 0; i < t.markers.size(); ++i) EXPECT_EQ(t.markers[i], thesis.markers[i]);
}

TEST(SetupFiles, ABadTargetIsRefusedWithItsPathAndLine) {
  const std::string missing = TempPath("no_such_target.yaml");
  EXPECT_NE(ErrorOf(ReadTargetLayoutYaml(missing)).find(missing), std::string::npos);
  const std::string no_markers = Write("no_markers.yaml", "name: x\nmarker_radius_m: 0.01\n");
  EXPECT_EQ(ErrorOf(ReadTargetLayoutYaml(no_markers)), no_markers + ": missing key 'markers'");
  const std::string bad_marker =
      Write("bad_marker.yaml", "name: x\nmarkers:\n  - [0.1, 0.2]\n  - [0.1, 0.2, 0.3]\n");
  EXPECT_EQ(ErrorOf(ReadTargetLayoutYaml(bad_marker)),
            bad_marker + ":4: a marker is [x, y] in metres");
  const std::string not_number = Write("not_number.yaml", "name: x\nmarkers:\n  - [0.1, abc]\n");
  EXPECT_NE(ErrorOf(ReadTargetLayoutYaml(not_number)).find(not_number + ":3:"), std::string::npos);
  const std::string plate = Write("plate.yaml", "plate_size_m: [0.1]\nmarkers: []\n");
  EXPECT_EQ(ErrorOf(ReadTargetLayoutYaml(plate)), plate + ": plate_size_m needs [width, height]");
  // A misspelt key was ignored: the default radius (the thesis's 8 mm) corrected the
  // perspective bias of larger markers' centres, with no word said.
  const std::string typo = Write("typo.yaml", "name: x\nmarker_radius: 0.02\nmarkers: []\n");
  EXPECT_EQ(ErrorOf(ReadTargetLayoutYaml(typo)),
            typo +
                ":2: unknown key 'marker_radius' (known: name, marker_radius_m, "
                "dark_on_light, plate_size_m, markers)");
  const std::string list = Write("list.yaml", "- [0.1, 0.2]\n");
  EXPECT_EQ(ErrorOf(ReadTargetLayoutYaml(list)), list + ": a target layout is a map of keys");
}

TEST(SetupFiles, AFloorFileReadsBackAndANonRotationIsRefused) {
  const double a = 0.3;
  cv::Mat R = (cv::Mat_<double>(3, 3) << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0,
               0, 0, 1);
  cv::Mat t = (cv::Mat_<double>(3, 1) << 0.1, -0.2, 1.5);
  const std::string good = TempPath("floor.yaml");
  {
    cv::FileStorage fs(good, cv::FileStorage::WRITE);
    fs << "R_cf" << R << "t_cf" << t;
  }
  const FloorExtrinsics f = ReadFloorYaml(good).value();
  EXPECT_NEAR(f.R_cf(1, 0), std::sin(a), 1e-15);
  EXPECT_NEAR(f.t_cf.z(), 1.5, 1e-15);

  const std::string scaled = TempPath("floor_scaled.yaml");
  {
    cv::FileStorage fs(scaled, cv::FileStorage::WRITE);
    fs << "R_cf" << cv::Mat(2.0 * R) << "t_cf" << t;
  }
  EXPECT_EQ(ErrorOf(ReadFloorYaml(scaled)), scaled + ": R_cf is not a rotation");
  const std::string short_t = TempPath("floor_short.yaml");
  {
    cv::FileStorage fs(short_t, cv::FileStorage::WRITE);
    const cv::Mat t2 = (cv::Mat_<double>(2, 1) << 0.1, 0.2);
    fs << "R_cf" << R << "t_cf" << t2;
  }
  EXPECT_EQ(ErrorOf(ReadFloorYaml(short_t)), short_t + ": expected a 3-vector 't_cf'");
  const std::string nan_t = TempPath("floor_nan.yaml");
  {
    cv::FileStorage fs(nan_t, cv::FileStorage::WRITE);
    const cv::Mat t3 = (cv::Mat_<double>(3, 1) << 0.1, std::nan(""), 1.5);
    fs << "R_cf" << R << "t_cf" << t3;
  }
  EXPECT_EQ(ErrorOf(ReadFloorYaml(nan_t)), nan_t + ": t_cf must be three finite numbers");
  const std::string missing = TempPath("no_floor.yaml");
  EXPECT_NE(ErrorOf(ReadFloorYaml(missing)).find(missing), std::string::npos);
}

// Straight down from h: the floor's x is the camera's x, the floor's y the camera's -y,
// and the floor is h in front of the camera.
TEST(SetupFiles, TheNadirFloorLooksStraightDown) {
  const FloorExtrinsics f = NadirFloor(2.0);
  const Eigen::Vector3d p_floor(0.3, 0.4, 0.0);
  const Eigen::Vector3d p_cam = f.R_cf * p_floor + f.t_cf;
  EXPECT_DOUBLE_EQ(p_cam.x(), 0.3);
  EXPECT_DOUBLE_EQ(p_cam.y(), -0.4);
  EXPECT_DOUBLE_EQ(p_cam.z(), 2.0);
  EXPECT_NEAR(f.R_cf.determinant(), 1.0, 1e-15);
}

}  // namespace
}  // namespace kincal::vision
