#include "server/rpc/services.h"

#include <google/protobuf/stubs/common.h>
#include <grpcpp/alarm.h>
#include <grpcpp/grpcpp.h>

#include <atomic>
#include <chrono>
#include <map>
#include <optional>

#include "absl/strings/match.h"

#include "server/billiards/batch.h"
#include "server/billiards/calibration.h"
#include "server/billiards/convert.h"
#include "server/billiards/preview.h"
#include "server/billiards/game_convert.h"
#include "server/rpc/status.h"
#include "server/world/work_pool.h"
#include "server/swing/round_world.h"
#include "server/swing/session_world.h"
#include "server/billiards/table_world.h"
#include "sim/billiards/shot.h"
#include "sim/core/cpu_clock.h"
#include "server/swing/convert.h"
#include "server/swing/golf_shot.h"
#include "sim/swing/swing_simulation.h"
#include "sportsim/v1/billiards.grpc.pb.h"
#include "sportsim/v1/common.grpc.pb.h"
#include "sportsim/v1/swing.grpc.pb.h"

#ifndef SPORTSIM_VERSION
#define SPORTSIM_VERSION "unknown"
#endif
#ifndef SPORTSIM_BUILD_TYPE
#define SPORTSIM_BUILD_TYPE "unknown"
#endif
#ifndef SPORTSIM_COMPILER
#define SPORTSIM_COMPILER "unknown"
#endif

namespace sportsim::server {
namespace {

class InfoService final : public v1::Server::CallbackService {
  grpc::ServerUnaryReactor* GetInfo(grpc::CallbackServerContext* ctx, const v1::GetInfoRequest*,
                                    v1::GetInfoResponse* response) override {
    *response = MakeServerInfo();
    auto* reactor = ctx->DefaultReactor();
    reactor->Finish(grpc::Status::OK);
    return reactor;
  }
};

// A call finished at once with `status` (refused before any work).
grpc::ServerUnaryReactor* Finished(grpc::CallbackServerContext* ctx, const absl::Status& status) {
  auto* reactor = ctx->DefaultReactor();
  reactor->Finish(ToGrpcStatus(status));
  return reactor;
}

// Unary calls on the registry: the status, or the response.
template <typename Response, typename Fn>
grpc::ServerUnaryReactor* Unary(grpc::CallbackServerContext* ctx, Response* response, Fn fn) {
  auto* reactor = ctx->DefaultReactor();
  absl::StatusOr<Response> result = fn();
  if (result.ok()) *response = *std::move(result);
  reactor->Finish(ToGrpcStatus(result.status()));
  return reactor;
}

// The call's deadline on the steady clock (none when the client set none).
std::optional<std::chrono::steady_clock::time_point> DeadlineOf(
    const grpc::CallbackServerContext* ctx) {
  const std::chrono::system_clock::time_point d = ctx->deadline();
  if (d >= std::chrono::system_clock::time_point::max() - std::chrono::hours(24 * 365)) {
    return std::nullopt;
  }
  return std::chrono::steady_clock::now() +
         std::chrono::duration_cast<std::chrono::steady_clock::duration>(
             d - std::chrono::system_clock::now());
}

// A unary call computed on the simulation pool: queued (or refused at once when the queue is
// full), run with a WorkControl that the computation polls, and finished from the worker.
// `fn(control)` returns the call's status and fills the response. A computation stopped by its
// control (cancelled, deadline, CPU budget, shutdown) reports why, not "cancelled".
template <typename Fn>
grpc::ServerUnaryReactor* Pooled(WorkPool* pool, grpc::CallbackServerContext* ctx, Fn fn) {
  auto* reactor = ctx->DefaultReactor();
  absl::Status queued = pool->Submit(
      [reactor, pool, fn = std::move(fn)](const WorkControl& control) mutable {
        absl::Status st = control.Check();  // it may have waited past its deadline
        if (st.ok()) st = fn(control);
        if (st.code() == absl::StatusCode::kCancelled) {
          if (absl::Status why = control.Check(); !why.ok()) st = why;
        }
        if (st.code() == absl::StatusCode::kResourceExhausted &&
            absl::StrContains(st.message(), "--max_request_cpu")) {
          pool->CountBudgetExhausted();
        }
        reactor->Finish(ToGrpcStatus(st));
      },
      [reactor](const absl::Status& dropped) { reactor->Finish(ToGrpcStatus(dropped)); },
      [ctx] { return ctx->IsCancelled(); }, DeadlineOf(ctx));
  if (!queued.ok()) reactor->Finish(ToGrpcStatus(queued));
  return reactor;
}

// One watch stream (WatchTable, WatchSwing): the registry's watcher decides what to write and
// when; this reactor only carries it to gRPC and back.
template <typename Registry, typename Watcher, typename Request>
class WatchReactor final : public grpc::ServerWriteReactor<typename Watcher::Snapshot>,
                           public StreamSink<typename Watcher::Snapshot> {
 public:
  using Snapshot = typename Watcher::Snapshot;
  WatchReactor(Registry* registry, const Request& request, std::string id)
      : registry_(registry), id_(std::move(id)) {
    // Registered without a sink: a tick worker may offer it a frame at once, and its write
    // must not complete before watcher_ is set. Attach, then pump.
    absl::StatusOr<std::shared_ptr<Watcher>> watcher = registry->Watch(request, nullptr);
    if (!watcher.ok()) {
      this->Finish(ToGrpcStatus(watcher.status()));
      return;
    }
    watcher_ = *std::move(watcher);
    watcher_->Attach(this);
    watcher_->Pump();
  }

  void SinkWrite(const Snapshot* snapshot) override { this->StartWrite(snapshot); }
  void SinkWriteLast(const Snapshot* snapshot, const absl::Status& status) override {
    this->StartWriteAndFinish(snapshot, grpc::WriteOptions(), ToGrpcStatus(status));
  }
  void SinkFinish(const absl::Status& status) override { this->Finish(ToGrpcStatus(status)); }

  void OnWriteDone(bool ok) override { watcher_->OnWriteDone(ok); }
  void OnCancel() override {
    if (watcher_ != nullptr) watcher_->OnCancel();
  }
  void OnDone() override {
    if (watcher_ != nullptr) {
      watcher_->OnDone();
      registry_->Unwatch(id_, watcher_.get());
    }
    delete this;
  }

 private:
  Registry* const registry_;
  const std::string id_;
  std::shared_ptr<Watcher> watcher_;
};

// One DriveSwing stream: reads the start message and then torque commands; what it writes is
// decided by the driver's watcher, as for WatchSwing. Reads and writes run concurrently; `mu_`
// guards the drive, which the first read sets.
class DriveReactor final : public grpc::ServerBidiReactor<v1::DriveSwingRequest, v1::SwingSnapshot>,
                           public SwingSink {
 public:
  explicit DriveReactor(SessionRegistry* registry) : registry_(registry) { StartRead(&request_); }

  void SinkWrite(const v1::SwingSnapshot* snapshot) override { StartWrite(snapshot); }
  void SinkWriteLast(const v1::SwingSnapshot* snapshot, const absl::Status& status) override {
    StartWriteAndFinish(snapshot, grpc::WriteOptions(), ToGrpcStatus(status));
  }
  void SinkFinish(const absl::Status& status) override { Finish(ToGrpcStatus(status)); }

  void OnReadDone(bool ok) override {
    std::shared_ptr<Drive> drive = Current();
    if (!ok) {
      // The client half-closed (or the call is going away): the stream ends after a last
      // snapshot; the swing goes on.
      if (drive != nullptr) {
        registry_->EndDrive(*drive, /*half_closed=*/true);
      } else {
        Finish(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                            "DriveSwing: the first message must be `start`"));
      }
      return;
    }
    if (drive == nullptr) {
      if (!request_.has_start()) {
        Finish(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                            "DriveSwing: the first message must be `start`"));
        return;
      }
      // Registered without a sink, as in WatchReactor: drive_ is set before any write starts.
      absl::StatusOr<std::shared_ptr<Drive>> started =
          registry_->StartDrive(request_.start(), nullptr);
      if (!started.ok()) {
        Finish(ToGrpcStatus(started.status()));
        return;
      }
      drive = *started;
      {
        absl::MutexLock lock(&mu_);
        drive_ = drive;
      }
      drive->watcher->Attach(this);
      drive->watcher->Pump();
    } else if (request_.has_torque()) {
      registry_->Command(*drive, request_.torque());
    } else {
      registry_->Refuse(*drive, absl::InvalidArgumentError(
                                    "only the first message may be `start`; then `torque`"));
    }
    StartRead(&request_);
  }

