// Launch monitors over GSPro Open Connect v1 (docs/golf-open-connect.md): a TCP listener that
// speaks the protocol every monitor connector speaks (JSON messages back to back; the
// simulator listens), so that an existing connector plays a seat of a round. A device is bound
// to a seat with the BindMonitor call (`round monitor`); its shots become that seat's launch
// strokes, played like any PlayStroke (on the simulation pool, under its CPU budget, by the
// round's rules). Each connection has its own thread: a slow, silent or hostile connection
// holds only itself, messages have a size cap, and a connection silent for the idle timeout is
// closed. No gRPC here.
#ifndef SPORTSIM_SERVER_RPC_OPEN_CONNECT_H_
#define SPORTSIM_SERVER_RPC_OPEN_CONNECT_H_

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "sim/golf/ball_flight.h"

namespace sportsim::server {

class RoundRegistry;
class WorkPool;

/// What one Open Connect message says.
struct OpenConnectMessageInfo {
  enum class Kind { kShot, kHeartbeat, kStatus };
  Kind kind = Kind::kStatus;
  std::string device_id;
  bool metres = false;  ///< Units "Meters": the reply's distances in metres (else yards)
  int64_t shot_number = 0;
  /// kShot: the launch relative to the target line (+ right), speed in m/s.
  golf::LaunchConditions launch;
};

/// Parses one message (one JSON object). INVALID_ARGUMENT names the field and the reason:
/// malformed JSON, a missing DeviceID, a shot without Speed or VLA or spin, absurd values.
/// Spin: TotalSpin (with SpinAxis, default 0) wins when sent; else BackSpin and SideSpin give
/// the total sqrt(b^2 + s^2) and the axis atan2(s, b).
absl::StatusOr<OpenConnectMessageInfo> ParseOpenConnect(std::string_view json);

/// The reply's JSON: {"Code", "Message"} and, with a player, "Player" {"Handed", "Club",
/// "DistanceToTarget"}.
std::string OpenConnectReplyJson(int code, std::string_view message, std::string_view club = "",
                                 std::optional<double> distance_to_target = std::nullopt);

/// GSPro's club code for a stroke of `distance_m` from a lie (`on_green`: the putter).
std::string_view SuggestClub(double distance_m, bool on_green);

/// Cuts a byte stream into JSON objects, by their braces (strings and escapes respected):
/// connectors send objects back to back, with or without newlines between.
class JsonObjectSplitter {
 public:
  explicit JsonObjectSplitter(size_t max_object_bytes) : max_(max_object_bytes) {}
  /// Appends bytes; each complete object goes to `out`. FAILED_PRECONDITION (the stream cannot
  /// be resynchronised) for an object longer than the cap or bytes other than whitespace
  /// between objects.
  absl::Status Feed(std::string_view bytes, std::vector<std::string>* out);

 private:
  size_t max_;
  std::string current_;
  int depth_ = 0;
  bool in_string_ = false, escape_ = false;
};

struct OpenConnectOptions {
  std::string listen;  ///< host:port; port 0: any free port
  absl::Duration idle_timeout = absl::Seconds(60);  ///< a connection silent this long is closed
  size_t max_message_bytes = 16 << 10;
  int max_connections = 64;
  absl::Duration write_timeout = absl::Seconds(5);  ///< a reply the peer does not read: closed
  absl::Duration rest_wait = absl::Seconds(120);    ///< the longest wait for the 201 at rest
};

class OpenConnectListener {
 public:
  /// Binds and starts accepting: UNAVAILABLE when the address cannot be bound.
  static absl::StatusOr<std::unique_ptr<OpenConnectListener>> Start(const OpenConnectOptions& options,
                                                                    RoundRegistry* rounds,
                                                                    WorkPool* pool);
  ~OpenConnectListener();  ///< Stop()s
  OpenConnectListener(const OpenConnectListener&) = delete;
  OpenConnectListener& operator=(const OpenConnectListener&) = delete;

  int port() const { return port_; }
  /// Closes the listening socket and every connection, joins the threads. Idempotent.
  void Stop();

  int64_t shots() const { return shots_.load(); }          ///< shots played
  int64_t failures() const { return failures_.load(); }    ///< 5xx replies
  int open_connections() const;

 private:
  OpenConnectListener(const OpenConnectOptions& options, RoundRegistry* rounds, WorkPool* pool)
      : options_(options), rounds_(rounds), pool_(pool) {}
  void Accept();
  void Serve(int fd);
  // One message, answered: false when the connection must close.
  bool Handle(int fd, const std::string& json);
  bool Send(int fd, const std::string& text);

  const OpenConnectOptions options_;
  RoundRegistry* const rounds_;
  WorkPool* const pool_;
  int listen_fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
  std::atomic<int64_t> shots_{0}, failures_{0};
  std::thread acceptor_;
  mutable absl::Mutex mu_;
  struct Connection {
    int fd = -1;
    std::thread thread;
    std::atomic<bool> done{false};
  };
  std::list<Connection> connections_ ABSL_GUARDED_BY(mu_);
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_RPC_OPEN_CONNECT_H_
