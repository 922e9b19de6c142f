// What the load tools (sportsim-load, sportsim-round-load) share: the process's CPU time, and a
// gRPC watcher that reads a world's snapshots as fast as they come, counting them and their
// bytes, with a hook on each snapshot.
#ifndef SPORTSIM_BENCH_LOAD_WATCH_H_
#define SPORTSIM_BENCH_LOAD_WATCH_H_

#include <sys/resource.h>

#include <atomic>
#include <cstdint>
#include <functional>

#include <grpcpp/grpcpp.h>
#include <grpcpp/support/client_callback.h>

#include "absl/synchronization/mutex.h"

namespace sportsim::bench {

inline double ProcessCpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// One watch stream. `start(ctx, request, reactor)` starts the call (the stub's async method);
/// `on_read` (may be empty) sees each snapshot on gRPC's thread.
template <typename Request, typename Snapshot>
class CountingWatch final : public ::grpc::ClientReadReactor<Snapshot> {
 public:
  template <typename Start>
  CountingWatch(Start start, const Request& request,
                std::function<void(const Snapshot&)> on_read = {})
      : request_(request), on_read_(std::move(on_read)) {
    start(&ctx_, &request_, this);
    this->StartRead(&snap_);
    this->StartCall();
  }
  void OnReadDone(bool ok) override {
    if (!ok) return;
    snapshots_.fetch_add(1, std::memory_order_relaxed);
    bytes_.fetch_add(static_cast<int64_t>(snap_.ByteSizeLong()), std::memory_order_relaxed);
    if (on_read_) on_read_(snap_);
    this->StartRead(&snap_);
  }
  void OnDone(const ::grpc::Status&) override {
    absl::MutexLock lock(&mu_);
    done_ = true;
  }
  /// Cancels the call and waits until gRPC is done with it.
  void Stop() {
    ctx_.TryCancel();
    absl::MutexLock lock(&mu_);
    mu_.Await(absl::Condition(&done_));
  }
  int64_t snapshots() const { return snapshots_.load(); }
  int64_t bytes() const { return bytes_.load(); }

 private:
  ::grpc::ClientContext ctx_;
  Request request_;
  Snapshot snap_;
  std::function<void(const Snapshot&)> on_read_;
  std::atomic<int64_t> snapshots_{0}, bytes_{0};
  absl::Mutex mu_;
  bool done_ = false;
};

}  // namespace sportsim::bench

#endif  // SPORTSIM_BENCH_LOAD_WATCH_H_