  void OnWriteDone(bool ok) override { Current()->watcher->OnWriteDone(ok); }
  void OnCancel() override {
    if (std::shared_ptr<Drive> drive = Current()) drive->watcher->OnCancel();
  }
  void OnDone() override {
    if (std::shared_ptr<Drive> drive = Current()) {
      drive->watcher->OnDone();
      registry_->EndDrive(*drive, /*half_closed=*/false);
    }
    delete this;
  }

 private:
  std::shared_ptr<Drive> Current() {
    absl::MutexLock lock(&mu_);
    return drive_;
  }

  SessionRegistry* const registry_;
  v1::DriveSwingRequest request_;
  absl::Mutex mu_;
  std::shared_ptr<Drive> drive_ ABSL_GUARDED_BY(mu_);
};

class SwingService final : public v1::Swing::CallbackService {
 public:
  SwingService(SessionRegistry* sessions, RoundRegistry* rounds, WorkPool* pool)
      : sessions_(sessions), rounds_(rounds), pool_(pool) {}

 private:
  SessionRegistry* const sessions_;
  RoundRegistry* const rounds_;
  WorkPool* const pool_;

  grpc::ServerUnaryReactor* CreateSession(grpc::CallbackServerContext* ctx,
                                          const v1::CreateSessionRequest* request,
                                          v1::CreateSessionResponse* response) override {
    return Unary(ctx, response, [&] { return sessions_->Create(*request); });
  }
  grpc::ServerUnaryReactor* GetSession(grpc::CallbackServerContext* ctx,
                                       const v1::GetSessionRequest* request,
                                       v1::SessionInfo* response) override {
    return Unary(ctx, response, [&] { return sessions_->Get(*request); });
  }
  grpc::ServerUnaryReactor* ListSessions(grpc::CallbackServerContext* ctx,
                                         const v1::ListSessionsRequest* request,
                                         v1::ListSessionsResponse* response) override {
    return Unary(ctx, response, [&] { return sessions_->List(*request); });
  }
  grpc::ServerUnaryReactor* DeleteSession(grpc::CallbackServerContext* ctx,
                                          const v1::DeleteSessionRequest* request,
                                          v1::DeleteSessionResponse* response) override {
    return Unary(ctx, response, [&]() -> absl::StatusOr<v1::DeleteSessionResponse> {
      if (absl::Status s = sessions_->Delete(*request); !s.ok()) return s;
      return v1::DeleteSessionResponse();
    });
  }
  grpc::ServerUnaryReactor* StartSwing(grpc::CallbackServerContext* ctx,
                                       const v1::StartSwingRequest* request,
                                       v1::StartSwingResponse* response) override {
    // StartSwing runs the swing once, off the session's lock, before it starts it: a
    // simulation like any other.
    return Pooled(pool_, ctx, [this, request, response](const WorkControl&) -> absl::Status {
      absl::StatusOr<v1::StartSwingResponse> r = sessions_->Start(*request);
      if (!r.ok()) return r.status();
      *response = *std::move(r);
      return absl::OkStatus();
    });
  }
  grpc::ServerUnaryReactor* ResetSwing(grpc::CallbackServerContext* ctx,
                                       const v1::ResetSwingRequest* request,
                                       v1::ResetSwingResponse* response) override {
    return Unary(ctx, response, [&] { return sessions_->Reset(*request); });
  }
  grpc::ServerBidiReactor<v1::DriveSwingRequest, v1::SwingSnapshot>* DriveSwing(
      grpc::CallbackServerContext*) override {
    return new DriveReactor(sessions_);
  }
  grpc::ServerWriteReactor<v1::SwingSnapshot>* WatchSwing(
      grpc::CallbackServerContext*, const v1::WatchSwingRequest* request) override {
    return new WatchReactor<SessionRegistry, SwingWatcher, v1::WatchSwingRequest>(
        sessions_, *request, request->session_id());
  }

