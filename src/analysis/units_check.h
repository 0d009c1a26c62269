// Fitted parameters that say the inputs' units are not kincal's: a wheel radius of 31 m is
// a recording whose poses are in millimetres, a realised-over-commanded speed of 1000 one
// whose poses and commands disagree on units. Fits are what the data say; these say what
// the data probably mean.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "kincal/model.h"

namespace kincal::analysis {

// A length (unit "m") this many times its generic value, or this many times smaller.
inline constexpr double kImplausibleLengthRatio = 50.0;
// A dimensionless scale (unit "1": realised over commanded) this many times 1, or smaller.
inline constexpr double kImplausibleScaleRatio = 10.0;

// One warning per model parameter of `p` (the model's own parameters first, as in a
// System) beyond those ratios of its generic value, naming the likely unit mistake.
std::vector<std::string> UnitWarnings(const KinematicModel& model, const Eigen::VectorXd& p);

}  // namespace kincal::analysis
