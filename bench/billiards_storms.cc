// Event storms in resting clusters (bench/results/storms-2026-12.md): a seeded batch of random
// shots from the tight 8-ball rack on a 9-ft table, FastFiz's shot distribution (heading
// uniform, cue speed 0.5-4.5 m/s, elevation 5-30 degrees, tip offsets within +-10 mm), each run
// to rest by the event engine. Prints the distribution of events handled and reported per shot,
// CPU per shot, the share of the batch's CPU spent in the 1 % of shots with the most events,
// and what the engine handled by kind; --trace dumps the worst shot's reported events.
//   billiards_storms [--shots N] [--seed S] [--repeat K] [--legacy] [--no-orientation]
//                    [--trace] [--only I]
// --legacy: RestingContacts::kHops (the treatment before 2026-12); --only I: run shot I once
// (with --trace: print its events);
// STORM_DUMP=1: per-shot "index handled reported cpu_us" lines on stderr.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench/billiards_storms.h"
#include "sim/billiards/event_engine.h"
#include "sim/billiards/shot.h"
#include "sim/core/cpu_clock.h"

namespace sportsim::billiards {
namespace {

struct ShotStats {
  int index = 0;
  int64_t handled = 0, reported = 0;
  double cpu_s = 0.0;
  EventEngineCounts counts;
};

double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
  return v[k];
}

void PrintEvents(const std::vector<Event>& events) {
  for (const Event& e : events) {
    std::printf("%.9f %-13s %2d %2d %2d %s->%s va(%.3g,%.3g) vb(%.3g,%.3g)\n", e.t_s,
                std::string(EventKindName(e.kind)).c_str(), e.a, e.b, e.other,
                std::string(MotionStateName(e.from)).c_str(),
                std::string(MotionStateName(e.to)).c_str(), e.va.x(), e.va.y(), e.vb.x(),
                e.vb.y());
  }
}

int Main(int argc, char** argv) {
  int shots = 1000, repeat = 3;
  uint64_t seed = 2026;
  bool legacy = false, trace = false, no_orientation = false;
  int only = -1;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--shots") && i + 1 < argc) shots = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--seed") && i + 1 < argc) seed = std::strtoull(argv[++i], nullptr, 10);
    else if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc) repeat = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--legacy")) legacy = true;
    else if (!std::strcmp(argv[i], "--no-orientation")) no_orientation = true;
    else if (!std::strcmp(argv[i], "--only") && i + 1 < argc) only = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--trace")) trace = true;
    else { std::fprintf(stderr, "unknown argument %s\n", argv[i]); return 2; }
  }
  const TableModel m = *TableModel::Create(*MakeTablePreset("pool-9ft"));
  const std::vector<TableState> batch = StormBatch(m, shots, seed);
  SolverOptions o = StormOptions(legacy);
  if (no_orientation) o.effects |= kEffectDisableOrientation;
  if (only >= 0) {
    absl::StatusOr<ShotResult> r = SimulateShot(m, o, batch[only], {});
    std::printf("shot %d: %s, %zu events reported\n", only, r.ok() ? "ok" : r.status().ToString().c_str(),
                r.ok() ? r->events.size() : 0);
    if (trace && r.ok()) PrintEvents(r->events);
    return 0;
  }
  std::vector<ShotStats> stats(batch.size());
  // CPU per shot: the median over `repeat` runs of each shot (the events are the same bits).
  for (size_t i = 0; i < batch.size(); ++i) {
    std::vector<double> cpu;
    for (int r = 0; r < repeat; ++r) {
      std::vector<Event> ev;
      const double c0 = ThreadCpuSeconds();
      std::unique_ptr<TableSimulation> sim = *TableSimulation::Create(m, o, batch[i], &ev);
      for (int k = 1; k <= 600 && !sim->AtRest(); ++k) {
        if (!sim->AdvanceTo(batch[i].t_s + k, &ev).ok()) {
          std::fprintf(stderr, "shot %zu failed\n", i);
          return 1;
        }
      }
      cpu.push_back(ThreadCpuSeconds() - c0);
      stats[i] = {static_cast<int>(i), sim->events_processed(), static_cast<int64_t>(ev.size()),
                  0.0, *EventCountsOf(*sim)};
    }
    stats[i].cpu_s = Quantile(cpu, 0.5);
  }
  std::vector<double> handled, reported, cpu;
  double total_cpu = 0.0;
  EventEngineCounts sum;
  for (const ShotStats& s : stats) {
    handled.push_back(static_cast<double>(s.handled));
    reported.push_back(static_cast<double>(s.reported));
    cpu.push_back(s.cpu_s);
    total_cpu += s.cpu_s;
    sum.ball_ball += s.counts.ball_ball;
    sum.ball_ball_plastic += s.counts.ball_ball_plastic;
    sum.ball_ball_push += s.counts.ball_ball_push;
    sum.cushion += s.counts.cushion;
    sum.cushion_plastic += s.counts.cushion_plastic;
    sum.pocket += s.counts.pocket;
    sum.transition += s.counts.transition;
    sum.state_changes += s.counts.state_changes;
    sum.predictions += s.counts.predictions;
    sum.sustained_contacts += s.counts.sustained_contacts;
    sum.sustained_sweeps += s.counts.sustained_sweeps;
    sum.group_balls += s.counts.group_balls;
  }
  std::vector<ShotStats> by_events = stats;
  std::sort(by_events.begin(), by_events.end(),
            [](const ShotStats& a, const ShotStats& b) { return a.handled > b.handled; });
  double top_cpu = 0.0;
  const size_t top = std::max<size_t>(1, stats.size() / 100);
  for (size_t k = 0; k < top; ++k) top_cpu += by_events[k].cpu_s;
  std::printf("%s treatment, %zu shots, seed %llu\n", legacy ? "legacy (hops)" : "default",
              stats.size(), static_cast<unsigned long long>(seed));
  std::printf("events handled per shot: median %.0f  mean %.1f  p90 %.0f  p99 %.0f  max %.0f\n",
              Quantile(handled, 0.5), [&] { double s = 0; for (double x : handled) s += x; return s / handled.size(); }(),
              Quantile(handled, 0.9), Quantile(handled, 0.99), Quantile(handled, 1.0));
  std::printf("events reported per shot: median %.0f  p99 %.0f  max %.0f\n",
              Quantile(reported, 0.5), Quantile(reported, 0.99), Quantile(reported, 1.0));
  std::printf("CPU per shot: mean %.1f us  median %.1f us  p99 %.1f us  max %.1f us\n",
              1e6 * total_cpu / stats.size(), 1e6 * Quantile(cpu, 0.5), 1e6 * Quantile(cpu, 0.99),
              1e6 * Quantile(cpu, 1.0));
  std::printf("top 1%% of shots by events: %.1f %% of the batch CPU\n", 100.0 * top_cpu / total_cpu);
  std::printf("handled (batch): ball-ball %lld (plastic %lld, pushes %lld), cushion %lld "
              "(plastic/push %lld), pocket %lld, transitions %lld, contact-caused state changes "
              "%lld, sustained contacts %lld (sweeps %lld, group balls %lld), predictions %lld\n",
              (long long)sum.ball_ball, (long long)sum.ball_ball_plastic,
              (long long)sum.ball_ball_push, (long long)sum.cushion, (long long)sum.cushion_plastic,
              (long long)sum.pocket, (long long)sum.transition, (long long)sum.state_changes,
              (long long)sum.sustained_contacts, (long long)sum.sustained_sweeps,
              (long long)sum.group_balls, (long long)sum.predictions);
  if (std::getenv("STORM_DUMP") != nullptr) {
    for (const ShotStats& st : stats) {
      std::fprintf(stderr, "%d %lld %lld %.2f\n", st.index, (long long)st.handled, (long long)st.reported, 1e6 * st.cpu_s);
    }
  }
  std::printf("worst shots:");
  for (size_t k = 0; k < std::min<size_t>(5, by_events.size()); ++k) {
    const ShotStats& s = by_events[k];
    std::printf(" #%d (%lld handled, %lld reported; bb %lld plastic %lld push %lld, trans %lld, "
                "sweeps %lld, group balls %lld, predictions %lld)",
                s.index, (long long)s.handled, (long long)s.reported, (long long)s.counts.ball_ball,
                (long long)s.counts.ball_ball_plastic, (long long)s.counts.ball_ball_push,
                (long long)s.counts.transition, (long long)s.counts.sustained_sweeps,
                (long long)s.counts.group_balls, (long long)s.counts.predictions);
  }
  std::printf("\n");
  if (trace) {
    const TableState& s = batch[by_events[0].index];
    absl::StatusOr<ShotResult> r = SimulateShot(m, o, s, {});
    if (r.ok()) PrintEvents(r->events);
  }
  return 0;
}

}  // namespace
}  // namespace sportsim::billiards

int main(int argc, char** argv) { return sportsim::billiards::Main(argc, argv); }
