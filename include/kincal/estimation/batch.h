// Batch maximum-likelihood calibration with Ceres, by multiple shooting.
//
// The recording is cut into segments (experiments, or pieces of a long run). Each
// segment has a free start pose at the time of its first measurement; the model is
// propagated open-loop through the control history from there, and every pose
// measurement contributes its whitened residual R^-1/2 (z - h(x(t))), heading wrapped.
// All segments share one parameter block (model + effect parameters). Effect states (a
// lag's realised controls) are warmed up: they start at steady state `warmup_s` before
// the segment and run through the command history up to its start, so that their value
// at the start is a function of the parameters and the history, not a free guess.
//
// An optional Gaussian prior on the parameters makes the problem Bayesian (needed when
// the design cannot identify every parameter, e.g. one constant-control experiment).
// The same machinery evaluated at the true parameters without solving gives the
// Cramer-Rao (or, with the prior, the Bayesian) bound of an experiment design.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "kincal/control_signal.h"
#include "kincal/status.h"
#include "kincal/system.h"
#include "kincal/time.h"

namespace kincal {

struct PoseMeasurement {
  TimeNs t_ns = 0;                                  // recording time base
  Eigen::Vector3d z = Eigen::Vector3d::Zero();      // measured target pose (m, m, rad)
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // its covariance
  int segment = 0;                                  // shooting segment id (non-decreasing)
};

struct ParamPrior {
  Eigen::VectorXd mean;        // over all System params
  Eigen::MatrixXd covariance;  // positive definite
};

struct BatchOptions {
  int max_iterations = 100;
  // Huber loss on whitened residuals with this scale (0: plain least squares).
  double huber_scale = 0.0;
  std::optional<ParamPrior> prior;
  bool compute_covariance = true;
  int num_threads = 1;
  // Also compute, from per-segment Jacobians with each segment's start pose profiled out,
  // the parameter information H, the model-based covariance H^-1 and the cluster-robust
  // (sandwich) covariance H^-1 (sum_s g_s g_s^T) H^-1 that treats segments as independent
  // blocks: honest when residuals within a segment are correlated (model error).
  bool profiled_covariance = false;
  // Effect-state warm-up before each segment start (s); 0 = steady state at the start.
  double warmup_s = 2.0;
  // Parameters (System indices) held at their value in params0: a measured dimension.
  // Their rows and columns of every covariance and of the information are zero.
  std::vector<int> fixed;
  // Starts of the recording's runs (increasing): a segment's warm-up never reaches back
  // into the run before its own (the robot was carried in between). Empty: one run.
  std::vector<TimeNs> run_starts;
  bool IsValid(const System& sys, std::string* error) const;
};

struct BatchResult {
  // Not ok when the inputs cannot be fitted (no measurements, times going backwards, a
  // covariance that is not positive definite, a guess of the wrong size); the rest is empty.
  Status status;
  Eigen::VectorXd params;      // estimate over all System params
  Eigen::MatrixXd covariance;  // their covariance (empty if not computed / singular)
  std::vector<Eigen::Vector3d> segment_start;  // reference pose at each segment start
  std::vector<TimeNs> segment_start_ns;
  // With profiled_covariance: information over the params (whitened units), H^-1, and
  // the cluster-robust covariance; empty when H is singular.
  Eigen::MatrixXd information;
  Eigen::MatrixXd profiled_covariance;
  Eigen::MatrixXd robust_covariance;
  int num_segments = 0;
  int num_residuals = 0;
  // Pooled lag-1 autocorrelation of each residual component along the measurements of a
  // segment, and the effective number of independent residuals it implies (AR(1) design
  // effect, at least one per segment).
  double residual_lag1 = 0.0;
  double effective_residuals = 0.0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int iterations = 0;
  bool converged = false;
  bool covariance_ok = false;
  std::string message;
};

// Fits the parameters. `params0` is the initial guess over all System params. Measurements
// must be sorted by time within each segment; bad inputs give a result whose status says
// what is wrong.
BatchResult FitBatch(const System& sys, const ControlSignal& controls,
                     std::span<const PoseMeasurement> meas, const Eigen::VectorXd& params0,
                     const BatchOptions& options);

// Covariance of the parameters implied by the design at the true parameters and true
// segment start poses (the Cramer-Rao bound; Bayesian if options.prior is set). Nothing is
// solved: only Jacobians are used, so measurement values are irrelevant.
BatchResult BoundAt(const System& sys, const ControlSignal& controls,
                    std::span<const PoseMeasurement> meas, const Eigen::VectorXd& params_true,
                    const std::vector<Eigen::Vector3d>& segment_start_true,
                    const BatchOptions& options);

}  // namespace kincal
