// A parameter set judged on the windows: the prediction error of every evaluation window
// (fit and held-out RMS), and the residual tests (bias, whiteness).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "analysis/windows.h"
#include "kincal/analysis/analyze.h"
#include "kincal/system.h"

namespace kincal::analysis {

struct Evaluation {
  ErrorStats fit, held;
  std::vector<ResidualPoint> points;  // one per evaluation window
};

// Predicts every evaluation window over one horizon from its measured start pose.
Evaluation Evaluate(const System& sys, const Eigen::VectorXd& p, const Dataset& d);
// Held-out position RMS at the horizon of two predictors that ignore the commands: the
// robot standing still, and going on at the velocity of the previous horizon.
void NaiveHeldOut(const Dataset& d, double* standstill_m, double* constant_velocity_m);
// Position and heading error in one number, each in units of its pose noise.
double Combined(const ErrorStats& s, const Eigen::Vector2d& sigma);
// Bias, lag-1 autocorrelation and Ljung-Box whiteness on non-overlapping fit windows.
ResidualTests TestResiduals(const Evaluation& e, double horizon);

}  // namespace kincal::analysis
