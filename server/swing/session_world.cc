#include "server/swing/session_world.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>
#include <utility>

#include "absl/strings/str_format.h"
#include "server/world/event_log.h"
#include "server/swing/convert.h"
#include "server/world/watcher_impl.h"
#include "server/world/world.h"
#include "sim/swing/realism.h"

namespace sportsim::server {

namespace sw = ::sportsim::swing;

// ---------------------------------------------------------------------------------------------
// Watcher

void SwingWatch::Fill(const SwingWatchOptions& /*options*/, const std::string& session_id,
                      const SwingFrame& frame, const SwingFrame* /*last_sent*/, bool /*full*/,
                      v1::SwingSnapshot* out) {
  out->set_session_id(session_id);
  out->set_tick(frame.tick);
  out->set_phase(frame.phase);
  out->set_swing_id(frame.swing_id);
  out->set_heartbeat(frame.heartbeat);
  out->set_qalpha_nm(frame.qalpha_nm);
  out->set_qbeta_nm(frame.qbeta_nm);
  if (!frame.heartbeat) SampleToProto(frame.state, out->mutable_state());
}

template class BasicWatcher<SwingWatch>;

// ---------------------------------------------------------------------------------------------
// Session

namespace {

// Flight samples in a session's IMPACT event: at most ~20 a second of flight.
constexpr double kMinSessionFlightSampleS = 0.05;

using SwingEventPtr = SwingWatcher::EventPtr;

// A tick time and a step end closer than this fraction of a tick period are the same instant.
constexpr double kSnapTicks = 1e-9;
constexpr double kDefaultTickHz = 400.0;
constexpr double kDefaultDurationS = 2.0;

absl::Status Unavailable() { return absl::UnavailableError("the server is shutting down"); }

absl::Status CheckSessionId(const std::string& id) {
  if (id.empty() || id.size() > 64) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "session_id must be 1 to 64 characters, got %d characters", static_cast<int>(id.size())));
  }
  return absl::OkStatus();
}

v1::SwingEvent SwingEvent(v1::SwingEventKind kind, double t_s, uint64_t swing_id, int64_t tick) {
  v1::SwingEvent e;
  e.set_kind(kind);
  e.set_t_s(t_s);
  e.set_swing_id(swing_id);
  e.set_tick(tick);
  return e;
}

// A driver's command waiting for its tick.
struct PendingCommand {
  int64_t n = 0;  // the swing tick from which it applies
  double t_s = 0, qalpha = 0, qbeta = 0;
  uint64_t index = 0;
  bool late = false;
};

}  // namespace

// The swing in progress. Not moved after creation: the stepper points at its model and program.
struct SwingRun {
  sw::SwingModel model;
  sw::TorqueProgram program;
  std::optional<sw::SwingStepper> stepper;
  sw::StepRecord record;
  bool driven = false;
  sw::SwingStop stop = sw::SwingStop::kImpact;
  double duration_s = kDefaultDurationS;
  int64_t start_tick = 0;  // the session tick at which the swing's time is 0
  uint32_t seat = 0;
  std::optional<sw::SwingSample> impact;
  bool impact_reported = false;
  std::deque<PendingCommand> pending;     // driven: in time order
  std::shared_ptr<SwingWatcher> driver;   // driven: the driver's stream, while it lasts
  double qalpha = 0, qbeta = 0;           // driven: the torques in force
  bool beyond_flagged = false;

  SwingRun(const sw::SwingModel& m, sw::TorqueProgram p) : model(m), program(std::move(p)) {}
};

struct Session : Ticked, std::enable_shared_from_this<Session> {
  explicit Session(SessionRegistry* r) : registry(r) {}
  void Wake(uint64_t generation, SteadyClock::time_point now) override {
    registry->Process(shared_from_this(), generation, now);
  }

  SessionRegistry* const registry;
  // Fixed at creation.
  std::string id;
  google::protobuf::RepeatedField<int> disabled_effects;
  sw::SwingSolverOptions solver;
  bool realistic = true;
  std::optional<StrikeJob> strike;  // CreateSession's `ball`: launched at each impact
  double tick_hz = kDefaultTickHz;
  double period_s = 1.0 / kDefaultTickHz;
  std::vector<SeatEntry> seats;

  absl::Mutex mu;
  TickClock clock ABSL_GUARDED_BY(mu);
  int64_t tick ABSL_GUARDED_BY(mu) = 0;  // last tick advanced or acted on
  uint64_t sequence ABSL_GUARDED_BY(mu) = 0;
  v1::SwingParameters params ABSL_GUARDED_BY(mu);  // as asked (the address position may change)
  std::shared_ptr<const sw::SwingModel> model ABSL_GUARDED_BY(mu);  // at the address position
  v1::SwingPhase phase ABSL_GUARDED_BY(mu) = v1::SWING_PHASE_ADDRESS;
  uint64_t swings ABSL_GUARDED_BY(mu) = 0;  // also the id of the current or last swing
  std::unique_ptr<SwingRun> run ABSL_GUARDED_BY(mu);
  sw::SwingSample state ABSL_GUARDED_BY(mu);  // at the last tick advanced
  double qalpha ABSL_GUARDED_BY(mu) = 0;  // in force at `state`
  double qbeta ABSL_GUARDED_BY(mu) = 0;
  std::optional<sw::SwingSample> last_impact ABSL_GUARDED_BY(mu);
  std::string last_end_reason ABSL_GUARDED_BY(mu);
  EventLog<v1::SwingEvent> log ABSL_GUARDED_BY(mu);
  std::vector<std::shared_ptr<SwingWatcher>> watchers ABSL_GUARDED_BY(mu);
  bool deleted ABSL_GUARDED_BY(mu) = false;
  bool closed ABSL_GUARDED_BY(mu) = false;
  uint64_t wake_generation ABSL_GUARDED_BY(mu) = 0;

