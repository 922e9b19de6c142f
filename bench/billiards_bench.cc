// Google Benchmark: one shot to rest per scene with the event engine and with the stepped engine
// per integrator at the default step (1/960 s); the 8-ball break (16 balls, 8 m/s) with the
// event engine and at game steps with the stepped one, with effects switched off or on
// (orientation tracking off; drag on, stepped only); and a batch of random shots with the event
// engine (what a bot needs). Reports shots per second and events per shot. And one
// ball-cushion impact per cushion model, over 256 seeded random approaches and spins. (Spin decay off is
// not benchmarked: a ball with side spin then never comes to rest.)
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "bench/billiards_scenes.h"
#include "bench/billiards_storms.h"
#include "sim/billiards/calibrate.h"
#include "sim/billiards/cloth.h"
#include "sim/billiards/collision.h"
#include "sim/billiards/shot.h"
#include "sim/core/units.h"
#include "sim/games/three_cushion.h"

namespace sportsim::billiards {
namespace {

const char* const kScenes[] = {"straight", "cut", "bank", "break"};

// Scheme 0..2: stepped engine with that integrator; 3: the event engine; 4: the event engine
// without orientation tracking.
SolverOptions Scheme(int64_t k) {
  if (k == 3) return {.engine = Engine::kEvent};
  if (k == 4) return {.engine = Engine::kEvent, .effects = kEffectDisableOrientation};
  return {.engine = Engine::kStepped, .integrator = static_cast<Integrator>(k),
          .dt_s = 1.0 / 960.0};
}
std::string SchemeName(const SolverOptions& o) {
  if (o.engine == Engine::kEvent) {
    return (o.effects & kEffectDisableOrientation) != 0 ? "event, no orientation" : "event";
  }
  return "stepped " + std::string(IntegratorName(o.integrator));
}

void BM_ShotToRest(benchmark::State& state) {
  const Scene scene = MakeScene(kScenes[state.range(0)]);
  const SolverOptions o = Scheme(state.range(1));
  state.SetLabel(scene.name + "/" + SchemeName(o));
  int64_t events = 0;
  for (auto _ : state) {
    absl::StatusOr<ShotResult> r = SimulateShot(scene.model, o, scene.state, {});
    events = static_cast<int64_t>(r->events.size());
    benchmark::DoNotOptimize(r);
  }
  state.counters["events"] = static_cast<double>(events);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_ShotToRest)->ArgsProduct({{0, 1, 2, 3}, {3, 4, 0, 1, 2}})->Unit(benchmark::kMicrosecond);

// range(0): 0 for the event engine, else the stepped engine's steps per second (rk4).
void BM_EightBallBreak(benchmark::State& state) {
  TableModel m = *TableModel::Create(*MakeTablePreset("pool-9ft"));
  TableState s{.balls = *MakeRack("8ball", m)};
  if (!ApplyStrike(m, 0, {.speed_mps = 8.0, .ball_speed = true}, 0, &s).ok()) std::abort();
  const bool event = state.range(0) == 0;
  const double dt = event ? 1.0 / 960.0 : 1.0 / static_cast<double>(state.range(0));
  const uint32_t effects = static_cast<uint32_t>(state.range(1));
  const SolverOptions o{.engine = event ? Engine::kEvent : Engine::kStepped, .dt_s = dt,
                        .effects = effects};
  state.SetLabel(event ? absl::StrFormat("event, effects 0x%x", effects)
                       : absl::StrFormat("stepped rk4 dt 1/%d, effects 0x%x", state.range(0),
                                         effects));
  int64_t events = 0;
  for (auto _ : state) {
    absl::StatusOr<ShotResult> r = SimulateShot(m, o, s, {});
    events = static_cast<int64_t>(r->events.size());
    benchmark::DoNotOptimize(r);
  }
  state.counters["events"] = static_cast<double>(events);
  // Events per second of CPU: its inverse is the cost per event.
  state.counters["events_rate"] = benchmark::Counter(
      static_cast<double>(events), benchmark::Counter::kIsIterationInvariantRate);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_EightBallBreak)
    ->Args({0, 0})
    ->Args({0, kEffectDisableOrientation})
    ->Args({120, 0})
    ->Args({960, 0})
    ->Args({960, kEffectDisableOrientation})
    ->Args({960, kEffectEnableDrag})
    ->Unit(benchmark::kMicrosecond);

// A batch of 256 seeded random shots on a 9-ft table with a 9-ball rack (random speed 0.5-8
// m/s, direction, elevation and tip offset), each to rest with the event engine: shots per
// second per core is items_per_second. range(0): effects; range(1): slip-speed friction's
// u_c in mm/s (0: off; 16 bands).
void BM_RandomShots(benchmark::State& state) {
  TableSpec spec = *MakeTablePreset("pool-9ft");
  spec.params.slide_fade_speed_mps = 1e-3 * static_cast<double>(state.range(1));
  TableModel m = *TableModel::Create(spec);
  std::vector<TableState> shots;
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  while (shots.size() < 256) {
    TableState s{.balls = *MakeRack("9ball", m, 0.0005 * unit(rng), rng())};
    const CueStrike strike{.speed_mps = 0.5 + 7.5 * unit(rng), .ball_speed = true,
                           .phi_rad = 6.283185307179586 * unit(rng),
                           .theta_rad = 0.2 * unit(rng), .a = 0.6 * (unit(rng) - 0.5),
                           .b = 0.6 * (unit(rng) - 0.5)};
    if (ApplyStrike(m, 0, strike, s.Find("cue"), &s).ok()) shots.push_back(s);
  }
  const SolverOptions o{.engine = Engine::kEvent,
                        .effects = static_cast<uint32_t>(state.range(0))};
  state.SetLabel(state.range(1) == 0
                     ? absl::StrFormat("event, effects 0x%x", state.range(0))
                     : absl::StrFormat("event, effects 0x%x, slip fade %d mm/s", state.range(0),
                                       state.range(1)));
  int64_t events = 0;
  std::vector<int64_t> per_shot;
  for (auto _ : state) {
    events = 0;
    per_shot.clear();
    for (const TableState& s : shots) {
      absl::StatusOr<ShotResult> r = SimulateShot(m, o, s, {});
      events += static_cast<int64_t>(r->events.size());
      per_shot.push_back(static_cast<int64_t>(r->events.size()));
      benchmark::DoNotOptimize(r);
    }
  }
  state.counters["events_per_shot"] = static_cast<double>(events) / 256.0;
  std::sort(per_shot.begin(), per_shot.end());
  state.counters["events_median"] = static_cast<double>(per_shot[per_shot.size() / 2]);
  state.counters["events_max"] = static_cast<double>(per_shot.back());
  state.SetItemsProcessed(state.iterations() * 256);
}
BENCHMARK(BM_RandomShots)
    ->Args({0, 0})
    ->Args({kEffectDisableOrientation, 0})
    ->Args({0, 300})
    ->Unit(benchmark::kMillisecond);

// The storm batch (bench/billiards_storms.h, bench/results/storms-2026-12.md): 1000 seeded
// random shots from the tight 8-ball rack with FastFiz's shot distribution, each to rest with
// the event engine (orientation on). range(0): 0 = sustained resting contacts (the default), 1 =
// the hops of before (RestingContacts::kHops). Time per iteration / 1000 = CPU per shot;
// counters: events handled per shot (mean, p99, max) and reported per shot (mean, max).
void BM_RackShots(benchmark::State& state) {
  const TableModel m = *TableModel::Create(*MakeTablePreset("pool-9ft"));
  const std::vector<TableState> batch = StormBatch(m, 1000, 2026);
  // Arg: bit 0 the legacy hops (before), bit 1 orientation off (a bot's summary needs none).
  SolverOptions o = StormOptions((state.range(0) & 1) != 0);
  if ((state.range(0) & 2) != 0) o.effects |= kEffectDisableOrientation;
  state.SetLabel(std::string((state.range(0) & 1) != 0 ? "hops (before)" : "sustained contacts") +
                 ((state.range(0) & 2) != 0 ? ", orientation off" : ""));
  std::vector<double> handled(batch.size());
  double reported = 0.0, reported_max = 0.0;
  for (auto _ : state) {
    reported = reported_max = 0.0;
    for (size_t i = 0; i < batch.size(); ++i) {
      std::vector<Event> ev;
      std::unique_ptr<TableSimulation> sim = *TableSimulation::Create(m, o, batch[i], &ev);
      for (int k = 1; k <= 600 && !sim->AtRest(); ++k) {
        if (!sim->AdvanceTo(batch[i].t_s + k, &ev).ok()) std::abort();
      }
      benchmark::DoNotOptimize(sim->state());
      handled[i] = static_cast<double>(sim->events_processed());
      reported += static_cast<double>(ev.size());
      reported_max = std::max(reported_max, static_cast<double>(ev.size()));
    }
  }
  std::vector<double> sorted = handled;
  std::sort(sorted.begin(), sorted.end());
  double sum = 0.0;
  for (double h : sorted) sum += h;
  state.counters["handled_mean"] = sum / static_cast<double>(sorted.size());
  state.counters["handled_p99"] = sorted[sorted.size() * 99 / 100];
  state.counters["handled_max"] = sorted.back();
  state.counters["reported_mean"] = reported / static_cast<double>(batch.size());
  state.counters["reported_max"] = reported_max;
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(batch.size()));
}
BENCHMARK(BM_RackShots)->Arg(0)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond);

