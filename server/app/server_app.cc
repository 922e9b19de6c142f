#include "server/app/server_app.h"

#include <google/protobuf/stubs/logging.h>

#include <iostream>

#include <netdb.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <thread>

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpc/grpc.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/notification.h"
#include "server/rpc/services.h"

namespace sportsim::server {
namespace {

// A duration in whole milliseconds, as gRPC's integer channel arguments take it.
int DurationMs(absl::Duration d) {
  return static_cast<int>(std::min<int64_t>(absl::ToInt64Milliseconds(d), INT32_MAX));
}

// Binds a throwaway socket to learn, with the OS's own words, whether gRPC will be able to
// listen there (gRPC's own failure is a multi-line log and a null server).
absl::Status CheckBindable(const ListenAddress& a) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* res = nullptr;
  const std::string port = std::to_string(a.port);
  const int rc = getaddrinfo(a.host.c_str(), port.c_str(), &hints, &res);
  if (rc != 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("cannot resolve host '%s': %s", a.host, gai_strerror(rc)));
  }
  absl::Status status = absl::OkStatus();
  for (addrinfo* ai = res; ai != nullptr; ai = ai->ai_next) {
    const int fd = socket(ai->ai_family, ai->ai_socktype, ai->ai_protocol);
    if (fd < 0) continue;
    const int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    if (bind(fd, ai->ai_addr, ai->ai_addrlen) != 0) {
      status = absl::UnavailableError(
          absl::StrFormat("cannot listen on %s:%d: %s", a.host, a.port, std::strerror(errno)));
    }
    close(fd);
    break;  // gRPC binds the first address that resolves; so do we
  }
  freeaddrinfo(res);
  return status;
}

}  // namespace

absl::StatusOr<ListenAddress> ParseListenAddress(std::string_view address) {
  const auto bad = [&](std::string_view why) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "--listen must be host:port or [ipv6]:port with a port in [0, 65535], got '%s' (%s)",
        address, why));
  };
  ListenAddress out;
  std::string_view port;
  if (!address.empty() && address.front() == '[') {
    const size_t close = address.find(']');
    if (close == std::string_view::npos || close + 1 >= address.size() ||
        address[close + 1] != ':') {
      return bad("unterminated [ipv6] or missing :port");
    }
    out.host = std::string(address.substr(1, close - 1));
    port = address.substr(close + 2);
  } else {
    const size_t colon = address.rfind(':');
    if (colon == std::string_view::npos) return bad("missing :port");
    out.host = std::string(address.substr(0, colon));
    if (out.host.find(':') != std::string::npos) return bad("an IPv6 host needs [brackets]");
    port = address.substr(colon + 1);
  }
  if (out.host.empty()) return bad("empty host");
  int value = -1;
  const auto [ptr, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (port.empty() || ec != std::errc() || ptr != port.data() + port.size() || value < 0 ||
      value > 65535) {
    return bad("bad port");
  }
  out.port = value;
  return out;
}

#ifndef SPORTSIM_WEB_ROOT
#define SPORTSIM_WEB_ROOT ""
#endif
const char* const kDefaultWebRoot = SPORTSIM_WEB_ROOT;

