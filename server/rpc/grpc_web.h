// gRPC-Web from the server itself, for browsers (which cannot speak gRPC): an HTTP/1.1 server
// (civetweb, from Debian; already a dependency of the metrics endpoint) that hands each call to
// the server's own services over an in-process channel with a generic stub, bytes in and bytes
// out. No RPC is written twice: every unary and server-streaming RPC of every registered
// service works, new ones without a line here. Client-streaming and bidirectional RPCs
// (DriveSwing) are refused clearly. Also serves the built viewer's static files.
//
// Protocol (the gRPC-Web spec, github.com/grpc/grpc/blob/master/doc/PROTOCOL-WEB.md, in our
// words): POST /package.Service/Method with content-type application/grpc-web[+proto] (binary)
// or application/grpc-web-text[+proto] (base64); the body is one length-prefixed message
// (1 flag byte, 4 length bytes big-endian); the response is 200 with data frames (flag 0)
// followed by one trailers frame (flag 0x80) holding "grpc-status" and "grpc-message"
// (percent-encoded) as HTTP/1 header lines.
#ifndef SPORTSIM_SERVER_RPC_GRPC_WEB_H_
#define SPORTSIM_SERVER_RPC_GRPC_WEB_H_

#include <atomic>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include <grpcpp/channel.h>
#include <grpcpp/client_context.h>

#include "absl/base/thread_annotations.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"

struct mg_context;
struct mg_connection;

namespace sportsim::server {

struct GrpcWebConfig {
  std::string listen;                     ///< host:port (port 0: any free one)
  std::string web_root;                   ///< the viewer's files ("": no static files)
  std::vector<std::string> cors_origins;  ///< Origins allowed cross-origin ("*": any)
  int max_request_bytes = 64 << 10;       ///< the gRPC server's request limit
  int max_streams_per_client = 4;         ///< open server streams per client address
  int threads = 32;                       ///< HTTP workers (a stream holds one while open)
};

class GrpcWebGateway {
 public:
  /// Listens on config.listen; calls go to `channel` (the server's in-process channel).
  /// UNAVAILABLE when it cannot listen.
  static absl::StatusOr<std::unique_ptr<GrpcWebGateway>> Start(
      const GrpcWebConfig& config, std::shared_ptr<grpc::Channel> channel);
  ~GrpcWebGateway();  ///< Shutdown()s and stops the HTTP server

  int port() const { return port_; }
  /// Cancels every open call (streams end) and refuses new ones. Idempotent.
  void Shutdown();

  int open_streams() const;

  /// The HTTP handler (civetweb's callback).
  int Handle(mg_connection* conn);

 private:
  explicit GrpcWebGateway(GrpcWebConfig config) : config_(std::move(config)) {}
  int Call(mg_connection* conn, const std::string& path, const std::string& origin);
  int Static(mg_connection* conn, const std::string& path, const std::string& origin);
  int Preflight(mg_connection* conn, const std::string& origin);
  /// The CORS headers for `origin` ("" when not allowed).
  std::string CorsHeaders(const std::string& origin) const;
  bool Track(grpc::ClientContext* ctx, const std::string& client, bool stream);
  void Untrack(grpc::ClientContext* ctx, const std::string& client, bool stream);

  const GrpcWebConfig config_;
  std::shared_ptr<grpc::Channel> channel_;
  mg_context* http_ = nullptr;
  int port_ = 0;
  mutable absl::Mutex mu_;
  bool shut_down_ ABSL_GUARDED_BY(mu_) = false;
  std::set<grpc::ClientContext*> calls_ ABSL_GUARDED_BY(mu_);
  std::map<std::string, int> streams_ ABSL_GUARDED_BY(mu_);  // per client address
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_RPC_GRPC_WEB_H_