  grpc::ServerUnaryReactor* CreateRound(grpc::CallbackServerContext* ctx,
                                        const v1::CreateRoundRequest* request,
                                        v1::CreateRoundResponse* response) override {
    return Unary(ctx, response, [&] { return rounds_->Create(*request); });
  }
  grpc::ServerUnaryReactor* GetRound(grpc::CallbackServerContext* ctx,
                                     const v1::GetRoundRequest* request,
                                     v1::RoundInfo* response) override {
    return Unary(ctx, response, [&] { return rounds_->Get(*request); });
  }
  grpc::ServerUnaryReactor* ListRounds(grpc::CallbackServerContext* ctx,
                                       const v1::ListRoundsRequest* request,
                                       v1::ListRoundsResponse* response) override {
    return Unary(ctx, response, [&] { return rounds_->List(*request); });
  }
  grpc::ServerUnaryReactor* DeleteRound(grpc::CallbackServerContext* ctx,
                                        const v1::DeleteRoundRequest* request,
                                        v1::DeleteRoundResponse* response) override {
    return Unary(ctx, response, [&]() -> absl::StatusOr<v1::DeleteRoundResponse> {
      if (absl::Status s = rounds_->Delete(*request); !s.ok()) return s;
      return v1::DeleteRoundResponse();
    });
  }
  grpc::ServerUnaryReactor* PlayStroke(grpc::CallbackServerContext* ctx,
                                       const v1::PlayStrokeRequest* request,
                                       v1::PlayStrokeResponse* response) override {
    // The stroke is simulated (flight and ground, a millisecond or so) before it takes effect:
    // a simulation like any other, on the pool, under its budget.
    return Pooled(pool_, ctx, [this, request, response](const WorkControl& control) -> absl::Status {
      absl::StatusOr<v1::PlayStrokeResponse> r =
          rounds_->Stroke(*request, [&control] { return control.ShouldStop(); });
      if (!r.ok()) return r.status();
      *response = *std::move(r);
      return absl::OkStatus();
    });
  }
  grpc::ServerUnaryReactor* DecideRound(grpc::CallbackServerContext* ctx,
                                        const v1::DecideRoundRequest* request,
                                        v1::DecideRoundResponse* response) override {
    return Unary(ctx, response, [&] { return rounds_->Decide(*request); });
  }
  grpc::ServerUnaryReactor* BindMonitor(grpc::CallbackServerContext* ctx,
                                        const v1::BindMonitorRequest* request,
                                        v1::BindMonitorResponse* response) override {
    return Unary(ctx, response, [&] { return rounds_->BindMonitor(*request); });
  }
  grpc::ServerWriteReactor<v1::RoundSnapshot>* WatchRound(
      grpc::CallbackServerContext*, const v1::WatchRoundRequest* request) override {
    return new WatchReactor<RoundRegistry, RoundWatcher, v1::WatchRoundRequest>(
        rounds_, *request, request->round_id());
  }
  grpc::ServerUnaryReactor* GetRoundRecord(grpc::CallbackServerContext* ctx,
                                           const v1::GetRoundRecordRequest* request,
                                           v1::RoundRecord* response) override {
    return Unary(ctx, response, [&] { return rounds_->Record(*request); });
  }

  grpc::ServerUnaryReactor* SimulateSwing(grpc::CallbackServerContext* ctx,
                                          const v1::SimulateSwingRequest* request,
                                          v1::SimulateSwingResponse* response) override {
    // Checked on the call's thread (cheap), computed on the pool.
    absl::StatusOr<SwingJob> job = SwingJobFromProto(*request);
    if (!job.ok()) return Finished(ctx, job.status());
    auto shared = std::make_shared<SwingJob>(*std::move(job));
    return Pooled(pool_, ctx, [shared, response](const WorkControl& control) {
      return Simulate(shared.get(), control, response);
    });
  }

  // A deadline, a client that goes away, the CPU budget or a server shutdown past its grace
  // stops the run: it polls its control.
  static absl::Status Simulate(SwingJob* job, const WorkControl& control,
                               v1::SimulateSwingResponse* response) {
    job->run.cancelled = [&control] { return control.ShouldStop(); };
    const double cpu0 = ThreadCpuSeconds();
    absl::StatusOr<swing::SwingRunResult> result =
        swing::SimulateSwing(job->model, job->program, job->solver, job->run);
    const double cpu_s = ThreadCpuSeconds() - cpu0;
    if (!result.ok()) return result.status();
    SwingResultToProto(*result, cpu_s, response);
    if (job->strike && result->impact) {
      job->strike->flight.options.cancelled = job->run.cancelled;
      LaunchBall(*job->strike, *result->impact, response->mutable_ball());
    }
    return absl::OkStatus();
  }

  grpc::ServerUnaryReactor* SimulateFlight(grpc::CallbackServerContext* ctx,
                                           const v1::SimulateFlightRequest* request,
                                           v1::SimulateFlightResponse* response) override {
    return Pooled(pool_, ctx, [request, response](const WorkControl& control) {
      return Fly(*request, control, response);
    });
  }

  grpc::ServerUnaryReactor* SimulateGolfShot(grpc::CallbackServerContext* ctx,
                                             const v1::SimulateGolfShotRequest* request,
                                             v1::SimulateGolfShotResponse* response) override {
    return Pooled(pool_, ctx, [request, response](const WorkControl& control) {
      absl::StatusOr<GolfShotJob> job = GolfShotJobFromProto(*request);
      if (!job.ok()) return job.status();
      const double cpu0 = ThreadCpuSeconds();
      absl::Status st = RunGolfShot(*job, [&control] { return control.ShouldStop(); }, response);
      response->set_cpu_s(ThreadCpuSeconds() - cpu0);
      return st;
    });
  }

  grpc::ServerUnaryReactor* ListCourses(grpc::CallbackServerContext* ctx,
                                        const v1::ListCoursesRequest*,
                                        v1::ListCoursesResponse* response) override {
    return Unary(ctx, response, [] { return absl::StatusOr<v1::ListCoursesResponse>(server::ListCourses()); });
  }
  grpc::ServerUnaryReactor* GetCourse(grpc::CallbackServerContext* ctx,
                                      const v1::GetCourseRequest* request,
                                      v1::CourseInfo* response) override {
    return Unary(ctx, response, [&] { return server::GetCourse(*request); });
  }

  // Like a swing, a flight polls its control (deadline, cancellation, CPU budget, shutdown).
  static absl::Status Fly(const v1::SimulateFlightRequest& request, const WorkControl& control,
                          v1::SimulateFlightResponse* response) {
    absl::StatusOr<FlightJob> job = FlightJobFromProto(request);
    if (!job.ok()) return job.status();
    job->options.cancelled = [&control] { return control.ShouldStop(); };
    const double cpu0 = ThreadCpuSeconds();
    absl::StatusOr<golf::FlightResult> result =
        golf::SimulateFlight(job->ball, job->launch, job->atmosphere, job->wind, job->options);
    if (!result.ok()) return result.status();
    FlightResultToProto(*result, 0.0, response);
    absl::Status rolled = RollOutToProto(*job, *result, response);  // with `fairway`
    response->set_cpu_s(ThreadCpuSeconds() - cpu0);
    return rolled;
  }
};