  absl::Status Gone() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    if (closed) return Unavailable();
    if (deleted) {
      return absl::NotFoundError(absl::StrFormat("session_id: session %s was deleted", id));
    }
    return absl::OkStatus();
  }
  absl::StatusOr<int> Authorize(const std::string& token) const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    if (absl::Status gone = Gone(); !gone.ok()) return gone;
    const int seat = SeatOf(seats, token);
    if (seat < 0) return absl::PermissionDeniedError("token: not a seat of this session");
    return seat;
  }
  // The tick now: the last one advanced while swinging, else the clock's.
  int64_t NowTick() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    return run != nullptr ? tick : clock.Tick(SteadyClock::now(), tick);
  }
  std::shared_ptr<const SwingFrame> MakeFrame(int64_t k, bool heartbeat, bool ticked = false)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    auto f = std::make_shared<SwingFrame>();
    f->sequence = sequence;
    f->tick = k;
    f->heartbeat = heartbeat;
    f->published = ticked ? clock.Deadline(k) : SteadyClock::now();
    f->phase = phase;
    f->swing_id = swings;
    f->state = state;
    f->qalpha_nm = qalpha;
    f->qbeta_nm = qbeta;
    return f;
  }
  SwingEventPtr Log(v1::SwingEvent e, int event_log) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    return log.Append(std::move(e), sequence, event_log);
  }
  void OfferAll(const std::shared_ptr<const SwingFrame>& frame,
                const std::vector<SwingEventPtr>& fresh,
                std::vector<std::shared_ptr<SwingWatcher>>* pump) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    for (const std::shared_ptr<SwingWatcher>& w : watchers) {
      if (w->Offer(frame, fresh)) pump->push_back(w);
    }
  }
  // The torques a scheduled swing applies at time t.
  void ScheduledTorques(const SwingRun& r, double t) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    const sw::Torques q = r.program.At(r.program.SegmentAt(t), t);
    qalpha = q.q_alpha;
    qbeta = r.model.wrist_torque_on() ? q.q_beta : 0.0;
  }
  void Forget(const SwingWatcher* w) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    watchers.erase(std::remove_if(watchers.begin(), watchers.end(),
                                  [w](const std::shared_ptr<SwingWatcher>& x) {
                                    return x.get() == w;
                                  }),
                   watchers.end());
  }
};

// ---------------------------------------------------------------------------------------------
// Registry

SessionRegistry::SessionRegistry(SessionLimits limits, TickScheduler* scheduler, int workers)
    : limits_(limits), counters_(std::make_shared<WatchCounters>()) {
  if (scheduler == nullptr) {
    own_scheduler_ = std::make_unique<TickScheduler>(workers);
    scheduler = own_scheduler_.get();
  }
  scheduler_ = scheduler;
}

SessionRegistry::~SessionRegistry() { Shutdown(Unavailable()); }

absl::StatusOr<std::shared_ptr<Session>> SessionRegistry::Find(const std::string& id) {
  if (absl::Status s = CheckSessionId(id); !s.ok()) return s;
  absl::MutexLock lock(&mu_);
  if (shut_down_) return Unavailable();
  auto it = sessions_.find(id);
  if (it == sessions_.end()) {
    return absl::NotFoundError(absl::StrFormat("session_id: no session \"%s\"", id));
  }
  return it->second;
}

void SessionRegistry::Schedule(Session& s, SteadyClock::time_point when) {
  scheduler_->Schedule(s.shared_from_this(), ++s.wake_generation, when);
}

absl::StatusOr<v1::CreateSessionResponse> SessionRegistry::Create(
    const v1::CreateSessionRequest& request) {
  const double tick_hz = request.tick_hz() == 0 ? kDefaultTickHz : request.tick_hz();
  if (absl::Status s = CheckFiniteInRange("tick_hz", tick_hz, 1, false, 1000, false); !s.ok()) {
    return s;
  }
  absl::StatusOr<std::vector<SeatEntry>> seats =
      MakeSeats(request.seats(), request.seat_names(), /*default_count=*/1);
  if (!seats.ok()) return seats.status();
  absl::StatusOr<sw::SwingModel> model =
      SwingModelFromProto(request.parameters(), request.disabled_effects());
  if (!model.ok()) return model.status();
  absl::StatusOr<sw::SwingSolverOptions> solver = SwingSolverFromProto(request.solver());
  if (!solver.ok()) return solver.status();
  if (request.profile() != v1::REALISM_PROFILE_UNSPECIFIED &&
      request.profile() != v1::REALISM_PROFILE_REALISTIC &&
      request.profile() != v1::REALISM_PROFILE_ARCADE) {
    return absl::InvalidArgumentError(
        absl::StrFormat("profile: unknown profile %d", request.profile()));
  }

  std::optional<StrikeJob> strike;
  if (request.has_ball()) {
    v1::BallStrike ball = request.ball();
    // A stream event should stay small: ~70 samples for a 7 s flight, not 700, and never the
    // ~580 kB of 1 ms samples (events are kept for resuming watchers).
    if (!ball.has_sample_interval_s()) ball.set_sample_interval_s(0.1);
    if (!(ball.sample_interval_s() >= kMinSessionFlightSampleS)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "ball.sample_interval_s must be at least %g s in a session, got %g",
          kMinSessionFlightSampleS, ball.sample_interval_s()));
    }
    absl::StatusOr<StrikeJob> job = StrikeJobFromProto(ball);
    if (!job.ok()) return job.status();
    strike = *std::move(job);
  }

  auto session = std::make_shared<Session>(this);
  session->strike = std::move(strike);
  session->tick_hz = tick_hz;
  session->period_s = 1.0 / tick_hz;
  session->disabled_effects = request.disabled_effects();
  session->solver = *solver;
  session->realistic = request.profile() != v1::REALISM_PROFILE_ARCADE;
  session->seats = *std::move(seats);
  v1::CreateSessionResponse response;
  SeatsToProto(session->seats, /*with_tokens=*/true, response.mutable_seats());
  {
    absl::MutexLock lock(&session->mu);
    session->clock.tick_hz = tick_hz;
    session->clock.origin = SteadyClock::now();
    session->params = request.parameters();
    session->model = std::make_shared<const sw::SwingModel>(*model);
    session->state = sw::MakeSample(*model, 0.0, sw::SwingStepper::InitialState(*model));
  }
  absl::MutexLock lock(&mu_);
  if (shut_down_) return Unavailable();
  if (static_cast<int>(sessions_.size()) >= limits_.max_sessions) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "the server holds its maximum of %d sessions (--max_sessions)", limits_.max_sessions));
  }
  do {
    session->id = "s-" + RandomHex(6);
  } while (sessions_.count(session->id) > 0);
  sessions_[session->id] = session;
  response.set_session_id(session->id);
  response.set_token(session->seats[0].token);
  response.set_tick_hz(tick_hz);
  response.set_integrator(std::string(sw::SwingIntegratorName(solver->integrator)));
  response.set_tick(0);
  response.set_profile(session->realistic ? "realistic" : "arcade");
  return response;
}

