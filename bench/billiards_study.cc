// Accuracy versus cost of the billiards engines: for each scene (straight draw, cut, two-rail
// bank, the bank with air drag, 9-ball break), integrator and step, the final-position error and
// the event-time error against a reference, and the CPU time per simulated second (median of
// repeated runs, thread CPU clock). The reference is the event engine (exact) where it applies,
// cross-checked against rk4 at 1e-5 s; with drag it is rk4 at 1e-5 s, checked against rk4 at
// 2e-5 s. The event engine has its own row (integrator "event", dt 0). CSV on stdout;
// bench/billiards_accuracy.py turns it into docs/billiards-accuracy.md and its plot.
//
// Usage: billiards_study [--quick]   (--quick: two steps per integrator, for the smoke test)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "bench/billiards_scenes.h"
#include "sim/billiards/shot.h"
#include "sim/core/cpu_clock.h"

namespace sportsim::billiards {
namespace {

struct Run {
  ShotResult result;
  double cpu_s = 0.0;
};

// dt = 0: the event engine.
Run Simulate(const Scene& scene, Integrator integ, double dt, int repeats) {
  Run best;
  std::vector<double> cpu;
  const SolverOptions options{.engine = dt > 0 ? Engine::kStepped : Engine::kEvent,
                              .integrator = integ,
                              .dt_s = dt > 0 ? dt : 1.0 / 960,
                              .effects = scene.effects};
  for (int k = 0; k < repeats; ++k) {
    const double c0 = ThreadCpuSeconds();
    absl::StatusOr<ShotResult> r = SimulateShot(scene.model, options, scene.state, {});
    cpu.push_back(ThreadCpuSeconds() - c0);
    if (!r.ok()) {
      std::fprintf(stderr, "%s: %s\n", scene.name.c_str(), r.status().ToString().c_str());
      std::exit(1);
    }
    best.result = *std::move(r);
  }
  std::sort(cpu.begin(), cpu.end());
  best.cpu_s = cpu[cpu.size() / 2];
  return best;
}

// Collision events only (ball-ball, cushion, pocket): the outcome a player sees.
std::vector<Event> Collisions(const ShotResult& r) {
  std::vector<Event> out;
  for (const Event& e : r.events) {
    if (e.kind != EventKind::kTransition) out.push_back(e);
  }
  return out;
}

struct Errors {
  double position_m = 0.0;   ///< largest final-position difference over the balls
  double event_time_s = 0.0; ///< largest event-time difference over the matching prefix
  size_t matched = 0;        ///< collision events that match the reference, in order
};

Errors Compare(const ShotResult& a, const ShotResult& ref) {
  Errors e;
  for (size_t i = 0; i < ref.final_state.balls.size(); ++i) {
    e.position_m = std::max(
        e.position_m, (a.final_state.balls[i].r - ref.final_state.balls[i].r).head<2>().norm());
  }
  const std::vector<Event> ea = Collisions(a), er = Collisions(ref);
  for (size_t i = 0; i < std::min(ea.size(), er.size()); ++i) {
    if (ea[i].kind != er[i].kind || ea[i].a != er[i].a || ea[i].b != er[i].b ||
        ea[i].other != er[i].other) {
      break;
    }
    e.event_time_s = std::max(e.event_time_s, std::abs(ea[i].t_s - er[i].t_s));
    ++e.matched;
  }
  return e;
}

}  // namespace
}  // namespace sportsim::billiards

int main(int argc, char** argv) {
  using namespace sportsim::billiards;
  const bool quick = argc > 1 && std::strcmp(argv[1], "--quick") == 0;
  const std::vector<double> steps =
      quick ? std::vector<double>{1.0 / 120, 1.0 / 960}
            : std::vector<double>{1.0 / 60,   1.0 / 120,  1.0 / 240, 1.0 / 480,
                                  1.0 / 960,  1.0 / 1920, 1.0 / 3840, 1.0 / 7680};
  const double ref_dt = quick ? 1.0 / 3840 : 1e-5;
  std::printf("scene,integrator,dt_s,position_error_m,event_time_error_s,events_matched,"
              "events_reference,cpu_s_per_simulated_s,t_rest_s,reference_self_error_m\n");
  for (const char* name : {"straight", "cut", "bank", "bank-drag", "break"}) {
    const Scene scene = MakeScene(name);
    const bool exact = (scene.effects & kEffectEnableDrag) == 0;
    const Run ref = exact ? Simulate(scene, Integrator::kRk4, 0.0, quick ? 3 : 201)
                          : Simulate(scene, Integrator::kRk4, ref_dt, 1);
    const Run check = Simulate(scene, Integrator::kRk4, exact ? ref_dt : 2 * ref_dt, 1);
    const double self = Compare(check.result, ref.result).position_m;
    const size_t n_ref = Collisions(ref.result).size();
    if (exact) {
      std::printf("%s,event,0,0,0,%zu,%zu,%.6g,%.6f,%.3g\n", name, n_ref, n_ref,
                  ref.cpu_s / ref.result.t_rest_s, ref.result.t_rest_s, self);
    }
    for (Integrator integ : {Integrator::kEuler, Integrator::kSemiImplicitEuler, Integrator::kRk4}) {
      for (double dt : steps) {
        const Run run = Simulate(scene, integ, dt, quick ? 1 : (dt < 1.0 / 2000 ? 3 : 7));
        const Errors e = Compare(run.result, ref.result);
        std::printf("%s,%s,%.9g,%.6g,%.6g,%zu,%zu,%.6g,%.6f,%.3g\n", name,
                    std::string(IntegratorName(integ)).c_str(), dt, e.position_m, e.event_time_s,
                    e.matched, n_ref, run.cpu_s / run.result.t_rest_s, run.result.t_rest_s, self);
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
