// Batches of candidate shots for bots (SimulateShots): the request checked once into a
// BatchJob, then each (strike, noise sample) computed independently (any thread, any order)
// into its outcome. No gRPC here; the RPC layer spreads the outcomes over the simulation pool
// and streams them in request order.
#ifndef SPORTSIM_SERVER_BILLIARDS_BATCH_H_
#define SPORTSIM_SERVER_BILLIARDS_BATCH_H_

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "server/billiards/convert.h"
#include "sim/billiards/cue.h"
#include "sportsim/v1/billiards.pb.h"

namespace sportsim::server {

/// Most strikes in one batch, and most noise samples of each; most outcomes in all.
inline constexpr int kMaxBatchStrikes = 10000;
inline constexpr int kMaxBatchSamples = 1000;
inline constexpr int64_t kMaxBatchOutcomes = 100000;

struct BatchJob {
  TableBuild table;
  billiards::SolverOptions solver;
  double max_time_s = 600.0;
  struct Strike {
    billiards::CueStrike strike;
    int cue = -1;       ///< the struck ball's index; -1: the strike is refused (`error`)
    std::string error;  ///< why this strike cannot be played (reported in its outcomes)
  };
  std::vector<Strike> strikes;
  int samples = 1;
  uint64_t seed = 0;
  uint32_t first_index = 0;  ///< the batch's first strike's index (a chunk of a longer batch)
  double noise = 0.0;
  v1::ShotOutcomeKind outcome = v1::SHOT_OUTCOME_SUMMARY;

  int64_t size() const { return static_cast<int64_t>(strikes.size()) * samples; }
};

/// Checks the request: the table and solver (INVALID_ARGUMENT naming the field), the batch's
/// size (RESOURCE_EXHAUSTED past the limits). A strike that cannot be played (a miscue, an
/// unknown ball) does not refuse the batch: its outcomes carry the error.
absl::StatusOr<BatchJob> BatchJobFromProto(const v1::SimulateShotsRequest& request);

/// Outcome n (strike n / samples, sample n % samples), polling `stop` between events.
void ComputeOutcome(const BatchJob& job, int64_t n, const std::function<bool()>& stop,
                    v1::ShotOutcome* out);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_BILLIARDS_BATCH_H_
