// Authoritative billiards tables: the table kind of world (what a table holds, how a tick
// advances its shot, how a shot ends) and the table calls, over the shared WorldHost. No gRPC
// here: a watcher writes through a SnapshotSink (the gRPC reactor in rpc/, a fake in tests).
// docs/server.md describes the design, docs/architecture.md the tick's stages.
//
// Time. Tick k of a table is due at origin + k / tick_hz on the monotonic clock. A shot struck
// at tick s is simulated in its own time from 0, and tick k advances it to (k - s) / tick_hz
// (for the stepped engine, to a whole number of steps), so a shot's states never depend on the
// load or on when the worker got to the table: the same strike gives the same bits as
// SimulateShot. A table at rest is not scheduled; its tick is read off the clock when asked.
//
// Locks: as world_host.h: the host's map -> Table::mu -> Watcher::mu_ -> TickScheduler::mu_.
#ifndef SPORTSIM_SERVER_BILLIARDS_TABLE_WORLD_H_
#define SPORTSIM_SERVER_BILLIARDS_TABLE_WORLD_H_

#include <optional>
#include <string_view>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "server/billiards/preview.h"
#include "server/world/journal.h"
#include "server/world/scheduler.h"
#include "server/world/watcher.h"
#include "server/world/world_host.h"
#include "sim/billiards/cue.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/referee.h"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"
#include "sim/games/game.h"
#include "sportsim/v1/billiards.pb.h"

namespace sportsim::server {

struct TableLimits {
  /// Limits every kind of world has (max_worlds: --max_tables). A checkpoint every few shots
  /// bounds what a restore replays (at most this many shots, each ~0.1 ms) while keeping what
  /// is written per shot small: a checkpoint holds the match record, ~200 bytes a shot, so
  /// writing one every shot would cost O(shots^2) bytes over a match.
  WorldLimits world{.checkpoint_every_runs = 4};
  double max_shot_s = 600.0;  ///< simulated time after which a shot is stopped
};

/// A shot as the table keeps it: who struck what, what the referee's facts were, how it ended.
struct ShotSummary {
  uint64_t shot_id = 0;
  uint32_t seat = 0;
  std::string struck_ball;
  std::string first_ball_hit;         ///< "" if none
  uint32_t rails = 0;                 ///< every ball-cushion hit
  uint32_t rails_after_contact = 0;   ///< ... after the struck ball's first contact
  std::vector<std::string> pocketed;  ///< in order
  bool struck_ball_pocketed = false;
  int64_t start_tick = 0;
  int64_t end_tick = 0;
  double duration_s = 0.0;            ///< simulated
  int64_t events = 0;                 ///< events the engine handled
  std::string error;                  ///< set when the engine stopped the shot
  games::ShotCall call;               ///< ruled games: what the shooter declared
  std::optional<games::Verdict> verdict;  ///< ruled games: the referee's word
};

/// One entry of a ruled table's match record: what was asked, at which tick, and what the
/// referee made of it.
struct MatchEntry {
  enum class Kind : uint8_t { kShoot, kPlace, kDecide, kConcede, kShotClock, kReset };
  Kind kind = Kind::kShoot;
  int64_t tick = 0;
  int seat = 0;
  std::string strike;          ///< kShoot: the CueStrike as asked (serialized)
  games::ShotCall call;        ///< kShoot
  uint64_t shot_id = 0;        ///< kShoot
  uint64_t seed = 0;           ///< kShoot: the noise seed applied
  billiards::StrikeOutcome applied;  ///< kShoot: the strike after noise
  std::string ball;            ///< kPlace
  double x_m = 0.0, y_m = 0.0; ///< kPlace
  std::string choice;          ///< kDecide
  std::optional<games::Verdict> verdict;  ///< kShoot (at its end), kShotClock, kConcede
};

/// The state of a table at one tick, shared by every watcher that sends it.
struct Frame {
  uint64_t sequence = 0;
  int64_t tick = 0;
  double t_s = 0.0;
  bool at_rest = true;
  bool heartbeat = false;
  uint32_t turn = 0;
  uint64_t shot_id = 0;
  std::shared_ptr<const billiards::TableModel> model;
  std::vector<billiards::Ball> balls;
  std::shared_ptr<const v1::GameState> game;  ///< ruled games
  SteadyClock::time_point published;  ///< when the tick was due, or when a call made it
                                      ///< (the start of publish-to-write latency)
};

/// What a table's reader asked for.
struct WatchOptions {
  bool position = true, velocity = true, spin = true, orientation = true;
  bool changed_only = false;
};

/// The table kind of BasicWatcher (watcher.h).
struct TableWatch {
  using Frame = server::Frame;
  using Event = v1::TableEvent;
  using Snapshot = v1::TableSnapshot;
  using Options = WatchOptions;
  static void Fill(const WatchOptions& options, const std::string& table_id, const Frame& frame,
                   const Frame* last_sent, bool full, v1::TableSnapshot* out);
};

using Watcher = BasicWatcher<TableWatch>;
using SnapshotSink = StreamSink<v1::TableSnapshot>;
using EventPtr = Watcher::EventPtr;

struct TableKind;
using Table = World<TableKind>;
using TableHost = WorldHost<TableKind>;

/// The billiards table kind of world (world_host.h).
struct TableKind {
  using Watch = TableWatch;
  static constexpr std::string_view kNoun = "table";
  static constexpr std::string_view kIdPrefix = "t-";
  static constexpr std::string_view kIdField = "table_id";
  static constexpr std::string_view kCreateRpc = "CreateTable";
  static constexpr std::string_view kMaxWorldsFlag = "--max_tables";
  static constexpr std::string_view kMaxWatchersFlag = "--max_watchers_per_table";

