#include "server/rpc/grpc_web.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <google/protobuf/descriptor.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/support/byte_buffer.h>
#include <microhttpd.h>
#include <netdb.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <thread>
#include <utility>

#include "absl/base/thread_annotations.h"
#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "absl/synchronization/mutex.h"
#include "grpc/health/v1/health.pb.h"
#include "server/rpc/status.h"

namespace sportsim::server {

namespace {

using Clock = std::chrono::steady_clock;

// "grpc-message" is percent-encoded (the gRPC HTTP/2 spec): anything outside printable ASCII,
// and '%' itself.
std::string PercentEncode(std::string_view s) {
  std::string out;
  for (const char ch : s) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (c >= 0x20 && c < 0x7f && c != '%') {
      out += ch;
    } else {
      out += absl::StrFormat("%%%02X", c);
    }
  }
  return out;
}

std::string Frame(uint8_t flag, std::string_view payload) {
  std::string f(5, '\0');
  f[0] = static_cast<char>(flag);
  const uint32_t n = static_cast<uint32_t>(payload.size());
  f[1] = static_cast<char>(n >> 24);
  f[2] = static_cast<char>(n >> 16);
  f[3] = static_cast<char>(n >> 8);
  f[4] = static_cast<char>(n);
  f.append(payload);
  return f;
}

std::string TrailersFrame(const grpc::Status& status) {
  return Frame(0x80, absl::StrCat("grpc-status:", static_cast<int>(status.error_code()),
                                  "\r\ngrpc-message:", PercentEncode(status.error_message()),
                                  "\r\n"));
}

std::string ToString(const grpc::ByteBuffer& bb) {
  std::vector<grpc::Slice> slices;
  std::string out;
  if (!bb.Dump(&slices).ok()) return out;
  for (const grpc::Slice& s : slices) out.append(reinterpret_cast<const char*>(s.begin()), s.size());
  return out;
}

grpc::ByteBuffer ToBuffer(std::string_view bytes) {
  grpc::Slice slice(bytes.data(), bytes.size());
  return grpc::ByteBuffer(&slice, 1);
}

std::string_view MimeOf(std::string_view name) {
  if (name.ends_with(".html")) return "text/html; charset=utf-8";
  if (name.ends_with(".js")) return "text/javascript; charset=utf-8";
  if (name.ends_with(".css")) return "text/css; charset=utf-8";
  if (name.ends_with(".map") || name.ends_with(".json")) return "application/json";
  if (name.ends_with(".svg")) return "image/svg+xml";
  if (name.ends_with(".png")) return "image/png";
  return "application/octet-stream";
}

using Headers = std::vector<std::pair<std::string, std::string>>;

// Queues a whole response with a body (copied).
MHD_Result Respond(MHD_Connection* conn, unsigned code, std::string_view type,
                   const Headers& headers, std::string_view body) {
  MHD_Response* r = MHD_create_response_from_buffer(
      body.size(), const_cast<char*>(body.data()), MHD_RESPMEM_MUST_COPY);
  if (r == nullptr) return MHD_NO;
  MHD_add_response_header(r, "Content-Type", std::string(type).c_str());
  MHD_add_response_header(r, "Cache-Control", "no-store");
  for (const auto& [k, v] : headers) MHD_add_response_header(r, k.c_str(), v.c_str());
  const MHD_Result ok = MHD_queue_response(conn, code, r);
  MHD_destroy_response(r);
  return ok;
}

const char* Header(MHD_Connection* conn, const char* name) {
  return MHD_lookup_connection_value(conn, MHD_HEADER_KIND, name);
}

// Seconds for libmicrohttpd's options, at least 1.
unsigned WholeSeconds(absl::Duration d) {
  return static_cast<unsigned>(std::clamp<int64_t>(absl::ToInt64Seconds(absl::Ceil(d, absl::Seconds(1))), 1, 1 << 30));
}

}  // namespace

std::optional<std::chrono::nanoseconds> ParseGrpcTimeout(std::string_view v) {
  // TimeoutValue: at most 8 ASCII digits; TimeoutUnit: one letter (gRPC over HTTP/2).
  if (v.size() < 2 || v.size() > 9) return std::nullopt;
  int64_t n = 0;
  for (const char c : v.substr(0, v.size() - 1)) {
    if (c < '0' || c > '9') return std::nullopt;
    n = n * 10 + (c - '0');
  }
  int64_t unit_ns = 0;
  switch (v.back()) {
    case 'H': unit_ns = int64_t{3600} * 1000000000; break;
    case 'M': unit_ns = int64_t{60} * 1000000000; break;
    case 'S': unit_ns = 1000000000; break;
    case 'm': unit_ns = 1000000; break;
    case 'u': unit_ns = 1000; break;
    case 'n': unit_ns = 1; break;
    default: return std::nullopt;
  }
  // 99999999 hours overflows 64-bit nanoseconds: anything past a century is a century.
  constexpr int64_t kCentury = int64_t{100} * 365 * 24 * 3600 * 1000000000;
  if (n > kCentury / unit_ns) return std::chrono::nanoseconds(kCentury);
  return std::chrono::nanoseconds(n * unit_ns);
}

// ---------------------------------------------------------------------------------------------