namespace {

std::atomic<int64_t> protobuf_log_messages{0};

// libprotobuf logs one ERROR line per request with a malformed string field (invalid UTF-8):
// a client could fill the server's log at will. Such lines are counted instead
// (sportsim_malformed_messages_total); anything graver still goes to stderr.
void CountProtobufLog(google::protobuf::LogLevel level, const char* filename, int line,
                      const std::string& message) {
  if (level <= google::protobuf::LOGLEVEL_ERROR) {
    protobuf_log_messages.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  std::cerr << "libprotobuf " << filename << ":" << line << ": " << message << "\n";
}

}  // namespace

void InstallProtobufLogCounter() { google::protobuf::SetLogHandler(&CountProtobufLog); }
int64_t ProtobufLogMessages() { return protobuf_log_messages.load(std::memory_order_relaxed); }

absl::StatusOr<std::unique_ptr<ServerApp>> ServerApp::Start(const ServerConfig& config) {
  struct {
    const char* name;
    absl::Duration value, lo, hi;
  } durations[] = {
      {"keepalive_time", config.keepalive_time, absl::Milliseconds(10), absl::Hours(24)},
      {"keepalive_timeout", config.keepalive_timeout, absl::Milliseconds(10), absl::Hours(1)},
      {"min_client_ping_interval", config.min_client_ping_interval, absl::Milliseconds(10),
       absl::Hours(24)}};
  for (const auto& d : durations) {
    if (d.value < d.lo || d.value > d.hi) {
      return absl::InvalidArgumentError(
          absl::StrFormat("--%s must be in [%s, %s], got %s", d.name, absl::FormatDuration(d.lo),
                          absl::FormatDuration(d.hi), absl::FormatDuration(d.value)));
    }
  }
  absl::StatusOr<ListenAddress> address = ParseListenAddress(config.listen);
  if (!address.ok()) return address.status();
  if (address->port != 0) {
    if (absl::Status s = CheckBindable(*address); !s.ok()) return s;
  }

  InstallProtobufLogCounter();
  grpc::EnableDefaultHealthCheckService(true);
  grpc::reflection::InitProtoReflectionServerBuilderPlugin();

  std::unique_ptr<ServerApp> app(new ServerApp());
  app->host_ = address->host;
  if (!config.store.data_dir.empty() || !config.store.postgres_uri.empty()) {
    store::StoreOptions options = config.store;
    options.clock_rate = config.tables.world.clock_rate;
    absl::StatusOr<std::unique_ptr<store::Store>> opened = store::Store::Open(options);
    if (!opened.ok()) return opened.status();
    app->store_ = *std::move(opened);
  }
  app->adopt_ = config.adopt && app->store_ != nullptr;
  app->services_.push_back(MakeInfoService());
  app->scheduler_ = std::make_unique<TickScheduler>(config.tick_workers);
  app->tables_ = std::make_unique<TableRegistry>(config.tables, app->scheduler_.get());
  app->sessions_ = std::make_unique<SessionRegistry>(config.sessions, app->scheduler_.get());
  app->rounds_ = std::make_unique<RoundRegistry>(config.rounds, app->scheduler_.get());
  if (app->store_ != nullptr) {
    app->tables_->SetJournal(app->store_.get());
    app->sessions_->SetJournal(app->store_.get());
    app->rounds_->SetJournal(app->store_.get());
    // Every world of this node comes back before the first call is served.
    absl::StatusOr<std::vector<StoredWorld>> mine = app->store_->Load();
    if (!mine.ok()) return mine.status();
    app->RestoreWorlds(*mine);
    if (app->adopt_) {
      absl::StatusOr<std::vector<StoredWorld>> adopted = app->store_->Adopt();
      if (!adopted.ok()) return adopted.status();
      app->RestoreWorlds(*adopted);
    }
  }
  app->pool_ = std::make_unique<WorkPool>(config.work);
  app->services_.push_back(MakeSwingService(app->sessions_.get(), app->rounds_.get(), app->pool_.get()));
  app->services_.push_back(MakeBilliardsService(app->tables_.get(), app->pool_.get(),
                                                config.max_send_message_bytes,
                                                absl::ToDoubleSeconds(config.work.cpu_budget),
                                                config.streams));

  app->rpc_counters_ = std::make_unique<RpcCounters>();
  if (!config.metrics_listen.empty()) {
    absl::StatusOr<std::unique_ptr<MetricsEndpoint>> metrics =
        MetricsEndpoint::Start(config.metrics_listen, app->tables_.get(), app->sessions_.get(),
                               app->scheduler_.get(), app->pool_.get(),
                               app->rpc_counters_.get(), app->store_.get());
    if (!metrics.ok()) return metrics.status();
    app->metrics_ = *std::move(metrics);
  }

  grpc::ServerBuilder builder;
  {
    std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> creators;
    creators.push_back(MakeRpcCountingInterceptor(app->rpc_counters_.get()));
    builder.experimental().SetInterceptorCreators(std::move(creators));
  }
  // Without this, gRPC sets SO_REUSEPORT and a second server would share a busy port silently.
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, 0);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, DurationMs(config.keepalive_time));
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, DurationMs(config.keepalive_timeout));
  // Server pings need no open call (an idle channel between streams is kept checked), and
  // clients may keep an idle channel alive with their own pings.
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS,
                             DurationMs(config.min_client_ping_interval));
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PING_STRIKES, 2);
  builder.SetMaxReceiveMessageSize(config.max_receive_message_bytes);
  builder.SetMaxSendMessageSize(config.max_send_message_bytes);
  const std::string target = address->host.find(':') != std::string::npos
                                 ? absl::StrCat("[", address->host, "]:", address->port)
                                 : absl::StrCat(address->host, ":", address->port);
  builder.AddListeningPort(target, grpc::InsecureServerCredentials(), &app->port_);
  for (auto& service : app->services_) builder.RegisterService(service.get());
  app->server_ = builder.BuildAndStart();
  if (app->server_ == nullptr || app->port_ == 0) {
    return absl::UnavailableError(absl::StrFormat("cannot listen on %s", target));
  }
  if (!config.http_listen.empty()) {
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(config.max_send_message_bytes);
    args.SetMaxSendMessageSize(config.max_receive_message_bytes);
    absl::StatusOr<ListenAddress> http_address = ParseListenAddress(config.http_listen);
    if (!http_address.ok()) {
      app->server_->Shutdown();
      return absl::InvalidArgumentError(absl::StrCat(
          "--http_listen: ", http_address.status().message()));
    }
    absl::StatusOr<std::unique_ptr<GrpcWebGateway>> web = GrpcWebGateway::Start(
        GrpcWebConfig{.listen = config.http_listen,
                      .host = http_address->host,
                      .port = http_address->port,
                      .web_root = config.web_root,
                      .cors_origins = config.http_cors_origins,
                      .max_request_bytes = config.max_receive_message_bytes,
                      .max_streams_per_client = config.http_max_streams_per_client,
                      .limits = config.http,
                      .window_bytes = config.streams.window_bytes},
        app->server_->InProcessChannel(args));
    if (!web.ok()) {
      app->server_->Shutdown();
      return web.status();
    }
    app->web_ = *std::move(web);
  }
  if (!config.open_connect.listen.empty()) {
    absl::StatusOr<std::unique_ptr<OpenConnectListener>> oc =
        OpenConnectListener::Start(config.open_connect, app->rounds_.get(), app->pool_.get());
    if (!oc.ok()) {
      if (app->web_ != nullptr) app->web_->Shutdown();
      app->server_->Shutdown();
      return oc.status();
    }
    app->open_connect_ = *std::move(oc);
    const size_t colon = config.open_connect.listen.rfind(':');
    app->rounds_->SetMonitorListen(
        absl::StrCat(config.open_connect.listen.substr(0, colon), ":", app->open_connect_->port()));
  }
  app->server_->GetHealthCheckService()->SetServingStatus(true);
  if (app->store_ != nullptr) {
    const absl::Duration adopt_every = config.store.lease / 2;
    ServerApp* self = app.get();
    app->monitor_ = std::thread([self, adopt_every] { self->MonitorStore(adopt_every); });
  }
  return app;
}

