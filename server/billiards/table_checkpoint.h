// A billiards table at rest as a journal checkpoint stores it (journal.h): an exact, versioned
// encoding (proto/sportsim/store/v1/table_state.proto) of every member a table holds between
// shots, so that a restore from it continues bit for bit as the uninterrupted table would.
// Pure translation, no gRPC, no lock: the caller copies the members under the table's mutex.
#ifndef SPORTSIM_SERVER_BILLIARDS_TABLE_CHECKPOINT_H_
#define SPORTSIM_SERVER_BILLIARDS_TABLE_CHECKPOINT_H_

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "server/billiards/table_world.h"
#include "sim/billiards/state.h"
#include "sim/games/game.h"

namespace sportsim::server {

/// The version EncodeTableRestState writes, and the only one DecodeTableRestState reads.
inline constexpr uint32_t kTableCheckpointVersion = 1;

/// A table at rest: the world's tick and sequence, and the members of TableKind::Data guarded
/// by its mutex that hold between shots. Not stored, because they hold nothing at rest or are
/// derived: sim, referee, shot_start, shot_events (empty), game_view (made from game), and
/// `current`, which at rest equals last_shot (EndShot copies it).
struct TableRestState {
  int64_t tick = 0;
  uint64_t sequence = 0;
  uint32_t turn = 0;
  billiards::TableState rest;
  ShotSummary last_shot;
  uint64_t shots = 0;
  games::GameState game;
  bool placed = false;
  std::optional<int64_t> clock_deadline;
  std::vector<MatchEntry> record;
};

/// The checkpoint's bytes (a sportsim.store.v1.TableRestState of version
/// kTableCheckpointVersion, ending with the CRC-32C of the bytes before it). Every value is kept
/// exactly: doubles bit for bit (-0.0, NaN payloads), strings byte for byte, optionals with
/// their presence.
std::string EncodeTableRestState(const TableRestState& state);

/// The state EncodeTableRestState encoded. DATA_LOSS when the bytes are damaged or cut short
/// (the checksum), are not such a message, or hold what no encoder writes (an unknown field or
/// enum value, an array of the wrong length, a missing member); INVALID_ARGUMENT for a version
/// other than kTableCheckpointVersion. The message names the field ("table checkpoint:
/// record[3].applied.v: missing"). Never crashes on any input.
absl::StatusOr<TableRestState> DecodeTableRestState(std::string_view bytes);

/// True when a and b hold the same values: doubles compared by their bits (-0.0 differs from
/// 0.0, NaNs by payload), every field of every member. For tests and checks of a restore.
bool SameRestState(const TableRestState& a, const TableRestState& b);

/// The first difference between a and b as a field path and both values ("game.scores[1]: 3 vs
/// 4"), or "" when SameRestState(a, b). For test failure messages.
std::string RestStateDifference(const TableRestState& a, const TableRestState& b);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_BILLIARDS_TABLE_CHECKPOINT_H_