absl::StatusOr<v1::SessionInfo> SessionRegistry::Get(const v1::GetSessionRequest& request) {
  absl::StatusOr<std::shared_ptr<Session>> found = Find(request.session_id());
  if (!found.ok()) return found.status();
  Session& s = **found;
  absl::MutexLock lock(&s.mu);
  v1::SessionInfo info;
  info.set_session_id(s.id);
  info.set_tick_hz(s.tick_hz);
  info.set_tick(s.NowTick());
  info.set_sequence(s.sequence);
  info.set_phase(s.phase);
  info.set_swing_id(s.swings);
  info.set_swings(s.swings);
  SampleToProto(s.state, info.mutable_state());
  if (s.last_impact) ImpactToProto(*s.last_impact, info.mutable_last_impact());
  SeatsToProto(s.seats, /*with_tokens=*/false, info.mutable_seats());
  info.set_watchers(static_cast<uint32_t>(s.watchers.size()));
  info.set_integrator(std::string(sw::SwingIntegratorName(s.solver.integrator)));
  if (s.solver.integrator != sw::SwingIntegrator::kDp45) {
    info.set_dt_s(s.solver.dt_s.value_or(sw::SwingSolverOptions::kDefaultDt));
  }
  info.set_profile(s.realistic ? "realistic" : "arcade");
  // As given (degrees to radians and back need not round-trip), else the default.
  info.set_gamma_deg(s.params.has_gamma_deg() ? s.params.gamma_deg()
                                              : RadToDeg(s.model->params().gamma_rad));
  info.set_beta0_deg(s.params.has_beta0_deg() ? s.params.beta0_deg()
                                              : RadToDeg(s.model->params().beta0_rad));
  info.set_last_end_reason(s.last_end_reason);
  return info;
}

absl::StatusOr<v1::ListSessionsResponse> SessionRegistry::List(
    const v1::ListSessionsRequest& request) {
  if (request.page_size() > 1000) {
    return absl::InvalidArgumentError(
        absl::StrFormat("page_size must be in [0, 1000], got %d", request.page_size()));
  }
  const size_t page = request.page_size() == 0 ? 100 : request.page_size();
  std::vector<std::shared_ptr<Session>> sessions;
  v1::ListSessionsResponse response;
  {
    absl::MutexLock lock(&mu_);
    if (shut_down_) return Unavailable();
    response.set_total(static_cast<uint32_t>(sessions_.size()));
    for (auto it = sessions_.upper_bound(request.page_token());
         it != sessions_.end() && sessions.size() <= page; ++it) {
      sessions.push_back(it->second);
    }
  }
  if (sessions.size() > page) {
    sessions.pop_back();
    response.set_next_page_token(sessions.back()->id);
  }
  for (const std::shared_ptr<Session>& p : sessions) {
    Session& s = *p;
    absl::MutexLock lock(&s.mu);
    v1::SessionBrief* brief = response.add_sessions();
    brief->set_session_id(s.id);
    brief->set_phase(s.phase);
    brief->set_tick(s.NowTick());
    brief->set_swings(s.swings);
    brief->set_watchers(static_cast<uint32_t>(s.watchers.size()));
    brief->set_tick_hz(s.tick_hz);
  }
  return response;
}

// Ends the swing in progress: phase FINISHED, an ENDED event, and the driver's stream closed
// after the frame the caller offers next. Commands still waiting for their tick are refused on
// the driver's stream (FAILED_PRECONDITION), so a client that sent its schedule ahead learns
// which ones never took effect.
void SessionRegistry::EndSwing(Session& s, const std::string& reason,
                               std::vector<SwingEventPtr>* fresh,
                               std::shared_ptr<SwingWatcher>* driver) {
  SwingRun& r = *s.run;
  if (r.driver != nullptr && !r.pending.empty()) {
    std::vector<SwingEventPtr> leftovers;
    for (const PendingCommand& c : r.pending) {
      v1::SwingEvent e = SwingEvent(v1::SWING_EVENT_COMMAND_REFUSED, s.state.t_s, s.swings, s.tick);
      e.set_sequence(s.sequence);
      e.set_command(c.index);
      e.set_command_t_s(c.t_s);
      e.set_qalpha_nm(c.qalpha);
      e.set_qbeta_nm(c.qbeta);
      e.set_seat(r.seat);
      e.set_code(static_cast<int32_t>(absl::StatusCode::kFailedPrecondition));
      e.set_reason(absl::StrFormat("command %d: the swing ended (%s) before its tick", c.index,
                                   reason));
      leftovers.push_back(std::make_shared<const v1::SwingEvent>(std::move(e)));
      refused_.fetch_add(1);
      refused_by_code_[static_cast<size_t>(absl::StatusCode::kFailedPrecondition)].fetch_add(1);
    }
    r.driver->Offer(nullptr, leftovers);  // they ride with the last frame, before ENDED
  }
  v1::SwingEvent e = SwingEvent(v1::SWING_EVENT_ENDED, s.state.t_s, s.swings, s.tick);
  e.set_reason(reason);
  e.set_seat(r.seat);
  fresh->push_back(s.Log(std::move(e), limits_.event_log));
  s.last_end_reason = reason;
  s.phase = v1::SWING_PHASE_FINISHED;
  *driver = std::move(r.driver);
  s.run.reset();
  swinging_.fetch_sub(1);
}

absl::Status SessionRegistry::Delete(const v1::DeleteSessionRequest& request) {
  if (absl::Status s = CheckSessionId(request.session_id()); !s.ok()) return s;
  if (absl::Status s = CheckToken(request.token(), "CreateSession"); !s.ok()) return s;
  std::shared_ptr<Session> session;
  {
    absl::MutexLock lock(&mu_);
    if (shut_down_) return Unavailable();
    auto it = sessions_.find(request.session_id());
    if (it == sessions_.end()) {
      return absl::NotFoundError(
          absl::StrFormat("session_id: no session \"%s\"", request.session_id()));
    }
    session = it->second;
    {
      absl::MutexLock slock(&session->mu);
      if (SeatOf(session->seats, request.token()) < 0) {
        return absl::PermissionDeniedError("token: not a seat of this session");
      }
    }
    sessions_.erase(it);
  }
  std::vector<std::shared_ptr<SwingWatcher>> pump;
  {
    absl::MutexLock lock(&session->mu);
    session->deleted = true;
    std::vector<SwingEventPtr> fresh;
    if (session->run != nullptr) {
      ++session->sequence;
      std::shared_ptr<SwingWatcher> driver;  // closed below with the others
      EndSwing(*session, "deleted", &fresh, &driver);
    }
    const auto last = session->MakeFrame(session->NowTick(), false);
    const absl::Status gone = absl::NotFoundError(
        absl::StrFormat("session_id: session %s was deleted", session->id));
    for (const std::shared_ptr<SwingWatcher>& w : session->watchers) {
      w->Offer(nullptr, fresh);  // the ENDED event rides with the last snapshot
      if (w->Close(gone, last)) pump.push_back(w);
    }
  }
  for (const auto& w : pump) w->Pump();
  return absl::OkStatus();
}