// SimulateShots: a batch's outcomes computed in chunks on the pool's batch workers (every
// core, below interactive work), streamed in request order, one chunk a message. The batch
// computes ahead of its reader only within a window: at most a few chunks queued, running or
// finished and unsent, and at most limits.window_bytes of finished unsent outcomes, so a client
// that reads slowly or not at all holds a few kilobytes of the server's memory, not gigabytes,
// and no CPU while it does not read. A write that makes no progress for limits.stall_timeout
// (the client reads nothing) ends the call. The batch's CPU (all chunks together) is held to
// --max_request_cpu; cancellation and the deadline stop the chunks at their next poll. The
// stream is finished only once no chunk is running, no write is in flight and the stall alarm
// is idle, so nothing touches the reactor after it is done.
class BatchReactor final : public grpc::ServerWriteReactor<v1::SimulateShotsResponse> {
 public:
  BatchReactor(WorkPool* pool, grpc::CallbackServerContext* ctx,
               const v1::SimulateShotsRequest& request, double cpu_budget_s,
               const StreamLimits& limits)
      : pool_(pool), ctx_(ctx), cpu_budget_s_(cpu_budget_s), limits_(limits),
        owner_(pool->NewOwner()) {
    absl::StatusOr<BatchJob> job = BatchJobFromProto(request);
    if (!job.ok()) {
      Finish(ToGrpcStatus(job.status()));
      return;
    }
    job_ = std::make_shared<const BatchJob>(*std::move(job));
    // Outcomes with every event are large: one a message.
    chunk_ = job_->outcome == v1::SHOT_OUTCOME_EVENTS ? 1 : 32;
    chunks_ = (job_->size() + chunk_ - 1) / chunk_;
    std::optional<grpc::Status> finish;
    {
      absl::MutexLock lock(&mu_);
      finish = Pump();
    }
    if (finish.has_value()) Finish(*finish);
  }

  void OnWriteDone(bool ok) override {
    Step([&] {
      writing_ = false;
      ++writes_done_;
      if (!ok && error_.ok()) error_ = absl::CancelledError("the stream was closed");
    });
  }
  void OnCancel() override {
    Step([&] {
      if (error_.ok()) error_ = absl::CancelledError("the call was cancelled");
    });
  }
  void OnDone() override { delete this; }

 private:
  // Runs `f` under mu_, pumps, then (without the lock) does what the pump asked for: cancel
  // the stall alarm, cancel the call, finish. Nothing touches the reactor after Finish.
  template <typename F>
  void Step(F f) {
    std::optional<grpc::Status> finish;
    bool cancel_alarm = false;
    bool cancel_call = false;
    {
      absl::MutexLock lock(&mu_);
      f();
      finish = Pump();
      cancel_alarm = std::exchange(cancel_alarm_, false);
      cancel_call = std::exchange(cancel_call_, false);
    }
    if (cancel_alarm) alarm_->Cancel();  // its callback (not fired) comes back through Step
    if (cancel_call) ctx_->TryCancel();  // the stuck write completes, not ok
    if (finish.has_value()) Finish(*finish);
  }