class GrpcWebGateway::Impl {
 public:
  struct Call;
  // What a connection is doing, for the watchdog.
  enum class Phase {
    kHead,   // waiting for a request's head (a new or kept-alive connection)
    kBody,   // the head is in, the body is arriving
    kCall,   // a call is under way (its connection suspended while it waits)
    kReply,  // a static or error reply is being sent
  };
  struct Conn {
    int fd = -1;
    std::string client;
    Phase phase = Phase::kHead;
    Clock::time_point since;
    std::shared_ptr<Call> call;
    bool over_limit = false;  // opened past a connection limit: refused at its first request
  };
  // One request on a connection (libmicrohttpd's req_cls).
  struct Request {
    std::string body;
    bool too_large = false;
    std::shared_ptr<Call> call;
  };
  // One gRPC call, shared by its HTTP side (the request and the streamed response) and its
  // gRPC side (the completion queue's operations).
  struct Call {
    Impl* gw = nullptr;
    MHD_Connection* conn = nullptr;
    std::string client;
    bool stream = false;
    bool text = false;
    Headers headers;  // CORS
    std::string reply_type;
    grpc::ClientContext ctx;
    grpc::ByteBuffer request;
    std::unique_ptr<grpc::GenericClientAsyncResponseReader> unary;
    std::unique_ptr<grpc::GenericClientAsyncReaderWriter> rw;
    grpc::ByteBuffer message;  // the unary response, or the stream's message being read
    grpc::Status status;
    absl::Mutex mu;
    std::string out ABSL_GUARDED_BY(mu);  // stream: bytes not yet handed to the client
    bool grpc_done ABSL_GUARDED_BY(mu) = false;  // the call's status is in
    bool suspended ABSL_GUARDED_BY(mu) = false;  // its HTTP connection is suspended
    bool read_paused ABSL_GUARDED_BY(mu) = false;  // out is full: the next Read waits
    bool departed ABSL_GUARDED_BY(mu) = false;  // the client left (the watchdog saw it)

    // Under mu: whether the caller must resume the connection (then outside mu).
    bool TakeResume() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
      if (!suspended) return false;
      suspended = false;
      return true;
    }
    void Suspend() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
      suspended = true;
      MHD_suspend_connection(conn);
    }
  };
  enum class OpKind { kUnaryDone, kStarted, kWritten, kWritesDone, kRead, kFinished };
  struct Op {
    std::shared_ptr<Call> call;
    OpKind kind;
  };

  explicit Impl(GrpcWebConfig config) : config_(std::move(config)) {}

  absl::Status Start(std::shared_ptr<grpc::Channel> channel);
  void Shutdown();
  void Stop();  // the destructor's: waits for calls, stops the HTTP server and the threads

  int port() const { return port_; }
  int open_streams() const {
    absl::MutexLock lock(&mu_);
    return total_streams_;
  }
  int open_connections() const {
    absl::MutexLock lock(&conns_mu_);
    return static_cast<int>(conns_.size());
  }
  int64_t slow_closed() const { return slow_closed_.load(); }
  int64_t departed() const { return departed_.load(); }

  // libmicrohttpd's callbacks.
  MHD_Result Handle(MHD_Connection* conn, const char* url, const char* method,
                    const char* upload_data, size_t* upload_data_size, void** req_cls);
  void Completed(MHD_Connection* conn, void** req_cls);
  void Connection(MHD_Connection* conn, void** socket_context,
                  MHD_ConnectionNotificationCode code);
  static ssize_t ReadStream(void* cls, uint64_t pos, char* buf, size_t max);
  static void FreeStream(void* cls);

 private:
  MHD_Result Post(MHD_Connection* conn, Conn* c, Request* req, const std::string& path,
                  const std::string& origin);
  MHD_Result Static(MHD_Connection* conn, const std::string& path, const std::string& origin);
  MHD_Result Preflight(MHD_Connection* conn, const std::string& origin);
  MHD_Result Fail(MHD_Connection* conn, bool text, const Headers& cors, grpc::StatusCode code,
                  const std::string& message);
  Headers CorsHeaders(const std::string& origin) const;
  void SetPhase(Conn* c, Phase phase, std::shared_ptr<Call> call = nullptr);
  // Admission: false (and why) when a limit or the shutdown refuses the call.
  bool Track(Call* call, std::string* why);
  void Untrack(Call* call);
  void StartStream(const std::shared_ptr<Call>& call, const std::string& rpc);
  void IssueRead(const std::shared_ptr<Call>& call);
  void FinishStream(const std::shared_ptr<Call>& call);
  void OnOp(Op* op, bool ok);
  void PollQueue();
  void Watchdog();

  const GrpcWebConfig config_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<grpc::GenericStub> stub_;
  grpc::CompletionQueue cq_;
  std::thread cq_thread_;
  MHD_Daemon* http_ = nullptr;
  int port_ = 0;

  mutable absl::Mutex mu_;  // calls and their limits
  absl::CondVar calls_cv_;
  bool shut_down_ ABSL_GUARDED_BY(mu_) = false;
  std::set<Call*> calls_ ABSL_GUARDED_BY(mu_);
  std::map<std::string, int> streams_ ABSL_GUARDED_BY(mu_);  // per client address
  std::map<std::string, int> unary_ ABSL_GUARDED_BY(mu_);    // per client address
  int total_streams_ ABSL_GUARDED_BY(mu_) = 0;

  mutable absl::Mutex conns_mu_;  // connections, for the watchdog; before any Call::mu
  std::set<Conn*> conns_ ABSL_GUARDED_BY(conns_mu_);
  std::map<std::string, int> conns_per_client_ ABSL_GUARDED_BY(conns_mu_);
  bool stopping_ ABSL_GUARDED_BY(conns_mu_) = false;
  bool closing_idle_ ABSL_GUARDED_BY(conns_mu_) = false;
  absl::CondVar watchdog_cv_;
  std::thread watchdog_;
  std::atomic<int64_t> slow_closed_{0}, departed_{0};
};

