// kincal simulate: drives a simulated robot (true parameters and optional hidden effects
// from a YAML scenario), measures its target pose like a camera would, and calibrates it
// online, printing the parameters converging with their 1-sigma. Writes the convergence
// history as CSV (t_s,name,value,sigma,truth) for scripts/plot_convergence.py.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include "commands.h"
#include "kincal/estimation/online_calibrator.h"
#include "kincal/sim/scenario.h"
#include "kincal/sim/simulator.h"

namespace kincal::app {

namespace {

struct SimulatedRun {
  ControlSignal cmd{1, 0};
  std::vector<PoseMeasurement> meas;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
};

// The scenario's commands, the true robot's motion and the camera's noisy poses of it.
StatusOr<SimulatedRun> SimulateScenario(const Scenario& sc, const System& truth_sys,
                                        const VecN<kMaxState>& p_true, const std::string& config) {
  SimulatedRun run;
  std::mt19937_64 rng(sc.seed);
  const TimeNs t1 = SecondsToNs(sc.duration_s);
  run.cmd = ControlSignal(truth_sys.num_controls(), 0);
  if (sc.profile == "smooth") {
    AppendSmoothRandom(&run.cmd, 0, t1, sc.control_low, sc.control_high, sc.min_period_s,
                       sc.control_rate_hz, rng);
  } else if (sc.profile == "piecewise") {
    AppendPiecewiseRandom(&run.cmd, 0, t1, sc.control_low, sc.control_high, sc.min_period_s,
                          3.0 * sc.min_period_s, rng);
  } else {
    return Status::Error(config + ": controls.profile must be smooth or piecewise");
  }
  const auto times = FrameTimes(0, t1, sc.camera, rng);
  const StateVec x0 = truth_sys.MakeState(0.0, 0.0, 0.0, p_true, run.cmd, 0.0);
  const auto traj = SimulateTruth(truth_sys, x0, run.cmd, times);
  run.R = sc.pose_sigma.array().square().matrix().asDiagonal();
  run.meas = MeasurePoses(traj, run.R, 0, rng);
  return run;
}

// DIR/controls.csv and DIR/poses.csv, the input of `kincal analyze`.
Status ExportRecording(const std::string& dir, const System& sys, const SimulatedRun& run) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return Status::Error(dir + ": cannot create the directory: " + ec.message());
  std::ostringstream c, p;
  c << "t";
  for (const auto& ch : sys.model().controls()) c << "," << ch.name;
  c << "\n" << std::setprecision(10);
  for (size_t i = 0; i < run.cmd.size(); ++i) {
    c << run.cmd.TimeAt(static_cast<int>(i));
    for (int k = 0; k < sys.num_controls(); ++k)
      c << "," << run.cmd.ValuesAt(static_cast<int>(i))[static_cast<size_t>(k)];
    c << "\n";
  }
  p << "t,x,y,theta\n" << std::setprecision(10);
  for (const auto& m : run.meas)
    p << NsToSeconds(m.t_ns) << "," << m.z.x() << "," << m.z.y() << "," << m.z.z() << "\n";
  KINCAL_RETURN_IF_ERROR(WriteOutput(dir + "/controls.csv", c.str(), "controls CSV"));
  KINCAL_RETURN_IF_ERROR(WriteOutput(dir + "/poses.csv", p.str(), "poses CSV"));
  std::cout << "wrote " << dir << "/controls.csv and poses.csv\n";
  return Status();
}

// The guess's covariance: each sigma a fraction of the guess (or of the default sigma).
StateMat GuessCovariance(const System& est_sys, const VecN<kMaxState>& p_guess, double fraction) {
  const int np = est_sys.num_params();
  StateMat P0 = StateMat::Zero(np, np);
  for (int i = 0; i < np; ++i) {
    const double s = fraction * std::max(std::abs(p_guess[i]),
                                         est_sys.params()[static_cast<size_t>(i)].default_sigma);
    P0(i, i) = s * s;
  }
  return P0;
}

void PrintHeader(const Scenario& sc, const System& est_sys, size_t poses) {
  std::cout << "Simulated " << sc.model << " (" << sc.profile << " controls, " << sc.duration_s
            << " s, " << poses << " poses at " << sc.camera.rate_hz << " Hz), filter " << sc.filter
            << ", seed " << sc.seed << "\n";
  if (!sc.hidden_effects.empty()) {
    std::cout << "hidden effects (not modelled by the estimator):";
    for (const auto& e : sc.hidden_effects) std::cout << " " << e;
    std::cout << "\n";
  }
  std::cout << std::setw(8) << "t [s]";
  for (const auto& p : est_sys.params())
    std::cout << std::setw(26) << (p.name + " [" + p.unit + "]");
  std::cout << "\n" << std::setprecision(5);
}

// One row of the table: the estimate +- 1 sigma at time t.
void PrintRow(const OnlineCalibrator& cal, double t) {
  const auto p = cal.params();
  const auto C = cal.params_covariance();
  std::cout << std::setw(8) << std::fixed << std::setprecision(1) << t << std::defaultfloat
            << std::setprecision(5);
  for (int i = 0; i < cal.system().num_params(); ++i) {
    std::ostringstream cell;
    cell << std::setprecision(5) << p[i] << " +- " << std::setprecision(2) << std::sqrt(C(i, i));
    std::cout << std::setw(26) << cell.str();
  }
  std::cout << "\n";
}

// The truth under the table, and how many parameters ended within 3 sigma of it.
void PrintTruth(const OnlineCalibrator& cal, const std::function<double(int)>& truth_of) {
  const int np = cal.system().num_params();
  std::cout << std::setw(8) << "truth";
  for (int i = 0; i < np; ++i) std::cout << std::setw(26) << truth_of(i);
  std::cout << "\n";
  int inside = 0;
  const auto p = cal.params();
  const auto C = cal.params_covariance();
  for (int i = 0; i < np; ++i) {
    if (std::abs(p[i] - truth_of(i)) <= 3.0 * std::sqrt(C(i, i))) ++inside;
  }
  std::cout << inside << "/" << np << " parameters within 3 sigma of the truth\n";
}

// The most frames (or control samples) one run keeps in memory: 9 hours at 30 Hz.
constexpr int kMaxSimulatedSamples = 1'000'000;

struct SimulateArgs {
  std::string config = "config/sim_diffdrive.yaml";
  std::string csv;
  double duration_s = 0.0;
  uint64_t seed = 0;
  std::string filter;
  std::string export_dir;
};

// The scenario the command line names, with its overrides.
StatusOr<Scenario> ScenarioFrom(const SimulateArgs& a) {
  KINCAL_ASSIGN_OR_RETURN(Scenario sc, LoadScenario(a.config));
  if (a.duration_s > 0.0) sc.duration_s = a.duration_s;
  if (a.seed != 0) sc.seed = a.seed;
  if (!a.filter.empty()) sc.filter = a.filter;
  return sc;
}

StatusOr<int> RunSimulate(const SimulateArgs& a) {
  KINCAL_ASSIGN_OR_RETURN(const Scenario sc, ScenarioFrom(a));
  KINCAL_ASSIGN_OR_RETURN(const System truth_sys, MakeSystem(sc.model, sc.hidden_effects));
  KINCAL_ASSIGN_OR_RETURN(const System est_sys, MakeSystem(sc.model, sc.estimator_effects));
  const int nc = truth_sys.num_controls();
  if (static_cast<int>(sc.control_low.size()) != nc ||
      static_cast<int>(sc.control_high.size()) != nc) {
    return Status::Error(a.config + ": controls.low/high need " + std::to_string(nc) +
                         " values for model " + sc.model);
  }
  KINCAL_ASSIGN_OR_RETURN(const VecN<kMaxState> p_true,
                          ParamsFrom(truth_sys, sc.truth, a.config + ": truth"));
  KINCAL_ASSIGN_OR_RETURN(const VecN<kMaxState> p_guess,
                          ParamsFrom(est_sys, sc.guess, a.config + ": guess"));
  OnlineCalibratorOptions opt;
  opt.filter = sc.filter;
  opt.noise.control_psd = sc.control_psd;
  if (std::string error; !opt.IsValid(est_sys, &error)) {
    return Status::Error((a.filter.empty() ? a.config : std::string("--filter")) + ": " + error);
  }
  if (sc.duration_s * std::max(sc.camera.rate_hz, sc.control_rate_hz) > kMaxSimulatedSamples) {
    return Status::Error(a.config + ": kincal simulate keeps the whole run in memory: at most " +
                         std::to_string(kMaxSimulatedSamples) +
                         " frames or control samples (duration_s x camera.rate_hz, "
                         "controls.rate_hz); kincald's simulated camera streams longer runs");
  }
  KINCAL_ASSIGN_OR_RETURN(const SimulatedRun run,
                          SimulateScenario(sc, truth_sys, p_true, a.config));
  const auto& meas = run.meas;
  if (meas.empty()) {
    std::ostringstream why;
    why << a.config << ": the simulated camera gave no pose in its " << sc.duration_s
        << " s (duration_s, camera.rate_hz, camera.dropout_prob)";
    return Status::Error(why.str());
  }
  if (!a.export_dir.empty()) KINCAL_RETURN_IF_ERROR(ExportRecording(a.export_dir, truth_sys, run));

  OnlineCalibrator cal(est_sys, opt, 0);
  cal.controls() = run.cmd;
  const int np = est_sys.num_params();
  cal.Initialize(meas.front().t_ns, meas.front().z, run.R, p_guess,
                 GuessCovariance(est_sys, p_guess, sc.guess_sigma_fraction));

  std::ostringstream csv;  // written whole at the end
  const bool want_csv = !a.csv.empty();
  if (want_csv) csv << "t_s,name,value,sigma,truth\n";
  auto truth_of = [&](int i) {
    const int j = truth_sys.ParamIndex(est_sys.params()[static_cast<size_t>(i)].name);
    return j < 0 ? NAN : p_true[j];
  };
  PrintHeader(sc, est_sys, meas.size());
  double next_report = 0.0;
  for (size_t k = 1; k < meas.size(); ++k) {
    cal.AddPose(meas[k].t_ns, meas[k].z, meas[k].R);
    const double t = NsToSeconds(meas[k].t_ns);
    if (want_csv) {
      const auto p = cal.params();
      const auto C = cal.params_covariance();
      for (int i = 0; i < np; ++i) {
        csv << t << "," << est_sys.params()[static_cast<size_t>(i)].name << "," << p[i] << ","
            << std::sqrt(C(i, i)) << "," << truth_of(i) << "\n";
      }
    }
    if (t >= next_report) {
      PrintRow(cal, t);
      next_report += sc.report_every_s;
    }
  }
  PrintRow(cal, NsToSeconds(meas.back().t_ns));
  PrintTruth(cal, truth_of);
  if (want_csv) KINCAL_RETURN_IF_ERROR(WriteOutput(a.csv, csv.str(), "convergence CSV"));
  return 0;
}

}  // namespace

Command AddSimulate(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  app.add_option("--config", args->config, "scenario YAML")->capture_default_str();
  app.add_option("--csv", args->csv, "write convergence history (t_s,name,value,sigma,truth)");
  app.add_option("--duration", args->duration_s, "override duration_s");
  app.add_option("--seed", args->seed, "override seed");
  app.add_option("--filter", args->filter, "override filter (dd2, ekf, ukf)");
  app.add_option("--export", args->export_dir,
                 "write the simulated recording as DIR/controls.csv and DIR/poses.csv "
                 "(input for `kincal analyze`)");
  return [args]() -> StatusOr<int> { return RunSimulate(*args); };
}

}  // namespace kincal::app
