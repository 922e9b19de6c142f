// Google Benchmark: the cost of one swing to impact per integrator at its nominal setting, and
// of one force evaluation. Reports swings (or evaluations) per second.
#include <benchmark/benchmark.h>

#include "sim/swing/swing_dynamics.h"
#include "sim/swing/swing_simulation.h"

namespace sportsim::swing {
namespace {

void BM_SwingToImpact(benchmark::State& state) {
  const SwingIntegrator integ = kAllSwingIntegrators[static_cast<size_t>(state.range(0))];
  const SwingModel m = *SwingModel::Create(SwingParams{});
  const TorqueProgram p = TorqueProgram::Chapter();
  SwingSolverOptions o{.integrator = integ};
  if (integ == SwingIntegrator::kDp45) o.accuracy.tolerance = 1e-8; else o.accuracy.dt_s = 0.0025;
  state.SetLabel(std::string(SwingIntegratorName(integ)));
  for (auto _ : state) {
    absl::StatusOr<SwingRunResult> r = SimulateSwing(m, p, o, {});
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SwingToImpact)->DenseRange(0, 4);

void BM_SwingDerivative(benchmark::State& state) {
  const SwingModel m = *SwingModel::Create(SwingParams{}, static_cast<uint32_t>(state.range(0)));
  SwingVec y(1.0, 0.5, 10.0, -5.0);
  for (auto _ : state) {
    benchmark::DoNotOptimize(y);
    SwingVec f = SwingDerivative(m, y, {100.0, -10.0});
    benchmark::DoNotOptimize(f);
  }
  state.SetLabel(state.range(0) == 0 ? "full physics" : "gravity+shoulder off");
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_SwingDerivative)->Arg(0)->Arg(kSwingDisableGravity | kSwingDisableShoulderAccel);

}  // namespace
}  // namespace sportsim::swing

BENCHMARK_MAIN();
