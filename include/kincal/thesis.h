// The thesis experiment (McNamee 2003, ch. 6) reproduced in simulation.
//
// Robot: differential drive, R_L = 31.0 mm, R_R = 31.3 mm, D = 148 mm. Camera: nadir,
// 1.5 m above the floor, 320 px wide with a 52 deg horizontal field of view (f = 328 px),
// frames at 6 Hz with capture stalls of up to 0.4 s. Target: four markers on an
// 80 x 120 mm plate; centroid noise 0.02 px, propagated to planar pose noise. Controls:
// the 99 constant wheel-rate vectors of Table 6-4. Each run lasts one full turn of the
// true robot, but at least 20 nominal frame periods (the fastest runs turn in 0.66 s).
// Estimators start from a guess with 5 % (1 sigma) error per parameter and a matching
// prior covariance, never from the truth.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "kincal/simulator.h"

namespace kincal {

// Table 6-4: (omega_L, omega_R) in rad/s for experiments 1..99.
extern const double kThesisControls[99][2];
// Table 6-5: (R_L, R_R, D) in mm estimated by the thesis for experiments 1..99.
extern const double kThesisEstimates[99][3];
// Thesis robot (m).
inline constexpr double kThesisRL = 0.0310, kThesisRR = 0.0313, kThesisD = 0.148;
// NNDE the thesis reports (section 7.2), percent. It equals the NNDE of the mean of the
// Table 6-5 estimates.
inline constexpr double kThesisNndePercent = 0.466;

// Systematic wheel-rate errors of the thesis's robot (all zero: the idealised world). Its
// wheels turn at the rate its look-up table (Fig. 6-6) gives for the integer command the
// requested rate maps to, not at the requested rate: the command is quantised (0.1 rad/s,
// §7.3.2), saturates, and each wheel's table is off by a gain error per speed band, fixed
// for a trial (the table was measured once). The estimators see the requested rates.
struct WheelRateErrors {
  double gain_sigma = 0.0;          // per wheel and speed band, N(0, sigma^2)
  double band_width_rad_s = 5.0;    // width of a look-up-table speed band
  double command_step_rad_s = 0.0;  // command resolution; 0: none
  double max_rad_s = 0.0;           // saturation; 0: none
  bool IsValid(std::string* error) const;
};

// The rate wheel `wheel` (0 left, 1 right) turns at for requested rate `w`; `gains[b][wheel]`
// is the gain error of speed band b (bands beyond the table's use its last band).
double RealisedWheelRate(double w, int wheel, const WheelRateErrors& e,
                         const std::vector<std::array<double, 2>>& gains);

struct ThesisOptions {
  int runs = 99;  // experiments 1..runs of Table 6-4
  uint64_t seed = 1;
  int trials = 1;  // Monte-Carlo repetitions (figures are RMS over trials)
  double guess_error = 0.05;
  double centroid_sigma_px = 0.02;
  double camera_height_m = 1.5;
  double image_width_px = 320.0;
  double hfov_rad = 52.0 * 3.14159265358979323846 / 180.0;
  FrameTimingOptions timing{6.0, 0.4, 0.25, 0.0};
  double min_frames = 20.0;
  WheelRateErrors wheel;
  double stamp_step_s = 0.0;  // frames stamped on a timer of this tick (floor); 0: exact
  std::vector<std::string> filters = {"dd2", "ekf", "ukf"};
  bool batch = true;
  bool per_run = true;
  bool IsValid(std::string* error) const;
};

struct ThesisResult {
  int runs = 0;
  int trials = 0;
  int frames = 0;            // pose measurements per trial
  double duration_s = 0.0;   // total driving time per trial
  Eigen::Matrix3d pose_cov;  // measurement covariance used
  // Joint calibration over all runs: RMS NNDE (%) over trials, by estimator.
  std::map<std::string, double> joint_nnde_percent;
  // Bayesian Cramer-Rao bound of the joint design, as an RMS NNDE (%).
  double joint_bound_nnde_percent = 0.0;
  // Per-experiment calibration (one filter per run): RMS NNDE (%) over runs and trials, as
  // the bound (a mean NNDE against an RMS bound reads below the bound when it is not).
  std::map<std::string, double> per_run_nnde_percent;
  double per_run_bound_nnde_percent = 0.0;
  // Thesis figures for comparison.
  double thesis_nnde_percent = kThesisNndePercent;
  double thesis_per_run_nnde_percent = 0.0;  // mean NNDE of Table 6-5 rows
  // Last trial's joint estimates (m) and 1-sigma, by estimator.
  std::map<std::string, Eigen::Vector3d> joint_estimate;
  std::map<std::string, Eigen::Vector3d> joint_sigma;
  // Fraction of parameter errors of the joint estimates inside 3 sigma, over trials.
  std::map<std::string, double> joint_within_3sigma;
  // Per trial: each estimator's joint NNDE and the bound's expected NNDE (fractions).
  std::map<std::string, std::vector<double>> joint_trial_nnde;
  std::vector<double> bound_trial_nnde;
};

// An estimator's mean-square NNDE over the trials divided by the bound's, with a 95 %
// confidence interval (the mean of the squared errors' standard error; the bound varies
// little between trials). An efficient estimator's interval contains 1.
struct BoundRatio {
  double ratio = 0.0, low = 0.0, high = 0.0;
  int trials = 0;
};
BoundRatio RatioToBound(const ThesisResult& r, const std::string& estimator);

// NNDE = || (a_est - a_true) / a_true || (thesis eq. 7.2), as a fraction.
double Nnde(const Eigen::VectorXd& est, const Eigen::VectorXd& truth);
// Expected (RMS) NNDE of an estimator with covariance C: sqrt(trace(W C W)), W = diag(1/a).
double ExpectedNnde(const Eigen::MatrixXd& C, const Eigen::VectorXd& truth);

ThesisResult ReproduceThesis(const ThesisOptions& options);

}  // namespace kincal
