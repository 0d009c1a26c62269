// F1TENTH's vesc.yaml from a car's calibration: with the corrected gains, the car realises
// the speed and the steering angle it is commanded.
#include "kincal/io/vesc.h"

#include <gtest/gtest.h>

#include <sstream>

namespace kincal {
namespace {

Checkpoint Car(double k_v, double k_steer, double offset) {
  Checkpoint c;
  c.model = "bicycle";
  c.names = {"k_v", "k_steer", "steer_offset", "wheelbase"};
  c.values = {k_v, k_steer, offset, 0.33};
  c.covariance = Eigen::MatrixXd::Identity(4, 4) * 1e-6;
  return c;
}

std::map<std::string, double> ParseVesc(const std::string& text) {
  std::map<std::string, double> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const size_t colon = line.find(':');
    out[line.substr(0, colon)] = std::stod(line.substr(colon + 1));
  }
  return out;
}

TEST(Vesc, CorrectedGainsMakeTheCarRealiseItsCommands) {
  const std::map<std::string, double> in_use = {{"speed_to_erpm_gain", 4614.0},
                                                {"steering_angle_to_servo_gain", -1.2135},
                                                {"steering_angle_to_servo_offset", 0.5304}};
  // The car as measured with those values: k_v 0.9, k_steer 0.6, offset 0.02 rad, i.e. the
  // servo turns the wheels by phi = 0.6 (servo - 0.5304) / -1.2135 + 0.02, and the motor
  // realises 0.9 x the speed whose ERPM 4614 x v asks for.
  std::ostringstream out;
  ASSERT_TRUE(WriteVescYaml(out, Car(0.9, 0.6, 0.02), "test", in_use).ok());
  const auto v = ParseVesc(out.str());
  for (double cmd : {-0.3, 0.0, 0.1, 0.34}) {
    const double servo =
        v.at("steering_angle_to_servo_gain") * cmd + v.at("steering_angle_to_servo_offset");
    const double phi = 0.6 * (servo - 0.5304) / -1.2135 + 0.02;
    EXPECT_NEAR(phi, cmd, 1e-9) << cmd;
  }
  const double speed = 2.0, erpm = v.at("speed_to_erpm_gain") * speed;
  EXPECT_NEAR(0.9 * erpm / 4614.0, speed, 1e-9);
}

TEST(Vesc, MissingValuesAndOtherModelsAreNamedErrors) {
  std::ostringstream out;
  const Status missing = WriteVescYaml(out, Car(0.9, 0.6, 0.02), "test", {});
  EXPECT_NE(missing.message().find("--nominal speed_to_erpm_gain=VALUE"), std::string::npos)
      << missing.message();
  Checkpoint other = Car(0.9, 0.6, 0.02);
  other.model = "unicycle";
  EXPECT_NE(WriteVescYaml(out, other, "test",
                          {{"speed_to_erpm_gain", 1},
                           {"steering_angle_to_servo_gain", 1},
                           {"steering_angle_to_servo_offset", 0}})
                .message()
                .find("model bicycle"),
            std::string::npos);
  EXPECT_TRUE(out.str().empty());
}

}  // namespace
}  // namespace kincal
