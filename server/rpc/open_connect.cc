#include "server/rpc/open_connect.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <numbers>

#include <google/protobuf/util/json_util.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/notification.h"
#include "server/swing/round_world.h"
#include "server/world/work_pool.h"
#include "server/world/world.h"
#include "sportsim/v1/open_connect.pb.h"
#include "sportsim/v1/swing.pb.h"

namespace sportsim::server {
namespace {

constexpr double kMetresPerSecondPerMph = 0.44704;  // exact: 1609.344 m / 3600 s
constexpr double kMetresPerYard = 0.9144;
constexpr double kDeg = 180.0 / std::numbers::pi;

absl::Status Bad(const std::string& field, const std::string& why) {
  return absl::InvalidArgumentError(absl::StrCat(field, ": ", why));
}

// A value of the message in range, named as the protocol names it.
absl::Status InRange(const std::string& field, double v, double lo, double hi, const std::string& unit) {
  if (std::isfinite(v) && v >= lo && v <= hi) return absl::OkStatus();
  return Bad(field, absl::StrFormat("must be in [%g, %g] %s, got %g", lo, hi, unit, v));
}

// The parser's complaint, short and printable (it may quote the input).
std::string Printable(std::string_view s, size_t max) {
  std::string out;
  for (char c : s.substr(0, max)) out += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? '?' : c;
  if (s.size() > max) out += "...";
  return out;
}

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

absl::StatusOr<OpenConnectMessageInfo> ParseOpenConnect(std::string_view json) {
  v1::OpenConnectMessage m;
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = true;  // connectors add their own fields
  const auto parsed = google::protobuf::util::JsonStringToMessage(std::string(json), &m, options);
  if (!parsed.ok()) {
    return Bad("JSON", absl::StrCat("not an Open Connect message: ", Printable(std::string(parsed.message()), 120)));
  }
  OpenConnectMessageInfo out;
  if (m.deviceid().empty() || m.deviceid().size() > 64) {
    return Bad("DeviceID", "required, 1 to 64 characters");
  }
  out.device_id = m.deviceid();
  if (m.units().empty() || m.units() == "Yards") {
    out.metres = false;
  } else if (m.units() == "Meters") {
    out.metres = true;
  } else {
    return Bad("Units", absl::StrCat("must be Yards or Meters, got \"", Printable(m.units(), 16), "\""));
  }
  if (!m.apiversion().empty() && m.apiversion() != "1") {
    return Bad("APIversion", absl::StrCat("this listener speaks version 1, got \"",
                                          Printable(m.apiversion(), 16), "\""));
  }
  out.shot_number = m.shotnumber();
  const v1::OpenConnectShotDataOptions& o = m.shotdataoptions();
  if (o.isheartbeat()) {
    out.kind = OpenConnectMessageInfo::Kind::kHeartbeat;
    return out;
  }
  // A shot: the options say it carries ball data (a connector that sends no options but ball
  // data means a shot too).
  const bool shot = o.containsballdata() || (!m.has_shotdataoptions() && m.has_balldata());
  if (!shot) {
    out.kind = OpenConnectMessageInfo::Kind::kStatus;  // readiness, ball detected, club data only
    return out;
  }
  out.kind = OpenConnectMessageInfo::Kind::kShot;
  const v1::OpenConnectBallData& b = m.balldata();
  if (!b.has_speed()) return Bad("BallData.Speed", "required in a shot (mph)");
  if (absl::Status s = InRange("BallData.Speed", b.speed(), 0.1, 268.0, "mph"); !s.ok()) return s;
  if (!b.has_vla()) return Bad("BallData.VLA", "required in a shot (deg)");
  if (absl::Status s = InRange("BallData.VLA", b.vla(), -90.0, 90.0, "deg"); !s.ok()) return s;
  const double hla = b.has_hla() ? b.hla() : 0.0;
  if (absl::Status s = InRange("BallData.HLA", hla, -90.0, 90.0, "deg"); !s.ok()) return s;
  double spin = 0.0, axis = 0.0;
  if (b.has_totalspin()) {
    // TotalSpin and SpinAxis are what radar monitors measure; BackSpin and SideSpin are
    // derived from them. When a message carries both (as the protocol's own example does, and
    // they disagree there), TotalSpin and SpinAxis win.
    spin = b.totalspin();
    axis = b.has_spinaxis() ? b.spinaxis() : 0.0;
    if (absl::Status s = InRange("BallData.TotalSpin", spin, 0.0, 30000.0, "rpm"); !s.ok()) return s;
    if (absl::Status s = InRange("BallData.SpinAxis", axis, -90.0, 90.0, "deg"); !s.ok()) return s;
  } else if (b.has_backspin() || b.has_sidespin()) {
    const double back = b.backspin(), side = b.sidespin();
    if (absl::Status s = InRange("BallData.BackSpin", back, -30000.0, 30000.0, "rpm"); !s.ok()) return s;
    if (absl::Status s = InRange("BallData.SideSpin", side, -30000.0, 30000.0, "rpm"); !s.ok()) return s;
    spin = std::hypot(back, side);
    axis = spin > 0.0 ? std::atan2(side, back) * kDeg : 0.0;
    if (absl::Status s = InRange("BallData.TotalSpin", spin, 0.0, 30000.0, "rpm (from BackSpin and SideSpin)");
        !s.ok()) {
      return s;
    }
  } else {
    return Bad("BallData", "a shot needs TotalSpin (with SpinAxis) or BackSpin and SideSpin (rpm)");
  }
  out.launch.ball_speed_mps = b.speed() * kMetresPerSecondPerMph;
  out.launch.launch_angle_deg = b.vla();
  out.launch.launch_direction_deg = hla;
  out.launch.spin_rpm = spin;
  out.launch.spin_axis_deg = axis;
  return out;
}

std::string OpenConnectReplyJson(int code, std::string_view message, std::string_view club,
                                 std::optional<double> distance_to_target) {  // NOLINT
  v1::OpenConnectReply r;
  r.set_code(code);
  r.set_message(std::string(message));
  if (distance_to_target) {
    v1::OpenConnectPlayer* p = r.mutable_player();
    p->set_handed("RH");
    p->set_club(std::string(club));
    p->set_distancetotarget(std::round(*distance_to_target * 10.0) / 10.0);
  }
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.always_print_primitive_fields = true;
  std::string out;
  (void)google::protobuf::util::MessageToJsonString(r, &out, options);
  return out;
}

std::string_view SuggestClub(double d, bool on_green) {
  // Typical carries of an average male amateur, in metres (a suggestion the connector shows).
  if (on_green) return "PT";
  if (d > 190) return "DR";
  if (d > 175) return "W3";
  if (d > 160) return "I4";
  if (d > 150) return "I5";
  if (d > 140) return "I6";
  if (d > 130) return "I7";
  if (d > 120) return "I8";
  if (d > 110) return "I9";
  if (d > 90) return "PW";
  if (d > 70) return "GW";
  if (d > 40) return "SW";
  return "LW";
}

absl::Status JsonObjectSplitter::Feed(std::string_view bytes, std::vector<std::string>* out) {
  for (char c : bytes) {
    if (depth_ == 0) {
      if (c == ' ' || c == '\n' || c == '\r' || c == '\t') continue;
      if (c != '{') {
        return absl::FailedPreconditionError(absl::StrFormat(
            "the stream must be JSON objects; byte 0x%02x is outside any", static_cast<unsigned char>(c)));
      }
    }
    current_ += c;
    if (current_.size() > max_) {
      return absl::FailedPreconditionError(
          absl::StrFormat("a message is longer than %d bytes", max_));
    }
    if (in_string_) {
      if (escape_) {
        escape_ = false;
      } else if (c == '\\') {
        escape_ = true;
      } else if (c == '"') {
        in_string_ = false;
      }
      continue;
    }
    if (c == '"') {
      in_string_ = true;
    } else if (c == '{' || c == '[') {
      ++depth_;
    } else if (c == '}' || c == ']') {
      if (--depth_ == 0) {
        out->push_back(std::move(current_));
        current_.clear();
      }
    }
  }
  return absl::OkStatus();
}

// --- the listener ---------------------------------------------------------------------------

absl::StatusOr<std::unique_ptr<OpenConnectListener>> OpenConnectListener::Start(
    const OpenConnectOptions& options, RoundRegistry* rounds, WorkPool* pool) {
  const size_t colon = options.listen.rfind(':');
  if (colon == std::string::npos) {
    return absl::InvalidArgumentError("--open_connect_listen must be host:port");
  }
  std::string host = options.listen.substr(0, colon);
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  const std::string port = options.listen.substr(colon + 1);
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE | AI_NUMERICSERV;
  addrinfo* res = nullptr;
  if (const int rc = getaddrinfo(host.c_str(), port.c_str(), &hints, &res); rc != 0) {
    return absl::InvalidArgumentError(absl::StrFormat("--open_connect_listen: cannot resolve '%s': %s",
                                                      host, gai_strerror(rc)));
  }
  std::unique_ptr<OpenConnectListener> l(new OpenConnectListener(options, rounds, pool));
  absl::Status status = absl::UnavailableError("--open_connect_listen: no address to listen on");
  for (addrinfo* ai = res; ai != nullptr && l->listen_fd_ < 0; ai = ai->ai_next) {
    const int fd = socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC, ai->ai_protocol);
    if (fd < 0) continue;
    const int one = 1;
    setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    if (bind(fd, ai->ai_addr, ai->ai_addrlen) != 0 || listen(fd, 64) != 0) {
      status = absl::UnavailableError(absl::StrFormat("cannot listen on %s (--open_connect_listen): %s",
                                                      options.listen, std::strerror(errno)));
      close(fd);
      continue;
    }
    l->listen_fd_ = fd;
  }
  freeaddrinfo(res);
  if (l->listen_fd_ < 0) return status;
  sockaddr_storage bound{};
  socklen_t len = sizeof(bound);
  getsockname(l->listen_fd_, reinterpret_cast<sockaddr*>(&bound), &len);
  l->port_ = ntohs(bound.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&bound)->sin6_port
                                               : reinterpret_cast<sockaddr_in*>(&bound)->sin_port);
  OpenConnectListener* self = l.get();
  l->acceptor_ = std::thread([self] { self->Accept(); });
  return l;
}

