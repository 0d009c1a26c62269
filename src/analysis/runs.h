// The recording judged run by run: each run's 1-horizon prediction error, and open-loop
// dead reckoning over a run from its first pose (before and after the selection).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "analysis/evaluation.h"
#include "analysis/windows.h"
#include "kincal/analysis/analyze.h"
#include "kincal/system.h"

namespace kincal::analysis {

// Dead reckoning through poses [first, last] of the recording from the first one, effect
// states at rest at its time.
DeadReckoning DeadReckon(const System& sys, const Eigen::VectorXd& p, const Dataset& d, int first,
                         int last);

// Per run (d.by_runs), from the evaluations before and after and both models.
std::vector<RunReport> PerRun(const Dataset& d, const Evaluation& before, const Evaluation& after,
                              const System& before_sys, const Eigen::VectorXd& before_p,
                              const System& after_sys, const Eigen::VectorXd& after_p);

// Dead reckoning over the held-out part, pooled over the held-out runs (or the held-out
// span of one run).
DeadReckoning HeldOutDeadReckoning(const System& sys, const Eigen::VectorXd& p, const Dataset& d);

}  // namespace kincal::analysis
