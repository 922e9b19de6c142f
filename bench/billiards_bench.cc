// Google Benchmark: one shot to rest with the stepped engine, per scene and integrator at the
// default step (1/960 s), the 8-ball break at game steps, and the same break with effects
// switched off or on (orientation tracking off; drag on). Reports shots per second. (Spin decay
// off is not benchmarked: a ball with side spin then never comes to rest.)
#include <benchmark/benchmark.h>

#include "absl/strings/str_format.h"
#include "bench/billiards_scenes.h"
#include "sim/billiards/shot.h"

namespace sportsim::billiards {
namespace {

const char* const kScenes[] = {"straight", "cut", "bank", "break"};

void BM_ShotToRest(benchmark::State& state) {
  const Scene scene = MakeScene(kScenes[state.range(0)]);
  const auto integ = static_cast<Integrator>(state.range(1));
  const SolverOptions o{.integrator = integ, .dt_s = 1.0 / 960.0};
  state.SetLabel(scene.name + "/" + std::string(IntegratorName(integ)));
  for (auto _ : state) {
    absl::StatusOr<ShotResult> r = SimulateShot(scene.model, o, scene.state, {});
    benchmark::DoNotOptimize(r);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ShotToRest)->ArgsProduct({{0, 1, 2, 3}, {0, 1, 2}})->Unit(benchmark::kMicrosecond);

void BM_EightBallBreak(benchmark::State& state) {
  TableModel m = *TableModel::Create(*MakeTablePreset("pool-9ft"));
  TableState s{.balls = *MakeRack("8ball", m)};
  if (!ApplyStrike(m, 0, {.speed_mps = 8.0, .ball_speed = true}, 0, &s).ok()) std::abort();
  const double dt = 1.0 / static_cast<double>(state.range(0));
  const uint32_t disabled = static_cast<uint32_t>(state.range(1));
  state.SetLabel(absl::StrFormat("dt 1/%d, disabled 0x%x", state.range(0), disabled));
  int64_t events = 0;
  for (auto _ : state) {
    absl::StatusOr<ShotResult> r = SimulateShot(m, {.dt_s = dt, .disabled = disabled}, s, {});
    events = static_cast<int64_t>(r->events.size());
    benchmark::DoNotOptimize(r);
  }
  state.counters["events"] = static_cast<double>(events);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EightBallBreak)
    ->Args({120, kEffectDrag})
    ->Args({960, kEffectDrag})
    ->Args({960, kEffectDrag | kEffectOrientation})
    ->Args({960, 0})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace sportsim::billiards
