// sportsim-load: the table server under load. Starts the server in-process on a loopback port,
// creates N tables, keeps each moving (a fresh 8-ball rack broken again as soon as the last shot
// ends), attaches gRPC watchers over loopback, and after a warm-up measures for a while:
// ticks and late ticks, snapshots/s, latest-wins replacements, publish-to-write latency p50/p99,
// payload bytes per watcher per second, and CPU (the tick workers' and the whole process's,
// clients included). docs/server.md has the results and what they mean.
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/synchronization/mutex.h"
#include "bench/load_watch.h"
#include "server/app/server_app.h"
#include "sportsim/v1/billiards.grpc.pb.h"

ABSL_FLAG(int, tables, 1000, "Tables, each kept moving");
ABSL_FLAG(double, tick_hz, 120, "Tick rate of every table");
ABSL_FLAG(int, watchers, 1, "Watchers per table");
ABSL_FLAG(double, watch_hz, 30, "Snapshot rate each watcher asks for");
ABSL_FLAG(bool, changed_only, false, "Watchers ask for changed balls only");
ABSL_FLAG(bool, positions_only, false, "Watchers ask for positions only");
ABSL_FLAG(double, seconds, 20, "Measured time");
ABSL_FLAG(double, warmup, 5, "Time before measuring (tables start and spread out)");
ABSL_FLAG(int, channels, 8, "Client connections the watchers share");
ABSL_FLAG(int, workers, 0, "Tick workers (0: one per core)");
ABSL_FLAG(std::string, engine, "event", "event or stepped");
ABSL_FLAG(uint64_t, seed, 1, "Seed of the break speeds and angles");
ABSL_FLAG(std::string, data_dir, "",
          "Journal every command in SQLite in this directory (empty: no journal), to measure "
          "what durability costs the ticks");

