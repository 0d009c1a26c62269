// Batch fits over the prediction windows, and the baseline: the bare model fitted by a
// staged multi-start (short windows from many starts, the best refined on full windows).
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "analysis/windows.h"
#include "kincal/analysis/analyze.h"
#include "kincal/control_signal.h"
#include "kincal/estimation/batch.h"
#include "kincal/system.h"

namespace kincal::analysis {

struct Fit {
  Eigen::VectorXd p;
  std::vector<int> fixed;  // parameters held at their start value
  Eigen::MatrixXd cov_robust, cov_model, info;
  double cost = 0.0;
  double n_eff = 0.0;  // effective number of independent residuals
  bool ok = false;
};

// One robust multiple-shooting fit from p0; ok = false when Ceres finds no finite solution.
// Held parameters (limits.fixed) stay at their value in p0.
Fit RunFit(const System& sys, const ControlSignal& u, const std::vector<PoseMeasurement>& meas,
           const Eigen::VectorXd& p0, const FitLimits& limits, bool covariance, int threads,
           int max_iterations = 60);
// Parameters [from, to) with their robust and model sigmas.
std::vector<ParamEstimate> Estimates(const System& sys, const Fit& f, int from, int to);
// Parameters the information matrix cannot pin down, one sentence each.
std::vector<std::string> Unobservable(const System& sys, const Fit& f);
// The model's defaults with the user's --init values; an error names an unknown name.
StatusOr<Eigen::VectorXd> InitialParams(const System& sys,
                                        const std::map<std::string, double>& init);
// The indices of the --fix parameters, their values set in *p0; an error names a name that
// is not one of the model's parameters, or says that every one of them is fixed.
StatusOr<std::vector<int>> FixParams(const System& sys, const std::map<std::string, double>& fixed,
                                     Eigen::VectorXd* p0);
// Weakly determined parameters of a fit (FitReport::weak).
std::vector<std::string> WeaklyDetermined(const System& sys, const Fit& f);
// The bare model's fit; *report says whether the optimum was unique. An error when no start
// converges.
StatusOr<Fit> FitBaseline(const System& sys, const Dataset& d, const Eigen::VectorXd& p0,
                          const AnalyzeOptions& o, FitReport* report);

}  // namespace kincal::analysis
