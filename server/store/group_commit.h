// Group commit, shared by the SQLite and PostgreSQL journals (store.h): one writer thread per
// store owns the database connection. Append and Remove queue their write and block until it is
// durable; the writer takes everything queued at once and commits it in ONE transaction, so
// that 200 tables shooting in the same instant share one fsync, and it gives each waiter its
// own status. Checkpoints and anchors ride along in the next batch, not awaited. Between
// batches the writer persists the node's clock (a tiny transaction, every clock_interval: the
// health probe too) and, for PostgreSQL, renews the lease. Internal to server/store/.
#ifndef SPORTSIM_SERVER_STORE_GROUP_COMMIT_H_
#define SPORTSIM_SERVER_STORE_GROUP_COMMIT_H_

#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "server/world/journal.h"

namespace sportsim::server::store {

/// One write of the journal, as queued for the writer.
struct JournalOp {
  enum class Type {
    kAppend,      ///< `entry` (index 1 creates the world); awaited
    kRemove,      ///< `entry` is the deletion: the world, its entries and checkpoint go; awaited
    kCheckpoint,  ///< entry.world_id, .index, .tick, and the state in .body; not awaited
    kAnchor,      ///< entry.world_id, .tick, .anchor_s; not awaited
  };
  Type type = Type::kAppend;
  JournalEntry entry;
};

/// What a backend does for the writer. Called on the writer thread only (one at a time), so a
/// backend needs no lock of its own around its connection.
class CommitBackend {
 public:
  virtual ~CommitBackend() = default;
  /// Applies `ops` (in order) in one transaction and commits it durably. An error means nothing
  /// of the batch is stored, and it becomes every waiter's status (UNAVAILABLE naming the
  /// reason). On OK, `results` (one per op, OK on entry) holds each op's own outcome: an op
  /// refused by a check of its own (its world belongs to another node, an index out of turn)
  /// changed nothing, and every other op is durable.
  virtual absl::Status CommitBatch(const std::vector<const JournalOp*>& ops,
                                   std::vector<absl::Status>* results) = 0;
  /// Persists the node's clock (world seconds) in a transaction of its own; with `renew`, also
  /// renews the lease (PostgreSQL).
  virtual absl::Status PersistClock(double clock_s, bool renew) = 0;
  /// A failure no retry can mend (PostgreSQL: this node lost its lease), else OK. Once not OK,
  /// every later write fails with it at once.
  virtual absl::Status Fatal() const = 0;
};

struct GroupCommitOptions {
  std::string name;         ///< the store as Describe() names it, for messages
  double clock0_s = 0.0;    ///< the node's clock as persisted before this start
  double clock_rate = 1.0;  ///< world seconds per wall second
  absl::Duration clock_interval = absl::Milliseconds(100);
  absl::Duration renew_interval = absl::InfiniteDuration();  ///< lease renewals (PostgreSQL)
};

/// Counters, for tests and benchmarks.
struct GroupCommitStats {
  int64_t batches = 0;         ///< write transactions committed
  int64_t ops = 0;             ///< writes in them (refused ones included)
  int64_t failed_batches = 0;  ///< write transactions that failed (nothing stored)
  int64_t clock_persists = 0;  ///< clock transactions committed
};

class GroupCommit {
 public:
  /// Starts the writer over `backend` (not owned; it must outlive Close()). The clock is
  /// persisted at once, then every clock_interval.
  GroupCommit(CommitBackend* backend, GroupCommitOptions options);
  ~GroupCommit();  ///< Close()s
  GroupCommit(const GroupCommit&) = delete;
  GroupCommit& operator=(const GroupCommit&) = delete;

  /// Queues `op` and waits until the batch it joined committed: its own status (UNAVAILABLE
  /// when the batch failed, the store is closed, or Fatal() is set).
  absl::Status Write(JournalOp op);
  /// Queues `op` without waiting. It commits no later than the batch of any Write queued after
  /// it; dropped once closed or fatal, or when its batch fails.
  void Post(JournalOp op);
  /// Runs `job` on the writer thread between batches and returns its status (a read, or a
  /// transaction of the backend's own such as Adopt). UNAVAILABLE once closed.
  absl::Status Run(std::function<absl::Status()> job);

  /// The node's clock: clock0_s plus the wall seconds since the start times the clock rate.
  double NodeSeconds() const;
  /// OK after the last transaction (a batch or the clock's) committed; else UNAVAILABLE with
  /// its reason, for good once the backend's Fatal() is set.
  absl::Status Healthy() const;
  GroupCommitStats stats() const;

  /// Test hook: no more clock persists or lease renewals (a node that hangs, for its lease to
  /// lapse); writes still go through.
  void StopClockForTesting();

  /// Commits what is queued, persists the clock a last time (the clock the node reached, not a
  /// promise beyond it), and stops the writer. Later writes are UNAVAILABLE. Idempotent.
  void Close();

 private:
  /// One queued write; `waiter` is null for a posted one.
  struct Waiter {
    absl::Status status;
    bool done = false;
  };
  struct Queued {
    JournalOp op;
    Waiter* waiter = nullptr;
  };
  struct Job {
    std::function<absl::Status()> fn;
    Waiter* waiter = nullptr;
  };

  void Loop();
  /// Commits `batch` and hands out the statuses.
  void CommitBatch(std::deque<Queued>* batch);
  /// Persists the clock: `final` persists NodeSeconds() itself (at Close), else the promise
  /// NodeSeconds() + 2 clock_interval x clock_rate.
  void PersistClock(bool renew, bool final);
  /// Records the outcome of a transaction for Healthy().
  void SetHealth(const absl::Status& status) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  CommitBackend* const backend_;
  const GroupCommitOptions options_;
  const std::chrono::steady_clock::time_point start_;

  mutable absl::Mutex mu_;
  absl::CondVar work_;  ///< the writer waits here for writes, jobs or closing
  absl::CondVar done_;  ///< waiters wait here for their batch
  std::deque<Queued> queue_ ABSL_GUARDED_BY(mu_);
  std::deque<Job> jobs_ ABSL_GUARDED_BY(mu_);
  bool closing_ ABSL_GUARDED_BY(mu_) = false;
  bool closed_ ABSL_GUARDED_BY(mu_) = false;
  bool clock_stopped_ ABSL_GUARDED_BY(mu_) = false;
  absl::Status health_ ABSL_GUARDED_BY(mu_);
  absl::Status fatal_ ABSL_GUARDED_BY(mu_);
  GroupCommitStats stats_ ABSL_GUARDED_BY(mu_);
  std::thread writer_;
};

}  // namespace sportsim::server::store

#endif  // SPORTSIM_SERVER_STORE_GROUP_COMMIT_H_
