// The journal a world host writes every accepted command to before the command takes effect,
// and reads back on start to restore every world. An interface only: server/store/ implements
// it over SQLite (one node) and PostgreSQL (a fleet, with leases). No database here.
//
// What is stored is inputs, never states: physics and referees are deterministic, so a world is
// its creation plus its commands at the ticks they took effect, replayed. A checkpoint (a
// world's state at rest, encoded by its kind) lets a restore start late in a long history; the
// entries it covers may then be dropped.
//
// Time. Each node keeps a clock in world seconds that runs only while the node runs
// (NodeSeconds()). A world records, with every entry, where its tick stood on that clock (the
// anchor); the store persists the node's clock often. A restore puts the world at
// anchor_tick + (node clock last persisted - anchor_seconds) * tick_hz, so that a world's clock
// pauses while no server runs it.
#ifndef SPORTSIM_SERVER_WORLD_JOURNAL_H_
#define SPORTSIM_SERVER_WORLD_JOURNAL_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace sportsim::server {

/// One accepted command.
struct JournalEntry {
  std::string world_id;   ///< "t-..." or "s-..."
  std::string kind;       ///< "table", "session": the kind of world
  uint64_t index = 0;     ///< per world, from 1 (the creation) without gaps
  int64_t tick = 0;       ///< the tick the command took effect at
  int32_t seat = 0;       ///< the seat that asked (-1: the admin)
  uint32_t type = 0;      ///< the kind's command type (the creation is type 0)
  std::string body;       ///< the command as the kind encodes it (never a token in clear)
  double anchor_s = 0.0;  ///< the node's clock (world seconds) when the world was at `tick`
};

/// A world as the store holds it, for a restore.
struct StoredWorld {
  std::string world_id;
  std::string kind;
  uint64_t checkpoint_index = 0;  ///< the last entry the checkpoint covers (0: none)
  int64_t checkpoint_tick = 0;
  std::string checkpoint;         ///< the kind's encoding of the world at rest ("" : none)
  /// Ascending: the creation (index 1, always kept: it holds the seats and the tick rate),
  /// then every entry with index > checkpoint_index.
  std::vector<JournalEntry> entries;
  int64_t anchor_tick = 0;        ///< the world's tick at node clock `anchor_s`
  double anchor_s = 0.0;
  /// The clock of the node that last ran the world, as that node last persisted it (at least
  /// the time it had reached): the world had reached anchor_tick + (clock_s - anchor_s) *
  /// tick_hz ticks when it stopped.
  double clock_s = 0.0;
};

class Journal {
 public:
  virtual ~Journal() = default;

  /// Makes `entry` durable before returning (concurrent appends are committed together).
  /// UNAVAILABLE, naming the reason, when it cannot be made durable (the store is down, full,
  /// read-only, or this node lost its lease); nothing is then stored.
  virtual absl::Status Append(JournalEntry entry) = 0;
  /// The world's last entry (its deletion) and then the world itself leave the store, durably.
  virtual absl::Status Remove(JournalEntry deletion) = 0;
  /// Stores a checkpoint of the world covering its entries up to `index` (which may then be
  /// dropped, all but the creation). Not awaited: a checkpoint is never needed for
  /// correctness, only for speed. Ignored for a world not in the store, or not past an older
  /// checkpoint.
  virtual void Checkpoint(const std::string& world_id, uint64_t index, int64_t tick,
                          std::string state) = 0;
  /// Moves a restored world's anchor to this node's clock (after a restore or a takeover).
  /// Not awaited.
  virtual void Anchor(const std::string& world_id, int64_t tick, double anchor_s) = 0;

  /// The node's clock in world seconds: the clock persisted when the node started, plus the
  /// world seconds run since (wall time times the clock rate).
  virtual double NodeSeconds() const = 0;
  /// OK while commands can be made durable; else UNAVAILABLE with the reason (health reports
  /// NOT_SERVING meanwhile).
  virtual absl::Status Healthy() const = 0;
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_WORLD_JOURNAL_H_
