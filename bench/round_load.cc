// sportsim-round-load: rounds of golf held at once. Starts the server in-process on a loopback
// port, creates N rounds of four players on sportsim_links, attaches a gRPC watcher to each,
// and plays them: each round takes its next command (a stroke or a relief choice, by the fixed
// policy of bench/golf_round_bench.cc) every --stroke_every seconds once its ball is at rest,
// the rounds' turns spread over that period; a finished round is deleted and another created.
// After a warm-up it measures: strokes played and their CPU, ticks and late ticks, snapshots,
// publish-to-write latency, bytes per watcher, and the CPU of the tick workers and of the whole
// process (clients included). docs/golf-rounds.md has the results.
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/synchronization/mutex.h"
#include "bench/load_watch.h"
#include "sim/core/cpu_clock.h"
#include "server/app/server_app.h"
#include "sportsim/v1/swing.grpc.pb.h"

ABSL_FLAG(int, rounds, 1000, "Rounds held at once, four players each");
ABSL_FLAG(double, tick_hz, 30, "Tick rate of every round");
ABSL_FLAG(double, stroke_every, 10, "Seconds between a round's commands (human pace: ~50)");
ABSL_FLAG(double, watch_hz, 30, "Snapshot rate each watcher asks for");
ABSL_FLAG(double, seconds, 20, "Measured time");
ABSL_FLAG(double, warmup, 5, "Time before measuring");
ABSL_FLAG(int, channels, 8, "Client connections the watchers share");
ABSL_FLAG(int, workers, 0, "Tick workers (0: one per core)");

namespace sportsim {
namespace {

using Clock = std::chrono::steady_clock;

using bench::ProcessCpuSeconds;


using Watch = bench::CountingWatch<v1::WatchRoundRequest, v1::RoundSnapshot>;

struct R {
  std::string id, admin;
  std::vector<std::string> tokens;
  std::unique_ptr<Watch> watch;
  std::atomic<int64_t> past_snapshots{0}, past_bytes{0};  // of the round's earlier watchers
  Clock::time_point next;
};

// The fixed policy (bench/golf_round_bench.cc) on the round's state as the wire gives it.
void PlayNext(server::RoundRegistry& reg, R& r, const v1::RoundState& st) {
  if (st.has_decision()) {
    v1::DecideRoundRequest q;
    q.set_round_id(r.id);
    q.set_token(r.tokens[st.decision().seat()]);
    q.set_choice(st.decision().choices(st.decision().choices_size() - 1));
    (void)reg.Decide(q);
    return;
  }
  const int seat = st.to_play();
  if (seat < 0) return;
  const v1::RoundPlayerState& p = st.players(seat);
  const double d = p.ball().distance_to_pin_m();
  v1::PlayStrokeRequest q;
  q.set_round_id(r.id);
  q.set_token(r.tokens[seat]);
  const golf::RoundStroke k = golf::ReferenceStroke(
      d, p.ball().lie() == "green", static_cast<int>(p.strokes()) - static_cast<int>(st.par()));
  if (k.kind == golf::RoundStroke::Kind::kPutt) {
    q.set_putt_speed_mps(k.speed_mps);
  } else {
    v1::LaunchConditions* l = q.mutable_launch();
    l->set_ball_speed_mps(k.launch.ball_speed_mps);
    l->set_launch_angle_deg(k.launch.launch_angle_deg);
    l->set_spin_rpm(k.launch.spin_rpm);
  }
  (void)reg.Stroke(q);
}

int Run() {
  const int n = absl::GetFlag(FLAGS_rounds);
  server::ServerConfig config{.listen = "127.0.0.1:0"};
  config.rounds.world.max_worlds = 2 * n + 1;
  config.tick_workers = absl::GetFlag(FLAGS_workers);
  absl::StatusOr<std::unique_ptr<server::ServerApp>> app = server::ServerApp::Start(config);
  if (!app.ok()) {
    std::fprintf(stderr, "sportsim-round-load: %s\n", std::string(app.status().message()).c_str());
    return 2;
  }
  server::RoundRegistry& reg = (*app)->rounds();
  std::vector<std::unique_ptr<v1::Swing::Stub>> stubs;
  for (int c = 0; c < std::max(1, absl::GetFlag(FLAGS_channels)); ++c) {
    grpc::ChannelArguments args;
    args.SetInt("sportsim.channel", c);  // distinct arguments: distinct connections
    stubs.push_back(v1::Swing::NewStub(grpc::CreateCustomChannel(
        (*app)->address(), grpc::InsecureChannelCredentials(), args)));
  }
  v1::CreateRoundRequest create;
  create.set_course("sportsim_links");
  for (const char* name : {"Ann", "Bob", "Cat", "Dan"}) create.add_players()->set_name(name);
  create.set_tick_hz(absl::GetFlag(FLAGS_tick_hz));
  const auto every = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(absl::GetFlag(FLAGS_stroke_every)));
  int64_t made = 0;
  auto start = [&](R& r, Clock::time_point first) -> bool {
    create.set_seed(static_cast<uint64_t>(made++));
    absl::StatusOr<v1::CreateRoundResponse> c = reg.Create(create);
    if (!c.ok()) {
      std::fprintf(stderr, "create: %s\n", std::string(c.status().message()).c_str());
      return false;
    }
    r.id = c->round_id();
    r.admin = c->admin_token();
    r.tokens.clear();
    for (const v1::Seat& s : c->seats()) r.tokens.push_back(s.token());
    v1::WatchRoundRequest w;
    w.set_round_id(r.id);
    w.set_rate_hz(absl::GetFlag(FLAGS_watch_hz));
    if (r.watch != nullptr) {
      r.watch->Stop();
      r.past_snapshots += r.watch->snapshots();
      r.past_bytes += r.watch->bytes();
    }
    v1::Swing::Stub* stub = stubs[static_cast<size_t>(made) % stubs.size()].get();
    r.watch = std::make_unique<Watch>(
        [stub](grpc::ClientContext* ctx, const v1::WatchRoundRequest* q,
               grpc::ClientReadReactor<v1::RoundSnapshot>* reactor) {
          stub->async()->WatchRound(ctx, q, reactor);
        },
        w);
    r.next = first;
    return true;
  };
  std::vector<R> rounds(static_cast<size_t>(n));
  const Clock::time_point t0 = Clock::now();
  for (int i = 0; i < n; ++i) {
    if (!start(rounds[static_cast<size_t>(i)], t0 + every * i / n)) return 2;  // spread out
  }

