// Authoritative billiards tables: the registry, the fixed-rate scheduler and the snapshot
// fan-out to watchers. No gRPC here: a watcher writes through a SnapshotSink (the gRPC reactor in
// services.cc, a fake in tests). docs/server.md describes the design.
//
// Time. Tick k of a table is due at origin + k / tick_hz on the monotonic clock. A shot struck
// at tick s is simulated in its own time from 0, and tick k advances it to (k - s) / tick_hz
// (for the stepped engine, to a whole number of steps), so a shot's states never depend on the
// load or on when the worker got to the table: the same strike gives the same bits as
// SimulateShot. A table at rest is not scheduled; its tick is read off the clock when asked.
//
// Locks: Registry::mu_ -> Table::mu -> Watcher::mu_ -> Registry::sched_mu_ (never the other
// way). Sinks are only called with no lock held.
#ifndef SPORTSIM_SERVER_TABLES_H_
#define SPORTSIM_SERVER_TABLES_H_

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <queue>
#include <string>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"
#include "sportsim/v1/billiards.pb.h"

namespace sportsim::server {

using SteadyClock = std::chrono::steady_clock;

struct TableLimits {
  int max_tables = 2000;
  int max_watchers_per_table = 64;
  int event_log = 512;            ///< events a table holds for resuming watchers
  int watcher_backlog = 1024;     ///< events a watcher may have unsent before it is resynced
  int workers = 0;                ///< tick threads; 0: one per core
  int max_catchup_ticks = 12;     ///< a table further behind slips instead of racing
  absl::Duration heartbeat = absl::Seconds(1);
  double max_shot_s = 600.0;      ///< simulated time after which a shot is stopped
};

/// Counters for the load generator, metrics and tests (monotonic totals).
struct TableStats {
  int64_t ticks = 0;           ///< table ticks advanced
  int64_t late_ticks = 0;      ///< advanced more than one period after their deadline
  int64_t slipped_ticks = 0;   ///< never advanced on time: the catch-up cap moved the table's
                               ///< clock on instead (not counted in ticks or late_ticks)
  int64_t snapshots_sent = 0;
  int64_t snapshots_replaced = 0;  ///< latest wins: offered but overtaken before being sent
  int64_t resyncs = 0;
  int64_t events = 0;          ///< table events produced
  int64_t tick_cpu_ns = 0;     ///< thread CPU time the workers spent on tables
  int tables = 0;
  int moving = 0;
  int watchers = 0;
};

/// The state of a table at one tick, shared by every watcher that sends it.
struct Frame {
  uint64_t sequence = 0;
  int64_t tick = 0;
  double t_s = 0.0;
  bool at_rest = true;
  bool heartbeat = false;
  uint32_t turn = 0;
  uint64_t shot_id = 0;
  std::shared_ptr<const billiards::TableModel> model;
  std::vector<billiards::Ball> balls;
  SteadyClock::time_point published;  ///< when the tick was due, or when a call made it
                                      ///< (the start of publish-to-write latency)
};

using EventPtr = std::shared_ptr<const v1::TableEvent>;

/// Where a watcher's snapshots go. At most one write is in flight: the owner calls
/// Watcher::OnWriteDone when it completes. After SinkFinish or SinkWriteLast nothing more comes.
class SnapshotSink {
 public:
  virtual ~SnapshotSink() = default;
  virtual void SinkWrite(const v1::TableSnapshot* snapshot) = 0;
  virtual void SinkWriteLast(const v1::TableSnapshot* snapshot, const absl::Status& status) = 0;
  virtual void SinkFinish(const absl::Status& status) = 0;
};

struct WatchOptions {
  double interval_ticks = 1.0;  ///< tick_hz / rate_hz, >= 1
  bool position = true, velocity = true, spin = true, orientation = true;
  bool changed_only = false;
  int backlog = 1024;
};

/// A lock-free histogram of durations: bucket i holds [2^(i/4), 2^((i+1)/4)) microseconds
/// (about 19 % wide), from 1 us to 2^32 us.
class LatencyHistogram {
 public:
  static constexpr int kBuckets = 128;
  void Add(std::chrono::nanoseconds d);
  /// The upper edge of the bucket holding quantile q of what was added (seconds); 0 if empty.
  /// `since` subtracts an earlier copy, for a window.
  double Quantile(double q, const std::vector<int64_t>& since = {}) const;
  /// The same over bucket counts (e.g. a window: later Counts() minus earlier ones).
  static double QuantileOf(const std::vector<int64_t>& counts, double q);
  std::vector<int64_t> Counts() const;

 private:
  std::array<std::atomic<int64_t>, kBuckets> counts_{};
};

/// Totals over every watcher of a registry.
struct WatchCounters {
  std::atomic<int64_t> sent{0}, replaced{0}, resyncs{0};
  LatencyHistogram publish_to_write;  ///< from the tick's deadline to the start of its write
};

/// One reader of a table: the newest unsent frame (latest wins) and every unsent event. Thread
/// safe; see SnapshotSink for the write protocol.
class Watcher {
 public:
  Watcher(std::string table_id, WatchOptions options,
          std::shared_ptr<WatchCounters> counters = nullptr);

  void Attach(SnapshotSink* sink);
  /// Table side. Queues events and, if given, a frame (replacing an unsent one). Returns true
  /// when the caller should Pump (no write in flight).
  bool Offer(std::shared_ptr<const Frame> frame, const std::vector<EventPtr>& events);
  /// A heartbeat: only when nothing else is pending.
  bool OfferHeartbeat(std::shared_ptr<const Frame> frame);
  /// Marks the reader as resynced (events after its resume point are gone).
  void MarkResync();
  /// The rate: true when tick k is due (and consumes it).
  bool Due(int64_t tick);
  /// Ends the stream after one last frame (table deleted, server stopping).
  bool Close(const absl::Status& status, std::shared_ptr<const Frame> last);

