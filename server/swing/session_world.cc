#include "server/swing/session_world.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "absl/strings/str_format.h"
#include "server/world/event_log.h"
#include "server/swing/convert.h"
#include "server/swing/session_checkpoint.h"
#include "server/world/watcher_impl.h"
#include "sportsim/store/v1/journal.pb.h"
#include "server/world/world.h"
#include "sim/swing/live_swing.h"
#include "sim/swing/realism.h"

namespace sportsim::server {

namespace sw = ::sportsim::swing;

// ---------------------------------------------------------------------------------------------
// Watcher

namespace {

v1::SwingPhase PhaseToProto(SessionPhase p) {
  switch (p) {
    case SessionPhase::kAddress: return v1::SWING_PHASE_ADDRESS;
    case SessionPhase::kSwinging: return v1::SWING_PHASE_SWINGING;
    case SessionPhase::kFinished: return v1::SWING_PHASE_FINISHED;
  }
  return v1::SWING_PHASE_UNSPECIFIED;
}

}  // namespace

void SwingWatch::Fill(const SwingWatchOptions& /*options*/, const std::string& session_id,
                      const SwingFrame& frame, const SwingFrame* /*last_sent*/, bool /*full*/,
                      v1::SwingSnapshot* out) {
  out->set_session_id(session_id);
  out->set_tick(frame.tick);
  out->set_phase(PhaseToProto(frame.phase));
  out->set_swing_id(frame.swing_id);
  out->set_heartbeat(frame.heartbeat);
  out->set_qalpha_nm(frame.qalpha_nm);
  out->set_qbeta_nm(frame.qbeta_nm);
  if (!frame.heartbeat) SampleToProto(frame.state, out->mutable_state());
}

template class BasicWatcher<SwingWatch>;

// ---------------------------------------------------------------------------------------------
// The session kind

namespace {

// Flight samples in a session's IMPACT event: at most ~20 a second of flight.
constexpr double kMinSessionFlightSampleS = 0.05;
constexpr double kDefaultTickHz = 400.0;
constexpr double kDefaultDurationS = 2.0;

using SwingEventPtr = SwingWatcher::EventPtr;

v1::SwingEvent SwingEvent(v1::SwingEventKind kind, double t_s, uint64_t swing_id, int64_t tick) {
  v1::SwingEvent e;
  e.set_kind(kind);
  e.set_t_s(t_s);
  e.set_swing_id(swing_id);
  e.set_tick(tick);
  return e;
}

// Starts a swing at the next tick. The caller checked that none is in progress.
void BeginSwing(SessionHost& host, Session& s, std::unique_ptr<sw::LiveSwing> live,
                uint32_t seat, std::vector<SwingEventPtr>* fresh)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(s.mu) {
  const int64_t start = s.ClockTick(SteadyClock::now()) + 1;
  s.tick = start;
  s.start_tick = start;
  s.seat = seat;
  ++s.swings;
  ++s.sequence;
  s.phase = SessionPhase::kSwinging;
  s.state = live->state();
  s.qalpha = live->qalpha_nm();
  s.qbeta = live->qbeta_nm();
  v1::SwingEvent e = SwingEvent(v1::SWING_EVENT_STARTED, 0.0, s.swings, start);
  e.set_seat(seat);
  e.set_driven(live->options().driven);
  e.set_qalpha_nm(s.qalpha);
  e.set_qbeta_nm(s.qbeta);
  fresh->push_back(s.Log(std::move(e)));
  s.live = std::move(live);
  host.RunStarted();
  host.CountEvents(fresh->size());
}

// Ends the swing in progress: phase FINISHED and an ENDED event. Commands still waiting for
// their tick are refused on the driver's stream (FAILED_PRECONDITION), so a client that sent
// its schedule ahead learns which ones never took effect. Returns the driver's stream, which
// the caller closes after the frame it offers next.
std::shared_ptr<SwingWatcher> EndSwing(SessionHost& host, Session& s, const sw::LiveSwingEnd& end,
                                       std::vector<SwingEventPtr>* fresh)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(s.mu) {
  const std::string reason = end.Describe();
  if (s.driver != nullptr && !s.live->pending().empty()) {
    std::vector<SwingEventPtr> leftovers;
    for (const sw::QueuedTorque& c : s.live->pending()) {
      v1::SwingEvent e =
          SwingEvent(v1::SWING_EVENT_COMMAND_REFUSED, s.state.t_s, s.swings, s.tick);
      e.set_sequence(s.sequence);
      e.set_command(c.index);
      e.set_command_t_s(c.t_s);
      e.set_qalpha_nm(c.qalpha_nm);
      e.set_qbeta_nm(c.qbeta_nm);
      e.set_seat(s.seat);
      e.set_code(static_cast<int32_t>(absl::StatusCode::kFailedPrecondition));
      e.set_reason(absl::StrFormat("command %d: the swing ended (%s) before its tick", c.index,
                                   reason));
      leftovers.push_back(std::make_shared<const v1::SwingEvent>(std::move(e)));
      s.counters->Refused(absl::StatusCode::kFailedPrecondition);
    }
    s.driver->Offer(nullptr, leftovers);  // they ride with the last frame, before ENDED
  }
  v1::SwingEvent e = SwingEvent(v1::SWING_EVENT_ENDED, s.state.t_s, s.swings, s.tick);
  e.set_reason(reason);
  e.set_seat(s.seat);
  fresh->push_back(s.Log(std::move(e)));
  s.last_end_reason = reason;
  s.phase = SessionPhase::kFinished;
  s.live.reset();
  host.RunEnded();
  return std::move(s.driver);
}

// A restore from a checkpoint: the session at rest as it was, its golfer made again from the
// parameters (as MakeSession and ResetOn make it).
absl::Status LoadCheckpoint(Session& s, const std::string& bytes)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(s.mu) {
  absl::StatusOr<SessionRestState> state = DecodeSessionRestState(bytes);
  if (!state.ok()) return state.status();
  if (state->phase == SessionPhase::kSwinging) {
    return absl::DataLossError(
        "session checkpoint: phase: swinging, but a checkpoint is taken at rest");
  }
  absl::StatusOr<sw::SwingModel> model = SwingModelFromProto(state->params, s.disabled_effects);
  if (!model.ok()) {
    return absl::DataLossError(
        absl::StrFormat("session checkpoint: params: %s", model.status().message()));
  }
  s.tick = state->tick;
  s.sequence = state->sequence;
  s.params = std::move(state->params);
  s.model = std::make_shared<const sw::SwingModel>(*std::move(model));
  s.phase = state->phase;
  s.swings = state->swings;
  s.start_tick = state->start_tick;
  s.seat = state->seat;
  s.state = state->state;
  s.qalpha = state->qalpha;
  s.qbeta = state->qbeta;
  s.last_impact = state->last_impact;
  s.last_end_reason = std::move(state->last_end_reason);
  return absl::OkStatus();
}

}  // namespace

bool SessionKind::Running(const Session& s) ABSL_NO_THREAD_SAFETY_ANALYSIS {
  return s.live != nullptr;
}

std::optional<SessionKind::End> SessionKind::AdvanceTick(SessionHost& /*host*/, Session& s,
                                                         int64_t k, TickOut* out) {
  std::optional<End> end = s.live->Advance(k - s.start_tick, &out->events);
  s.state = s.live->state();
  s.qalpha = s.live->qalpha_nm();
  s.qbeta = s.live->qbeta_nm();
  if (s.live->impact().has_value()) s.last_impact = s.live->impact();
  return end;
}

OffLockWork SessionKind::OffLock(Session& s, TickOut* out) {
  if (!s.strike.has_value()) return nullptr;
  const bool impact =
      std::any_of(out->events.begin(), out->events.end(), [](const sw::LiveSwingEvent& e) {
        return e.kind == sw::LiveSwingEvent::Kind::kImpact;
      });
  if (!impact) return nullptr;
  // The ball's flight (~1 ms of CPU for a 7 s flight at the default 1 ms step) runs without the
  // session's lock. The strike job is fixed at creation; the impact is the tick's own copy.
  const StrikeJob* job = &*s.strike;
  return [job, out] {
    for (const sw::LiveSwingEvent& e : out->events) {
      if (e.kind != sw::LiveSwingEvent::Kind::kImpact) continue;
      LaunchBall(*job, e.impact, &out->launches.emplace_back());
    }
  };
}

void SessionKind::Publish(SessionHost& /*host*/, Session& s, TickOut* out,
                          std::vector<SwingEventPtr>* fresh) {
  size_t launch = 0;
  for (const sw::LiveSwingEvent& le : out->events) {
    const int64_t tick = s.start_tick + le.n;
    v1::SwingEvent e;
    std::vector<v1::SwingEvent> then;  // logged right after e
    switch (le.kind) {
      case sw::LiveSwingEvent::Kind::kTorque:
        e = SwingEvent(v1::SWING_EVENT_TORQUE, le.t_s, s.swings, tick);
        e.set_qalpha_nm(le.command.qalpha_nm);
        e.set_qbeta_nm(le.command.qbeta_nm);
        e.set_command_t_s(le.command.t_s);
        e.set_command(le.command.index);
        if (le.command.late) {
          e.set_reason(absl::StrFormat("late: asked for t = %g s, applied at t = %g s",
                                       le.command.t_s, le.t_s));
        }
        s.counters->applied.fetch_add(1);
        break;
      case sw::LiveSwingEvent::Kind::kImpact:
        e = SwingEvent(v1::SWING_EVENT_IMPACT, le.t_s, s.swings, tick);
        ImpactToProto(le.impact, e.mutable_impact());
        if (launch < out->launches.size()) {
          const v1::BallLaunch& ball = out->launches[launch++];
          *e.mutable_ball() = ball;
          if (ball.error().empty()) {
            // The ball leaves the face and, its flight computed at once, where and when it
            // lands: events of their own a watcher can key on, after the impact's.
            v1::SwingEvent& off = then.emplace_back(
                SwingEvent(v1::SWING_EVENT_BALL_LAUNCH, le.t_s, s.swings, tick));
            *off.mutable_ball() = ball;
            off.mutable_ball()->clear_flight();
            if (ball.has_flight()) {
              v1::SwingEvent& land = then.emplace_back(SwingEvent(
                  v1::SWING_EVENT_LANDING, le.t_s + ball.flight().flight_time_s(), s.swings,
                  tick));
              *land.mutable_ball() = ball;
              land.mutable_ball()->mutable_flight()->clear_samples();
            }
          }
        }
        break;
      case sw::LiveSwingEvent::Kind::kBeyondHuman:
        e = SwingEvent(v1::SWING_EVENT_BEYOND_HUMAN, le.t_s, s.swings, tick);
        e.set_reason(absl::StrFormat(
            "the clubhead reached %.1f m/s, beyond what a human golfer reaches (realistic "
            "profile: %g m/s; the long-drive record is about 67 m/s)",
            le.clubhead_speed_mps, sw::kHumanLimits.max_clubhead_speed_mps));
        break;
    }
    e.set_seat(s.seat);
    fresh->push_back(s.Log(std::move(e)));
    for (v1::SwingEvent& next : then) {
      next.set_seat(s.seat);
      fresh->push_back(s.Log(std::move(next)));
    }
  }
}

void SessionKind::EndRun(SessionHost& host, Session& s, const End& end,
                         std::vector<SwingEventPtr>* fresh, Session::Pump* pump) {
  const std::shared_ptr<SwingWatcher> driver = EndSwing(host, s, end, fresh);
  if (driver != nullptr) {
    // The driven swing is over: its stream gets this tick's last frame and events, then ends.
    s.Forget(driver.get());
    driver->Offer(s.MakeFrame(s.tick, false, true), *fresh);
    if (driver->Close(absl::OkStatus(), nullptr)) pump->push_back(driver);
  }
}

uint64_t SessionKind::Runs(const Session& s) ABSL_NO_THREAD_SAFETY_ANALYSIS { return s.swings; }

std::string SessionKind::Checkpoint(const Session& s) ABSL_NO_THREAD_SAFETY_ANALYSIS {
  return EncodeSessionRestState(SessionRestState{.tick = s.tick,
                                                 .sequence = s.sequence,
                                                 .params = s.params,
                                                 .phase = s.phase,
                                                 .swings = s.swings,
                                                 .start_tick = s.start_tick,
                                                 .seat = s.seat,
                                                 .state = s.state,
                                                 .qalpha = s.qalpha,
                                                 .qbeta = s.qbeta,
                                                 .last_impact = s.last_impact,
                                                 .last_end_reason = s.last_end_reason});
}

std::shared_ptr<const SwingFrame> SessionKind::MakeFrame(const Session& s, int64_t k,
                                                         bool heartbeat,
                                                         SteadyClock::time_point published)
    ABSL_NO_THREAD_SAFETY_ANALYSIS {
  auto f = std::make_shared<SwingFrame>();
  f->sequence = s.sequence;
  f->tick = k;
  f->heartbeat = heartbeat;
  f->published = published;
  f->phase = s.phase;
  f->swing_id = s.swings;
  f->state = s.state;
  f->qalpha_nm = s.qalpha;
  f->qbeta_nm = s.qbeta;
  return f;
}

// ---------------------------------------------------------------------------------------------
// Registry

SessionRegistry::SessionRegistry(SessionLimits limits, TickScheduler* scheduler, int workers)
    : limits_(limits), host_([&] {
        WorldLimits w = limits.world;
        if (workers != 0) w.workers = workers;
        return w;
      }(), scheduler) {}

SessionRegistry::~SessionRegistry() {
  Shutdown(absl::UnavailableError("the server is shutting down"));
}

absl::StatusOr<v1::CreateSessionResponse> SessionRegistry::Create(
    const v1::CreateSessionRequest& request) {
  const std::shared_ptr<Session> session = host_.Make();
  std::vector<std::string> tokens;
  absl::StatusOr<v1::CreateSessionResponse> made = MakeSession(request, *session, &tokens);
  if (!made.ok()) return made.status();
  v1::CreateSessionResponse response = *std::move(made);
  SeatsToProto(session->seats, &tokens, response.mutable_seats());
  ::sportsim::store::v1::SessionCreated created;
  created.set_request(request.SerializeAsString());
  if (absl::Status s = host_.Add(session, created.SerializeAsString()); !s.ok()) return s;
  response.set_session_id(session->id);
  response.set_token(tokens[0]);
  return response;
}

absl::StatusOr<v1::CreateSessionResponse> SessionRegistry::MakeSession(
    const v1::CreateSessionRequest& request, Session& made, std::vector<std::string>* tokens) {
  const double tick_hz = request.tick_hz() == 0 ? kDefaultTickHz : request.tick_hz();
  if (absl::Status s = CheckFiniteInRange("tick_hz", tick_hz, 1, false, 1000, false); !s.ok()) {
    return s;
  }
  absl::StatusOr<std::vector<SeatEntry>> seats =
      MakeSeats(request.seats(), request.seat_names(), /*default_count=*/1, tokens);
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

  Session* const session = &made;
  session->counters = &counters_;
  session->strike = std::move(strike);
  session->tick_hz = tick_hz;
  session->period_s = 1.0 / tick_hz;
  session->disabled_effects = request.disabled_effects();
  session->solver = *solver;
  session->realistic = request.profile() != v1::REALISM_PROFILE_ARCADE;
  if (session->seats.empty()) session->seats = *std::move(seats);  // a restore keeps its own
  v1::CreateSessionResponse response;
  {
    absl::MutexLock lock(&session->mu);
    session->clock.tick_hz = tick_hz * host_.limits().clock_rate;
    session->clock.origin = SteadyClock::now();
    session->params = request.parameters();
    session->model = std::make_shared<const sw::SwingModel>(*model);
    session->state = sw::MakeSample(*model, 0.0, sw::SwingStepper::InitialState(*model));
  }
  response.set_tick_hz(tick_hz);
  response.set_integrator(std::string(sw::SwingIntegratorName(solver->integrator)));
  response.set_tick(0);
  response.set_profile(session->realistic ? "realistic" : "arcade");
  return response;
}

absl::StatusOr<v1::SessionInfo> SessionRegistry::Get(const v1::GetSessionRequest& request) {
  absl::StatusOr<std::shared_ptr<Session>> found = host_.Find(request.session_id());
  if (!found.ok()) return found.status();
  Session& s = **found;
  absl::MutexLock lock(&s.mu);
  v1::SessionInfo info;
  info.set_session_id(s.id);
  info.set_tick_hz(s.tick_hz);
  info.set_tick(s.NowTick());
  info.set_sequence(s.sequence);
  info.set_phase(PhaseToProto(s.phase));
  info.set_swing_id(s.swings);
  info.set_swings(s.swings);
  SampleToProto(s.state, info.mutable_state());
  if (s.last_impact) ImpactToProto(*s.last_impact, info.mutable_last_impact());
  SeatsToProto(s.seats, nullptr, info.mutable_seats());
  info.set_watchers(static_cast<uint32_t>(s.watchers.size()));
  info.set_integrator(std::string(sw::SwingIntegratorName(s.solver.integrator)));
  if (s.solver.integrator != sw::SwingIntegrator::kDp45) {
    info.set_dt_s(s.solver.dt());
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
  v1::ListSessionsResponse response;
  absl::StatusOr<uint32_t> total = host_.List(
      PageRequest{.page_size = request.page_size(), .page_token = request.page_token()},
      response.mutable_next_page_token(), [&](const Session& s) ABSL_NO_THREAD_SAFETY_ANALYSIS {
        v1::SessionBrief* brief = response.add_sessions();
        brief->set_session_id(s.id);
        brief->set_phase(PhaseToProto(s.phase));
        brief->set_tick(s.NowTick());
        brief->set_swings(s.swings);
        brief->set_watchers(static_cast<uint32_t>(s.watchers.size()));
        brief->set_tick_hz(s.tick_hz);
      });
  if (!total.ok()) return total.status();
  response.set_total(*total);
  return response;
}

absl::Status SessionRegistry::Delete(const v1::DeleteSessionRequest& request) {
  return host_.Delete(
      request.session_id(), request.token(),
      [](const Session&, int) { return absl::OkStatus(); },
      [&](Session& s, std::vector<SwingEventPtr>* fresh, Session::Pump* /*pump*/)
          ABSL_NO_THREAD_SAFETY_ANALYSIS {
        if (s.live != nullptr) {
          ++s.sequence;
          // The driver's stream is closed with the others.
          EndSwing(host_, s, sw::LiveSwingEnd{.reason = sw::SwingEnd::kDeleted}, fresh);
        }
      },
      static_cast<uint32_t>(SessionCommand::kDelete), JournalBody(request));
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

absl::StatusOr<v1::StartSwingResponse> SessionRegistry::Start(const v1::StartSwingRequest& request) {
  if (absl::Status s = CheckToken(request.token(), "CreateSession"); !s.ok()) return s;
  absl::StatusOr<std::shared_ptr<Session>> found = host_.Find(request.session_id());
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
    if (s.live != nullptr) {
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
          run.duration_s / s.solver.dt();
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
  return host_.Act<v1::StartSwingResponse>(
      request.session_id(), request.token(),
      [&](const std::shared_ptr<Session>& ptr, int seat, Session::Pump& pump) {
        return StartOn(*ptr, seat, request, model.get(), pump);
      });
}

absl::StatusOr<v1::StartSwingResponse> SessionRegistry::StartOn(
    Session& s, int seat, const v1::StartSwingRequest& request, const sw::SwingModel* checked,
    Session::Pump& pump) {
  absl::StatusOr<sw::TorqueProgram> program =
      TorqueProgramFromProto(request.torques(), request.has_torques());
  if (!program.ok()) return program.status();
  absl::StatusOr<std::pair<sw::SwingStop, double>> stop =
      StopFromProto(request.stop(), request.has_duration_s(), request.duration_s(), "");
  if (!stop.ok()) return stop.status();
  if (s.live != nullptr || (checked != nullptr && s.model.get() != checked)) {
    return absl::FailedPreconditionError(
        "the session started another swing or was reset while this one was checked; try again");
  }
  const sw::LiveSwingOptions options{.stop = stop->first, .duration_s = stop->second,
                                     .tick_hz = s.tick_hz, .realistic = s.realistic};
  absl::StatusOr<std::unique_ptr<sw::LiveSwing>> live =
      sw::LiveSwing::Create(*s.model, *std::move(program), s.solver, options);
  if (!live.ok()) return live.status();  // the solver was validated at creation
  if (absl::Status st = host_.Commit(s, seat, static_cast<uint32_t>(SessionCommand::kStart),
                                     JournalBody(request));
      !st.ok()) {
    return st;
  }
  v1::StartSwingResponse response;
  std::vector<SwingEventPtr> fresh;
  BeginSwing(host_, s, *std::move(live), static_cast<uint32_t>(seat), &fresh);
  s.OfferFrameAt(s.tick, fresh, &pump);
  host_.ScheduleNextTick(s);
  response.set_swing_id(s.swings);
  response.set_start_tick(s.tick);
  response.set_sequence(s.sequence);
  return response;
}

absl::StatusOr<v1::ResetSwingResponse> SessionRegistry::Reset(const v1::ResetSwingRequest& request) {
  return host_.Act<v1::ResetSwingResponse>(
      request.session_id(), request.token(),
      [&](const std::shared_ptr<Session>& ptr, int seat, Session::Pump& pump) {
        return ResetOn(*ptr, seat, request, pump);
      });
}

absl::StatusOr<v1::ResetSwingResponse> SessionRegistry::ResetOn(
    Session& s, int seat, const v1::ResetSwingRequest& request, Session::Pump& pump) {
  v1::ResetSwingResponse response;
  v1::SwingParameters params = s.params;
  if (request.has_gamma_deg()) params.set_gamma_deg(request.gamma_deg());
  if (request.has_beta0_deg()) params.set_beta0_deg(request.beta0_deg());
  absl::StatusOr<sw::SwingModel> model = SwingModelFromProto(params, s.disabled_effects);
  if (!model.ok()) return model.status();
  if (absl::Status st = host_.Commit(s, seat, static_cast<uint32_t>(SessionCommand::kReset),
                                     JournalBody(request));
      !st.ok()) {
    return st;
  }
  const int64_t tick = s.NowTick();
  s.tick = tick;
  ++s.sequence;
  std::vector<SwingEventPtr> fresh;
  std::shared_ptr<SwingWatcher> driver;
  if (s.live != nullptr) {
    driver = EndSwing(host_, s, sw::LiveSwingEnd{.reason = sw::SwingEnd::kReset}, &fresh);
    host_.AfterRunEndedByCall(s);
  }
  s.params = params;
  s.model = std::make_shared<const sw::SwingModel>(*model);
  s.phase = SessionPhase::kAddress;
  s.state = sw::MakeSample(*model, 0.0, sw::SwingStepper::InitialState(*model));
  s.qalpha = s.qbeta = 0.0;
  v1::SwingEvent e = SwingEvent(v1::SWING_EVENT_RESET, 0.0, s.swings, tick);
  e.set_seat(static_cast<uint32_t>(seat));
  fresh.push_back(s.Log(std::move(e)));
  host_.CountEvents(fresh.size());
  s.OfferFrameAt(tick, fresh, &pump);
  if (driver != nullptr) {
    s.Forget(driver.get());
    if (driver->Close(absl::OkStatus(), nullptr)) pump.push_back(driver);
  }
  response.set_sequence(s.sequence);
  response.set_tick(tick);
  return response;
}

absl::StatusOr<std::shared_ptr<SwingWatcher>> SessionRegistry::Watch(
    const v1::WatchSwingRequest& request, SwingSink* sink) {
  std::optional<uint64_t> from;
  if (request.has_from_sequence()) from = request.from_sequence();
  return host_.Watch(request.session_id(), request.rate_hz(), SwingWatchOptions{}, from, sink);
}

void SessionRegistry::Unwatch(const std::string& session_id, const SwingWatcher* watcher) {
  host_.Unwatch(session_id, watcher);
}

absl::StatusOr<std::shared_ptr<Drive>> SessionRegistry::StartDrive(const v1::DriveStart& start,
                                                                   SwingSink* sink) {
  if (absl::Status s = CheckToken(start.token(), "CreateSession"); !s.ok()) {
    return PrefixStatus("start.", s);
  }
  absl::StatusOr<std::shared_ptr<Session>> found = host_.Find(start.session_id());
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
  absl::StatusOr<double> interval =
      SessionHost::IntervalTicks("start.rate_hz", start.rate_hz(), s.tick_hz);
  if (!interval.ok()) return interval.status();
  std::shared_ptr<SwingWatcher> watcher = host_.NewWatcher(s, SwingWatchOptions{}, *interval, sink);
  Session::Pump pump;
  auto drive = std::make_shared<Drive>();
  drive->session = ptr;
  drive->watcher = watcher;
  drive->apply_late = start.apply_late();
  {
    absl::MutexLock lock(&s.mu);
    SessionHost::AwaitCommitted(s);
    absl::StatusOr<int> seat = s.Authorize(start.token());
    if (!seat.ok()) return PrefixStatus("start.", seat.status());
    absl::Status started = DriveStartOn(s, *seat, start, *drive, pump);
    host_.AfterCall(s);
    if (!started.ok()) return started;
  }
  // The others are pumped here, with no lock held; the caller pumps its own stream once it is
  // ready.
  for (const auto& w : pump) {
    if (w != watcher) w->Pump();
  }
  return drive;
}

absl::Status SessionRegistry::DriveStartOn(Session& s, int seat, const v1::DriveStart& start,
                                           Drive& drive, Session::Pump& pump) {
  absl::StatusOr<std::pair<sw::SwingStop, double>> stop =
      StopFromProto(start.stop(), start.has_duration_s(), start.duration_s(), "start.");
  if (!stop.ok()) return stop.status();
  if (s.live != nullptr) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "a swing is in progress (swing %d); wait for its end or ResetSwing", s.swings));
  }
  if (absl::Status room = host_.CheckWatcherRoom(s); !room.ok()) return room;
  const sw::LiveSwingOptions options{.stop = stop->first, .duration_s = stop->second,
                                     .tick_hz = s.tick_hz, .driven = true,
                                     .realistic = s.realistic};
  absl::StatusOr<std::unique_ptr<sw::LiveSwing>> live = sw::LiveSwing::Create(
      *s.model, sw::TorqueProgram::Constant(start.qalpha_nm(), start.qbeta_nm()), s.solver,
      options, start.qalpha_nm(), start.qbeta_nm());
  if (!live.ok()) return live.status();  // the solver was validated at creation
  if (absl::Status st = host_.Commit(s, seat, static_cast<uint32_t>(SessionCommand::kDriveStart),
                                     JournalBody(start));
      !st.ok()) {
    return st;
  }
  const std::shared_ptr<SwingWatcher>& watcher = drive.watcher;
  s.watchers.push_back(watcher);
  std::vector<SwingEventPtr> fresh;
  BeginSwing(host_, s, *std::move(live), static_cast<uint32_t>(seat), &fresh);
  s.driver = watcher;
  watcher->Due(s.tick);
  s.OfferFrameAt(s.tick, fresh, &pump);
  host_.ScheduleNextTick(s);
  drive.swing_id = s.swings;
  drive.seat = seat;
  drive.apply_late = start.apply_late();
  return absl::OkStatus();
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
    // The command's values are echoed only where finite: a NaN or an infinity is named in the
    // reason, never sent back as a number.
    if (command != nullptr) {
      if (std::isfinite(command->t_s())) e.set_command_t_s(command->t_s());
      if (std::isfinite(command->qalpha_nm())) e.set_qalpha_nm(command->qalpha_nm());
      if (std::isfinite(command->qbeta_nm())) e.set_qbeta_nm(command->qbeta_nm());
    }
    counters_.Refused(why.code());
    pump = drive.watcher->Offer(nullptr, {std::make_shared<const v1::SwingEvent>(std::move(e))});
  }
  if (pump) drive.watcher->Pump();
}