  /// A table's own members (guarded by its mu unless fixed at creation).
  struct Data {
    // Fixed at creation.
    std::string preset;
    std::string rack;
    std::shared_ptr<const billiards::TableModel> model;
    billiards::TableState initial;
    billiards::SolverOptions solver;
    int64_t steps_per_tick = 0;  ///< stepped engine: dt_s * steps_per_tick = period
    double max_shot_s = 600.0;
    games::Rules rules;                           ///< game kFree: free play, no referee
    const games::Referee* game_referee = nullptr;
    games::Start start = games::Start::kBreak;
    double noise = 0.0;                           ///< ruled games: on every strike
    uint64_t seed = 0;                            ///< the noise's; secret until the match ends
    std::string create_request;                   ///< CreateTableRequest as asked (serialized)
    bool aim_lines = true;                        ///< PreviewShot allowed
    // Guarded by mu.
    uint32_t turn = 0;
    billiards::TableState rest;                            ///< the balls when no shot moves
    std::unique_ptr<billiards::TableSimulation> sim;       ///< the shot in progress
    std::unique_ptr<billiards::ShotReferee> referee;
    billiards::TableState shot_start;                      ///< ids for the shot's events
    ShotSummary current;                                   ///< the shot in progress
    ShotSummary last_shot;
    uint64_t shots = 0;
    games::GameState game;                                 ///< ruled games
    std::shared_ptr<const v1::GameState> game_view;        ///< its API view, made on change
    bool placed = false;                      ///< the cue ball was placed since the last shot
    std::vector<billiards::Event> shot_events;  ///< ruled games: the shot's, for the referee
    std::optional<int64_t> clock_deadline;    ///< the shot clock runs out at this tick
    std::vector<MatchEntry> record;           ///< ruled games: the match so far
  };
  /// One wake's engine events.
  struct TickOut {
    std::vector<billiards::Event> events;
  };
  /// How a shot ended: at rest (no error), stopped (error), or voided (the balls go back).
  struct End {
    std::string error;
    bool voided = false;
  };

  static bool Running(const Table& t);
  static std::optional<End> AdvanceTick(TableHost& host, Table& t, int64_t k, TickOut* out);
  static OffLockWork OffLock(Table&, TickOut*) { return nullptr; }
  static void Publish(TableHost& host, Table& t, TickOut* out,
                      std::vector<std::shared_ptr<const v1::TableEvent>>* fresh);
  static void EndRun(TableHost& host, Table& t, const End& end,
                     std::vector<std::shared_ptr<const v1::TableEvent>>* fresh,
                     Table::Pump* pump);
  static std::shared_ptr<const Frame> MakeFrame(const Table& t, int64_t k, bool heartbeat,
                                                SteadyClock::time_point published);
  /// Ruled games at rest: the shot clock's tick, when it runs.
  static std::optional<int64_t> RestDeadline(const Table& t);
  /// The shot clock ran out: the game's penalty.
  static void AtRestDeadline(TableHost& host, Table& t,
                             std::vector<std::shared_ptr<const v1::TableEvent>>* fresh);
  /// Shots struck so far.
  static uint64_t Runs(const Table& t);
  /// The table at rest as a journal checkpoint (table_checkpoint.h).
  static std::string Checkpoint(const Table& t);
};

/// A table's commands in the journal (JournalEntry::type; the creation is 0). Stored: never
/// renumber.
enum class TableCommand : uint32_t {
  kCreate = 0,
  kReset = 1,
  kPlace = 2,
  kShoot = 3,
  kSetTurn = 4,
  kDecide = 5,
  kConcede = 6,
  kDelete = 7,
};

/// Every table of the server: the table-specific calls over a WorldHost<TableKind>.
class TableRegistry {
 public:
  explicit TableRegistry(TableLimits limits, TickScheduler* scheduler = nullptr);
  ~TableRegistry();
  TableRegistry(const TableRegistry&) = delete;
  TableRegistry& operator=(const TableRegistry&) = delete;