// One impact per iteration, cycling through 256 approaches on the pool-9ft nose. range(0): the
// CushionModel; range(1): the approaches, 0 random (0.05-3 m/s into the rail, up to 3 m/s along
// it, every spin component up to 150 rad/s), 1 rolling balls at 0.2-3.8 m/s from any heading
// into the rail, with side spin up to 100 rad/s (the common impact in play), 2 stun or rolling
// balls at 10-90 deg to the rail (the cushion study's kind, where many nose slips stick).
void BM_CushionImpact(benchmark::State& state) {
  TableSpec spec = *MakeTablePreset("pool-9ft");
  spec.params.cushion_model = static_cast<CushionModel>(state.range(0));
  const TableModel model = *TableModel::Create(spec);
  const bool rolling = state.range(1) == 1, square = state.range(1) == 2;
  state.SetLabel(std::string(state.range(0) == 0   ? "han"
                             : state.range(0) == 2 ? "mathavan2010"
                                                   : "stronge") +
                 (square ? ", stun or rolling, 10-90 deg" : rolling ? ", rolling" : ", random"));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Ball> balls(256);
  for (Ball& b : balls) {
    if (square) {
      // The cushion study's kind of approach: stun or natural roll, 10-90 deg to the rail at
      // 0.5-2.5 m/s, side spin of up to half the speed's worth each way; many nose slips stick.
      const double speed = 1.5 + u(rng), angle = 0.5 * kPi + 0.5 * kPi * 8.0 / 9.0 * u(rng);
      b.v = {speed * std::cos(angle), speed * std::sin(angle), 0.0};
      b.w = Eigen::Vector3d::Zero();
      if (u(rng) > 0.0) b.w = Eigen::Vector3d::UnitZ().cross(b.v) / model.radius();
      b.w.z() = 0.5 * u(rng) * speed / model.radius();
    } else if (rolling) {
      const double speed = 2.0 + 1.8 * u(rng), heading = 0.5 * kPi + 1.45 * u(rng);
      b.v = {speed * std::cos(heading), speed * std::sin(heading), 0.0};
      b.w = Eigen::Vector3d::UnitZ().cross(b.v) / model.radius();
      b.w.z() = 100.0 * u(rng);
    } else {
      b.v = {3.0 * u(rng), 0.05 + 1.475 * (1.0 + u(rng)), 0.0};
      b.w = {150.0 * u(rng), 150.0 * u(rng), 150.0 * u(rng)};
    }
    b.state = Classify(model, b);
  }
  size_t i = 0;
  for (auto _ : state) {
    Ball b = balls[i++ % balls.size()];
    CollideCushion(model, Eigen::Vector2d(0.0, -1.0), &b);
    benchmark::DoNotOptimize(b);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_CushionImpact)
    ->ArgsProduct({{static_cast<int>(CushionModel::kHan),
                    static_cast<int>(CushionModel::kStrongeCompliant),
                    static_cast<int>(CushionModel::kMathavan2010)},
                   {0, 1, 2}})
    ->Unit(benchmark::kNanosecond);

// One ball-ball impact per iteration, cycling through 256 approaches on the pool table.
// range(0): the BallBallModel (0 TP A-14's single impulse, 1 Mathavan's 2014 integration);
// range(1): the approaches, 0 a rolling cue ball at 0.3-4 m/s cutting a ball at rest at 0-80
// deg with side spin up to half its speed's worth (the common impact in play), 1 random (both
// balls moving, every spin component up to 150 rad/s).
void BM_BallImpact(benchmark::State& state) {
  TableSpec spec = *MakeTablePreset("pool-9ft");
  spec.params.ball_ball_model = static_cast<BallBallModel>(state.range(0));
  const TableModel model = *TableModel::Create(spec);
  const bool random = state.range(1) == 1;
  state.SetLabel(std::string(state.range(0) == 0 ? "alciatore" : "mathavan2014") +
                 (random ? ", random" : ", rolling cut"));
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double radius = model.radius();
  std::vector<std::pair<Ball, Ball>> pairs;
  while (pairs.size() < 256) {
    Ball a, b;
    a.r = {0.0, 0.0, radius};
    const double cut = random ? kPi * u(rng) : DegToRad(40.0 + 40.0 * u(rng));
    b.r = {2.0 * radius * std::cos(cut), 2.0 * radius * std::sin(cut), radius};
    if (random) {
      a.v = {3.0 * u(rng), 3.0 * u(rng), 0.0};
      b.v = {u(rng), u(rng), 0.0};
      a.w = {150.0 * u(rng), 150.0 * u(rng), 150.0 * u(rng)};
      b.w = {150.0 * u(rng), 150.0 * u(rng), 150.0 * u(rng)};
    } else {
      const double speed = 2.15 + 1.85 * u(rng);
      a.v = {speed, 0.0, 0.0};
      a.w = Eigen::Vector3d::UnitZ().cross(a.v) / radius;
      a.w.z() = 0.5 * u(rng) * speed / radius;
    }
    if ((a.v - b.v).dot(b.r - a.r) <= 0.0) continue;
    a.state = Classify(model, a);
    b.state = Classify(model, b);
    pairs.emplace_back(a, b);
  }
  size_t i = 0;
  for (auto _ : state) {
    auto [a, b] = pairs[i++ % pairs.size()];
    CollideBalls(model, 0, &a, &b);
    benchmark::DoNotOptimize(a);
    benchmark::DoNotOptimize(b);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_BallImpact)->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kNanosecond);

// n random three-ball carom shots at 2-4 m/s, aimed within 0.2 rad of the first object ball,
// tracked with 1 mm noise at rate_hz (seeded: the same shots every run).
absl::StatusOr<std::vector<Recording>> TrackedCaromShots(const TableModel& model, double rate_hz,
                                                          int n) {
  const double l = model.spec().length_m, w = model.spec().width_m;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Recording> recs;
  for (int i = 0; i < n; ++i) {
    TableState s;
    for (const char* id : {"white", "yellow", "red"}) {
      Ball b;
      b.id = id;
      b.r = {0.4 * l * u(rng), 0.4 * w * u(rng), model.radius()};
      bool clear = true;
      for (const Ball& o : s.balls) clear = clear && (o.r - b.r).norm() > 8 * model.radius();
      if (clear) s.balls.push_back(b);
    }
    if (s.balls.size() < 2) continue;
    CueStrike strike;
    strike.ball_speed = true;
    strike.speed_mps = 3.0 + u(rng);
    const Eigen::Vector3d to = s.balls[1].r - s.balls[0].r;
    strike.phi_rad = std::atan2(to.y(), to.x()) + 0.2 * u(rng);
    strike.a = 0.3 * u(rng);
    strike.b = 0.3 * u(rng);
    absl::StatusOr<Recording> r = SyntheticRecording(
        model, SolverOptions{}, s, 0, strike,
        SyntheticOptions{.rate_hz = rate_hz, .noise_m = 1e-3, .seed = static_cast<uint64_t>(i + 1)});
    if (!r.ok()) return r.status();
    recs.push_back(*std::move(r));
  }
  return recs;
}

// The cloth read from tracks (ReadCloth, what CalibrationOptions::read_cloth does before a
// calibration): eight random three-ball carom shots (TrackedCaromShots), tracked at range(0)
// Hz (50: a match tracker; 250: a fast camera, five times the points and finer roll starts to
// try). Items: tracked points, so the rate is per point.
void BM_ReadCloth(benchmark::State& state) {
  const TableModel model = *TableModel::Create(*MakeTablePreset("carom"));
  absl::StatusOr<std::vector<Recording>> recs =
      TrackedCaromShots(model, static_cast<double>(state.range(0)), 8);
  if (!recs.ok()) {
    state.SkipWithError(std::string(recs.status().message()).c_str());
    return;
  }
  size_t points = 0;
  for (const Recording& r : *recs) points += r.track.size();
  state.SetLabel(absl::StrFormat("%d Hz, %d shots, %d points", state.range(0), recs->size(), points));
  for (auto _ : state) {
    const ClothReading c = ReadCloth(*recs, model.spec().params.gravity_mps2);
    benchmark::DoNotOptimize(c);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(points));
}
BENCHMARK(BM_ReadCloth)->Arg(50)->Arg(250)->Unit(benchmark::kMillisecond);

// A prediction from a shot's first 0.4 s (FitStrike on a window): range(0) 0, the best fit of
// the window; 1, the plausible strikes' central rest (StrikeBounds::central_rest: a grid of
// strikes fitted and played to rest); 2, the same with the three-cushion point intended
// (StrikeBounds::intent: the grid refined where plausible). Four shots of TrackedCaromShots
// at 50 Hz under their own table; items: shots, so the time per item is a prediction's. The
// label gives the simulations a shot.
void BM_PredictFromStart(benchmark::State& state) {
  const TableModel model = *TableModel::Create(*MakeTablePreset("carom"));
  absl::StatusOr<std::vector<Recording>> recs = TrackedCaromShots(model, 50.0, 4);
  if (!recs.ok()) {
    state.SkipWithError(std::string(recs.status().message()).c_str());
    return;
  }
  const StrikeBounds bounds{.central_rest = state.range(0) >= 1,
                            .intent = state.range(0) == 2 ? games::ThreeCushionIntent() : nullptr};
  int64_t simulations = 0, fits = 0;
  for (auto _ : state) {
    for (const Recording& r : *recs) {
      absl::StatusOr<StrikeFit> fit = FitStrike(model, SolverOptions{}, r, bounds, 0.4);
      if (!fit.ok()) {
        state.SkipWithError(std::string(fit.status().message()).c_str());
        return;
      }
      simulations += fit->simulations;
      ++fits;
      benchmark::DoNotOptimize(fit->strike);
    }
  }
  constexpr std::array kLabels{"best fit", "central rest", "central rest, the point intended"};
  state.SetLabel(absl::StrFormat("%s, %d simulations a shot",
                                 kLabels[static_cast<size_t>(state.range(0))],
                                 fits > 0 ? simulations / fits : 0));
  state.SetItemsProcessed(fits);
}
BENCHMARK(BM_PredictFromStart)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace sportsim::billiards
