// Ceres logs through glog. kincal routes it into its own logging (spdlog) once, before
// the first solve: nothing reaches stderr directly (no "Logging before
// InitGoogleLogging()", no rank-deficiency warnings in the middle of a run), and glog
// writes no log files. Ceres's warnings are expected where kincal uses it (a covariance
// of an unexcited parameter is rank deficient; kincal reports that itself), so they go
// to spdlog's debug level; its errors to warn. A host program that initialised glog
// itself keeps its own configuration.
#pragma once

namespace kincal {

void RouteCeresLogging();

}  // namespace kincal
