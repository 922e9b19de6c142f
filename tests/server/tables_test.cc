// The table registry without a network: seats and turns, validation, the scheduler, and the
// watcher protocol (latest wins, events never lost, resync, resume) through fake sinks.
#include "server/billiards/table_world.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>

#include "absl/strings/str_format.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/billiards/convert.h"
#include "tests/server/fake_sink.h"
#include "sim/billiards/referee.h"
#include "sim/billiards/shot.h"

namespace sportsim::server {
namespace {

using ::testing::HasSubstr;
namespace b = ::sportsim::billiards;

using FakeSink = FakeSinkFor<Watcher>;

// A quick table: a 9-ball rack on heavy cloth so shots end within a second or two.
v1::CreateTableRequest QuickTable(double tick_hz = 1000) {
  v1::CreateTableRequest r;
  r.mutable_table()->set_rack("9ball");
  (*r.mutable_table()->mutable_params())["mu_roll"] = 0.3;
  (*r.mutable_table()->mutable_params())["spin_decel_rps2"] = 100;
  r.set_tick_hz(tick_hz);
  return r;
}

v1::CueStrike Break(double speed = 3.0) {
  v1::CueStrike s;
  s.set_ball_speed_mps(speed);
  s.set_phi_deg(0.5);
  s.set_b(0.2);
  return s;
}

absl::StatusOr<v1::TableInfo> WaitAtRest(TableRegistry& reg, const std::string& id,
                                         double timeout_s = 20) {
  const auto until = std::chrono::steady_clock::now() +
                     std::chrono::milliseconds(static_cast<int>(timeout_s * 1e3));
  v1::GetTableRequest get;
  get.set_table_id(id);
  for (;;) {
    absl::StatusOr<v1::TableInfo> info = reg.Get(get);
    if (!info.ok() || (info->at_rest() && info->shots() > 0)) return info;
    if (std::chrono::steady_clock::now() > until) {
      return absl::DeadlineExceededError("the table did not come to rest");
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

v1::ShootRequest Shot(const v1::CreateTableResponse& t, int seat, v1::CueStrike strike) {
  v1::ShootRequest r;
  r.set_table_id(t.table_id());
  r.set_token(t.seats(seat).token());
  *r.mutable_strike() = std::move(strike);
  return r;
}

// The same shot fast-forwarded by SimulateShot.
v1::SimulateShotResponse Reference(const v1::CreateTableRequest& table, const v1::CueStrike& s,
                                   double table_dt_s = 0) {
  v1::SimulateShotRequest req;
  *req.mutable_table() = table.table();
  *req.mutable_solver() = table.solver();
  *req.mutable_strike() = s;
  absl::StatusOr<ShotJob> job = ShotJobFromProto(req);
  EXPECT_TRUE(job.ok()) << job.status();
  if (table_dt_s > 0) job->solver.dt_s = table_dt_s;  // the step the table chose
  absl::StatusOr<b::ShotResult> result =
      b::SimulateShot(job->table.model, job->solver, job->table.state, job->shot);
  EXPECT_TRUE(result.ok()) << result.status();
  v1::SimulateShotResponse out;
  ShotResultToProto(*job, *result, &out);
  return out;
}

void ExpectSameBalls(const google::protobuf::RepeatedPtrField<v1::BallState>& got,
                     const google::protobuf::RepeatedPtrField<v1::BallState>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (int i = 0; i < got.size(); ++i) {
    // Bit for bit: the shot's states do not depend on the ticks or the load.
    EXPECT_EQ(got[i].SerializeAsString(), want[i].SerializeAsString())
        << got[i].DebugString() << " vs " << want[i].DebugString();
  }
}

class TablesTest : public ::testing::Test {
 protected:
  TableRegistry reg_{TableLimits{.world = {.max_worlds = 8, .max_watchers = 4, .event_log = 64,
                                 .watcher_backlog = 32}}};
  // Registers `sink` as a watcher (bound, so it detaches when destroyed) and sends the first
  // snapshot; null (and a test failure) if the registry refuses.
  std::shared_ptr<Watcher> Attach(FakeSink& sink, const v1::WatchTableRequest& w) {
    absl::StatusOr<std::shared_ptr<Watcher>> watcher = reg_.Watch(w, &sink);
    EXPECT_TRUE(watcher.ok()) << watcher.status();
    if (!watcher.ok()) return nullptr;
    sink.Bind(*watcher);
    (*watcher)->Pump();
    return *watcher;
  }
  v1::CreateTableResponse Create(const v1::CreateTableRequest& r = QuickTable()) {
    absl::StatusOr<v1::CreateTableResponse> t = reg_.Create(r);
    EXPECT_TRUE(t.ok()) << t.status();
    return t.ok() ? *t : v1::CreateTableResponse();
  }
};

TEST_F(TablesTest, CreateGivesSeatsWithDistinctSecretTokens) {
  v1::CreateTableRequest r = QuickTable();
  r.set_seats(3);
  const v1::CreateTableResponse t = Create(r);
  ASSERT_EQ(t.seats_size(), 3);
  EXPECT_EQ(t.engine(), "event");
  EXPECT_EQ(t.tick_hz(), 1000);
  EXPECT_NE(t.seats(0).token(), t.seats(1).token());
  EXPECT_GE(t.seats(0).token().size(), 32u);
  v1::GetTableRequest get;
  get.set_table_id(t.table_id());
  absl::StatusOr<v1::TableInfo> info = reg_.Get(get);
  ASSERT_TRUE(info.ok());
  EXPECT_EQ(info->balls_size(), 10);
  EXPECT_TRUE(info->at_rest());
  for (const v1::Seat& s : info->seats()) EXPECT_TRUE(s.token().empty()) << "tokens leaked";
}

TEST_F(TablesTest, BadCreateRequestsNameTheFieldAndCreateNothing) {
  const auto expect_bad = [&](v1::CreateTableRequest r, const std::string& field) {
    absl::StatusOr<v1::CreateTableResponse> t = reg_.Create(r);
    ASSERT_FALSE(t.ok()) << field;
    EXPECT_EQ(t.status().code(), absl::StatusCode::kInvalidArgument) << t.status();
    EXPECT_THAT(t.status().message(), HasSubstr(field));
  };
  v1::CreateTableRequest r = QuickTable();
  r.set_tick_hz(std::nan(""));
  expect_bad(r, "tick_hz");
  r.set_tick_hz(5000);
  expect_bad(r, "tick_hz");
  r = QuickTable();
  r.set_seats(17);
  expect_bad(r, "seats");
  r = QuickTable();
  r.add_seat_names("a");
  r.add_seat_names("");
  expect_bad(r, "seat_names[1]");
  r = QuickTable();
  r.mutable_table()->set_preset("pool-99ft");
  expect_bad(r, "table.preset");
  r = QuickTable(100);
  r.mutable_solver()->set_engine(v1::ENGINE_STEPPED);
  r.mutable_solver()->set_dt_s(0.003);  // 0.01 / 0.003 is not a whole number of steps
  expect_bad(r, "solver.dt_s");
  r = QuickTable();
  r.mutable_solver()->add_disable("gravity-ish");
  expect_bad(r, "solver.disable");
  absl::StatusOr<v1::ListTablesResponse> list = reg_.List({});
  ASSERT_TRUE(list.ok());
  EXPECT_EQ(list->total(), 0u);
}

TEST_F(TablesTest, TableLimitIsResourceExhausted) {
  for (int i = 0; i < 8; ++i) Create();
  absl::StatusOr<v1::CreateTableResponse> t = reg_.Create(QuickTable());
  ASSERT_FALSE(t.ok());
  EXPECT_EQ(t.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(t.status().message(), HasSubstr("max_tables"));
}

TEST_F(TablesTest, ShotEndsBitIdenticalToSimulateShotOnBothEngines) {
  for (const v1::Engine engine : {v1::ENGINE_EVENT, v1::ENGINE_STEPPED}) {
    for (const double hz : {1000.0, 120.0}) {
      SCOPED_TRACE(absl::StrFormat("engine %d, %g Hz", engine, hz));
      v1::CreateTableRequest r = QuickTable(hz);
      r.mutable_solver()->set_engine(engine);
      const v1::CreateTableResponse t = Create(r);
      const v1::CueStrike strike = Break(2.0);
      absl::StatusOr<v1::ShootResponse> shot = reg_.Shoot(Shot(t, 0, strike));
      ASSERT_TRUE(shot.ok()) << shot.status();
      absl::StatusOr<v1::TableInfo> info = WaitAtRest(reg_, t.table_id());
      ASSERT_TRUE(info.ok()) << info.status();
      if (engine == v1::ENGINE_STEPPED) {
        EXPECT_EQ(t.dt_s(), 1.0 / (hz > 960 ? 1000 : 960));
      }
      const v1::SimulateShotResponse want = Reference(r, strike, t.dt_s());
      ExpectSameBalls(info->balls(), want.balls());
      // The summary agrees with the reference's events.
      const v1::ShotSummary& s = info->last_shot();
      EXPECT_EQ(s.shot_id(), 1u);
      EXPECT_EQ(s.struck_ball(), "cue");
      EXPECT_TRUE(s.error().empty()) << s.error();
      std::string first;
      int rails = 0;
      for (const v1::TableEvent& e : want.events()) {
        if (e.kind() == v1::ball_ball && first.empty()) first = e.balls(0) == "cue" ? e.balls(1) : e.balls(0);
        rails += e.kind() == v1::ball_cushion;
      }
      EXPECT_EQ(s.first_ball_hit(), first);
      EXPECT_EQ(static_cast<int>(s.rails()), rails);
      EXPECT_NEAR(s.duration_s(), want.t_rest_s(), 1.0 / hz + 1e-12);
      EXPECT_GE(s.duration_s(), want.t_rest_s());
    }
  }
}

TEST_F(TablesTest, TurnsTokensAndMovingBalls) {
  const v1::CreateTableResponse t = Create();
  // Seat 1 may not shoot first; an unknown token (a spectator) never.
  absl::StatusOr<v1::ShootResponse> s = reg_.Shoot(Shot(t, 1, Break()));
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.status().code(), absl::StatusCode::kPermissionDenied);
  EXPECT_THAT(s.status().message(), HasSubstr("seat 0's turn"));
  v1::ShootRequest spectator = Shot(t, 0, Break());
  spectator.set_token("0123456789abcdef0123456789abcdef");
  s = reg_.Shoot(spectator);
  EXPECT_EQ(s.status().code(), absl::StatusCode::kPermissionDenied);
  spectator.set_token("");  // no token is a wrong token
  EXPECT_EQ(reg_.Shoot(spectator).status().code(), absl::StatusCode::kPermissionDenied);
  spectator.set_token(std::string(200, 'a'));
  EXPECT_EQ(reg_.Shoot(spectator).status().code(), absl::StatusCode::kPermissionDenied);
  // Seat 0 shoots and passes the turn; while balls move nobody shoots or places.
  v1::ShootRequest first = Shot(t, 0, Break());
  first.set_next_seat(1);
  ASSERT_TRUE(reg_.Shoot(first).ok());
  s = reg_.Shoot(Shot(t, 1, Break()));
  EXPECT_EQ(s.status().code(), absl::StatusCode::kFailedPrecondition) << s.status();
  v1::PlaceBallRequest place;
  place.set_table_id(t.table_id());
  place.set_token(t.seats(1).token());
  place.mutable_ball()->set_id("cue");
  place.mutable_ball()->set_x_m(-0.6);
  EXPECT_EQ(reg_.Place(place).status().code(), absl::StatusCode::kFailedPrecondition);
  ASSERT_TRUE(WaitAtRest(reg_, t.table_id()).ok());
  // Now seat 0 is refused and seat 1 plays.
  EXPECT_EQ(reg_.Shoot(Shot(t, 0, Break())).status().code(),
            absl::StatusCode::kPermissionDenied);
  // next_seat out of range changes nothing.
  v1::ShootRequest bad = Shot(t, 1, Break());
  bad.set_next_seat(2);
  EXPECT_EQ(reg_.Shoot(bad).status().code(), absl::StatusCode::kInvalidArgument);
  v1::SetTurnRequest turn;
  turn.set_table_id(t.table_id());
  turn.set_token(t.seats(0).token());
  turn.set_seat(0);
  EXPECT_EQ(reg_.SetTurn(turn).status().code(), absl::StatusCode::kPermissionDenied);
  turn.set_token(t.seats(1).token());
  ASSERT_TRUE(reg_.SetTurn(turn).ok());
  v1::GetTableRequest get;
  get.set_table_id(t.table_id());
  EXPECT_EQ(reg_.Get(get)->turn(), 0u);
  EXPECT_EQ(reg_.Get(get)->shots(), 1u);
}

TEST_F(TablesTest, BadShotsAndPlacementsChangeNothing) {
  const v1::CreateTableResponse t = Create();
  v1::GetTableRequest get;
  get.set_table_id(t.table_id());
  const v1::TableInfo before = *reg_.Get(get);
  const auto expect = [&](absl::Status s, absl::StatusCode code, const std::string& field) {
    EXPECT_EQ(s.code(), code) << s;
    EXPECT_THAT(s.message(), HasSubstr(field));
  };
  v1::CueStrike nan = Break();
  nan.set_phi_deg(std::nan(""));
  expect(reg_.Shoot(Shot(t, 0, nan)).status(), absl::StatusCode::kInvalidArgument, "strike.phi");
  v1::CueStrike miscue = Break();
  miscue.set_a(0.9);
  miscue.set_b(0.9);
  expect(reg_.Shoot(Shot(t, 0, miscue)).status(), absl::StatusCode::kInvalidArgument, "strike.");
  v1::CueStrike ghost = Break();
  ghost.set_ball("ghost");
  expect(reg_.Shoot(Shot(t, 0, ghost)).status(), absl::StatusCode::kInvalidArgument,
         "strike.ball");
  v1::ShootRequest unknown = Shot(t, 0, Break());
  unknown.set_table_id("t-nope");
  expect(reg_.Shoot(unknown).status(), absl::StatusCode::kNotFound, "table_id");

  v1::PlaceBallRequest place;
  place.set_table_id(t.table_id());
  place.set_token(t.seats(0).token());
  place.mutable_ball()->set_id("cue");
  place.mutable_ball()->set_x_m(std::numeric_limits<double>::infinity());
  expect(reg_.Place(place).status(), absl::StatusCode::kInvalidArgument, "ball");
  place.mutable_ball()->set_x_m(before.balls(1).x_m());  // on top of the 1 ball
  place.mutable_ball()->set_y_m(before.balls(1).y_m());
  expect(reg_.Place(place).status(), absl::StatusCode::kInvalidArgument, "overlap");
  place.mutable_ball()->set_x_m(5.0);
  expect(reg_.Place(place).status(), absl::StatusCode::kInvalidArgument, "not on the cloth");
  // In a pocket's capture circle, where the cloth reaches into it (a point the rails allow).
  absl::StatusOr<v1::TableInfo> geo = [&] {
    v1::GetTableRequest g = get;
    g.set_include_geometry(true);
    return reg_.Get(g);
  }();
  ASSERT_TRUE(geo.ok());
  const double lim_x = 0.5 * geo->geometry().length_m() - geo->geometry().cushion_contact_m();
  const double lim_y = 0.5 * geo->geometry().width_m() - geo->geometry().cushion_contact_m();
  bool found = false;
  for (const v1::PocketCircle& p : geo->geometry().pockets()) {
    const double x = std::clamp(p.x_m(), -lim_x, lim_x);
    const double y = std::clamp(p.y_m(), -lim_y, lim_y);
    if (std::hypot(x - p.x_m(), y - p.y_m()) < p.radius_m() && !found) {
      found = true;
      place.mutable_ball()->set_x_m(x);
      place.mutable_ball()->set_y_m(y);
      expect(reg_.Place(place).status(), absl::StatusCode::kInvalidArgument, "capture circle");
    }
  }
  EXPECT_TRUE(found) << "no point of the cloth lies in a capture circle: the check is untested";
  place.mutable_ball()->set_id("");
  expect(reg_.Place(place).status(), absl::StatusCode::kInvalidArgument, "ball.id");

  const v1::TableInfo after = *reg_.Get(get);
  EXPECT_EQ(after.sequence(), before.sequence());
  EXPECT_EQ(after.shots(), 0u);
  ExpectSameBalls(after.balls(), before.balls());

  // A good placement moves the ball and bumps the sequence.
  place.mutable_ball()->set_id("cue");
  place.mutable_ball()->set_x_m(-0.7);
  place.mutable_ball()->set_y_m(0.1);
  ASSERT_TRUE(reg_.Place(place).ok());
  const v1::TableInfo placed = *reg_.Get(get);
  EXPECT_EQ(placed.sequence(), before.sequence() + 1);
  EXPECT_EQ(placed.balls(0).x_m(), -0.7);
}

TEST_F(TablesTest, DeleteNeedsASeatTokenAndEndsWatchers) {
  const v1::CreateTableResponse t = Create();
  FakeSink sink;
  v1::WatchTableRequest w;
  w.set_table_id(t.table_id());
  const std::shared_ptr<Watcher> watcher = Attach(sink, w);
  ASSERT_NE(watcher, nullptr);
  sink.StartReading(watcher, std::chrono::microseconds(200));
  v1::DeleteTableRequest del;
  del.set_table_id(t.table_id());
  del.set_token("not-a-token");
  EXPECT_EQ(reg_.Delete(del).code(), absl::StatusCode::kPermissionDenied);
  del.set_token(t.seats(1).token());
  ASSERT_TRUE(reg_.Delete(del).ok());
  for (int i = 0; i < 200 && !sink.finished(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_TRUE(sink.finished());
  EXPECT_EQ(sink.status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(reg_.Delete(del).code(), absl::StatusCode::kNotFound);
  v1::GetTableRequest get;
  get.set_table_id(t.table_id());
  EXPECT_EQ(reg_.Get(get).status().code(), absl::StatusCode::kNotFound);
}

TEST_F(TablesTest, WatcherSeesEveryEventAndTheFinalStateWhileAStalledOneStaysBounded) {
  const v1::CreateTableResponse t = Create();
  FakeSink reader, stalled;
  v1::WatchTableRequest w;
  w.set_table_id(t.table_id());
  w.set_rate_hz(60);
  const std::shared_ptr<Watcher> rw = Attach(reader, w);
  const std::shared_ptr<Watcher> sw = Attach(stalled, w);
  ASSERT_TRUE(rw != nullptr && sw != nullptr);
  reader.StartReading(rw, std::chrono::microseconds(100));
  // stalled: its first write never completes.
  const v1::CueStrike strike = Break(3.0);
  ASSERT_TRUE(reg_.Shoot(Shot(t, 0, strike)).ok());
  absl::StatusOr<v1::TableInfo> info = WaitAtRest(reg_, t.table_id());
  ASSERT_TRUE(info.ok());
  for (int i = 0; i < 200; ++i) {
    const auto got = reader.got();
    if (!got.empty() && got.back().at_rest() && got.back().events_size() > 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  reader.StopReading();
  const std::vector<v1::TableSnapshot> got = reader.got();
  ASSERT_GE(got.size(), 3u);
  // Every event exactly once, in order; the last snapshot is the final state.
  const v1::SimulateShotResponse want = Reference(QuickTable(), strike);
  std::vector<const v1::TableEvent*> physics;
  bool resync = false;
  uint64_t last_seq = 0;
  for (const v1::TableSnapshot& s : got) {
    // Every snapshot is a full one (events never travel alone, so the rate holds).
    EXPECT_EQ(s.balls_size(), 10);
    EXPECT_GE(s.tick(), got.front().tick());
    resync |= s.resync();
    EXPECT_GE(s.sequence(), last_seq);
    last_seq = s.sequence();
    for (const v1::TableEvent& e : s.events()) {
      if (e.kind() <= v1::transition) physics.push_back(&e);
    }
  }
  EXPECT_FALSE(resync);
  ASSERT_EQ(physics.size(), static_cast<size_t>(want.events_size()));
  for (size_t i = 0; i < physics.size(); ++i) {
    EXPECT_EQ(physics[i]->kind(), want.events(i).kind()) << i;
    EXPECT_THAT(physics[i]->balls(), ::testing::ElementsAreArray(want.events(i).balls())) << i;
  }
  ExpectSameBalls(got.back().balls(), want.balls());
  EXPECT_TRUE(got.back().at_rest());
  // At 60 Hz on a 1 kHz table the reader got roughly one snapshot per 1/60 s of the shot.
  const double shot_s = info->last_shot().duration_s();
  EXPECT_GT(static_cast<double>(got.size()), 0.25 * 60 * shot_s);
  EXPECT_LT(static_cast<double>(got.size()), 1.5 * 60 * shot_s + 5);
  // The stalled watcher got one write (the first snapshot), still in flight; its backlog of 32
  // events overflowed, so it is marked for a resync, never grown without bound.
  EXPECT_EQ(stalled.got().size(), 1u);
  EXPECT_EQ(sw->sent(), 1);
  EXPECT_GT(sw->replaced(), 0);
  EXPECT_GT(reg_.stats().resyncs, 0);
}

TEST_F(TablesTest, LatestWinsAndEventsRideAlong) {
  // The watcher alone: while a write is in flight, three frames come; one write carries the
  // newest and the events of all three.
  WatchOptions o;
  Watcher w("t", o, /*interval_ticks=*/1.0, /*backlog=*/1024);
  FakeSink sink;
  w.Attach(&sink);
  auto frame = [](uint64_t seq) {
    auto f = std::make_shared<Frame>();
    f->sequence = seq;
    f->tick = static_cast<int64_t>(seq);
    f->at_rest = false;
    return f;
  };
  auto event = [](uint64_t seq) {
    v1::TableEvent e;
    e.set_sequence(seq);
    e.set_kind(v1::ball_ball);
    return std::make_shared<const v1::TableEvent>(e);
  };
  ASSERT_TRUE(w.Offer(frame(1), {event(1)}));
  w.Pump();
  EXPECT_EQ(sink.got().size(), 1u);
  EXPECT_FALSE(w.Offer(frame(2), {event(2)}));
  EXPECT_FALSE(w.Offer(frame(3), {event(3)}));
  EXPECT_FALSE(w.OfferHeartbeat(frame(4)));  // never replaces a real frame
  EXPECT_FALSE(w.Offer(nullptr, {event(4)}));
  w.OnWriteDone(true);
  const auto got = sink.got();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[1].tick(), 3);
  EXPECT_EQ(got[1].sequence(), 4u);
  ASSERT_EQ(got[1].events_size(), 3);
  EXPECT_EQ(got[1].events(2).sequence(), 4u);
  EXPECT_EQ(got[1].snapshots_replaced(), 1u);
  EXPECT_FALSE(got[1].resync());
  // Cancelled: finished once, nothing written after.
  w.OnCancel();
  w.Offer(frame(5), {event(5)});
  w.OnWriteDone(false);
  EXPECT_EQ(sink.got().size(), 2u);
  EXPECT_TRUE(sink.finished());
  EXPECT_EQ(sink.status().code(), absl::StatusCode::kCancelled);
}

TEST_F(TablesTest, ResumeReplaysHeldEventsOrResyncs) {
  const v1::CreateTableResponse t = Create();
  ASSERT_TRUE(reg_.Shoot(Shot(t, 0, Break(1.0))).ok());
  ASSERT_TRUE(WaitAtRest(reg_, t.table_id()).ok());
  v1::GetTableRequest get;
  get.set_table_id(t.table_id());
  const uint64_t seq = reg_.Get(get)->sequence();
  v1::WatchTableRequest w;
  w.set_table_id(t.table_id());
  w.set_from_sequence(seq - 1);
  FakeSink recent;
  const std::shared_ptr<Watcher> rw = Attach(recent, w);
  ASSERT_NE(rw, nullptr);
  ASSERT_EQ(recent.got().size(), 1u);
  const v1::TableSnapshot first = recent.got()[0];
  EXPECT_FALSE(first.resync());
  ASSERT_GE(first.events_size(), 1);
  EXPECT_EQ(first.events(first.events_size() - 1).kind(), v1::shot_end);
  for (const v1::TableEvent& e : first.events()) EXPECT_EQ(e.sequence(), seq);
  EXPECT_EQ(first.sequence(), seq);

  // Many placements push the shot out of the 64-event log: resuming before them resyncs.
  v1::PlaceBallRequest place;
  place.set_table_id(t.table_id());
  place.set_token(t.seats(0).token());
  place.mutable_ball()->set_id("extra");
  for (int i = 0; i < 70; ++i) {
    place.mutable_ball()->set_x_m(-0.9 + 0.001 * i);
    place.mutable_ball()->set_y_m(0.5);
    ASSERT_TRUE(reg_.Place(place).ok()) << i;
  }
  w.set_from_sequence(1);
  FakeSink old;
  const std::shared_ptr<Watcher> ow = Attach(old, w);
  ASSERT_NE(ow, nullptr);
  ASSERT_EQ(old.got().size(), 1u);
  EXPECT_TRUE(old.got()[0].resync());
  EXPECT_EQ(old.got()[0].balls_size(), 11);  // the full state
  // The 64 events still held are more than this registry's watcher backlog (32): they count as
  // lost too, rather than one reader holding more than its share.
  EXPECT_EQ(old.got()[0].events_size(), 0);
  EXPECT_EQ(old.got()[0].events_lost(), 64u);

  w.set_from_sequence(seq + 1000);
  FakeSink ahead;
  EXPECT_EQ(reg_.Watch(w, &ahead).status().code(), absl::StatusCode::kOutOfRange);
  w.clear_from_sequence();
  w.set_rate_hz(5000);  // over 1000 Hz
  EXPECT_EQ(reg_.Watch(w, &ahead).status().code(), absl::StatusCode::kInvalidArgument);
  w.set_rate_hz(0);
  w.add_fields(static_cast<v1::SnapshotField>(99));
  EXPECT_EQ(reg_.Watch(w, &ahead).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST_F(TablesTest, WatcherLimitAndFieldsAndChangedOnly) {
  const v1::CreateTableResponse t = Create();
  v1::WatchTableRequest w;
  w.set_table_id(t.table_id());
  w.add_fields(v1::SNAPSHOT_FIELD_POSITION);
  w.set_changed_only(true);
  std::vector<std::unique_ptr<FakeSink>> sinks;
  std::vector<std::shared_ptr<Watcher>> watchers;
  for (int i = 0; i < 4; ++i) {
    sinks.push_back(std::make_unique<FakeSink>());
    watchers.push_back(Attach(*sinks.back(), w));
    ASSERT_NE(watchers.back(), nullptr);
  }
  FakeSink extra;
  absl::StatusOr<std::shared_ptr<Watcher>> x = reg_.Watch(w, &extra);
  EXPECT_EQ(x.status().code(), absl::StatusCode::kResourceExhausted);
  const v1::TableSnapshot first = sinks[0]->got().at(0);
  ASSERT_EQ(first.balls_size(), 10);
  EXPECT_NE(first.balls(0).x_m(), 0.0);
  EXPECT_TRUE(first.balls(0).has_x_m());
  EXPECT_FALSE(first.balls(0).has_qw());  // orientation not asked for: absent, not zero
  EXPECT_FALSE(first.balls(0).has_vx_mps());
  // A placement: with changed_only, only the moved ball comes next.
  sinks[0]->StartReading(watchers[0], std::chrono::microseconds(100));
  v1::PlaceBallRequest place;
  place.set_table_id(t.table_id());
  place.set_token(t.seats(0).token());
  place.mutable_ball()->set_id("cue");
  place.mutable_ball()->set_x_m(-0.8);
  ASSERT_TRUE(reg_.Place(place).ok());
  for (int i = 0; i < 200 && sinks[0]->got().size() < 2; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  sinks[0]->StopReading();
  ASSERT_GE(sinks[0]->got().size(), 2u);
  const v1::TableSnapshot second = sinks[0]->got()[1];
  ASSERT_EQ(second.balls_size(), 1);
  EXPECT_EQ(second.balls(0).id(), "cue");
  EXPECT_EQ(second.balls(0).x_m(), -0.8);
}

TEST_F(TablesTest, ShutdownEndsStreamsWithALastSnapshotAndRefusesCalls) {
  const v1::CreateTableResponse t = Create();
  FakeSink sink;
  v1::WatchTableRequest w;
  w.set_table_id(t.table_id());
  const std::shared_ptr<Watcher> watcher = Attach(sink, w);
  ASSERT_NE(watcher, nullptr);
  sink.StartReading(watcher, std::chrono::microseconds(100));
  ASSERT_TRUE(reg_.Shoot(Shot(t, 0, Break(3.0))).ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  reg_.Shutdown(absl::UnavailableError("stopping"));
  for (int i = 0; i < 200 && !sink.finished(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  sink.StopReading();
  ASSERT_TRUE(sink.finished());
  EXPECT_EQ(sink.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_GE(sink.got().size(), 2u);
  EXPECT_EQ(sink.got().back().balls_size(), 10);  // the last snapshot is a full state
  EXPECT_EQ(reg_.Create(QuickTable()).status().code(), absl::StatusCode::kUnavailable);
}

TEST_F(TablesTest, TheSameShotGivesTheSameBitsOnManyTablesAtOnce) {
  // Eight tables struck together share the workers; load and timing do not reach the physics.
  std::vector<v1::CreateTableResponse> tables;
  for (int i = 0; i < 8; ++i) tables.push_back(Create(QuickTable(1000)));
  for (const v1::CreateTableResponse& t : tables) {
    ASSERT_TRUE(reg_.Shoot(Shot(t, 0, Break(4.0))).ok());
  }
  std::string first;
  int64_t ticks = -1;
  for (const v1::CreateTableResponse& t : tables) {
    absl::StatusOr<v1::TableInfo> info = WaitAtRest(reg_, t.table_id());
    ASSERT_TRUE(info.ok());
    // The shot ends on the same tick of its own, however the workers got to the table.
    const int64_t took = info->last_shot().end_tick() - info->last_shot().start_tick();
    if (ticks < 0) ticks = took;
    EXPECT_EQ(took, ticks);
    std::string bits;
    for (const v1::BallState& ball : info->balls()) bits += ball.SerializeAsString();
    if (first.empty()) first = bits;
    EXPECT_EQ(bits, first);
  }
  const WorldStats s = reg_.stats();
  EXPECT_GT(s.ticks, 0);
  EXPECT_EQ(s.running, 0);
}

TEST_F(TablesTest, SeatNamesAloneSetTheSeats) {
  v1::CreateTableRequest r = QuickTable();
  r.add_seat_names("alice");
  const v1::CreateTableResponse t = Create(r);
  ASSERT_EQ(t.seats_size(), 1);
  EXPECT_EQ(t.seats(0).name(), "alice");
}

TEST_F(TablesTest, AnEngineFailureVoidsTheShot) {
  // An event cap of 20 stops the break early: the shot ends with the error, the balls go back.
  v1::CreateTableRequest r = QuickTable();
  r.mutable_solver()->set_max_events(20);
  const v1::CreateTableResponse t = Create(r);
  v1::GetTableRequest get;
  get.set_table_id(t.table_id());
  const v1::TableInfo before = *reg_.Get(get);
  ASSERT_TRUE(reg_.Shoot(Shot(t, 0, Break(3.0))).ok());
  absl::StatusOr<v1::TableInfo> after = WaitAtRest(reg_, t.table_id());
  ASSERT_TRUE(after.ok());
  EXPECT_THAT(after->last_shot().error(), HasSubstr("put back"));
  ExpectSameBalls(after->balls(), before.balls());
  // The table plays on.
  EXPECT_TRUE(reg_.Shoot(Shot(t, 0, Break(0.2))).ok());
}

TEST(ShotRefereeTest, FirstHitRailsAfterContactAndPockets) {
  b::ShotReferee r(0);
  r.Observe(b::Event{.kind = b::EventKind::kBallCushion, .a = 0});
  r.Observe(b::Event{.kind = b::EventKind::kBallBall, .a = 2, .b = 1});  // not the struck ball
  r.Observe(b::Event{.kind = b::EventKind::kBallBall, .a = 3, .b = 0});
  r.Observe(b::Event{.kind = b::EventKind::kBallBall, .a = 0, .b = 1});
  r.Observe(b::Event{.kind = b::EventKind::kBallCushion, .a = 3});
  r.Observe(b::Event{.kind = b::EventKind::kBallPocket, .a = 1});
  r.Observe(b::Event{.kind = b::EventKind::kBallPocket, .a = 0});
  const b::ShotFacts& f = r.facts();
  EXPECT_EQ(f.first_hit, 3);
  EXPECT_EQ(f.rails, 2);
  EXPECT_EQ(f.rails_after_contact, 1);
  EXPECT_THAT(f.pocketed, ::testing::ElementsAre(1, 0));
  EXPECT_TRUE(f.struck_pocketed);
}

}  // namespace
}  // namespace sportsim::server
