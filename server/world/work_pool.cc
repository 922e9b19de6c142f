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
  int n = limits_.workers;
  if (n <= 0) n = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  for (int i = 0; i < n; ++i) threads_.emplace_back([this] { Loop(); });
}

WorkPool::~WorkPool() { Stop(absl::ZeroDuration()); }

absl::Status WorkPool::Submit(Job job, Dropped dropped, std::function<bool()> cancelled,
                              std::optional<WorkControl::Clock::time_point> deadline) {
  absl::MutexLock lock(&mu_);
  if (stopping_) return absl::UnavailableError("the server is shutting down");
  if (static_cast<int>(queue_.size()) >= limits_.max_queued) {
    refused_.fetch_add(1);
    return absl::ResourceExhaustedError(absl::StrFormat(
        "the server's simulation queue is full (%d waiting, %d running): retry later",
        queue_.size(), running_.load()));
  }
  queue_.push_back(Pending{std::move(job), std::move(dropped), std::move(cancelled), deadline});
  cv_.Signal();
  return absl::OkStatus();
}

int WorkPool::queued() const {
  absl::MutexLock lock(&mu_);
  return static_cast<int>(queue_.size());
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
      cv_.SignalAll();
    }
  }
  for (Pending& p : dropped) p.dropped(absl::UnavailableError("the server is shutting down"));
  for (std::thread& t : threads_) {
    if (t.joinable()) t.join();
  }
}

void WorkPool::Loop() {
  // Below the server's other threads: health, reads and ticks come first on a busy machine.
  if (limits_.nice > 0) {
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), limits_.nice);
  }
  for (;;) {
    Pending p;
    {
      absl::MutexLock lock(&mu_);
      while (!stopping_ && queue_.empty()) cv_.Wait(&mu_);
      if (stopping_) return;  // the queue was handed to Stop()
      p = std::move(queue_.front());
      queue_.pop_front();
      running_.fetch_add(1);
    }
    const WorkControl control(std::move(p.cancelled), p.deadline,
                              absl::ToDoubleSeconds(limits_.cpu_budget), &stop_after_ns_);
    p.job(control);
    running_.fetch_sub(1);
  }
}

}  // namespace sportsim::server
