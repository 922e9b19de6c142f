// What every authoritative world (billiards table, swing session) has in common besides the
// scheduler and the watchers: seats with secret tokens, and a tick clock. No gRPC here
// (protobuf only, for the Seat message).
#ifndef SPORTSIM_SERVER_WORLD_H_
#define SPORTSIM_SERVER_WORLD_H_

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "google/protobuf/repeated_field.h"
#include "sportsim/v1/common.pb.h"

namespace sportsim::server {

using SteadyClock = std::chrono::steady_clock;

/// The same status with its message prefixed by the proto path it concerns ("table.rack: ",
/// "solver."); OK stays OK.
absl::Status PrefixStatus(std::string_view prefix, const absl::Status& s);

/// OK for a client-given id (ball, seat name) of 1 to 32 characters, each a letter, a digit,
/// '.', '_' or '-'; else InvalidArgument naming `field` and quoting at most a short prefix.
absl::Status CheckId(std::string_view field, const std::string& id);

/// At most the first 24 bytes of `value`, printable ASCII only, for quoting client input in an
/// error message (never the whole input: messages travel in gRPC's metadata).
std::string Quote(std::string_view value);

/// The seed of item n (a shot, a noise sample) from a secret or batch seed: SplitMix64's
/// finalizer (Steele, Lea & Flood, "Fast splittable pseudorandom number generators", OOPSLA
/// 2014) over seed + n * golden ratio, so that consecutive items get unrelated seeds.
uint64_t DeriveSeed(uint64_t seed, uint64_t n);

/// `bytes` random bytes as lower-case hex, from std::random_device.
std::string RandomHex(int bytes);

/// A token must be 1 to 128 characters, else PERMISSION_DENIED like any wrong token (`what`:
/// "CreateTable", "CreateSession", named in the message).
absl::Status CheckToken(const std::string& token, std::string_view what);

/// SHA-256 of a token (32 bytes). A world keeps only these, in memory and in the journal, so
/// that a copy of either hands out no seat. Tokens the server makes carry 128 random bits, so a
/// fast hash without salt is enough (a password hash exists to slow down guessing low-entropy
/// secrets; 2^128 guesses are out of reach at any speed).
std::string HashToken(std::string_view token);

struct SeatEntry {
  std::string name;
  std::string token_hash;  ///< HashToken of the seat's token (128 random bits, hex)
};

/// Seats for a create request: `count` (0: the number of names, or `default_count`) seats in
/// [1, 16], each with a fresh token, named `names` (1 to 32 characters each) or "0", "1", ...
/// The tokens themselves go to `tokens` (for the creator's reply only).
absl::StatusOr<std::vector<SeatEntry>> MakeSeats(
    uint32_t count, const google::protobuf::RepeatedPtrField<std::string>& names,
    int default_count, std::vector<std::string>* tokens);

/// The seats as protos, with their tokens when `tokens` is given (the creator's reply).
void SeatsToProto(const std::vector<SeatEntry>& seats, const std::vector<std::string>* tokens,
                  google::protobuf::RepeatedPtrField<v1::Seat>* out);

/// `given_hash` equals `secret_hash`, compared in time that depends only on the secret's length.
bool TokensEqual(const std::string& secret_hash, const std::string& given_hash);

/// The seat whose token hashes to `token_hash` (HashToken), or -1. Compares every seat in full
/// (no early exit).
int SeatOf(const std::vector<SeatEntry>& seats, const std::string& token_hash);

/// Tick k of a world falls due at origin + k / tick_hz on the monotonic clock.
struct TickClock {
  SteadyClock::time_point origin;  ///< tick 0 (moves on when the world slips)
  double tick_hz = 1.0;

  SteadyClock::time_point Deadline(int64_t k) const;
  /// The last tick whose deadline has passed.
  int64_t DueTick(SteadyClock::time_point now) const;
  /// The tick the clock is at, never below `floor`.
  int64_t Tick(SteadyClock::time_point now, int64_t floor) const;
  /// The tick to advance to from `done` when `due` is due: `due`, or if that is more than
  /// `max_catchup` ticks ahead, `done + max_catchup` with the origin moved on so that the world
  /// runs slower than real time for a moment instead of spending ever more ticks being late.
  /// `slipped` gets the ticks skipped that way.
  int64_t CatchUp(int64_t done, int64_t due, int max_catchup, int64_t* slipped);
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_WORLD_H_
