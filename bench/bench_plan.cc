// kincal plan as users run it: the reference case (a differential drive with
// actuator lag, time offset and lever arm, poses at 15 Hz with 2 mm / 5 mrad, a 3 x 2 m
// arena) planned for 60 s with the default options, and the usual motions evaluated on
// the same budget (what `kincal plan` prints beside the plan).
#include <benchmark/benchmark.h>

#include "kincal/plan/planner.h"
#include "plan/plan_cases.h"

namespace kincal {
namespace {

// The plan layer's tests' reference robot (tests/plan/plan_cases.h), planned for 60 s.
struct Reference : plan_testing::ReferenceRobot {
  Reference() : ReferenceRobot(60.0) {}
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
