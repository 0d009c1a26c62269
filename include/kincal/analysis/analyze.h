// Closing the loop: find what the kinematic model lacks in measured data.
//
// Analyze() fits the declared model to the first `fit_fraction` of a recording (batch
// maximum likelihood over non-overlapping prediction windows, staged and multi-start so
// that initial guesses off by a factor of five still reach the global optimum), measures
// the open-loop prediction residual over `horizon_s` from every measured pose on the fit
// part and on the held-out rest, diagnoses the residual (correlations with speed, turn
// rate, command changes..., whiteness, bias), then tries every candidate effect, keeps
// the one that improves the held-out error most and is supported by an information
// criterion, and repeats until nothing helps.
//
// Correlated residuals: the information criterion counts the effective number of
// independent residuals (windows never overlap; within a window the AR(1) design effect of
// the residuals shrinks the count, to one per window at worst), and every sigma is the
// cluster-robust (sandwich) covariance over windows, so neither is overconfident when
// prediction errors within a window are correlated.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "kincal/analysis/diagnosis.h"
#include "kincal/io/recording.h"
#include "kincal/status.h"

namespace kincal {

struct AnalyzeOptions {
  std::string model;
  std::map<std::string, double> init;  // initial guesses by parameter name
  // Model parameters held at a known value (--fix: a measured dimension), by name: not
  // fitted, zero sigma, listed in the report.
  std::map<std::string, double> fixed;
  std::string effects_mode = "auto";  // "auto", "none" or "list"
  std::vector<std::string> effects;   // candidate specs when effects_mode == "list"
  // Effects already in the model (the baseline is fitted with them; they are not
  // candidates). kincald's online search passes the effects it runs with.
  std::vector<std::string> base_effects;
  double fit_fraction = 0.7;  // first part of the time span used for fitting (one run)
  // A recording of several runs holds out whole runs: these (1-based), or every third run
  // (3, 6, ...; the second of two) when empty. fit_fraction does not apply then.
  std::vector<int> heldout_runs;
  double horizon_s = 1.0;  // open-loop prediction horizon
  // Pose noise (position m, heading rad) weighting the residuals; estimated from the
  // data (second differences) when not given.
  std::optional<Eigen::Vector2d> pose_sigma;
  int max_fit_windows = 250;    // non-overlapping windows used by the fits
  int max_eval_windows = 4000;  // windows (from measured poses) for the residual metrics
  int poses_per_window = 8;     // measurements used inside each fit window
  double min_gain = 0.02;       // held-out improvement needed to accept an effect
  int max_effects = 4;
  // Each round screens every candidate on every screen_stride-th fit window (1: all of
  // them), then confirms the confirm_candidates best screened on all windows (0: every
  // candidate); only confirmed candidates can be accepted.
  int screen_stride = 4;
  int confirm_candidates = 4;
  uint64_t seed = 1;
  int num_threads = 1;  // candidates fitted in parallel on this many threads
  std::function<void(double fraction, const std::string& stage)> progress;
  bool IsValid(std::string* error) const;
};

struct ParamEstimate {
  std::string name;
  std::string unit;
  double value = 0.0;
  double sigma = 0.0;        // cluster-robust 1-sigma
  double sigma_model = 0.0;  // model-based 1-sigma (white-residual assumption)
  bool held = false;         // held at a given value (--fix): sigma 0 by design
};

struct ErrorStats {
  double pos_rms_m = 0.0;
  double heading_rms_rad = 0.0;
  int windows = 0;
};

struct FitReport {
  std::vector<std::string> effects;  // effect specs in the model
  std::vector<ParamEstimate> params;
  // The parameters' cluster-robust covariance (params' order; empty when the fit gave
  // none): the sigmas above are its diagonal.
  Eigen::MatrixXd covariance;
  ErrorStats fit, heldout;
  double cost = 0.0;  // sum of squared whitened residuals over the fit windows
  int fit_windows = 0;
  bool unique = true;
  std::string uniqueness;                 // explanation when not unique
  std::vector<std::string> unobservable;  // messages
  std::vector<std::string> fixed;         // parameters held (--fix), "name=value"
  // Weakly determined parameters (sigma above half the value, or correlated above 0.98
  // with another): which trade off, and what would separate them. One sentence each.
  std::vector<std::string> weak;
};

struct ResidualTests {
  double bias_z[3] = {0, 0, 0};  // mean / standard error (along, cross, heading)
  double lag1_autocorr[3] = {0, 0, 0};
  double ljung_box_p[3] = {1, 1, 1};  // whiteness over 10 lags (non-overlapping windows)
};

struct EffectTrial {
  std::string name;  // effect spec
  int round = 0;
  bool accepted = false;
  std::vector<ParamEstimate> params;  // the effect's own parameters
  double heldout_gain = 0.0;          // 1 - heldout pos RMS with / without
  double combined_gain = 0.0;         // same for the noise-weighted position+heading error
  double delta_bic = 0.0;
  double signature_z = 0.0;  // strength of its residual signature before the round
  std::string evidence;
};

// Does the model explain the motion at all? Its held-out prediction error against two
// guesses that know nothing of the commands: standing still, and going on at the velocity
// of the previous horizon. A model no better than the better guess explains nothing (the
// controls do not drive it, or the data are not a robot's motion); then no estimate of it
// is unique.
struct GoodnessOfFit {
  double model_m = 0.0;              // held-out position RMS at the horizon, the final model
  double standstill_m = 0.0;         // ... predicting that the robot stays where it is
  double constant_velocity_m = 0.0;  // ... extrapolating the previous horizon's velocity
  bool judged = false;   // false: the motion is too small against the pose noise to judge
  bool explains = true;  // the model beats the better guess clearly
  std::string verdict;
};

// Open-loop dead reckoning from a run's first pose through all of it, against the poses:
// what odometry users judge by.
struct DeadReckoning {
  double duration_s = 0.0;
  double rms_m = 0.0;      // position error RMS over the run's poses
  double final_m = 0.0;    // position error at its last pose
  double final_rad = 0.0;  // |heading error| at its last pose
  int runs = 0;            // runs pooled (summaries)
};

// One run of a recording of several (AnalyzeResult::runs): the 1-horizon prediction error
// of its windows and its dead reckoning, before and after.
struct RunReport {
  int index = 0;  // 1-based
  std::string source;
  bool heldout = false;
  int windows = 0;
  double before_pos_rms_m = 0.0, after_pos_rms_m = 0.0;
  double before_heading_rms_rad = 0.0, after_heading_rms_rad = 0.0;
  DeadReckoning dr_before, dr_after;
};

struct AnalyzeResult {
  std::string model;
  std::string source;
  Eigen::Vector2d pose_sigma{0, 0};  // weights used (m, rad)
  bool pose_sigma_estimated = true;
  double t_begin_s = 0, t_split_s = 0, t_end_s = 0;
  double horizon_s = 1.0;
  FitReport before, after;
  GoodnessOfFit goodness;
  std::vector<EffectTrial> trials;
  std::vector<DiagnosisTerm> diagnosis_before, diagnosis_after;
  ResidualTests tests_before, tests_after;
  // Residual series per selection step: "before", then "+<effect>" for each accepted one.
  std::vector<std::pair<std::string, std::vector<ResidualPoint>>> residual_steps;
  std::vector<std::string> warnings;
  RecordingStats stats;
  // Per run (a recording of two or more runs; empty otherwise), and dead reckoning over
  // the held-out part (each held-out run from its first pose, pooled; for one run, the
  // held-out span), before and after.
  std::vector<RunReport> runs;
  DeadReckoning heldout_dr_before, heldout_dr_after;
};

// An error names the recording, option or parameter at fault (too short, unknown names,
// a parameter the data cannot determine).
StatusOr<AnalyzeResult> Analyze(const Recording& rec, const AnalyzeOptions& options);

// Writes DIR/residuals.csv, DIR/report.html (which shows the PNGs that
// scripts/plot_analysis.py draws from those files) and last DIR/report.json, each whole or
// not at all (kincal/io/output_file.h). An error names the file and errno's text.
Status WriteAnalysisReport(const AnalyzeResult& r, const std::string& dir);

// The final estimate of a report.json WriteAnalysisReport wrote: model, accepted effects,
// parameters with units and sigma (a diagonal covariance: the report keeps no more).
struct ReportEstimate {
  std::string model, source;
  std::vector<std::string> effects, names, units;
  std::vector<double> values, sigmas;
};
// An error names the file and the field that is missing or not what was expected.
Status ReadReportEstimate(const std::string& path, ReportEstimate* out);

}  // namespace kincal
