// What the robot was commanded to do in each evaluation window (the regressors of the
// diagnosis, kincal/signature.h), and the lag of the measured motion behind the commands.
#pragma once

#include <Eigen/Core>

#include "analysis/windows.h"
#include "kincal/system.h"

namespace kincal::analysis {

// Regressors per evaluation window (d->features), from the commanded body twist of the
// bare model at parameters p.
void ComputeFeatures(Dataset* d, const System& bare, const Eigen::VectorXd& p);
// Lag (s) by which the measured motion follows the commanded one (cross-correlation over
// lags in [-5, 5] s): the start for timing effects.
double EstimateCommandLag(const Dataset& d, const System& bare, const Eigen::VectorXd& p);

}  // namespace kincal::analysis