void ServerApp::RestoreWorlds(const std::vector<StoredWorld>& worlds) {
  const absl::Time start = absl::Now();
  RestoreReport r;
  for (const StoredWorld& w : worlds) {
    absl::Status s;
    if (w.kind == "table") {
      s = tables_->Restore(w);
      r.tables += s.ok();
    } else if (w.kind == "session") {
      s = sessions_->Restore(w);
      r.sessions += s.ok();
    } else if (w.kind == "round") {
      s = rounds_->Restore(w);
      r.rounds += s.ok();
    } else {
      s = absl::DataLossError(absl::StrFormat("%s: unknown kind %s", w.world_id, w.kind));
    }
    if (!s.ok()) {
      ++r.failed;
      std::cerr << "sportsim-server: not restored: " << s.message() << "\n";
    }
  }
  r.seconds = absl::ToDoubleSeconds(absl::Now() - start);
  if (!worlds.empty()) {
    std::cerr << absl::StrFormat(
        "sportsim-server: restored %d tables, %d sessions and %d rounds from %s in %.3f s%s\n",
        r.tables, r.sessions, r.rounds, store_->Describe(), r.seconds,
        r.failed > 0 ? absl::StrFormat(" (%d failed)", r.failed) : "");
  }
  absl::MutexLock lock(&monitor_mu_);
  restored_.tables += r.tables;
  restored_.sessions += r.sessions;
  restored_.rounds += r.rounds;
  restored_.failed += r.failed;
  restored_.seconds += r.seconds;
}

