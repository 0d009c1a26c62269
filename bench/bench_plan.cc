// kincal plan as users run it: the reference case (a differential drive with
// actuator lag, time offset and lever arm, poses at 15 Hz with 2 mm / 5 mrad, a 3 x 2 m
// arena) planned for 60 s with the default options, and the usual motions evaluated on
// the same budget (what `kincal plan` prints beside the plan).
#include <benchmark/benchmark.h>

#include "kincal/plan/planner.h"

namespace kincal {
namespace {

struct Reference {
  System sys = MakeSystem("diffdrive", {"actuator_lag", "time_offset", "lever_arm"}).value();
  Eigen::VectorXd p = (Eigen::VectorXd(8) << 0.03, 0.03, 0.3, 0.1, 0.0, 0.0, 0.0, 0.0).finished();
  Eigen::MatrixXd prior = (Eigen::VectorXd(8) << 0.003, 0.003, 0.03, 0.1, 0.1, 0.05, 0.05, 0.05)
                              .finished()
                              .cwiseAbs2()
                              .asDiagonal();
  std::unique_ptr<Workspace> ws = MakeArena(-1.5, -1.0, 1.5, 1.0);
  PlanOptions o;
  Reference() {
    o.duration_s = 60.0;
    o.max_abs = {20.0, 20.0};
    o.max_accel = {40.0, 40.0};
    o.targets = (Eigen::VectorXd(8) << 3e-5, 3e-5, 3e-4, 3e-3, 3e-3, 2e-3, 2e-3, 0.0).finished();
    o.care = {0, 1, 2, 3, 4, 5, 6};
  }
};

void BM_Plan60s(benchmark::State& state) {
  const Reference r;
  for (auto _ : state) {
    Motion plan;
    const Status s = PlanMotion(r.sys, r.p, r.prior, *r.ws, r.o, &plan);
    if (!s.ok()) state.SkipWithError(s.message().c_str());
    benchmark::DoNotOptimize(plan.curve.time_to_target_s);
  }
  state.counters["plan_seconds"] = r.o.duration_s;
}
BENCHMARK(BM_Plan60s)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_UsualMotions60s(benchmark::State& state) {
  const Reference r;
  for (auto _ : state) {
    const auto m = UsualMotions(r.sys, r.p, r.prior, *r.ws, r.o);
    benchmark::DoNotOptimize(m.size());
  }
  state.counters["motions"] = 4;
}
BENCHMARK(BM_UsualMotions60s)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
}  // namespace kincal
