// kincal reproduce thesis: the thesis's 99 experiments in simulation, DD2 / EKF / UKF /
// batch against the thesis's figures and the Bayesian Cramer-Rao bound, in the realistic
// world (the default) or the idealised one (--ideal).
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>

#include "commands.h"
#include "kincal/sim/thesis.h"
#include "options.h"

namespace kincal::app {
namespace {

// Options a user set on the command line, applied over the chosen world's preset.
// What the command line changes of the world's options (each unset unless given).
struct Overrides {
  bool ideal = false, no_batch = false;
  std::vector<std::string> filters;
  int runs = 99, trials = 1;
  std::optional<int> frames, runs_per_day;
  uint64_t seed = 1;
  std::optional<double> centroid, gain, step, stamp;
  ThesisOptions Resolve() const {
    ThesisOptions o = ideal ? ThesisOptions::Ideal() : ThesisOptions::Realistic();
    o.runs = runs;
    o.trials = trials;
    o.seed = seed;
    if (frames) o.frames_per_run = *frames;
    if (centroid) (ideal ? o.centroid_sigma_px : o.pixel.centroid_sigma_px) = *centroid;
    if (gain) o.wheel.gain_sigma = *gain;
    if (gain == 0.0) o.nuisance_gains = false;
    if (step) o.wheel.command_step_rad_s = *step;
    if (stamp) o.stamp_step_s = *stamp;
    if (runs_per_day) o.pixel.calibration.enabled = *runs_per_day > 0;
    if (runs_per_day > 0) o.pixel.calibration.runs_per_day = *runs_per_day;
    if (!filters.empty()) o.filters = filters;
    if (no_batch) o.batch = false;
    return o;
  }
};

void PrintJoint(const ThesisResult& r) {
  if (!r.poses_gated.empty()) {
    std::cout << "  poses refused at the filters' innovation gate (NIS > 25), all trials:";
    for (const auto& [name, n] : r.poses_gated) std::cout << " " << name << " " << n;
    std::cout << "\n";
  }
  std::cout << "  Joint calibration over all runs (NNDE %, RMS over trials; NEES: mean over "
               "trials, 3 when honest):\n";
  for (const auto& [name, v] : r.joint_nnde_percent) {
    const auto& e = r.joint_estimate.at(name);
    const auto& s = r.joint_sigma.at(name);
    std::cout << "    " << std::setw(11) << name << "  " << std::setw(9) << v << std::fixed
              << std::setprecision(4) << "   R_L " << e[0] * 1e3 << " +- " << s[0] * 1e3
              << " mm, R_R " << e[1] * 1e3 << " +- " << s[1] * 1e3 << " mm, D " << e[2] * 1e3
              << " +- " << s[2] * 1e3 << " mm" << std::defaultfloat << std::setprecision(3)
              << "   within 3 sigma " << 100.0 * r.joint_within_3sigma.at(name) << " %, NEES "
              << r.joint_nees.at(name) << "\n"
              << std::setprecision(4);
  }
  std::cout << "    " << std::setw(11) << "bound"
            << "  " << std::setw(9) << r.joint_bound_nnde_percent << "   (Bayesian Cramer-Rao)\n";
  if (r.joint_gains_bound_nnde_percent > 0.0) {
    std::cout << "    " << std::setw(11) << "bound+gains"
              << "  " << std::setw(9) << r.joint_gains_bound_nnde_percent
              << "   (with the band gains as nuisance parameters)\n";
  }
  std::cout << "  Mean-square NNDE over the bound's (95 % interval, " << r.trials
            << " trials; an efficient estimator's contains 1):\n";
  for (const auto& [name, v] : r.joint_nnde_percent) {
    if (name.find("+gains") != std::string::npos) continue;
    const BoundRatio b = RatioToBound(r, name);
    std::cout << "    " << std::setw(11) << name << "  " << std::setw(9) << b.ratio << "   ["
              << b.low << ", " << b.high << "]\n";
  }
  std::cout << "    " << std::setw(11) << "thesis"
            << "  " << std::setw(9) << r.thesis_nnde_percent
            << "   (consistent with the NNDE of the mean of Table 6-5)\n\n";
}

void PrintPerRun(const ThesisResult& r) {
  if (r.per_run_nnde_percent.empty()) return;
  std::cout << "  Per experiment (one filter per run), as Table 6-5 (%): mean NNDE, NNDE of "
               "the mean, scatter of speed and turn rate; RMS NNDE\n";
  auto row = [](const std::string& name, const TableStats& s, double rms) {
    std::cout << "    " << std::setw(11) << name << "  " << std::setw(9) << 100 * s.mean_nnde
              << std::setw(9) << 100 * s.nnde_of_mean << std::setw(9) << 100 * s.speed_scatter
              << std::setw(9) << 100 * s.turn_scatter << std::setw(9) << rms << "\n";
  };
  for (const auto& [name, v] : r.per_run_nnde_percent) row(name, r.per_run_stats.at(name), v);
  row("thesis", r.thesis_stats, NAN);
  std::cout << "    " << std::setw(11) << "bound" << std::setw(47) << r.per_run_bound_nnde_percent
            << "\n\n";
}

nlohmann::json ToJson(const ThesisOptions& o, const ThesisResult& r) {
  nlohmann::json j;
  j["world"] = o.pixels ? "realistic" : "ideal";
  j["nnde_percent"] = r.joint_nnde_percent;
  j["within_3sigma"] = r.joint_within_3sigma;
  j["nees"] = r.joint_nees;
  j["crlb_nnde_percent"] = r.joint_bound_nnde_percent;
  j["crlb_gains_nnde_percent"] = r.joint_gains_bound_nnde_percent;
  for (const auto& [name, v] : r.joint_nnde_percent) {
    const BoundRatio b = RatioToBound(r, name);
    j["ms_ratio_to_bound"][name] = {{"ratio", b.ratio}, {"low95", b.low}, {"high95", b.high}};
  }
  j["per_run_nnde_percent"] = r.per_run_nnde_percent;
  j["per_run_crlb_nnde_percent"] = r.per_run_bound_nnde_percent;
  auto stats = [](const TableStats& s) {
    return nlohmann::json{{"mean_nnde", s.mean_nnde},
                          {"nnde_of_mean", s.nnde_of_mean},
                          {"speed_scatter", s.speed_scatter},
                          {"turn_scatter", s.turn_scatter}};
  };
  for (const auto& [name, s] : r.per_run_stats) j["per_run_stats"][name] = stats(s);
  j["thesis_stats"] = stats(r.thesis_stats);
  j["thesis_nnde_percent"] = r.thesis_nnde_percent;
  j["thesis_per_run_nnde_percent"] = r.thesis_per_run_nnde_percent;
  j["runs"] = r.runs;
  j["trials"] = r.trials;
  j["seed"] = o.seed;
  j["frames_per_trial"] = r.frames;
  j["frames_lost"] = r.frames_lost;
  j["frames_gross"] = r.frames_gross;
  j["poses_gated"] = r.poses_gated;
  j["pose_sigma"] = {std::sqrt(r.pose_cov(0, 0)), std::sqrt(r.pose_cov(1, 1)),
                     std::sqrt(r.pose_cov(2, 2))};
  j["pose_rms_error"] = {r.pose_rms_error[0], r.pose_rms_error[1], r.pose_rms_error[2]};
  j["pose_nees"] = r.pose_nees;
  j["image_noise_grey"] = r.image_noise_grey;
  j["centroid_sigma_px"] = r.centroid_sigma_px;
  if (o.pixels) {
    j["camera_calibration"] = {
        {"runs_per_day", o.pixel.calibration.enabled ? o.pixel.calibration.runs_per_day : 0},
        {"days", r.camera_days},
        {"scale_rms", r.camera_scale_rms},
        {"bend_rms_m", r.camera_bend_rms_m},
        {"scale_sigma_rms", r.camera_scale_sigma_rms}};
  }
  for (const auto& [name, e] : r.joint_estimate) {
    const auto& s = r.joint_sigma.at(name);
    j["estimates"][name] = {{"r_l", {{"value", e[0]}, {"sigma", s[0]}}},
                            {"r_r", {{"value", e[1]}, {"sigma", s[1]}}},
                            {"d", {{"value", e[2]}, {"sigma", s[2]}}}};
  }
  for (const auto& [name, rows] : r.per_run_estimate) {
    const auto& sig = r.per_run_sigma.at(name);
    for (size_t k = 0; k < rows.size(); ++k) {
      j["per_run"][name].push_back({{"value", {rows[k][0], rows[k][1], rows[k][2]}},
                                    {"sigma", {sig[k][0], sig[k][1], sig[k][2]}}});
    }
  }
  for (int k = 0; k < r.runs; ++k) {
    j["thesis_table_6_5"].push_back({1e-3 * kThesisEstimates[k][0], 1e-3 * kThesisEstimates[k][1],
                                     1e-3 * kThesisEstimates[k][2]});
    j["controls"].push_back({kThesisControls[k][0], kThesisControls[k][1]});
  }
  j["truth"] = {{"r_l", r.truth[0]}, {"r_r", r.truth[1]}, {"d", r.truth[2]}};
  j["nominal"] = {{"r_l", kThesisRL}, {"r_r", kThesisRR}, {"d", kThesisD}};
  return j;
}

void PrintSetup(const ThesisOptions& o, const ThesisResult& r) {
  std::cout << std::setprecision(4);
  if (o.pixels) {
    std::cout << "  realistic world: poses through pixels (Table 6-3 camera), image noise "
              << r.image_noise_grey << " grey levels -> centres scatter " << r.centroid_sigma_px
              << " px; pose error RMS x " << r.pose_rms_error[0] * 1e3 << " mm, y "
              << r.pose_rms_error[1] * 1e3 << " mm, theta " << r.pose_rms_error[2] * 1e3
              << " mrad, pose NEES " << r.pose_nees << " (3 when honest), " << r.frames_lost
              << " frames lost, " << r.frames_gross
              << " gross errors (NEES > 100)\n  wheel gain sigma " << o.wheel.gain_sigma << " per "
              << o.wheel.band_width_rad_s << " rad/s band, command step "
              << o.wheel.command_step_rad_s << " rad/s, stamp tick " << o.stamp_step_s
              << " s; estimators start at the nominal robot\n";
    if (o.pixel.calibration.enabled) {
      std::cout << "  camera calibration error: calibrated anew every "
                << o.pixel.calibration.runs_per_day << " runs (" << r.camera_days
                << " days over the trials): the floor's scale off by " << 100.0 * r.camera_scale_rms
                << " % RMS (the calibrations' own sigma " << 100.0 * r.camera_scale_sigma_rms
                << " %), " << r.camera_bend_rms_m * 1e3 << " mm RMS of bend beside it\n";
    } else {
      std::cout << "  camera calibration error: none (poses solved with the true camera)\n";
    }
  } else {
    std::cout << "  idealised world: pose noise (1 sigma) x,y " << std::sqrt(r.pose_cov(0, 0)) * 1e3
              << " mm, theta " << std::sqrt(r.pose_cov(2, 2)) * 1e3 << " mrad ("
              << o.centroid_sigma_px << " px centroid noise)\n";
  }
  std::cout << "  " << r.frames << " pose measurements over " << r.duration_s
            << " s of driving per trial\n\n";
}

}  // namespace

Command AddReproduce(CLI::App& app) {
  struct Args {
    std::string what;
    Overrides ov;
    bool realistic = false;
    std::string json;
  };
  auto args = std::make_shared<Args>();
  app.add_option("experiment", args->what, "which experiment (only 'thesis')")
      ->required()
      ->check(CLI::IsMember({"thesis"}));
  auto* ideal = app.add_flag("--ideal", args->ov.ideal,
                             "the idealised world: Gaussian pose noise, exact controls and stamps");
  app.add_flag("--realistic", args->realistic,
               "the realistic world (the default): pixels, wheel-rate errors, timer stamps")
      ->excludes(ideal);
  app.add_option("--runs", args->ov.runs, "number of Table 6-4 experiments (1..99)")
      ->capture_default_str();
  app.add_option("--seed", args->ov.seed, "random seed")->capture_default_str();
  app.add_option("--trials", args->ov.trials, "Monte-Carlo repetitions (RMS over trials)")
      ->capture_default_str();
  app.add_option("--frames", args->ov.frames,
                 "frames per run (realistic: 128; ideal: 0 = one full turn)")
      ->check(AtLeastZero());
  app.add_option("--centroid-sigma", args->ov.centroid,
                 "marker centre noise per axis, px (realistic: 0.1414, the thesis's 0.02 px^2; "
                 "ideal: 0.02)")
      ->check(AboveZero());
  app.add_option("--wheel-gain-sigma", args->ov.gain,
                 "look-up-table gain error per wheel and speed band (fraction; 0: none)")
      ->check(AtLeastZero());
  app.add_option("--command-step", args->ov.step,
                 "wheel-rate command resolution, rad/s (thesis 7.3.2: 0.1; 0: exact)")
      ->check(AtLeastZero());
  app.add_option("--stamp-step", args->ov.stamp,
                 "frame timestamps on a timer of this tick, s (0: exact)")
      ->check(AtLeastZero());
  app.add_option("--runs-per-day", args->ov.runs_per_day,
                 "realistic: the camera and floor calibrated anew every N runs, the poses "
                 "solved with that day's calibration (default 10; 0: the true camera)")
      ->check(AtLeastZero());
  app.add_option("--filters", args->ov.filters, "filters to run (default dd2,ekf,ukf)")
      ->delimiter(',')
      ->check(CLI::IsMember({"dd2", "ekf", "ukf"}));
  app.add_flag("--no-batch", args->ov.no_batch, "skip the batch (Ceres) calibrations");
  app.add_option("--json", args->json, "write the results as JSON to this file");
  return [args]() -> StatusOr<int> {
    const ThesisOptions o = args->ov.Resolve();
    std::string error;
    if (!o.IsValid(&error)) {
      std::cerr << "kincal reproduce: " << error << "\n";
      return 2;
    }
    std::cout << "Reproducing McNamee (2003) ch. 6: " << o.runs << " experiments, " << o.trials
              << " trial(s), seed " << o.seed << "\n";
    const StatusOr<ThesisResult> reproduced = ReproduceThesis(o);
    if (!reproduced.ok()) {
      std::cerr << "kincal reproduce: " << reproduced.status().message() << "\n";
      return 1;
    }
    const ThesisResult& r = reproduced.value();
    PrintSetup(o, r);
    PrintJoint(r);
    PrintPerRun(r);
    const double dd2 = r.joint_nnde_percent.count("dd2") ? r.joint_nnde_percent.at("dd2") : NAN;
    std::cout << "  target: joint DD2 NNDE <= 0.1 %: " << (dd2 <= 0.1 ? "met" : "NOT met") << " ("
              << dd2 << " %)\n";
    if (!args->json.empty()) {
      KINCAL_RETURN_IF_ERROR(WriteOutput(args->json, ToJson(o, r).dump(2) + "\n", "results JSON"));
      std::cout << "  wrote " << args->json << "\n";
    }
    return 0;
  };
}

}  // namespace kincal::app
