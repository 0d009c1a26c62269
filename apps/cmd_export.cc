// kincal export: the calibrated parameters with their sigma (and covariance) as YAML a
// robot's configuration can include, or as the parameters of a ros2_control controller;
// from a kincald checkpoint, the last kincal.params_t in an LCM log, or an analyze report.
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <kincal/params_t.hpp>
#include <map>
#include <memory>
#include <sstream>

#include "commands.h"
#include "kincal/analysis/analyze.h"
#include "kincal/io/checkpoint.h"
#include "kincal/io/lcm_guard.h"
#include "kincal/io/lcm_log_reader.h"
#include "kincal/io/ros2_control.h"
#include "kincal/io/vesc.h"
#include "python_scripts.h"

namespace kincal::app {
namespace {

// The last plausible kincal.params_t on `channel`.
Checkpoint FromLog(const std::string& path, const std::string& channel) {
  std::unique_ptr<LcmLogReader> opened;
  if (const Status s = LcmLogReader::Open(path, &opened); !s.ok()) {
    throw std::runtime_error(s.message());
  }
  LcmLogReader& file = *opened;
  kincal::params_t last;
  bool found = false;
  int64_t bad = 0;
  LcmLogEvent ev;
  while (file.Next(&ev)) {
    if (ev.channel != channel) continue;
    kincal::params_t m;
    std::string why;
    if (!PlausibleParams(ev.data.data(), ev.data.size(), 1000, &why) ||
        m.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())) < 0 || m.num_params < 0 ||
        m.covariance.size() != static_cast<size_t>(m.num_params)) {
      ++bad;
      continue;
    }
    last = std::move(m);
    found = true;
  }
  if (!found) throw std::runtime_error(path + ": no kincal.params_t on channel " + channel);
  if (bad > 0) {
    std::cerr << "kincal export: " << bad << " undecodable events on " << channel << " skipped\n";
  }
  for (const auto& p : file.problems()) std::cerr << "kincal export: " << p << "\n";
  Checkpoint c;
  FillCheckpoint(last, {}, &c);
  return c;
}

// "k=v,k=v" into numbers; an error names the item.
std::map<std::string, double> ParseNominal(const std::string& text) {
  std::map<std::string, double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const size_t eq = item.find('=');
    char* end = nullptr;
    const double v = eq == std::string::npos ? 0.0 : std::strtod(item.c_str() + eq + 1, &end);
    if (eq == std::string::npos || end == item.c_str() + eq + 1 || *end != '\0') {
      throw std::runtime_error("--nominal: '" + item + "': expected name=number");
    }
    out[item.substr(0, eq)] = v;
  }
  return out;
}

}  // namespace

Checkpoint ReadCheckpointOrThrow(const std::string& path) {
  StatusOr<Checkpoint> c = ReadCheckpoint(path);
  if (!c.ok()) throw std::runtime_error(c.status().message());
  return std::move(c).value();
}

Checkpoint ReadReportAsCheckpoint(const std::string& path) {
  ReportEstimate r;
  if (Status s = ReadReportEstimate(path, &r); !s.ok()) throw std::runtime_error(s.message());
  Checkpoint c;
  c.model = r.model;
  c.effects = r.effects;
  c.filter = "batch (kincal analyze)";
  c.names = r.names;
  c.units = r.units;
  c.values = r.values;
  c.covariance =
      Eigen::MatrixXd::Zero(static_cast<int>(r.names.size()), static_cast<int>(r.names.size()));
  for (size_t i = 0; i < r.sigmas.size(); ++i) {
    c.covariance(static_cast<int>(i), static_cast<int>(i)) = r.sigmas[i] * r.sigmas[i];
  }
  return c;
}

namespace {

// --format mcap: scripts/kincal_mcap.py (foxglove-sdk, from PyPI) in this process's place.
[[noreturn]] void ExportMcap(const std::string& log, const std::string& out) {
  if (log.empty() || out.empty()) {
    throw std::runtime_error("--format mcap needs --log FILE (a kincald recording) and --out FILE");
  }
  ExecPythonScript("kincal_mcap.py", "KINCAL_MCAP_SCRIPT", {"--log", log, "--out", out},
                   "foxglove-sdk and lcm");
}

}  // namespace

Command AddExport(CLI::App& app) {
  struct Args {
    std::string checkpoint, log, report, channel = "KINCAL_PARAMS", out, format = "yaml";
    std::string nominal, controller;
  };
  auto a = std::make_shared<Args>();
  auto* ck = app.add_option("--checkpoint", a->checkpoint, "kincald checkpoint (JSON)");
  auto* log = app.add_option("--log", a->log, "LCM log: its last kincal.params_t on --channel");
  auto* rep = app.add_option("--report", a->report, "kincal analyze's report.json");
  ck->excludes(log)->excludes(rep);
  log->excludes(rep);
  app.add_option("--channel", a->channel, "params channel in the log")->capture_default_str();
  app.add_option("--format", a->format,
                 "yaml | ros2_control | vesc (F1TENTH's vesc.yaml) | mcap (--log as MCAP for "
                 "Foxglove: frames, overlay, poses, every message)")
      ->check(CLI::IsMember({"yaml", "ros2_control", "vesc", "mcap"}))
      ->capture_default_str();
  app.add_option("--nominal", a->nominal,
                 "ros2_control: your nominal wheel_radius=R,wheel_separation=D (kept; the "
                 "calibration goes into the multipliers), or drive_ticks_per_rad=N (tricycle); "
                 "vesc: the speed_to_erpm_gain, steering_angle_to_servo_gain and _offset in use");
  app.add_option("--controller", a->controller,
                 "ros2_control: the controller's name (default: its type's)");
  app.add_option("--out", a->out, "YAML file (default: standard output)");
  return [a]() -> int {
    if (a->format == "mcap") ExportMcap(a->log, a->out);
    Checkpoint c;
    std::string source;
    if (!a->checkpoint.empty()) {
      c = ReadCheckpointOrThrow(a->checkpoint);
      source = a->checkpoint;
    } else if (!a->log.empty()) {
      c = FromLog(a->log, a->channel);
      source = a->log + " (" + a->channel + ")";
    } else if (!a->report.empty()) {
      c = ReadReportAsCheckpoint(a->report);
      source = a->report;
    } else {
      throw std::runtime_error("give --checkpoint FILE, --log FILE or --report FILE");
    }
    std::ostringstream out;
    if (a->format == "ros2_control") {
      Ros2ControlOptions o;
      o.controller = a->controller;
      o.nominal = ParseNominal(a->nominal);
      if (Status s = WriteRos2ControlYaml(out, c, source, o); !s.ok()) {
        throw std::runtime_error(s.message());
      }
    } else if (a->format == "vesc") {
      if (Status s = WriteVescYaml(out, c, source, ParseNominal(a->nominal)); !s.ok()) {
        throw std::runtime_error(s.message());
      }
    } else {
      WriteExportYaml(out, c, source);
    }
    if (a->out.empty()) {
      std::cout << out.str();
    } else {
      WriteOutput(a->out, out.str(), "export");
      std::cout << "wrote " << a->out << "\n";
    }
    return 0;
  };
}

}  // namespace kincal::app
