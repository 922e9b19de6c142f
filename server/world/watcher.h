// The snapshot fan-out shared by every kind of authoritative world (billiards tables, swing
// sessions): one Watcher per reader holds the newest unsent frame (latest wins) and every unsent
// event, and writes through a StreamSink with at most one write in flight. No gRPC here: the
// sink is a gRPC reactor in services.cc, or a fake in tests.
//
// A world kind supplies Traits:
//   using Frame = ...;     // shared by every watcher; has `uint64_t sequence`, `bool heartbeat`,
//                          // `SteadyClock::time_point published`
//   using Event = ...;     // a proto message with sequence()
//   using Snapshot = ...;  // a proto message with add_events(), set_sequence(), set_resync(),
//                          // set_events_lost(), set_snapshots_replaced()
//   using Options = ...;   // the reader's choices (fields, changed_only, ...)
//   static void Fill(const Options&, const std::string& id, const Frame& frame,
//                    const Frame* last_sent, bool full, Snapshot* out);
//     writes the frame's part of a snapshot; `full`: send everything, not only what changed
//     since `last_sent` (a resync, or the first snapshot).
// The member definitions are in watcher_impl.h, instantiated once per kind in its .cc file.
#ifndef SPORTSIM_SERVER_WATCHER_H_
#define SPORTSIM_SERVER_WATCHER_H_

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"

namespace sportsim::server {

using SteadyClock = std::chrono::steady_clock;

/// Where a watcher's snapshots go. At most one write is in flight: the owner calls
/// Watcher::OnWriteDone when it completes. After SinkFinish or SinkWriteLast nothing more comes.
template <typename Snapshot>
class StreamSink {
 public:
  virtual ~StreamSink() = default;
  virtual void SinkWrite(const Snapshot* snapshot) = 0;
  virtual void SinkWriteLast(const Snapshot* snapshot, const absl::Status& status) = 0;
  virtual void SinkFinish(const absl::Status& status) = 0;
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
  /// The upper edge of bucket i (seconds).
  static double UpperEdge(int i);
  std::vector<int64_t> Counts() const;
  /// The sum of what was added (seconds), for Prometheus' _sum.
  double Sum() const { return static_cast<double>(sum_ns_.load(std::memory_order_relaxed)) * 1e-9; }

 private:
  std::array<std::atomic<int64_t>, kBuckets> counts_{};
  std::atomic<int64_t> sum_ns_{0};
};

/// Totals over every watcher of a registry.
struct WatchCounters {
  std::atomic<int64_t> sent{0}, replaced{0}, resyncs{0};
  LatencyHistogram publish_to_write;  ///< from the tick's deadline to the start of its write
};

/// One reader of a world. Thread safe; see StreamSink for the write protocol.
template <typename Traits>
class BasicWatcher {
 public:
  using Frame = typename Traits::Frame;
  using Event = typename Traits::Event;
  using Snapshot = typename Traits::Snapshot;
  using Options = typename Traits::Options;
  using EventPtr = std::shared_ptr<const Event>;
  using Sink = StreamSink<Snapshot>;

  /// `interval_ticks`: ticks between snapshots (tick rate / reader's rate, >= 1); `backlog`:
  /// unsent events past which the reader is resynced instead.
  BasicWatcher(std::string id, Options options, double interval_ticks, int backlog,
               std::shared_ptr<WatchCounters> counters = nullptr);

  void Attach(Sink* sink);
  /// World side. Queues events and, if given, a frame (replacing an unsent one). Returns true
  /// when the caller should Pump (no write in flight).
  bool Offer(std::shared_ptr<const Frame> frame, const std::vector<EventPtr>& events);
  /// A heartbeat: only when nothing else is pending.
  bool OfferHeartbeat(std::shared_ptr<const Frame> frame);
  /// Marks the reader as resynced (events after its resume point are gone).
  void MarkResync();
  /// The rate: true when tick k is due (and consumes it).
  bool Due(int64_t tick);
  /// Ends the stream after one last frame (world deleted, server stopping, stream done).
  bool Close(const absl::Status& status, std::shared_ptr<const Frame> last);

  /// Sink side, with no lock held: writes what is pending, or finishes.
  void Pump();
  void OnWriteDone(bool ok);
  void OnCancel();
  void OnDone();

  int64_t sent() const;
  int64_t replaced() const;
  bool closed() const;
  const std::string& id() const { return id_; }

 private:
  void Build(Snapshot* out) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  const std::string id_;
  const Options options_;
  const double interval_ticks_;
  const int backlog_;
  const std::shared_ptr<WatchCounters> counters_;
  mutable absl::Mutex mu_;
  Sink* sink_ ABSL_GUARDED_BY(mu_) = nullptr;
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
  Snapshot out_;  // written only when no write is in flight
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_WATCHER_H_
