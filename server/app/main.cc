// sportsim-server: the authoritative sports-physics gRPC server.
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <algorithm>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/time/time.h"
#include "server/app/server_app.h"

namespace {

// A duration flag: seconds as a bare number (`--lease 10`, `--max_request_cpu 2.5`) or with a
// unit (`10s`, `500ms`, `1m`, absl's duration syntax).
struct Seconds {
  absl::Duration d;
};
bool AbslParseFlag(absl::string_view text, Seconds* out, std::string* error) {
  if (absl::ParseDuration(text, &out->d)) return true;
  double s = 0;
  if (absl::SimpleAtod(text, &s) && std::isfinite(s)) {
    out->d = absl::Seconds(s);
    return true;
  }
  *error = "must be seconds (10, 2.5) or a duration with its unit (10s, 500ms, 1m)";
  return false;
}
std::string AbslUnparseFlag(Seconds s) { return absl::FormatDuration(s.d); }

}  // namespace

ABSL_FLAG(std::string, listen, "127.0.0.1:50051",
          "Address to serve on, host:port or [ipv6]:port; port 0 picks a free port");
ABSL_FLAG(int, port, -1, "If set, overrides the port of --listen");
ABSL_FLAG(Seconds, shutdown_grace, Seconds{absl::Seconds(3)},
          "On SIGINT/SIGTERM, how long in-flight calls may take to finish before cancellation "
          "(watch streams end at once, with a last snapshot)");
ABSL_FLAG(int, max_request_bytes, 64 << 10, "Largest request message accepted (bytes)");
ABSL_FLAG(int, max_tables, 2000, "Most tables the server holds at once");
ABSL_FLAG(int, max_watchers_per_table, 64, "Most WatchTable streams per table");
ABSL_FLAG(std::string, metrics_listen, "",
          "HOST:PORT of a Prometheus /metrics endpoint (e.g. 127.0.0.1:9464; port 0: any free "
          "port, printed at start); off when empty");
ABSL_FLAG(Seconds, keepalive_time, Seconds{absl::Seconds(30)},
          "Ping a connection silent for this long; with --keepalive_timeout, how soon a vanished "
          "client's streams end");
ABSL_FLAG(Seconds, keepalive_timeout, Seconds{absl::Seconds(10)},
          "Drop a connection whose keepalive ping is not answered in this long");
ABSL_FLAG(Seconds, min_client_ping_interval, Seconds{absl::Seconds(10)},
          "Clients may send keepalive pings this often (with or without calls); faster pings "
          "get a GOAWAY");
ABSL_FLAG(int, max_sessions, 2000, "Most swing sessions the server holds at once");
ABSL_FLAG(int, max_watchers_per_session, 64,
          "Most WatchSwing and DriveSwing streams per swing session");
ABSL_FLAG(int, max_rounds, 2000, "Most golf rounds the server holds at once");
ABSL_FLAG(int, max_watchers_per_round, 64, "Most WatchRound streams per round");
ABSL_FLAG(int, tick_workers, 0,
          "Threads that tick the tables and swing sessions (one pool); 0: one per core");
ABSL_FLAG(int, max_catchup_ticks, 12,
          "A table further behind its clock than this slips (runs slower than real time) instead "
          "of racing to catch up");
ABSL_FLAG(int, event_log, 512, "Events each table keeps for watchers resuming with from_sequence");
ABSL_FLAG(std::string, open_connect_listen, "",
          "host:port for launch monitors speaking GSPro Open Connect v1 (JSON over TCP; the "
          "convention is port 921); empty: off");
ABSL_FLAG(absl::Duration, open_connect_idle_timeout, absl::Seconds(60),
          "An Open Connect connection silent this long is closed (connectors send heartbeats)");
ABSL_FLAG(std::string, http_listen, "",
          "host:port for gRPC-Web (browsers) and the viewer; empty: off");
ABSL_FLAG(std::string, web_root, sportsim::server::kDefaultWebRoot,
          "Directory of the viewer's built files, served at /");
ABSL_FLAG(std::vector<std::string>, http_cors_origins, {},
          "Origins allowed to call gRPC-Web from another origin (comma-separated; * for any)");
