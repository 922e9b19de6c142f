#include "server/billiards/batch.h"

#include <algorithm>
#include <utility>

#include "absl/strings/str_format.h"
#include "server/world/world.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/shot.h"
#include "sim/core/check.h"

namespace sportsim::server {

namespace b = ::sportsim::billiards;

absl::StatusOr<BatchJob> BatchJobFromProto(const v1::SimulateShotsRequest& request) {
  if (request.strikes_size() == 0) return absl::InvalidArgumentError("strikes: at least one");
  if (request.strikes_size() > kMaxBatchStrikes) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "strikes: at most %d in one batch, got %d", kMaxBatchStrikes, request.strikes_size()));
  }
  if (request.samples_per_strike() > kMaxBatchSamples) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "samples_per_strike must be in [0, %d], got %d", kMaxBatchSamples,
        request.samples_per_strike()));
  }
  const int samples =
      request.samples_per_strike() == 0 ? 1 : static_cast<int>(request.samples_per_strike());
  if (static_cast<int64_t>(request.strikes_size()) * samples > kMaxBatchOutcomes) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "strikes x samples_per_strike is %d, above the %d outcomes of one batch",
        static_cast<int64_t>(request.strikes_size()) * samples, kMaxBatchOutcomes));
  }
  if (static_cast<uint64_t>(request.first_index()) + static_cast<uint64_t>(request.strikes_size()) >
      uint64_t{UINT32_MAX} + 1) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "first_index: %u plus %d strikes passes the largest index, %u", request.first_index(),
        request.strikes_size(), UINT32_MAX));
  }
  if (absl::Status s = CheckFiniteInRange("noise", request.noise(), 0, false, 100, false);
      !s.ok()) {
    return s;
  }
  if (request.max_time_s() != 0) {
    if (absl::Status s = CheckFiniteInRange("max_time_s", request.max_time_s(), 0, true, 3600,
                                            false);
        !s.ok()) {
      return s;
    }
  }
  switch (request.outcome()) {
    case v1::SHOT_OUTCOME_SUMMARY:
    case v1::SHOT_OUTCOME_FINAL:
    case v1::SHOT_OUTCOME_EVENTS: break;
    default:
      return absl::InvalidArgumentError(
          absl::StrFormat("outcome: unknown kind %d", static_cast<int>(request.outcome())));
  }
  absl::StatusOr<TableBuild> table = TableFromProto(request.table());
  if (!table.ok()) return table.status();
  if (absl::Status s = b::ValidateLayout(table->model, table->state); !s.ok()) {
    return PrefixStatus("table: ", s);
  }
  absl::StatusOr<b::SolverOptions> solver = SolverFromProto(request.solver());
  if (!solver.ok()) return solver.status();
  if (absl::Status s = b::ValidateSolverOptions(*solver); !s.ok()) {
    return PrefixStatus("solver: ", s);
  }
  BatchJob job{.table = *std::move(table), .solver = *solver};
  if (request.max_time_s() != 0) job.max_time_s = request.max_time_s();
  job.samples = samples;
  job.seed = request.seed();
  job.first_index = request.first_index();
  job.noise = request.noise();
  job.outcome = request.outcome();
  // A summary carries no ball states, so nothing reads the balls' orientation: its tracking
  // (a third of a break's CPU) is switched off. It never changes a position, a contact or a
  // time (no law reads it), so the outcome is the same either way.
  if (job.outcome == v1::SHOT_OUTCOME_SUMMARY) job.solver.effects |= b::kEffectDisableOrientation;
  job.strikes.reserve(static_cast<size_t>(request.strikes_size()));
  for (int i = 0; i < request.strikes_size(); ++i) {
    const v1::CueStrike& p = request.strikes(i);
    BatchJob::Strike s;
    if (p.noise() != 0 || p.seed() != 0) {
      s.error = absl::StrFormat("strikes[%d]: noise and seed are the batch's (noise, seed)", i);
    } else if (absl::StatusOr<b::CueStrike> strike = StrikeFromProto(p); !strike.ok()) {
      s.error = absl::StrFormat("strikes[%d].%s", i, strike.status().message());
    } else {
      s.strike = *strike;
      const std::string id = p.ball().empty() ? "cue" : p.ball();
      s.cue = job.table.state.Find(id);
      if (s.cue < 0) {
        s.error = absl::StrFormat("strikes[%d].ball: no ball %s on the table", i, Quote(id));
      }
    }
    job.strikes.push_back(std::move(s));
  }
  return job;
}

void ComputeOutcome(const BatchJob& job, int64_t n, const std::function<bool()>& stop,
                    v1::ShotOutcome* out) {
  const int64_t local = n / job.samples;
  const uint64_t index = job.first_index + static_cast<uint64_t>(local);  // the batch's
  const int64_t sample = n % job.samples;
  out->set_index(static_cast<uint32_t>(index));
  out->set_sample(static_cast<uint32_t>(sample));
  const BatchJob::Strike& s = job.strikes[static_cast<size_t>(local)];
  if (s.cue < 0) {
    out->set_error(s.error);
    return;
  }
  const b::TableModel& model = job.table.model;
  b::TableState state = job.table.state;
  b::CueStrike strike = s.strike;
  strike.noise = job.noise;
  // Sample k of strike i: a seed of (seed, i, k) alone, so that asking for more samples keeps
  // the ones already seen.
  strike.seed = job.noise > 0 ? DeriveSeed(DeriveSeed(job.seed, index),
                                           static_cast<uint64_t>(sample))
                              : 0;
  absl::StatusOr<b::StrikeOutcome> applied =
      b::ApplyStrike(model, job.solver.effects, strike, s.cue, &state);
  if (!applied.ok()) {
    out->set_error(absl::StrFormat("strike: %s", applied.status().message()));
    return;
  }
  b::ShotOptions options;
  options.max_time_s = job.max_time_s;
  options.cancelled = stop;
  absl::StatusOr<b::ShotResult> result = b::SimulateShot(model, job.solver, state, options);
  if (!result.ok()) {
    out->set_error(std::string(result.status().message()));
    return;
  }
  // What a bot ranks candidates by: the struck ball's first contact, what fell where, when
  // all was at rest.
  for (const b::Event& e : result->events) {
    if (e.kind == b::EventKind::kBallBall && out->first_contact().empty() &&
        (e.a == s.cue || e.b == s.cue)) {
      out->set_first_contact(result->final_state.balls[e.a == s.cue ? e.b : e.a].id);
    }
    if (e.kind == b::EventKind::kBallPocket) {
      out->add_pocketed(result->final_state.balls[e.a].id);
      out->add_pockets(e.other >= 0 ? model.spec().pockets[e.other].name : "off_table");
    }
  }
  out->set_events_handled(static_cast<uint64_t>(result->events_handled));
  out->set_t_rest_s(result->t_rest_s);
  if (job.outcome != v1::SHOT_OUTCOME_SUMMARY) {
    for (const b::Ball& ball : result->final_state.balls) BallToProto(model, ball, out->add_balls());
  }
  if (job.outcome == v1::SHOT_OUTCOME_EVENTS) {
    for (const b::Event& e : result->events) {
      EventToProto(model, result->final_state, e, out->add_events());
    }
  }
}

}  // namespace sportsim::server
