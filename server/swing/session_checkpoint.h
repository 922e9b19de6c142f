// A swing session at rest as a journal checkpoint stores it (journal.h): an exact, versioned
// encoding (proto/sportsim/store/v1/session_state.proto) of every member a session holds
// between swings, so that a restore from it continues bit for bit as the uninterrupted session
// would. Pure translation, no gRPC, no lock: the caller copies the members under the session's
// mutex. The framing (checksum, version, field paths) is server/world/checkpoint_codec.h's.
#ifndef SPORTSIM_SERVER_SWING_SESSION_CHECKPOINT_H_
#define SPORTSIM_SERVER_SWING_SESSION_CHECKPOINT_H_

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "server/swing/session_world.h"
#include "sim/swing/swing_simulation.h"
#include "sportsim/v1/swing.pb.h"

namespace sportsim::server {

/// The version EncodeSessionRestState writes, and the only one DecodeSessionRestState reads.
inline constexpr uint32_t kSessionCheckpointVersion = 1;

/// A session at rest: the world's tick and sequence, and the members of SessionKind::Data
/// guarded by its mutex that hold between swings. Not stored, because they are derived or hold
/// nothing at rest: model (made again from params and the creation's disabled effects), live
/// and driver (null: no swing in flight, no driver attached).
struct SessionRestState {
  int64_t tick = 0;
  uint64_t sequence = 0;
  v1::SwingParameters params;        ///< as asked (creation, then each reset)
  SessionPhase phase = SessionPhase::kAddress;
  uint64_t swings = 0;
  /// The last swing's start tick and seat: read only while it runs, kept so that a restored
  /// session equals the uninterrupted one member for member.
  int64_t start_tick = 0;
  uint32_t seat = 0;
  swing::SwingSample state;
  double qalpha = 0, qbeta = 0;      ///< (N m)
  std::optional<swing::SwingSample> last_impact;
  std::string last_end_reason;
};

/// The checkpoint's bytes (a sportsim.store.v1.SessionRestState of version
/// kSessionCheckpointVersion, ending with the CRC-32C of the bytes before it). Every value is
/// kept exactly: doubles bit for bit (-0.0, NaN payloads), strings byte for byte, optionals and
/// the parameters' optional fields with their presence.
std::string EncodeSessionRestState(const SessionRestState& state);

/// The state EncodeSessionRestState encoded. DATA_LOSS when the bytes are damaged or cut short
/// (the checksum), are not such a message, or hold what no encoder writes (an unknown field or
/// enum value, parameters that do not parse, a missing member); INVALID_ARGUMENT for a version
/// other than kSessionCheckpointVersion. The message names the field ("session checkpoint:
/// state: missing"). Never crashes on any input.
absl::StatusOr<SessionRestState> DecodeSessionRestState(std::string_view bytes);

/// The first difference between a and b as a field path and both values ("state.beta: ... vs
/// ..."), doubles compared by their bits; "" when they hold the same values. For tests and
/// checks of a restore.
std::string SessionRestStateDifference(const SessionRestState& a, const SessionRestState& b);

/// True when SessionRestStateDifference(a, b) is "".
bool SameSessionRestState(const SessionRestState& a, const SessionRestState& b);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_SWING_SESSION_CHECKPOINT_H_