  // Chunks queued, running, or finished and not yet written.
  int64_t Ahead() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    return outstanding_ + static_cast<int64_t>(ready_.size());
  }

  // Submits chunks while the window has room, writes the next chunk in order when it is
  // ready, and says when to finish: when all is written (or on an error once nothing runs).
  // The caller finishes after releasing mu_ and touches nothing after that (OnDone may delete
  // the reactor at once, on another thread).
  std::optional<grpc::Status> Pump() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (finished_) return std::nullopt;
    const int64_t window_chunks = std::max(2, 2 * pool_->batch_workers());
    while (error_.ok() && next_submit_ < chunks_ && Ahead() < window_chunks &&
           ready_bytes_ < limits_.window_bytes) {
      const int64_t c = next_submit_++;
      ++outstanding_;
      absl::Status queued = pool_->Submit(
          [this, c](const WorkControl& control) { Run(c, control); },
          [this](const absl::Status& dropped) {
            Step([&]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
              --outstanding_;
              if (error_.ok()) error_ = dropped;
            });
          },
          [this] { return ctx_->IsCancelled(); }, DeadlineOf(ctx_), WorkClass::kBatch, owner_);
      if (!queued.ok()) {
        --outstanding_;
        error_ = queued;
      }
    }
    if (!writing_ && error_.ok()) {
      auto it = ready_.find(next_write_);
      if (it != ready_.end()) {
        out_ = std::move(it->second.response);
        ready_bytes_ -= it->second.bytes;
        ready_.erase(it);
        ++next_write_;
        writing_ = true;
        ArmStallAlarm();
        StartWrite(&out_);
        return std::nullopt;
      }
    }
    // Nothing finished and unsent is kept once the batch has failed.
    if (!error_.ok() && !ready_.empty()) {
      ready_.clear();
      ready_bytes_ = 0;
    }
    const bool all_written = next_write_ == chunks_;
    const bool done = !writing_ && outstanding_ == 0 && (all_written || !error_.ok());
    if (done && alarm_pending_ && !alarm_cancelled_) {
      alarm_cancelled_ = true;
      cancel_alarm_ = true;
    }
    if (done && !alarm_pending_) {
      finished_ = true;
      return ToGrpcStatus(error_);
    }
    return std::nullopt;
  }

  // The stall alarm: while a write is in flight, it checks every stall_timeout that some
  // write completed since it was set; if none did, the reader has stalled and the call ends.
  void ArmStallAlarm() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (alarm_pending_ || limits_.stall_timeout <= absl::ZeroDuration()) return;
    alarm_pending_ = true;
    alarm_cancelled_ = false;
    alarm_writes_ = writes_done_;
    // A fresh alarm each time (the one that fired may be the caller, still running).
    alarm_ = std::make_unique<grpc::Alarm>();
    alarm_->Set(absl::ToChronoTime(absl::Now() + limits_.stall_timeout),
                [this](bool fired) { OnStallAlarm(fired); });
  }
  void OnStallAlarm(bool fired) {
    Step([&]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
      alarm_pending_ = false;
      if (!fired || !error_.ok() || !writing_) return;
      if (writes_done_ == alarm_writes_) {
        error_ = absl::ResourceExhaustedError(absl::StrFormat(
            "the client read nothing for %s (--stream_stall_timeout): the batch was stopped",
            absl::FormatDuration(limits_.stall_timeout)));
        cancel_call_ = true;
      } else {
        ArmStallAlarm();
      }
    });
  }

  // One chunk on a worker: outcomes [c * chunk_, ...), each polling the call and the batch's
  // CPU budget between events.
  void Run(int64_t c, const WorkControl& control) {
    v1::SimulateShotsResponse response;
    const int64_t first = c * chunk_;
    const int64_t last = std::min(job_->size(), first + chunk_);
    absl::Status stopped;
    const double cpu0 = control.CpuSeconds();
    double counted_so_far = 0.0;
    const auto stop = [&] {
      return control.ShouldStop() ||
             cpu_used_.load(std::memory_order_relaxed) +
                     (control.CpuSeconds() - cpu0 - counted_so_far) >
                 cpu_budget_s_;
    };
    // Why the chunk stops: the call (cancelled, deadline, shutdown) or the batch's budget.
    const auto why = [&](int64_t n) {
      absl::Status st = control.Check();
      if (st.ok()) {
        st = absl::ResourceExhaustedError(absl::StrFormat(
            "the batch used its CPU budget of %g s (--max_request_cpu) after %d outcomes: send "
            "fewer strikes or samples per call",
            cpu_budget_s_, n));
        pool_->CountBudgetExhausted();
      }
      return st;
    };
    double counted = 0.0;  // of this chunk's CPU, what cpu_used_ already holds
    for (int64_t n = first; n < last && stopped.ok(); ++n) {
      if (stop()) {
        stopped = why(n);
        break;
      }
      ComputeOutcome(*job_, n, stop, response.add_outcomes());
      // An outcome the stop cut short is not an outcome: the batch ends with the reason.
      if (stop()) {
        response.mutable_outcomes()->RemoveLast();
        stopped = why(n);
        break;
      }
      // The budget is the batch's: every chunk sees the others' CPU as it goes.
      const double now = control.CpuSeconds() - cpu0;
      AddCpu(now - counted);
      counted = now;
      counted_so_far = counted;
    }
    const double used = control.CpuSeconds() - cpu0 - counted;
    const int64_t bytes = static_cast<int64_t>(response.ByteSizeLong());
    Step([&]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
      AddCpu(used);
      --outstanding_;
      if (!stopped.ok()) {
        if (error_.ok()) error_ = stopped;
      } else if (error_.ok()) {
        ready_bytes_ += bytes;
        ready_.emplace(c, Ready{std::move(response), bytes});
      }
    });
  }

  void AddCpu(double s) {
    double old = cpu_used_.load(std::memory_order_relaxed);
    while (!cpu_used_.compare_exchange_weak(old, old + s, std::memory_order_relaxed)) {
    }
  }

  struct Ready {
    v1::SimulateShotsResponse response;
    int64_t bytes = 0;
  };

  WorkPool* const pool_;
  grpc::CallbackServerContext* const ctx_;
  const double cpu_budget_s_;
  const StreamLimits limits_;
  const uint64_t owner_;
  std::shared_ptr<const BatchJob> job_;
  int64_t chunk_ = 1;
  int64_t chunks_ = 0;
  std::atomic<double> cpu_used_{0.0};
  absl::Mutex mu_;
  int64_t next_submit_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t next_write_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t outstanding_ ABSL_GUARDED_BY(mu_) = 0;
  bool writing_ ABSL_GUARDED_BY(mu_) = false;
  bool finished_ ABSL_GUARDED_BY(mu_) = false;
  absl::Status error_ ABSL_GUARDED_BY(mu_);
  std::map<int64_t, Ready> ready_ ABSL_GUARDED_BY(mu_);
  int64_t ready_bytes_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t writes_done_ ABSL_GUARDED_BY(mu_) = 0;
  std::unique_ptr<grpc::Alarm> alarm_;  // set and cancelled as Step and ArmStallAlarm say
  bool alarm_pending_ ABSL_GUARDED_BY(mu_) = false;
  bool alarm_cancelled_ ABSL_GUARDED_BY(mu_) = false;
  bool cancel_alarm_ ABSL_GUARDED_BY(mu_) = false;
  bool cancel_call_ ABSL_GUARDED_BY(mu_) = false;
  int64_t alarm_writes_ ABSL_GUARDED_BY(mu_) = 0;
  v1::SimulateShotsResponse out_;  // the message being written
};