namespace {

// Checks a swing's run options and, for the realistic profile, the torques of its schedule.
absl::Status CheckProgram(const sw::TorqueProgram& program, bool realistic) {
  if (!realistic) return absl::OkStatus();
  const auto check = [](const sw::TorqueSchedule& s, const char* name, double limit) {
    for (size_t i = 0; i < s.knots.size(); ++i) {
      if (absl::Status st = sw::CheckHumanTorque(
              absl::StrFormat("torques.%s.knots[%d].torque_nm", name, i), s.knots[i].torque_nm,
              limit);
          !st.ok()) {
        return st;
      }
    }
    return absl::OkStatus();
  };
  if (absl::Status s = check(program.q_alpha(), "qalpha", sw::kHumanLimits.max_shoulder_torque_nm);
      !s.ok()) {
    return s;
  }
  return check(program.q_beta(), "qbeta", sw::kHumanLimits.max_wrist_torque_nm);
}

absl::StatusOr<std::pair<sw::SwingStop, double>> StopFromProto(v1::SwingStop stop,
                                                               bool has_duration, double duration,
                                                               std::string_view prefix) {
  if (stop != v1::SWING_STOP_UNSPECIFIED && stop != v1::SWING_STOP_IMPACT &&
      stop != v1::SWING_STOP_DURATION) {
    return absl::InvalidArgumentError(absl::StrFormat("%sstop: unknown stop %d", prefix, stop));
  }
  const double d = has_duration ? duration : kDefaultDurationS;
  if (absl::Status s = sw::ValidateDuration(d); !s.ok()) return PrefixStatus(prefix, s);
  return std::make_pair(stop == v1::SWING_STOP_DURATION ? sw::SwingStop::kDuration
                                                        : sw::SwingStop::kImpact,
                        d);
}

}  // namespace

// Starts a swing at the next tick. The caller checked that none is in progress.
static void BeginSwing(Session& s, std::unique_ptr<SwingRun> run, uint32_t seat, int event_log,
                       std::vector<SwingEventPtr>* fresh) ABSL_EXCLUSIVE_LOCKS_REQUIRED(s.mu) {
  const int64_t start = s.clock.Tick(SteadyClock::now(), s.tick) + 1;
  s.tick = start;
  run->start_tick = start;
  run->seat = seat;
  absl::StatusOr<sw::SwingStepper> stepper =
      sw::SwingStepper::Create(&run->model, &run->program, s.solver);
  // The solver was validated when the session was created.
  run->stepper.emplace(*std::move(stepper));
  ++s.swings;
  ++s.sequence;
  s.phase = v1::SWING_PHASE_SWINGING;
  s.state = sw::MakeSample(run->model, 0.0, run->stepper->y());
  if (run->driven) {
    s.qalpha = run->qalpha;
    s.qbeta = run->model.wrist_torque_on() ? run->qbeta : 0.0;
  } else {
    s.ScheduledTorques(*run, 0.0);
  }
  v1::SwingEvent e = SwingEvent(v1::SWING_EVENT_STARTED, 0.0, s.swings, start);
  e.set_seat(seat);
  e.set_driven(run->driven);
  e.set_qalpha_nm(s.qalpha);
  e.set_qbeta_nm(s.qbeta);
  fresh->push_back(s.Log(std::move(e), event_log));
  s.run = std::move(run);
}

absl::StatusOr<v1::StartSwingResponse> SessionRegistry::Start(const v1::StartSwingRequest& request) {
  if (absl::Status s = CheckToken(request.token(), "CreateSession"); !s.ok()) return s;
  absl::StatusOr<std::shared_ptr<Session>> found = Find(request.session_id());
  if (!found.ok()) return found.status();
  Session& s = **found;
  absl::StatusOr<sw::TorqueProgram> program =
      TorqueProgramFromProto(request.torques(), request.has_torques());
  if (!program.ok()) return program.status();
  absl::StatusOr<std::pair<sw::SwingStop, double>> stop =
      StopFromProto(request.stop(), request.has_duration_s(), request.duration_s(), "");
  if (!stop.ok()) return stop.status();
  std::shared_ptr<const sw::SwingModel> model;
  {
    absl::MutexLock lock(&s.mu);
    if (absl::StatusOr<int> seat = s.Authorize(request.token()); !seat.ok()) return seat.status();
    if (s.run != nullptr) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "a swing is in progress (swing %d); wait for its end or ResetSwing", s.swings));
    }
    model = s.model;
  }
  if (absl::Status st = CheckProgram(*program, s.realistic); !st.ok()) return st;
  // A dry run, off the session's lock: the swing this program makes is known before it starts,
  // so one the solver cannot resolve, or (realistic) one no human could make, is refused here
  // and changes nothing. It costs what the swing itself will.
  {
    sw::SwingRunOptions run;
    run.stop = stop->first;
    run.duration_s = stop->second;
    if (s.solver.integrator == sw::SwingIntegrator::kDp45) {
      run.sample_interval_s = run.duration_s / 4000.0;
    } else {
      const double steps =
          run.duration_s / s.solver.dt_s.value_or(sw::SwingSolverOptions::kDefaultDt);
      run.sample_stride = std::max(1, static_cast<int>(std::ceil(steps / 4000.0)));
    }
    absl::StatusOr<sw::SwingRunResult> dry = sw::SimulateSwing(*model, *program, s.solver, run);
    if (!dry.ok()) return PrefixStatus("torques: ", dry.status());
    if (s.realistic) {
      const sw::SwingSample* fastest = nullptr;
      for (const sw::SwingSample& x : dry->samples) {
        if (fastest == nullptr || x.clubhead_speed_ground_mps > fastest->clubhead_speed_ground_mps) {
          fastest = &x;
        }
      }
      if (dry->impact && dry->impact->clubhead_speed_ground_mps >
                             (fastest != nullptr ? fastest->clubhead_speed_ground_mps : 0.0)) {
        fastest = &*dry->impact;
      }
      if (fastest != nullptr &&
          fastest->clubhead_speed_ground_mps > sw::kHumanLimits.max_clubhead_speed_mps) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "torques: this swing brings the clubhead to %.1f m/s at t = %.3f s, beyond what a "
            "human golfer reaches (realistic profile: %g m/s; the long-drive record is about "
            "67 m/s); use the arcade profile to lift the bound",
            fastest->clubhead_speed_ground_mps, fastest->t_s,
            sw::kHumanLimits.max_clubhead_speed_mps));
      }
    }
  }
  std::vector<std::shared_ptr<SwingWatcher>> pump;
  v1::StartSwingResponse response;
  {
    absl::MutexLock lock(&s.mu);
    absl::StatusOr<int> seat = s.Authorize(request.token());
    if (!seat.ok()) return seat.status();
    if (s.run != nullptr || s.model != model) {
      return absl::FailedPreconditionError(
          "the session started another swing or was reset while this one was checked; try again");
    }
    auto run = std::make_unique<SwingRun>(*model, *std::move(program));
    run->stop = stop->first;
    run->duration_s = stop->second;
    std::vector<SwingEventPtr> fresh;
    BeginSwing(s, std::move(run), static_cast<uint32_t>(*seat), limits_.event_log, &fresh);
    swinging_.fetch_add(1);
    events_.fetch_add(static_cast<int64_t>(fresh.size()));
    s.OfferAll(s.MakeFrame(s.tick, false), fresh, &pump);
    Schedule(s, s.clock.Deadline(s.tick + 1));
    response.set_swing_id(s.swings);
    response.set_start_tick(s.tick);
    response.set_sequence(s.sequence);
  }
  for (const auto& w : pump) w->Pump();
  return response;
}

