// Builds, starts and stops the sportsim gRPC server (used by main.cc and in-process tests).
#ifndef SPORTSIM_SERVER_SERVER_APP_H_
#define SPORTSIM_SERVER_SERVER_APP_H_

#include <atomic>
#include <thread>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "server/app/metrics.h"
#include "server/rpc/grpc_web.h"
#include "server/rpc/open_connect.h"
#include "server/rpc/services.h"
#include "server/store/store.h"
#include "server/swing/round_world.h"
#include "server/swing/session_world.h"
#include "server/world/work_pool.h"
#include "server/billiards/table_world.h"

namespace grpc {
class Server;
class Service;
}  // namespace grpc

namespace sportsim::server {

/// Where the build puts the viewer's files.
extern const char* const kDefaultWebRoot;

struct ServerConfig {
  std::string listen = "127.0.0.1:50051";  ///< host:port ([v6]:port); port 0 = any free port
  int max_receive_message_bytes = 64 << 10;  ///< requests are small: 64 KiB (--max_request_bytes)
  int max_send_message_bytes = 64 << 20;    ///< sampled trajectories can be large: 64 MiB
  std::string metrics_listen;  ///< host:port of the Prometheus /metrics endpoint; "" = off
  int tick_workers = 0;  ///< threads ticking every table and session; 0: one per core
  // Keepalive for long-lived watch and drive streams (docs/operations.md). The server pings a
  // connection that has been silent for keepalive_time and drops it when the ping is not
  // answered within keepalive_timeout, so a vanished client's streams end (and free their
  // watcher slots) in under a minute. Clients may ping too, with or without calls open, but
  // no more often than min_client_ping_interval; faster pings get a GOAWAY (too_many_pings).
  absl::Duration keepalive_time = absl::Seconds(30);             ///< --keepalive_time
  absl::Duration keepalive_timeout = absl::Seconds(10);          ///< --keepalive_timeout
  absl::Duration min_client_ping_interval = absl::Seconds(10);   ///< --min_client_ping_interval
  TableLimits tables;
  SessionLimits sessions;
  RoundLimits rounds;
  /// gRPC-Web and the viewer: listen address ("" = off), files, allowed origins.
  std::string http_listen;
  std::string web_root = kDefaultWebRoot;
  std::vector<std::string> http_cors_origins;
  int http_max_streams_per_client = 4;
  GrpcWebLimits http;  ///< the web port's connection limits and timeouts (--http_*)
  /// Launch monitors over GSPro Open Connect: listen address ("" = off, the default).
  OpenConnectOptions open_connect;
  StreamLimits streams;  ///< --stream_window_bytes, --stream_stall_timeout, --max_upload_bytes
  WorkLimits work;  ///< the simulation pool (--sim_workers, --max_queued_simulations,
                    ///< --max_request_cpu)
  /// The journal (--data_dir, --store, --node, --lease): none when both data_dir and
  /// postgres_uri are empty (everything in memory).
  store::StoreOptions store;
  bool adopt = false;  ///< --adopt: take over the worlds of nodes whose lease lapsed
};

/// What a start restored from the journal.
struct RestoreReport {
  int tables = 0;
  int sessions = 0;
  int rounds = 0;
  int failed = 0;        ///< worlds that could not be restored (logged, left in the store)
  double seconds = 0.0;  ///< wall time of the restore
};

/// Routes libprotobuf's per-message error lines (malformed requests) to a counter instead of
/// stderr. Process-wide; ServerApp::Start installs it.
void InstallProtobufLogCounter();
/// Malformed-message lines libprotobuf reported since then.
int64_t ProtobufLogMessages();

/// host and port of a listen address.
struct ListenAddress {
  std::string host;
  int port = 0;
};

/// Parses "host:port" or "[ipv6]:port" with a port in [0, 65535].
absl::StatusOr<ListenAddress> ParseListenAddress(std::string_view address);

/// A running server. Destroying it shuts it down.
class ServerApp {
 public:
  /// Starts serving. Errors: a malformed address (INVALID_ARGUMENT), an address that cannot be
  /// bound, e.g. a port in use (UNAVAILABLE).
  static absl::StatusOr<std::unique_ptr<ServerApp>> Start(const ServerConfig& config);
  ~ServerApp();

  int port() const { return port_; }
  /// The gRPC-Web port, or 0 when off.
  int http_port() const;
  /// The gRPC-Web gateway, or null when off.
  GrpcWebGateway* web() { return web_.get(); }
  /// The Open Connect listener's port, or 0 when off.
  int open_connect_port() const { return open_connect_ != nullptr ? open_connect_->port() : 0; }
  OpenConnectListener* open_connect() { return open_connect_.get(); }
  /// The /metrics port, or 0 when metrics are off.
  int metrics_port() const;
  TableRegistry& tables() { return *tables_; }
  SessionRegistry& sessions() { return *sessions_; }
  RoundRegistry& rounds() { return *rounds_; }
  WorkPool& pool() { return *pool_; }
  std::string address() const;
  /// The journal, or null when everything is in memory.
  store::Store* journal() { return store_.get(); }
  /// What the start restored (and, with --adopt, every takeover since).
  RestoreReport restored() const;

  /// Marks health NOT_SERVING, ends every WatchTable stream (UNAVAILABLE after a last
  /// snapshot), stops accepting, lets in-flight calls finish for up to `grace`, then cancels
  /// what is left. Idempotent.
  void Shutdown(absl::Duration grace);
  /// Blocks until the server has shut down.
  void Wait();

 private:
  ServerApp() = default;
  /// Restores `worlds` into the registries (a start, a takeover).
  void RestoreWorlds(const std::vector<StoredWorld>& worlds);
  /// Health follows the journal's; with --adopt, takes over lapsed nodes' worlds.
  void MonitorStore(absl::Duration adopt_every);

  std::unique_ptr<store::Store> store_;       // closed after the server stopped calling it
  std::unique_ptr<TickScheduler> scheduler_;  // stopped before the registries go
  std::unique_ptr<WorkPool> pool_;            // outlives the services that queue on it
  std::unique_ptr<TableRegistry> tables_;  // the registries outlive the services
  std::unique_ptr<SessionRegistry> sessions_;
  std::unique_ptr<RoundRegistry> rounds_;
  std::unique_ptr<RpcCounters> rpc_counters_;   // outlives the gRPC server (its interceptor)
  std::unique_ptr<MetricsEndpoint> metrics_;    // goes before the registries it reads
  std::vector<std::unique_ptr<grpc::Service>> services_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<GrpcWebGateway> web_;  // goes before the server its channel calls
  std::unique_ptr<OpenConnectListener> open_connect_;  // goes before the pool and registries
  std::string host_;
  int port_ = 0;
  std::atomic<bool> shut_down_{false};
  bool adopt_ = false;
  mutable absl::Mutex monitor_mu_;
  bool monitor_stop_ ABSL_GUARDED_BY(monitor_mu_) = false;
  RestoreReport restored_ ABSL_GUARDED_BY(monitor_mu_);
  std::thread monitor_;
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_SERVER_APP_H_
