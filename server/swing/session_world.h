// Live golf-swing sessions: the session kind of world (a golfer and club that swing on the
// server's clock through a sim LiveSwing) and the session calls, over the shared WorldHost that
// ticks the billiards tables too. No gRPC here: streams write through a StreamSink (rpc/, or a
// fake in tests). docs/swing-sessions.md describes the design, docs/architecture.md the tick.
//
// Time. Tick k of a session is due at origin + k / tick_hz. A swing started at tick s is
// integrated in its own time from 0, and tick k advances it to swing tick k - s, at
// (k - s) / tick_hz (sim/swing/live_swing.h has what that guarantees: bit-identity with
// SimulateSwing).
//
// Locks: as world_host.h: the host's map -> Session::mu -> Watcher::mu_ -> TickScheduler::mu_.
#ifndef SPORTSIM_SERVER_SWING_SESSION_WORLD_H_
#define SPORTSIM_SERVER_SWING_SESSION_WORLD_H_

#include <algorithm>
#include <array>
#include <optional>
#include <string_view>
#include <atomic>
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
#include "server/world/journal.h"
#include "server/world/scheduler.h"
#include "server/swing/convert.h"
#include "server/world/watcher.h"
#include "server/world/world_host.h"
#include "sim/swing/live_swing.h"
#include "sim/swing/swing_simulation.h"
#include "sportsim/v1/swing.pb.h"

namespace sportsim::server {

struct SessionLimits {
  /// max_worlds: --max_sessions. A checkpoint is ~330 bytes at any age, one more store write,
  /// and a swing replays in ~30 us: one every 8 swings bounds a restore to 8 swings (~0.25 ms)
  /// for ~40 bytes more written per swing.
  WorldLimits world{.event_log = 256, .checkpoint_every_runs = 8};
  int max_pending_commands = 1024;  ///< a driver's queued (future) torque commands
};

/// Counters of the driven swings' commands, shared by a registry's sessions.
struct CommandCounters {
  std::atomic<int64_t> applied{0};
  std::atomic<int64_t> refused{0};
  std::array<std::atomic<int64_t>, 17> refused_by_code{};  ///< by google.rpc code
  void Refused(absl::StatusCode code) {
    refused.fetch_add(1);
    refused_by_code[static_cast<size_t>(std::clamp(static_cast<int>(code), 0, 16))].fetch_add(1);
  }
};

struct SessionStats : WorldStats {
  int64_t commands = 0;          ///< torque commands applied
  int64_t commands_refused = 0;  ///< late, non-finite, out of range or out of order
  std::array<int64_t, 17> refused_by_code{};  ///< the same, by google.rpc code
};

/// What a session is doing (the API's SwingPhase).
enum class SessionPhase : uint8_t { kAddress, kSwinging, kFinished };

/// A session's state at one tick, shared by every watcher that sends it.
struct SwingFrame {
  uint64_t sequence = 0;
  int64_t tick = 0;
  bool heartbeat = false;
  SteadyClock::time_point published;
  SessionPhase phase = SessionPhase::kAddress;
  uint64_t swing_id = 0;
  swing::SwingSample state;
  double qalpha_nm = 0, qbeta_nm = 0;
};

struct SwingWatchOptions {};

/// The swing-session kind of BasicWatcher (watcher.h).
struct SwingWatch {
  using Frame = SwingFrame;
  using Event = v1::SwingEvent;
  using Snapshot = v1::SwingSnapshot;
  using Options = SwingWatchOptions;
  static void Fill(const SwingWatchOptions& options, const std::string& session_id,
                   const SwingFrame& frame, const SwingFrame* last_sent, bool full,
                   v1::SwingSnapshot* out);
};

using SwingWatcher = BasicWatcher<SwingWatch>;
using SwingSink = StreamSink<v1::SwingSnapshot>;

struct SessionKind;
using Session = World<SessionKind>;
using SessionHost = WorldHost<SessionKind>;

/// The swing-session kind of world (world_host.h).
struct SessionKind {
  using Watch = SwingWatch;
  static constexpr std::string_view kNoun = "session";
  static constexpr std::string_view kIdPrefix = "s-";
  static constexpr std::string_view kIdField = "session_id";
  static constexpr std::string_view kCreateRpc = "CreateSession";
  static constexpr std::string_view kMaxWorldsFlag = "--max_sessions";
  static constexpr std::string_view kMaxWatchersFlag = "--max_watchers_per_session";