// A calibration's call: one calibration, one job on the pool's batch workers (below
// interactive work), under the request's CPU budget (--max_request_cpu), cancellation and
// deadline. Its progress is streamed as it goes; only the latest unsent progress is kept (a
// slow reader sees fewer, and the server holds one message), and the last message carries the
// report. The stream is finished once the job has ended, no write is in flight and the
// derived call holds nothing (Holding: UploadCalibration's reads and read alarm), so nothing
// touches the reactor after it is done. `Base` is the reactor: CalibrateTable's writes only,
// UploadCalibration's reads the request first.
template <typename Base>
class CalibrationCall : public Base {
 public:
  void OnWriteDone(bool ok) override {
    Step([&]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
      writing_ = false;
      if (!ok && error_.ok()) error_ = absl::CancelledError("the stream was closed");
    });
  }
  void OnDone() override { delete this; }

 protected:
  // Checks the request and queues its job, or ends the call with the error.
  void Begin(WorkPool* pool, grpc::CallbackServerContext* ctx, const v1::CalibrateTableRequest& request) {
    absl::StatusOr<CalibrationJob> job = CalibrationJobFromProto(request);
    Step([&]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
      Begun();
      if (!job.ok()) {
        FailLocked(job.status());
      } else {
        running_ = true;
      }
    });
    if (!job.ok()) return;
    auto shared = std::make_shared<CalibrationJob>(*std::move(job));
    absl::Status queued = pool->Submit(
        [this, shared, pool](const WorkControl& control) { Run(shared.get(), control, pool); },
        [this](const absl::Status& dropped) {
          Step([&]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
            running_ = false;
            if (error_.ok()) error_ = dropped;
          });
        },
        [ctx] { return ctx->IsCancelled(); }, DeadlineOf(ctx), WorkClass::kBatch, pool->NewOwner());
    if (!queued.ok()) {
      Step([&]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
        running_ = false;
        error_ = queued;
      });
    }
  }

  // The call's first error: no job is started after one, and the call ends once nothing
  // runs, is written or is held.
  void FailLocked(const absl::Status& status) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (error_.ok()) error_ = status;
  }

  // Called once, just before the call finishes (its job ended, nothing left to write), so a
  // client that has its status sees what the call held given back.
  virtual void Finishing() {}
  // Whether the derived call still holds what must end before the call does (an alarm whose
  // callback has not come back); it may ask for AfterStep to end it.
  virtual bool Holding() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) { return false; }
  // Called as Begin has checked the request, before the job is queued or the call fails.
  virtual void Begun() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {}
  // Whether a step is to end with AfterStep (taking the request: each is done once).
  virtual bool TakeAfterStep() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) { return false; }
  // What TakeAfterStep asked for, without mu_ (cancel an alarm). The call holds on (Holding)
  // until that is done, so the reactor is alive.
  virtual void AfterStep() {}

  // Runs `f` under mu_, pumps, then (without the lock) what the derived call asked for and,
  // when the pump says so, Finishing and Finish. Nothing touches the reactor after Finish
  // (nor, in a step that does not finish, after the lock is released: another thread's step
  // may finish the call).
  template <typename F>
  void Step(F f) {
    std::optional<grpc::Status> finish;
    bool after = false;
    {
      absl::MutexLock lock(&mu_);
      f();
      finish = Pump();
      after = TakeAfterStep();
    }
    if (after) AfterStep();
    if (finish.has_value()) {
      Finishing();
      this->Finish(*finish);
    }
  }

  absl::Mutex mu_;

 private:

  // Writes the pending message when no write is in flight; says when to finish: the job has
  // ended and nothing is left to write (or it failed).
  std::optional<grpc::Status> Pump() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (finished_) return std::nullopt;
    if (!error_.ok()) pending_.reset();
    if (!writing_ && pending_.has_value()) {
      out_ = *std::move(pending_);
      pending_.reset();
      writing_ = true;
      this->StartWrite(&out_);
      return std::nullopt;
    }
    if (!writing_ && !running_ && !Holding()) {
      finished_ = true;
      return ToGrpcStatus(error_);
    }
    return std::nullopt;
  }

  // The calibration on a worker.
  void Run(CalibrationJob* job, const WorkControl& control, WorkPool* pool) {
    job->options.cancelled = [&control] { return control.ShouldStop(); };
    job->options.progress = [this](double fraction, std::string_view stage) {
      v1::CalibrateTableResponse r;
      r.set_fraction(fraction);
      r.set_stage(std::string(stage));
      Step([&]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) { pending_ = std::move(r); });
    };
    absl::StatusOr<billiards::CalibrationReport> report =
        billiards::Calibrate(job->spec, job->solver, job->recordings, job->options);
    absl::Status st = report.status();
    if (st.code() == absl::StatusCode::kCancelled) {
      if (absl::Status why = control.Check(); !why.ok()) st = why;
    }
    if (st.code() == absl::StatusCode::kResourceExhausted &&
        absl::StrContains(st.message(), "--max_request_cpu")) {
      pool->CountBudgetExhausted();
      st = absl::ResourceExhaustedError(absl::StrFormat(
          "the calibration used its CPU budget (--max_request_cpu) after %.3g s: give fewer "
          "shots, parameters or max_iterations, or run it on a server with a larger budget",
          control.CpuSeconds()));
    }
    v1::CalibrateTableResponse last;
    if (st.ok()) {
      last.set_fraction(1.0);
      last.set_stage("done");
      CalibrationReportToProto(*job, *report, last.mutable_report());
      last.mutable_report()->set_cpu_s(control.CpuSeconds());
    }
    Step([&]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
      running_ = false;
      if (!st.ok()) {
        if (error_.ok()) error_ = st;
      } else {
        pending_ = std::move(last);
      }
    });
  }

  bool running_ ABSL_GUARDED_BY(mu_) = false;
  bool writing_ ABSL_GUARDED_BY(mu_) = false;
  bool finished_ ABSL_GUARDED_BY(mu_) = false;
  absl::Status error_ ABSL_GUARDED_BY(mu_);
  std::optional<v1::CalibrateTableResponse> pending_ ABSL_GUARDED_BY(mu_);
  v1::CalibrateTableResponse out_;  // the message being written
};

// CalibrateTable: the request in one message.
class CalibrateReactor final
    : public CalibrationCall<grpc::ServerWriteReactor<v1::CalibrateTableResponse>> {
 public:
  CalibrateReactor(WorkPool* pool, grpc::CallbackServerContext* ctx,
                   const v1::CalibrateTableRequest& request) {
    Begin(pool, ctx, request);
  }
};

// Bytes held by all the calls of one kind at once (UploadCalibration's uploads), against a cap.
class ByteBudget {
 public:
  explicit ByteBudget(int64_t cap) : cap_(cap) {}
  bool Reserve(int64_t n) {
    int64_t used = used_.load(std::memory_order_relaxed);
    do {
      if (used + n > cap_) return false;
    } while (!used_.compare_exchange_weak(used, used + n, std::memory_order_relaxed));
    return true;
  }
  void Release(int64_t n) { used_.fetch_sub(n, std::memory_order_relaxed); }
  int64_t cap() const { return cap_; }

 private:
  const int64_t cap_;
  std::atomic<int64_t> used_{0};
};

