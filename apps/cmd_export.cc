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
StatusOr<Checkpoint> FromLog(const std::string& path, const std::string& channel) {
  std::unique_ptr<LcmLogReader> opened;
  KINCAL_RETURN_IF_ERROR(LcmLogReader::Open(path, &opened));
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
  if (!found) return Status::Error(path + ": no kincal.params_t on channel " + channel);
  if (bad > 0) {
    std::cerr << "kincal export: " << bad << " undecodable events on " << channel << " skipped\n";
  }
  for (const auto& p : file.problems()) std::cerr << "kincal export: " << p << "\n";
  Checkpoint c;
  FillCheckpoint(last, {}, &c);
  return c;
}

// "k=v,k=v" into numbers; an error names the item.
StatusOr<std::map<std::string, double>> ParseNominal(const std::string& text) {
  std::map<std::string, double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    const size_t eq = item.find('=');
    char* end = nullptr;
    const double v = eq == std::string::npos ? 0.0 : std::strtod(item.c_str() + eq + 1, &end);
    if (eq == std::string::npos || end == item.c_str() + eq + 1 || *end != '\0') {
      return Status::Error("--nominal: '" + item + "': expected name=number");
    }
    out[item.substr(0, eq)] = v;
  }
  return out;
}

}  // namespace

StatusOr<Checkpoint> ReadReportAsCheckpoint(const std::string& path) {
  ReportEstimate r;
  KINCAL_RETURN_IF_ERROR(ReadReportEstimate(path, &r));
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
Status ExportMcap(const std::string& log, const std::string& out) {
  if (log.empty() || out.empty()) {
    return Status::Error("--format mcap needs --log FILE (a kincald recording) and --out FILE");
  }
  return ExecPythonScript("kincal_mcap.py", "KINCAL_MCAP_SCRIPT", {"--log", log, "--out", out},
                          "foxglove-sdk and lcm");
}

struct ExportArgs {
  std::string checkpoint, log, report, channel = "KINCAL_PARAMS", out, format = "yaml";
  std::string nominal, controller;
};

// The parameters from the checkpoint, the log or the report the command line names, and
// where they came from.
StatusOr<Checkpoint> ReadSource(const ExportArgs& a, std::string* source) {
  if (!a.checkpoint.empty()) {
    *source = a.checkpoint;
    return ReadCheckpoint(a.checkpoint);
  }
  if (!a.log.empty()) {
    *source = a.log + " (" + a.channel + ")";
    return FromLog(a.log, a.channel);
  }
  if (!a.report.empty()) {
    *source = a.report;
    return ReadReportAsCheckpoint(a.report);
  }
  return Status::Error("give --checkpoint FILE, --log FILE or --report FILE");
}

StatusOr<int> RunExport(const ExportArgs& a) {
  if (a.format == "mcap") return ExportMcap(a.log, a.out);
  std::string source;
  KINCAL_ASSIGN_OR_RETURN(const Checkpoint c, ReadSource(a, &source));
  std::ostringstream out;
  if (a.format == "ros2_control") {
    Ros2ControlOptions o;
    o.controller = a.controller;
    KINCAL_ASSIGN_OR_RETURN(o.nominal, ParseNominal(a.nominal));
    KINCAL_RETURN_IF_ERROR(WriteRos2ControlYaml(out, c, source, o));
  } else if (a.format == "vesc") {
    KINCAL_ASSIGN_OR_RETURN(const auto nominal, ParseNominal(a.nominal));
    KINCAL_RETURN_IF_ERROR(WriteVescYaml(out, c, source, nominal));
  } else {
    WriteExportYaml(out, c, source);
  }
  if (a.out.empty()) {
    std::cout << out.str();
  } else {
    KINCAL_RETURN_IF_ERROR(WriteOutput(a.out, out.str(), "export"));
    std::cout << "wrote " << a.out << "\n";
  }
  return 0;
}

}  // namespace

Command AddExport(CLI::App& app) {
  auto a = std::make_shared<ExportArgs>();
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
  return [a]() -> StatusOr<int> { return RunExport(*a); };
}

}  // namespace kincal::app