absl::StatusOr<v1::ResetSwingResponse> SessionRegistry::Reset(const v1::ResetSwingRequest& request) {
  if (absl::Status s = CheckToken(request.token(), "CreateSession"); !s.ok()) return s;
  absl::StatusOr<std::shared_ptr<Session>> found = Find(request.session_id());
  if (!found.ok()) return found.status();
  Session& s = **found;
  std::vector<std::shared_ptr<SwingWatcher>> pump;
  v1::ResetSwingResponse response;
  {
    absl::MutexLock lock(&s.mu);
    absl::StatusOr<int> seat = s.Authorize(request.token());
    if (!seat.ok()) return seat.status();
    v1::SwingParameters params = s.params;
    if (request.has_gamma_deg()) params.set_gamma_deg(request.gamma_deg());
    if (request.has_beta0_deg()) params.set_beta0_deg(request.beta0_deg());
    absl::StatusOr<sw::SwingModel> model = SwingModelFromProto(params, s.disabled_effects);
    if (!model.ok()) return model.status();
    const int64_t tick = s.NowTick();
    s.tick = tick;
    ++s.sequence;
    std::vector<SwingEventPtr> fresh;
    std::shared_ptr<SwingWatcher> driver;
    if (s.run != nullptr) {
      EndSwing(s, "reset", &fresh, &driver);
    }
    s.params = params;
    s.model = std::make_shared<const sw::SwingModel>(*model);
    s.phase = v1::SWING_PHASE_ADDRESS;
    s.state = sw::MakeSample(*model, 0.0, sw::SwingStepper::InitialState(*model));
    s.qalpha = s.qbeta = 0.0;
    v1::SwingEvent e = SwingEvent(v1::SWING_EVENT_RESET, 0.0, s.swings, tick);
    e.set_seat(static_cast<uint32_t>(*seat));
    fresh.push_back(s.Log(std::move(e), limits_.event_log));
    events_.fetch_add(static_cast<int64_t>(fresh.size()));
    const auto frame = s.MakeFrame(tick, false);
    s.OfferAll(frame, fresh, &pump);
    if (driver != nullptr) {
      s.Forget(driver.get());
      if (driver->Close(absl::OkStatus(), nullptr)) pump.push_back(driver);
    }
    if (!s.watchers.empty()) {
      Schedule(s, SteadyClock::now() + absl::ToChronoNanoseconds(limits_.heartbeat));
    }
    response.set_sequence(s.sequence);
    response.set_tick(tick);
  }
  for (const auto& w : pump) w->Pump();
  return response;
}

absl::StatusOr<std::shared_ptr<SwingWatcher>> SessionRegistry::Watch(
    const v1::WatchSwingRequest& request, SwingSink* sink) {
  absl::StatusOr<std::shared_ptr<Session>> found = Find(request.session_id());
  if (!found.ok()) return found.status();
  Session& s = **found;
  double interval_ticks = 1.0;
  if (request.rate_hz() != 0) {
    if (absl::Status st = CheckFiniteInRange("rate_hz", request.rate_hz(), 0, true, 1000, false);
        !st.ok()) {
      return st;
    }
    interval_ticks = std::max(1.0, s.tick_hz / request.rate_hz());
  }
  auto watcher = std::make_shared<SwingWatcher>(s.id, SwingWatchOptions{}, interval_ticks,
                                                limits_.watcher_backlog, counters_);
  watcher->Attach(sink);
  absl::MutexLock lock(&s.mu);
  if (absl::Status gone = s.Gone(); !gone.ok()) return gone;
  if (static_cast<int>(s.watchers.size()) >= limits_.max_watchers_per_session) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "session %s has its maximum of %d watchers (--max_watchers_per_session)", s.id,
        limits_.max_watchers_per_session));
  }
  std::vector<SwingEventPtr> replay;
  if (request.has_from_sequence()) {
    bool lost = false;
    absl::StatusOr<std::vector<SwingEventPtr>> after =
        s.log.After(request.from_sequence(), s.sequence, "session", &lost);
    if (!after.ok()) return after.status();
    if (lost) watcher->MarkResync();
    replay = *std::move(after);
  }
  const int64_t tick = s.NowTick();
  watcher->Due(tick);  // the first snapshot is now
  watcher->Offer(s.MakeFrame(tick, false), replay);
  s.watchers.push_back(watcher);
  if (s.run == nullptr && s.watchers.size() == 1) {
    Schedule(s, SteadyClock::now() + absl::ToChronoNanoseconds(limits_.heartbeat));
  }
  return watcher;
}

void SessionRegistry::Unwatch(const std::string& session_id, const SwingWatcher* watcher) {
  std::shared_ptr<Session> session;
  {
    absl::MutexLock lock(&mu_);
    auto it = sessions_.find(session_id);
    if (it == sessions_.end()) return;
    session = it->second;
  }
  absl::MutexLock lock(&session->mu);
  session->Forget(watcher);
}

