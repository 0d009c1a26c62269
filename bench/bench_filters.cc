// Filter step time per model: one predict (through the control history, exact arcs) plus
// one pose update on the augmented state, for SR-DD2, EKF and UKF. Also the bare
// propagation, which the DD2 evaluates 2n+1 (+2 per active noise input) times per step.
#include <benchmark/benchmark.h>

#include <random>

#include "kincal/estimation/online_calibrator.h"
#include "kincal/model.h"
#include "kincal/sim/simulator.h"

namespace kincal {
namespace {

struct Fixture {
  explicit Fixture(const std::string& model)
      : sys(MakeSystem(model).value()), controls(sys.num_controls(), 0) {
    std::mt19937_64 rng(1);
    std::vector<double> lo(static_cast<size_t>(sys.num_controls()), -1.0);
    std::vector<double> hi(static_cast<size_t>(sys.num_controls()), 1.0);
    AppendSmoothRandom(&controls, 0, SecondsToNs(10.0), lo, hi, 1.0, 50.0, rng);
    x = sys.DefaultState(0.0, 0.0, 0.0);
  }
  System sys;
  ControlSignal controls;
  StateVec x;
};

void BM_FilterStep(benchmark::State& state, std::string model, std::string filter) {
  Fixture fx(model);
  auto f = MakeFilter(filter).value();
  const int n = fx.sys.state_dim();
  StateMat P = StateMat::Identity(n, n) * 1e-4;
  f->Initialize(fx.x, P, 1u << 2);
  // One 30 Hz frame interval with a control change inside it (50 Hz controls).
  const SystemProcess proc(fx.sys, fx.controls, 1.00, 1.0 + 1.0 / 30.0);
  ProcessNoiseOptions noise;
  noise.control_psd.assign(static_cast<size_t>(fx.sys.num_controls()), 1e-4);
  const NoiseMat Sv = ProcessNoiseSqrt(fx.sys, noise, 1.0 / 30.0);
  const SystemPoseMeasurement meas(fx.sys);
  MeasMat Sw = MeasMat::Identity(3, 3) * 1e-3;
  MeasVec z = fx.x.head(3);
  for (auto _ : state) {
    f->Predict(proc, Sv);
    benchmark::DoNotOptimize(f->Update(meas, z, Sw));
  }
  state.counters["state_dim"] = n;
}

void BM_Propagate(benchmark::State& state, std::string model) {
  Fixture fx(model);
  StateVec out(fx.x.size());
  for (auto _ : state) {
    fx.sys.Propagate(fx.x.data(), out.data(), 1.0, 1.0 + 1.0 / 30.0, fx.controls,
                     static_cast<const double*>(nullptr));
    benchmark::DoNotOptimize(out.data());
  }
}

// The SR-DD2 step of `model` with `effects` over one 30 Hz frame interval.
void AugmentedStep(benchmark::State& state, const std::string& model,
                   const std::vector<std::string>& effects) {
  const System sys = MakeSystem(model, effects).value();
  ControlSignal controls(2, 0);
  std::mt19937_64 rng(1);
  const std::vector<double> lo = {-1, -1}, hi = {1, 1};
  AppendSmoothRandom(&controls, 0, SecondsToNs(10.0), lo, hi, 1.0, 50.0, rng);
  auto f = MakeFilter("dd2").value();
  const int n = sys.state_dim();
  f->Initialize(sys.DefaultState(0, 0, 0), StateMat::Identity(n, n) * 1e-4, 1u << 2);
  const SystemProcess proc(sys, controls, 1.0, 1.0 + 1.0 / 30.0);
  const NoiseMat Sv = NoiseMat::Zero(sys.noise_dim(), sys.noise_dim());
  const SystemPoseMeasurement meas(sys);
  const MeasMat Sw = MeasMat::Identity(3, 3) * 1e-3;
  const MeasVec z = MeasVec::Zero(3);
  for (auto _ : state) {
    f->Predict(proc, Sv);
    benchmark::DoNotOptimize(f->Update(meas, z, Sw));
  }
  state.counters["state_dim"] = n;
}

void BM_DiffDriveStepVsStateSize(benchmark::State& state) {
  // Cost growth with the augmented state: diffdrive plus effects adding parameters.
  static const std::vector<std::vector<std::string>> kEffects = {
      {},
      {"time_offset"},
      {"time_offset", "lever_arm"},
      {"time_offset", "lever_arm", "lateral_slip", "yaw_rate_bias"}};
  AugmentedStep(state, "diffdrive", kEffects[static_cast<size_t>(state.range(0))]);
}
BENCHMARK(BM_DiffDriveStepVsStateSize)->DenseRange(0, 3);

// What kincald steps with effects: auto once the search has added what it found: the
// MR.CLAM pattern (unicycle + delay + speed lost in turns) and the demo's diffdrive + lag.
void BM_AutoEffectsStep(benchmark::State& state) {
  if (state.range(0) == 0) {
    AugmentedStep(state, "unicycle", {"time_offset", "turn_slowdown"});
  } else {
    AugmentedStep(state, "diffdrive", {"actuator_lag"});
  }
}
BENCHMARK(BM_AutoEffectsStep)->Arg(0)->Arg(1);

const bool kRegistered = [] {
  for (const auto& model : ModelRegistry::Instance().Names()) {
    for (const char* filter : {"dd2", "ekf", "ukf"}) {
      benchmark::RegisterBenchmark(("FilterStep/" + model + "/" + filter).c_str(), BM_FilterStep,
                                   model, std::string(filter));
    }
    benchmark::RegisterBenchmark(("Propagate/" + model).c_str(), BM_Propagate, model);
  }
  return true;
}();

}  // namespace
}  // namespace kincal

BENCHMARK_MAIN();
