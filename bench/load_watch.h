// What the load tools (sportsim-load, sportsim-round-load) share: the process's CPU time, and a
// gRPC watcher that reads a world's snapshots as fast as they come, counting them and their
// bytes, with a hook on each snapshot.
#ifndef SPORTSIM_BENCH_LOAD_WATCH_H_
#define SPORTSIM_BENCH_LOAD_WATCH_H_

#include <sys/resource.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

#include <grpcpp/grpcpp.h>
#include <grpcpp/support/client_callback.h>

#include "absl/synchronization/mutex.h"
#include "server/world/watcher.h"
#include "server/world/world_host.h"

namespace sportsim::bench {

inline double ProcessCpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// A world host's counters and publish-to-write latencies at one moment.
struct HostSample {
  server::WorldStats stats;
  std::vector<int64_t> latency;  ///< LatencyHistogram::Counts()
};

/// What happened between two samples `secs` apart.
struct HostWindow {
  double ticks = 0, late = 0, slipped = 0;  ///< per second
  double late_pct = 0, slipped_pct = 0;     ///< of the ticks
  double sent = 0, replaced = 0;            ///< snapshots written and overtaken, per second
  double tick_cores = 0;                    ///< the tick workers' CPU, in cores
  double p50_ms = 0, p99_ms = 0;            ///< publish-to-write (bucket upper edges)
};

inline HostWindow Between(const HostSample& a, const HostSample& b, double secs) {
  HostWindow w;
  const double ticks = static_cast<double>(b.stats.ticks - a.stats.ticks);
  const double late = static_cast<double>(b.stats.late_ticks - a.stats.late_ticks);
  const double slipped = static_cast<double>(b.stats.slipped_ticks - a.stats.slipped_ticks);
  w.ticks = ticks / secs;
  w.late = late / secs;
  w.slipped = slipped / secs;
  w.late_pct = ticks > 0 ? 100 * late / ticks : 0;
  w.slipped_pct = ticks > 0 ? 100 * slipped / ticks : 0;
  w.sent = static_cast<double>(b.stats.snapshots_sent - a.stats.snapshots_sent) / secs;
  w.replaced = static_cast<double>(b.stats.snapshots_replaced - a.stats.snapshots_replaced) / secs;
  w.tick_cores = 1e-9 * static_cast<double>(b.stats.tick_cpu_ns - a.stats.tick_cpu_ns) / secs;
  std::vector<int64_t> window = b.latency;  // the window's latencies: b's counts minus a's
  for (size_t i = 0; i < window.size() && i < a.latency.size(); ++i) window[i] -= a.latency[i];
  w.p50_ms = 1e3 * server::LatencyHistogram::QuantileOf(window, 0.5);
  w.p99_ms = 1e3 * server::LatencyHistogram::QuantileOf(window, 0.99);
  return w;
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
