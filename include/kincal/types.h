// Fixed capacities and Eigen aliases shared by the estimation core.
//
// Every vector and matrix on the per-step path is a dynamic-size Eigen type with a
// compile-time maximum, so it lives on the stack: no heap allocation per filter step,
// yet models with different state sizes share one implementation.
#pragma once

#include <ceres/jet.h>

#include <Eigen/Dense>
#include <limits>
#include <string>
#include <string_view>

namespace kincal {

// Augmented state: pose (3) + model parameters + effect parameters + effect states.
// A planar pose (x, y, theta): the reference pose in every state, and every measurement.
inline constexpr int kPoseDim = 3;
inline constexpr int kMaxState = 24;
// Control channels of any model.
inline constexpr int kMaxControls = 4;
// Effect states (e.g. a lag's realised controls) of all effects together.
inline constexpr int kMaxEffectStates = 6;
// Process-noise inputs: one per control channel, 3 additive pose terms, one per effect
// state.
inline constexpr int kMaxNoise = kMaxControls + kPoseDim + kMaxEffectStates;
// Measurement dimension (a planar pose is 3).
inline constexpr int kMaxMeas = 6;
// Derivative slots of the autodiff scalar: enough for state + noise, or for one batch
// segment's start pose + all parameters.
inline constexpr int kJetSize = kMaxState + kMaxNoise + 1;

using Jet = ceres::Jet<double, kJetSize>;
// A smaller autodiff scalar for batch fits: a segment's start pose (3) + up to 9
// parameters. Larger problems fall back to Jet.
inline constexpr int kBatchJetSize = 12;
using BJet = ceres::Jet<double, kBatchJetSize>;

template <int MaxRows>
using VecN = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, MaxRows, 1>;
template <int MaxRows, int MaxCols>
using MatN = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, MaxRows, MaxCols>;

using StateVec = VecN<kMaxState>;
using StateMat = MatN<kMaxState, kMaxState>;
using NoiseVec = VecN<kMaxNoise>;
using NoiseMat = MatN<kMaxNoise, kMaxNoise>;
using MeasVec = VecN<kMaxMeas>;
using MeasMat = MatN<kMaxMeas, kMaxMeas>;
using StateNoiseMat = MatN<kMaxState, kMaxNoise>;
using MeasStateMat = MatN<kMaxMeas, kMaxState>;
using StateMeasMat = MatN<kMaxState, kMaxMeas>;

// Describes one scalar parameter of a model or effect.
struct ParamInfo {
  std::string name;             // interface name: CSV, LCM, --init
  std::string unit;             // SI unit, e.g. "m", "rad", "s", "1"
  double default_value;         // generic initial guess for an unknown robot
  double default_sigma;         // 1-sigma of that guess, same unit
  std::string excitation = {};  // what motion identifies it (for "unobservable" messages)
  // Physical lower bound (e.g. a length > 0), enforced by the batch fits; -inf if none.
  double min_value = -std::numeric_limits<double>::infinity();
};

// Describes one control channel.
struct ControlInfo {
  std::string name;  // interface name
  std::string unit;  // e.g. "rad/s", "m/s", "rad", "tick", "tick/s"
};

// The largest magnitude a control in `unit` can have on a ground robot; beyond it a value
// read from a file or a message is a unit mistake or garbage, refused by its reader. Wide
// on purpose (10^4 rad/s is 95,000 rpm): it stops overflow, not unusual robots.
inline double PlausibleControlLimit(std::string_view unit) {
  if (unit == "rad/s") return 1e4;
  if (unit == "m/s" || unit == "rad") return 1e3;
  return 1e12;  // counts: ticks, ticks/s
}

// Scalar part of double or Jet, for branching and indexing.
inline double ScalarOf(double v) { return v; }
template <typename T, int N>
double ScalarOf(const ceres::Jet<T, N>& v) {
  return v.a;
}

}  // namespace kincal