OpenConnectListener::~OpenConnectListener() { Stop(); }

int OpenConnectListener::open_connections() const {
  absl::MutexLock lock(&mu_);
  return static_cast<int>(std::count_if(connections_.begin(), connections_.end(),
                                        [](const Connection& c) { return !c.done.load(); }));
}

void OpenConnectListener::Stop() {
  if (stopping_.exchange(true)) return;
  if (acceptor_.joinable()) acceptor_.join();
  absl::MutexLock lock(&mu_);
  for (Connection& c : connections_) shutdown(c.fd, SHUT_RDWR);  // wakes its thread
  for (Connection& c : connections_) {
    c.thread.join();
    close(c.fd);
  }
  connections_.clear();
  if (listen_fd_ >= 0) close(listen_fd_);
  listen_fd_ = -1;
}

void OpenConnectListener::Accept() {
  while (!stopping_.load()) {
    {
      // Reap the connections that ended: their threads are done with their sockets.
      absl::MutexLock lock(&mu_);
      for (auto it = connections_.begin(); it != connections_.end();) {
        if (!it->done.load()) {
          ++it;
          continue;
        }
        it->thread.join();
        close(it->fd);
        it = connections_.erase(it);
      }
    }
    pollfd p{listen_fd_, POLLIN, 0};
    if (poll(&p, 1, 100) <= 0) continue;
    const int fd = accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd < 0) continue;
    const int one = 1;
    setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
    absl::MutexLock lock(&mu_);
    if (static_cast<int>(connections_.size()) >= options_.max_connections) {
      const std::string busy = OpenConnectReplyJson(
          503, absl::StrFormat("too many connections (at most %d)", options_.max_connections));
      (void)send(fd, busy.data(), busy.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
      close(fd);
      failures_.fetch_add(1);
      continue;
    }
    Connection& c = connections_.emplace_back();
    c.fd = fd;
    Connection* conn = &c;
    c.thread = std::thread([this, conn] {
      Serve(conn->fd);
      conn->done.store(true);
    });
  }
}