namespace {

MHD_Result OnRequest(void* cls, MHD_Connection* conn, const char* url, const char* method,
                     const char* /*version*/, const char* upload_data, size_t* upload_data_size,
                     void** req_cls) {
  return static_cast<GrpcWebGateway::Impl*>(cls)->Handle(conn, url, method, upload_data,
                                                         upload_data_size, req_cls);
}

void OnCompleted(void* cls, MHD_Connection* conn, void** req_cls,
                 MHD_RequestTerminationCode /*code*/) {
  static_cast<GrpcWebGateway::Impl*>(cls)->Completed(conn, req_cls);
}

void OnConnection(void* cls, MHD_Connection* conn, void** socket_context,
                  MHD_ConnectionNotificationCode code) {
  static_cast<GrpcWebGateway::Impl*>(cls)->Connection(conn, socket_context, code);
}

std::string ClientAddress(MHD_Connection* conn) {
  const MHD_ConnectionInfo* info =
      MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
  if (info == nullptr || info->client_addr == nullptr) return "?";
  char buf[INET6_ADDRSTRLEN] = {};
  const sockaddr* sa = info->client_addr;
  if (sa->sa_family == AF_INET) {
    inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(sa)->sin_addr, buf, sizeof(buf));
  } else if (sa->sa_family == AF_INET6) {
    inet_ntop(AF_INET6, &reinterpret_cast<const sockaddr_in6*>(sa)->sin6_addr, buf, sizeof(buf));
  }
  return buf;
}

}  // namespace

absl::Status GrpcWebGateway::Impl::Start(std::shared_ptr<grpc::Channel> channel) {
  channel_ = std::move(channel);
  stub_ = std::make_unique<grpc::GenericStub>(channel_);
  // The methods are looked up in the generated descriptor pool. gRPC's built-in health service
  // brings no descriptors of its own: touching health.proto's here links them in, so that
  // /grpc.health.v1.Health/Check is served over gRPC-Web like every other unary RPC.
  (void)grpc::health::v1::HealthCheckRequest::descriptor();

  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* found = nullptr;
  const std::string port_text = absl::StrCat(config_.port);
  if (getaddrinfo(config_.host.empty() ? nullptr : config_.host.c_str(), port_text.c_str(),
                  &hints, &found) != 0 ||
      found == nullptr) {
    return absl::UnavailableError(
        absl::StrFormat("--http_listen: cannot resolve %s", config_.listen));
  }
  sockaddr_storage bind_addr{};
  std::memcpy(&bind_addr, found->ai_addr, std::min<size_t>(found->ai_addrlen, sizeof(bind_addr)));
  const bool v6 = found->ai_family == AF_INET6;
  freeaddrinfo(found);

  // Every connection is a descriptor: raise the soft limit to the hard one.
  rlimit nofile{};
  if (getrlimit(RLIMIT_NOFILE, &nofile) == 0 && nofile.rlim_cur < nofile.rlim_max) {
    nofile.rlim_cur = nofile.rlim_max;
    setrlimit(RLIMIT_NOFILE, &nofile);
  }

  const GrpcWebLimits& l = config_.limits;
  unsigned flags = MHD_USE_EPOLL_INTERNAL_THREAD | MHD_ALLOW_SUSPEND_RESUME;
  if (v6) flags |= MHD_USE_IPv6;
  // libmicrohttpd's own total is a little above ours, so that the connections in between get a
  // clear refusal (503) instead of a dropped socket.
  const unsigned hard_limit = static_cast<unsigned>(l.max_connections + 64);
  http_ = MHD_start_daemon(
      flags, 0, nullptr, nullptr, &OnRequest, this,                                 //
      MHD_OPTION_SOCK_ADDR, reinterpret_cast<sockaddr*>(&bind_addr),                //
      MHD_OPTION_LISTENING_ADDRESS_REUSE, 1u,                                       //
      MHD_OPTION_THREAD_POOL_SIZE, static_cast<unsigned>(std::max(1, l.threads)),  //
      MHD_OPTION_CONNECTION_LIMIT, hard_limit,                                      //
      MHD_OPTION_CONNECTION_TIMEOUT, WholeSeconds(l.idle_timeout),                  //
      MHD_OPTION_CONNECTION_MEMORY_LIMIT, static_cast<size_t>(64 << 10),            //
      MHD_OPTION_NOTIFY_COMPLETED, &OnCompleted, this,                              //
      MHD_OPTION_NOTIFY_CONNECTION, &OnConnection, this,                            //
      MHD_OPTION_END);
  if (http_ == nullptr) {
    return absl::UnavailableError(
        absl::StrFormat("--http_listen: cannot listen on %s", config_.listen));
  }
  const MHD_DaemonInfo* info = MHD_get_daemon_info(http_, MHD_DAEMON_INFO_BIND_PORT);
  port_ = info != nullptr ? info->port : 0;
  cq_thread_ = std::thread([this] { PollQueue(); });
  watchdog_ = std::thread([this] { Watchdog(); });
  return absl::OkStatus();
}