void SessionRegistry::Command(Drive& drive, const v1::TorqueCommand& c) {
  Session& s = *drive.session;
  absl::Status refused;
  {
    absl::MutexLock lock(&s.mu);
    SessionHost::AwaitCommitted(s);
    refused = CommandOn(s, drive, c);
    host_.AfterCall(s);
  }
  // Refused: reported on the driver's stream; nothing else changes.
  if (!refused.ok()) Refuse(drive, refused, &c);
}

absl::Status SessionRegistry::CommandOn(Session& s, Drive& drive, const v1::TorqueCommand& c) {
  absl::Status refused;
  {
    sw::LiveSwing* r = s.live.get();
    const uint64_t index = drive.commands + 1;
    const auto refuse = [&](absl::Status st) {
      refused = std::move(st);
    };
    if (r == nullptr || s.swings != drive.swing_id || s.driver != drive.watcher) {
      refuse(absl::FailedPreconditionError("the swing this stream drove has ended"));
    } else if (!std::isfinite(c.t_s()) || !std::isfinite(c.qalpha_nm()) ||
               !std::isfinite(c.qbeta_nm())) {
      refuse(absl::InvalidArgumentError(absl::StrFormat(
          "command %d: t_s, qalpha_nm and qbeta_nm must be finite, got %g, %g, %g", index,
          c.t_s(), c.qalpha_nm(), c.qbeta_nm())));
    } else if (c.t_s() < 0 || c.t_s() > r->options().duration_s) {
      refuse(absl::OutOfRangeError(absl::StrFormat(
          "command %d: t_s must be in [0, %g] s (the swing's duration), got %g", index,
          r->options().duration_s, c.t_s())));
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
    } else if (static_cast<int>(r->pending().size()) >= limits_.max_pending_commands) {
      refuse(absl::ResourceExhaustedError(absl::StrFormat(
          "command %d: %d commands are already waiting for their ticks", index,
          limits_.max_pending_commands)));
    } else {
      // Applied from the first tick at or after its time; the state at the last tick
      // advanced (swing tick `done`) is known, what follows it is not.
      int64_t n = r->CommandTick(c.t_s());
      const int64_t done = s.tick - s.start_tick;
      // The swing ends at the first tick at or after its duration; a command from there on
      // would never act.
      const int64_t last = r->LastCommandTick();
      bool late = false;
      if (n > last) {
        refuse(absl::OutOfRangeError(absl::StrFormat(
            "command %d: t_s %g s is at or after the swing's last tick (duration %g s)", index,
            c.t_s(), r->options().duration_s)));
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
        ::sportsim::store::v1::DriveCommand body;
        body.set_command(c.SerializeAsString());
        body.set_index(index);
        refused = host_.Commit(s, drive.seat, static_cast<uint32_t>(SessionCommand::kDriveCommand),
                               body.SerializeAsString());
      }
      if (refused.ok()) {
        ++drive.commands;
        drive.last_t_s = c.t_s();
        r->pending().push_back(sw::QueuedTorque{.n = n, .t_s = c.t_s(),
                                                .qalpha_nm = c.qalpha_nm(),
                                                .qbeta_nm = c.qbeta_nm(),
                                                .index = drive.commands, .late = late});
        return absl::OkStatus();
      }
    }
  }
  return refused;
}