bool OpenConnectListener::Send(int fd, const std::string& text) {
  size_t sent = 0;
  const int64_t deadline = NowNs() + absl::ToInt64Nanoseconds(options_.write_timeout);
  while (sent < text.size()) {
    const ssize_t n = send(fd, text.data() + sent, text.size() - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      sent += static_cast<size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) return false;
    const int64_t left_ms = (deadline - NowNs()) / 1000000;
    if (left_ms <= 0 || stopping_.load()) return false;  // the peer does not read its replies
    pollfd p{fd, POLLOUT, 0};
    poll(&p, 1, static_cast<int>(std::min<int64_t>(left_ms, 100)));
  }
  return true;
}

void OpenConnectListener::Serve(int fd) {
  JsonObjectSplitter split(options_.max_message_bytes);
  char buf[4096];
  int64_t last = NowNs();
  const int64_t idle_ns = absl::ToInt64Nanoseconds(options_.idle_timeout);
  while (!stopping_.load()) {
    pollfd p{fd, POLLIN, 0};
    const int rc = poll(&p, 1, 100);
    if (rc < 0 && errno != EINTR) return;
    if (rc <= 0) {
      if (NowNs() - last > idle_ns) {
        (void)Send(fd, OpenConnectReplyJson(
                           504, absl::StrFormat("closed: nothing received for %s (send heartbeats)",
                                                absl::FormatDuration(options_.idle_timeout))));
        return;
      }
      continue;
    }
    const ssize_t n = recv(fd, buf, sizeof(buf), 0);
    if (n <= 0) return;  // closed by the peer, or Stop's shutdown
    last = NowNs();
    std::vector<std::string> messages;
    const absl::Status s = split.Feed(std::string_view(buf, static_cast<size_t>(n)), &messages);
    for (const std::string& m : messages) {
      if (!Handle(fd, m)) return;
    }
    if (!s.ok()) {
      failures_.fetch_add(1);
      (void)Send(fd, OpenConnectReplyJson(501, absl::StrCat("closed: ", s.message())));
      return;
    }
  }
}