  /// A session's own members (guarded by its mu unless fixed at creation).
  struct Data {
    // Fixed at creation.
    google::protobuf::RepeatedField<int> disabled_effects;
    swing::SwingSolverOptions solver;
    bool realistic = true;
    std::optional<StrikeJob> strike;  ///< CreateSession's `ball`: launched at each impact
    CommandCounters* counters = nullptr;
    // Guarded by mu.
    v1::SwingParameters params;  ///< as asked (echoed by GetSession; Reset may change it)
    std::shared_ptr<const swing::SwingModel> model;  ///< at the address position
    SessionPhase phase = SessionPhase::kAddress;
    uint64_t swings = 0;  ///< also the id of the current or last swing
    std::unique_ptr<swing::LiveSwing> live;  ///< the swing in progress
    int64_t start_tick = 0;                  ///< the session tick at the swing's time 0
    uint32_t seat = 0;                       ///< who started it
    std::shared_ptr<SwingWatcher> driver;    ///< driven: the driver's stream, while it lasts
    swing::SwingSample state;                ///< at the last tick advanced
    double qalpha = 0, qbeta = 0;            ///< in force at `state`
    std::optional<swing::SwingSample> last_impact;
    std::string last_end_reason;
  };
  /// One wake's swing events, and the ball launched at an impact (computed off the lock).
  struct TickOut {
    std::vector<swing::LiveSwingEvent> events;
    std::vector<v1::BallLaunch> launches;  ///< one per kImpact event, when the session has a ball
  };
  using End = swing::LiveSwingEnd;

  static bool Running(const Session& s);
  static std::optional<End> AdvanceTick(SessionHost& host, Session& s, int64_t k, TickOut* out);
  static OffLockWork OffLock(Session& s, TickOut* out);
  static void Publish(SessionHost& host, Session& s, TickOut* out,
                      std::vector<std::shared_ptr<const v1::SwingEvent>>* fresh);
  static void EndRun(SessionHost& host, Session& s, const End& end,
                     std::vector<std::shared_ptr<const v1::SwingEvent>>* fresh,
                     Session::Pump* pump);
  static std::shared_ptr<const SwingFrame> MakeFrame(const Session& s, int64_t k, bool heartbeat,
                                                     SteadyClock::time_point published);
  /// Nothing falls due while a session is at rest.
  static std::optional<int64_t> RestDeadline(const Session&) { return std::nullopt; }
  static void AtRestDeadline(SessionHost&, Session&,
                             std::vector<std::shared_ptr<const v1::SwingEvent>>*) {}
  /// Swings started so far.
  static uint64_t Runs(const Session& s);
  /// The session at rest as a journal checkpoint (session_checkpoint.h).
  static std::string Checkpoint(const Session& s);
};

/// One DriveSwing stream's hold on its session.
struct Drive {
  std::shared_ptr<Session> session;
  std::shared_ptr<SwingWatcher> watcher;  ///< the driver's own stream
  uint64_t swing_id = 0;
  int seat = 0;
  bool apply_late = false;
  uint64_t commands = 0;      ///< received so far (the next one is commands + 1)
  double last_t_s = 0.0;      ///< the time of the last accepted command
  bool ended = false;
};

/// A session's commands in the journal (JournalEntry::type; the creation is 0). Stored: never
/// renumber.
enum class SessionCommand : uint32_t {
  kCreate = 0,
  kStart = 1,
  kReset = 2,
  kDriveStart = 3,
  kDriveCommand = 4,
  kDriveEnd = 5,
  kDelete = 6,
};

/// Every swing session of the server: the session calls over a WorldHost<SessionKind>.
class SessionRegistry {
 public:
  /// Ticks run on `scheduler` (its owner stops it before destroying the registry), or on a
  /// scheduler of the registry's own with `workers` threads.
  SessionRegistry(SessionLimits limits, TickScheduler* scheduler, int workers = 0);
  ~SessionRegistry();
  SessionRegistry(const SessionRegistry&) = delete;
  SessionRegistry& operator=(const SessionRegistry&) = delete;

