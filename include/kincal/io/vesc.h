// F1TENTH's vesc.yaml from a car's calibration (model bicycle): the VESC driver turns a
// commanded speed into motor ERPM by speed_to_erpm_gain (and _offset), and a commanded
// steering angle into a servo position by steering_angle_to_servo_gain and _offset. With the
// values in use (--nominal), a car that realises k_v x the commanded speed and
// k_steer x the commanded angle + steer_offset is corrected so that it realises the command:
//   speed_to_erpm_gain'            = speed_to_erpm_gain / k_v
//   steering_angle_to_servo_gain'   = steering_angle_to_servo_gain / k_steer
//   steering_angle_to_servo_offset' = steering_angle_to_servo_offset
//                                     - steering_angle_to_servo_gain x steer_offset / k_steer
// (the servo maps linearly to the angle: phi = k_steer (servo - offset) / gain + steer_offset).
#pragma once

#include <map>
#include <ostream>
#include <string>

#include "kincal/io/checkpoint.h"
#include "kincal/status.h"

namespace kincal {

// `nominal` holds the three values in use: speed_to_erpm_gain,
// steering_angle_to_servo_gain, steering_angle_to_servo_offset. An error names a missing
// one, a model other than bicycle, or a gain that is not usable.
Status WriteVescYaml(std::ostream& out, const Checkpoint& c, const std::string& source,
                     const std::map<std::string, double>& nominal);

}  // namespace kincal
