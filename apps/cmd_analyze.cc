// kincal analyze: calibrate the declared model on measured data, find the effects it
// lacks, add them, and report the error before and after.
#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <iostream>
#include <thread>

#include "commands.h"
#include "kincal/analysis/analyze.h"
#include "kincal/analysis/option_lists.h"
#include "options.h"

namespace kincal::app {
namespace {

// "pos_m,heading_rad": two finite numbers > 0.
StatusOr<Eigen::Vector2d> ParsePoseSigma(const std::string& text) {
  Eigen::Vector2d v(0, 0);
  const size_t comma = text.find(',');
  for (int i = 0; i < 2 && comma != std::string::npos; ++i) {
    const char* begin = text.data() + (i == 0 ? 0 : comma + 1);
    const char* end = text.data() + (i == 0 ? comma : text.size());
    const auto [stop, ec] = std::from_chars(begin, end, v[i]);
    if (ec != std::errc() || stop != end || !std::isfinite(v[i])) v[i] = 0;
  }
  if (!(v[0] > 0) || !(v[1] > 0)) {
    return Status::Error("--pose-sigma '" + text +
                         "': expected 'pos_m,heading_rad', two numbers > 0");
  }
  return v;
}

// Finds scripts/plot_analysis.py: $KINCAL_SCRIPTS, the source tree, or the install tree.
std::string PlotScript() {
  if (const char* env = std::getenv("KINCAL_SCRIPTS"))
    return std::string(env) + "/plot_analysis.py";
  for (const std::string& dir : {std::string(KINCAL_SOURCE_DIR) + "/scripts",
                                 std::string(KINCAL_INSTALL_DATADIR) + "/scripts"}) {
    if (std::filesystem::exists(dir + "/plot_analysis.py")) return dir + "/plot_analysis.py";
  }
  return {};
}

std::string Python() {
  const std::string venv = std::string(KINCAL_SOURCE_DIR) + "/.venv/bin/python";
  return std::filesystem::exists(venv) ? venv : "python3";
}

struct AnalyzeArgs {
  std::string model, mrclam, out, init, fix, heldout_runs, effects = "auto", pose_sigma;
  std::string controls_kind = "rate";  // or "position": encoder counts or angles
  double counts_per_rev = 0.0;
  std::vector<std::string> controls, poses, log;  // repeated: one run (or more) each
  int robot = 0;
  RecordingLimits limits;
  AnalyzeOptions opt;
};

// The options the command line asks for (an error names the option at fault).
StatusOr<AnalyzeOptions> OptionsFrom(AnalyzeArgs* a) {
  AnalyzeOptions o = a->opt;
  if (!a->mrclam.empty()) {
    if (a->model.empty()) a->model = "unicycle";
    if (a->robot < 1) return Status::Error("--mrclam needs --robot N (1..5 in dataset 6)");
  }
  if (a->model.empty()) return Status::Error("--model is required (see `kincal models`)");
  o.model = a->model;
  KINCAL_RETURN_IF_ERROR(ParseInitList(a->init, &o.init));
  KINCAL_RETURN_IF_ERROR(ParseInitList(a->fix, &o.fixed, "--fix"));
  KINCAL_RETURN_IF_ERROR(ParseRunList(a->heldout_runs, &o.heldout_runs));
  if (a->effects == "auto" || a->effects == "none") {
    o.effects_mode = a->effects;
  } else {
    o.effects_mode = "list";
    KINCAL_RETURN_IF_ERROR(ParseEffectList(a->effects, &o.effects));
  }
  if (!a->pose_sigma.empty()) {
    KINCAL_ASSIGN_OR_RETURN(o.pose_sigma, ParsePoseSigma(a->pose_sigma));
  }
  return o;
}

// The recording from the inputs the command line names: one kind of input, each
// repeated --log (or --controls/--poses pair) one run or more, joined in the order given.
StatusOr<Recording> ReadInput(const AnalyzeArgs& a, const AnalyzeOptions& o) {
  auto made = MakeModel(o.model);
  if (!made.ok()) return made.status();
  const auto model = std::move(made).value();
  const int sources =
      !a.mrclam.empty() + !a.log.empty() + (!a.controls.empty() || !a.poses.empty());
  if (sources != 1) return Status::Error("give exactly one of --controls/--poses, --log, --mrclam");
  if (!a.mrclam.empty() && o.model != "unicycle")
    return Status::Error("MR.CLAM logs velocity commands: use --model unicycle");
  if (a.controls.size() != a.poses.size()) {
    return Status::Error(
        "--controls and --poses go together: " + std::to_string(a.controls.size()) +
        " --controls, " + std::to_string(a.poses.size()) + " --poses");
  }
  std::vector<StatusOr<Recording>> read;
  if (!a.mrclam.empty()) read.push_back(ReadMrclam(a.mrclam, a.robot, a.limits));
  for (const auto& log : a.log) read.push_back(ReadLcmLog(log, *model, a.limits));
  for (size_t k = 0; k < a.controls.size(); ++k) {
    read.push_back(ReadCsvRecording(a.controls[k], a.poses[k], *model,
                                    a.controls_kind == "position", a.limits));
  }
  std::vector<Recording> parts;
  for (auto& r : read) {
    if (!r.ok()) return r.status();
    parts.push_back(std::move(r).value());
  }
  StatusOr<Recording> rec = JoinRuns(std::move(parts));
  if (!rec.ok()) return rec;
  if (a.controls_kind == "position") {
    if (const Status s = PositionsToRates(a.counts_per_rev, &rec.value()); !s.ok()) return s;
  }
  std::cerr << "read " << rec->source << ": " << rec->stats.control_rows << " control rows ("
            << rec->stats.control_repeated_times << " repeated times), " << rec->stats.pose_rows
            << " pose rows (" << rec->stats.pose_repeated_times << " repeated times"
            << (rec->stats.pose_rows_lost > 0
                    ? ", " + std::to_string(rec->stats.pose_rows_lost) + " without a pose, skipped"
                    : std::string())
            << ")\n";
  return rec;
}

// A bar on a terminal, a line per stage otherwise.
std::function<void(double, const std::string&)> Progress() {
  const bool tty = isatty(STDERR_FILENO);
  return [tty](double f, const std::string& stage) {
    const int width = 30;
    const int filled = static_cast<int>(f * width);
    if (tty) {
      std::cerr << "\r[" << std::string(static_cast<size_t>(filled), '#')
                << std::string(static_cast<size_t>(width - filled), ' ') << "] " << std::setw(3)
                << static_cast<int>(f * 100) << "% " << std::left << std::setw(40)
                << stage.substr(0, 40) << std::right << std::flush;
      if (f >= 1.0) std::cerr << "\n";
    } else {
      static std::string last;
      if (stage.substr(0, 8) != last.substr(0, 8))
        std::cerr << "[" << static_cast<int>(f * 100) << "%] " << stage << "\n";
      last = stage;
    }
  };
}

// Plots from the report's data (matplotlib); the report stands without them.
void Plot(const std::string& out) {
  const std::string script = PlotScript();
  if (!script.empty()) {
    const std::string cmd = Python() + " " + script + " " + out + " >/dev/null";
    if (std::system(cmd.c_str()) != 0) std::cerr << "warning: plotting failed (" << cmd << ")\n";
  } else {
    std::cerr << "warning: scripts/plot_analysis.py not found: no PNG plots\n";
  }
}

// The terminal's summary: errors before and after, the final parameters, the effects.
void PrintSummary(const AnalyzeResult& r, const std::string& out) {
  std::cout << std::setprecision(4);
  std::cout << "\nmodel " << r.model << ", residual weights " << r.pose_sigma[0] << " m / "
            << r.pose_sigma[1] << " rad" << (r.pose_sigma_estimated ? " (estimated)" : "") << "\n";
  std::cout << std::left << std::setw(28) << "" << std::setw(16) << "before"
            << "after\n";
  auto row = [](const std::string& n, double b, double af) {
    std::cout << std::left << std::setw(28) << n << std::setw(16) << b << af << "\n";
  };
  row("fit position RMS [m]", r.before.fit.pos_rms_m, r.after.fit.pos_rms_m);
  row("fit heading RMS [rad]", r.before.fit.heading_rms_rad, r.after.fit.heading_rms_rad);
  row("held-out position RMS [m]", r.before.heldout.pos_rms_m, r.after.heldout.pos_rms_m);
  row("held-out heading RMS [rad]", r.before.heldout.heading_rms_rad,
      r.after.heldout.heading_rms_rad);
  row("dead reckoning RMS [m]", r.heldout_dr_before.rms_m, r.heldout_dr_after.rms_m);
  row("dead reckoning final [m]", r.heldout_dr_before.final_m, r.heldout_dr_after.final_m);
  if (!r.runs.empty()) {
    std::cout << std::right << "runs (position RMS at the horizon, dead reckoning final, m):\n";
    for (const auto& x : r.runs) {
      std::cout << "  run " << std::setw(3) << x.index << (x.heldout ? " held out " : " fit      ")
                << std::setw(12) << x.before_pos_rms_m << " -> " << std::setw(12)
                << x.after_pos_rms_m << "   " << std::setw(10) << x.dr_before.final_m << " -> "
                << x.dr_after.final_m << "\n";
    }
  }
  std::cout << std::right << "parameters after:\n";
  for (const auto& p : r.after.params) {
    std::cout << "  " << std::left << std::setw(14) << p.name << std::right << std::setw(12)
              << p.value << " +- " << std::setw(10) << p.sigma << " " << p.unit << "\n";
  }
  if (!r.after.fixed.empty()) {
    std::cout << "held (--fix):";
    for (const auto& f : r.after.fixed) std::cout << " " << f;
    std::cout << "\n";
  }
  for (const auto& w : r.after.weak) std::cout << "note: " << w << "\n";
  std::cout << "effects accepted:";
  for (const auto& e : r.after.effects) std::cout << " " << e;
  if (r.after.effects.empty()) std::cout << " none";
  std::cout << "\n";
  if (!r.before.unique)
    std::cout << "warning: the baseline optimum is not unique: " << r.before.uniqueness << "\n";
  for (const auto& w : r.warnings) std::cout << "warning: " << w << "\n";
  std::cout << "goodness of fit: " << r.goodness.verdict << "\n";
  if (r.goodness.judged && !r.goodness.explains) {
    std::cerr << "kincal analyze: " << r.goodness.verdict << "\n";
  }
  std::cout << "wrote " << out << "/report.json, report.html, residuals.csv\n";
}

}  // namespace

Command AddAnalyze(CLI::App& app) {
  auto a = std::make_shared<AnalyzeArgs>();
  app.add_option("--model", a->model, "kinematic model (see `kincal models`)");
  app.add_option("--controls", a->controls,
                 "controls CSV: t,<control names>[,run]; repeated with --poses: one run each");
  app.add_option("--poses", a->poses, "poses CSV: t,x,y,theta[,run]");
  app.add_option("--log", a->log,
                 "a kincald recording or `kincal import` log (LCM) instead of CSV files; "
                 "repeated: one run (or more) each");
  app.add_option("--controls-kind", a->controls_kind,
                 "rate (the model's controls) or position (wheel encoders: cumulative counts "
                 "with --counts-per-rev, or angles in rad), differenced into rates")
      ->check(CLI::IsMember({"rate", "position"}))
      ->capture_default_str();
  app.add_option("--counts-per-rev", a->counts_per_rev,
                 "with --controls-kind position: encoder counts per wheel revolution (0: rad)")
      ->check(AtLeastZero());
  app.add_option("--heldout-runs", a->heldout_runs,
                 "runs held out (1-based, e.g. 3,6,9; default: every third run)");
  app.add_option("--max-rows", a->limits.max_rows,
                 "the most lines read from one file (or samples on one channel of a log): a "
                 "recording is held in memory whole, and this bounds it")
      ->check(AtLeastOne())
      ->capture_default_str();
  app.add_option("--mrclam", a->mrclam, "a UTIAS MR.CLAM dataset directory (model unicycle)");
  app.add_option("--robot", a->robot, "MR.CLAM robot number");
  app.add_option("--out", a->out, "output directory")->required();
  app.add_option("--init", a->init, "initial guesses, name=value,...");
  app.add_option("--fix", a->fix,
                 "model parameters held at known values (not fitted), name=value,...");
  app.add_option("--effects", a->effects, "auto | none | effect,effect[channel],...")
      ->capture_default_str();
  app.add_option("--fit-fraction", a->opt.fit_fraction, "fraction of the span used for fitting")
      ->capture_default_str();
  app.add_option("--horizon", a->opt.horizon_s, "open-loop prediction horizon, s")
      ->capture_default_str();
  app.add_option("--pose-sigma", a->pose_sigma,
                 "pose noise 'pos_m,heading_rad' (default: estimated)");
  app.add_option("--max-effects", a->opt.max_effects, "at most this many effects")
      ->capture_default_str();
  a->opt.num_threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  app.add_option("--threads", a->opt.num_threads,
                 "threads: candidate effects are fitted in parallel (default: every core; the "
                 "result does not depend on it)")
      ->capture_default_str();
  return [a]() -> StatusOr<int> {
    KINCAL_ASSIGN_OR_RETURN(AnalyzeOptions o, OptionsFrom(a.get()));
    KINCAL_RETURN_IF_ERROR(CheckOutputFolder(a->out, "report"));
    KINCAL_ASSIGN_OR_RETURN(const Recording rec, ReadInput(*a, o));
    o.progress = Progress();
    KINCAL_ASSIGN_OR_RETURN(const AnalyzeResult r, Analyze(rec, o));
    if (const Status written = WriteAnalysisReport(r, a->out); !written.ok()) {
      std::cerr << "kincal analyze: the report was not written: " << written.message() << "\n";
      return 1;
    }
    Plot(a->out);
    PrintSummary(r, a->out);
    return 0;
  };
}

}  // namespace kincal::app
