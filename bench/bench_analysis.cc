// Accuracy and scaling of the offline estimators:
//  - the thesis experiment (ch. 6) in simulation: NNDE of SR-DD2, EKF, UKF and the batch
//    fit against the Bayesian Cramer-Rao bound, RMS over Monte-Carlo trials;
//  - Analyze() time against recording length (a differential-drive robot with a hidden
//    time offset, 20 Hz poses), with the window caps lifted so that every window counts;
//  - what users run: `kincal analyze` with its default options (automatic effect
//    selection, every core) on the five MR.CLAM robots of dataset 6 (read from ../shared
//    beside the source tree) and on simulated unicycle recordings of 1, 10 and 60 minutes
//    at 100 Hz with a hidden delay and speed loss in turns (the MR.CLAM pattern). Wall time.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>
#include <random>
#include <thread>

#include "kincal/analysis/analyze.h"
#include "kincal/io/recording.h"
#include "kincal/model.h"
#include "kincal/sim/simulator.h"
#include "kincal/sim/thesis.h"

namespace kincal {
namespace {

void BM_ThesisAccuracy(benchmark::State& state) {
  ThesisOptions o;
  o.trials = 32;
  o.seed = 2003;
  o.per_run = false;
  ThesisResult r;
  for (auto _ : state) {
    StatusOr<ThesisResult> run = ReproduceThesis(o);
    if (!run.ok()) {
      state.SkipWithError(run.status().message().c_str());
      return;
    }
    r = std::move(run).value();
  }
  state.counters["bound_pct"] = r.joint_bound_nnde_percent;
  for (const auto& [name, v] : r.joint_nnde_percent) {
    state.counters[name + "_pct"] = v;
    state.counters[name + "_over_bound"] = v / r.joint_bound_nnde_percent;
    state.counters[name + "_in_3sigma"] = r.joint_within_3sigma.at(name);
  }
  state.counters["thesis_pct"] = r.thesis_nnde_percent;
  state.counters["trials"] = o.trials;
}
BENCHMARK(BM_ThesisAccuracy)->Unit(benchmark::kSecond)->Iterations(1);

// `duration_s` of piecewise-constant random commands in [lo, hi] driving `model` with
// `effects` at `truth` (by name), poses at `pose_hz` with 1 mm / 3 mrad noise.
Recording SimulatedRecording(const std::string& model, const std::vector<std::string>& effects,
                             const std::map<std::string, double>& truth,
                             const std::vector<double>& lo, const std::vector<double>& hi,
                             double duration_s, double pose_hz, uint64_t seed) {
  const System sys = MakeSystem(model, effects).value();
  VecN<kMaxState> p(sys.num_params());
  p.setZero();
  for (const auto& [name, v] : truth) p[sys.ParamIndex(name)] = v;
  std::mt19937_64 rng(seed);
  Recording rec;
  rec.source = "simulated " + model;
  rec.controls = ControlSignal(sys.num_controls(), 0);
  const TimeNs t1 = SecondsToNs(duration_s);
  AppendPiecewiseRandom(&rec.controls, 0, t1, lo, hi, 0.7, 2.5, rng);
  const auto times = FrameTimes(0, t1, FrameTimingOptions{pose_hz, 0.0, 0.0, 0.0}, rng);
  const StateVec x0 = sys.MakeState(0.0, 0.0, 0.3, p, rec.controls, 0.0);
  const auto traj = SimulateTruth(sys, x0, rec.controls, times);
  const Eigen::Matrix3d R = Eigen::Vector3d(1e-6, 1e-6, 9e-6).asDiagonal();
  for (const auto& m : MeasurePoses(traj, R, 0, rng)) rec.poses.push_back({m.t_ns, m.z});
  return rec;
}

Recording DiffDriveRecording(double duration_s) {
  return SimulatedRecording("diffdrive", {"time_offset"},
                            {{"r_l", 0.031}, {"r_r", 0.0313}, {"d", 0.148}, {"delay_s", 0.05}},
                            {-10.0, -10.0}, {25.0, 25.0}, duration_s, 20.0, 5);
}

void BM_AnalyzeVsLength(benchmark::State& state) {
  const double seconds = static_cast<double>(state.range(0));
  const Recording rec = DiffDriveRecording(seconds);
  AnalyzeOptions o;
  o.model = "diffdrive";
  o.effects_mode = "list";
  o.effects = {"time_offset"};
  o.max_fit_windows = 1 << 30;
  o.max_eval_windows = 1 << 30;
  AnalyzeResult r;
  for (auto _ : state) r = Analyze(rec, o).value();
  state.counters["recording_s"] = seconds;
  state.counters["poses"] = static_cast<double>(rec.poses.size());
  state.counters["fit_windows"] = r.after.fit_windows;
  state.counters["heldout_mm_before"] = 1e3 * r.before.heldout.pos_rms_m;
  state.counters["heldout_mm_after"] = 1e3 * r.after.heldout.pos_rms_m;
}
BENCHMARK(BM_AnalyzeVsLength)
    ->Arg(30)
    ->Arg(60)
    ->Arg(120)
    ->Arg(240)
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

// The options `kincal analyze` runs with by default.
AnalyzeOptions UserDefaults(const std::string& model) {
  AnalyzeOptions o;
  o.model = model;
  o.num_threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return o;
}

void Report(benchmark::State& state, const AnalyzeResult& r) {
  std::string effects;
  for (const auto& e : r.after.effects) effects += (effects.empty() ? "" : "+") + e;
  state.SetLabel(effects.empty() ? "none" : effects);
  state.counters["effects"] = static_cast<double>(r.after.effects.size());
  state.counters["heldout_mm_before"] = 1e3 * r.before.heldout.pos_rms_m;
  state.counters["heldout_mm_after"] = 1e3 * r.after.heldout.pos_rms_m;
  state.counters["gain"] = 1.0 - r.after.heldout.pos_rms_m / r.before.heldout.pos_rms_m;
}

void BM_AnalyzeMrclam(benchmark::State& state) {
  const std::string dir = std::string(KINCAL_SOURCE_DIR) + "/../shared/data/mrclam/dataset6";
  if (!std::filesystem::is_directory(dir)) {
    state.SkipWithError(("no MR.CLAM data at " + dir).c_str());
    return;
  }
  const Recording rec = ReadMrclam(dir, static_cast<int>(state.range(0))).value();
  AnalyzeResult r;
  for (auto _ : state) r = Analyze(rec, UserDefaults("unicycle")).value();
  Report(state, r);
  state.counters["poses"] = static_cast<double>(rec.poses.size());
}
BENCHMARK(BM_AnalyzeMrclam)
    ->DenseRange(1, 5)
    ->Unit(benchmark::kSecond)
    ->Iterations(1)
    ->UseRealTime();

Recording UnicycleRecording(double duration_s) {
  return SimulatedRecording("unicycle", {"time_offset", "turn_slowdown"},
                            {{"k_v", 0.95}, {"k_omega", 0.9}, {"delay_s", 0.2}, {"c_slow", 0.5}},
                            {-0.3, -1.5}, {1.0, 1.5}, duration_s, 100.0, 7);
}

void BM_AnalyzeDefaultsVsLength(benchmark::State& state) {
  const double seconds = static_cast<double>(state.range(0));
  const Recording rec = UnicycleRecording(seconds);
  AnalyzeResult r;
  for (auto _ : state) r = Analyze(rec, UserDefaults("unicycle")).value();
  Report(state, r);
  state.counters["recording_s"] = seconds;
  state.counters["poses"] = static_cast<double>(rec.poses.size());
}
BENCHMARK(BM_AnalyzeDefaultsVsLength)
    ->Arg(60)
    ->Arg(600)
    ->Arg(3600)
    ->Unit(benchmark::kSecond)
    ->Iterations(1)
    ->UseRealTime();

}  // namespace
}  // namespace kincal