void SessionRegistry::EndDrive(Drive& drive, bool half_closed) {
  Session& s = *drive.session;
  bool pump = false;
  {
    absl::MutexLock lock(&s.mu);
    SessionHost::AwaitCommitted(s);
    if (drive.ended) return;
    drive.ended = true;
    if (s.live != nullptr && s.driver == drive.watcher) {
      ::sportsim::store::v1::DriveEnded body;
      body.set_half_closed(half_closed);
      // Not durable (the store is down): the queued commands stand, as if half-closed.
      const bool durable =
          host_.Commit(s, drive.seat, static_cast<uint32_t>(SessionCommand::kDriveEnd),
                       body.SerializeAsString())
              .ok();
      DriveEndOn(s, half_closed || !durable);
      host_.AfterCall(s);
    }
    s.Forget(drive.watcher.get());
    if (half_closed) {
      pump = drive.watcher->Close(absl::OkStatus(), s.MakeFrame(s.NowTick(), false));
    }
  }
  if (pump) drive.watcher->Pump();
}

void SessionRegistry::DriveEndOn(Session& s, bool half_closed) {
  s.driver = nullptr;
  // Half-closed: "no more commands", the queued ones stand. Gone: the controller that sent
  // them is gone too; the torques in force hold.
  if (!half_closed) s.live->pending().clear();
}

