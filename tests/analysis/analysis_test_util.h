// A simulated recording for the analysis stages' unit tests: a unicycle (k_v 0.9,
// k_omega 0.8, optionally with hidden effects) under piecewise-constant commands, poses at
// 20 Hz with 1 mm / 3 mrad noise, all seeded.
#pragma once

#include <random>
#include <string>
#include <vector>

#include "kincal/io/recording.h"
#include "kincal/sim/scenario.h"
#include "kincal/sim/simulator.h"

namespace kincal::testing {

// The recording of `sys` at parameters p driven by `controls` for duration_s: poses at
// `pose_hz` with 1 mm / 3 mrad noise, starting at (0, 0, 0.3).
inline Recording Observe(const System& sys, const VecN<kMaxState>& p, ControlSignal controls,
                         double duration_s, double pose_hz, std::mt19937_64& rng) {
  Recording rec;
  rec.source = "simulated unicycle";
  rec.controls = std::move(controls);
  const TimeNs t1 = SecondsToNs(duration_s);
  const auto times = FrameTimes(0, t1, FrameTimingOptions{pose_hz, 0.0, 0.0, 0.0}, rng);
  const StateVec x0 = sys.MakeState(0.0, 0.0, 0.3, p, rec.controls, 0.0);
  const auto traj = SimulateTruth(sys, x0, rec.controls, times);
  const Eigen::Matrix3d R = Eigen::Vector3d(1e-6, 1e-6, 9e-6).asDiagonal();
  for (const auto& m : MeasurePoses(traj, R, 0, rng)) rec.poses.push_back({m.t_ns, m.z});
  return rec;
}

// kincal analyze on a unicycle with the effect selection on, one thread.
inline AnalyzeOptions AutoUnicycleOptions() {
  AnalyzeOptions o;
  o.model = "unicycle";
  o.effects_mode = "auto";
  o.num_threads = 1;
  return o;
}

inline Recording UnicycleRecording(double duration_s, const std::vector<std::string>& hidden,
                                   const std::map<std::string, double>& truth, uint64_t seed) {
  const System sys = MakeSystem("unicycle", hidden).value();
  std::map<std::string, double> values = {{"k_v", 0.9}, {"k_omega", 0.8}};
  values.insert(truth.begin(), truth.end());
  const VecN<kMaxState> p = ParamsFrom(sys, values, "truth").value();
  std::mt19937_64 rng(seed);
  ControlSignal u(2, 0);
  const std::array<double, 2> lo = {-0.2, -1.0}, hi = {0.8, 1.0};
  AppendPiecewiseRandom(&u, 0, SecondsToNs(duration_s), lo, hi, 0.7, 2.5, rng);
  return Observe(sys, p, std::move(u), duration_s, 20.0, rng);
}

// A clean unicycle (k_v 0.9, k_omega 0.8) under smooth random commands sampled at
// `control_hz`, poses at `pose_hz` with 1 mm / 3 mrad noise.
inline Recording UnicycleAtRates(double duration_s, double pose_hz, double control_hz,
                                 uint64_t seed) {
  const System sys = MakeSystem("unicycle").value();
  VecN<kMaxState> p(2);
  p << 0.9, 0.8;
  std::mt19937_64 rng(seed);
  ControlSignal u(2, 0);
  const std::array<double, 2> lo = {-0.2, -1.0}, hi = {0.8, 1.0};
  AppendSmoothRandom(&u, 0, SecondsToNs(duration_s), lo, hi, 2.0, control_hz, rng);
  return Observe(sys, p, std::move(u), duration_s, pose_hz, rng);
}

}  // namespace kincal::testing
