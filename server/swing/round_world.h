// Rounds of golf: the round kind of world (players taking strokes on a course, refereed by
// sim/golf/round.h) and the round calls, over the WorldHost that ticks tables and sessions.
// No gRPC here. docs/golf-rounds.md describes the design.
//
// A stroke's outcome is known when it is played (the shot is simulated once, off the world's
// lock, exactly as PlayCourseShot plays it offline, then judged); the ball then travels along
// its path on the round's clock, its events published at their ticks, and the referee's ruling
// (rest, penalty, decision, the hole's end) at the tick it comes to rest. With fast_forward the
// ball comes to rest at the next tick.
//
// Locks: as world_host.h: the host's map -> Round::mu -> Watcher::mu_ -> TickScheduler::mu_.
#ifndef SPORTSIM_SERVER_SWING_ROUND_WORLD_H_
#define SPORTSIM_SERVER_SWING_ROUND_WORLD_H_

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "server/world/journal.h"
#include "server/world/scheduler.h"
#include "server/world/watcher.h"
#include "server/world/world_host.h"
#include "sim/golf/course.h"
#include "sim/golf/course_shot.h"
#include "sim/golf/round.h"
#include "sportsim/v1/swing.pb.h"

namespace sportsim::server {

struct RoundLimits {
  /// max_worlds: --max_rounds. No checkpoints: a round replays from its creation (a stroke
  /// replays in about a millisecond; a whole 18-hole round of four in well under a second).
  WorldLimits world{.event_log = 512};
};

/// A round at one tick, shared by every watcher that sends it.
struct RoundFrame {
  uint64_t sequence = 0;
  int64_t tick = 0;
  bool heartbeat = false;
  SteadyClock::time_point published;
  std::shared_ptr<const v1::RoundState> round;  ///< built once per change
  std::optional<v1::RoundMovingBall> ball;      ///< while a stroke is in play
};

struct RoundWatchOptions {};

/// The round kind of BasicWatcher (watcher.h).
struct RoundWatch {
  using Frame = RoundFrame;
  using Event = v1::RoundEvent;
  using Snapshot = v1::RoundSnapshot;
  using Options = RoundWatchOptions;
  static void Fill(const RoundWatchOptions& options, const std::string& round_id,
                   const RoundFrame& frame, const RoundFrame* last_sent, bool full,
                   v1::RoundSnapshot* out);
};

using RoundWatcher = BasicWatcher<RoundWatch>;
using RoundSink = StreamSink<v1::RoundSnapshot>;

struct RoundKind;
using Round = World<RoundKind>;
using RoundHost = WorldHost<RoundKind>;

/// A stroke worked out before it takes effect: its shot, path and ruling.
struct PlayedStroke {
  int seat = 0;
  golf::CourseShotResult shot;
  golf::RoundStep after;
  uint64_t version = 0;  ///< the round's version it was computed on
};

/// The round kind of world (world_host.h).
struct RoundKind {
  using Watch = RoundWatch;
  static constexpr std::string_view kNoun = "round";
  static constexpr std::string_view kIdPrefix = "r-";
  static constexpr std::string_view kIdField = "round_id";
  static constexpr std::string_view kCreateRpc = "CreateRound";
  static constexpr std::string_view kMaxWorldsFlag = "--max_rounds";
  static constexpr std::string_view kMaxWatchersFlag = "--max_watchers_per_round";

  struct Data {
    // Fixed at creation.
    std::shared_ptr<const golf::Course> course;
    golf::RoundSettings settings;
    v1::CreateRoundRequest setup;  ///< as asked, for the record
    bool fast_forward = false;
    double shot_clock_s = 0.0;  ///< 0: none
    // Guarded by mu.
    std::optional<int64_t> clock_deadline;  ///< the shot clock's tick, at rest
    golf::RoundState state;
    uint64_t version = 0;  ///< bumped by every change of `state`
    std::shared_ptr<const v1::RoundState> state_proto;
    std::optional<PlayedStroke> stroke;  ///< in play
    int64_t start_tick = 0, rest_tick = 0;
    size_t next_ball_event = 0;  ///< the stroke's ball events published so far
    std::vector<v1::RoundEvent> ball_events;  ///< the stroke's, in time order
    std::vector<v1::RoundCommand> commands;   ///< the record
  };
  struct TickOut {
    std::vector<v1::RoundEvent> events;
  };
  struct End {};

