#include "server/world/scheduler.h"

#include <time.h>

#include <algorithm>

#include "absl/time/time.h"

namespace sportsim::server {

TickScheduler::TickScheduler(int workers) {
  int n = workers;
  if (n <= 0) n = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  for (int i = 0; i < n; ++i) threads_.emplace_back([this] { Loop(); });
}

TickScheduler::~TickScheduler() { Stop(); }

void TickScheduler::Schedule(std::shared_ptr<Ticked> target, uint64_t generation,
                             std::chrono::steady_clock::time_point when) {
  absl::MutexLock lock(&mu_);
  if (stopping_) return;
  const bool earliest = wakes_.empty() || when < wakes_.top().when;
  wakes_.push(Pending{when, generation, std::move(target)});
  if (earliest) cv_.Signal();
}

void TickScheduler::Stop() {
  {
    absl::MutexLock lock(&mu_);
    stopping_ = true;
    cv_.SignalAll();
  }
  for (std::thread& t : threads_) {
    if (t.joinable()) t.join();
  }
  // Dropped outside the lock: a world's destructor may run here.
  std::priority_queue<Pending, std::vector<Pending>, std::greater<>> dropped;
  {
    absl::MutexLock lock(&mu_);
    std::swap(dropped, wakes_);
  }
}

void TickScheduler::Loop() {
  for (;;) {
    Pending wake;
    {
      absl::MutexLock lock(&mu_);
      for (;;) {
        if (stopping_) return;
        if (wakes_.empty()) {
          cv_.Wait(&mu_);
          continue;
        }
        const auto now = std::chrono::steady_clock::now();
        if (wakes_.top().when <= now) break;
        cv_.WaitWithTimeout(&mu_, absl::FromChrono(wakes_.top().when - now));
      }
      wake = wakes_.top();
      wakes_.pop();
      // Another worker may be waiting for the next one.
      if (!wakes_.empty()) cv_.Signal();
    }
    timespec c0{}, c1{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
    const auto w0 = std::chrono::steady_clock::now();
    wake.target->Wake(wake.generation, w0);
    wake_durations_.Add(std::chrono::steady_clock::now() - w0);
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
    cpu_ns_.fetch_add((c1.tv_sec - c0.tv_sec) * 1000000000LL + (c1.tv_nsec - c0.tv_nsec),
                      std::memory_order_relaxed);
  }
}

}  // namespace sportsim::server
