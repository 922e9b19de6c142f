// sportsim.v1 billiards messages <-> sim/billiards types. Pure translation, tested without a
// network. Error messages name the proto field ("table.rack", "strike.a", "solver.dt_s").
#ifndef SPORTSIM_SERVER_BILLIARDS_CONVERT_H_
#define SPORTSIM_SERVER_BILLIARDS_CONVERT_H_

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "sim/billiards/cue.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/model.h"
#include "sim/billiards/shot.h"
#include "sim/billiards/state.h"
#include "sportsim/v1/billiards.pb.h"
#include "sportsim/v1/common.pb.h"

namespace sportsim::server {

struct ShotSummary;  // table_world.h

/// A table's shot summary as the API's message.
void ShotSummaryToProto(const ShotSummary& s, v1::ShotSummary* out);

/// Most balls a table may hold (snooker has 22).
inline constexpr int kMaxBalls = 64;

/// A table built from a TableSetup: model and balls at rest.
struct TableBuild {
  billiards::TableModel model;
  billiards::TableState state;
  std::string rack;  ///< the rack used (after defaulting)
};
absl::StatusOr<TableBuild> TableFromProto(const v1::TableSetup& setup);

absl::StatusOr<billiards::SolverOptions> SolverFromProto(const v1::SolverConfig& solver);
absl::StatusOr<billiards::CueStrike> StrikeFromProto(const v1::CueStrike& strike);
/// The inverse (no ball, noise or seed: the caller names the ball).
void StrikeToProto(const billiards::CueStrike& strike, v1::CueStrike* out);

/// Everything a SimulateShotRequest asks for, validated, with the shot already applied to the
/// state (strike or explicit motions).
struct ShotJob {
  TableBuild table;
  billiards::SolverOptions solver;
  billiards::ShotOptions shot;
  std::optional<billiards::StrikeOutcome> strike;
  bool include_geometry = false;
};
absl::StatusOr<ShotJob> ShotJobFromProto(const v1::SimulateShotRequest& request);

/// Bounds what a shot may build before it runs: its samples (samples x balls) and events stay
/// within `max_reply_bytes` (the run stops with RESOURCE_EXHAUSTED, naming sample_rate_hz,
/// when it would pass them), and the stepped engine's step count is refused above 1e9 steps
/// (INVALID_ARGUMENT naming max_time_s and solver.dt_s).
absl::Status BoundShotWork(int64_t max_reply_bytes, ShotJob* job);

v1::MotionState MotionStateToProto(billiards::MotionState s);
void BallToProto(const billiards::TableModel& model, const billiards::Ball& ball,
                 v1::BallState* out);
void EventToProto(const billiards::TableModel& model, const billiards::TableState& state,
                  const billiards::Event& event, v1::TableEvent* out);
void GeometryToProto(const billiards::TableModel& model, v1::TableGeometry* out);
void StrikeReportToProto(const billiards::StrikeOutcome& strike, v1::StrikeReport* out);
void ShotResultToProto(const ShotJob& job, const billiards::ShotResult& result,
                       v1::SimulateShotResponse* out);

/// GetInfo: the billiards parameters (with the pool-9ft defaults), effects, presets, racks.
void AddBilliardsCapabilities(v1::Capabilities* caps);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_BILLIARDS_CONVERT_H_
