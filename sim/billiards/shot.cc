#include "sim/billiards/shot.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "absl/strings/str_format.h"
#include "sim/billiards/cloth.h"
#include "sim/billiards/cue.h"
#include "sim/core/check.h"
#include "sim/core/cpu_clock.h"

namespace sportsim::billiards {
namespace {

Sample TakeSample(const TableState& s) {
  Sample out;
  out.t_s = s.t_s;
  out.r.reserve(s.balls.size());
  out.state.reserve(s.balls.size());
  for (const Ball& b : s.balls) {
    out.r.push_back(b.r.head<2>());
    out.state.push_back(b.state);
  }
  return out;
}

}  // namespace

absl::Status ValidateShotOptions(const ShotOptions& shot) {
  if (absl::Status s = CheckFiniteInRange("max_time_s", shot.max_time_s, 0, true, 3600, false);
      !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckFiniteInRange("sample_interval_s", shot.sample_interval_s, 0, false,
                                          3600, false);
      !s.ok()) {
    return s;
  }
  if (shot.max_samples < 1 || shot.max_samples > 10'000'000) {
    return absl::InvalidArgumentError("max_samples must be in [1, 10000000]");
  }
  return absl::OkStatus();
}

absl::StatusOr<ShotResult> SimulateShot(const TableModel& model, const SolverOptions& options,
                                        const TableState& initial, const ShotOptions& shot) {
  if (absl::Status s = ValidateSolverOptions(options); !s.ok()) return s;
  if (absl::Status s = ValidateShotOptions(shot); !s.ok()) return s;
  if (absl::Status s = ValidateLayout(model, initial); !s.ok()) return s;
  const double cpu0 = ThreadCpuSeconds();
  ShotResult out;
  absl::StatusOr<std::unique_ptr<TableSimulation>> created =
      TableSimulation::Create(model, options, initial, &out.events);
  if (!created.ok()) return created.status();
  TableSimulation& sim = **created;
  const double t_start = sim.time();
  const double t_stop = t_start + shot.max_time_s;
  // Chunks: one per sample, or (without sampling) 1024 steps or one simulated second, where
  // cancellation is polled. The stepped engine's chunks end on its step grid (whole numbers of
  // steps), so sampling never changes its physics; the event engine's never do.
  const bool stepped = options.engine == Engine::kStepped;
  const double dt = options.dt_s;
  double chunk = stepped ? 1024.0 * dt : 1.0;
  if (shot.sample_interval_s > 0) {
    chunk = stepped ? std::max(1.0, std::round(shot.sample_interval_s / dt)) * dt
                    : shot.sample_interval_s;
    out.samples.push_back(TakeSample(sim.state()));
  }
  int64_t k = 0;
  while (!sim.AtRest() && sim.time() < t_stop) {
    ++k;
    if (shot.cancelled && shot.cancelled()) {
      return absl::CancelledError(absl::StrFormat("cancelled at t = %.6f s", sim.time()));
    }
    const double t_next = std::min(t_start + static_cast<double>(k) * chunk, t_stop);
    if (absl::Status st = sim.AdvanceTo(t_next, &out.events); !st.ok()) return st;
    if (shot.sample_interval_s > 0) {
      if (static_cast<int64_t>(out.samples.size()) >= shot.max_samples) {
        return absl::ResourceExhaustedError(absl::StrFormat(
            "the trajectory would exceed %d samples: sample less often (sample_interval_s, "
            "sample_rate_hz on the wire)", shot.max_samples));
      }
      out.samples.push_back(TakeSample(sim.state()));
    }
  }
  out.final_state = sim.state();
  out.events_handled = sim.events_processed();
  const TableState& s = out.final_state;
  out.at_rest = s.AtRest();
  out.t_rest_s = t_start;
  if (out.at_rest) {
    // The instant the last ball stopped (or fell), not the chunk boundary.
    for (const Event& e : out.events) {
      if (e.kind == EventKind::kTransition &&
          (e.to == MotionState::kStationary || e.to == MotionState::kPocketed)) {
        out.t_rest_s = std::max(out.t_rest_s, e.t_s);
      }
    }
  } else {
    out.t_rest_s = s.t_s;
  }
  out.cpu_s = ThreadCpuSeconds() - cpu0;
  return out;
}

}  // namespace sportsim::billiards
