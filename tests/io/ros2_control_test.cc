// ros2_control export: each model's controller parameters reproduce the calibrated
// geometry, sigma goes in as comments, and what a model cannot say is an error.
#include "kincal/io/ros2_control.h"

#include <gtest/gtest.h>

#include <map>
#include <sstream>

namespace kincal {
namespace {

Checkpoint CheckpointOf(const std::string& model, const std::map<std::string, double>& v) {
  Checkpoint c;
  c.model = model;
  for (const auto& [name, value] : v) {
    c.names.push_back(name);
    c.units.push_back("");
    c.values.push_back(value);
  }
  const int n = static_cast<int>(v.size());
  c.covariance = Eigen::MatrixXd::Identity(n, n) * 1e-10;  // sigma 1e-5
  return c;
}

// key -> value under ros__parameters.
std::map<std::string, double> Parse(const std::string& yaml) {
  std::map<std::string, double> out;
  std::istringstream in(yaml);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("    ", 0) != 0) continue;
    const size_t colon = line.find(':');
    out[line.substr(4, colon - 4)] = std::stod(line.substr(colon + 1));
  }
  return out;
}

TEST(Ros2Control, DiffDriveMultipliersGiveTheCalibratedWheelsAndTrack) {
  const auto c = CheckpointOf("diffdrive", {{"r_l", 0.0342}, {"r_r", 0.0336}, {"d", 0.172}});
  for (const bool nominal : {false, true}) {
    Ros2ControlOptions o;
    if (nominal) o.nominal = {{"wheel_radius", 0.035}, {"wheel_separation", 0.17}};
    std::ostringstream out;
    ASSERT_TRUE(WriteRos2ControlYaml(out, c, "test", o).ok());
    EXPECT_NE(out.str().find("diff_drive_controller:\n  ros__parameters:\n"), std::string::npos);
    EXPECT_NE(out.str().find("sigma 1e-05 m"), std::string::npos) << out.str();
    const auto p = Parse(out.str());
    EXPECT_NEAR(p.at("wheel_radius") * p.at("left_wheel_radius_multiplier"), 0.0342, 1e-10);
    EXPECT_NEAR(p.at("wheel_radius") * p.at("right_wheel_radius_multiplier"), 0.0336, 1e-10);
    EXPECT_NEAR(p.at("wheel_separation") * p.at("wheel_separation_multiplier"), 0.172, 1e-10);
    EXPECT_EQ(p.at("wheel_radius"), nominal ? 0.035 : 0.0339);
  }
}

TEST(Ros2Control, UnicycleScalesOnNominalWheels) {
  // Realised v = k_v v, omega = k_omega omega on a differential drive configured with
  // (r0, d0): radii k_v r0 and track d0 k_v / k_omega give exactly those.
  const auto c = CheckpointOf("unicycle", {{"k_v", 0.95}, {"k_omega", 1.05}});
  Ros2ControlOptions o;
  std::ostringstream out;
  const Status missing = WriteRos2ControlYaml(out, c, "test", o);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.message().find("--nominal wheel_radius"), std::string::npos);
  o.nominal = {{"wheel_radius", 0.05}, {"wheel_separation", 0.3}};
  ASSERT_TRUE(WriteRos2ControlYaml(out, c, "test", o).ok());
  const auto p = Parse(out.str());
  const double r = 0.05 * p.at("left_wheel_radius_multiplier");
  const double d = 0.3 * p.at("wheel_separation_multiplier");
  // A command (v, omega) through the configured wheels, realised by the effective ones.
  const double v = 0.4, w = 0.7;
  const double wl = (v - 0.5 * w * 0.3) / 0.05, wr = (v + 0.5 * w * 0.3) / 0.05;
  EXPECT_NEAR(0.5 * r * (wl + wr), 0.95 * v, 1e-10);
  EXPECT_NEAR(r * (wr - wl) / d, 1.05 * w, 1e-10);
}

