// The fixed-rate machinery every authoritative world shares: a pool of worker threads and one
// min-heap of wake-ups. A world (a billiards table, a swing session) asks to be woken at a time;
// a worker calls it back then. A later request supersedes an earlier one through a generation
// number the world keeps, so stale wakes cost one comparison. No gRPC here.
#ifndef SPORTSIM_SERVER_SCHEDULER_H_
#define SPORTSIM_SERVER_SCHEDULER_H_

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <queue>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"
#include "server/world/watcher.h"

namespace sportsim::server {

/// Something a worker wakes: the world's own lock and bookkeeping are its business.
class Ticked {
 public:
  virtual ~Ticked() = default;
  /// On a worker thread, with no scheduler lock held. `generation` is the one passed to
  /// Schedule; the world ignores the wake if it has scheduled another since.
  virtual void Wake(uint64_t generation, std::chrono::steady_clock::time_point now) = 0;
};

class TickScheduler {
 public:
  /// `workers` threads; 0: one per core.
  explicit TickScheduler(int workers);
  ~TickScheduler();  ///< Stop()s
  TickScheduler(const TickScheduler&) = delete;
  TickScheduler& operator=(const TickScheduler&) = delete;

  /// Wakes `target` at `when` (or as soon as a worker is free after it). Ignored once stopped.
  void Schedule(std::shared_ptr<Ticked> target, uint64_t generation,
                std::chrono::steady_clock::time_point when) ABSL_LOCKS_EXCLUDED(mu_);
  /// Joins the workers (a wake in progress finishes) and drops every pending wake. Idempotent.
  void Stop() ABSL_LOCKS_EXCLUDED(mu_);

  /// Thread CPU time the workers spent in Wake calls (ns).
  int64_t cpu_ns() const { return cpu_ns_.load(std::memory_order_relaxed); }
  int workers() const { return static_cast<int>(threads_.size()); }
  /// Wall time of each Wake call: one tick (or heartbeat) of one world.
  const LatencyHistogram& wake_durations() const { return wake_durations_; }

 private:
  struct Pending {
    std::chrono::steady_clock::time_point when;
    uint64_t generation;
    std::shared_ptr<Ticked> target;
    bool operator>(const Pending& o) const { return when > o.when; }
  };
  void Loop();

  absl::Mutex mu_;
  absl::CondVar cv_;
  std::priority_queue<Pending, std::vector<Pending>, std::greater<>> wakes_ ABSL_GUARDED_BY(mu_);
  bool stopping_ ABSL_GUARDED_BY(mu_) = false;
  std::vector<std::thread> threads_;
  std::atomic<int64_t> cpu_ns_{0};
  LatencyHistogram wake_durations_;
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_SCHEDULER_H_
