// The swing-session registry without a network: validation, the scheduled and driven swings
// against SimulateSwing bit for bit, refused and late torque commands, realism, tokens, reset,
// stalled and vanished readers, delete, shutdown and resume, through fake sinks.
#include "server/swing/session_world.h"

#include <google/protobuf/util/message_differencer.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_format.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/swing/convert.h"
#include "sim/swing/swing_simulation.h"
#include "sim/swing/torque_program.h"
#include "tests/server/fake_sink.h"

namespace sportsim::server {
namespace {

namespace sw = ::sportsim::swing;
using ::google::protobuf::util::MessageDifferencer;
using ::testing::HasSubstr;

using FakeSink = FakeSinkFor<SwingWatcher>;

constexpr char kWrongToken[] = "0123456789abcdef0123456789abcdef";  // well formed, no seat's
constexpr char kUnknownId[] = "s-000000000000";
constexpr std::chrono::microseconds kReadDelay(100);
constexpr int32_t kInvalidArgument = static_cast<int32_t>(absl::StatusCode::kInvalidArgument);
constexpr int32_t kOutOfRange = static_cast<int32_t>(absl::StatusCode::kOutOfRange);

SteadyClock::duration Seconds(double s) {
  return std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(s));
}

// Polls `done` every millisecond until it holds or `timeout_s` passes; its last value.
bool WaitFor(const std::function<bool()>& done, double timeout_s = 5.0) {
  const SteadyClock::time_point until = SteadyClock::now() + Seconds(timeout_s);
  for (;;) {
    if (done()) return true;
    if (SteadyClock::now() > until) return done();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

v1::GetSessionRequest GetReq(const std::string& id) {
  v1::GetSessionRequest r;
  r.set_session_id(id);
  return r;
}

v1::StartSwingRequest StartReq(const v1::CreateSessionResponse& s) {
  v1::StartSwingRequest r;  // no torques: the chapter's program
  r.set_session_id(s.session_id());
  r.set_token(s.token());
  return r;
}

v1::ResetSwingRequest ResetReq(const v1::CreateSessionResponse& s) {
  v1::ResetSwingRequest r;
  r.set_session_id(s.session_id());
  r.set_token(s.token());
  return r;
}

v1::DeleteSessionRequest DeleteReq(const v1::CreateSessionResponse& s) {
  v1::DeleteSessionRequest r;
  r.set_session_id(s.session_id());
  r.set_token(s.token());
  return r;
}

v1::WatchSwingRequest WatchReq(const std::string& id) {
  v1::WatchSwingRequest r;
  r.set_session_id(id);
  return r;
}

v1::DriveStart DriveReq(const v1::CreateSessionResponse& s, double qalpha, double qbeta) {
  v1::DriveStart r;
  r.set_session_id(s.session_id());
  r.set_token(s.token());
  r.set_qalpha_nm(qalpha);
  r.set_qbeta_nm(qbeta);
  return r;
}

v1::TorqueCommand Cmd(double t_s, double qalpha, double qbeta) {
  v1::TorqueCommand c;
  c.set_t_s(t_s);
  c.set_qalpha_nm(qalpha);
  c.set_qbeta_nm(qbeta);
  return c;
}

// SimulateSwing as the server runs a swing of a session created with `create`: the same golfer
// (SwingModelFromProto) and solver (SwingSolverFromProto), to impact with the 2 s cap, every step
// kept as a sample.
absl::StatusOr<sw::SwingRunResult> Reference(const v1::CreateSessionRequest& create,
                                             const sw::TorqueProgram& program) {
  absl::StatusOr<sw::SwingModel> model =
      SwingModelFromProto(create.parameters(), create.disabled_effects());
  if (!model.ok()) return model.status();
  absl::StatusOr<sw::SwingSolverOptions> solver = SwingSolverFromProto(create.solver());
  if (!solver.ok()) return solver.status();
  sw::SwingRunOptions run;
  run.stop = sw::SwingStop::kImpact;
  run.duration_s = 2.0;
  run.sample_stride = 1;
  return sw::SimulateSwing(*model, program, *solver, run);
}

v1::SwingImpact ImpactProto(const sw::SwingSample& x) {
  v1::SwingImpact out;
  ImpactToProto(x, &out);
  return out;
}

v1::SwingSample SampleProto(const sw::SwingSample& x) {
  v1::SwingSample out;
  SampleToProto(x, &out);
  return out;
}

// Bit for bit: MessageDifferencer compares doubles exactly.
void ExpectSameImpact(const v1::SwingImpact& got, const v1::SwingImpact& want) {
  EXPECT_TRUE(MessageDifferencer::Equals(got, want))
      << "got  " << got.ShortDebugString() << "\nwant " << want.ShortDebugString();
}

// Every event of `got`, in order; only those of `kind` unless it is UNSPECIFIED.
std::vector<v1::SwingEvent> EventsOf(const std::vector<v1::SwingSnapshot>& got,
                                     v1::SwingEventKind kind = v1::SWING_EVENT_KIND_UNSPECIFIED) {
  std::vector<v1::SwingEvent> out;
  for (const v1::SwingSnapshot& snap : got) {
    for (const v1::SwingEvent& e : snap.events()) {
      if (kind == v1::SWING_EVENT_KIND_UNSPECIFIED || e.kind() == kind) out.push_back(e);
    }
  }
  return out;
}

bool HasEvent(const v1::SwingSnapshot& snap, v1::SwingEventKind kind) {
  for (const v1::SwingEvent& e : snap.events()) {
    if (e.kind() == kind) return true;
  }
  return false;
}

// The last snapshot with a state (not a heartbeat), or null. Points into `got`.
const v1::SwingSnapshot* LastFull(const std::vector<v1::SwingSnapshot>& got) {
  for (auto it = got.rbegin(); it != got.rend(); ++it) {
    if (!it->heartbeat()) return &*it;
  }
  return nullptr;
}

// The sink has been sent the final state of a finished swing.
bool GotFinished(const FakeSink& sink) {
  const std::vector<v1::SwingSnapshot> got = sink.got();
  const v1::SwingSnapshot* last = LastFull(got);
  return last != nullptr && last->phase() == v1::SWING_PHASE_FINISHED;
}

class SessionsTest : public ::testing::Test {
 protected:
  // Declared before reg_ so that they outlive it: its workers, and its Shutdown in the
  // destructor, may still write to them.
  std::deque<std::unique_ptr<FakeSink>> sinks_;
  SessionRegistry reg_{SessionLimits{}, nullptr, /*workers=*/2};

  FakeSink& NewSink() {
    sinks_.push_back(std::make_unique<FakeSink>());
    return *sinks_.back();
  }

  v1::CreateSessionResponse Create(const v1::CreateSessionRequest& r) {
    absl::StatusOr<v1::CreateSessionResponse> s = reg_.Create(r);
    EXPECT_TRUE(s.ok()) << s.status();
    return s.ok() ? *s : v1::CreateSessionResponse();
  }
  v1::CreateSessionResponse Create() { return Create(v1::CreateSessionRequest()); }
  v1::CreateSessionResponse CreateArcade() {
    v1::CreateSessionRequest r;
    r.set_profile(v1::REALISM_PROFILE_ARCADE);
    return Create(r);
  }

  v1::SessionInfo Info(const std::string& id) {
    absl::StatusOr<v1::SessionInfo> info = reg_.Get(GetReq(id));
    EXPECT_TRUE(info.ok()) << info.status();
    return info.ok() ? *info : v1::SessionInfo();
  }

  // Polls Get until `done` holds (at most `timeout_s`).
  absl::StatusOr<v1::SessionInfo> WaitInfo(const std::string& id,
                                           const std::function<bool(const v1::SessionInfo&)>& done,
                                           double timeout_s = 5.0) {
    const SteadyClock::time_point until = SteadyClock::now() + Seconds(timeout_s);
    for (;;) {
      absl::StatusOr<v1::SessionInfo> info = reg_.Get(GetReq(id));
      if (!info.ok() || done(*info)) return info;
      if (SteadyClock::now() > until) {
        return absl::DeadlineExceededError(absl::StrFormat(
            "session %s: still in phase %d at t = %g s after %g s", id,
            static_cast<int>(info->phase()), info->state().t_s(), timeout_s));
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  absl::StatusOr<v1::SessionInfo> WaitFinished(const std::string& id, double timeout_s = 5.0) {
    return WaitInfo(
        id, [](const v1::SessionInfo& i) { return i.phase() == v1::SWING_PHASE_FINISHED; },
        timeout_s);
  }
  // Until the swing in progress has been simulated to swing time `t_s`; an error if it ended.
  absl::StatusOr<v1::SessionInfo> WaitSwingTime(const std::string& id, double t_s) {
    absl::StatusOr<v1::SessionInfo> info = WaitInfo(id, [t_s](const v1::SessionInfo& i) {
      return i.phase() != v1::SWING_PHASE_SWINGING || i.state().t_s() >= t_s;
    });
    if (info.ok() && info->phase() != v1::SWING_PHASE_SWINGING) {
      return absl::FailedPreconditionError(
          absl::StrFormat("the swing ended before t = %g s", t_s));
    }
    return info;
  }

  // Registers `sink` as a watcher and sends its first snapshot. `read`: the sink completes its
  // writes (after kReadDelay); else it is bound but never completes one (a stalled client).
  std::shared_ptr<SwingWatcher> Watch(const v1::WatchSwingRequest& w, FakeSink& sink,
                                      bool read = true) {
    absl::StatusOr<std::shared_ptr<SwingWatcher>> watcher = reg_.Watch(w, &sink);
    EXPECT_TRUE(watcher.ok()) << watcher.status();
    if (!watcher.ok()) return nullptr;
    if (read) {
      sink.StartReading(*watcher, kReadDelay);
    } else {
      sink.Bind(*watcher);
    }
    (*watcher)->Pump();
    return *watcher;
  }

  // DriveSwing's first message: starts a driven swing whose stream `sink` reads.
  std::shared_ptr<Drive> StartDriving(const v1::DriveStart& start, FakeSink& sink) {
    absl::StatusOr<std::shared_ptr<Drive>> drive = reg_.StartDrive(start, &sink);
    EXPECT_TRUE(drive.ok()) << drive.status();
    if (!drive.ok()) return nullptr;
    sink.StartReading((*drive)->watcher, kReadDelay);
    (*drive)->watcher->Pump();  // the caller pumps the driver's own stream
    return *drive;
  }
};

// ---------------------------------------------------------------------------------------------
// Create

// Every bad field is INVALID_ARGUMENT naming it, and creates nothing; unset fields take the
// documented defaults (400 Hz, rk4 at 0.0025 s, realistic, one seat with a secret token).
TEST_F(SessionsTest, CreateValidatesEachFieldAndDefaultsTheRest) {
  const auto expect_bad = [&](const v1::CreateSessionRequest& r, const std::string& field) {
    absl::StatusOr<v1::CreateSessionResponse> s = reg_.Create(r);
    ASSERT_FALSE(s.ok()) << field << " was accepted: " << r.ShortDebugString();
    EXPECT_EQ(s.status().code(), absl::StatusCode::kInvalidArgument) << s.status();
    EXPECT_THAT(s.status().message(), HasSubstr(field));
  };
  v1::CreateSessionRequest r;
  r.set_tick_hz(std::nan(""));
  expect_bad(r, "tick_hz");
  r.set_tick_hz(0.5);
  expect_bad(r, "tick_hz");
  r.set_tick_hz(2000);
  expect_bad(r, "tick_hz");
  r = v1::CreateSessionRequest();
  r.set_seats(17);
  expect_bad(r, "seats");
  r = v1::CreateSessionRequest();
  r.set_seats(2);
  r.add_seat_names("ann");
  r.add_seat_names("bob");
  r.add_seat_names("cy");
  expect_bad(r, "seat_names");
  r = v1::CreateSessionRequest();
  r.mutable_parameters()->set_arm_length_m(-1);
  expect_bad(r, "parameters.arm_length_m");
  r = v1::CreateSessionRequest();
  r.mutable_solver()->set_integrator(v1::SWING_INTEGRATOR_DP45);
  r.mutable_solver()->set_dt_s(0.001);  // a fixed step for an adaptive scheme
  expect_bad(r, "solver.dt_s");
  r = v1::CreateSessionRequest();
  r.set_profile(static_cast<v1::RealismProfile>(99));
  expect_bad(r, "profile");
  EXPECT_EQ(reg_.stats().worlds, 0);
  absl::StatusOr<v1::ListSessionsResponse> list = reg_.List(v1::ListSessionsRequest());
  ASSERT_TRUE(list.ok()) << list.status();
  EXPECT_EQ(list->total(), 0u);

  absl::StatusOr<v1::CreateSessionResponse> s = reg_.Create(v1::CreateSessionRequest());
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_FALSE(s->session_id().empty());
  EXPECT_EQ(s->tick_hz(), 400.0);
  EXPECT_EQ(s->integrator(), "rk4");
  EXPECT_EQ(s->profile(), "realistic");
  ASSERT_EQ(s->seats_size(), 1);
  EXPECT_FALSE(s->token().empty());
  EXPECT_EQ(s->token(), s->seats(0).token());
  EXPECT_EQ(reg_.stats().worlds, 1);
  const v1::SessionInfo info = Info(s->session_id());
  EXPECT_EQ(info.phase(), v1::SWING_PHASE_ADDRESS);
  EXPECT_EQ(info.integrator(), "rk4");
  EXPECT_EQ(info.dt_s(), 0.0025);
  EXPECT_EQ(info.profile(), "realistic");
  EXPECT_EQ(info.swings(), 0u);
  EXPECT_EQ(info.watchers(), 0u);
  EXPECT_NEAR(info.gamma_deg(), 135.0, 1e-12);
  EXPECT_NEAR(info.beta0_deg(), 120.0, 1e-12);
  EXPECT_EQ(info.state().t_s(), 0.0);
  EXPECT_EQ(info.state().alpha_deg(), 0.0);
  EXPECT_FALSE(info.has_last_impact());
  ASSERT_EQ(info.seats_size(), 1);
  EXPECT_TRUE(info.seats(0).token().empty()) << "Get leaked a token";
}

// ---------------------------------------------------------------------------------------------
// Determinism

struct IntegratorCase {
  const char* name;
  v1::SwingIntegrator integrator;
  double dt_s;      // 0: the default
  bool fixed_step;  // every tick time is a step time
};

class ScheduledSwingTest : public SessionsTest,
                           public ::testing::WithParamInterface<IntegratorCase> {};

// A scheduled swing steps exactly as SimulateSwing does whatever the load and the tick timing:
// its impact, the impact state it ends on, and (fixed steps) every tick's state are the same
// doubles as SimulateSwing's for the same golfer, program and solver.
TEST_P(ScheduledSwingTest, ImpactAndTickStatesAreBitIdenticalToSimulateSwing) {
  const IntegratorCase& c = GetParam();
  v1::CreateSessionRequest create;
  create.mutable_solver()->set_integrator(c.integrator);
  if (c.dt_s > 0) create.mutable_solver()->set_dt_s(c.dt_s);
  const v1::CreateSessionResponse s = Create(create);
  ASSERT_FALSE(s.session_id().empty());
  EXPECT_EQ(s.integrator(), c.name);
  absl::StatusOr<sw::SwingRunResult> want = Reference(create, sw::TorqueProgram::Chapter());
  ASSERT_TRUE(want.ok()) << want.status();
  ASSERT_TRUE(want->impact.has_value());

  FakeSink& sink = NewSink();
  ASSERT_NE(Watch(WatchReq(s.session_id()), sink), nullptr);
  absl::StatusOr<v1::StartSwingResponse> started = reg_.Start(StartReq(s));
  ASSERT_TRUE(started.ok()) << started.status();
  EXPECT_EQ(started->swing_id(), 1u);
  absl::StatusOr<v1::SessionInfo> info = WaitFinished(s.session_id());
  ASSERT_TRUE(info.ok()) << info.status();
  EXPECT_EQ(info->last_end_reason(), "impact");
  ExpectSameImpact(info->last_impact(), ImpactProto(*want->impact));
  EXPECT_TRUE(MessageDifferencer::Equals(info->state(), SampleProto(*want->impact)))
      << info->state().ShortDebugString();

  // The watcher's last snapshot is the impact state.
  ASSERT_TRUE(WaitFor([&] { return GotFinished(sink); }));
  const std::vector<v1::SwingSnapshot> got = sink.got();
  const v1::SwingSnapshot* last = LastFull(got);
  ASSERT_NE(last, nullptr);
  EXPECT_EQ(last->phase(), v1::SWING_PHASE_FINISHED);
  EXPECT_EQ(last->state().t_s(), want->impact->t_s);
  EXPECT_TRUE(MessageDifferencer::Equals(last->state(), SampleProto(*want->impact)))
      << last->state().ShortDebugString();
  const std::vector<v1::SwingEvent> impacts = EventsOf(got, v1::SWING_EVENT_IMPACT);
  ASSERT_EQ(impacts.size(), 1u);
  ExpectSameImpact(impacts[0].impact(), ImpactProto(*want->impact));
  EXPECT_EQ(impacts[0].t_s(), want->impact->t_s);

  // Swing time never runs backwards on the stream.
  double t_prev = 0.0;
  for (const v1::SwingSnapshot& snap : got) {
    if (snap.heartbeat() || snap.phase() == v1::SWING_PHASE_ADDRESS) continue;
    EXPECT_GE(snap.state().t_s(), t_prev);
    t_prev = snap.state().t_s();
  }

  if (!c.fixed_step) return;  // dp45's tick states are interpolated between its steps
  // Every tick lands on a step: each state sent is SimulateSwing's sample at that time.
  std::map<double, v1::SwingSample> by_time;
  for (const sw::SwingSample& x : want->samples) by_time[x.t_s] = SampleProto(x);
  int full = 0, matched = 0;
  for (const v1::SwingSnapshot& snap : got) {
    if (snap.heartbeat()) continue;
    ++full;
    const auto it = by_time.find(snap.state().t_s());
    if (it == by_time.end()) {
      ADD_FAILURE() << "a snapshot at t = " << snap.state().t_s()
                    << " s, not a step time of SimulateSwing";
      continue;
    }
    if (MessageDifferencer::Equals(snap.state(), it->second)) {
      ++matched;
    } else {
      ADD_FAILURE() << "tick " << snap.tick() << ": " << snap.state().ShortDebugString()
                    << "\n  SimulateSwing: " << it->second.ShortDebugString();
    }
  }
  EXPECT_EQ(matched, full);
  EXPECT_GE(matched, 20) << "the reader should have seen most of the swing's ~117 ticks";
}

INSTANTIATE_TEST_SUITE_P(
    Integrators, ScheduledSwingTest,
    ::testing::Values(
        IntegratorCase{"rk4", v1::SWING_INTEGRATOR_RK4, 0.0, true},
        IntegratorCase{"book", v1::SWING_INTEGRATOR_BOOK, 0.0, true},
        // Ten steps a tick at 400 Hz.
        IntegratorCase{"semi_implicit_euler", v1::SWING_INTEGRATOR_SEMI_IMPLICIT_EULER,
                       1.0 / 4000, true},
        IntegratorCase{"dp45", v1::SWING_INTEGRATOR_DP45, 0.0, false}),
    [](const ::testing::TestParamInfo<IntegratorCase>& p) { return std::string(p.param.name); });

// A session created with `ball` launches it at each impact: the IMPACT event carries the ball
// that SimulateSwing's `ball` would give for the same impact (0.1 s flight samples by default in
// a session), and a bad `ball` creates nothing.
TEST_F(SessionsTest, ImpactEventCarriesTheLaunchedBallAndItsFlight) {
  v1::CreateSessionRequest create;
  create.mutable_ball()->set_club("5-iron");
  create.mutable_ball()->set_club_path_deg(-3);
  const v1::CreateSessionResponse s = Create(create);
  ASSERT_FALSE(s.session_id().empty());
  absl::StatusOr<sw::SwingRunResult> want = Reference(create, sw::TorqueProgram::Chapter());
  ASSERT_TRUE(want.ok() && want->impact.has_value());

  FakeSink& sink = NewSink();
  ASSERT_NE(Watch(WatchReq(s.session_id()), sink), nullptr);
  ASSERT_TRUE(reg_.Start(StartReq(s)).ok());
  ASSERT_TRUE(WaitFinished(s.session_id()).ok());
  ASSERT_TRUE(WaitFor([&] { return GotFinished(sink); }));
  const std::vector<v1::SwingEvent> impacts = EventsOf(sink.got(), v1::SWING_EVENT_IMPACT);
  ASSERT_EQ(impacts.size(), 1u);
  const v1::BallLaunch& got = impacts[0].ball();
  EXPECT_EQ(got.error(), "");
  EXPECT_EQ(got.club(), "5-iron");

  v1::BallStrike strike = create.ball();
  strike.set_sample_interval_s(0.1);
  absl::StatusOr<StrikeJob> job = StrikeJobFromProto(strike);
  ASSERT_TRUE(job.ok()) << job.status();
  v1::BallLaunch expected;
  LaunchBall(*job, *want->impact, &expected);
  expected.mutable_flight()->set_cpu_s(got.flight().cpu_s());
  EXPECT_TRUE(MessageDifferencer::Equals(got, expected)) << got.ShortDebugString();
  EXPECT_GT(got.flight().carry_m(), 50.0);
  EXPECT_LT(got.launch().launch_direction_deg(), 0.0);  // an out-to-in path starts it left
  // 0.1 s samples: about ten a second of flight, plus the landing.
  EXPECT_NEAR(got.flight().samples_size(), got.flight().flight_time_s() / 0.1 + 2, 1.0);
  // The ball's launch and landing as events of their own, right after the impact's: the launch
  // at the impact's time without the flight, the landing at impact + flight time with the
  // flight's summary.
  const std::vector<v1::SwingEvent> launches = EventsOf(sink.got(), v1::SWING_EVENT_BALL_LAUNCH);
  const std::vector<v1::SwingEvent> landings = EventsOf(sink.got(), v1::SWING_EVENT_LANDING);
  ASSERT_EQ(launches.size(), 1u);
  ASSERT_EQ(landings.size(), 1u);
  std::vector<v1::SwingEventKind> order;
  for (const v1::SwingEvent& e : EventsOf(sink.got())) order.push_back(e.kind());
  const auto at = std::find(order.begin(), order.end(), v1::SWING_EVENT_IMPACT);
  ASSERT_LE(at + 3, order.end());
  EXPECT_EQ(at[1], v1::SWING_EVENT_BALL_LAUNCH);
  EXPECT_EQ(at[2], v1::SWING_EVENT_LANDING);
  EXPECT_EQ(launches[0].sequence(), impacts[0].sequence());  // the same tick's
  EXPECT_EQ(landings[0].sequence(), impacts[0].sequence());
  EXPECT_EQ(launches[0].t_s(), impacts[0].t_s());
  EXPECT_TRUE(MessageDifferencer::Equals(launches[0].ball().launch(), got.launch()));
  EXPECT_FALSE(launches[0].ball().has_flight());
  EXPECT_EQ(landings[0].t_s(), impacts[0].t_s() + got.flight().flight_time_s());
  EXPECT_EQ(landings[0].ball().flight().carry_m(), got.flight().carry_m());
  EXPECT_EQ(landings[0].ball().flight().samples_size(), 0);
  EXPECT_EQ(landings[0].tick(), impacts[0].tick());

  v1::CreateSessionRequest bad;
  bad.mutable_ball()->set_club("driver");
  bad.mutable_ball()->set_face_angle_deg(std::nan(""));
  const int before = reg_.stats().worlds;
  absl::StatusOr<v1::CreateSessionResponse> refused = reg_.Create(bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(refused.status().message(), HasSubstr("ball."));
  EXPECT_EQ(reg_.stats().worlds, before);
  // Fine flight samples would make each IMPACT event (kept for resumes) hundreds of kB.
  bad.mutable_ball()->set_face_angle_deg(0);
  bad.mutable_ball()->set_sample_interval_s(0.001);
  refused = reg_.Create(bad);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(refused.status().message(), HasSubstr("ball.sample_interval_s"));
  EXPECT_EQ(reg_.stats().worlds, before);
}

// Driven torques (100, -10) then (100, 0) from t = 0.1 s are the chapter's program: with rk4 at
// one step a tick, the driven swing is the scheduled one, bit for bit. The command is reported
// when it takes effect, and the driver's stream ends OK after the snapshot carrying ENDED.
TEST_F(SessionsTest, DrivenChapterTorquesGiveTheChapterImpactBitForBit) {
  const v1::CreateSessionResponse s = Create();
  absl::StatusOr<sw::SwingRunResult> want =
      Reference(v1::CreateSessionRequest(), sw::TorqueProgram::Chapter());
  ASSERT_TRUE(want.ok()) << want.status();
  ASSERT_TRUE(want->impact.has_value());

  FakeSink& sink = NewSink();
  const std::shared_ptr<Drive> drive = StartDriving(DriveReq(s, 100, -10), sink);
  ASSERT_NE(drive, nullptr);
  EXPECT_EQ(drive->swing_id, 1u);
  reg_.Command(*drive, Cmd(0.1, 100, 0));  // the chapter's wrist release
  absl::StatusOr<v1::SessionInfo> info = WaitFinished(s.session_id());
  ASSERT_TRUE(info.ok()) << info.status();
  EXPECT_EQ(info->last_end_reason(), "impact");
  ExpectSameImpact(info->last_impact(), ImpactProto(*want->impact));
  EXPECT_EQ(info->watchers(), 0u) << "the driver's stream outlived its swing";

  ASSERT_TRUE(WaitFor([&] { return sink.finished(); }));
  EXPECT_TRUE(sink.status().ok()) << sink.status();
  const std::vector<v1::SwingSnapshot> got = sink.got();
  ASSERT_FALSE(got.empty());
  EXPECT_FALSE(got.back().heartbeat());
  EXPECT_EQ(got.back().phase(), v1::SWING_PHASE_FINISHED);
  EXPECT_TRUE(HasEvent(got.back(), v1::SWING_EVENT_ENDED)) << got.back().ShortDebugString();
  EXPECT_EQ(got.back().qalpha_nm(), 100.0);
  EXPECT_EQ(got.back().qbeta_nm(), 0.0);

  const std::vector<v1::SwingEvent> started = EventsOf(got, v1::SWING_EVENT_STARTED);
  ASSERT_EQ(started.size(), 1u);
  EXPECT_TRUE(started[0].driven());
  EXPECT_EQ(started[0].qalpha_nm(), 100.0);
  EXPECT_EQ(started[0].qbeta_nm(), -10.0);
  const std::vector<v1::SwingEvent> torques = EventsOf(got, v1::SWING_EVENT_TORQUE);
  ASSERT_EQ(torques.size(), 1u);
  EXPECT_EQ(torques[0].command_t_s(), 0.1);
  EXPECT_NEAR(torques[0].t_s(), 0.1, 1e-12);
  EXPECT_EQ(torques[0].command(), 1u);
  EXPECT_EQ(torques[0].qalpha_nm(), 100.0);
  EXPECT_EQ(torques[0].qbeta_nm(), 0.0);
  EXPECT_TRUE(torques[0].reason().empty()) << torques[0].reason();
  EXPECT_TRUE(EventsOf(got, v1::SWING_EVENT_COMMAND_REFUSED).empty());
  const std::vector<v1::SwingEvent> impacts = EventsOf(got, v1::SWING_EVENT_IMPACT);
  ASSERT_EQ(impacts.size(), 1u);
  ExpectSameImpact(impacts[0].impact(), ImpactProto(*want->impact));
  EXPECT_EQ(reg_.stats().commands, 1);
  EXPECT_EQ(reg_.stats().commands_refused, 0);

  // A command after the swing is refused (never an error), and the finished stream gets nothing.
  const size_t sent = got.size();
  reg_.Command(*drive, Cmd(0.2, 100, 0));
  EXPECT_EQ(reg_.stats().commands_refused, 1);
  EXPECT_EQ(sink.got().size(), sent);
}

// ---------------------------------------------------------------------------------------------
// Commands

// Refused commands (not finite, beyond a human, out of range, late, before the previous one)
// are reported to the driver with their code and reason and change nothing: with the one
// accepted command holding the same torques, the swing is SimulateSwing's with constant
// (100, -10) bit for bit.
TEST_F(SessionsTest, RefusedCommandsAreReportedAndChangeNothing) {
  const v1::CreateSessionResponse s = Create();  // realistic
  absl::StatusOr<sw::SwingRunResult> want =
      Reference(v1::CreateSessionRequest(), sw::TorqueProgram::Constant(100, -10));
  ASSERT_TRUE(want.ok()) << want.status();
  ASSERT_TRUE(want->impact.has_value());

  FakeSink& sink = NewSink();
  const std::shared_ptr<Drive> drive = StartDriving(DriveReq(s, 100, -10), sink);
  ASSERT_NE(drive, nullptr);
  const double not_finite = std::numeric_limits<double>::quiet_NaN();
  reg_.Command(*drive, Cmd(0.25, not_finite, -10));  // 1: not finite
  reg_.Command(*drive, Cmd(0.25, 1000, -10));  // 2: beyond a human shoulder
  reg_.Command(*drive, Cmd(-1, 100, -10));     // 3: before the swing
  // A late command is tested before the accepted one: later, "before the previous" would win.
  ASSERT_TRUE(WaitSwingTime(s.session_id(), 0.1).ok());
  reg_.Command(*drive, Cmd(0.05, 100, -10));  // 4: its tick was simulated
  reg_.Command(*drive, Cmd(0.2, 100, -10));   // 5: accepted (the same torques)
  reg_.Command(*drive, Cmd(0.15, 100, -10));  // 6: before the previous

  absl::StatusOr<v1::SessionInfo> info = WaitFinished(s.session_id());
  ASSERT_TRUE(info.ok()) << info.status();
  EXPECT_EQ(info->last_end_reason(), "impact");
  ExpectSameImpact(info->last_impact(), ImpactProto(*want->impact));
  EXPECT_EQ(reg_.stats().commands_refused, 5);
  EXPECT_EQ(reg_.stats().commands, 1);

  ASSERT_TRUE(WaitFor([&] { return sink.finished(); }));
  EXPECT_TRUE(sink.status().ok()) << sink.status();
  const std::vector<v1::SwingSnapshot> got = sink.got();
  const std::vector<v1::SwingEvent> refused = EventsOf(got, v1::SWING_EVENT_COMMAND_REFUSED);
  ASSERT_EQ(refused.size(), 5u);
  const struct {
    uint64_t command;
    int32_t code;
    const char* reason;
  } expected[] = {{1, kInvalidArgument, "finite"},
                  {2, kInvalidArgument, "human"},
                  {3, kOutOfRange, "t_s must be in"},
                  {4, kOutOfRange, "late"},
                  {6, kOutOfRange, "before the previous"}};
  for (size_t i = 0; i < refused.size(); ++i) {
    SCOPED_TRACE(absl::StrFormat("refusal %d: %s", static_cast<int>(i), refused[i].reason()));
    EXPECT_EQ(refused[i].command(), expected[i].command);
    EXPECT_EQ(refused[i].code(), expected[i].code);
    EXPECT_THAT(refused[i].reason(), HasSubstr(expected[i].reason));
    EXPECT_EQ(refused[i].swing_id(), 1u);
  }
  // The NaN is named in the reason, never echoed as a number; the finite values are.
  EXPECT_EQ(refused[0].qalpha_nm(), 0.0);
  EXPECT_EQ(refused[0].qbeta_nm(), -10.0);
  EXPECT_EQ(refused[0].command_t_s(), 0.25);
  const std::vector<v1::SwingEvent> torques = EventsOf(got, v1::SWING_EVENT_TORQUE);
  ASSERT_EQ(torques.size(), 1u);
  EXPECT_EQ(torques[0].command(), 5u);
  EXPECT_EQ(torques[0].command_t_s(), 0.2);
  EXPECT_NEAR(torques[0].t_s(), 0.2, 1e-12);
}

// Commands queued for ticks the swing never reaches are not lost silently: one past the last
// tick is refused at once (OUT_OF_RANGE), and those still waiting when the swing ends (here at
// impact, ~0.3 s) are refused with the last snapshot (FAILED_PRECONDITION), before ENDED.
TEST_F(SessionsTest, CommandsTheSwingNeverReachesAreRefusedNotDropped) {
  const v1::CreateSessionResponse s = Create();
  FakeSink& sink = NewSink();
  const std::shared_ptr<Drive> drive = StartDriving(DriveReq(s, 100, -10), sink);
  ASSERT_NE(drive, nullptr);
  reg_.Command(*drive, Cmd(1.0, 100, -10));  // 1: queued; impact comes first
  reg_.Command(*drive, Cmd(1.5, 100, -10));  // 2: queued too
  reg_.Command(*drive, Cmd(2.0, 100, -10));  // 3: the duration's own tick: never acts
  absl::StatusOr<v1::SessionInfo> info = WaitFinished(s.session_id());
  ASSERT_TRUE(info.ok()) << info.status();
  EXPECT_EQ(info->last_end_reason(), "impact");
  ASSERT_TRUE(WaitFor([&] { return sink.finished(); }));
  const std::vector<v1::SwingSnapshot> got = sink.got();
  const std::vector<v1::SwingEvent> refused = EventsOf(got, v1::SWING_EVENT_COMMAND_REFUSED);
  ASSERT_EQ(refused.size(), 3u);
  EXPECT_EQ(refused[0].command(), 3u);
  EXPECT_EQ(refused[0].code(), kOutOfRange);
  EXPECT_THAT(refused[0].reason(), HasSubstr("last tick"));
  for (size_t i = 1; i < 3; ++i) {
    EXPECT_EQ(refused[i].command(), i);
    EXPECT_EQ(refused[i].code(), static_cast<int32_t>(absl::StatusCode::kFailedPrecondition));
    EXPECT_THAT(refused[i].reason(), HasSubstr("ended (impact)"));
    EXPECT_EQ(refused[i].command_t_s(), i == 1 ? 1.0 : 1.5);
  }
  EXPECT_EQ(reg_.stats().commands_refused, 3);
  EXPECT_EQ(reg_.stats().commands, 0);
  EXPECT_EQ(reg_.stats().running, 0);
}

// With apply_late, a command whose tick was already simulated is applied at the next tick and
// reported as such; holding the same torques, it changes no bits.
TEST_F(SessionsTest, ApplyLateAppliesALateCommandAtTheNextTick) {
  const v1::CreateSessionResponse s = Create();
  absl::StatusOr<sw::SwingRunResult> want =
      Reference(v1::CreateSessionRequest(), sw::TorqueProgram::Constant(100, -10));
  ASSERT_TRUE(want.ok()) << want.status();
  ASSERT_TRUE(want->impact.has_value());

  FakeSink& sink = NewSink();
  v1::DriveStart start = DriveReq(s, 100, -10);
  start.set_apply_late(true);
  const std::shared_ptr<Drive> drive = StartDriving(start, sink);
  ASSERT_NE(drive, nullptr);
  absl::StatusOr<v1::SessionInfo> at = WaitSwingTime(s.session_id(), 0.1);
  ASSERT_TRUE(at.ok()) << at.status();
  const double simulated = at->state().t_s();
  reg_.Command(*drive, Cmd(0.05, 100, -10));

  absl::StatusOr<v1::SessionInfo> info = WaitFinished(s.session_id());
  ASSERT_TRUE(info.ok()) << info.status();
  ExpectSameImpact(info->last_impact(), ImpactProto(*want->impact));
  ASSERT_TRUE(WaitFor([&] { return sink.finished(); }));
  const std::vector<v1::SwingSnapshot> got = sink.got();
  EXPECT_TRUE(EventsOf(got, v1::SWING_EVENT_COMMAND_REFUSED).empty());
  const std::vector<v1::SwingEvent> torques = EventsOf(got, v1::SWING_EVENT_TORQUE);
  ASSERT_EQ(torques.size(), 1u);
  EXPECT_THAT(torques[0].reason(), HasSubstr("late"));
  EXPECT_EQ(torques[0].command_t_s(), 0.05);
  EXPECT_GE(torques[0].t_s(), simulated);  // not before what was simulated when it came
  const double ticks = torques[0].t_s() * 400.0;
  EXPECT_NEAR(ticks, std::round(ticks), 1e-6) << "applied between ticks";
  EXPECT_EQ(reg_.stats().commands_refused, 0);
  EXPECT_EQ(reg_.stats().commands, 1);
}

// ---------------------------------------------------------------------------------------------
// Realism

// The realistic profile refuses, before starting, a torque beyond a human (1000 N m) and a
// schedule under the torque bound whose swing passes 70 m/s (340 N m: about 71.7 m/s at
// impact); nothing changes. The arcade profile swings 1000 N m to a clubhead beyond 70 m/s.
TEST_F(SessionsTest, RealisticProfileRefusesInhumanSwingsAndArcadeAllowsThem) {
  const v1::CreateSessionResponse s = Create();
  const v1::SessionInfo before = Info(s.session_id());
  const auto shoulder = [&](const v1::CreateSessionResponse& to, double q) {
    v1::StartSwingRequest r = StartReq(to);
    v1::TorqueKnot* k = r.mutable_torques()->mutable_qalpha()->add_knots();
    k->set_t_s(0.0);
    k->set_torque_nm(q);
    return r;
  };
  absl::StatusOr<v1::StartSwingResponse> r = reg_.Start(shoulder(s, 1000));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument) << r.status();
  EXPECT_THAT(r.status().message(), HasSubstr("torques.qalpha.knots[0]"));
  r = reg_.Start(shoulder(s, 340));
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument) << r.status();
  EXPECT_THAT(r.status().message(), HasSubstr("m/s"));
  const v1::SessionInfo after = Info(s.session_id());
  EXPECT_EQ(after.phase(), v1::SWING_PHASE_ADDRESS);
  EXPECT_EQ(after.sequence(), before.sequence());
  EXPECT_EQ(after.swings(), 0u);
  EXPECT_EQ(reg_.stats().running, 0);

  const v1::CreateSessionResponse arcade = CreateArcade();
  EXPECT_EQ(arcade.profile(), "arcade");
  r = reg_.Start(shoulder(arcade, 1000));
  ASSERT_TRUE(r.ok()) << r.status();
  absl::StatusOr<v1::SessionInfo> info = WaitFinished(arcade.session_id());
  ASSERT_TRUE(info.ok()) << info.status();
  EXPECT_EQ(info->last_end_reason(), "impact");
  EXPECT_GT(info->last_impact().clubhead_speed_ground_mps(), 70.0);
}

// ---------------------------------------------------------------------------------------------
// Errors

// Wrong tokens are PERMISSION_DENIED, unknown ids NOT_FOUND, empty ids INVALID_ARGUMENT, and a
// second swing while one is in progress FAILED_PRECONDITION; none of them changes anything.
TEST_F(SessionsTest, WrongTokensUnknownIdsAndBusySessionsAreRefused) {
  v1::CreateSessionRequest create;
  create.set_seats(2);
  create.set_profile(v1::REALISM_PROFILE_ARCADE);  // a 1 s swing passes 70 m/s
  const v1::CreateSessionResponse s = Create(create);
  const std::string id = s.session_id();
  FakeSink& sink = NewSink();

  v1::StartSwingRequest start = StartReq(s);
  start.set_token(kWrongToken);
  EXPECT_EQ(reg_.Start(start).status().code(), absl::StatusCode::kPermissionDenied);
  v1::ResetSwingRequest reset = ResetReq(s);
  reset.set_token(kWrongToken);
  EXPECT_EQ(reg_.Reset(reset).status().code(), absl::StatusCode::kPermissionDenied);
  v1::DeleteSessionRequest del = DeleteReq(s);
  del.set_token(kWrongToken);
  EXPECT_EQ(reg_.Delete(del).code(), absl::StatusCode::kPermissionDenied);
  v1::DriveStart drive = DriveReq(s, 100, -10);
  drive.set_token(kWrongToken);
  EXPECT_EQ(reg_.StartDrive(drive, &sink).status().code(), absl::StatusCode::kPermissionDenied);

  for (const std::string& bad : {std::string(kUnknownId), std::string()}) {
    SCOPED_TRACE("session_id \"" + bad + "\"");
    const absl::StatusCode code =
        bad.empty() ? absl::StatusCode::kInvalidArgument : absl::StatusCode::kNotFound;
    EXPECT_EQ(reg_.Get(GetReq(bad)).status().code(), code);
    v1::StartSwingRequest st = StartReq(s);
    st.set_session_id(bad);
    EXPECT_EQ(reg_.Start(st).status().code(), code);
    v1::ResetSwingRequest re = ResetReq(s);
    re.set_session_id(bad);
    EXPECT_EQ(reg_.Reset(re).status().code(), code);
    v1::DeleteSessionRequest de = DeleteReq(s);
    de.set_session_id(bad);
    EXPECT_EQ(reg_.Delete(de).code(), code);
    EXPECT_EQ(reg_.Watch(WatchReq(bad), &sink).status().code(), code);
    v1::DriveStart dr = DriveReq(s, 100, -10);
    dr.set_session_id(bad);
    EXPECT_EQ(reg_.StartDrive(dr, &sink).status().code(), code);
  }
  v1::SessionInfo info = Info(id);
  EXPECT_EQ(info.phase(), v1::SWING_PHASE_ADDRESS);
  EXPECT_EQ(info.swings(), 0u);
  EXPECT_EQ(info.watchers(), 0u);
  EXPECT_EQ(reg_.stats().worlds, 1);

  start = StartReq(s);
  start.set_stop(v1::SWING_STOP_DURATION);
  start.set_duration_s(1.0);
  ASSERT_TRUE(reg_.Start(start).ok());
  absl::StatusOr<v1::StartSwingResponse> again = reg_.Start(StartReq(s));
  EXPECT_EQ(again.status().code(), absl::StatusCode::kFailedPrecondition) << again.status();
  EXPECT_THAT(again.status().message(), HasSubstr("in progress"));
  absl::StatusOr<std::shared_ptr<Drive>> busy = reg_.StartDrive(DriveReq(s, 100, -10), &sink);
  EXPECT_EQ(busy.status().code(), absl::StatusCode::kFailedPrecondition) << busy.status();
  info = Info(id);
  EXPECT_EQ(info.phase(), v1::SWING_PHASE_SWINGING);
  EXPECT_EQ(info.swings(), 1u);
  EXPECT_EQ(info.watchers(), 0u) << "a refused DriveSwing left its stream registered";
  EXPECT_EQ(reg_.stats().running, 1);

  // Any seat's token acts on the session: seat 1 ends the swing.
  reset = ResetReq(s);
  reset.set_token(s.seats(1).token());
  ASSERT_TRUE(reg_.Reset(reset).ok());
  info = Info(id);
  EXPECT_EQ(info.phase(), v1::SWING_PHASE_ADDRESS);
  EXPECT_EQ(info.last_end_reason(), "reset");
  EXPECT_EQ(reg_.stats().running, 0);
}

// ---------------------------------------------------------------------------------------------
// Reset

// Reset mid-swing ends it (ENDED "reset", then RESET, on every stream) and puts the golfer at
// the new address position: alpha = 0 and theta = gamma = 120 deg; the next swing starts there.
TEST_F(SessionsTest, ResetMidSwingEndsItAtANewAddressPosition) {
  const v1::CreateSessionResponse s = CreateArcade();  // a 1 s swing passes 70 m/s
  const std::string id = s.session_id();
  FakeSink& sink = NewSink();
  ASSERT_NE(Watch(WatchReq(id), sink), nullptr);
  v1::StartSwingRequest start = StartReq(s);
  start.set_stop(v1::SWING_STOP_DURATION);
  start.set_duration_s(1.0);
  ASSERT_TRUE(reg_.Start(start).ok());
  ASSERT_TRUE(WaitSwingTime(id, 0.05).ok());

  v1::ResetSwingRequest reset = ResetReq(s);
  reset.set_gamma_deg(120);
  absl::StatusOr<v1::ResetSwingResponse> done = reg_.Reset(reset);
  ASSERT_TRUE(done.ok()) << done.status();
  const v1::SessionInfo info = Info(id);
  EXPECT_EQ(info.phase(), v1::SWING_PHASE_ADDRESS);
  EXPECT_EQ(info.last_end_reason(), "reset");
  EXPECT_EQ(info.sequence(), done->sequence());
  EXPECT_EQ(info.swings(), 1u);
  EXPECT_EQ(info.gamma_deg(), 120.0);
  EXPECT_EQ(info.state().t_s(), 0.0);
  EXPECT_EQ(info.state().alpha_deg(), 0.0);
  EXPECT_NEAR(info.state().theta_deg(), 120.0, 1e-12);
  EXPECT_NEAR(info.state().beta_deg(), 120.0, 1e-12);  // beta0 unchanged
  EXPECT_EQ(reg_.stats().running, 0);

  ASSERT_TRUE(WaitFor([&] { return !EventsOf(sink.got(), v1::SWING_EVENT_RESET).empty(); }));
  const std::vector<v1::SwingSnapshot> got = sink.got();
  const std::vector<v1::SwingEvent> events = EventsOf(got);
  int ended = -1, was_reset = -1;
  for (size_t i = 0; i < events.size(); ++i) {
    if (events[i].kind() == v1::SWING_EVENT_ENDED) {
      EXPECT_EQ(ended, -1) << "two ENDED events";
      ended = static_cast<int>(i);
      EXPECT_EQ(events[i].reason(), "reset");
      EXPECT_EQ(events[i].swing_id(), 1u);
    }
    if (events[i].kind() == v1::SWING_EVENT_RESET) was_reset = static_cast<int>(i);
  }
  ASSERT_GE(ended, 0);
  EXPECT_GT(was_reset, ended);
  const v1::SwingSnapshot* last = LastFull(got);
  ASSERT_NE(last, nullptr);
  EXPECT_EQ(last->phase(), v1::SWING_PHASE_ADDRESS);
  EXPECT_EQ(last->state().alpha_deg(), 0.0);
  EXPECT_NEAR(last->state().theta_deg(), 120.0, 1e-12);

  start.set_duration_s(0.05);
  absl::StatusOr<v1::StartSwingResponse> next = reg_.Start(start);
  ASSERT_TRUE(next.ok()) << next.status();
  EXPECT_EQ(next->swing_id(), 2u);
  absl::StatusOr<v1::SessionInfo> finished = WaitFinished(id);
  ASSERT_TRUE(finished.ok()) << finished.status();
  EXPECT_EQ(finished->last_end_reason(), "duration");
  EXPECT_NEAR(finished->state().t_s(), 0.05, 1e-12);
}

// ---------------------------------------------------------------------------------------------
// Readers

// A watcher that never completes a write holds up neither the swing nor the other watcher: the
// chapter swing ends on time, the stalled stream keeps only the newest snapshot (replacing the
// rest), and the reader gets the impact exactly once.
TEST_F(SessionsTest, AStalledWatcherDelaysNeitherTheSwingNorTheOtherWatcher) {
  const v1::CreateSessionResponse s = Create();
  const std::string id = s.session_id();
  FakeSink& stalled = NewSink();
  FakeSink& reader = NewSink();
  const std::shared_ptr<SwingWatcher> stalled_w = Watch(WatchReq(id), stalled, /*read=*/false);
  const std::shared_ptr<SwingWatcher> reader_w = Watch(WatchReq(id), reader);
  ASSERT_TRUE(stalled_w != nullptr && reader_w != nullptr);
  ASSERT_EQ(stalled.got().size(), 1u);  // its first write, never completed

  const SteadyClock::time_point t0 = SteadyClock::now();
  ASSERT_TRUE(reg_.Start(StartReq(s)).ok());
  absl::StatusOr<v1::SessionInfo> info = WaitFinished(id, 3.0);
  const double took = std::chrono::duration<double>(SteadyClock::now() - t0).count();
  ASSERT_TRUE(info.ok()) << info.status();
  EXPECT_LT(took, info->last_impact().t_s() + 1.5);
  EXPECT_NEAR(info->last_impact().t_s(), 0.2914, 1e-3);

  EXPECT_EQ(stalled.got().size(), 1u);
  EXPECT_EQ(stalled_w->sent(), 1);
  EXPECT_GT(stalled_w->replaced(), 0);
  EXPECT_GT(reg_.stats().snapshots_replaced, 0);

  ASSERT_TRUE(WaitFor([&] { return GotFinished(reader); }));
  const std::vector<v1::SwingSnapshot> got = reader.got();
  EXPECT_EQ(EventsOf(got, v1::SWING_EVENT_IMPACT).size(), 1u);
  for (const v1::SwingSnapshot& snap : got) EXPECT_FALSE(snap.resync());
}

// A watcher whose client cancelled is finished CANCELLED, and Unwatch (what the gRPC layer
// calls when the stream is done) leaves no watcher behind.
TEST_F(SessionsTest, ACancelledWatcherIsForgottenOnUnwatch) {
  const v1::CreateSessionResponse s = Create();
  const std::string id = s.session_id();
  FakeSink& sink = NewSink();
  const std::shared_ptr<SwingWatcher> w = Watch(WatchReq(id), sink);
  ASSERT_NE(w, nullptr);
  EXPECT_EQ(Info(id).watchers(), 1u);
  w->OnCancel();
  ASSERT_TRUE(WaitFor([&] { return sink.finished(); }));
  EXPECT_EQ(sink.status().code(), absl::StatusCode::kCancelled) << sink.status();
  reg_.Unwatch(id, w.get());
  EXPECT_EQ(Info(id).watchers(), 0u);
  EXPECT_EQ(reg_.stats().watchers, 0);
  reg_.Unwatch(id, w.get());          // twice: harmless
  reg_.Unwatch(kUnknownId, w.get());  // an unknown session: harmless
  EXPECT_EQ(Info(id).watchers(), 0u);
}

// A driver that goes away mid-swing is forgotten at once and its stream gets nothing more; the
// swing goes on with the torques in force, to SimulateSwing's impact for constant (100, -10).
TEST_F(SessionsTest, ADriverThatGoesAwayLeavesTheSwingToFinishWithItsTorques) {
  const v1::CreateSessionResponse s = Create();
  const std::string id = s.session_id();
  absl::StatusOr<sw::SwingRunResult> want =
      Reference(v1::CreateSessionRequest(), sw::TorqueProgram::Constant(100, -10));
  ASSERT_TRUE(want.ok()) << want.status();
  ASSERT_TRUE(want->impact.has_value());
  FakeSink& sink = NewSink();
  const std::shared_ptr<Drive> drive = StartDriving(DriveReq(s, 100, -10), sink);
  ASSERT_NE(drive, nullptr);
  EXPECT_EQ(Info(id).watchers(), 1u);
  ASSERT_TRUE(WaitSwingTime(id, 0.05).ok());
  reg_.EndDrive(*drive, /*half_closed=*/false);
  EXPECT_EQ(Info(id).watchers(), 0u);
  EXPECT_EQ(reg_.stats().watchers, 0);
  reg_.EndDrive(*drive, /*half_closed=*/true);  // idempotent: the first call decided

  absl::StatusOr<v1::SessionInfo> info = WaitFinished(id);
  ASSERT_TRUE(info.ok()) << info.status();
  EXPECT_EQ(info->last_end_reason(), "impact");
  ExpectSameImpact(info->last_impact(), ImpactProto(*want->impact));
  EXPECT_FALSE(sink.finished()) << "the server finished a stream that went away";
  for (const v1::SwingSnapshot& snap : sink.got()) {
    EXPECT_NE(snap.phase(), v1::SWING_PHASE_FINISHED) << "written to after it went away";
  }
}

// A driver that half-closes gets its stream ended OK after a last snapshot; the swing goes on.
TEST_F(SessionsTest, ADriverThatHalfClosesGetsItsStreamEndedOk) {
  const v1::CreateSessionResponse s = Create();
  const std::string id = s.session_id();
  FakeSink& sink = NewSink();
  const std::shared_ptr<Drive> drive = StartDriving(DriveReq(s, 100, -10), sink);
  ASSERT_NE(drive, nullptr);
  ASSERT_TRUE(WaitSwingTime(id, 0.05).ok());
  reg_.EndDrive(*drive, /*half_closed=*/true);
  EXPECT_EQ(Info(id).watchers(), 0u);
  ASSERT_TRUE(WaitFor([&] { return sink.finished(); }));
  EXPECT_TRUE(sink.status().ok()) << sink.status();
  const std::vector<v1::SwingSnapshot> got = sink.got();
  const v1::SwingSnapshot* last = LastFull(got);
  ASSERT_NE(last, nullptr);
  EXPECT_EQ(&got.back(), last) << "the stream ended on a heartbeat";
  EXPECT_EQ(last->phase(), v1::SWING_PHASE_SWINGING);  // it ended before the swing did

  absl::StatusOr<v1::SessionInfo> info = WaitFinished(id);
  ASSERT_TRUE(info.ok()) << info.status();
  EXPECT_EQ(info->last_end_reason(), "impact");
  EXPECT_EQ(sink.got().size(), got.size());
}

// ---------------------------------------------------------------------------------------------
// Delete, shutdown, resume

// Delete (any seat's token) ends every stream with NOT_FOUND after a last full snapshot, at rest
// or mid-swing, and the session is gone for every call.
TEST_F(SessionsTest, DeleteEndsEveryStreamWithNotFoundAfterALastSnapshot) {
  const v1::CreateSessionResponse rest = Create();
  const v1::CreateSessionResponse moving = Create();
  FakeSink& rest_sink = NewSink();
  FakeSink& moving_sink = NewSink();
  ASSERT_NE(Watch(WatchReq(rest.session_id()), rest_sink), nullptr);
  ASSERT_NE(Watch(WatchReq(moving.session_id()), moving_sink), nullptr);
  ASSERT_TRUE(reg_.Start(StartReq(moving)).ok());
  ASSERT_TRUE(WaitSwingTime(moving.session_id(), 0.02).ok());

  v1::DeleteSessionRequest del = DeleteReq(rest);
  del.set_token(kWrongToken);
  EXPECT_EQ(reg_.Delete(del).code(), absl::StatusCode::kPermissionDenied);
  ASSERT_TRUE(reg_.Delete(DeleteReq(rest)).ok());
  ASSERT_TRUE(WaitFor([&] { return rest_sink.finished(); }));
  EXPECT_EQ(rest_sink.status().code(), absl::StatusCode::kNotFound) << rest_sink.status();
  std::vector<v1::SwingSnapshot> got = rest_sink.got();
  ASSERT_GE(got.size(), 2u);  // the first snapshot and the last
  EXPECT_FALSE(got.back().heartbeat());
  EXPECT_TRUE(got.back().has_state());
  EXPECT_EQ(got.back().phase(), v1::SWING_PHASE_ADDRESS);

  ASSERT_TRUE(reg_.Delete(DeleteReq(moving)).ok());
  ASSERT_TRUE(WaitFor([&] { return moving_sink.finished(); }));
  EXPECT_EQ(moving_sink.status().code(), absl::StatusCode::kNotFound) << moving_sink.status();
  got = moving_sink.got();
  ASSERT_FALSE(got.empty());
  EXPECT_FALSE(got.back().heartbeat());
  EXPECT_TRUE(got.back().has_state());

  const SessionStats st = reg_.stats();
  EXPECT_EQ(st.worlds, 0);
  EXPECT_EQ(st.running, 0);
  EXPECT_EQ(st.watchers, 0);
  for (const v1::CreateSessionResponse* s : {&rest, &moving}) {
    EXPECT_EQ(reg_.Get(GetReq(s->session_id())).status().code(), absl::StatusCode::kNotFound);
    EXPECT_EQ(reg_.Delete(DeleteReq(*s)).code(), absl::StatusCode::kNotFound);
    EXPECT_EQ(reg_.Start(StartReq(*s)).status().code(), absl::StatusCode::kNotFound);
    FakeSink& late = NewSink();
    EXPECT_EQ(reg_.Watch(WatchReq(s->session_id()), &late).status().code(),
              absl::StatusCode::kNotFound);
  }
}

// Shutdown ends every stream (watchers and drivers) with its status after a last full snapshot,
// and every later call is UNAVAILABLE.
TEST_F(SessionsTest, ShutdownEndsEveryStreamAndRefusesLaterCalls) {
  const v1::CreateSessionResponse watched = Create();
  const v1::CreateSessionResponse driven = Create();
  FakeSink& watch_sink = NewSink();
  FakeSink& drive_sink = NewSink();
  ASSERT_NE(Watch(WatchReq(watched.session_id()), watch_sink), nullptr);
  ASSERT_TRUE(reg_.Start(StartReq(watched)).ok());
  const std::shared_ptr<Drive> drive = StartDriving(DriveReq(driven, 100, -10), drive_sink);
  ASSERT_NE(drive, nullptr);
  ASSERT_TRUE(WaitSwingTime(watched.session_id(), 0.02).ok());

  reg_.Shutdown(absl::UnavailableError("stopping"));
  for (FakeSink* sink : {&watch_sink, &drive_sink}) {
    ASSERT_TRUE(WaitFor([&] { return sink->finished(); }));
    EXPECT_EQ(sink->status().code(), absl::StatusCode::kUnavailable) << sink->status();
    const std::vector<v1::SwingSnapshot> got = sink->got();
    ASSERT_FALSE(got.empty());
    EXPECT_FALSE(got.back().heartbeat());
    EXPECT_TRUE(got.back().has_state());
  }

  const absl::StatusCode unavailable = absl::StatusCode::kUnavailable;
  EXPECT_EQ(reg_.Create(v1::CreateSessionRequest()).status().code(), unavailable);
  EXPECT_EQ(reg_.Get(GetReq(watched.session_id())).status().code(), unavailable);
  EXPECT_EQ(reg_.List(v1::ListSessionsRequest()).status().code(), unavailable);
  EXPECT_EQ(reg_.Start(StartReq(driven)).status().code(), unavailable);
  EXPECT_EQ(reg_.Reset(ResetReq(watched)).status().code(), unavailable);
  EXPECT_EQ(reg_.Delete(DeleteReq(watched)).code(), unavailable);
  FakeSink& late = NewSink();
  EXPECT_EQ(reg_.Watch(WatchReq(watched.session_id()), &late).status().code(), unavailable);
  EXPECT_EQ(reg_.StartDrive(DriveReq(watched, 100, -10), &late).status().code(), unavailable);
  reg_.Shutdown(absl::UnavailableError("again"));  // idempotent
}

// WatchSwing with from_sequence replays the session's held events after that sequence (a
// finished swing: STARTED, IMPACT, ENDED); a sequence the session has not reached is
// OUT_OF_RANGE.
TEST_F(SessionsTest, ResumingReplaysTheEventsAfterTheGivenSequence) {
  const v1::CreateSessionResponse s = Create();
  const std::string id = s.session_id();
  EXPECT_EQ(Info(id).sequence(), 0u);
  ASSERT_TRUE(reg_.Start(StartReq(s)).ok());
  absl::StatusOr<v1::SessionInfo> info = WaitFinished(id);
  ASSERT_TRUE(info.ok()) << info.status();
  const uint64_t last = info->sequence();
  ASSERT_GT(last, 2u);

  const auto resume = [&](uint64_t from) {
    v1::WatchSwingRequest w = WatchReq(id);
    w.set_from_sequence(from);
    FakeSink& sink = NewSink();
    EXPECT_NE(Watch(w, sink, /*read=*/false), nullptr);
    const std::vector<v1::SwingSnapshot> got = sink.got();
    EXPECT_EQ(got.size(), 1u);  // the first write, with the replay
    return got.empty() ? v1::SwingSnapshot() : got[0];
  };
  v1::SwingSnapshot first = resume(0);
  EXPECT_FALSE(first.resync());
  EXPECT_EQ(first.sequence(), last);
  EXPECT_EQ(first.phase(), v1::SWING_PHASE_FINISHED);
  ASSERT_EQ(first.events_size(), 3);
  EXPECT_EQ(first.events(0).kind(), v1::SWING_EVENT_STARTED);
  EXPECT_EQ(first.events(1).kind(), v1::SWING_EVENT_IMPACT);
  EXPECT_EQ(first.events(2).kind(), v1::SWING_EVENT_ENDED);
  EXPECT_EQ(first.events(2).reason(), "impact");
  for (const v1::SwingEvent& e : first.events()) {
    EXPECT_GT(e.sequence(), 0u);
    EXPECT_LE(e.sequence(), last);
    EXPECT_EQ(e.swing_id(), 1u);
  }
  ExpectSameImpact(first.events(1).impact(), info->last_impact());

  first = resume(last - 1);
  ASSERT_EQ(first.events_size(), 2);
  EXPECT_EQ(first.events(0).kind(), v1::SWING_EVENT_IMPACT);
  EXPECT_EQ(first.events(1).kind(), v1::SWING_EVENT_ENDED);
  for (const v1::SwingEvent& e : first.events()) EXPECT_GT(e.sequence(), last - 1);

  first = resume(last);
  EXPECT_EQ(first.events_size(), 0);
  EXPECT_EQ(first.sequence(), last);

  v1::WatchSwingRequest ahead = WatchReq(id);
  ahead.set_from_sequence(last + 1);
  FakeSink& sink = NewSink();
  EXPECT_EQ(reg_.Watch(ahead, &sink).status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(Info(id).watchers(), 3u);  // the three resumed ones; the refused one is not kept
}

}  // namespace
}  // namespace sportsim::server