  std::atomic<bool> stop{false};
  std::atomic<int64_t> commands{0}, finished{0};
  std::atomic<int64_t> player_cpu_ns{0};
  std::thread player([&] {
    while (!stop) {
      const Clock::time_point now = Clock::now();
      for (R& r : rounds) {
        if (stop) break;
        if (now < r.next) continue;
        v1::GetRoundRequest g;
        g.set_round_id(r.id);
        absl::StatusOr<v1::RoundInfo> info = reg.Get(g);
        if (!info.ok() || info->round().stroke_in_play()) continue;
        if (!info->round().result().empty()) {
          v1::DeleteRoundRequest del;
          del.set_round_id(r.id);
          del.set_token(r.admin);
          (void)reg.Delete(del);
          finished.fetch_add(1);
          start(r, now + every);
          continue;
        }
        const double c0 = ThreadCpuSeconds();
        PlayNext(reg, r, info->round());
        player_cpu_ns.fetch_add(static_cast<int64_t>(1e9 * (ThreadCpuSeconds() - c0)));
        commands.fetch_add(1);
        r.next = now + every;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  });

  std::this_thread::sleep_for(std::chrono::duration<double>(absl::GetFlag(FLAGS_warmup)));
  struct S {
    bench::HostSample host;
    int64_t snapshots = 0, bytes = 0, commands = 0, finished = 0, player_ns = 0;
    double cpu = 0;
    Clock::time_point at;
  };
  const auto snapshot = [&] {
    S s;
    s.host = {reg.stats(), reg.publish_to_write().Counts()};
    for (const R& r : rounds) {  // (a round replaced meanwhile may be off by one watcher)
      s.snapshots += r.past_snapshots + r.watch->snapshots();
      s.bytes += r.past_bytes + r.watch->bytes();
    }
    s.commands = commands.load();
    s.finished = finished.load();
    s.player_ns = player_cpu_ns.load();
    s.cpu = ProcessCpuSeconds();
    s.at = Clock::now();
    return s;
  };
  const S a = snapshot();
  std::this_thread::sleep_for(std::chrono::duration<double>(absl::GetFlag(FLAGS_seconds)));
  const S b = snapshot();
  stop = true;
  player.join();

  const double secs = std::chrono::duration<double>(b.at - a.at).count();
  const bench::HostWindow w = bench::Between(a.host, b.host, secs);
  const double cmds = static_cast<double>(b.commands - a.commands);
  std::printf("rounds %d (4 players) at %g Hz, a command every %g s each, a watcher each at %g "
              "Hz, %.1f s measured\n",
              n, absl::GetFlag(FLAGS_tick_hz), absl::GetFlag(FLAGS_stroke_every),
              absl::GetFlag(FLAGS_watch_hz), secs);
  std::printf("commands                 %.1f /s (strokes and choices), %lld rounds finished\n",
              cmds / secs, static_cast<long long>(b.finished - a.finished));
  std::printf("command CPU              %.2f ms each (the stroke's simulation and ruling)\n",
              cmds > 0 ? 1e-6 * static_cast<double>(b.player_ns - a.player_ns) / cmds : 0.0);
  std::printf("moving balls (end)       %d\n", b.host.stats.running);
  std::printf("ticks/s                  %.0f\n", w.ticks);
  std::printf("late ticks               %.3f %%  (+ %.3f %% slipped)\n", w.late_pct, w.slipped_pct);
  std::printf("snapshots/s              %.0f written, %.0f read by clients\n", w.sent,
              static_cast<double>(b.snapshots - a.snapshots) / secs);
  std::printf("publish-to-write         p50 %.3f ms, p99 %.3f ms\n", w.p50_ms, w.p99_ms);
  std::printf("bytes per watcher        %.0f B/s (payload)\n",
              static_cast<double>(b.bytes - a.bytes) / secs / n);
  std::printf("CPU                      tick workers %.2f cores, whole process %.2f cores "
              "(server and clients)\n",
              w.tick_cores, (b.cpu - a.cpu) / secs);
  for (R& r : rounds) r.watch->Stop();
  (*app)->Shutdown(absl::Seconds(1));
  (*app)->Wait();
  return 0;
}

}  // namespace
}  // namespace sportsim

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "sportsim-round-load [--rounds N --stroke_every S --seconds S]: golf rounds held at once, "
      "a watcher each, in-process over loopback");
  absl::ParseCommandLine(argc, argv);
  return sportsim::Run();
}