absl::Status SessionRegistry::Restore(const StoredWorld& stored) {
  std::shared_ptr<Drive> drive;  // the driven swing being replayed, if any
  absl::Status restored = host_.Restore(
      stored,
      [&](Session& s, const std::string& kind_body) -> absl::Status {
        ::sportsim::store::v1::SessionCreated created;
        v1::CreateSessionRequest request;
        if (!created.ParseFromString(kind_body) || !request.ParseFromString(created.request())) {
          return absl::DataLossError("its creation does not parse");
        }
        std::vector<std::string> unused;
        return MakeSession(request, s, &unused).status();
      },
      [&](Session& s, const std::string& checkpoint) ABSL_NO_THREAD_SAFETY_ANALYSIS {
        return LoadCheckpoint(s, checkpoint);
      },
      [&](Session& s, const JournalEntry& e, Session::Pump& pump)
          ABSL_NO_THREAD_SAFETY_ANALYSIS -> absl::Status {
        const auto bad = [&] {
          return absl::DataLossError(
              absl::StrFormat("entry %d: the command does not parse", e.index));
        };
        switch (static_cast<SessionCommand>(e.type)) {
          case SessionCommand::kStart: {
            v1::StartSwingRequest r;
            if (!r.ParseFromString(e.body)) return bad();
            return StartOn(s, e.seat, r, nullptr, pump).status();
          }
          case SessionCommand::kReset: {
            v1::ResetSwingRequest r;
            if (!r.ParseFromString(e.body)) return bad();
            return ResetOn(s, e.seat, r, pump).status();
          }
          case SessionCommand::kDriveStart: {
            v1::DriveStart r;
            if (!r.ParseFromString(e.body)) return bad();
            drive = std::make_shared<Drive>();
            drive->session = std::static_pointer_cast<Session>(s.shared_from_this());
            // The driver's stream did not survive its server: a stand-in nobody reads.
            drive->watcher = host_.NewWatcher(s, SwingWatchOptions{}, 1.0, nullptr);
            return DriveStartOn(s, e.seat, r, *drive, pump);
          }
          case SessionCommand::kDriveCommand: {
            ::sportsim::store::v1::DriveCommand body;
            v1::TorqueCommand c;
            if (!body.ParseFromString(e.body) || !c.ParseFromString(body.command())) return bad();
            if (drive == nullptr || body.index() == 0) return bad();
            drive->commands = body.index() - 1;  // refused commands count too
            return CommandOn(s, *drive, c);
          }
          case SessionCommand::kDriveEnd: {
            ::sportsim::store::v1::DriveEnded body;
            if (!body.ParseFromString(e.body)) return bad();
            if (s.live != nullptr && drive != nullptr && s.driver == drive->watcher) {
              DriveEndOn(s, body.half_closed());
            }
            if (drive != nullptr) s.Forget(drive->watcher.get());
            drive = nullptr;
            return absl::OkStatus();
          }
          case SessionCommand::kCreate:
          case SessionCommand::kDelete:
            break;
        }
        return absl::DataLossError(
            absl::StrFormat("entry %d: no session command of type %d", e.index, e.type));
      });
  if (drive != nullptr) {
    // A driven swing in flight goes on with the commands it accepted, as if its driver had
    // half-closed: no stream drives it after a restore.
    Session& s = *drive->session;
    absl::MutexLock lock(&s.mu);
    if (s.live != nullptr && s.driver == drive->watcher) s.driver = nullptr;
    s.Forget(drive->watcher.get());
  }
  return restored;
}

void SessionRegistry::Shutdown(const absl::Status& status) {
  host_.Shutdown(status, [&](Session& s) ABSL_NO_THREAD_SAFETY_ANALYSIS {
    if (s.live != nullptr) {
      s.live.reset();
      host_.RunEnded();
    }
  });
}

SessionStats SessionRegistry::stats() const {
  SessionStats st;
  static_cast<WorldStats&>(st) = host_.stats();
  st.commands = counters_.applied.load();
  st.commands_refused = counters_.refused.load();
  for (size_t i = 0; i < st.refused_by_code.size(); ++i) {
    st.refused_by_code[i] = counters_.refused_by_code[i].load();
  }
  return st;
}

}  // namespace sportsim::server
