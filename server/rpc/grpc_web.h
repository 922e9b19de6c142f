// gRPC-Web from the server itself, for browsers (which cannot speak gRPC): an event-driven
// HTTP/1.1 server (GNU libmicrohttpd, from Debian) that hands each call to the server's own
// services over an in-process channel with a generic stub, bytes in and bytes out. No RPC is
// written twice: every unary and server-streaming RPC of every registered service works, new
// ones without a line here. Client-streaming and bidirectional RPCs (DriveSwing) are refused
// clearly. Also serves the built viewer's static files.
//
// Why libmicrohttpd: a few polling threads (epoll) serve every connection, so an open viewer
// stream costs a socket and a few kilobytes, not a thread (civetweb, used before, held a worker
// per open stream: 32 viewers took the whole port). It has per-address and total connection
// limits, idle timeouts, and suspend/resume, on which every call here is asynchronous: a call
// waiting for the server, or a stream waiting for its next message, is a suspended connection
// that no thread waits on.
//
// A suspended connection is not polled by the HTTP server, so it would never notice its client
// leaving (a health Watch writes nothing after its first message). A watchdog thread polls the
// sockets of suspended calls for the peer's hang-up (POLLRDHUP) and cancels their gRPC call at
// once; it also enforces the request-head and body deadlines (slow-header and slow-body
// clients), which an idle timeout alone cannot, by shutting such sockets down.
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
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <grpcpp/channel.h>

#include "absl/status/statusor.h"
#include "absl/time/time.h"

namespace sportsim::server {

/// The web port's bounds (flags --http_*; docs/operations.md).
struct GrpcWebLimits {
  int max_connections = 4096;           ///< open connections in all
  int max_connections_per_client = 64;  ///< open connections per client address
  int max_streams = 2048;               ///< open server streams in all
  int max_calls_per_client = 16;        ///< unary calls in flight per client address
  absl::Duration idle_timeout = absl::Seconds(30);    ///< no bytes either way this long: closed
  absl::Duration header_timeout = absl::Seconds(10);  ///< a request's head must arrive within
  absl::Duration body_timeout = absl::Seconds(10);    ///< its body within, once the head is in
  absl::Duration call_deadline = absl::Seconds(60);   ///< the most a unary call may take
  int threads = 2;                                    ///< polling threads
};

struct GrpcWebConfig {
  std::string listen;                     ///< host:port, as given (for messages)
  std::string host;                       ///< what to bind: a numeric address or a name
  int port = 0;                           ///< 0: any free one
  std::string web_root;                   ///< the viewer's files ("": no static files)
  std::vector<std::string> cors_origins;  ///< Origins allowed cross-origin ("*": any)
  int max_request_bytes = 64 << 10;       ///< the gRPC server's request limit
  int max_streams_per_client = 4;         ///< open server streams per client address
  GrpcWebLimits limits;
  int64_t window_bytes = 1 << 20;  ///< a stream's unsent bytes before it stops reading
};

/// The "grpc-timeout" header's value (an integer of at most 8 digits and a unit, H M S m u n),
/// saturated at a century; nullopt when malformed.
std::optional<std::chrono::nanoseconds> ParseGrpcTimeout(std::string_view value);

class GrpcWebGateway {
 public:
  /// Listens on config.listen; calls go to `channel` (the server's in-process channel).
  /// UNAVAILABLE when it cannot listen.
  static absl::StatusOr<std::unique_ptr<GrpcWebGateway>> Start(
      const GrpcWebConfig& config, std::shared_ptr<grpc::Channel> channel);
  ~GrpcWebGateway();  ///< Shutdown()s, waits briefly for calls to end, stops the HTTP server

  int port() const;
  /// Cancels every open call (streams end), refuses new ones and closes idle connections.
  /// Idempotent.
  void Shutdown();

  int open_streams() const;
  int open_connections() const;
  /// Connections closed by the watchdog: slow heads or bodies; calls cancelled because their
  /// client left.
  int64_t slow_clients_closed() const;
  int64_t departed_calls_cancelled() const;

  class Impl;

 private:
  explicit GrpcWebGateway(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_RPC_GRPC_WEB_H_
