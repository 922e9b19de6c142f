// Durable journals: the Journal interface (server/world/journal.h) over SQLite (one node, a
// data directory) or PostgreSQL (a fleet of nodes with leases). No gRPC here.
//
// Both commit in groups (group_commit.h): one writer thread per store; an Append or Remove
// waits for the transaction it joined, and every write queued meanwhile shares it (one fsync).
// An append out of turn (a gap or a duplicate index) is refused with INTERNAL and changes
// nothing; an append to a world that another node now owns, UNAVAILABLE naming that node.
// The node's clock is persisted every clock_interval as a promise (NodeSeconds() + 2 x
// clock_interval x clock_rate), and exactly at Close(); the next Open resumes from it, so the
// clock never goes back across runs. Healthy() follows the last transaction (a batch or a
// clock persist).
#ifndef SPORTSIM_SERVER_STORE_STORE_H_
#define SPORTSIM_SERVER_STORE_STORE_H_

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "server/world/journal.h"

namespace sportsim::server::store {

struct StoreOptions {
  /// SQLite: the data directory (created if missing; holds journal.db and a lock file).
  std::string data_dir;
  /// PostgreSQL: a libpq connection URI ("postgresql://user@host:port/db"); when set, data_dir
  /// is ignored.
  std::string postgres_uri;
  /// PostgreSQL: this node's name (its lease and its worlds).
  std::string node = "local";
  /// PostgreSQL: how long a lease lasts without renewal; renewed every lease / 3.
  absl::Duration lease = absl::Seconds(10);
  /// World seconds per wall second (the server's --clock_rate), for NodeSeconds().
  double clock_rate = 1.0;
  /// How often the node's clock is persisted.
  absl::Duration clock_interval = absl::Milliseconds(100);
};

/// What a store has done since it opened (monotonic counters).
struct StoreStats {
  int64_t batches = 0;         ///< write transactions committed (each one fsync)
  int64_t ops = 0;             ///< writes committed in them
  int64_t failed_batches = 0;  ///< write transactions that failed (nothing of them stored)
  int64_t clock_persists = 0;  ///< clock transactions committed
};

class Store : public Journal {
 public:
  /// Opens (creating the schema if needed) the store named by `options`: a clear
  /// FAILED_PRECONDITION / UNAVAILABLE naming the path or the server when it cannot (an
  /// unwritable or full directory, a second server on the same directory, a database that does
  /// not answer). PostgreSQL: takes this node's lease, bumping its epoch (a previous process of
  /// the same node can no longer write).
  static absl::StatusOr<std::unique_ptr<Store>> Open(const StoreOptions& options);

  /// This node's worlds, for the restore at start.
  virtual absl::StatusOr<std::vector<StoredWorld>> Load() = 0;
  /// PostgreSQL: takes over the worlds of every other node whose lease lapsed (their epochs are
  /// bumped in the same transaction, so those nodes can no longer write) and returns them.
  /// SQLite: none.
  virtual absl::StatusOr<std::vector<StoredWorld>> Adopt() = 0;
  /// Its counters, for /metrics.
  virtual StoreStats stats() const = 0;
  /// "sqlite:DIR/journal.db" or "postgresql:host:port/db node NAME" (no password), for logs.
  virtual std::string Describe() const = 0;
  /// Stops the background threads after committing what is queued and persisting the clock
  /// the node reached; later writes are UNAVAILABLE. SQLite: the data directory is released.
  /// Idempotent; the destructor calls it.
  virtual void Close() = 0;
};

}  // namespace sportsim::server::store

#endif  // SPORTSIM_SERVER_STORE_STORE_H_