TEST(Ros2Control, AckermannAndTricycle) {
  std::ostringstream out;
  ASSERT_TRUE(WriteRos2ControlYaml(
                  out,
                  CheckpointOf("ackermann", {{"r_b", 0.05}, {"l", 0.3}, {"steer_offset", 0.01}}),
                  "test", {})
                  .ok());
  auto p = Parse(out.str());
  EXPECT_EQ(p.at("wheelbase"), 0.3);
  EXPECT_EQ(p.at("traction_wheels_radius"), 0.05);
  EXPECT_NE(out.str().find("ackermann_steering_controller:"), std::string::npos);
  EXPECT_NE(out.str().find("steering offset 0.01 rad"), std::string::npos);

  const auto tri = CheckpointOf(
      "tricycle", {{"k_steer", 0.001}, {"steer_offset", 0}, {"k_drive", 1e-4}, {"wheelbase", 0.5}});
  std::ostringstream t;
  const Status missing = WriteRos2ControlYaml(t, tri, "test", {});
  EXPECT_NE(missing.message().find("drive_ticks_per_rad"), std::string::npos);
  Ros2ControlOptions o;
  o.nominal = {{"drive_ticks_per_rad", 650.0}};
  ASSERT_TRUE(WriteRos2ControlYaml(t, tri, "test", o).ok());
  p = Parse(t.str());
  EXPECT_NEAR(p.at("wheel_radius"), 0.065, 1e-10);
  EXPECT_EQ(p.at("wheelbase"), 0.5);
}

// A car commanded by speed and steering angle: the wheelbase, the effective traction radius
// on the nominal wheels (a realised speed k_v x the command is a radius k_v x nominal), and
// the steering correction said where the controller has no parameter for it.
TEST(Ros2Control, BicycleOnItsNominalWheel) {
  const auto car = CheckpointOf(
      "bicycle", {{"k_v", 0.95}, {"k_steer", 0.6}, {"steer_offset", 0.02}, {"wheelbase", 0.33}});
  std::ostringstream plain;
  ASSERT_TRUE(WriteRos2ControlYaml(plain, car, "test", {}).ok());
  EXPECT_EQ(Parse(plain.str()).at("wheelbase"), 0.33);
  EXPECT_EQ(Parse(plain.str()).count("traction_wheels_radius"), 0u);
  EXPECT_NE(plain.str().find("--nominal wheel_radius=R"), std::string::npos) << plain.str();
  Ros2ControlOptions o;
  o.nominal = {{"wheel_radius", 0.05}};
  std::ostringstream out;
  ASSERT_TRUE(WriteRos2ControlYaml(out, car, "test", o).ok());
  EXPECT_NEAR(Parse(out.str()).at("traction_wheels_radius"), 0.0475, 1e-12);
  EXPECT_NE(out.str().find("realised angle = 0.6 x command + 0.02 rad"), std::string::npos)
      << out.str();
}

TEST(Ros2Control, BadOptionsAndUnknownModelsAreErrors) {
  std::string why;
  Ros2ControlOptions o;
  o.nominal = {{"wheel_radius", -1.0}};
  EXPECT_FALSE(o.IsValid(&why));
  EXPECT_NE(why.find("wheel_radius"), std::string::npos);
  o.nominal = {{"wheel_diameter", 0.1}};
  EXPECT_FALSE(o.IsValid(&why));
  o.nominal.clear();
  o.controller = "bad name:";
  EXPECT_FALSE(o.IsValid(&why));
  std::ostringstream out;
  const Status s = WriteRos2ControlYaml(out, CheckpointOf("hovercraft", {{"k", 1}}), "t", {});
  EXPECT_NE(s.message().find("hovercraft"), std::string::npos);
  const Status m = WriteRos2ControlYaml(out, CheckpointOf("diffdrive", {{"r_l", 0.03}}), "t", {});
  EXPECT_NE(m.message().find("'r_r'"), std::string::npos) << m.message();
}

}  // namespace
}  // namespace kincal
