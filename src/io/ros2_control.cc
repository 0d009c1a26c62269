#include "kincal/io/ros2_control.h"

#include <cctype>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <vector>

namespace kincal {
namespace {

// One parameter of the controller, with the comment that goes beside it.
struct Entry {
  std::string key;
  double value;
  std::string comment;
};

struct Mapped {
  std::string controller;          // ros2_controllers' type name
  std::vector<Entry> entries;      // under ros__parameters
  std::vector<std::string> notes;  // comment lines above them
};

// A model parameter's value and sigma by name.
struct Param {
  double value = 0.0, sigma = 0.0;
};

bool Find(const Checkpoint& c, const std::string& name, Param* p) {
  return FindParameter(c, name, &p->value, &p->sigma);
}

std::string Num(double v, int digits = 6) {
  std::ostringstream s;
  s << std::setprecision(digits) << v;
  return s.str();
}

// sigma of a value and of the quantity it stands for.
std::string Sigma(const std::string& what, const Param& p, const std::string& unit) {
  return what + " " + Num(p.value, 7) + " " + unit + ", sigma " + Num(p.sigma, 2) + " " + unit;
}

Status Need(const Checkpoint& c, std::initializer_list<const char*> names,
            std::map<std::string, Param>* out) {
  for (const char* n : names) {
    if (!Find(c, n, &(*out)[n])) {
      return Status::Error("model " + c.model + ": the estimate has no parameter '" + n + "'");
    }
  }
  return Status();
}

double NominalOr(const Ros2ControlOptions& o, const std::string& key, double fallback) {
  const auto it = o.nominal.find(key);
  return it == o.nominal.end() ? fallback : it->second;
}

// Effective radius r = wheel_radius * multiplier; track d = wheel_separation * multiplier.
void DiffDriveEntries(const Param& rl, const Param& rr, const Param& d, double radius,
                      double separation, Mapped* m) {
  m->entries = {
      {"wheel_separation", separation, "m"},
      {"wheel_radius", radius, "m"},
      {"wheel_separation_multiplier", d.value / separation, Sigma("effective track", d, "m")},
      {"left_wheel_radius_multiplier", rl.value / radius, Sigma("effective left radius", rl, "m")},
      {"right_wheel_radius_multiplier", rr.value / radius,
       Sigma("effective right radius", rr, "m")},
  };
}

Status MapDiffDrive(const Checkpoint& c, const Ros2ControlOptions& o, Mapped* m) {
  std::map<std::string, Param> p;
  if (Status s = Need(c, {"r_l", "r_r", "d"}, &p); !s.ok()) return s;
  const double radius = NominalOr(o, "wheel_radius", 0.5 * (p["r_l"].value + p["r_r"].value));
  const double separation = NominalOr(o, "wheel_separation", p["d"].value);
  m->controller = "diff_drive_controller";
  DiffDriveEntries(p["r_l"], p["r_r"], p["d"], radius, separation, m);
  return Status();
}

// A velocity-commanded robot on a differential drive: realised v = k_v v and
// omega = k_omega omega mean radii k_v times the configured ones and a track
// k_v / k_omega times the configured one.
Status MapUnicycle(const Checkpoint& c, const Ros2ControlOptions& o, Mapped* m) {
  std::map<std::string, Param> p;
  if (Status s = Need(c, {"k_v", "k_omega"}, &p); !s.ok()) return s;
  if (!o.nominal.count("wheel_radius") || !o.nominal.count("wheel_separation")) {
    return Status::Error(
        "model unicycle: give --nominal wheel_radius=R,wheel_separation=D (the values the "
        "controller ran with): its scales k_v, k_omega are relative to them");
  }
  const double r0 = o.nominal.at("wheel_radius"), d0 = o.nominal.at("wheel_separation");
  const Param kv = p["k_v"], kw = p["k_omega"];
  const Param r{r0 * kv.value, r0 * kv.sigma};
  const double ratio = kv.value / kw.value;
  const double ratio_sigma = ratio * std::hypot(kv.sigma / kv.value, kw.sigma / kw.value);
  const Param d{d0 * ratio, d0 * ratio_sigma};
  m->controller = "diff_drive_controller";
  m->notes.push_back("from the unicycle scales k_v = " + Num(kv.value) +
                     ", k_omega = " + Num(kw.value) + " on the nominal wheels");
  DiffDriveEntries(r, r, d, r0, d0, m);
  return Status();
}

Status MapAckermann(const Checkpoint& c, const Ros2ControlOptions&, Mapped* m) {
  std::map<std::string, Param> p;
  if (Status s = Need(c, {"r_b", "l", "steer_offset"}, &p); !s.ok()) return s;
  m->controller = "ackermann_steering_controller";
  m->entries = {
      {"wheelbase", p["l"].value, Sigma("wheelbase", p["l"], "m")},
      {"traction_wheels_radius", p["r_b"].value, Sigma("rear (driven) radius", p["r_b"], "m")},
      {"rear_wheels_radius", p["r_b"].value, "the same, under its name before ROS 2 Jazzy"},
  };
  m->notes.push_back("steering offset " + Num(p["steer_offset"].value) + " rad (sigma " +
                     Num(p["steer_offset"].sigma, 2) +
                     "): no controller parameter; move the steering joint's zero by it");
  m->notes.push_back("track widths are not calibrated by kincal: keep yours");
  return Status();
}

// A car commanded by speed and steering angle: ackermann_steering_controller turns its
// twist into a traction wheel speed through its radius (a realised speed k_v x the command
// is a radius k_v x the nominal one) and a steering angle through the wheelbase; the
// steering gain and offset have no controller parameter.
Status MapBicycle(const Checkpoint& c, const Ros2ControlOptions& o, Mapped* m) {
  std::map<std::string, Param> p;
  if (Status s = Need(c, {"k_v", "k_steer", "steer_offset", "wheelbase"}, &p); !s.ok()) return s;
  m->controller = "ackermann_steering_controller";
  m->entries = {{"wheelbase", p["wheelbase"].value, Sigma("wheelbase", p["wheelbase"], "m")}};
  if (o.nominal.count("wheel_radius")) {
    const double r0 = o.nominal.at("wheel_radius");
    const Param r{r0 * p["k_v"].value, r0 * p["k_v"].sigma};
    m->entries.push_back({"traction_wheels_radius", r.value, Sigma("effective radius", r, "m")});
    m->entries.push_back(
        {"rear_wheels_radius", r.value, "the same, under its name before ROS 2 Jazzy"});
  } else {
    m->notes.push_back("speed: the car realises k_v = " + Num(p["k_v"].value) + " (sigma " +
                       Num(p["k_v"].sigma, 2) +
                       ") x the commanded speed; give --nominal wheel_radius=R for the "
                       "controller's traction_wheels_radius (R x k_v)");
  }
  m->notes.push_back("steering: realised angle = " + Num(p["k_steer"].value) + " x command + " +
                     Num(p["steer_offset"].value) +
                     " rad: no controller parameter; scale and offset the steering joint's "
                     "command by them (or export --format vesc)");
  return Status();
}

Status MapTricycle(const Checkpoint& c, const Ros2ControlOptions& o, Mapped* m) {
  std::map<std::string, Param> p;
  if (Status s = Need(c, {"k_drive", "wheelbase", "k_steer", "steer_offset"}, &p); !s.ok()) {
    return s;
  }
  if (!o.nominal.count("drive_ticks_per_rad")) {
    return Status::Error(
        "model tricycle: give --nominal drive_ticks_per_rad=N (the drive control's ticks per "
        "wheel radian; 1 if it is in rad/s): the wheel radius is k_drive times it");
  }
  const double tpr = o.nominal.at("drive_ticks_per_rad");
  const Param r{p["k_drive"].value * tpr, p["k_drive"].sigma * tpr};
  m->controller = "tricycle_controller";
  m->entries = {
      {"wheelbase", p["wheelbase"].value, Sigma("wheelbase", p["wheelbase"], "m")},
      {"wheel_radius", r.value, Sigma("traction wheel radius", r, "m")},
  };
  m->notes.push_back("steering: " + Num(p["k_steer"].value) + " rad per tick, offset " +
                     Num(p["steer_offset"].value) +
                     " rad: no controller parameter; they belong to the steering joint's "
                     "hardware interface");
  return Status();
}

}  // namespace

bool Ros2ControlOptions::IsValid(std::string* error) const {
  for (char ch : controller) {
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_' && ch != '/') {
      *error = "controller name '" + controller + "': expected letters, digits, '_' and '/'";
      return false;
    }
  }
  for (const auto& [key, value] : nominal) {
    if (key != "wheel_radius" && key != "wheel_separation" && key != "drive_ticks_per_rad") {
      *error =
          "nominal '" + key + "': expected wheel_radius, wheel_separation or drive_ticks_per_rad";
      return false;
    }
    if (!(std::isfinite(value) && value > 0.0)) {
      *error = "nominal " + key + " = " + Num(value) + ": expected a positive number";
      return false;
    }
  }
  return true;
}

