// The checks of kincald's configuration: each section says what it expects, and a
// section is checked only when it is used.
#include <gtest/gtest.h>

#include <stdexcept>

#include "kincal/daemon/config.h"

namespace kincal::daemon {
namespace {

TEST(Config, EachSectionSaysWhatItExpects) {
  DaemonConfig c;
  std::string error;
  ASSERT_TRUE(c.IsValid(&error)) << error;
  c.v4l2.buffers = 2;
  EXPECT_TRUE(c.IsValid(&error)) << "the v4l2 section is checked only when it is the source";
  c.source = SourceKind::kV4l2;
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_EQ(error, "v4l2.buffers must be 4..32");
  c = DaemonConfig{};
  c.v4l2.pixel_format = PixelFormat::kPng;  // a recording's encoding, not a camera's
  c.source = SourceKind::kV4l2;
  EXPECT_FALSE(c.v4l2.IsValid(&error));
  EXPECT_EQ(error, "v4l2.pixel_format must be GREY, YUYV, MJPG, BGR3 or RGB3 (got 'PNG')");
  c = DaemonConfig{};
  c.calibration.every_s = 0.5;
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_EQ(error, "calibration.every_s must be in [1, 86400] s");
  c = DaemonConfig{};
  c.calibration.growth = -1;
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_EQ(error, "calibration.growth must be in [0, 10]");
  c = DaemonConfig{};
  c.calibration.max_poses = 10;
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_EQ(error, "calibration.max_poses must be 1000..10000000");
  c = DaemonConfig{};
  c.filter.type = "kalman";
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_NE(error.find("filter.type: unknown filter 'kalman' (known: "), std::string::npos)
      << error;
  c = DaemonConfig{};
  c.robot.guess["wheel_base"] = 0.3;
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_EQ(error, "robot.guess: model 'diffdrive' with its effects has no parameter 'wheel_base'");
  c = DaemonConfig{};
  c.filter.control_psd = {1e-4};
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_EQ(error, "filter.control_psd needs 2 values for model diffdrive");
  c = DaemonConfig{};
  c.target.height_m = 2.5;  // above the nadir camera at 2 m
  EXPECT_FALSE(c.IsValid(&error));
  EXPECT_EQ(error, "target.height_m must be >= 0 and below the camera");
}

}  // namespace
}  // namespace kincal::daemon
