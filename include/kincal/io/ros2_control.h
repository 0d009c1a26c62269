// Calibrated parameters as the configuration a ros2_control controller loads:
// diff_drive_controller (diffdrive, and unicycle scales on a differential drive),
// ackermann_steering_controller (ackermann) and tricycle_controller (tricycle).
#pragma once

#include <map>
#include <ostream>
#include <string>

#include "kincal/io/checkpoint.h"
#include "kincal/status.h"

namespace kincal {

struct Ros2ControlOptions {
  // The controller's name, the YAML file's top key; empty: the controller type's own.
  std::string controller;
  // The user's nominal values, kept as the base parameters so that the calibration lands
  // in the multipliers: diffdrive "wheel_radius", "wheel_separation" (optional; unicycle
  // needs both); tricycle "drive_ticks_per_rad" (the drive control's ticks per wheel
  // radian; 1 when it is in rad/s).
  std::map<std::string, double> nominal;

  bool IsValid(std::string* error) const;
};

// Writes `c` (a checkpoint, a log's last estimate or an analyze report) as the
// parameters of the controller for c.model, with each value's sigma as a YAML comment.
// An error names what is missing (a parameter of the model, a nominal value it needs).
Status WriteRos2ControlYaml(std::ostream& out, const Checkpoint& c, const std::string& source,
                            const Ros2ControlOptions& options);

}  // namespace kincal