  /// Every accepted command goes to `journal` before it takes effect (null: none). Set before
  /// the first call.
  void SetJournal(Journal* journal) { host_.SetJournal(journal); }
  /// Recreates a session from the journal under its own id, from its latest checkpoint if it has
  /// one (session_checkpoint.h; DATA_LOSS naming the field when it is damaged); a swing in
  /// flight goes on (a driven one with the commands it accepted, its driver's stream gone).
  absl::Status Restore(const StoredWorld& stored);

  absl::StatusOr<v1::CreateSessionResponse> Create(const v1::CreateSessionRequest& request);
  absl::StatusOr<v1::SessionInfo> Get(const v1::GetSessionRequest& request);
  absl::StatusOr<v1::ListSessionsResponse> List(const v1::ListSessionsRequest& request);
  absl::Status Delete(const v1::DeleteSessionRequest& request);
  absl::StatusOr<v1::StartSwingResponse> Start(const v1::StartSwingRequest& request);
  absl::StatusOr<v1::ResetSwingResponse> Reset(const v1::ResetSwingRequest& request);

  /// Spectators: registers a watcher writing to `sink` and queues its first snapshot; the
  /// caller then Pump()s it. With a null sink, the caller Attach()es one before pumping.
  /// Errors change nothing.
  absl::StatusOr<std::shared_ptr<SwingWatcher>> Watch(const v1::WatchSwingRequest& request,
                                                      SwingSink* sink);
  /// Forgets a watcher whose stream is done.
  void Unwatch(const std::string& session_id, const SwingWatcher* watcher);

  /// DriveSwing's first message: starts a driven swing at the next tick and registers the
  /// driver's stream (the caller Pump()s drive->watcher). Errors change nothing.
  absl::StatusOr<std::shared_ptr<Drive>> StartDrive(const v1::DriveStart& start, SwingSink* sink);
  /// A torque command from the driver: queued for its tick, or refused with a COMMAND_REFUSED
  /// event on the driver's stream (never an error: the stream goes on).
  void Command(Drive& drive, const v1::TorqueCommand& command);
  /// Reports a refused command (or a message that is not a torque command, with `command`
  /// null) on the driver's stream as COMMAND_REFUSED. Nothing else changes.
  void Refuse(Drive& drive, const absl::Status& why, const v1::TorqueCommand* command = nullptr);
  /// The driver half-closed (`half_closed`: the stream ends OK after a last snapshot) or went
  /// away. The swing goes on with the torques in force. Idempotent.
  void EndDrive(Drive& drive, bool half_closed);

  /// Ends every stream with `status` after a last snapshot and stops ticking. Idempotent.
  void Shutdown(const absl::Status& status);

  SessionStats stats() const;
  const LatencyHistogram& publish_to_write() const { return host_.publish_to_write(); }

 private:
  /// A session as `request` makes it (checked), into `made`: everything but its id. Seats are
  /// made unless `made` has them (a restore), their tokens going to `tokens`.
  absl::StatusOr<v1::CreateSessionResponse> MakeSession(const v1::CreateSessionRequest& request,
                                                        Session& made,
                                                        std::vector<std::string>* tokens);
  // The calls on a session under its lock, as `seat`: what a call does, and what a restore
  // replays. `checked`: the model StartSwing's dry run used (null: no dry run, a replay).
  absl::StatusOr<v1::StartSwingResponse> StartOn(Session& s, int seat,
                                                 const v1::StartSwingRequest& request,
                                                 const swing::SwingModel* checked,
                                                 Session::Pump& pump);
  absl::StatusOr<v1::ResetSwingResponse> ResetOn(Session& s, int seat,
                                                 const v1::ResetSwingRequest& request,
                                                 Session::Pump& pump);
  absl::Status DriveStartOn(Session& s, int seat, const v1::DriveStart& start, Drive& drive,
                            Session::Pump& pump);
  /// OK when queued; else why it was refused (nothing changed).
  absl::Status CommandOn(Session& s, Drive& drive, const v1::TorqueCommand& c);
  void DriveEndOn(Session& s, bool half_closed);

  const SessionLimits limits_;
  CommandCounters counters_;
  SessionHost host_;
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_SWING_SESSION_WORLD_H_
