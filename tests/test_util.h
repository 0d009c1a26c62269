// Shared scenarios for the tests: a realistic truth and control range for every model.
#pragma once

#include <random>
#include <string>
#include <vector>

#include "kincal/estimation/batch.h"
#include "kincal/sim/simulator.h"
#include "kincal/system.h"

namespace kincal::testing {

struct ModelScenario {
  std::string model;
  std::vector<double> truth;   // model parameters
  std::vector<double> lo, hi;  // control range
};

inline std::vector<ModelScenario> AllModelScenarios() {
  return {
      {"diffdrive", {0.031, 0.0313, 0.148}, {-10.0, -10.0}, {25.0, 25.0}},
      {"unicycle", {0.9, 0.85}, {-0.3, -1.5}, {1.0, 1.5}},
      {"ackermann", {0.05, 0.3, 0.03}, {-5.0, -0.5}, {20.0, 0.5}},
      {"tricycle", {0.001, 0.02, 1e-4, 0.5}, {-400.0, -2000.0}, {400.0, 8000.0}},
      {"bicycle", {0.9, 0.6, 0.02, 0.33}, {-0.5, -0.5}, {2.5, 0.5}},
  };
}

struct SimData {
  ControlSignal controls;
  std::vector<TrajectoryPoint> truth;
  std::vector<PoseMeasurement> meas;
};

// Smooth random controls for `duration_s`, camera at `rate_hz`, pose noise sigma.
inline SimData Simulate(const System& truth_sys, const VecN<kMaxState>& params,
                        std::span<const double> lo, std::span<const double> hi, double duration_s,
                        double rate_hz, const Eigen::Vector3d& sigma, std::mt19937_64& rng) {
  SimData d{ControlSignal(truth_sys.num_controls(), 0), {}, {}};
  const TimeNs t1 = SecondsToNs(duration_s);
  AppendSmoothRandom(&d.controls, 0, t1, lo, hi, 2.0, 50.0, rng);
  FrameTimingOptions cam{rate_hz, 0.0, 0.0, 0.0};
  const auto times = FrameTimes(0, t1, cam, rng);
  const StateVec x0 = truth_sys.MakeState(0.1, -0.2, 0.3, params, d.controls, 0.0);
  d.truth = SimulateTruth(truth_sys, x0, d.controls, times);
  const Eigen::Matrix3d R = sigma.array().square().matrix().asDiagonal();
  d.meas = MeasurePoses(d.truth, R, 0, rng);
  return d;
}

inline VecN<kMaxState> ToVec(const std::vector<double>& v) {
  VecN<kMaxState> out(static_cast<int>(v.size()));
  for (size_t i = 0; i < v.size(); ++i) out[static_cast<int>(i)] = v[i];
  return out;
}

}  // namespace kincal::testing