RestoreReport ServerApp::restored() const {
  absl::MutexLock lock(&monitor_mu_);
  return restored_;
}

void ServerApp::MonitorStore(absl::Duration adopt_every) {
  bool serving = true;
  absl::Time next_adopt = absl::Now() + adopt_every;
  absl::MutexLock lock(&monitor_mu_);
  for (;;) {
    monitor_mu_.AwaitWithTimeout(absl::Condition(&monitor_stop_), absl::Milliseconds(100));
    if (monitor_stop_) return;
    monitor_mu_.Unlock();
    // Health answers NOT_SERVING while no command can be made durable.
    const bool healthy = store_->Healthy().ok();
    if (healthy != serving && !shut_down_.load()) {
      server_->GetHealthCheckService()->SetServingStatus(healthy);
      serving = healthy;
    }
    if (adopt_ && healthy && absl::Now() >= next_adopt) {
      next_adopt = absl::Now() + adopt_every;
      absl::StatusOr<std::vector<StoredWorld>> adopted = store_->Adopt();
      if (adopted.ok()) {
        RestoreWorlds(*adopted);
      } else {
        std::cerr << "sportsim-server: adopt: " << adopted.status().message() << "\n";
      }
    }
    monitor_mu_.Lock();
  }
}

ServerApp::~ServerApp() {
  Shutdown(absl::ZeroDuration());
  Wait();
  // No wake may reach a registry being destroyed.
  if (scheduler_ != nullptr) scheduler_->Stop();
  // The journal goes last: no call is left to write to it.
  if (store_ != nullptr) store_->Close();
}

int ServerApp::http_port() const { return web_ != nullptr ? web_->port() : 0; }

int ServerApp::metrics_port() const { return metrics_ != nullptr ? metrics_->port() : 0; }

std::string ServerApp::address() const {
  return host_.find(':') != std::string::npos ? absl::StrCat("[", host_, "]:", port_)
                                               : absl::StrCat(host_, ":", port_);
}

void ServerApp::Shutdown(absl::Duration grace) {
  if (server_ == nullptr || shut_down_.exchange(true)) return;
  if (monitor_.joinable()) {
    {
      absl::MutexLock lock(&monitor_mu_);
      monitor_stop_ = true;
    }
    monitor_.join();
  }
  server_->GetHealthCheckService()->SetServingStatus(false);
  tables_->Shutdown(absl::UnavailableError("the server is shutting down"));
  sessions_->Shutdown(absl::UnavailableError("the server is shutting down"));
  rounds_->Shutdown(absl::UnavailableError("the server is shutting down"));
  if (web_ != nullptr) web_->Shutdown();
  if (open_connect_ != nullptr) open_connect_->Stop();
  scheduler_->Stop();
  // Queued simulations end now (UNAVAILABLE); running ones get the grace, then stop at their
  // next poll. Then the calls still open get what is left of the grace.
  const absl::Time deadline = absl::Now() + grace;
  pool_->Stop(grace);
  // gRPC's shutdown waits for every connection to close, idle ones too (a client that keeps its
  // channel open would hold the whole grace). Once no call is in flight, cancel-all closes the
  // connections; it is repeated while shutdown runs, for a connection that raced in.
  absl::Notification done;
  std::thread closer([this, &done] {
    while (!done.WaitForNotificationWithTimeout(absl::Milliseconds(20))) {
      if (rpc_counters_->in_flight() == 0) grpc_server_cancel_all_calls(server_->c_server());
    }
  });
  server_->Shutdown(absl::ToChronoTime(std::max(deadline, absl::Now())));
  done.Notify();
  closer.join();
}

void ServerApp::Wait() {
  if (server_ != nullptr) server_->Wait();
}

}  // namespace sportsim::server
