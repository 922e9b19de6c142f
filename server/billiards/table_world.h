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
// Locks: Registry::mu_ -> Table::mu -> Watcher::mu_ -> TickScheduler::mu_ (never the other
// way). Sinks are only called with no lock held.
#ifndef SPORTSIM_SERVER_TABLES_H_
#define SPORTSIM_SERVER_TABLES_H_

#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "server/world/scheduler.h"
#include "server/world/watcher.h"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"
#include "sportsim/v1/billiards.pb.h"

namespace sportsim::server {

struct TableLimits {
  int max_tables = 2000;
  int max_watchers_per_table = 64;
  int event_log = 512;            ///< events a table holds for resuming watchers
  int watcher_backlog = 1024;     ///< events a watcher may have unsent before it is resynced
  int workers = 0;                ///< tick threads when the registry has its own scheduler;
                                  ///< 0: one per core
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
  int64_t tick_cpu_ns = 0;     ///< thread CPU time the scheduler's workers spent (on every
                               ///< kind of world they tick)
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

/// What a table's reader asked for.
struct WatchOptions {
  bool position = true, velocity = true, spin = true, orientation = true;
  bool changed_only = false;
};

/// The table kind of BasicWatcher (watcher.h).
struct TableWatch {
  using Frame = server::Frame;
  using Event = v1::TableEvent;
  using Snapshot = v1::TableSnapshot;
  using Options = WatchOptions;
  static void Fill(const WatchOptions& options, const std::string& table_id, const Frame& frame,
                   const Frame* last_sent, bool full, v1::TableSnapshot* out);
};

using Watcher = BasicWatcher<TableWatch>;
using SnapshotSink = StreamSink<v1::TableSnapshot>;
using EventPtr = Watcher::EventPtr;

struct Table;

/// Every table of the server. Ticks run on `scheduler` (shared with the other kinds of world;
/// its owner stops it before destroying the registry), or on a scheduler of the registry's own
/// with limits.workers threads.
class TableRegistry {
 public:
  explicit TableRegistry(TableLimits limits, TickScheduler* scheduler = nullptr);
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
  /// Pump() on it. With a null sink, the caller Attach()es one before pumping (nothing is
  /// written until then). Errors change nothing.
  absl::StatusOr<std::shared_ptr<Watcher>> Watch(const v1::WatchTableRequest& request,
                                                 SnapshotSink* sink);
  /// Forgets a watcher whose stream is done.
  void Unwatch(const std::string& table_id, const Watcher* watcher);

  /// Ends every stream with `status` after a last snapshot and stops ticking (stops its own
  /// scheduler, if it has one). Afterwards every call fails with UNAVAILABLE. Idempotent.
  void Shutdown(const absl::Status& status);

  TableStats stats() const;
  const LatencyHistogram& publish_to_write() const { return counters_->publish_to_write; }

 private:
  friend struct Table;
  absl::StatusOr<std::shared_ptr<Table>> Find(const std::string& id);
  template <typename Response, typename Fn>
  absl::StatusOr<Response> Act(const std::string& table_id, const std::string& token,
                               bool to_play, Fn fn);
  /// Wakes a worker for `t` at `when`, superseding its previous wake. Call with t.mu held.
  void Schedule(Table& t, const std::shared_ptr<Table>& ptr, SteadyClock::time_point when);
  void Process(const std::shared_ptr<Table>& table, uint64_t generation,
               SteadyClock::time_point now);

  const TableLimits limits_;
  const std::shared_ptr<WatchCounters> counters_;
  mutable absl::Mutex mu_;
  std::map<std::string, std::shared_ptr<Table>, std::less<>> tables_ ABSL_GUARDED_BY(mu_);
  bool shut_down_ ABSL_GUARDED_BY(mu_) = false;

  std::unique_ptr<TickScheduler> own_scheduler_;
  TickScheduler* scheduler_;

  std::atomic<int64_t> ticks_{0}, late_ticks_{0}, slipped_ticks_{0}, events_{0};
  std::atomic<int> moving_{0};
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_TABLES_H_