  /// Sink side, with no lock held: writes what is pending, or finishes.
  void Pump();
  void OnWriteDone(bool ok);
  void OnCancel();
  void OnDone();

  int64_t sent() const;
  int64_t replaced() const;
  bool closed() const;

 private:
  void Build(v1::TableSnapshot* out) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  const std::string table_id_;
  const WatchOptions options_;
  const std::shared_ptr<WatchCounters> counters_;
  mutable absl::Mutex mu_;
  SnapshotSink* sink_ ABSL_GUARDED_BY(mu_) = nullptr;
  double next_due_ ABSL_GUARDED_BY(mu_) = 0.0;
  std::shared_ptr<const Frame> pending_ ABSL_GUARDED_BY(mu_);
  std::vector<EventPtr> events_ ABSL_GUARDED_BY(mu_);
  std::shared_ptr<const Frame> last_sent_ ABSL_GUARDED_BY(mu_);
  uint64_t last_sequence_ ABSL_GUARDED_BY(mu_) = 0;
  bool resync_ ABSL_GUARDED_BY(mu_) = false;
  uint64_t lost_ ABSL_GUARDED_BY(mu_) = 0;
  bool in_flight_ ABSL_GUARDED_BY(mu_) = false;
  bool finished_ ABSL_GUARDED_BY(mu_) = false;
  bool cancelled_ ABSL_GUARDED_BY(mu_) = false;
  bool closing_ ABSL_GUARDED_BY(mu_) = false;
  absl::Status close_status_ ABSL_GUARDED_BY(mu_);
  int64_t sent_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t replaced_ ABSL_GUARDED_BY(mu_) = 0;
  v1::TableSnapshot out_;  // written only when no write is in flight
};

struct Table;

/// Every table of the server, and the threads that tick them.
class TableRegistry {
 public:
  explicit TableRegistry(TableLimits limits);
  ~TableRegistry();
  TableRegistry(const TableRegistry&) = delete;
  TableRegistry& operator=(const TableRegistry&) = delete;

  absl::StatusOr<v1::CreateTableResponse> Create(const v1::CreateTableRequest& request);
  absl::StatusOr<v1::TableInfo> Get(const v1::GetTableRequest& request);
  absl::StatusOr<v1::ListTablesResponse> List(const v1::ListTablesRequest& request);
  absl::Status Delete(const v1::DeleteTableRequest& request);
  absl::StatusOr<v1::ResetTableResponse> Reset(const v1::ResetTableRequest& request);
  absl::StatusOr<v1::PlaceBallResponse> Place(const v1::PlaceBallRequest& request);
  absl::StatusOr<v1::ShootResponse> Shoot(const v1::ShootRequest& request);
  absl::StatusOr<v1::SetTurnResponse> SetTurn(const v1::SetTurnRequest& request);

  /// Registers a watcher writing to `sink` and queues its first snapshot; the caller then calls
  /// Pump() on it. Errors change nothing.
  absl::StatusOr<std::shared_ptr<Watcher>> Watch(const v1::WatchTableRequest& request,
                                                 SnapshotSink* sink);
  /// Forgets a watcher whose stream is done.
  void Unwatch(const std::string& table_id, const Watcher* watcher);

  /// Stops the tick threads and ends every stream with `status` after a last snapshot.
  /// Afterwards every call fails with UNAVAILABLE. Idempotent.
  void Shutdown(const absl::Status& status);

  TableStats stats() const;
  const LatencyHistogram& publish_to_write() const { return counters_->publish_to_write; }

 private:
  struct Wake {
    SteadyClock::time_point when;
    uint64_t generation;
    std::shared_ptr<Table> table;
    bool operator>(const Wake& o) const { return when > o.when; }
  };

  absl::StatusOr<std::shared_ptr<Table>> Find(const std::string& id);
  template <typename Response, typename Fn>
  absl::StatusOr<Response> Act(const std::string& table_id, const std::string& token,
                               bool to_play, Fn fn);
  /// Wakes a worker for `t` at `when`, superseding its previous wake. Call with t.mu held.
  void Schedule(Table& t, const std::shared_ptr<Table>& ptr, SteadyClock::time_point when)
      ABSL_LOCKS_EXCLUDED(sched_mu_);
  void WorkerLoop();
  void Process(const std::shared_ptr<Table>& table, uint64_t generation,
               SteadyClock::time_point now);

  const TableLimits limits_;
  const std::shared_ptr<WatchCounters> counters_;
  mutable absl::Mutex mu_;
  std::map<std::string, std::shared_ptr<Table>, std::less<>> tables_ ABSL_GUARDED_BY(mu_);
  bool shut_down_ ABSL_GUARDED_BY(mu_) = false;

  absl::Mutex sched_mu_;
  absl::CondVar sched_cv_;
  std::priority_queue<Wake, std::vector<Wake>, std::greater<>> wakes_ ABSL_GUARDED_BY(sched_mu_);
  bool stopping_ ABSL_GUARDED_BY(sched_mu_) = false;
  std::vector<std::thread> workers_;

  std::atomic<int64_t> ticks_{0}, late_ticks_{0}, slipped_ticks_{0}, events_{0}, tick_cpu_ns_{0};
  std::atomic<int> moving_{0};
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_TABLES_H_