// UploadCalibration: the request in parts, each counted against the server's upload budget
// from its arrival until the call finishes (the job's recordings are about as large); the
// calibration begins when the client half-closes. A client that sends nothing for
// --stream_stall_timeout while it uploads ends its upload (RESOURCE_EXHAUSTED), so that a
// trickle cannot hold the budget for as long as its deadline: a read alarm checks every
// stall_timeout that some part arrived since it was set.
class UploadCalibrationReactor final
    : public CalibrationCall<grpc::ServerBidiReactor<v1::CalibrationUpload, v1::CalibrateTableResponse>> {
 public:
  UploadCalibrationReactor(WorkPool* pool, grpc::CallbackServerContext* ctx, ByteBudget* budget,
                           absl::Duration stall_timeout)
      : pool_(pool), ctx_(ctx), budget_(budget), stall_timeout_(stall_timeout) {
    StartRead(&in_);
    absl::MutexLock lock(&mu_);  // OnDone waits for this handler to return
    ArmReadAlarm();
  }
  ~UploadCalibrationReactor() override { budget_->Release(held_); }  // 0 once finished

  void OnReadDone(bool ok) override {
    {
      absl::MutexLock lock(&mu_);
      // Stopped while this read was pending (a stall): the call is finishing without it.
      if (!reading_) return;
      if (ok) ++reads_;
    }
    if (!ok) {  // the client half-closed, or the call is going away
      if (ctx_->IsCancelled()) {
        StopReading(absl::CancelledError("the upload was cancelled"));
        return;
      }
      absl::StatusOr<v1::CalibrateTableRequest> request = std::move(assembler_).Finish();
      if (!request.ok()) {
        StopReading(request.status());
        return;
      }
      Begin(pool_, ctx_, *request);  // stops reading (Begun)
      return;
    }
    const int64_t n = static_cast<int64_t>(in_.ByteSizeLong());
    if (!budget_->Reserve(n)) {
      StopReading(absl::ResourceExhaustedError(absl::StrFormat(
          "the uploads in progress hold the server's --max_upload_bytes (%d) already: try again "
          "later",
          budget_->cap())));
      return;
    }
    held_ += n;
    if (absl::Status s = assembler_.Add(in_); !s.ok()) {
      StopReading(s);
      return;
    }
    StartRead(&in_);
  }

 private:
  // Ends the upload with `status`: no more reads, and the call finishes once the read alarm
  // is back.
  void StopReading(const absl::Status& status) {
    Step([&]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
      reading_ = false;
      FailLocked(status);
    });
  }

  void ArmReadAlarm() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (alarm_pending_ || !reading_ || stall_timeout_ <= absl::ZeroDuration()) return;
    alarm_pending_ = true;
    alarm_reads_ = reads_;
    // A fresh alarm each time (the one that fired may be the caller, still running).
    alarm_ = std::make_unique<grpc::Alarm>();
    alarm_->Set(absl::ToChronoTime(absl::Now() + stall_timeout_),
                [this](bool fired) { OnReadAlarm(fired); });
  }
  void OnReadAlarm(bool fired) {
    Step([&]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
      alarm_pending_ = false;
      if (!fired || !reading_) return;
      if (reads_ == alarm_reads_) {
        // The pending read completes after the status goes out, and is ignored.
        reading_ = false;
        FailLocked(absl::ResourceExhaustedError(absl::StrFormat(
            "the client sent nothing for %s (--stream_stall_timeout): the upload was stopped",
            absl::FormatDuration(stall_timeout_))));
      } else {
        ArmReadAlarm();
      }
    });
  }

  bool Holding() override ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (!reading_ && alarm_pending_ && !alarm_cancel_asked_) {
      alarm_cancel_asked_ = true;
      cancel_alarm_ = true;
    }
    return reading_ || alarm_pending_;
  }
  void Begun() override ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) { reading_ = false; }
  bool TakeAfterStep() override ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    return std::exchange(cancel_alarm_, false);
  }
  void AfterStep() override { alarm_->Cancel(); }  // its callback (not fired) comes back

  // Given back before the status goes out, not when gRPC is done with the call (later), so
  // the client's next upload finds it free.
  void Finishing() override {
    budget_->Release(held_);
    held_ = 0;
  }

  WorkPool* const pool_;
  grpc::CallbackServerContext* const ctx_;
  ByteBudget* const budget_;
  const absl::Duration stall_timeout_;
  int64_t held_ = 0;  // reserved from budget_
  v1::CalibrationUpload in_;
  CalibrationUploadAssembler assembler_;
  bool reading_ ABSL_GUARDED_BY(mu_) = true;  // parts may still come (no end, no error)
  int64_t reads_ ABSL_GUARDED_BY(mu_) = 0;    // parts arrived
  std::unique_ptr<grpc::Alarm> alarm_;       // set by ArmReadAlarm, cancelled by AfterStep
  bool alarm_pending_ ABSL_GUARDED_BY(mu_) = false;
  bool alarm_cancel_asked_ ABSL_GUARDED_BY(mu_) = false;
  bool cancel_alarm_ ABSL_GUARDED_BY(mu_) = false;
  int64_t alarm_reads_ ABSL_GUARDED_BY(mu_) = 0;
};

class BilliardsService final : public v1::Billiards::CallbackService {
 public:
  BilliardsService(TableRegistry* tables, WorkPool* pool, int64_t max_reply_bytes,
                   double cpu_budget_s, StreamLimits streams)
      : tables_(tables), pool_(pool), max_reply_bytes_(max_reply_bytes),
        cpu_budget_s_(cpu_budget_s), streams_(streams), uploads_(streams.upload_bytes) {}

 private:
  TableRegistry* const tables_;
  WorkPool* const pool_;
  const int64_t max_reply_bytes_;
  const double cpu_budget_s_;
  const StreamLimits streams_;
  ByteBudget uploads_;  // UploadCalibration's uploads in progress