void GrpcWebGateway::Impl::Shutdown() {
  {
    absl::MutexLock lock(&mu_);
    shut_down_ = true;
    for (Call* call : calls_) call->ctx.TryCancel();
  }
  absl::MutexLock lock(&conns_mu_);
  closing_idle_ = true;  // the watchdog closes every connection that is between requests
  watchdog_cv_.Signal();
}

void GrpcWebGateway::Impl::Stop() {
  Shutdown();
  {
    // Every call ends soon once cancelled; a suspended connection must be resumed (each call
    // does it as it ends) before the HTTP server may stop.
    absl::MutexLock lock(&mu_);
    const absl::Time until = absl::Now() + absl::Seconds(5);
    while (!calls_.empty() && absl::Now() < until) calls_cv_.WaitWithDeadline(&mu_, until);
  }
  {
    absl::MutexLock lock(&conns_mu_);
    stopping_ = true;
    watchdog_cv_.Signal();
  }
  if (watchdog_.joinable()) watchdog_.join();
  if (http_ != nullptr) MHD_stop_daemon(http_);
  http_ = nullptr;
  cq_.Shutdown();
  if (cq_thread_.joinable()) cq_thread_.join();
}

// --- connections and the watchdog -------------------------------------------------------------

void GrpcWebGateway::Impl::Connection(MHD_Connection* conn, void** socket_context,
                                      MHD_ConnectionNotificationCode code) {
  if (code == MHD_CONNECTION_NOTIFY_STARTED) {
    auto* c = new Conn;
    const MHD_ConnectionInfo* info = MHD_get_connection_info(conn, MHD_CONNECTION_INFO_CONNECTION_FD);
    c->fd = info != nullptr ? info->connect_fd : -1;
    c->client = ClientAddress(conn);
    c->since = Clock::now();
    *socket_context = c;
    absl::MutexLock lock(&conns_mu_);
    int& mine = conns_per_client_[c->client];
    ++mine;
    c->over_limit = mine > config_.limits.max_connections_per_client ||
                    static_cast<int>(conns_.size()) >= config_.limits.max_connections;
    conns_.insert(c);
    return;
  }
  auto* c = static_cast<Conn*>(*socket_context);
  if (c == nullptr) return;
  {
    absl::MutexLock lock(&conns_mu_);
    conns_.erase(c);
    if (--conns_per_client_[c->client] <= 0) conns_per_client_.erase(c->client);
  }
  delete c;
  *socket_context = nullptr;
}

void GrpcWebGateway::Impl::SetPhase(Conn* c, Phase phase, std::shared_ptr<Call> call) {
  if (c == nullptr) return;
  absl::MutexLock lock(&conns_mu_);
  c->phase = phase;
  c->since = Clock::now();
  c->call = std::move(call);
}

// Every 100 ms: connections past their head or body deadline (or idle ones, once shutting
// down) are shut down, so that libmicrohttpd closes them; suspended calls whose client hung
// up are cancelled. The connection registry's lock is held while a socket is shut down, and
// libmicrohttpd reports a connection closed before it closes its socket, so the descriptor is
// always still the connection's.
void GrpcWebGateway::Impl::Watchdog() {
  const auto head = absl::ToChronoNanoseconds(config_.limits.header_timeout);
  const auto body = absl::ToChronoNanoseconds(config_.limits.body_timeout);
  std::vector<pollfd> fds;
  std::vector<std::shared_ptr<Call>> watched;
  absl::MutexLock lock(&conns_mu_);
  while (!stopping_) {
    watchdog_cv_.WaitWithTimeout(&conns_mu_, absl::Milliseconds(100));
    if (stopping_) break;
    const Clock::time_point now = Clock::now();
    fds.clear();
    watched.clear();
    for (Conn* c : conns_) {
      const bool late = (c->phase == Phase::kHead && (closing_idle_ || now - c->since > head)) ||
                        (c->phase == Phase::kBody && now - c->since > body);
      if (late && c->fd >= 0) {
        ::shutdown(c->fd, SHUT_RDWR);
        c->fd = -1;  // once
        if (!closing_idle_) slow_closed_.fetch_add(1);
        continue;
      }
      if (c->phase != Phase::kCall || c->call == nullptr || c->fd < 0) continue;
      absl::MutexLock call_lock(&c->call->mu);
      if (c->call->suspended && !c->call->departed && !c->call->grpc_done) {
        fds.push_back(pollfd{.fd = c->fd, .events = POLLRDHUP, .revents = 0});
        watched.push_back(c->call);
      }
    }
    if (fds.empty()) continue;
    // A hang-up only (POLLRDHUP, POLLHUP, POLLERR): bytes a client sends after its request are
    // not a departure.
    if (::poll(fds.data(), fds.size(), 0) <= 0) continue;
    for (size_t i = 0; i < fds.size(); ++i) {
      if ((fds[i].revents & (POLLRDHUP | POLLHUP | POLLERR)) == 0) continue;
      Call& call = *watched[i];
      {
        absl::MutexLock call_lock(&call.mu);
        call.departed = true;
      }
      departed_.fetch_add(1);
      call.ctx.TryCancel();  // its end resumes the connection, which then closes
    }
  }
}

