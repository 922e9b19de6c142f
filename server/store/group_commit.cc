#include "server/store/group_commit.h"

#include <algorithm>
#include <utility>

#include "absl/strings/str_format.h"

namespace sportsim::server::store {

GroupCommit::GroupCommit(CommitBackend* backend, GroupCommitOptions options)
    : backend_(backend),
      options_(std::move(options)),
      start_(std::chrono::steady_clock::now()) {
  writer_ = std::thread([this] { Loop(); });
}

GroupCommit::~GroupCommit() { Close(); }

absl::Status GroupCommit::Write(JournalOp op) {
  Waiter waiter;
  absl::MutexLock lock(&mu_);
  if (closing_) {
    return absl::UnavailableError(
        absl::StrFormat("the journal %s is closed (the server is stopping)", options_.name));
  }
  if (!fatal_.ok()) return fatal_;
  queue_.push_back(Queued{.op = std::move(op), .waiter = &waiter});
  work_.Signal();
  while (!waiter.done) done_.Wait(&mu_);
  return waiter.status;
}

void GroupCommit::Post(JournalOp op) {
  absl::MutexLock lock(&mu_);
  if (closing_ || !fatal_.ok()) return;
  queue_.push_back(Queued{.op = std::move(op), .waiter = nullptr});
  work_.Signal();
}

absl::Status GroupCommit::Run(std::function<absl::Status()> job) {
  Waiter waiter;
  absl::MutexLock lock(&mu_);
  if (closing_) {
    return absl::UnavailableError(
        absl::StrFormat("the journal %s is closed (the server is stopping)", options_.name));
  }
  jobs_.push_back(Job{.fn = std::move(job), .waiter = &waiter});
  work_.Signal();
  while (!waiter.done) done_.Wait(&mu_);
  return waiter.status;
}

double GroupCommit::NodeSeconds() const {
  const std::chrono::duration<double> ran = std::chrono::steady_clock::now() - start_;
  return options_.clock0_s + ran.count() * options_.clock_rate;
}

absl::Status GroupCommit::Healthy() const {
  absl::MutexLock lock(&mu_);
  return health_;
}

GroupCommitStats GroupCommit::stats() const {
  absl::MutexLock lock(&mu_);
  return stats_;
}

void GroupCommit::StopClockForTesting() {
  absl::MutexLock lock(&mu_);
  clock_stopped_ = true;
  work_.Signal();
}

void GroupCommit::Close() {
  {
    absl::MutexLock lock(&mu_);
    if (closing_) {
      // Another thread closes: wait until it is done.
      while (!closed_) done_.Wait(&mu_);
      return;
    }
    closing_ = true;
    work_.Signal();
  }
  writer_.join();
  absl::MutexLock lock(&mu_);
  closed_ = true;
  done_.SignalAll();
}

void GroupCommit::SetHealth(const absl::Status& status) {
  health_ = fatal_.ok() ? status : fatal_;
}

void GroupCommit::Loop() {
  // The clock is persisted at once (the first health probe), then every clock_interval; the
  // lease was taken when the store opened, so its first renewal is one renew_interval away.
  absl::Time next_clock = absl::Now();
  absl::Time next_renew = absl::Now() + options_.renew_interval;
  for (;;) {
    std::deque<Queued> batch;
    std::deque<Job> jobs;
    bool closing = false;
    bool clock_stopped = false;
    {
      absl::MutexLock lock(&mu_);
      for (;;) {
        if (!queue_.empty() || !jobs_.empty() || closing_) break;
        const absl::Time due =
            clock_stopped_ ? absl::InfiniteFuture() : std::min(next_clock, next_renew);
        if (absl::Now() >= due) break;
        work_.WaitWithDeadline(&mu_, due);
      }
      // Writes are refused once closing_ is set, so this batch is the last one then.
      batch.swap(queue_);
      jobs.swap(jobs_);
      closing = closing_;
      clock_stopped = clock_stopped_;
    }
    for (Job& job : jobs) {
      const absl::Status status = job.fn();
      absl::MutexLock lock(&mu_);
      job.waiter->status = status;
      job.waiter->done = true;
      done_.SignalAll();
    }
    if (!batch.empty()) CommitBatch(&batch);
    if (closing) {
      if (!clock_stopped) PersistClock(/*renew=*/false, /*final=*/true);
      return;
    }
    if (clock_stopped) continue;
    const absl::Time now = absl::Now();
    const bool renew = now >= next_renew;
    if (renew || now >= next_clock) {
      PersistClock(renew, /*final=*/false);
      next_clock = absl::Now() + options_.clock_interval;
      if (renew) next_renew = absl::Now() + options_.renew_interval;
    }
  }
}

void GroupCommit::CommitBatch(std::deque<Queued>* batch) {
  std::vector<const JournalOp*> ops;
  ops.reserve(batch->size());
  for (const Queued& q : *batch) ops.push_back(&q.op);
  std::vector<absl::Status> results(ops.size());
  absl::Status status = backend_->Fatal();
  if (status.ok()) status = backend_->CommitBatch(ops, &results);
  const absl::Status fatal = backend_->Fatal();

  absl::MutexLock lock(&mu_);
  if (!fatal.ok()) fatal_ = fatal;
  SetHealth(status);
  if (status.ok()) {
    ++stats_.batches;
    stats_.ops += static_cast<int64_t>(ops.size());
  } else {
    ++stats_.failed_batches;
  }
  for (size_t i = 0; i < batch->size(); ++i) {
    Waiter* waiter = (*batch)[i].waiter;
    if (waiter == nullptr) continue;
    waiter->status = status.ok() ? results[i] : status;
    waiter->done = true;
  }
  done_.SignalAll();
}

void GroupCommit::PersistClock(bool renew, bool final) {
  if (!backend_->Fatal().ok()) {
    absl::MutexLock lock(&mu_);
    fatal_ = backend_->Fatal();
    SetHealth(fatal_);
    return;
  }
  // A promise: the clock will not pass this value before the next persist (or the node stops),
  // so a restore after a crash never puts a world behind where it got to. At Close the clock
  // the node reached is exact.
  const double clock_s =
      final ? NodeSeconds()
            : NodeSeconds() + 2.0 * absl::ToDoubleSeconds(options_.clock_interval) *
                                  options_.clock_rate;
  const absl::Status status = backend_->PersistClock(clock_s, renew);
  const absl::Status fatal = backend_->Fatal();
  absl::MutexLock lock(&mu_);
  if (!fatal.ok()) fatal_ = fatal;
  SetHealth(status);
  if (status.ok()) ++stats_.clock_persists;
}

}  // namespace sportsim::server::store
