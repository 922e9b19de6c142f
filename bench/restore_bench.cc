// sportsim-restore: what a restart costs. Starts the server in-process on a journal (SQLite in
// a fresh temporary directory, or PostgreSQL with --store), creates N tables, breaks a 9-ball
// rack on each and plays `--shots` shots per table, stops the server with every table mid-shot
// (a stop after the last shot's strike, before it ends), starts it again on the same journal and
// reports: the restore's wall time (every table recreated, its commands replayed, its shot
// advanced to the tick it had reached), tables restored, and journal bytes per shot.
//
// With --sessions, as many swing sessions each swing `--swings` times (the chapter's swing, the
// last one in flight at the stop) before the restart: the restore then replays each session's
// swings since its latest checkpoint, or since its creation with --nosession_checkpoints.
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/match.h"
#include "absl/strings/str_format.h"
#include "server/app/server_app.h"

ABSL_FLAG(int, tables, 1000, "Tables, each mid-shot at the restart");
ABSL_FLAG(int, shots, 4, "Shots per table before the restart (the last one in flight)");
ABSL_FLAG(std::string, store, "", "postgresql://... (empty: SQLite in a temporary directory)");
ABSL_FLAG(int, sessions, 0, "Swing sessions, each mid-swing at the restart");
ABSL_FLAG(int, swings, 200, "Swings per session before the restart (the last one in flight)");
ABSL_FLAG(bool, session_checkpoints, true,
          "Sessions write their checkpoints (false: a restore replays every swing)");
ABSL_FLAG(double, clock_rate, 50,
          "World time per wall time while the shots and swings before the last play");

namespace sportsim {
namespace {

namespace fs = std::filesystem;
using server::ServerApp;
using server::ServerConfig;

int64_t DirBytes(const fs::path& dir) {
  int64_t total = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) total += static_cast<int64_t>(e.file_size());
  }
  return total;
}