ABSL_FLAG(int, http_max_streams_per_client, 4,
          "Open gRPC-Web server streams per client address");
ABSL_FLAG(int, http_max_streams, 2048, "Open gRPC-Web server streams in all");
ABSL_FLAG(int, http_max_connections, 4096,
          "Open connections to the gRPC-Web port in all (more get 503 or are not accepted)");
ABSL_FLAG(int, http_max_connections_per_client, 64,
          "Open connections to the gRPC-Web port per client address (more get 429)");
ABSL_FLAG(int, http_max_calls_per_client, 16,
          "gRPC-Web unary calls in flight per client address (more get RESOURCE_EXHAUSTED)");
ABSL_FLAG(Seconds, http_idle_timeout, Seconds{absl::Seconds(30)},
          "A gRPC-Web connection with no bytes either way this long is closed (a waiting call "
          "or stream is not idle)");
ABSL_FLAG(Seconds, http_header_timeout, Seconds{absl::Seconds(10)},
          "A request's head must arrive within this of the connection's opening or of the "
          "previous response; slower clients are closed");
ABSL_FLAG(Seconds, http_body_timeout, Seconds{absl::Seconds(10)},
          "A request's body must arrive within this of its head");
ABSL_FLAG(Seconds, http_call_deadline, Seconds{absl::Seconds(60)},
          "The longest a gRPC-Web unary call may take (a shorter grpc-timeout wins)");
ABSL_FLAG(int, http_threads, 2, "Threads polling the gRPC-Web port's connections");
ABSL_FLAG(int64_t, stream_window_bytes, 1 << 20,
          "Finished, unsent work a server stream may hold per call (SimulateShots computes ahead "
          "of its reader only this far; gRPC-Web streams stop reading past it)");
ABSL_FLAG(int64_t, max_upload_bytes, int64_t{64} << 20,
          "What UploadCalibration's uploads in progress may hold in all (bytes; an upload past "
          "it is refused with RESOURCE_EXHAUSTED)");
ABSL_FLAG(Seconds, stream_stall_timeout, Seconds{absl::Seconds(30)},
          "A SimulateShots stream whose client reads nothing this long, or an UploadCalibration "
          "whose client sends nothing this long while it uploads, is stopped (0: never)");
ABSL_FLAG(int, sim_workers, 0,
          "Threads computing simulations (SimulateShot, SimulateSwing, SimulateFlight, "
          "StartSwing), apart from gRPC's and the tick workers, at a lower priority; 0: one "
          "per core");
ABSL_FLAG(int, max_queued_simulations, 64,
          "Simulations that may wait for a worker; more are refused with RESOURCE_EXHAUSTED");
ABSL_FLAG(Seconds, max_request_cpu, Seconds{absl::Seconds(10)},
          "CPU time one simulation request may use before it is stopped with "
          "RESOURCE_EXHAUSTED, in [10ms, 1h]");
ABSL_FLAG(double, clock_rate, 1.0,
          "Table and session time per wall-clock time, in [0.01, 1000]: 1 is real time; more "
          "plays every world faster (tests, bots, replays). Outcomes depend on ticks only");
ABSL_FLAG(int, watcher_backlog, 1024,
          "Unsent events a watcher may hold before it is resynced (full state, events lost)");
ABSL_FLAG(std::string, data_dir, "",
          "Keep every table and session in a journal (SQLite) in this directory, restored on "
          "start; empty: everything in memory, lost when the process ends");
ABSL_FLAG(std::string, store, "",
          "Keep the journal in PostgreSQL instead (postgresql://user@host:port/db), for a fleet "
          "of servers; --data_dir is then ignored");
ABSL_FLAG(std::string, node, "",
          "This server's name in the PostgreSQL store (its lease and its worlds); default: the "
          "host name");
ABSL_FLAG(Seconds, lease, Seconds{absl::Seconds(10)},
          "PostgreSQL: how long this node's lease lasts unrenewed (renewed every third of it); "
          "another server with --adopt takes its worlds over once it lapses");
