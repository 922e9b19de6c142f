#include "server/rpc/grpc_web.h"

#include <civetweb.h>
#include <google/protobuf/descriptor.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>
#include <grpcpp/support/byte_buffer.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string_view>
#include <utility>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "grpc/health/v1/health.pb.h"
#include "server/rpc/status.h"

namespace sportsim::server {

namespace {

int Dispatch(mg_connection* conn, void* self) {
  return static_cast<GrpcWebGateway*>(self)->Handle(conn);
}

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

// The "grpc-timeout" header: an integer and a unit (H M S m u n).
std::optional<std::chrono::nanoseconds> ParseTimeout(const char* header) {
  if (header == nullptr) return std::nullopt;
  std::string_view v(header);
  if (v.size() < 2 || v.size() > 9) return std::nullopt;
  int64_t n = 0;
  for (const char c : v.substr(0, v.size() - 1)) {
    if (c < '0' || c > '9') return std::nullopt;
    n = n * 10 + (c - '0');
  }
  switch (v.back()) {
    case 'H': return std::chrono::hours(n);
    case 'M': return std::chrono::minutes(n);
    case 'S': return std::chrono::seconds(n);
    case 'm': return std::chrono::milliseconds(n);
    case 'u': return std::chrono::microseconds(n);
    case 'n': return std::chrono::nanoseconds(n);
    default: return std::nullopt;
  }
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

// Writes a whole response with a body.
int Respond(mg_connection* conn, int code, std::string_view reason, std::string_view type,
            const std::string& extra_headers, std::string_view body) {
  mg_printf(conn,
            "HTTP/1.1 %d %.*s\r\nContent-Type: %.*s\r\nContent-Length: %zu\r\n"
            "Cache-Control: no-store\r\n%s\r\n",
            code, static_cast<int>(reason.size()), reason.data(), static_cast<int>(type.size()),
            type.data(), body.size(), extra_headers.c_str());
  if (!body.empty()) mg_write(conn, body.data(), body.size());
  return code;
}

}  // namespace

absl::StatusOr<std::unique_ptr<GrpcWebGateway>> GrpcWebGateway::Start(
    const GrpcWebConfig& config, std::shared_ptr<grpc::Channel> channel) {
  std::unique_ptr<GrpcWebGateway> g(new GrpcWebGateway(config));
  g->channel_ = std::move(channel);
  // The methods are looked up in the generated descriptor pool. gRPC's built-in health service
  // brings no descriptors of its own: touching health.proto's here links them in, so that
  // /grpc.health.v1.Health/Check is served over gRPC-Web like every other unary RPC.
  (void)grpc::health::v1::HealthCheckRequest::descriptor();
  const std::string threads = absl::StrCat(config.threads);
  const char* options[] = {"listening_ports", config.listen.c_str(),
                           "num_threads", threads.c_str(),
                           "enable_keep_alive", "yes",
                           "request_timeout_ms", "30000",
                           // CORS is ours (--http_cors_origins): civetweb's own answers to
                           // preflights, "*" by default, are switched off.
                           "access_control_allow_origin", "",
                           "access_control_allow_methods", "",
                           "access_control_allow_headers", "",
                           nullptr};
  mg_callbacks callbacks{};
  g->http_ = mg_start(&callbacks, g.get(), options);
  if (g->http_ == nullptr) {
    return absl::UnavailableError(
        absl::StrFormat("--http_listen: cannot listen on %s", config.listen));
  }
  mg_set_request_handler(g->http_, "/", &Dispatch, g.get());
  mg_server_port ports[4] = {};
  const int n = mg_get_server_ports(g->http_, 4, ports);
  g->port_ = n > 0 ? ports[0].port : 0;
  return g;
}

GrpcWebGateway::~GrpcWebGateway() {
  Shutdown();
  if (http_ != nullptr) mg_stop(http_);
}

void GrpcWebGateway::Shutdown() {
  absl::MutexLock lock(&mu_);
  shut_down_ = true;
  for (grpc::ClientContext* ctx : calls_) ctx->TryCancel();
}

int GrpcWebGateway::open_streams() const {
  absl::MutexLock lock(&mu_);
  int n = 0;
  for (const auto& [client, k] : streams_) n += k;
  return n;
}

bool GrpcWebGateway::Track(grpc::ClientContext* ctx, const std::string& client, bool stream) {
  absl::MutexLock lock(&mu_);
  if (shut_down_) return false;
  if (stream) {
    int& k = streams_[client];
    if (k >= config_.max_streams_per_client) {
      if (k == 0) streams_.erase(client);
      return false;
    }
    ++k;
  }
  calls_.insert(ctx);
  return true;
}

void GrpcWebGateway::Untrack(grpc::ClientContext* ctx, const std::string& client, bool stream) {
  absl::MutexLock lock(&mu_);
  calls_.erase(ctx);
  if (stream && --streams_[client] <= 0) streams_.erase(client);
}

std::string GrpcWebGateway::CorsHeaders(const std::string& origin) const {
  if (origin.empty()) return "";
  const bool allowed = std::any_of(config_.cors_origins.begin(), config_.cors_origins.end(),
                                   [&](const std::string& o) { return o == "*" || o == origin; });
  if (!allowed) return "";
  return absl::StrCat("Access-Control-Allow-Origin: ", origin,
                      "\r\nVary: Origin\r\nAccess-Control-Expose-Headers: grpc-status, "
                      "grpc-message\r\n");
}

int GrpcWebGateway::Preflight(mg_connection* conn, const std::string& origin) {
  const std::string cors = CorsHeaders(origin);
  if (cors.empty()) {
    return Respond(conn, 403, "Forbidden", "text/plain", "",
                   "origin not allowed (sportsim-server --http_cors_origins)\n");
  }
  return Respond(conn, 204, "No Content", "text/plain",
                 cors + "Access-Control-Allow-Methods: POST, GET, OPTIONS\r\n"
                        "Access-Control-Allow-Headers: content-type, x-grpc-web, "
                        "x-user-agent, grpc-timeout\r\nAccess-Control-Max-Age: 600\r\n",
                 "");
}

int GrpcWebGateway::Handle(mg_connection* conn) {
  const mg_request_info* ri = mg_get_request_info(conn);
  const std::string method = ri->request_method != nullptr ? ri->request_method : "";
  const std::string path = ri->local_uri != nullptr ? ri->local_uri : "/";
  const char* origin_h = mg_get_header(conn, "Origin");
  const std::string origin = origin_h != nullptr ? origin_h : "";
  if (method == "OPTIONS") return Preflight(conn, origin);
  if (method == "POST") return Call(conn, path, origin);
  if (method == "GET" || method == "HEAD") return Static(conn, path, origin);
  return Respond(conn, 405, "Method Not Allowed", "text/plain", "Allow: GET, POST, OPTIONS\r\n",
                 "gRPC-Web calls are POSTs; the viewer is GET\n");
}

int GrpcWebGateway::Static(mg_connection* conn, const std::string& path,
                           const std::string& origin) {
  if (config_.web_root.empty()) {
    return Respond(conn, 404, "Not Found", "text/plain", CorsHeaders(origin),
                   "no viewer here (sportsim-server --web_root)\n");
  }
  // The viewer's pages are one page; its assets are plain names in the root (no directories,
  // nothing hidden), so no request can name a file outside it.
  // Browsers ask for an icon on their own; the viewer has none.
  if (path == "/favicon.ico") return Respond(conn, 204, "No Content", "image/x-icon", "", "");
  std::string name = path.substr(1);
  if (name.empty() || path.starts_with("/table/") || path.starts_with("/swing/")) {
    name = "index.html";
  }
  const bool plain = !name.empty() && name[0] != '.' &&
                     std::all_of(name.begin(), name.end(), [](char c) {
                       return std::isalnum(static_cast<unsigned char>(c)) || c == '.' ||
                              c == '_' || c == '-';
                     });
  const std::filesystem::path file = std::filesystem::path(config_.web_root) / name;
  std::error_code ec;
  if (!plain || !std::filesystem::is_regular_file(file, ec)) {
    return Respond(conn, 404, "Not Found", "text/plain", "", "not found\n");
  }
  const std::string mime(MimeOf(name));
  mg_send_mime_file2(conn, file.c_str(), mime.c_str(), "Cache-Control: no-cache\r\n");
  return 200;
}

int GrpcWebGateway::Call(mg_connection* conn, const std::string& path,
                         const std::string& origin) {
  const std::string cors = CorsHeaders(origin);
  const char* type_h = mg_get_header(conn, "Content-Type");
  const std::string type = type_h != nullptr ? type_h : "";
  const bool text = type.starts_with("application/grpc-web-text");
  if (!text && !type.starts_with("application/grpc-web")) {
    return Respond(conn, 415, "Unsupported Media Type", "text/plain", cors,
                   "content-type must be application/grpc-web[+proto] or "
                   "application/grpc-web-text[+proto]\n");
  }
  const std::string reply_type = text ? "application/grpc-web-text+proto"
                                      : "application/grpc-web+proto";
  // Errors before any message: a trailers-only response, the status in the headers too.
  const auto fail = [&](grpc::StatusCode code, const std::string& message) {
    const grpc::Status st(code, message);
    const std::string trailers = TrailersFrame(st);
    const std::string body = text ? absl::Base64Escape(trailers) : trailers;
    return Respond(conn, 200, "OK", reply_type,
                   absl::StrCat(cors, "grpc-status: ", static_cast<int>(code),
                                "\r\ngrpc-message: ", PercentEncode(message), "\r\n"),
                   body);
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
  const size_t frame_limit = static_cast<size_t>(config_.max_request_bytes) + 5;
  const size_t limit = text ? (frame_limit + 2) / 3 * 4 + 4 : frame_limit;
  std::string body;
  char buf[8192];
  for (;;) {
    const int n = mg_read(conn, buf, sizeof(buf));
    if (n <= 0) break;
    body.append(buf, static_cast<size_t>(n));
    if (body.size() > limit) {
      return fail(grpc::StatusCode::RESOURCE_EXHAUSTED,
                  absl::StrFormat("the request is larger than the server's limit of %d bytes",
                                  config_.max_request_bytes));
    }
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
  const grpc::ByteBuffer request = ToBuffer(std::string_view(body).substr(5, len));

  grpc::ClientContext ctx;
  if (const std::optional<std::chrono::nanoseconds> t =
          ParseTimeout(mg_get_header(conn, "grpc-timeout"));
      t.has_value()) {
    ctx.set_deadline(std::chrono::system_clock::now() + *t);
  }
  const bool stream = md->server_streaming();
  const std::string client = mg_get_request_info(conn)->remote_addr;
  if (!Track(&ctx, client, stream)) {
    return fail(grpc::StatusCode::RESOURCE_EXHAUSTED,
                absl::StrFormat("at most %d open streams per client over gRPC-Web (a browser "
                                "holds six connections to one origin), or the server is "
                                "shutting down",
                                config_.max_streams_per_client));
  }
  const std::string rpc = "/" + parts[0] + "/" + parts[1];
  grpc::GenericStub stub(channel_);
  grpc::CompletionQueue cq;
  void* tag = nullptr;
  bool ok = false;
  int code = 200;
  if (!stream) {
    grpc::ByteBuffer response;
    grpc::Status status;
    std::unique_ptr<grpc::GenericClientAsyncResponseReader> call =
        stub.PrepareUnaryCall(&ctx, rpc, request, &cq);
    call->StartCall();
    call->Finish(&response, &status, reinterpret_cast<void*>(1));
    cq.Next(&tag, &ok);
    std::string out;
    if (status.ok()) out = Frame(0, ToString(response));
    out += TrailersFrame(status);
    if (text) out = absl::Base64Escape(out);
    Respond(conn, 200, "OK", reply_type, cors, out);
  } else {
    // A server stream: each message as soon as it comes, one HTTP chunk each; a write that
    // fails (the browser went away) cancels the call. The stream's heartbeats bound how long
    // that takes to notice.
    std::unique_ptr<grpc::GenericClientAsyncReaderWriter> call = stub.PrepareCall(&ctx, rpc, &cq);
    const auto step = [&](auto op) {
      op();
      cq.Next(&tag, &ok);
      return ok;
    };
    bool alive = step([&] { call->StartCall(reinterpret_cast<void*>(1)); }) &&
                 step([&] { call->Write(request, reinterpret_cast<void*>(2)); }) &&
                 step([&] { call->WritesDone(reinterpret_cast<void*>(3)); });
    mg_printf(conn,
              "HTTP/1.1 200 OK\r\nContent-Type: %s\r\nCache-Control: no-store\r\n"
              "Transfer-Encoding: chunked\r\n%s\r\n",
              reply_type.c_str(), cors.c_str());
    bool writable = true;
    grpc::ByteBuffer message;
    while (alive && step([&] { call->Read(&message, reinterpret_cast<void*>(4)); })) {
      std::string f = Frame(0, ToString(message));
      if (text) f = absl::Base64Escape(f);
      if (mg_send_chunk(conn, f.data(), static_cast<unsigned>(f.size())) < 0) {
        writable = false;
        ctx.TryCancel();
      }
    }
    grpc::Status status;
    step([&] { call->Finish(&status, reinterpret_cast<void*>(5)); });
    if (writable) {
      std::string f = TrailersFrame(status);
      if (text) f = absl::Base64Escape(f);
      mg_send_chunk(conn, f.data(), static_cast<unsigned>(f.size()));
      mg_send_chunk(conn, "", 0);
    }
  }
  Untrack(&ctx, client, stream);
  cq.Shutdown();
  while (cq.Next(&tag, &ok)) {
  }
  return code;
}

}  // namespace sportsim::server
