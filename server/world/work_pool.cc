#include "server/world/work_pool.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <utility>

#include "absl/strings/str_format.h"
#include "sim/core/cpu_clock.h"

namespace sportsim::server {

namespace {

int64_t SteadyNs(WorkControl::Clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

}  // namespace

WorkControl::WorkControl(std::function<bool()> cancelled,
                         std::optional<Clock::time_point> deadline, double cpu_budget_s,
                         const std::atomic<int64_t>* stop_after_ns)
    : cancelled_(std::move(cancelled)),
      deadline_(deadline),
      cpu_budget_s_(cpu_budget_s),
      cpu0_s_(ThreadCpuSeconds()),
      stop_after_ns_(stop_after_ns) {}

double WorkControl::CpuSeconds() const { return ThreadCpuSeconds() - cpu0_s_; }

absl::Status WorkControl::Check() const {
  if (cancelled_ && cancelled_()) return absl::CancelledError("the call was cancelled");
  const Clock::time_point now = Clock::now();
  if (deadline_.has_value() && now >= *deadline_) {
    return absl::DeadlineExceededError("the call's deadline passed while it was computed");
  }
  if (stop_after_ns_ != nullptr) {
    const int64_t stop = stop_after_ns_->load(std::memory_order_relaxed);
    if (stop != 0 && SteadyNs(now) >= stop) {
      return absl::UnavailableError("the server is shutting down");
    }
  }
  if (const double used = CpuSeconds(); used > cpu_budget_s_) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "the request used its CPU budget of %g s (--max_request_cpu) and was stopped after "
        "%.3g s: ask for less (a larger dt_s, fewer samples, a shorter max_time_s)",
        cpu_budget_s_, used));
  }
  return absl::OkStatus();
}

WorkPool::WorkPool(WorkLimits limits) : limits_(limits) {
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  interactive_workers_ = limits_.workers > 0 ? limits_.workers : cores;
  const int batch = limits_.batch_workers > 0 ? limits_.batch_workers : interactive_workers_;
  for (int i = 0; i < interactive_workers_; ++i) {
    threads_.emplace_back([this] { Loop(WorkClass::kInteractive); });
  }
  for (int i = 0; i < batch; ++i) threads_.emplace_back([this] { Loop(WorkClass::kBatch); });
}

WorkPool::~WorkPool() { Stop(absl::ZeroDuration()); }

absl::Status WorkPool::Submit(Job job, Dropped dropped, std::function<bool()> cancelled,
                              std::optional<WorkControl::Clock::time_point> deadline,
                              WorkClass cls, uint64_t owner) {
  absl::MutexLock lock(&mu_);
  if (stopping_) return absl::UnavailableError("the server is shutting down");
  const int waiting = cls == WorkClass::kBatch ? batch_queued_ : static_cast<int>(queue_.size());
  if (waiting >= limits_.max_queued) {
    refused_.fetch_add(1);
    return absl::ResourceExhaustedError(absl::StrFormat(
        "the server's %s queue is full (%d waiting, %d running): retry later",
        cls == WorkClass::kBatch ? "batch" : "simulation", waiting, running_.load()));
  }
  Pending p{std::move(job), std::move(dropped), std::move(cancelled), deadline};
  if (cls == WorkClass::kInteractive) {
    queue_.push_back(std::move(p));
    cv_.Signal();
  } else {
    std::deque<Pending>& mine = batches_[owner];
    if (mine.empty()) turns_.push_back(owner);
    mine.push_back(std::move(p));
    ++batch_queued_;
    batch_cv_.Signal();
  }
  return absl::OkStatus();
}

int WorkPool::queued() const {
  absl::MutexLock lock(&mu_);
  return static_cast<int>(queue_.size()) + batch_queued_;
}

bool WorkPool::HasWork(WorkClass cls) const {
  return cls == WorkClass::kInteractive ? !queue_.empty() : !turns_.empty();
}

WorkPool::Pending WorkPool::Take(WorkClass cls) {
  Pending p;
  if (cls == WorkClass::kInteractive) {
    p = std::move(queue_.front());
    queue_.pop_front();
    return p;
  }
  const uint64_t owner = turns_.front();
  turns_.pop_front();
  auto it = batches_.find(owner);
  p = std::move(it->second.front());
  it->second.pop_front();
  --batch_queued_;
  if (it->second.empty()) {
    batches_.erase(it);
  } else {
    turns_.push_back(owner);  // its next chunk waits for the others' turns
  }
  return p;
}

void WorkPool::Stop(absl::Duration grace) {
  std::deque<Pending> dropped;
  {
    absl::MutexLock lock(&mu_);
    if (!stopping_) {
      stopping_ = true;
      stop_after_ns_.store(
          SteadyNs(WorkControl::Clock::now() + absl::ToChronoNanoseconds(grace)));
      std::swap(dropped, queue_);
      for (const uint64_t owner : turns_) {
        for (Pending& p : batches_[owner]) dropped.push_back(std::move(p));
      }
      batches_.clear();
      turns_.clear();
      batch_queued_ = 0;
      cv_.SignalAll();
      batch_cv_.SignalAll();
    }
  }
  for (Pending& p : dropped) p.dropped(absl::UnavailableError("the server is shutting down"));
  for (std::thread& t : threads_) {
    if (t.joinable()) t.join();
  }
}

void WorkPool::Loop(WorkClass cls) {
  // Below the server's other threads: health, reads and ticks come first on a busy machine;
  // batch chunks below interactive jobs.
  const int nice =
      cls == WorkClass::kBatch ? std::max(limits_.nice, limits_.batch_nice) : limits_.nice;
  if (nice > 0) setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), nice);
  absl::CondVar& cv = cls == WorkClass::kBatch ? batch_cv_ : cv_;
  for (;;) {
    Pending p;
    {
      absl::MutexLock lock(&mu_);
      while (!stopping_ && !HasWork(cls)) cv.Wait(&mu_);
      if (stopping_) return;  // the queues were handed to Stop()
      p = Take(cls);
      running_.fetch_add(1);
    }
    const WorkControl control(std::move(p.cancelled), p.deadline,
                              absl::ToDoubleSeconds(limits_.cpu_budget), &stop_after_ns_);
    p.job(control);
    running_.fetch_sub(1);
  }
}

}  // namespace sportsim::server