ABSL_FLAG(bool, adopt, false,
          "PostgreSQL: take over (and keep watching for) the worlds of nodes whose lease lapsed");

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "sportsim-server [--listen=HOST:PORT] [--port=N]: serves sportsim.v1 (Server, Swing, Billiards), "
      "gRPC health and reflection. Stops cleanly on SIGINT or SIGTERM. --helpfull lists flags.");
  // absl flag names cannot contain '-': accept --metrics-listen for --metrics_listen (the name
  // before any '=' only).
  std::vector<std::string> args(argv, argv + argc);
  for (size_t i = 1; i < args.size(); ++i) {
    std::string& a = args[i];
    if (a == "--") break;
    if (a.size() > 2 && a[0] == '-' && a[1] == '-') {
      const size_t end = std::min(a.find('='), a.size());
      for (size_t j = 2; j < end; ++j) {
        if (a[j] == '-') a[j] = '_';
      }
    }
  }
  std::vector<char*> arg_ptrs;
  for (std::string& a : args) arg_ptrs.push_back(a.data());
  absl::ParseCommandLine(static_cast<int>(arg_ptrs.size()), arg_ptrs.data());

  // Block the stop signals in every thread (gRPC's threads inherit this mask); main waits.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  sportsim::server::ServerConfig config;
  config.listen = absl::GetFlag(FLAGS_listen);
  config.metrics_listen = absl::GetFlag(FLAGS_metrics_listen);
  config.keepalive_time = absl::GetFlag(FLAGS_keepalive_time).d;
  config.keepalive_timeout = absl::GetFlag(FLAGS_keepalive_timeout).d;
  config.min_client_ping_interval = absl::GetFlag(FLAGS_min_client_ping_interval).d;
  config.max_receive_message_bytes = absl::GetFlag(FLAGS_max_request_bytes);
  config.tables.world.max_worlds = absl::GetFlag(FLAGS_max_tables);
  config.tables.world.max_watchers = absl::GetFlag(FLAGS_max_watchers_per_table);
  config.tick_workers = absl::GetFlag(FLAGS_tick_workers);
  config.tables.world.max_catchup_ticks = absl::GetFlag(FLAGS_max_catchup_ticks);
  config.tables.world.event_log = absl::GetFlag(FLAGS_event_log);
  config.tables.world.watcher_backlog = absl::GetFlag(FLAGS_watcher_backlog);
  config.sessions.world.max_worlds = absl::GetFlag(FLAGS_max_sessions);
  config.sessions.world.max_watchers = absl::GetFlag(FLAGS_max_watchers_per_session);
  config.sessions.world.max_catchup_ticks = config.tables.world.max_catchup_ticks;
  config.rounds.world.max_worlds = absl::GetFlag(FLAGS_max_rounds);
  config.rounds.world.max_watchers = absl::GetFlag(FLAGS_max_watchers_per_round);
  config.rounds.world.max_catchup_ticks = config.tables.world.max_catchup_ticks;
  const double clock_rate = absl::GetFlag(FLAGS_clock_rate);
  if (!(clock_rate >= 0.01 && clock_rate <= 1000)) {
    std::cerr << "sportsim-server: --clock_rate must be in [0.01, 1000], got " << clock_rate
              << "\n";
    return 2;
  }
  if (const absl::Duration grace = absl::GetFlag(FLAGS_shutdown_grace).d;
      grace < absl::ZeroDuration() || grace > absl::Hours(1)) {
    std::cerr << "sportsim-server: --shutdown_grace must be in [0s, 1h], got "
              << absl::FormatDuration(grace) << "\n";
    return 2;
  }
  config.http_listen = absl::GetFlag(FLAGS_http_listen);
  config.open_connect.listen = absl::GetFlag(FLAGS_open_connect_listen);
  config.open_connect.idle_timeout = absl::GetFlag(FLAGS_open_connect_idle_timeout);
  if (config.open_connect.idle_timeout < absl::Seconds(1) ||
      config.open_connect.idle_timeout > absl::Hours(1)) {
    std::cerr << "sportsim-server: --open_connect_idle_timeout must be in [1s, 1h], got "
              << absl::FormatDuration(config.open_connect.idle_timeout) << "\n";
    return 2;
  }
  config.web_root = absl::GetFlag(FLAGS_web_root);
  config.http_cors_origins = absl::GetFlag(FLAGS_http_cors_origins);
  config.http_max_streams_per_client = absl::GetFlag(FLAGS_http_max_streams_per_client);
  config.http.max_streams = absl::GetFlag(FLAGS_http_max_streams);
  config.http.max_connections = absl::GetFlag(FLAGS_http_max_connections);
  config.http.max_connections_per_client = absl::GetFlag(FLAGS_http_max_connections_per_client);
  config.http.max_calls_per_client = absl::GetFlag(FLAGS_http_max_calls_per_client);
  config.http.idle_timeout = absl::GetFlag(FLAGS_http_idle_timeout).d;
  config.http.header_timeout = absl::GetFlag(FLAGS_http_header_timeout).d;
  config.http.body_timeout = absl::GetFlag(FLAGS_http_body_timeout).d;
  config.http.call_deadline = absl::GetFlag(FLAGS_http_call_deadline).d;
  config.http.threads = absl::GetFlag(FLAGS_http_threads);
  config.streams.window_bytes = absl::GetFlag(FLAGS_stream_window_bytes);
  config.streams.stall_timeout = absl::GetFlag(FLAGS_stream_stall_timeout).d;
  config.streams.upload_bytes = absl::GetFlag(FLAGS_max_upload_bytes);
  if (config.streams.upload_bytes < (64 << 10) || config.streams.upload_bytes > (int64_t{1} << 36)) {
    std::cerr << "sportsim-server: --max_upload_bytes must be in [65536, 68719476736], got "
              << config.streams.upload_bytes << "\n";
    return 2;
  }
  if (config.streams.window_bytes < (16 << 10) || config.streams.window_bytes > (int64_t{1} << 30)) {
    std::cerr << "sportsim-server: --stream_window_bytes must be in [16384, 1073741824], got "
              << config.streams.window_bytes << "\n";
    return 2;
  }
  const struct {
    const char* name;
    absl::Duration value, lo, hi;
  } durations[] = {{"http_idle_timeout", config.http.idle_timeout, absl::Seconds(1), absl::Hours(24)},
                   {"http_header_timeout", config.http.header_timeout, absl::Milliseconds(100), absl::Hours(1)},
                   {"http_body_timeout", config.http.body_timeout, absl::Milliseconds(100), absl::Hours(1)},
                   {"http_call_deadline", config.http.call_deadline, absl::Milliseconds(100), absl::Hours(24)},
                   {"stream_stall_timeout", config.streams.stall_timeout, absl::ZeroDuration(), absl::Hours(24)}};
  for (const auto& d : durations) {
    if (d.value < d.lo || d.value > d.hi) {
      std::cerr << "sportsim-server: --" << d.name << " must be in [" << absl::FormatDuration(d.lo)
                << ", " << absl::FormatDuration(d.hi) << "], got " << absl::FormatDuration(d.value)
                << "\n";
      return 2;
    }
  }
  config.work.workers = absl::GetFlag(FLAGS_sim_workers);
  config.work.max_queued = absl::GetFlag(FLAGS_max_queued_simulations);
  config.work.cpu_budget = absl::GetFlag(FLAGS_max_request_cpu).d;
  if (config.work.cpu_budget < absl::Milliseconds(10) || config.work.cpu_budget > absl::Hours(1)) {
    std::cerr << "sportsim-server: --max_request_cpu must be in [10ms, 1h], got "
              << absl::FormatDuration(config.work.cpu_budget) << "\n";
    return 2;
  }
  config.tables.world.clock_rate = clock_rate;
  config.sessions.world.clock_rate = clock_rate;
  config.sessions.world.watcher_backlog = config.tables.world.watcher_backlog;
  config.rounds.world.clock_rate = clock_rate;
  config.rounds.world.watcher_backlog = config.tables.world.watcher_backlog;
  const struct {
    const char* name;
    int value, lo, hi;
  } checks[] = {{"max_request_bytes", config.max_receive_message_bytes, 1024, 64 << 20},
                {"max_tables", config.tables.world.max_worlds, 1, 1000000},
                {"max_watchers_per_table", config.tables.world.max_watchers, 1, 100000},
                {"tick_workers", config.tick_workers, 0, 256},
                {"sim_workers", config.work.workers, 0, 256},
                {"http_max_streams_per_client", config.http_max_streams_per_client, 1, 64},
                {"http_max_streams", config.http.max_streams, 1, 100000},
                {"http_max_connections", config.http.max_connections, 1, 100000},
                {"http_max_connections_per_client", config.http.max_connections_per_client, 1, 100000},
                {"http_max_calls_per_client", config.http.max_calls_per_client, 1, 10000},
                {"http_threads", config.http.threads, 1, 64},
                {"max_queued_simulations", config.work.max_queued, 0, 100000},
                {"max_catchup_ticks", config.tables.world.max_catchup_ticks, 1, 100000},
                {"event_log", config.tables.world.event_log, 1, 10000000},
                {"watcher_backlog", config.tables.world.watcher_backlog, 1, 10000000},
                {"max_sessions", config.sessions.world.max_worlds, 1, 1000000},
                {"max_watchers_per_session", config.sessions.world.max_watchers, 1, 100000},
                {"max_rounds", config.rounds.world.max_worlds, 1, 1000000},
                {"max_watchers_per_round", config.rounds.world.max_watchers, 1, 100000}};
  for (const auto& c : checks) {
    if (c.value < c.lo || c.value > c.hi) {
      std::cerr << "sportsim-server: --" << c.name << " must be in [" << c.lo << ", " << c.hi
                << "], got " << c.value << "\n";
      return 2;
    }
  }
  config.store.data_dir = absl::GetFlag(FLAGS_data_dir);
  config.store.postgres_uri = absl::GetFlag(FLAGS_store);
  config.store.node = absl::GetFlag(FLAGS_node);
  if (config.store.node.empty()) {
    char host[256] = {};
    config.store.node = gethostname(host, sizeof host - 1) == 0 && host[0] != 0 ? host : "local";
  }
  config.store.lease = absl::GetFlag(FLAGS_lease).d;
  config.adopt = absl::GetFlag(FLAGS_adopt);
  if (!config.store.postgres_uri.empty() &&
      (config.store.lease < absl::Seconds(1) || config.store.lease > absl::Hours(1))) {
    std::cerr << "sportsim-server: --lease must be in [1s, 1h], got "
              << absl::FormatDuration(config.store.lease) << "\n";
    return 2;
  }
  if (config.adopt && config.store.postgres_uri.empty()) {
    std::cerr << "sportsim-server: --adopt needs --store postgresql://... (a single node's "
                 "SQLite journal has no other nodes to adopt from)\n";
    return 2;
  }
  if (const int port = absl::GetFlag(FLAGS_port); port >= 0) {
    absl::StatusOr<sportsim::server::ListenAddress> a =
        sportsim::server::ParseListenAddress(config.listen);
    if (!a.ok()) {
      std::cerr << "sportsim-server: " << a.status().message() << "\n";
      return 2;
    }
    const bool v6 = a->host.find(':') != std::string::npos;
    config.listen = v6 ? absl::StrCat("[", a->host, "]:", port) : absl::StrCat(a->host, ":", port);
  }
  absl::StatusOr<std::unique_ptr<sportsim::server::ServerApp>> app =
      sportsim::server::ServerApp::Start(config);
  if (!app.ok()) {
    std::cerr << "sportsim-server: " << app.status().message() << "\n";
    return 2;
  }
  std::cout << "sportsim-server listening on " << (*app)->address() << std::endl;
  if ((*app)->open_connect_port() != 0) {
    std::cout << "sportsim-server Open Connect (launch monitors) on port "
              << (*app)->open_connect_port() << std::endl;
  }
  if ((*app)->http_port() != 0) {
    std::cout << "sportsim-server gRPC-Web and viewer on port " << (*app)->http_port()
              << std::endl;
  }
  if ((*app)->metrics_port() != 0) {
    std::cout << "sportsim-server metrics on port " << (*app)->metrics_port() << " (/metrics)"
              << std::endl;
  }

  int sig = 0;
  sigwait(&stop_signals, &sig);
  std::cout << "sportsim-server: " << (sig == SIGINT ? "SIGINT" : "SIGTERM")
            << ", draining" << std::endl;
  (*app)->Shutdown(absl::GetFlag(FLAGS_shutdown_grace).d);
  (*app)->Wait();
  std::cout << "sportsim-server: stopped" << std::endl;
  return 0;
}
