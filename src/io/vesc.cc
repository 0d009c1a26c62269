#include "kincal/io/vesc.h"

#include <cmath>
#include <iomanip>

namespace kincal {
namespace {

constexpr const char* kKeys[] = {"speed_to_erpm_gain", "steering_angle_to_servo_gain",
                                 "steering_angle_to_servo_offset"};

}  // namespace

Status WriteVescYaml(std::ostream& out, const Checkpoint& c, const std::string& source,
                     const std::map<std::string, double>& nominal) {
  if (c.model != "bicycle") {
    return Status::Error("--format vesc: model '" + c.model +
                         "': the VESC gains are for a car commanded by speed and steering angle "
                         "(model bicycle)");
  }
  for (const char* k : kKeys) {
    if (!nominal.count(k) || !std::isfinite(nominal.at(k))) {
      return Status::Error(std::string("--format vesc: give --nominal ") + k +
                           "=VALUE (the value in your vesc.yaml; all three of "
                           "speed_to_erpm_gain, steering_angle_to_servo_gain, "
                           "steering_angle_to_servo_offset)");
    }
  }
  double kv = 0, kv_s = 0, ks = 0, ks_s = 0, off = 0, off_s = 0;
  if (!FindParameter(c, "k_v", &kv, &kv_s) || !FindParameter(c, "k_steer", &ks, &ks_s) ||
      !FindParameter(c, "steer_offset", &off, &off_s)) {
    return Status::Error("--format vesc: the estimate lacks k_v, k_steer or steer_offset");
  }
  if (!(std::abs(kv) > 1e-6) || !(std::abs(ks) > 1e-6)) {
    return Status::Error(
        "--format vesc: k_v or k_steer is zero: the car does not follow its "
        "commands, nothing to correct");
  }
  const double erpm = nominal.at(kKeys[0]), gain = nominal.at(kKeys[1]),
               offset = nominal.at(kKeys[2]);
  out << std::setprecision(15)
      << "# kincal calibration of a car for the VESC driver (vesc.yaml), from " << source
      << "\n# measured: k_v " << kv << " (sigma " << kv_s << "), k_steer " << ks << " (sigma "
      << ks_s << "), steer_offset " << off << " rad (sigma " << off_s
      << ")\n# corrected from the values in use: speed_to_erpm_gain " << erpm
      << ", steering_angle_to_servo_gain " << gain << ", steering_angle_to_servo_offset " << offset
      << "\n";
  out << "speed_to_erpm_gain: " << erpm / kv << "\n";
  out << "steering_angle_to_servo_gain: " << gain / ks << "\n";
  out << "steering_angle_to_servo_offset: " << offset - gain * off / ks << "\n";
  return Status();
}

}  // namespace kincal