namespace sportsim {
namespace {

using Clock = std::chrono::steady_clock;

using bench::ProcessCpuSeconds;

// One watcher: reads snapshots as fast as they come, and flags the table idle when its shot
// ends (a resynced reader may have lost shot_end, but it still sees the table at rest).
using Watch = bench::CountingWatch<v1::WatchTableRequest, v1::TableSnapshot>;

std::unique_ptr<Watch> NewWatch(v1::Billiards::Stub* stub, const v1::WatchTableRequest& request,
                                std::atomic<bool>* idle) {
  return std::make_unique<Watch>(
      [stub](grpc::ClientContext* ctx, const v1::WatchTableRequest* r,
             grpc::ClientReadReactor<v1::TableSnapshot>* reactor) {
        stub->async()->WatchTable(ctx, r, reactor);
      },
      request, [idle](const v1::TableSnapshot& snap) {
        bool rest = snap.resync() && snap.at_rest();
        for (const v1::TableEvent& e : snap.events()) rest |= e.kind() == v1::shot_end;
        if (rest && idle != nullptr) idle->store(true);
      });
}

int Run() {
  const int n = absl::GetFlag(FLAGS_tables);
  server::ServerConfig config{.listen = "127.0.0.1:0"};
  config.tables.world.max_worlds = n + 1;
  config.tables.world.max_watchers = std::max(1, absl::GetFlag(FLAGS_watchers));
  config.tick_workers = absl::GetFlag(FLAGS_workers);
  config.store.data_dir = absl::GetFlag(FLAGS_data_dir);
  absl::StatusOr<std::unique_ptr<server::ServerApp>> app = server::ServerApp::Start(config);
  if (!app.ok()) {
    std::fprintf(stderr, "sportsim-load: %s\n", std::string(app.status().message()).c_str());
    return 2;
  }
  server::TableRegistry& reg = (*app)->tables();

  v1::CreateTableRequest create;
  create.mutable_table()->set_rack("8ball");
  create.set_tick_hz(absl::GetFlag(FLAGS_tick_hz));
  create.set_seats(1);
  create.mutable_solver()->set_engine(absl::GetFlag(FLAGS_engine) == "stepped"
                                          ? v1::ENGINE_STEPPED
                                          : v1::ENGINE_EVENT);
  struct T {
    std::string id, token;
    std::atomic<bool> idle{true};
  };
  std::vector<std::unique_ptr<T>> tables;
  for (int i = 0; i < n; ++i) {
    absl::StatusOr<v1::CreateTableResponse> t = reg.Create(create);
    if (!t.ok()) {
      std::fprintf(stderr, "create: %s\n", std::string(t.status().message()).c_str());
      return 2;
    }
    auto x = std::make_unique<T>();
    x->id = t->table_id();
    x->token = t->seats(0).token();
    tables.push_back(std::move(x));
  }

  std::vector<std::unique_ptr<v1::Billiards::Stub>> stubs;
  for (int c = 0; c < std::max(1, absl::GetFlag(FLAGS_channels)); ++c) {
    grpc::ChannelArguments args;
    args.SetInt("sportsim.channel", c);  // distinct arguments: distinct connections
    stubs.push_back(v1::Billiards::NewStub(grpc::CreateCustomChannel(
        (*app)->address(), grpc::InsecureChannelCredentials(), args)));
  }
  std::vector<std::unique_ptr<Watch>> watches;
  for (int i = 0; i < n; ++i) {
    for (int w = 0; w < absl::GetFlag(FLAGS_watchers); ++w) {
      v1::WatchTableRequest req;
      req.set_table_id(tables[i]->id);
      req.set_rate_hz(absl::GetFlag(FLAGS_watch_hz));
      req.set_changed_only(absl::GetFlag(FLAGS_changed_only));
      if (absl::GetFlag(FLAGS_positions_only)) req.add_fields(v1::SNAPSHOT_FIELD_POSITION);
      // Only the first watcher of a table decides when it is idle (the others would re-flag a
      // shot_end the shooter already acted on).
      watches.push_back(NewWatch(stubs[watches.size() % stubs.size()].get(), req,
                                 w == 0 ? &tables[i]->idle : nullptr));
    }
  }

  // The shooter: every idle table is re-racked and broken again (8-ball break, 6-9 m/s).
  std::atomic<bool> stop{false};
  std::atomic<int64_t> shots{0};
  std::thread shooter([&] {
    std::mt19937_64 rng(absl::GetFlag(FLAGS_seed));
    std::uniform_real_distribution<double> speed(6, 9), phi(-1, 1), side(-0.2, 0.2);
    while (!stop) {
      for (const auto& t : tables) {
        if (stop) break;
        if (!t->idle.exchange(false)) continue;
        v1::ResetTableRequest reset;
        reset.set_table_id(t->id);
        reset.set_token(t->token);
        (void)reg.Reset(reset);
        v1::ShootRequest shot;
        shot.set_table_id(t->id);
        shot.set_token(t->token);
        shot.mutable_strike()->set_ball_speed_mps(speed(rng));
        shot.mutable_strike()->set_phi_deg(phi(rng));
        shot.mutable_strike()->set_a(side(rng));
        if (reg.Shoot(shot).ok()) {
          shots.fetch_add(1);
        } else {
          t->idle = true;
        }
        // Spread the first breaks over a second, so ticks are not all in phase.
        if (shots.load() <= n) std::this_thread::sleep_for(std::chrono::microseconds(1000000 / n));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });

  std::this_thread::sleep_for(std::chrono::duration<double>(absl::GetFlag(FLAGS_warmup)));
  const auto snapshot = [&] {
    struct S {
      bench::HostSample host;
      int64_t client_snapshots = 0, bytes = 0, shots = 0;
      double cpu = 0;
      Clock::time_point at;
    } s;
    s.host = {reg.stats(), reg.publish_to_write().Counts()};
    for (const auto& w : watches) {
      s.client_snapshots += w->snapshots();
      s.bytes += w->bytes();
    }
    s.shots = shots.load();
    s.cpu = ProcessCpuSeconds();
    s.at = Clock::now();
    return s;
  };
  const auto a = snapshot();
  std::this_thread::sleep_for(std::chrono::duration<double>(absl::GetFlag(FLAGS_seconds)));
  const auto b = snapshot();
  stop = true;
  shooter.join();

  const double secs = std::chrono::duration<double>(b.at - a.at).count();
  const bench::HostWindow w = bench::Between(a.host, b.host, secs);
  const double got = static_cast<double>(b.client_snapshots - a.client_snapshots);
  const double nw = std::max<double>(1.0, static_cast<double>(watches.size()));
  std::printf(
      "tables %d at %g Hz (%s engine), %d watcher(s) each at %g Hz%s%s, %d tick workers, %.1f s "
      "measured\n",
      n, absl::GetFlag(FLAGS_tick_hz), absl::GetFlag(FLAGS_engine).c_str(),
      absl::GetFlag(FLAGS_watchers), absl::GetFlag(FLAGS_watch_hz),
      absl::GetFlag(FLAGS_changed_only) ? ", changed only" : "",
      absl::GetFlag(FLAGS_positions_only) ? ", positions only" : "",
      config.tick_workers > 0 ? config.tick_workers
                                : static_cast<int>(std::thread::hardware_concurrency()),
      secs);
  std::printf("moving tables (end)      %d\n", b.host.stats.running);
  std::printf("ticks/s                  %.0f (of %.0f if all %d moved)\n", w.ticks,
              n * absl::GetFlag(FLAGS_tick_hz), n);
  std::printf("late ticks               %.3f %%  (+ %.3f %% slipped)\n", w.late_pct,
              w.slipped_pct);
  std::printf("snapshots/s              %.0f written, %.0f read by clients, %.0f replaced\n",
              w.sent, got / secs, w.replaced);
  std::printf("publish-to-write         p50 %.3f ms, p99 %.3f ms (from the tick's deadline; "
              "bucket upper edges)\n",
              w.p50_ms, w.p99_ms);
  std::printf("bytes per watcher        %.0f B/s (payload)\n",
              static_cast<double>(b.bytes - a.bytes) / secs / nw);
  std::printf("shots                    %lld started\n",
              static_cast<long long>(b.shots - a.shots));
  std::printf("CPU                      tick workers %.2f cores, whole process %.2f cores "
              "(server and clients)\n",
              w.tick_cores, (b.cpu - a.cpu) / secs);

  for (auto& watch : watches) watch->Stop();
  (*app)->Shutdown(absl::Seconds(1));
  (*app)->Wait();
  return 0;
}

}  // namespace
}  // namespace sportsim

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "sportsim-load [--tables N --tick_hz HZ --watchers W --watch_hz HZ --seconds S]: the "
      "table server under load, in-process over loopback");
  absl::ParseCommandLine(argc, argv);
  return sportsim::Run();
}
