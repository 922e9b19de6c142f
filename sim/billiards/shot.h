// SimulateShot: fast-forward a table from a struck (or explicitly set) state until every ball is
// at rest, recording events and, optionally, a sampled trajectory. No side effects.
#ifndef SPORTSIM_SIM_BILLIARDS_SHOT_H_
#define SPORTSIM_SIM_BILLIARDS_SHOT_H_

#include <cstdint>
#include <functional>
#include <vector>

#include "absl/functional/function_ref.h"
#include "absl/status/statusor.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"

namespace sportsim::billiards {

struct ShotOptions {
  double max_time_s = 600.0;        ///< stop (not at rest) after this much simulated time (s)
  double sample_interval_s = 0.0;   ///< 0: no trajectory; else a sample about this often (s)
  int64_t max_samples = 200000;     ///< cap on the trajectory's length
  /// Polled every 1024 steps or so; returning true stops the run with Cancelled.
  std::function<bool()> cancelled;
};

struct ShotResult {
  TableState final_state;
  std::vector<Event> events;
  bool at_rest = false;
  double t_rest_s = 0.0;            ///< when the last ball stopped (exact), or the end time
  std::vector<Sample> samples;      ///< includes t = start and the final state
  double cpu_s = 0.0;               ///< thread CPU time of the simulation (s)
  int64_t events_handled = 0;       ///< events the engine handled, reported or not
};

/// Simulates from `initial` (velocities and spins already set, e.g. by ApplyStrike) until every
/// ball is at rest or max_time_s passes. Balls at rest that were given a velocity start moving
/// first (StartMoving; their transitions at the start time are reported). Samples fall on step
/// boundaries (the interval is rounded to a whole number of steps), so sampling never changes
/// the physics.
absl::StatusOr<ShotResult> SimulateShot(const TableModel& model, const SolverOptions& options,
                                        const TableState& initial, const ShotOptions& shot);

/// Validates ShotOptions (ranges named in the message).
absl::Status ValidateShotOptions(const ShotOptions& shot);

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_SHOT_H_