  static bool Running(const Round& r);
  static std::optional<End> AdvanceTick(RoundHost& host, Round& r, int64_t k, TickOut* out);
  static OffLockWork OffLock(Round&, TickOut*) { return nullptr; }
  static void Publish(RoundHost& host, Round& r, TickOut* out,
                      std::vector<std::shared_ptr<const v1::RoundEvent>>* fresh);
  static void EndRun(RoundHost& host, Round& r, const End& end,
                     std::vector<std::shared_ptr<const v1::RoundEvent>>* fresh, Round::Pump* pump);
  static std::shared_ptr<const RoundFrame> MakeFrame(const Round& r, int64_t k, bool heartbeat,
                                                     SteadyClock::time_point published);
  /// The shot clock's deadline while the round is at rest and not over.
  static std::optional<int64_t> RestDeadline(const Round& r);
  /// The shot clock ran out: a penalty stroke for the seat to play, and it restarts.
  static void AtRestDeadline(RoundHost& host, Round& r,
                             std::vector<std::shared_ptr<const v1::RoundEvent>>* fresh);
  static uint64_t Runs(const Round& r);
  static std::string Checkpoint(const Round&) { return {}; }  // never taken (RoundLimits)
};

/// A round's commands in the journal (JournalEntry::type; the creation is 0). Stored: never
/// renumber.
enum class RoundCommandType : uint32_t { kCreate = 0, kStroke = 1, kDecide = 2, kDelete = 3 };

/// The round's state for the wire.
void RoundStateToProto(const golf::Course& course, const golf::RoundSettings& settings,
                       const golf::RoundState& state, bool stroke_in_play, v1::RoundState* out);

/// The settings a creation asks for, checked (INVALID_ARGUMENT names the field).
absl::StatusOr<golf::RoundSettings> RoundSettingsFromProto(const v1::CreateRoundRequest& request,
                                                           const golf::Course& course);
/// A stroke request's stroke (INVALID_ARGUMENT names the field).
absl::StatusOr<golf::RoundStroke> RoundStrokeFromProto(const v1::PlayStrokeRequest& request);

/// A launch monitor's GSPro Open Connect DeviceID bound to a seat (BindMonitor).
struct MonitorBinding {
  std::string round_id;
  std::string token;  ///< the seat's: the monitor's shots are that seat's strokes
  int seat = 0;
};

/// Every round of the server: the round calls over a WorldHost<RoundKind>.
class RoundRegistry {
 public:
  RoundRegistry(RoundLimits limits, TickScheduler* scheduler, int workers = 0);
  ~RoundRegistry();
  RoundRegistry(const RoundRegistry&) = delete;
  RoundRegistry& operator=(const RoundRegistry&) = delete;

  void SetJournal(Journal* journal) { host_.SetJournal(journal); }
  /// Recreates a round from the journal under its own id by replaying its commands.
  absl::Status Restore(const StoredWorld& stored);

  absl::StatusOr<v1::CreateRoundResponse> Create(const v1::CreateRoundRequest& request);
  absl::StatusOr<v1::RoundInfo> Get(const v1::GetRoundRequest& request);
  absl::StatusOr<v1::ListRoundsResponse> List(const v1::ListRoundsRequest& request);
  /// The admin token only.
  absl::Status Delete(const v1::DeleteRoundRequest& request);
  /// Simulates the stroke off the round's lock (polling `cancelled`), then plays it at the next
  /// tick if the round has not changed meanwhile.
  absl::StatusOr<v1::PlayStrokeResponse> Stroke(const v1::PlayStrokeRequest& request,
                                                const std::function<bool()>& cancelled = {});
  absl::StatusOr<v1::DecideRoundResponse> Decide(const v1::DecideRoundRequest& request);
  absl::StatusOr<v1::RoundRecord> Record(const v1::GetRoundRecordRequest& request);

  /// Binds a DeviceID to the seat of the request's token (kept in memory: a restarted server
  /// needs the binding again). FAILED_PRECONDITION when no listener was set.
  absl::StatusOr<v1::BindMonitorResponse> BindMonitor(const v1::BindMonitorRequest& request);
  /// The seat a DeviceID plays, if bound.
  std::optional<MonitorBinding> Monitor(const std::string& device_id) const;
  /// The Open Connect listener's address ("": none, the default).
  void SetMonitorListen(std::string address);

  absl::StatusOr<std::shared_ptr<RoundWatcher>> Watch(const v1::WatchRoundRequest& request,
                                                      RoundSink* sink);
  void Unwatch(const std::string& round_id, const RoundWatcher* watcher);

  void Shutdown(const absl::Status& status);
  WorldStats stats() const { return host_.stats(); }
  const LatencyHistogram& publish_to_write() const { return host_.publish_to_write(); }

 private:
  absl::StatusOr<v1::CreateRoundResponse> MakeRound(const v1::CreateRoundRequest& request,
                                                    Round& made, std::vector<std::string>* tokens);
  // The calls under the round's lock, as `seat`: what a call does and what a restore replays.
  // `played`: the stroke computed off the lock (null: compute it here, a replay).
  absl::StatusOr<v1::PlayStrokeResponse> StrokeOn(Round& r, int seat,
                                                  const v1::PlayStrokeRequest& request,
                                                  std::optional<PlayedStroke> played,
                                                  Round::Pump& pump);
  absl::StatusOr<v1::DecideRoundResponse> DecideOn(Round& r, int seat,
                                                   const v1::DecideRoundRequest& request,
                                                   Round::Pump& pump);

  const RoundLimits limits_;
  RoundHost host_;
  mutable absl::Mutex monitors_mu_;
  std::map<std::string, MonitorBinding> monitors_ ABSL_GUARDED_BY(monitors_mu_);
  std::string monitor_listen_ ABSL_GUARDED_BY(monitors_mu_);
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_SWING_ROUND_WORLD_H_