  /// Every accepted command goes to `journal` before it takes effect (null: none). Set before
  /// the first call.
  void SetJournal(Journal* journal) { host_.SetJournal(journal); }
  /// Recreates a table from the journal (a restart, a takeover) under its own id, its clock
  /// resuming at the tick it had reached.
  absl::Status Restore(const StoredWorld& stored);

  absl::StatusOr<v1::CreateTableResponse> Create(const v1::CreateTableRequest& request);
  absl::StatusOr<v1::TableInfo> Get(const v1::GetTableRequest& request);
  absl::StatusOr<v1::ListTablesResponse> List(const v1::ListTablesRequest& request);
  absl::Status Delete(const v1::DeleteTableRequest& request);
  absl::StatusOr<v1::ResetTableResponse> Reset(const v1::ResetTableRequest& request);
  absl::StatusOr<v1::PlaceBallResponse> Place(const v1::PlaceBallRequest& request);
  absl::StatusOr<v1::ShootResponse> Shoot(const v1::ShootRequest& request);
  absl::StatusOr<v1::SetTurnResponse> SetTurn(const v1::SetTurnRequest& request);
  absl::StatusOr<v1::DecideResponse> Decide(const v1::DecideRequest& request);
  absl::StatusOr<v1::ConcedeResponse> Concede(const v1::ConcedeRequest& request);
  absl::StatusOr<v1::MatchRecord> GetMatchRecord(const v1::GetMatchRecordRequest& request);
  /// PreviewShot's checks and a copy of the table's balls for RunPreview (preview.h): the seat
  /// to play, every ball at rest, aim lines allowed. Changes nothing.
  absl::StatusOr<PreviewJob> PreparePreview(const v1::PreviewShotRequest& request);

  /// Registers a watcher writing to `sink` and queues its first snapshot; the caller then calls
  /// Pump() on it. With a null sink, the caller Attach()es one before pumping (nothing is
  /// written until then). Errors change nothing.
  absl::StatusOr<std::shared_ptr<Watcher>> Watch(const v1::WatchTableRequest& request,
                                                 SnapshotSink* sink);
  /// Forgets a watcher whose stream is done.
  void Unwatch(const std::string& table_id, const Watcher* watcher);

  /// Ends every stream with `status` after a last snapshot and stops ticking (stops its own
  /// scheduler, if it has one). Afterwards every call fails with UNAVAILABLE. Idempotent.
  void Shutdown(const absl::Status& status);

  WorldStats stats() const { return host_.stats(); }
  const LatencyHistogram& publish_to_write() const { return host_.publish_to_write(); }

 private:
  /// A table as `request` makes it (checked), into `made`: everything but its id and admin
  /// token. `seed`: the restored secret seed (none: the request's or a fresh one). Seats are
  /// made unless `made` has them (a restore), their tokens going to `tokens`.
  absl::StatusOr<v1::CreateTableResponse> MakeTable(const v1::CreateTableRequest& request,
                                                    std::optional<uint64_t> seed, Table& made,
                                                    std::vector<std::string>* tokens);
  // The calls on a table under its lock, authorized as `seat`: what a call does, and what a
  // restore replays.
  absl::StatusOr<v1::ResetTableResponse> ResetOn(Table& t, int seat,
                                                 const v1::ResetTableRequest& request,
                                                 Table::Pump& pump);
  absl::StatusOr<v1::PlaceBallResponse> PlaceOn(Table& t, int seat,
                                                const v1::PlaceBallRequest& request,
                                                Table::Pump& pump);
  absl::StatusOr<v1::ShootResponse> ShootOn(Table& t, int seat, const v1::ShootRequest& request,
                                            Table::Pump& pump);
  absl::StatusOr<v1::SetTurnResponse> SetTurnOn(Table& t, int seat,
                                                const v1::SetTurnRequest& request,
                                                Table::Pump& pump);
  absl::StatusOr<v1::DecideResponse> DecideOn(Table& t, int seat,
                                              const v1::DecideRequest& request,
                                              Table::Pump& pump);
  absl::StatusOr<v1::ConcedeResponse> ConcedeOn(Table& t, int seat,
                                                const v1::ConcedeRequest& request,
                                                Table::Pump& pump);
  /// Applies a journal entry (restore).
  absl::Status Replay(Table& t, const JournalEntry& e, Table::Pump& pump);
  template <typename Req, typename Resp>
  absl::Status ReplayAs(absl::StatusOr<Resp> (TableRegistry::*on)(Table&, int, const Req&,
                                                                  Table::Pump&),
                        Table& t, const JournalEntry& e, Table::Pump& pump);

  const TableLimits limits_;
  TableHost host_;
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_BILLIARDS_TABLE_WORLD_H_