absl::StatusOr<std::shared_ptr<Drive>> SessionRegistry::StartDrive(const v1::DriveStart& start,
                                                                   SwingSink* sink) {
  if (absl::Status s = CheckToken(start.token(), "CreateSession"); !s.ok()) {
    return PrefixStatus("start.", s);
  }
  absl::StatusOr<std::shared_ptr<Session>> found = Find(start.session_id());
  if (!found.ok()) return PrefixStatus("start.", found.status());
  const std::shared_ptr<Session>& ptr = *found;
  Session& s = *ptr;
  absl::StatusOr<std::pair<sw::SwingStop, double>> stop =
      StopFromProto(start.stop(), start.has_duration_s(), start.duration_s(), "start.");
  if (!stop.ok()) return stop.status();
  for (const auto& [name, q, limit] :
       {std::tuple{"start.qalpha_nm", start.qalpha_nm(), sw::kHumanLimits.max_shoulder_torque_nm},
        std::tuple{"start.qbeta_nm", start.qbeta_nm(), sw::kHumanLimits.max_wrist_torque_nm}}) {
    if (absl::Status st =
            CheckFiniteInRange(name, q, -sw::TorqueProgram::kMaxTorqueNm, false,
                               sw::TorqueProgram::kMaxTorqueNm, false);
        !st.ok()) {
      return st;
    }
    if (s.realistic) {
      if (absl::Status st = sw::CheckHumanTorque(name, q, limit); !st.ok()) return st;
    }
  }
  double interval_ticks = 1.0;
  if (start.rate_hz() != 0) {
    if (absl::Status st =
            CheckFiniteInRange("start.rate_hz", start.rate_hz(), 0, true, 1000, false);
        !st.ok()) {
      return st;
    }
    interval_ticks = std::max(1.0, s.tick_hz / start.rate_hz());
  }
  auto watcher = std::make_shared<SwingWatcher>(s.id, SwingWatchOptions{}, interval_ticks,
                                                limits_.watcher_backlog, counters_);
  watcher->Attach(sink);
  std::vector<std::shared_ptr<SwingWatcher>> pump;
  auto drive = std::make_shared<Drive>();
  drive->session = ptr;
  drive->watcher = watcher;
  drive->apply_late = start.apply_late();
  {
    absl::MutexLock lock(&s.mu);
    absl::StatusOr<int> seat = s.Authorize(start.token());
    if (!seat.ok()) return PrefixStatus("start.", seat.status());
    if (s.run != nullptr) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "a swing is in progress (swing %d); wait for its end or ResetSwing", s.swings));
    }
    if (static_cast<int>(s.watchers.size()) >= limits_.max_watchers_per_session) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "session %s has its maximum of %d watchers (--max_watchers_per_session)", s.id,
          limits_.max_watchers_per_session));
    }
    auto run = std::make_unique<SwingRun>(
        *s.model, sw::TorqueProgram::Constant(start.qalpha_nm(), start.qbeta_nm()));
    run->driven = true;
    run->stop = stop->first;
    run->duration_s = stop->second;
    run->qalpha = start.qalpha_nm();
    run->qbeta = start.qbeta_nm();
    run->driver = watcher;
    s.watchers.push_back(watcher);
    std::vector<SwingEventPtr> fresh;
    BeginSwing(s, std::move(run), static_cast<uint32_t>(*seat), limits_.event_log, &fresh);
    swinging_.fetch_add(1);
    events_.fetch_add(static_cast<int64_t>(fresh.size()));
    watcher->Due(s.tick);
    s.OfferAll(s.MakeFrame(s.tick, false), fresh, &pump);
    Schedule(s, s.clock.Deadline(s.tick + 1));
    drive->swing_id = s.swings;
    drive->seat = *seat;
  }
  // The others are pumped here, with no lock held; the caller pumps its own stream once it is
  // ready.
  for (const auto& w : pump) {
    if (w != watcher) w->Pump();
  }
  return drive;
}

void SessionRegistry::Refuse(Drive& drive, const absl::Status& why,
                             const v1::TorqueCommand* command) {
  Session& s = *drive.session;
  bool pump = false;
  {
    absl::MutexLock lock(&s.mu);
    v1::SwingEvent e = SwingEvent(v1::SWING_EVENT_COMMAND_REFUSED, s.state.t_s, drive.swing_id,
                                  s.tick);
    e.set_sequence(s.sequence);
    e.set_command(++drive.commands);
    e.set_code(static_cast<int32_t>(why.code()));
    e.set_reason(std::string(why.message()));
    e.set_seat(static_cast<uint32_t>(drive.seat));
    if (command != nullptr) {
      e.set_command_t_s(command->t_s());
      e.set_qalpha_nm(command->qalpha_nm());
      e.set_qbeta_nm(command->qbeta_nm());
    }
    refused_.fetch_add(1);
    refused_by_code_[std::clamp(static_cast<int>(why.code()), 0, 16)].fetch_add(1);
    pump = drive.watcher->Offer(nullptr, {std::make_shared<const v1::SwingEvent>(std::move(e))});
  }
  if (pump) drive.watcher->Pump();
}

void SessionRegistry::Command(Drive& drive, const v1::TorqueCommand& c) {
  Session& s = *drive.session;
  absl::Status refused;
  {
    absl::MutexLock lock(&s.mu);
    SwingRun* r = s.run.get();
    const uint64_t index = drive.commands + 1;
    const auto refuse = [&](absl::Status st) {
      refused = std::move(st);
    };
    if (r == nullptr || s.swings != drive.swing_id || r->driver != drive.watcher) {
      refuse(absl::FailedPreconditionError("the swing this stream drove has ended"));
    } else if (!std::isfinite(c.t_s()) || !std::isfinite(c.qalpha_nm()) ||
               !std::isfinite(c.qbeta_nm())) {
      refuse(absl::InvalidArgumentError(absl::StrFormat(
          "command %d: t_s, qalpha_nm and qbeta_nm must be finite, got %g, %g, %g", index,
          c.t_s(), c.qalpha_nm(), c.qbeta_nm())));
    } else if (c.t_s() < 0 || c.t_s() > r->duration_s) {
      refuse(absl::OutOfRangeError(absl::StrFormat(
          "command %d: t_s must be in [0, %g] s (the swing's duration), got %g", index,
          r->duration_s, c.t_s())));
    } else if (std::abs(c.qalpha_nm()) > sw::TorqueProgram::kMaxTorqueNm ||
               std::abs(c.qbeta_nm()) > sw::TorqueProgram::kMaxTorqueNm) {
      refuse(absl::InvalidArgumentError(absl::StrFormat(
          "command %d: |torque| must be at most %g N m, got %g and %g", index,
          sw::TorqueProgram::kMaxTorqueNm, c.qalpha_nm(), c.qbeta_nm())));
    } else if (absl::Status st = s.realistic ? sw::CheckHumanTorque(
                                                   absl::StrFormat("command %d: qalpha_nm", index),
                                                   c.qalpha_nm(),
                                                   sw::kHumanLimits.max_shoulder_torque_nm)
                                             : absl::OkStatus();
               !st.ok()) {
      refuse(st);
    } else if (absl::Status st2 = s.realistic ? sw::CheckHumanTorque(
                                                    absl::StrFormat("command %d: qbeta_nm", index),
                                                    c.qbeta_nm(),
                                                    sw::kHumanLimits.max_wrist_torque_nm)
                                              : absl::OkStatus();
               !st2.ok()) {
      refuse(st2);
    } else if (c.t_s() < drive.last_t_s) {
      refuse(absl::OutOfRangeError(absl::StrFormat(
          "command %d: t_s %g s is before the previous command's %g s (commands are applied in "
          "the order of their times, never reordered)",
          index, c.t_s(), drive.last_t_s)));
    } else if (static_cast<int>(r->pending.size()) >= limits_.max_pending_commands) {
      refuse(absl::ResourceExhaustedError(absl::StrFormat(
          "command %d: %d commands are already waiting for their ticks", index,
          limits_.max_pending_commands)));
    } else {
      // Applied from the first tick at or after its time; the state at the last tick
      // advanced (swing tick `done`) is known, what follows it is not.
      int64_t n = static_cast<int64_t>(std::ceil(c.t_s() * s.tick_hz - kSnapTicks));
      const int64_t done = s.tick - r->start_tick;
      // The swing ends at the first tick at or after its duration; a command from there on
      // would never act.
      const int64_t last =
          static_cast<int64_t>(std::ceil(r->duration_s * s.tick_hz - kSnapTicks)) - 1;
      bool late = false;
      if (n > last) {
        refuse(absl::OutOfRangeError(absl::StrFormat(
            "command %d: t_s %g s is at or after the swing's last tick (duration %g s)", index,
            c.t_s(), r->duration_s)));
      } else if (n < done) {
        if (!drive.apply_late) {
          refuse(absl::OutOfRangeError(absl::StrFormat(
              "command %d: late: t_s %g s was already simulated (the swing is at %g s); not "
              "applied (DriveStart.apply_late applies late commands at the next tick)",
              index, c.t_s(), static_cast<double>(done) * s.period_s)));
        }
        n = done;
        late = true;
      }
      if (refused.ok()) {
        ++drive.commands;
        drive.last_t_s = c.t_s();
        r->pending.push_back(PendingCommand{.n = n, .t_s = c.t_s(), .qalpha = c.qalpha_nm(),
                                            .qbeta = c.qbeta_nm(), .index = drive.commands,
                                            .late = late});
        return;
      }
    }
  }
  // Refused: reported on the driver's stream; nothing else changes.
  Refuse(drive, refused, &c);
}

