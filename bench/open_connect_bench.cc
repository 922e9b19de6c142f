// sportsim-open-connect-bench: what a launch monitor's shot costs over GSPro Open Connect
// (docs/golf-open-connect.md). An in-process server with its Open Connect listener on loopback:
//   1. latency: --shots drives, each from a fresh one-player round in fast-forward (the ball
//      rests at the next tick, so what is left is the server's own time): from the shot's last
//      byte sent to the 200 (the stroke simulated, checked and committed) and to the 201 (the
//      ball at rest, the player's next club and distance). A round on the real clock adds the
//      ball's own time in motion, printed for one drive.
//   2. bytes: one round on the real clock with a gRPC WatchRound watcher at the default rate;
//      a drive and a pitch sent by the monitor; the watcher's snapshot bytes from the shot until
//      the ball is at rest (its frames, events and state, heartbeats included).
// Prints one line per measure; medians over the shots.
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <google/protobuf/util/json_util.h>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/strings/str_format.h"
#include "bench/load_watch.h"
#include "server/app/server_app.h"
#include "server/rpc/open_connect.h"
#include "sportsim/v1/open_connect.pb.h"
#include "sportsim/v1/swing.grpc.pb.h"

ABSL_FLAG(int, shots, 30, "drives timed (each from a fresh round)");

namespace sportsim::bench {
namespace {

using Clock = std::chrono::steady_clock;

double Ms(Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[static_cast<size_t>(q * static_cast<double>(v.size() - 1))];
}

std::string Shot(const std::string& device, double mph, double vla, double spin) {
  return absl::StrFormat(
      R"({"DeviceID": "%s", "Units": "Yards", "ShotNumber": 1, "APIversion": "1",
          "BallData": {"Speed": %g, "VLA": %g, "HLA": 0, "TotalSpin": %g, "SpinAxis": 0},
          "ShotDataOptions": {"ContainsBallData": true, "ContainsClubData": false, "IsHeartBeat": false}})",
      device, mph, vla, spin);
}

class Monitor {
 public:
  explicit Monitor(int port) : split_(1 << 16) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ok_ = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
  }
  ~Monitor() { ::close(fd_); }
  bool ok() const { return ok_; }
  void Send(const std::string& text) { ok_ = ok_ && ::send(fd_, text.data(), text.size(), MSG_NOSIGNAL) > 0; }
  // The next reply's code (0: none within the timeout).
  int Next(double seconds = 60) {
    const auto until = Clock::now() + std::chrono::duration<double>(seconds);
    while (pending_.empty() && Clock::now() < until) {
      pollfd p{fd_, POLLIN, 0};
      if (poll(&p, 1, 20) <= 0) continue;
      char buf[4096];
      const ssize_t n = ::recv(fd_, buf, sizeof(buf), 0);
      if (n <= 0) return 0;
      (void)split_.Feed(std::string_view(buf, static_cast<size_t>(n)), &pending_);
    }
    if (pending_.empty()) return 0;
    v1::OpenConnectReply r;
    (void)google::protobuf::util::JsonStringToMessage(pending_.front(), &r);
    pending_.erase(pending_.begin());
    return r.code();
  }

 private:
  int fd_ = -1;
  bool ok_ = false;
  server::JsonObjectSplitter split_;
  std::vector<std::string> pending_;
};

v1::CreateRoundResponse NewRound(server::ServerApp& app, bool fast, const std::string& device) {
  v1::CreateRoundRequest c;
  c.add_players()->set_name("Ann");
  c.set_fast_forward(fast);
  v1::CreateRoundResponse made = *app.rounds().Create(c);
  v1::BindMonitorRequest b;
  b.set_round_id(made.round_id());
  b.set_token(made.seats(0).token());
  b.set_device_id(device);
  (void)app.rounds().BindMonitor(b);
  return made;
}

int Run() {
  server::ServerConfig config;
  config.listen = "127.0.0.1:0";
  config.open_connect.listen = "127.0.0.1:0";
  absl::StatusOr<std::unique_ptr<server::ServerApp>> started = server::ServerApp::Start(config);
  if (!started.ok()) {
    std::fprintf(stderr, "server: %s\n", std::string(started.status().message()).c_str());
    return 1;
  }
  server::ServerApp& app = **started;
  const int port = app.open_connect_port();

  // 1. Latency, fast-forward.
  std::vector<double> accepted, at_rest;
  for (int i = 0; i < absl::GetFlag(FLAGS_shots); ++i) {
    const std::string device = absl::StrFormat("LM-%d", i);
    NewRound(app, true, device);
    Monitor m(port);
    const auto t0 = Clock::now();
    m.Send(Shot(device, 150, 11, 2700));
    const int a = m.Next();
    const auto t1 = Clock::now();
    const int b = m.Next();
    const auto t2 = Clock::now();
    if (a != 200 || b != 201) {
      std::fprintf(stderr, "shot %d: replies %d and %d\n", i, a, b);
      return 1;
    }
    accepted.push_back(Ms(t1 - t0));
    at_rest.push_back(Ms(t2 - t0));
  }
  std::printf("shot to 200 (simulated, committed): median %.2f ms, p90 %.2f ms (%zu drives)\n",
              Quantile(accepted, 0.5), Quantile(accepted, 0.9), accepted.size());
  std::printf("shot to 201 (at rest, fast-forward): median %.2f ms, p90 %.2f ms\n",
              Quantile(at_rest, 0.5), Quantile(at_rest, 0.9));

  // 2. Bytes per watcher per stroke, on the real clock; also the drive's real time to rest.
  const v1::CreateRoundResponse live = NewRound(app, false, "LM-LIVE");
  std::unique_ptr<v1::Swing::Stub> stub = v1::Swing::NewStub(
      grpc::CreateChannel(app.address(), grpc::InsecureChannelCredentials()));
  v1::WatchRoundRequest w;
  w.set_round_id(live.round_id());
  CountingWatch<v1::WatchRoundRequest, v1::RoundSnapshot> watch(
      [&](grpc::ClientContext* ctx, const v1::WatchRoundRequest* q,
          grpc::ClientReadReactor<v1::RoundSnapshot>* r) { stub->async()->WatchRound(ctx, q, r); },
      w);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  Monitor m(port);
  for (const auto& [what, shot] : {std::pair{"drive", Shot("LM-LIVE", 150, 11, 2700)},
                                   std::pair{"pitch", Shot("LM-LIVE", 45, 30, 8000)}}) {
    const int64_t b0 = watch.bytes(), s0 = watch.snapshots();
    const auto t0 = Clock::now();
    m.Send(shot);
    const int a = m.Next(), b = m.Next(120);
    const auto t1 = Clock::now();
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the rest frame in flight
    if (a != 200 || b != 201) {
      std::fprintf(stderr, "%s: replies %d and %d\n", what, a, b);
      return 1;
    }
    std::printf("%s on the real clock: shot to 201 %.2f s; the watcher got %lld snapshots, %lld bytes\n",
                what, Ms(t1 - t0) / 1e3, static_cast<long long>(watch.snapshots() - s0),
                static_cast<long long>(watch.bytes() - b0));
  }
  watch.Stop();
  app.Shutdown(absl::Seconds(1));
  return 0;
}

}  // namespace
}  // namespace sportsim::bench

int main(int argc, char** argv) {
  absl::ParseCommandLine(argc, argv);
  return sportsim::bench::Run();
}
