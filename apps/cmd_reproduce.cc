// kincal reproduce thesis: the thesis's 99 experiments in simulation, DD2 / EKF / UKF /
// batch against the thesis's figures and the Bayesian Cramer-Rao bound.
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "kincal/thesis.h"

namespace kincal::app {

Command AddReproduce(CLI::App& app) {
  struct Args {
    std::string what;
    ThesisOptions opt;
    std::string json;
  };
  auto args = std::make_shared<Args>();
  app.add_option("experiment", args->what, "which experiment (only 'thesis')")
      ->required()
      ->check(CLI::IsMember({"thesis"}));
  app.add_option("--runs", args->opt.runs, "number of Table 6-4 experiments (1..99)")
      ->capture_default_str();
  app.add_option("--seed", args->opt.seed, "random seed")->capture_default_str();
  app.add_option("--trials", args->opt.trials, "Monte-Carlo repetitions (RMS over trials)")
      ->capture_default_str();
  app.add_option("--centroid-sigma", args->opt.centroid_sigma_px,
                 "marker centre noise, px (thesis: 0.02)")
      ->capture_default_str();
  app.add_option("--wheel-gain-sigma", args->opt.wheel.gain_sigma,
                 "look-up-table gain error per wheel and speed band (fraction; 0: none)")
      ->capture_default_str();
  app.add_option("--command-step", args->opt.wheel.command_step_rad_s,
                 "wheel-rate command resolution, rad/s (thesis 7.3.2: 0.1; 0: exact)")
      ->capture_default_str();
  app.add_option("--stamp-step", args->opt.stamp_step_s,
                 "frame timestamps on a timer of this tick, s (0: exact)")
      ->capture_default_str();
  app.add_option("--json", args->json, "write the results as JSON to this file");
  return [args]() -> int {
    const ThesisOptions& o = args->opt;
    std::cout << "Reproducing McNamee (2003) ch. 6: " << o.runs << " experiments, " << o.trials
              << " trial(s), seed " << o.seed << "\n";
    const ThesisResult r = ReproduceThesis(o);
    std::cout << std::setprecision(4);
    std::cout << "  pose noise (1 sigma): x,y " << std::sqrt(r.pose_cov(0, 0)) * 1e3
              << " mm, theta " << std::sqrt(r.pose_cov(2, 2)) * 1e3 << " mrad ("
              << o.centroid_sigma_px << " px centroid noise)\n";
    std::cout << "  " << r.frames << " pose measurements over " << r.duration_s
              << " s of driving per trial (each run: one turn, >= " << o.min_frames
              << " frames)\n\n";
    std::cout << "  Joint calibration over all runs (NNDE %, RMS over trials):\n";
    for (const auto& [name, v] : r.joint_nnde_percent) {
      const auto& e = r.joint_estimate.at(name);
      const auto& s = r.joint_sigma.at(name);
      std::cout << "    " << std::setw(6) << name << "  " << std::setw(10) << v << std::fixed
                << std::setprecision(5) << "   R_L " << e[0] * 1e3 << " +- " << s[0] * 1e3
                << " mm, R_R " << e[1] * 1e3 << " +- " << s[1] * 1e3 << " mm, D " << e[2] * 1e3
                << " +- " << s[2] * 1e3 << " mm\n"
                << std::defaultfloat << std::setprecision(4);
    }
    std::cout << "    " << std::setw(6) << "bound"
              << "  " << std::setw(10) << r.joint_bound_nnde_percent
              << "   (Bayesian Cramer-Rao)\n";
    std::cout << "  Mean-square NNDE over the bound's (95 % interval, " << r.trials
              << " trials; an efficient estimator's contains 1):\n";
    for (const auto& [name, v] : r.joint_nnde_percent) {
      const BoundRatio b = RatioToBound(r, name);
      std::cout << "    " << std::setw(6) << name << "  " << std::setw(10) << b.ratio << "   ["
                << b.low << ", " << b.high << "]\n";
    }
    std::cout << "    " << std::setw(6) << "thesis"
              << "  " << std::setw(10) << r.thesis_nnde_percent
              << "   (NNDE of the mean of Table 6-5)\n\n";
    if (!r.per_run_nnde_percent.empty()) {
      std::cout << "  Per experiment (one filter per run, prior-dependent; RMS NNDE %):\n";
      for (const auto& [name, v] : r.per_run_nnde_percent) {
        std::cout << "    " << std::setw(6) << name << "  " << std::setw(10) << v << "\n";
      }
      std::cout << "    " << std::setw(6) << "bound"
                << "  " << std::setw(10) << r.per_run_bound_nnde_percent << "\n";
      std::cout << "    " << std::setw(6) << "thesis"
                << "  " << std::setw(10) << r.thesis_per_run_nnde_percent
                << "   (mean over Table 6-5 rows)\n";
    }
    const double dd2 = r.joint_nnde_percent.count("dd2") ? r.joint_nnde_percent.at("dd2") : NAN;
    std::cout << "\n  target: joint DD2 NNDE <= 0.1 % and <= 1.2 x bound: "
              << ((dd2 <= 0.1 && dd2 <= 1.2 * r.joint_bound_nnde_percent) ? "met" : "NOT met")
              << " (ratio " << dd2 / r.joint_bound_nnde_percent << ")\n";
    if (!args->json.empty()) {
      nlohmann::json j;
      j["nnde_percent"] = r.joint_nnde_percent;
      j["crlb_nnde_percent"] = r.joint_bound_nnde_percent;
      for (const auto& [name, v] : r.joint_nnde_percent) {
        const BoundRatio b = RatioToBound(r, name);
        j["ms_ratio_to_bound"][name] = {{"ratio", b.ratio}, {"low95", b.low}, {"high95", b.high}};
      }
      j["per_run_nnde_percent"] = r.per_run_nnde_percent;
      j["per_run_crlb_nnde_percent"] = r.per_run_bound_nnde_percent;
      j["thesis_nnde_percent"] = r.thesis_nnde_percent;
      j["thesis_per_run_nnde_percent"] = r.thesis_per_run_nnde_percent;
      j["runs"] = r.runs;
      j["trials"] = r.trials;
      j["seed"] = o.seed;
      j["frames_per_trial"] = r.frames;
      j["pose_sigma"] = {std::sqrt(r.pose_cov(0, 0)), std::sqrt(r.pose_cov(1, 1)),
                         std::sqrt(r.pose_cov(2, 2))};
      for (const auto& [name, e] : r.joint_estimate) {
        const auto& s = r.joint_sigma.at(name);
        j["estimates"][name] = {{"r_l", {{"value", e[0]}, {"sigma", s[0]}}},
                                {"r_r", {{"value", e[1]}, {"sigma", s[1]}}},
                                {"d", {{"value", e[2]}, {"sigma", s[2]}}}};
      }
      j["truth"] = {{"r_l", kThesisRL}, {"r_r", kThesisRR}, {"d", kThesisD}};
      WriteOutput(args->json, j.dump(2) + "\n", "results JSON");
      std::cout << "  wrote " << args->json << "\n";
    }
    return 0;
  };
}

}  // namespace kincal::app
