// Live golf-swing sessions: a golfer and club that swing on the server's clock, ticking on the
// same scheduler as the billiards tables and fanning out through the same watchers. No gRPC
// here: streams write through a StreamSink (services.cc, or a fake in tests).
// docs/swing-sessions.md describes the design.
//
// Time. Tick k of a session is due at origin + k / tick_hz. A swing started at tick s is
// integrated in its own time from 0, and tick k advances it to (k - s) / tick_hz. A scheduled
// swing (StartSwing) steps exactly as SimulateSwing does (the same Step calls, the same impact
// search), so its states and impact are bit-identical to SimulateSwing's whatever the load; a
// tick reports the state at its time, interpolated when a step overshoots it. A driven swing
// (DriveSwing) never steps past the last tick (a command may still come for the next one); with
// a fixed step that divides the tick period it too is bit-identical to SimulateSwing with the
// same torques as a schedule.
//
// Locks: Registry::mu_ -> Session::mu -> Watcher::mu_ -> TickScheduler::mu_.
#ifndef SPORTSIM_SERVER_SESSIONS_H_
#define SPORTSIM_SERVER_SESSIONS_H_

#include <array>
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
#include "server/world/scheduler.h"
#include "server/world/watcher.h"
#include "sim/swing/swing_simulation.h"
#include "sportsim/v1/swing.pb.h"

namespace sportsim::server {

struct SessionLimits {
  int max_sessions = 2000;
  int max_watchers_per_session = 64;
  int event_log = 256;            ///< events a session holds for resuming watchers
  int watcher_backlog = 1024;     ///< events a watcher may have unsent before it is resynced
  int max_catchup_ticks = 12;     ///< a session further behind slips instead of racing
  int max_pending_commands = 1024;  ///< a driver's queued (future) torque commands
  absl::Duration heartbeat = absl::Seconds(1);
};

struct SessionStats {
  int64_t ticks = 0;
  int64_t late_ticks = 0;
  int64_t slipped_ticks = 0;
  int64_t snapshots_sent = 0;
  int64_t snapshots_replaced = 0;
  int64_t resyncs = 0;
  int64_t events = 0;
  int64_t commands = 0;          ///< torque commands applied
  int64_t commands_refused = 0;  ///< late, non-finite, out of range or out of order
  std::array<int64_t, 17> refused_by_code{};  ///< the same, by google.rpc code
  int sessions = 0;
  int swinging = 0;
  int watchers = 0;
};

/// A session's state at one tick, shared by every watcher that sends it.
struct SwingFrame {
  uint64_t sequence = 0;
  int64_t tick = 0;
  bool heartbeat = false;
  SteadyClock::time_point published;
  v1::SwingPhase phase = v1::SWING_PHASE_ADDRESS;
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

struct Session;

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

class SessionRegistry {
 public:
  /// Ticks run on `scheduler` (its owner stops it before destroying the registry), or on a
  /// scheduler of the registry's own with `workers` threads.
  SessionRegistry(SessionLimits limits, TickScheduler* scheduler, int workers = 0);
  ~SessionRegistry();
  SessionRegistry(const SessionRegistry&) = delete;
  SessionRegistry& operator=(const SessionRegistry&) = delete;

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
  const LatencyHistogram& publish_to_write() const { return counters_->publish_to_write; }

 private:
  friend struct Session;
  absl::StatusOr<std::shared_ptr<Session>> Find(const std::string& id);
  void Schedule(Session& s, SteadyClock::time_point when);
  void EndSwing(Session& s, const std::string& reason,
                std::vector<std::shared_ptr<const v1::SwingEvent>>* fresh,
                std::shared_ptr<SwingWatcher>* driver);
  void Process(const std::shared_ptr<Session>& session, uint64_t generation,
               SteadyClock::time_point now);

  const SessionLimits limits_;
  const std::shared_ptr<WatchCounters> counters_;
  mutable absl::Mutex mu_;
  std::map<std::string, std::shared_ptr<Session>, std::less<>> sessions_ ABSL_GUARDED_BY(mu_);
  bool shut_down_ ABSL_GUARDED_BY(mu_) = false;
  std::unique_ptr<TickScheduler> own_scheduler_;
  TickScheduler* scheduler_;
  std::atomic<int64_t> ticks_{0}, late_ticks_{0}, slipped_ticks_{0}, events_{0}, commands_{0},
      refused_{0};
  std::atomic<int> swinging_{0};
  std::array<std::atomic<int64_t>, 17> refused_by_code_{};
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_SESSIONS_H_
