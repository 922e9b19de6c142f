// Prometheus metrics (issue #9): an HTTP /metrics endpoint, off unless --metrics_listen is
// given, and a gRPC interceptor that counts RPCs by method and status code. Values are read
// from the registries and the scheduler at scrape time (no second set of counters to keep in
// step). No table or session id is ever a label: label sets stay bounded.
#ifndef SPORTSIM_SERVER_METRICS_H_
#define SPORTSIM_SERVER_METRICS_H_

#include <array>
#include <atomic>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"

namespace grpc::experimental {
class ServerInterceptorFactoryInterface;
}  // namespace grpc::experimental

namespace prometheus {
class Exposer;
}  // namespace prometheus

namespace sportsim::server {

namespace store {
class Store;
}  // namespace store

class TableRegistry;
class SessionRegistry;
class TickScheduler;
class WorkPool;

/// RPCs finished, by full method name and gRPC status code, and RPCs in flight. Thread safe.
class RpcCounters {
 public:
  void Count(const std::string& method, int code);
  std::map<std::pair<std::string, int>, int64_t> Snapshot() const;
  /// Calls that have started and not yet been destroyed.
  int64_t in_flight() const { return in_flight_.load(std::memory_order_acquire); }
  void Begin() { in_flight_.fetch_add(1, std::memory_order_acq_rel); }
  void End() { in_flight_.fetch_sub(1, std::memory_order_acq_rel); }

 private:
  std::atomic<int64_t> in_flight_{0};
  mutable absl::Mutex mu_;
  std::map<std::pair<std::string, int>, int64_t> counts_ ABSL_GUARDED_BY(mu_);
};

/// Counts every RPC's final status into `counters` (which must outlive the server).
std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> MakeRpcCountingInterceptor(
    RpcCounters* counters);

/// A running /metrics endpoint.
class MetricsEndpoint {
 public:
  /// Serves the metrics of these (which must outlive the endpoint) on `listen` (host:port;
  /// port 0 picks a free one). UNAVAILABLE if it cannot listen there.
  static absl::StatusOr<std::unique_ptr<MetricsEndpoint>> Start(const std::string& listen,
                                                                TableRegistry* tables,
                                                                SessionRegistry* sessions,
                                                                TickScheduler* scheduler,
                                                                WorkPool* pool,
                                                                RpcCounters* rpcs,
                                                                store::Store* journal = nullptr);
  ~MetricsEndpoint();
  int port() const { return port_; }

 private:
  MetricsEndpoint() = default;
  std::shared_ptr<void> collectable_;
  std::unique_ptr<prometheus::Exposer> exposer_;
  int port_ = 0;
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_METRICS_H_