bool OpenConnectListener::Handle(int fd, const std::string& json) {
  absl::StatusOr<OpenConnectMessageInfo> m = ParseOpenConnect(json);
  if (!m.ok()) {
    failures_.fetch_add(1);
    return Send(fd, OpenConnectReplyJson(501, std::string(m.status().message())));
  }
  if (m->kind == OpenConnectMessageInfo::Kind::kHeartbeat) {
    return Send(fd, OpenConnectReplyJson(200, "heartbeat received"));
  }
  if (m->kind == OpenConnectMessageInfo::Kind::kStatus) {
    return Send(fd, OpenConnectReplyJson(200, "status received"));
  }
  std::optional<MonitorBinding> bound = rounds_->Monitor(m->device_id);
  if (!bound) {
    failures_.fetch_add(1);
    return Send(fd, OpenConnectReplyJson(
                        502, absl::StrFormat("DeviceID %s is bound to no seat: bind it with `sportsim "
                                             "round monitor ID --token T --device DEVICE_ID`",
                                             Quote(m->device_id))));
  }
  v1::PlayStrokeRequest q;
  q.set_round_id(bound->round_id);
  q.set_token(bound->token);
  v1::LaunchConditions* l = q.mutable_launch();
  l->set_ball_speed_mps(m->launch.ball_speed_mps);
  l->set_launch_angle_deg(m->launch.launch_angle_deg);
  l->set_launch_direction_deg(m->launch.launch_direction_deg);
  l->set_spin_rpm(m->launch.spin_rpm);
  l->set_spin_axis_deg(m->launch.spin_axis_deg);
  // The stroke is a simulation like any other: on the pool, under its CPU budget.
  absl::Notification done;
  absl::StatusOr<v1::PlayStrokeResponse> result = absl::UnknownError("not run");
  const absl::Status queued = pool_->Submit(
      [&](const WorkControl& control) {
        result = rounds_->Stroke(q, [&control] { return control.ShouldStop(); });
        if (!result.ok() && !control.Check().ok()) result = control.Check();
        done.Notify();
      },
      [&](const absl::Status& why) {
        result = why;
        done.Notify();
      },
      [this] { return stopping_.load(); }, std::nullopt);
  if (!queued.ok()) {
    result = queued;
  } else {
    done.WaitForNotification();
  }
  if (!result.ok()) {
    failures_.fetch_add(1);
    return Send(fd, OpenConnectReplyJson(500, absl::StrCat(absl::StatusCodeToString(result.status().code()),
                                                           ": ", result.status().message())));
  }
  shots_.fetch_add(1);
  if (!Send(fd, OpenConnectReplyJson(200, absl::StrFormat("Shot received successfully (stroke %d)",
                                                          result->stroke())))) {
    return false;
  }
  // At rest: the seat's next club and distance (201), as a simulator tells the connector.
  v1::GetRoundRequest g;
  g.set_round_id(bound->round_id);
  const int64_t give_up = NowNs() + absl::ToInt64Nanoseconds(options_.rest_wait);
  while (!stopping_.load() && NowNs() < give_up) {
    absl::StatusOr<v1::RoundInfo> info = rounds_->Get(g);
    if (!info.ok()) return true;  // deleted meanwhile: nothing more to say
    if (!info->round().stroke_in_play()) {
      const v1::RoundPlayerState& p = info->round().players(bound->seat);
      const double d = p.ball().distance_to_pin_m();
      return Send(fd, OpenConnectReplyJson(201, "Player information",
                                           SuggestClub(d, p.ball().lie() == "green"),
                                           m->metres ? d : d / kMetresPerYard));
    }
    absl::SleepFor(absl::Milliseconds(20));
  }
  return true;
}

}  // namespace sportsim::server