  grpc::ServerUnaryReactor* CreateTable(grpc::CallbackServerContext* ctx,
                                        const v1::CreateTableRequest* request,
                                        v1::CreateTableResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->Create(*request); });
  }
  grpc::ServerUnaryReactor* GetTable(grpc::CallbackServerContext* ctx,
                                     const v1::GetTableRequest* request,
                                     v1::TableInfo* response) override {
    return Unary(ctx, response, [&] { return tables_->Get(*request); });
  }
  grpc::ServerUnaryReactor* ListTables(grpc::CallbackServerContext* ctx,
                                       const v1::ListTablesRequest* request,
                                       v1::ListTablesResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->List(*request); });
  }
  grpc::ServerUnaryReactor* DeleteTable(grpc::CallbackServerContext* ctx,
                                        const v1::DeleteTableRequest* request,
                                        v1::DeleteTableResponse* response) override {
    return Unary(ctx, response, [&]() -> absl::StatusOr<v1::DeleteTableResponse> {
      if (absl::Status s = tables_->Delete(*request); !s.ok()) return s;
      return v1::DeleteTableResponse();
    });
  }
  grpc::ServerUnaryReactor* ResetTable(grpc::CallbackServerContext* ctx,
                                       const v1::ResetTableRequest* request,
                                       v1::ResetTableResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->Reset(*request); });
  }
  grpc::ServerUnaryReactor* PlaceBall(grpc::CallbackServerContext* ctx,
                                      const v1::PlaceBallRequest* request,
                                      v1::PlaceBallResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->Place(*request); });
  }
  grpc::ServerUnaryReactor* Shoot(grpc::CallbackServerContext* ctx,
                                  const v1::ShootRequest* request,
                                  v1::ShootResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->Shoot(*request); });
  }
  grpc::ServerUnaryReactor* SetTurn(grpc::CallbackServerContext* ctx,
                                    const v1::SetTurnRequest* request,
                                    v1::SetTurnResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->SetTurn(*request); });
  }
  grpc::ServerWriteReactor<v1::SimulateShotsResponse>* SimulateShots(
      grpc::CallbackServerContext* ctx, const v1::SimulateShotsRequest* request) override {
    return new BatchReactor(pool_, ctx, *request, cpu_budget_s_, streams_);
  }
  grpc::ServerWriteReactor<v1::CalibrateTableResponse>* CalibrateTable(
      grpc::CallbackServerContext* ctx, const v1::CalibrateTableRequest* request) override {
    return new CalibrateReactor(pool_, ctx, *request);
  }
  grpc::ServerBidiReactor<v1::CalibrationUpload, v1::CalibrateTableResponse>* UploadCalibration(
      grpc::CallbackServerContext* ctx) override {
    return new UploadCalibrationReactor(pool_, ctx, &uploads_, streams_.stall_timeout);
  }
  grpc::ServerUnaryReactor* PreviewShot(grpc::CallbackServerContext* ctx,
                                        const v1::PreviewShotRequest* request,
                                        v1::PreviewShotResponse* response) override {
    // The table's state is copied under its lock at once; the simulation runs on the pool.
    absl::StatusOr<PreviewJob> job = tables_->PreparePreview(*request);
    if (!job.ok()) return Finished(ctx, job.status());
    auto shared = std::make_shared<PreviewJob>(*std::move(job));
    return Pooled(pool_, ctx, [shared, response](const WorkControl& control) {
      return RunPreview(*shared, [&control] { return control.ShouldStop(); }, response);
    });
  }
  grpc::ServerUnaryReactor* Decide(grpc::CallbackServerContext* ctx,
                                   const v1::DecideRequest* request,
                                   v1::DecideResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->Decide(*request); });
  }
  grpc::ServerUnaryReactor* Concede(grpc::CallbackServerContext* ctx,
                                    const v1::ConcedeRequest* request,
                                    v1::ConcedeResponse* response) override {
    return Unary(ctx, response, [&] { return tables_->Concede(*request); });
  }
  grpc::ServerUnaryReactor* GetMatchRecord(grpc::CallbackServerContext* ctx,
                                           const v1::GetMatchRecordRequest* request,
                                           v1::MatchRecord* response) override {
    return Unary(ctx, response, [&] { return tables_->GetMatchRecord(*request); });
  }
  grpc::ServerWriteReactor<v1::TableSnapshot>* WatchTable(
      grpc::CallbackServerContext*, const v1::WatchTableRequest* request) override {
    return new WatchReactor<TableRegistry, Watcher, v1::WatchTableRequest>(tables_, *request,
                                                                           request->table_id());
  }

  grpc::ServerUnaryReactor* SimulateShot(grpc::CallbackServerContext* ctx,
                                         const v1::SimulateShotRequest* request,
                                         v1::SimulateShotResponse* response) override {
    // Checked on the call's thread, before any work: the request, and what its reply could
    // grow to (samples x balls against the reply limit).
    absl::StatusOr<ShotJob> job = ShotJobFromProto(*request);
    if (!job.ok()) return Finished(ctx, job.status());
    if (absl::Status s = BoundShotWork(max_reply_bytes_, &*job); !s.ok()) {
      return Finished(ctx, s);
    }
    auto shared = std::make_shared<ShotJob>(*std::move(job));
    return Pooled(pool_, ctx, [shared, response](const WorkControl& control) {
      return Simulate(shared.get(), control, response);
    });
  }

  static absl::Status Simulate(ShotJob* job, const WorkControl& control,
                               v1::SimulateShotResponse* response) {
    job->shot.cancelled = [&control] { return control.ShouldStop(); };
    absl::StatusOr<billiards::ShotResult> result = billiards::SimulateShot(
        job->table.model, job->solver, job->table.state, job->shot);
    if (!result.ok()) return result.status();
    ShotResultToProto(*job, *result, response);
    return absl::OkStatus();
  }
};

}  // namespace

v1::GetInfoResponse MakeServerInfo() {
  v1::GetInfoResponse info;
  info.set_version(SPORTSIM_VERSION);
  info.set_build_type(SPORTSIM_BUILD_TYPE);
  info.set_compiler(SPORTSIM_COMPILER);
  info.set_build(std::string(SPORTSIM_BUILD_TYPE) + ", " + SPORTSIM_COMPILER);
  info.set_grpc_version(grpc::Version());
  info.set_protobuf_version(
      google::protobuf::internal::VersionString(GOOGLE_PROTOBUF_VERSION));
  v1::Capabilities* caps = info.mutable_capabilities();
  AddBilliardsCapabilities(caps);
  for (swing::SwingIntegrator i : swing::kAllSwingIntegrators) {
    caps->add_swing_integrators(std::string(swing::SwingIntegratorName(i)));
  }
  for (const std::string& e : SwingEffectNames()) caps->add_swing_effects(e);
  for (v1::ParameterInfo& p : SwingParameterInfo()) *caps->add_swing_parameters() = std::move(p);
  GamesToProto(caps->mutable_games());
  for (std::string_view c : golf::BuiltinCourseNames()) caps->add_golf_courses(std::string(c));
  for (const golf::Surface& s : golf::BuiltinSurfaces()) caps->add_golf_surfaces(s.name);
  caps->add_golf_round_rules("order=honour|ready");
  caps->add_golf_round_rules("max_score=N|par+N|net_double_bogey|none");
  caps->add_golf_round_rules("allowance=PCT");
  for (const char* c : {"stroke_and_distance", "back_on_the_line", "lateral",
                        "back_on_the_line_outside_bunker", "unplayable", "pick_up",
                        "concede_stroke", "concede_hole", "concede_match"}) {
    caps->add_golf_round_choices(c);
  }
  for (golf::PlayFormat p : {golf::PlayFormat::kStroke, golf::PlayFormat::kMatch, golf::PlayFormat::kStableford}) {
    caps->add_golf_round_plays(std::string(golf::PlayFormatName(p)));
  }
  *caps->mutable_presets() = caps->table_presets();
  caps->add_services(v1::Server::service_full_name());
  caps->add_services(v1::Swing::service_full_name());
  caps->add_services(v1::Billiards::service_full_name());
  caps->add_services("grpc.health.v1.Health");
  caps->add_services("grpc.reflection.v1alpha.ServerReflection");
  return info;
}

std::unique_ptr<grpc::Service> MakeInfoService() { return std::make_unique<InfoService>(); }
std::unique_ptr<grpc::Service> MakeSwingService(SessionRegistry* sessions, RoundRegistry* rounds,
                                                WorkPool* pool) {
  return std::make_unique<SwingService>(sessions, rounds, pool);
}
std::unique_ptr<grpc::Service> MakeBilliardsService(TableRegistry* tables, WorkPool* pool,
                                                    int64_t max_reply_bytes,
                                                    double cpu_budget_s,
                                                    StreamLimits streams) {
  return std::make_unique<BilliardsService>(tables, pool, max_reply_bytes, cpu_budget_s,
                                            streams);
}

}  // namespace sportsim::server