void SessionRegistry::EndDrive(Drive& drive, bool half_closed) {
  Session& s = *drive.session;
  bool pump = false;
  {
    absl::MutexLock lock(&s.mu);
    if (drive.ended) return;
    drive.ended = true;
    if (s.run != nullptr && s.run->driver == drive.watcher) {
      s.run->driver = nullptr;
      // Half-closed: "no more commands", the queued ones stand. Gone: the controller that
      // sent them is gone too; the torques in force hold.
      if (!half_closed) s.run->pending.clear();
    }
    s.Forget(drive.watcher.get());
    if (half_closed) {
      pump = drive.watcher->Close(absl::OkStatus(), s.MakeFrame(s.NowTick(), false));
    }
  }
  if (pump) drive.watcher->Pump();
}

namespace {

// Advances the swing to session tick k: applies the driver's commands due, steps, finds the
// impact, and sets the session's state. Returns the end reason when the swing ended.
std::optional<std::string> AdvanceSwing(Session& s, int64_t k, std::vector<v1::SwingEvent>* out,
                                        int64_t* commands) ABSL_EXCLUSIVE_LOCKS_REQUIRED(s.mu) {
  SwingRun& r = *s.run;
  sw::SwingStepper& stepper = *r.stepper;
  const int64_t n = k - r.start_tick;
  const double tau = static_cast<double>(n) * s.period_s;
  const double snap = kSnapTicks * s.period_s;
  while (r.driven && !r.pending.empty() && r.pending.front().n <= n - 1) {
    const PendingCommand c = r.pending.front();
    r.pending.pop_front();
    r.program = sw::TorqueProgram::Constant(c.qalpha, c.qbeta);
    stepper.ProgramChanged(&r.program);
    r.qalpha = c.qalpha;
    r.qbeta = c.qbeta;
    ++*commands;
    v1::SwingEvent e = SwingEvent(v1::SWING_EVENT_TORQUE, stepper.t(), s.swings, k - 1);
    e.set_qalpha_nm(c.qalpha);
    e.set_qbeta_nm(c.qbeta);
    e.set_command_t_s(c.t_s);
    e.set_command(c.index);
    e.set_seat(r.seat);
    if (c.late) {
      e.set_reason(absl::StrFormat("late: asked for t = %g s, applied at t = %g s", c.t_s,
                                   stepper.t()));
    }
    out->push_back(std::move(e));
  }
  std::optional<std::string> ended;
  bool at_impact = false;
  // An impact is reported at the first tick at or after its time (a step may carry past the
  // tick it was taken for: dp45, or a step that does not divide the tick period).
  const auto report_impact = [&] {
    v1::SwingEvent e = SwingEvent(v1::SWING_EVENT_IMPACT, r.impact->t_s, s.swings, k);
    ImpactToProto(*r.impact, e.mutable_impact());
    // The ball's flight (~1 ms of CPU for a 7 s flight at the default 1 ms step) runs here, on
    // the tick, once per swing.
    if (s.strike) LaunchBall(*s.strike, *r.impact, e.mutable_ball());
    e.set_seat(r.seat);
    out->push_back(std::move(e));
    r.impact_reported = true;
    s.last_impact = r.impact;
    if (r.stop == sw::SwingStop::kImpact) {
      ended = "impact";
      at_impact = true;
    }
  };
  if (r.impact && !r.impact_reported && r.impact->t_s <= tau + snap) report_impact();
  const double limit = r.driven ? std::min(tau, r.duration_s) : r.duration_s;
  while (!ended && stepper.t() < tau - snap && stepper.t() < r.duration_s) {
    if (absl::Status st = stepper.Step(limit, &r.record); !st.ok()) {
      ended = absl::StrFormat("error: %s", st.message());
      break;
    }
    // Checked where SimulateSwing checks it (every kCancelPollSteps steps), so that a swing
    // its dry run accepted never fails here.
    if (s.solver.integrator == sw::SwingIntegrator::kDp45 &&
        stepper.steps() % sw::SwingRunOptions::kCancelPollSteps == 0 &&
        stepper.steps() >= sw::SwingRunOptions::kMaxAdaptiveSteps) {
      ended = absl::StrFormat(
          "error: the swing took %d steps by t = %.6g s: loosen the tolerance or raise "
          "max_step_s",
          stepper.steps(), stepper.t());
      break;
    }
    if (!r.impact) {
      if (auto hit = sw::FindImpactInStep(stepper, r.record)) {
        r.impact = sw::MakeSample(r.model, hit->first, hit->second);
        if (hit->first <= tau + snap) report_impact();
        // Stopping at impact, SimulateSwing takes no step after this one; neither do we.
        if (r.stop == sw::SwingStop::kImpact) break;
      }
    }
  }
  // The duration's end, at the first tick at or after it.
  if (!ended && stepper.t() >= r.duration_s && r.duration_s <= tau + snap) ended = "duration";
  if (at_impact) {
    s.state = *r.impact;
  } else if (ended && ended->rfind("error", 0) == 0) {
    // The state stays the last good one.
  } else if (stepper.t() <= tau + snap) {
    s.state = sw::MakeSample(r.model, stepper.t(), stepper.y());
  } else {
    // A step overshot the tick (dp45, or a step that does not divide the tick period): the
    // state at the tick's time, on the step's interpolant.
    s.state = sw::MakeSample(r.model, tau, stepper.Interpolate(r.record, tau));
  }
  if (r.driven) {
    s.qalpha = r.qalpha;
    s.qbeta = r.model.wrist_torque_on() ? r.qbeta : 0.0;
  } else {
    s.ScheduledTorques(r, s.state.t_s);
  }
  if (s.realistic && !r.beyond_flagged &&
      s.state.clubhead_speed_ground_mps > sw::kHumanLimits.max_clubhead_speed_mps) {
    r.beyond_flagged = true;
    v1::SwingEvent e = SwingEvent(v1::SWING_EVENT_BEYOND_HUMAN, s.state.t_s, s.swings, k);
    e.set_reason(absl::StrFormat(
        "the clubhead reached %.1f m/s, beyond what a human golfer reaches (realistic profile: "
        "%g m/s; the long-drive record is about 67 m/s)",
        s.state.clubhead_speed_ground_mps, sw::kHumanLimits.max_clubhead_speed_mps));
    e.set_seat(r.seat);
    out->push_back(std::move(e));
  }
  return ended;
}

}  // namespace

