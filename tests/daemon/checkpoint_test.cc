// Checkpoints: written atomically, read back exactly, exported as YAML.
#include "kincal/daemon/checkpoint.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <kincal/controls_t.hpp>
#include <kincal/params_t.hpp>
#include <kincal/pose_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <thread>

#include "daemon/daemon_test_util.h"

namespace kincal::daemon {
namespace {

using namespace test_util;

TEST(Checkpoint, RoundTripsAtomicallyAndExportsYaml) {
  Checkpoint c;
  c.model = "diffdrive";
  c.filter = "dd2";
  c.utime = 1234567;
  c.update_count = 42;
  c.names = {"r_l", "r_r", "d"};
  c.units = {"m", "m", "m"};
  c.values = {0.031, 0.0313, 0.148};
  c.covariance = Eigen::Matrix3d::Identity() * 1e-8;
  c.covariance(0, 1) = c.covariance(1, 0) = 3e-9;
  const std::string path = TempPath("ck.json");
  WriteCheckpoint(path, c);
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  const Checkpoint r = ReadCheckpoint(path);
  EXPECT_EQ(r.names, c.names);
  EXPECT_EQ(r.values, c.values);
  EXPECT_EQ(r.covariance, c.covariance);
  std::ostringstream yaml;
  WriteExportYaml(yaml, r, path);
  EXPECT_NE(yaml.str().find("  r_r: {value: 0.0313, sigma: 0.0001, unit: \"m\"}"),
            std::string::npos)
      << yaml.str();
  std::ofstream(path) << "{\"format\": \"kincal-checkpoint\", \"version\": 1, \"model\": 3}";
  EXPECT_THROW(ReadCheckpoint(path), std::runtime_error);
}

}  // namespace
}  // namespace kincal::daemon