Status WriteRos2ControlYaml(std::ostream& out, const Checkpoint& c, const std::string& source,
                            const Ros2ControlOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) return Status::Error(why);
  Mapped m;
  Status s;
  if (c.model == "diffdrive") {
    s = MapDiffDrive(c, options, &m);
  } else if (c.model == "unicycle") {
    s = MapUnicycle(c, options, &m);
  } else if (c.model == "ackermann") {
    s = MapAckermann(c, options, &m);
  } else if (c.model == "tricycle") {
    s = MapTricycle(c, options, &m);
  } else if (c.model == "bicycle") {
    s = MapBicycle(c, options, &m);
  } else {
    s = Status::Error("model '" + c.model + "': no ros2_control controller is known for it");
  }
  if (!s.ok()) return s;
  out << "# kincal calibration of a " << c.model << " robot for ros2_control's " << m.controller
      << ", from " << source << "\n# sigma is 1-sigma.";
  if (!c.effects.empty()) {
    out << " Effects estimated with it (not controller parameters):";
    for (const auto& e : c.effects) out << " " << e;
  }
  out << "\n";
  for (const auto& n : m.notes) out << "# " << n << "\n";
  out << (options.controller.empty() ? m.controller : options.controller)
      << ":\n  ros__parameters:\n";
  for (const auto& e : m.entries) {
    out << "    " << e.key << ": " << std::setprecision(12) << e.value;
    if (!e.comment.empty()) out << "  # " << e.comment;
    out << "\n";
  }
  return Status();
}

}  // namespace kincal