// Swing `swing` (from 0) of every session; all but the last are waited for.
bool SwingAll(server::SessionRegistry& registry,
              const std::vector<std::pair<std::string, std::string>>& sessions, int swing,
              bool last) {
  for (const auto& [id, token] : sessions) {
    v1::StartSwingRequest start;  // the chapter's torques
    start.set_session_id(id);
    start.set_token(token);
    absl::StatusOr<v1::StartSwingResponse> r = registry.Start(start);
    if (!r.ok()) {
      std::fprintf(stderr, "swing %d: %s\n", swing, std::string(r.status().message()).c_str());
      return false;
    }
  }
  if (last) return true;
  for (const auto& [id, token] : sessions) {
    v1::GetSessionRequest get;
    get.set_session_id(id);
    for (;;) {
      absl::StatusOr<v1::SessionInfo> info = registry.Get(get);
      if (!info.ok()) return false;
      if (info->phase() == v1::SWING_PHASE_FINISHED) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  return true;
}

int Run() {
  const int n = absl::GetFlag(FLAGS_tables);
  const int shots = std::max(1, absl::GetFlag(FLAGS_shots));
  const int m = absl::GetFlag(FLAGS_sessions);
  const int swings = std::max(1, absl::GetFlag(FLAGS_swings));
  const fs::path dir = fs::temp_directory_path() /
                       absl::StrFormat("sportsim-restore-%d", static_cast<int>(getpid()));
  ServerConfig config;
  config.listen = "127.0.0.1:0";
  config.tables.world.max_worlds = n + 1;
  config.tables.world.clock_rate = absl::GetFlag(FLAGS_clock_rate);
  config.sessions.world.max_worlds = m + 1;
  config.sessions.world.clock_rate = absl::GetFlag(FLAGS_clock_rate);
  if (!absl::GetFlag(FLAGS_session_checkpoints)) {
    config.sessions.world.checkpoint_every_runs = 0;
  }
  config.store.data_dir = dir.string();
  config.store.postgres_uri = absl::GetFlag(FLAGS_store);
  config.store.node = "restore-bench";
  std::vector<std::pair<std::string, std::string>> tables, sessions;
  {
    absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start(config);
    if (!app.ok()) {
      std::fprintf(stderr, "%s\n", std::string(app.status().message()).c_str());
      return 1;
    }
    server::TableRegistry& registry = (*app)->tables();
    v1::CreateTableRequest create;
    create.mutable_table()->set_rack("9ball");
    for (int i = 0; i < n; ++i) {
      absl::StatusOr<v1::CreateTableResponse> c = registry.Create(create);
      if (!c.ok()) return 1;
      tables.emplace_back(c->table_id(), c->seats(0).token());
    }
    for (int s = 0; s < shots; ++s) {
      for (int i = 0; i < n; ++i) {
        v1::ShootRequest shoot;
        shoot.set_table_id(tables[i].first);
        shoot.set_token(tables[i].second);
        shoot.mutable_strike()->set_ball_speed_mps(s == 0 ? 8.0 : 1.5 + 0.1 * (i % 7));
        shoot.mutable_strike()->set_phi_deg(s == 0 ? 0.3 * (i % 5)
                                                   : std::fmod(47.0 * s + i % 13, 360.0));
        for (int attempt = 0;; ++attempt) {
          absl::StatusOr<v1::ShootResponse> r = registry.Shoot(shoot);
          if (r.ok()) break;
          const std::string why(r.status().message());
          if (r.status().code() != absl::StatusCode::kFailedPrecondition || attempt == 3000) {
            std::fprintf(stderr, "shoot: %s\n", why.c_str());
            return 1;
          }
          if (absl::StrContains(why, "is pocketed")) {
            // The cue ball fell: back on the head string, the first free place along it.
            for (int k = 0; k < 9; ++k) {
              v1::PlaceBallRequest place;
              place.set_table_id(tables[i].first);
              place.set_token(tables[i].second);
              place.mutable_ball()->set_id("cue");
              place.mutable_ball()->set_x_m(-0.635);
              place.mutable_ball()->set_y_m(0.1 * (k - 4));
              if (registry.Place(place).ok()) break;
            }
            continue;
          }
          std::this_thread::sleep_for(std::chrono::milliseconds(20));  // still moving
        }
      }
    }
    server::SessionRegistry& swing_registry = (*app)->sessions();
    for (int i = 0; i < m; ++i) {
      absl::StatusOr<v1::CreateSessionResponse> c =
          swing_registry.Create(v1::CreateSessionRequest());
      if (!c.ok()) return 1;
      sessions.emplace_back(c->session_id(), c->token());
    }
    for (int s = 0; m > 0 && s < swings; ++s) {
      if (!SwingAll(swing_registry, sessions, s, s == swings - 1)) return 1;
    }
    // Every table is mid-shot now, every session mid-swing: the last was just started.
    (*app)->Shutdown(absl::ZeroDuration());
  }
  const int64_t bytes = config.store.postgres_uri.empty() ? DirBytes(dir) : 0;
  config.tables.world.clock_rate = 1.0;
  config.sessions.world.clock_rate = 1.0;
  const auto restart = std::chrono::steady_clock::now();
  absl::StatusOr<std::unique_ptr<ServerApp>> again = ServerApp::Start(config);
  const double restart_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - restart).count();
  if (!again.ok()) {
    std::fprintf(stderr, "%s\n", std::string(again.status().message()).c_str());
    return 1;
  }
  const server::RestoreReport r = (*again)->restored();
  int moving = 0;
  for (const auto& [id, token] : tables) {
    v1::GetTableRequest get;
    get.set_table_id(id);
    absl::StatusOr<v1::TableInfo> info = (*again)->tables().Get(get);
    if (info.ok() && !info->at_rest()) ++moving;
  }
  int swinging = 0;
  for (const auto& [id, token] : sessions) {
    v1::GetSessionRequest get;
    get.set_session_id(id);
    absl::StatusOr<v1::SessionInfo> info = (*again)->sessions().Get(get);
    if (info.ok() && info->phase() == v1::SWING_PHASE_SWINGING) ++swinging;
  }
  if (n > 0) {
    std::printf("tables %d, shots per table %d, store %s\n", n, shots,
                (*again)->journal()->Describe().c_str());
    std::printf("restored %d tables (%d failed) in %.3f s wall; %d still mid-shot after it\n",
                r.tables, r.failed, r.seconds, moving);
  }
  if (m > 0) {
    const std::string every =
        absl::GetFlag(FLAGS_session_checkpoints)
            ? absl::StrFormat("every %d swings", config.sessions.world.checkpoint_every_runs)
            : "off";
    std::printf("sessions %d, swings per session %d, checkpoints %s, store %s\n", m, swings,
                every.c_str(), (*again)->journal()->Describe().c_str());
    std::printf("restored %d sessions (%d failed) in %.2f ms wall%s; %d still mid-swing after it\n",
                r.sessions, r.failed, r.seconds * 1e3, n > 0 ? " (tables included)" : "",
                swinging);
  }
  std::printf("restart %.2f ms wall (the store's load included)\n", restart_s * 1e3);
  if (bytes > 0 && m == 0) {
    std::printf("journal %.1f kB on disk: %.0f bytes per shot (SQLite file sizes, WAL included)\n",
                bytes / 1e3, static_cast<double>(bytes) / (static_cast<double>(n) * shots));
  } else if (bytes > 0 && n == 0) {
    std::printf(
        "journal %.1f kB on disk: %.0f bytes per swing (SQLite file sizes, WAL included)\n",
        bytes / 1e3, static_cast<double>(bytes) / (static_cast<double>(m) * swings));
  }
  again->reset();
  std::error_code ignored;
  fs::remove_all(dir, ignored);
  return 0;
}

}  // namespace
}  // namespace sportsim

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage("Restore time and journal bytes per shot (docs/operations.md)");
  absl::ParseCommandLine(argc, argv);
  return sportsim::Run();
}
