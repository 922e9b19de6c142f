// Admission control for simulations (SimulateShot, SimulateSwing, SimulateFlight, StartSwing's
// dry run, batches, previews): a bounded pool of worker threads apart from gRPC's threads and
// from the tick workers, with a bounded queue, so that no valid request can starve health
// checks, reads or ticks. A running job polls its WorkControl between steps or events: the
// caller's cancellation, its deadline, its CPU budget and the server's shutdown stop it.
// Workers run at a lower scheduling priority (nice) than the rest of the server.
//
// Two classes of work, each with its own queue and its own workers: interactive jobs (a
// player's SimulateShot, PreviewShot, a swing's dry run, a round's stroke) and batch chunks
// (SimulateShots). Batch workers run at a lower priority still (batch_nice), so that on a busy
// machine the kernel's scheduler gives an interactive job most of a core the moment it is
// queued, instead of after the chunks ahead of it; when no interactive job waits, batches have
// every core. Batch chunks are taken round-robin over their owners (one owner per batch call),
// so that every batch gets a fair share and none gets all of it. No gRPC here.
#ifndef SPORTSIM_SERVER_WORLD_WORK_POOL_H_
#define SPORTSIM_SERVER_WORLD_WORK_POOL_H_

#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"

namespace sportsim::server {

struct WorkLimits {
  int workers = 0;                  ///< threads; 0: one per core
  int max_queued = 64;              ///< jobs waiting for a worker; more: RESOURCE_EXHAUSTED
  absl::Duration cpu_budget = absl::Seconds(10);  ///< thread CPU per request (--max_request_cpu)
  int nice = 10;                    ///< workers' niceness (0: as the server's other threads)
  int batch_workers = 0;            ///< threads for batch chunks; 0: one per core
  int batch_nice = 19;              ///< their niceness (kept >= nice)
};

/// Which queue a job waits in (see the file comment).
enum class WorkClass { kInteractive, kBatch };

/// What a running job polls. Thread-compatible: used by the job's own thread only.
class WorkControl {
 public:
  using Clock = std::chrono::steady_clock;
  WorkControl(std::function<bool()> cancelled, std::optional<Clock::time_point> deadline,
              double cpu_budget_s, const std::atomic<int64_t>* stop_after_ns);

  /// OK while the job may go on; else why it must stop: CANCELLED (the caller went away),
  /// DEADLINE_EXCEEDED (the call's deadline), RESOURCE_EXHAUSTED (the CPU budget, naming
  /// --max_request_cpu), UNAVAILABLE (the server is shutting down and its grace ran out).
  absl::Status Check() const;
  bool ShouldStop() const { return !Check().ok(); }
  /// Thread CPU the job has used so far (s).
  double CpuSeconds() const;

 private:
  std::function<bool()> cancelled_;
  std::optional<Clock::time_point> deadline_;
  double cpu_budget_s_;
  double cpu0_s_;
  const std::atomic<int64_t>* stop_after_ns_;  // steady-clock ns; 0: not stopping
};

class WorkPool {
 public:
  using Job = std::function<void(const WorkControl&)>;
  /// Called instead of the job when it never runs (the server stopped first).
  using Dropped = std::function<void(const absl::Status&)>;

  explicit WorkPool(WorkLimits limits);
  ~WorkPool();  ///< Stop(0)s
  WorkPool(const WorkPool&) = delete;
  WorkPool& operator=(const WorkPool&) = delete;

  /// Queues a job: RESOURCE_EXHAUSTED when max_queued jobs of its class already wait,
  /// UNAVAILABLE once stopping. Exactly one of `job` and `dropped` is called later, on a worker
  /// or in Stop(). `owner` (batch jobs): the batch the job belongs to, for the round-robin.
  absl::Status Submit(Job job, Dropped dropped, std::function<bool()> cancelled,
                      std::optional<WorkControl::Clock::time_point> deadline,
                      WorkClass cls = WorkClass::kInteractive, uint64_t owner = 0);
  /// A fresh owner id for a batch.
  uint64_t NewOwner() { return next_owner_.fetch_add(1) + 1; }

  /// Refuses new jobs, drops the queued ones (UNAVAILABLE), lets running ones go on for
  /// `grace`, then tells them to stop, and joins the workers. Idempotent.
  void Stop(absl::Duration grace);

  /// Interactive workers (batch workers are as many unless set apart).
  int workers() const { return interactive_workers_; }
  int batch_workers() const { return static_cast<int>(threads_.size()) - interactive_workers_; }
  int queued() const;  ///< both classes
  int running() const { return running_.load(); }
  int64_t refused() const { return refused_.load(); }   ///< queue full
  int64_t budget_exhausted() const { return budget_exhausted_.load(); }
  /// Counts a job stopped by its CPU budget (the job's caller reports it).
  void CountBudgetExhausted() { budget_exhausted_.fetch_add(1); }

 private:
  struct Pending {
    Job job;
    Dropped dropped;
    std::function<bool()> cancelled;
    std::optional<WorkControl::Clock::time_point> deadline;
  };
  void Loop(WorkClass cls);
  bool HasWork(WorkClass cls) const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  Pending Take(WorkClass cls) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  const WorkLimits limits_;
  int interactive_workers_ = 0;
  mutable absl::Mutex mu_;
  absl::CondVar cv_, batch_cv_;
  std::deque<Pending> queue_ ABSL_GUARDED_BY(mu_);  // interactive
  // Batch chunks: each owner's in order, owners served in turn.
  std::map<uint64_t, std::deque<Pending>> batches_ ABSL_GUARDED_BY(mu_);
  std::deque<uint64_t> turns_ ABSL_GUARDED_BY(mu_);  // owners with chunks waiting
  int batch_queued_ ABSL_GUARDED_BY(mu_) = 0;
  std::atomic<uint64_t> next_owner_{0};
  bool stopping_ ABSL_GUARDED_BY(mu_) = false;
  std::vector<std::thread> threads_;
  std::atomic<int64_t> stop_after_ns_{0};
  std::atomic<int> running_{0};
  std::atomic<int64_t> refused_{0}, budget_exhausted_{0};
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_WORLD_WORK_POOL_H_