// --- requests ----------------------------------------------------------------------------------

Headers GrpcWebGateway::Impl::CorsHeaders(const std::string& origin) const {
  if (origin.empty()) return {};
  const bool allowed = std::any_of(config_.cors_origins.begin(), config_.cors_origins.end(),
                                   [&](const std::string& o) { return o == "*" || o == origin; });
  if (!allowed) return {};
  return {{"Access-Control-Allow-Origin", origin},
          {"Vary", "Origin"},
          {"Access-Control-Expose-Headers", "grpc-status, grpc-message"}};
}

MHD_Result GrpcWebGateway::Impl::Handle(MHD_Connection* conn, const char* url,
                                        const char* method_c, const char* upload_data,
                                        size_t* upload_data_size, void** req_cls) {
  const MHD_ConnectionInfo* ci = MHD_get_connection_info(conn, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
  Conn* c = ci != nullptr ? static_cast<Conn*>(ci->socket_context) : nullptr;
  const std::string method = method_c != nullptr ? method_c : "";
  auto* req = static_cast<Request*>(*req_cls);
  if (req == nullptr) {  // the head is in
    req = new Request;
    *req_cls = req;
    SetPhase(c, Phase::kBody);
    if (c != nullptr && c->over_limit) {
      SetPhase(c, Phase::kReply);
      return Respond(conn, 429, "text/plain", {{"Connection", "close"}},
                     absl::StrFormat("too many connections (at most %d per client address, "
                                     "%d in all: sportsim-server --http_max_connections*)\n",
                                     config_.limits.max_connections_per_client,
                                     config_.limits.max_connections));
    }
    if (method != "POST") {
      // No body is read for these; the first call answers.
    } else {
      return MHD_YES;
    }
  }
  const std::string path = url != nullptr ? url : "/";
  const char* origin_h = Header(conn, "Origin");
  const std::string origin = origin_h != nullptr ? origin_h : "";
  if (method == "POST") {
    if (req->call == nullptr && *upload_data_size > 0) {  // the body, as it comes
      const size_t frame_limit = static_cast<size_t>(config_.max_request_bytes) + 5;
      const size_t limit = frame_limit * 4 / 3 + 8;  // base64 of the frame, or the frame
      if (req->body.size() + *upload_data_size > limit) req->too_large = true;
      if (!req->too_large) req->body.append(upload_data, *upload_data_size);
      *upload_data_size = 0;
      return MHD_YES;
    }
    return Post(conn, c, req, path, origin);
  }
  SetPhase(c, Phase::kReply);
  if (method == "OPTIONS") return Preflight(conn, origin);
  if (method == "GET" || method == "HEAD") return Static(conn, path, origin);
  return Respond(conn, 405, "text/plain", {{"Allow", "GET, POST, OPTIONS"}},
                 "gRPC-Web calls are POSTs; the viewer is GET\n");
}

void GrpcWebGateway::Impl::Completed(MHD_Connection* conn, void** req_cls) {
  delete static_cast<Request*>(*req_cls);
  *req_cls = nullptr;
  // Between requests again: the next head has its deadline from now.
  const MHD_ConnectionInfo* ci = MHD_get_connection_info(conn, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
  if (ci != nullptr) SetPhase(static_cast<Conn*>(ci->socket_context), Phase::kHead);
}

MHD_Result GrpcWebGateway::Impl::Preflight(MHD_Connection* conn, const std::string& origin) {
  Headers cors = CorsHeaders(origin);
  if (cors.empty()) {
    return Respond(conn, 403, "text/plain", {},
                   "origin not allowed (sportsim-server --http_cors_origins)\n");
  }
  cors.emplace_back("Access-Control-Allow-Methods", "POST, GET, OPTIONS");
  cors.emplace_back("Access-Control-Allow-Headers",
                    "content-type, x-grpc-web, x-user-agent, grpc-timeout");
  cors.emplace_back("Access-Control-Max-Age", "600");
  return Respond(conn, 204, "text/plain", cors, "");
}

MHD_Result GrpcWebGateway::Impl::Static(MHD_Connection* conn, const std::string& path,
                                        const std::string& origin) {
  if (config_.web_root.empty()) {
    return Respond(conn, 404, "text/plain", CorsHeaders(origin),
                   "no viewer here (sportsim-server --web_root)\n");
  }
  // The viewer's pages are one page; its assets are plain names in the root (no directories,
  // nothing hidden), so no request can name a file outside it.
  // Browsers ask for an icon on their own; the viewer has none.
  if (path == "/favicon.ico") return Respond(conn, 204, "image/x-icon", {}, "");
  std::string name = path.substr(1);
  if (name.empty() || path.starts_with("/table/") || path.starts_with("/swing/") ||
      path.starts_with("/round/")) {
    name = "index.html";
  }
  const bool plain = !name.empty() && name[0] != '.' &&
                     std::all_of(name.begin(), name.end(), [](char ch) {
                       return std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' ||
                              ch == '_' || ch == '-';
                     });
  const std::filesystem::path file = std::filesystem::path(config_.web_root) / name;
  std::error_code ec;
  if (!plain || !std::filesystem::is_regular_file(file, ec)) {
    return Respond(conn, 404, "text/plain", {}, "not found\n");
  }
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  struct stat st {};
  if (fd < 0 || ::fstat(fd, &st) != 0) {
    if (fd >= 0) ::close(fd);
    return Respond(conn, 404, "text/plain", {}, "not found\n");
  }
  MHD_Response* r = MHD_create_response_from_fd(static_cast<uint64_t>(st.st_size), fd);
  if (r == nullptr) {
    ::close(fd);
    return MHD_NO;
  }
  MHD_add_response_header(r, "Content-Type", std::string(MimeOf(name)).c_str());
  MHD_add_response_header(r, "Cache-Control", "no-cache");
  const MHD_Result ok = MHD_queue_response(conn, 200, r);
  MHD_destroy_response(r);
  return ok;
}

// Errors before any message: a trailers-only response, the status in the headers too.
MHD_Result GrpcWebGateway::Impl::Fail(MHD_Connection* conn, bool text, const Headers& cors,
                                      grpc::StatusCode code, const std::string& message) {
  const grpc::Status st(code, message);
  const std::string trailers = TrailersFrame(st);
  Headers headers = cors;
  headers.emplace_back("grpc-status", absl::StrCat(static_cast<int>(code)));
  headers.emplace_back("grpc-message", PercentEncode(message));
  return Respond(conn, 200,
                 text ? "application/grpc-web-text+proto" : "application/grpc-web+proto",
                 headers, text ? absl::Base64Escape(trailers) : trailers);
}

bool GrpcWebGateway::Impl::Track(Call* call, std::string* why) {
  absl::MutexLock lock(&mu_);
  if (shut_down_) {
    *why = "the server is shutting down";
    return false;
  }
  if (call->stream) {
    int& k = streams_[call->client];
    if (k >= config_.max_streams_per_client || total_streams_ >= config_.limits.max_streams) {
      *why = absl::StrFormat(
          "at most %d open streams per client over gRPC-Web (a browser holds six connections "
          "to one origin) and %d in all (sportsim-server --http_max_streams_per_client, "
          "--http_max_streams)",
          config_.max_streams_per_client, config_.limits.max_streams);
      if (k == 0) streams_.erase(call->client);
      return false;
    }
    ++k;
    ++total_streams_;
  } else {
    int& k = unary_[call->client];
    if (k >= config_.limits.max_calls_per_client) {
      *why = absl::StrFormat(
          "at most %d gRPC-Web calls in flight per client (sportsim-server "
          "--http_max_calls_per_client): wait for one to end",
          config_.limits.max_calls_per_client);
      if (k == 0) unary_.erase(call->client);
      return false;
    }
    ++k;
  }
  calls_.insert(call);
  return true;
}

void GrpcWebGateway::Impl::Untrack(Call* call) {
  absl::MutexLock lock(&mu_);
  if (calls_.erase(call) == 0) return;
  std::map<std::string, int>& counts = call->stream ? streams_ : unary_;
  if (--counts[call->client] <= 0) counts.erase(call->client);
  if (call->stream) --total_streams_;
  calls_cv_.SignalAll();
}

MHD_Result GrpcWebGateway::Impl::Post(MHD_Connection* conn, Conn* c, Request* req,
                                      const std::string& path, const std::string& origin) {
  const Headers cors = CorsHeaders(origin);
  const char* type_h = Header(conn, "Content-Type");
  const std::string type = type_h != nullptr ? type_h : "";
  const bool text = type.starts_with("application/grpc-web-text");
  if (req->call != nullptr) {
    // Resumed: a unary call's answer is in.
    Call& call = *req->call;
    std::string out;
    {
      absl::MutexLock lock(&call.mu);
      if (!call.grpc_done) return MHD_NO;  // never resumed before its end
    }
    if (call.status.ok()) out = Frame(0, ToString(call.message));
    out += TrailersFrame(call.status);
    if (call.text) out = absl::Base64Escape(out);
    SetPhase(c, Phase::kReply);
    return Respond(conn, 200, call.reply_type, call.headers, out);
  }
  SetPhase(c, Phase::kReply);
  if (!text && !type.starts_with("application/grpc-web")) {
    return Respond(conn, 415, "text/plain", cors,
                   "content-type must be application/grpc-web[+proto] or "
                   "application/grpc-web-text[+proto]\n");
  }
  const auto fail = [&](grpc::StatusCode code, const std::string& message) {
    return Fail(conn, text, cors, code, message);
  };
  // The method: /package.Service/Method, known to the server's descriptor pool.
  const std::vector<std::string> parts = absl::StrSplit(path.substr(1), '/');
  const google::protobuf::MethodDescriptor* md =
      parts.size() == 2 ? google::protobuf::DescriptorPool::generated_pool()->FindMethodByName(
                              parts[0] + "." + parts[1])
                        : nullptr;
  if (md == nullptr) {
    return fail(grpc::StatusCode::UNIMPLEMENTED,
                absl::StrFormat("no method %s", BoundedMessage(path.substr(0, 80))));
  }
  if (md->client_streaming()) {
    return fail(grpc::StatusCode::UNIMPLEMENTED,
                absl::StrFormat("%s streams from the client, which gRPC-Web cannot carry: call "
                                "it with gRPC (HTTP/2)",
                                md->full_name()));
  }
  // The body: one length-prefixed message, within the server's request limit.
  std::string body = std::move(req->body);
  const size_t frame_limit = static_cast<size_t>(config_.max_request_bytes) + 5;
  if (req->too_large || body.size() > (text ? (frame_limit + 2) / 3 * 4 + 4 : frame_limit)) {
    return fail(grpc::StatusCode::RESOURCE_EXHAUSTED,
                absl::StrFormat("the request is larger than the server's limit of %d bytes",
                                config_.max_request_bytes));
  }
  if (text) {
    std::string decoded;
    if (!absl::Base64Unescape(body, &decoded)) {
      return fail(grpc::StatusCode::INVALID_ARGUMENT, "the grpc-web-text body is not base64");
    }
    body = std::move(decoded);
  }
  if (body.size() < 5 || (static_cast<uint8_t>(body[0]) & 0x80) != 0) {
    return fail(grpc::StatusCode::INVALID_ARGUMENT, "the body must hold one message frame");
  }
  if ((static_cast<uint8_t>(body[0]) & 0x01) != 0) {
    return fail(grpc::StatusCode::UNIMPLEMENTED, "compressed messages are not accepted");
  }
  const uint32_t len = (static_cast<uint32_t>(static_cast<uint8_t>(body[1])) << 24) |
                       (static_cast<uint32_t>(static_cast<uint8_t>(body[2])) << 16) |
                       (static_cast<uint32_t>(static_cast<uint8_t>(body[3])) << 8) |
                       static_cast<uint32_t>(static_cast<uint8_t>(body[4]));
  if (body.size() - 5 < len) {
    return fail(grpc::StatusCode::INVALID_ARGUMENT, "the message frame is truncated");
  }

  auto call = std::make_shared<Call>();
  call->gw = this;
  call->conn = conn;
  call->client = c != nullptr ? c->client : ClientAddress(conn);
  call->stream = md->server_streaming();
  call->text = text;
  call->headers = cors;
  call->reply_type = text ? "application/grpc-web-text+proto" : "application/grpc-web+proto";
  call->request = ToBuffer(std::string_view(body).substr(5, len));
  // The deadline: the client's (grpc-timeout), and for a unary call at most
  // --http_call_deadline, so that no call outlives its use.
  std::optional<std::chrono::nanoseconds> timeout;
  if (const char* t = Header(conn, "grpc-timeout"); t != nullptr) {
    timeout = ParseGrpcTimeout(t);
    if (!timeout.has_value()) {
      return fail(grpc::StatusCode::INVALID_ARGUMENT,
                  absl::StrFormat("grpc-timeout: not a timeout (digits and one of H M S m u n): "
                                  "%s",
                                  BoundedMessage(std::string(t).substr(0, 24))));
    }
  }
  if (!call->stream) {
    const auto cap = absl::ToChronoNanoseconds(config_.limits.call_deadline);
    timeout = timeout.has_value() ? std::min(*timeout, cap) : cap;
  }
  if (timeout.has_value()) {
    call->ctx.set_deadline(std::chrono::system_clock::now() +
                           std::chrono::duration_cast<std::chrono::system_clock::duration>(*timeout));
  }
  std::string why;
  if (!Track(call.get(), &why)) return fail(grpc::StatusCode::RESOURCE_EXHAUSTED, why);
  req->call = call;
  SetPhase(c, Phase::kCall, call);
  const std::string rpc = "/" + parts[0] + "/" + parts[1];
  if (!call->stream) {
    {
      absl::MutexLock lock(&call->mu);
      call->Suspend();  // resumed when the answer is in; the handler is then called again
    }
    call->unary = stub_->PrepareUnaryCall(&call->ctx, rpc, call->request, &cq_);
    call->unary->StartCall();
    call->unary->Finish(&call->message, &call->status, new Op{call, OpKind::kUnaryDone});
    return MHD_YES;
  }
  // A server stream: each message as soon as it comes, in chunks, from ReadStream.
  auto* holder = new std::shared_ptr<Call>(call);
  MHD_Response* r = MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, 16 << 10, &ReadStream,
                                                      holder, &FreeStream);
  if (r == nullptr) {
    delete holder;
    call->ctx.TryCancel();
    Untrack(call.get());
    return MHD_NO;
  }
  MHD_add_response_header(r, "Content-Type", call->reply_type.c_str());
  MHD_add_response_header(r, "Cache-Control", "no-store");
  for (const auto& [k, v] : cors) MHD_add_response_header(r, k.c_str(), v.c_str());
  const MHD_Result ok = MHD_queue_response(conn, 200, r);
  MHD_destroy_response(r);  // the connection holds it (and so the call) until it is sent
  StartStream(call, rpc);
  return ok;
}

// --- streams -----------------------------------------------------------------------------------

void GrpcWebGateway::Impl::StartStream(const std::shared_ptr<Call>& call, const std::string& rpc) {
  call->rw = stub_->PrepareCall(&call->ctx, rpc, &cq_);
  call->rw->StartCall(new Op{call, OpKind::kStarted});
}

void GrpcWebGateway::Impl::IssueRead(const std::shared_ptr<Call>& call) {
  call->rw->Read(&call->message, new Op{call, OpKind::kRead});
}

void GrpcWebGateway::Impl::FinishStream(const std::shared_ptr<Call>& call) {
  call->rw->Finish(&call->status, new Op{call, OpKind::kFinished});
}

ssize_t GrpcWebGateway::Impl::ReadStream(void* cls, uint64_t /*pos*/, char* buf, size_t max) {
  const std::shared_ptr<Call>& call = *static_cast<std::shared_ptr<Call>*>(cls);
  bool read_more = false;
  ssize_t n = 0;
  {
    absl::MutexLock lock(&call->mu);
    if (!call->out.empty()) {
      n = static_cast<ssize_t>(std::min(max, call->out.size()));
      std::memcpy(buf, call->out.data(), static_cast<size_t>(n));
      call->out.erase(0, static_cast<size_t>(n));
      // Reading resumes once the client has taken half of the window.
      if (call->read_paused && !call->grpc_done &&
          static_cast<int64_t>(call->out.size()) < call->gw->config_.window_bytes / 2) {
        call->read_paused = false;
        read_more = true;
      }
    } else if (call->grpc_done) {
      return MHD_CONTENT_READER_END_OF_STREAM;
    } else {
      call->Suspend();  // until a message or the end comes
      return 0;
    }
  }
  if (read_more) call->gw->IssueRead(call);
  return n;
}

void GrpcWebGateway::Impl::FreeStream(void* cls) {
  auto* holder = static_cast<std::shared_ptr<Call>*>(cls);
  // The response is gone (sent, or its connection closed): the call has no one to go to.
  {
    absl::MutexLock lock(&(*holder)->mu);
    if (!(*holder)->grpc_done) (*holder)->ctx.TryCancel();
  }
  delete holder;
}

void GrpcWebGateway::Impl::OnOp(Op* op, bool ok) {
  const std::shared_ptr<Call>& call = op->call;
  switch (op->kind) {
    case OpKind::kUnaryDone: {
      bool resume = false;
      {
        absl::MutexLock lock(&call->mu);
        call->grpc_done = true;
        resume = call->TakeResume();
      }
      if (resume) MHD_resume_connection(call->conn);
      Untrack(call.get());
      break;
    }
    case OpKind::kStarted:
      if (ok) {
        call->rw->Write(call->request, new Op{call, OpKind::kWritten});
      } else {
        FinishStream(call);
      }
      break;
    case OpKind::kWritten:
      if (ok) {
        call->rw->WritesDone(new Op{call, OpKind::kWritesDone});
      } else {
        FinishStream(call);
      }
      break;
    case OpKind::kWritesDone:
      if (ok) {
        IssueRead(call);
      } else {
        FinishStream(call);
      }
      break;
    case OpKind::kRead: {
      if (!ok) {
        FinishStream(call);
        break;
      }
      std::string f = Frame(0, ToString(call->message));
      if (call->text) f = absl::Base64Escape(f);
      bool resume = false;
      bool more = true;
      {
        absl::MutexLock lock(&call->mu);
        call->out += f;
        // The window: past it, the next message waits until the client has read half.
        if (static_cast<int64_t>(call->out.size()) >= config_.window_bytes) {
          call->read_paused = true;
          more = false;
        }
        resume = call->TakeResume();
      }
      if (resume) MHD_resume_connection(call->conn);
      if (more) IssueRead(call);
      break;
    }
    case OpKind::kFinished: {
      std::string f = TrailersFrame(call->status);
      if (call->text) f = absl::Base64Escape(f);
      bool resume = false;
      {
        absl::MutexLock lock(&call->mu);
        call->out += f;
        call->grpc_done = true;
        resume = call->TakeResume();
      }
      if (resume) MHD_resume_connection(call->conn);
      Untrack(call.get());
      break;
    }
  }
}

void GrpcWebGateway::Impl::PollQueue() {
  void* tag = nullptr;
  bool ok = false;
  while (cq_.Next(&tag, &ok)) {
    auto* op = static_cast<Op*>(tag);
    OnOp(op, ok);
    delete op;
  }
}

// --- the public face ---------------------------------------------------------------------------

absl::StatusOr<std::unique_ptr<GrpcWebGateway>> GrpcWebGateway::Start(
    const GrpcWebConfig& config, std::shared_ptr<grpc::Channel> channel) {
  auto impl = std::make_unique<Impl>(config);
  if (absl::Status s = impl->Start(std::move(channel)); !s.ok()) {
    impl->Stop();
    return s;
  }
  return std::unique_ptr<GrpcWebGateway>(new GrpcWebGateway(std::move(impl)));
}

GrpcWebGateway::GrpcWebGateway(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GrpcWebGateway::~GrpcWebGateway() { impl_->Stop(); }
int GrpcWebGateway::port() const { return impl_->port(); }
void GrpcWebGateway::Shutdown() { impl_->Shutdown(); }
int GrpcWebGateway::open_streams() const { return impl_->open_streams(); }
int GrpcWebGateway::open_connections() const { return impl_->open_connections(); }
int64_t GrpcWebGateway::slow_clients_closed() const { return impl_->slow_closed(); }
int64_t GrpcWebGateway::departed_calls_cancelled() const { return impl_->departed(); }

}  // namespace sportsim::server