void SessionRegistry::Process(const std::shared_ptr<Session>& ptr, uint64_t generation,
                              SteadyClock::time_point now) {
  Session& s = *ptr;
  std::vector<std::shared_ptr<SwingWatcher>> pump;
  {
    absl::MutexLock lock(&s.mu);
    if (s.deleted || s.closed || generation != s.wake_generation) return;  // superseded
    if (s.run == nullptr) {
      // At rest: a heartbeat for the watchers, then sleep until the next one.
      if (s.watchers.empty()) return;
      const auto beat = s.MakeFrame(s.clock.Tick(now, s.tick), true);
      for (const auto& w : s.watchers) {
        if (w->OfferHeartbeat(beat)) pump.push_back(w);
      }
      Schedule(s, now + absl::ToChronoNanoseconds(limits_.heartbeat));
    } else {
      const int64_t due = s.clock.DueTick(now);
      if (due <= s.tick) {
        Schedule(s, s.clock.Deadline(s.tick + 1));
      } else {
        int64_t slipped = 0;
        const int64_t target = s.clock.CatchUp(s.tick, due, limits_.max_catchup_ticks, &slipped);
        if (slipped > 0) slipped_ticks_.fetch_add(slipped);
        // Tick by tick: commands apply at their own tick, and the tick a swing ends on does
        // not depend on how many ticks one visit covers.
        std::vector<v1::SwingEvent> events;
        std::optional<std::string> ended;
        int64_t applied = 0;
        int64_t k = s.tick;
        while (k < target && !ended) {
          ++k;
          ended = AdvanceSwing(s, k, &events, &applied);
        }
        const int64_t late = std::min(k, due - 1) - s.tick;
        if (late > 0) late_ticks_.fetch_add(late);
        ticks_.fetch_add(k - s.tick);
        if (applied > 0) commands_.fetch_add(applied);
        s.tick = k;
        ++s.sequence;
        std::vector<SwingEventPtr> fresh;
        for (v1::SwingEvent& e : events) fresh.push_back(s.Log(std::move(e), limits_.event_log));
        std::shared_ptr<SwingWatcher> driver;
        if (ended) {
          EndSwing(s, *ended, &fresh, &driver);
        }
        events_.fetch_add(static_cast<int64_t>(fresh.size()));
        std::shared_ptr<const SwingFrame> frame;
        for (const auto& w : s.watchers) {
          const bool due_now = w->Due(k) || ended.has_value();
          if (due_now && frame == nullptr) frame = s.MakeFrame(k, false, true);
          if (w->Offer(due_now ? frame : nullptr, fresh)) pump.push_back(w);
        }
        if (driver != nullptr) {
          // The driven swing is over: its stream ends after this last frame.
          s.Forget(driver.get());
          if (driver->Close(absl::OkStatus(), nullptr)) pump.push_back(driver);
        }
        if (!ended) {
          Schedule(s, s.clock.Deadline(s.tick + 1));
        } else if (!s.watchers.empty()) {
          Schedule(s, now + absl::ToChronoNanoseconds(limits_.heartbeat));
        }
      }
    }
  }
  for (const auto& w : pump) w->Pump();
}

void SessionRegistry::Shutdown(const absl::Status& status) {
  std::vector<std::shared_ptr<Session>> sessions;
  {
    absl::MutexLock lock(&mu_);
    if (shut_down_) return;
    shut_down_ = true;
    for (auto& [id, s] : sessions_) sessions.push_back(s);
  }
  std::vector<std::shared_ptr<SwingWatcher>> pump;
  for (const std::shared_ptr<Session>& p : sessions) {
    absl::MutexLock lock(&p->mu);
    p->closed = true;
    const auto last = p->MakeFrame(p->NowTick(), false);
    if (p->run != nullptr) {
      p->run.reset();
      swinging_.fetch_sub(1);
    }
    for (const auto& w : p->watchers) {
      if (w->Close(status, last)) pump.push_back(w);
    }
  }
  for (const auto& w : pump) w->Pump();
  if (own_scheduler_ != nullptr) own_scheduler_->Stop();
}

SessionStats SessionRegistry::stats() const {
  SessionStats st;
  st.ticks = ticks_.load();
  st.late_ticks = late_ticks_.load();
  st.slipped_ticks = slipped_ticks_.load();
  st.events = events_.load();
  st.commands = commands_.load();
  st.commands_refused = refused_.load();
  for (size_t i = 0; i < st.refused_by_code.size(); ++i) st.refused_by_code[i] = refused_by_code_[i].load();
  st.swinging = swinging_.load();
  std::vector<std::shared_ptr<Session>> sessions;
  {
    absl::MutexLock lock(&mu_);
    st.sessions = static_cast<int>(sessions_.size());
    for (const auto& [id, s] : sessions_) sessions.push_back(s);
  }
  for (const auto& s : sessions) {
    absl::MutexLock lock(&s->mu);
    st.watchers += static_cast<int>(s->watchers.size());
  }
  st.snapshots_sent = counters_->sent.load();
  st.snapshots_replaced = counters_->replaced.load();
  st.resyncs = counters_->resyncs.load();
  return st;
}

}  // namespace sportsim::server
