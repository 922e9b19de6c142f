// The round registry without a network: a whole scripted two-player round played against the
// same referee offline, bit for bit; its record replayed; a restore from the journal halfway;
// the cheating list refused and changing nothing; watchers' events.
#include "server/swing/round_world.h"

#include <google/protobuf/util/message_differencer.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/golf/round.h"
#include "tests/server/fake_sink.h"

namespace sportsim::server {
namespace {

using ::google::protobuf::util::MessageDifferencer;
using ::testing::HasSubstr;
using FakeSink = FakeSinkFor<RoundWatcher>;

constexpr double kDeg = std::numbers::pi / 180.0;

bool WaitFor(const std::function<bool()>& done, double timeout_s = 10.0) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    if (done()) return true;
    if (std::chrono::steady_clock::now() > until) return done();
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

// Every entry in memory, handed back as a store would.
class MemoryJournal final : public Journal {
 public:
  absl::Status Append(JournalEntry entry) override {
    absl::MutexLock lock(&mu_);
    entries_.push_back(std::move(entry));
    return absl::OkStatus();
  }
  absl::Status Remove(JournalEntry deletion) override { return Append(std::move(deletion)); }
  void Checkpoint(const std::string&, uint64_t, int64_t, std::string) override {}
  void Anchor(const std::string&, int64_t, double) override {}
  double NodeSeconds() const override { return 0.0; }
  absl::Status Healthy() const override { return absl::OkStatus(); }
  StoredWorld Stored(const std::string& id, int64_t reached) const {
    absl::MutexLock lock(&mu_);
    StoredWorld w{.world_id = id, .kind = "round"};
    for (const JournalEntry& e : entries_) {
      if (e.world_id == id) w.entries.push_back(e);
    }
    w.anchor_tick = reached;
    return w;
  }

 private:
  mutable absl::Mutex mu_;
  std::vector<JournalEntry> entries_ ABSL_GUARDED_BY(mu_);
};

v1::CreateRoundRequest TwoPlayers(int first = 1, int last = 3) {
  v1::CreateRoundRequest r;
  r.set_course("sportsim_links");
  r.set_first_hole(first);
  r.set_last_hole(last);
  r.add_players()->set_name("Ann");
  v1::RoundPlayerSpec* bob = r.add_players();
  bob->set_name("Bob");
  bob->set_tee("red");
  r.set_seed(11);
  r.set_fast_forward(true);
  return r;
}

// The referee's state offline, for the wire, as the server builds it.
v1::RoundState Offline(const golf::Course& c, const golf::RoundSettings& s, const golf::RoundState& st) {
  v1::RoundState out;
  RoundStateToProto(c, s, st, false, &out);
  return out;
}

// A scripted player: among a fan of strokes (launches by distance, putts near and on the
// green), the one that ends nearest the hole, tried offline on the referee's own state.
v1::PlayStrokeRequest Bot(const golf::Course& c, const golf::RoundSettings& s,
                          const golf::RoundState& st, int seat) {
  const golf::RoundBall& b = st.players[seat].ball;
  const Eigen::Vector2d pin = *c.Hole(st.hole)->pin_m;
  const double d = (pin - b.position_m.head<2>()).norm();
  const double aim = std::atan2(pin.y() - b.position_m.y(), pin.x() - b.position_m.x()) / kDeg;
  std::vector<golf::RoundStroke> fan;
  if (d < 25.0 || b.lie == golf::Terrain::kGreen) {
    for (double f : {0.9, 1.0, 1.1, 1.2, 0.8}) {
      for (double da : {0.0, 1.5, -1.5}) {
        golf::RoundStroke k;
        k.kind = golf::RoundStroke::Kind::kPutt;
        k.speed_mps = std::min(12.0, 1.4 * f * std::sqrt(1.2 * (d + 0.3)));
        k.aim_deg = aim + da;
        fan.push_back(k);
      }
    }
  }
  if (d >= 12.0) {
    const bool long_shot = d > 150.0;
    for (double v = long_shot ? 40.0 : 12.0; v <= (long_shot ? 72.0 : 50.0); v += long_shot ? 4.0 : 3.0) {
      golf::RoundStroke k;
      k.launch = golf::LaunchConditions{.ball_speed_mps = v, .launch_angle_deg = long_shot ? 12.0 : 28.0,
                                        .launch_direction_deg = 0, .spin_rpm = long_shot ? 2800.0 : 6500.0,
                                        .spin_axis_deg = 0};
      k.aim_deg = aim;
      fan.push_back(k);
    }
  }
  double best = 1e18;
  golf::RoundStroke chosen = fan.front();
  for (const golf::RoundStroke& k : fan) {
    absl::StatusOr<golf::RoundStep> r = golf::PlayStroke(c, s, st, seat, k);
    if (!r.ok()) continue;
    const golf::RoundPlayer& p = r->state.players[seat];
    const bool holed = r->state.hole != st.hole || r->state.over || p.ball.holed;
    double score = holed ? 0.0 : (p.ball.position_m.head<2>() - pin).norm();
    score += 100.0 * (p.penalties - st.players[seat].penalties) + (r->state.decision ? 100.0 : 0.0);
    if (score < best) {
      best = score;
      chosen = k;
    }
  }
  v1::PlayStrokeRequest q;
  if (chosen.kind == golf::RoundStroke::Kind::kPutt) {
    q.set_putt_speed_mps(chosen.speed_mps);
    q.set_aim_deg(*chosen.aim_deg);
  } else {
    v1::LaunchConditions* l = q.mutable_launch();
    l->set_ball_speed_mps(chosen.launch.ball_speed_mps);
    l->set_launch_angle_deg(chosen.launch.launch_angle_deg);
    l->set_spin_rpm(chosen.launch.spin_rpm);
    q.set_aim_deg(*chosen.aim_deg);
  }
  return q;
}

class RoundsTest : public ::testing::Test {
 protected:
  RoundsTest() : reg_(std::make_unique<RoundRegistry>(Limits(), nullptr, 2)) {}

  static RoundLimits Limits() {
    RoundLimits l;
    l.world.clock_rate = 20.0;  // strokes come to rest at the next tick anyway (fast_forward)
    return l;
  }

  v1::RoundInfo Get(const std::string& id) {
    v1::GetRoundRequest g;
    g.set_round_id(id);
    absl::StatusOr<v1::RoundInfo> info = reg_->Get(g);
    EXPECT_TRUE(info.ok()) << info.status();
    return info.ok() ? *info : v1::RoundInfo();
  }
  bool AtRest(const std::string& id) { return !Get(id).round().stroke_in_play(); }

  // Plays the round to its end (or `commands` commands) by the bot, the same commands applied
  // to an offline referee, the two compared after every command. Returns the offline state.
  golf::RoundState PlayOn(const v1::CreateRoundResponse& made, const golf::Course& c,
                          const golf::RoundSettings& s, golf::RoundState st, int commands) {
    for (int n = 0; n < commands && !st.over; ++n) {
      EXPECT_TRUE(WaitFor([&] { return AtRest(made.round_id()); }));
      const v1::RoundInfo info = Get(made.round_id());
      std::string diff;
      MessageDifferencer md;
      md.ReportDifferencesToString(&diff);
      EXPECT_TRUE(md.Compare(Offline(c, s, st), info.round())) << "command " << n << ": " << diff;
      if (st.decision) {
        const int seat = st.decision->seat;
        const std::vector<std::string>& choices = st.decision->choices;
        const std::string choice = choices.size() > 1 ? choices[1] : choices[0];
        v1::DecideRoundRequest q;
        q.set_round_id(made.round_id());
        q.set_token(made.seats(seat).token());
        q.set_choice(choice);
        absl::StatusOr<v1::DecideRoundResponse> r = reg_->Decide(q);
        EXPECT_TRUE(r.ok()) << r.status();
        absl::StatusOr<golf::RoundStep> off = golf::Decide(c, s, st, seat, {choice, std::nullopt});
        EXPECT_TRUE(off.ok()) << off.status();
        st = off->state;
        continue;
      }
      const int seat = golf::ToPlay(c, s, st);
      v1::PlayStrokeRequest q = Bot(c, s, st, seat);
      absl::StatusOr<golf::RoundStroke> k = RoundStrokeFromProto(q);
      EXPECT_TRUE(k.ok());
      q.set_round_id(made.round_id());
      q.set_token(made.seats(seat).token());
      absl::StatusOr<v1::PlayStrokeResponse> r = reg_->Stroke(q);
      EXPECT_TRUE(r.ok()) << r.status();
      if (!r.ok()) break;
      absl::StatusOr<golf::RoundStep> off = golf::PlayStroke(c, s, st, seat, *k);
      EXPECT_TRUE(off.ok()) << off.status();
      st = off->state;
    }
    EXPECT_TRUE(WaitFor([&] { return AtRest(made.round_id()); }));
    return st;
  }

  v1::RoundState WholeRound(const v1::CreateRoundRequest& create);

  std::unique_ptr<RoundRegistry> reg_;
};

TEST_F(RoundsTest, CreationIsCheckedAndReturnsTheTokens) {
  absl::StatusOr<v1::CreateRoundResponse> made = reg_->Create(TwoPlayers());
  ASSERT_TRUE(made.ok()) << made.status();
  EXPECT_THAT(made->round_id(), ::testing::StartsWith("r-"));
  ASSERT_EQ(made->seats_size(), 2);
  EXPECT_EQ(made->seats(1).name(), "Bob");
  EXPECT_FALSE(made->seats(0).token().empty());
  EXPECT_FALSE(made->admin_token().empty());
  EXPECT_EQ(made->round().hole(), 1u);
  EXPECT_EQ(made->round().to_play(), 0);
  EXPECT_EQ(made->round().players(1).tee(), "red");
  auto refused = [&](std::function<void(v1::CreateRoundRequest&)> change, std::string field) {
    v1::CreateRoundRequest r = TwoPlayers();
    change(r);
    absl::StatusOr<v1::CreateRoundResponse> bad = reg_->Create(r);
    EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_THAT(bad.status().message(), HasSubstr(field));
  };
  refused([](auto& r) { r.clear_players(); }, "players");
  refused([](auto& r) { r.set_last_hole(9); }, "holes");
  refused([](auto& r) { (*r.mutable_rules())["order"] = "random"; }, "order");
  refused([](auto& r) { r.set_noise(-1); }, "noise");
  refused([](auto& r) { r.set_tick_hz(1000); }, "tick_hz");
  refused([](auto& r) { r.mutable_players(0)->set_tee("gold"); }, "players[0].tee");
  refused([](auto& r) { r.set_play("skins"); }, "play");
  refused([](auto& r) { r.mutable_players(1)->set_handicap_index(99); }, "players[1].handicap_index");
  refused([](auto& r) { r.set_play("match"); r.add_players()->set_name("Cat"); }, "two players");
  refused([](auto& r) { (*r.mutable_rules())["max_score"] = "par+0"; }, "max_score");
  v1::CreateRoundRequest unknown = TwoPlayers();
  unknown.set_course("augusta");
  EXPECT_THAT(reg_->Create(unknown).status().message(), HasSubstr("course"));
  v1::ListRoundsRequest list;
  absl::StatusOr<v1::ListRoundsResponse> listed = reg_->List(list);
  ASSERT_TRUE(listed.ok());
  EXPECT_EQ(listed->total(), 1u);
  EXPECT_EQ(listed->rounds(0).players_size(), 2);
}

// A whole two-player, three-hole round by scripted players, every state equal to the offline
// referee's; its record replayed offline gives the same round. Returns the round at its end.
v1::RoundState RoundsTest::WholeRound(const v1::CreateRoundRequest& create) {
  absl::StatusOr<v1::CreateRoundResponse> made = reg_->Create(create);
  EXPECT_TRUE(made.ok()) << made.status();
  if (!made.ok()) return {};
  const golf::Course& c = **golf::BuiltinCourse("sportsim_links");
  const golf::RoundSettings s = *RoundSettingsFromProto(create, c);
  golf::RoundState st = PlayOn(*made, c, s, *golf::StartRound(c, s), 200);
  EXPECT_TRUE(st.over) << "the round did not finish in 200 commands";
  const v1::RoundInfo info = Get(made->round_id());
  EXPECT_TRUE(MessageDifferencer::Equals(Offline(c, s, st), info.round()));
  // The record: the creation and every command, replayed through the referee.
  v1::GetRoundRecordRequest rr;
  rr.set_round_id(made->round_id());
  absl::StatusOr<v1::RoundRecord> record = reg_->Record(rr);
  EXPECT_TRUE(record.ok()) << record.status();
  if (!record.ok()) return {};
  EXPECT_GE(record->commands_size(), 8) << "two players, two holes, two strokes at least each";
  golf::RoundState replay = *golf::StartRound(c, *RoundSettingsFromProto(record->setup(), c));
  for (const v1::RoundCommand& cmd : record->commands()) {
    absl::StatusOr<golf::RoundStep> step =
        cmd.has_stroke()   ? golf::PlayStroke(c, s, replay, cmd.seat(), *RoundStrokeFromProto(cmd.stroke()))
        : cmd.has_decide() ? golf::Decide(c, s, replay, cmd.seat(), {cmd.decide().choice(), std::nullopt})
                           : golf::ShotClockExpired(c, s, replay);
    EXPECT_TRUE(step.ok()) << step.status();
    if (!step.ok()) return {};
    replay = step->state;
  }
  EXPECT_TRUE(MessageDifferencer::Equals(Offline(c, s, replay), record->round()));
  EXPECT_TRUE(MessageDifferencer::Equals(record->round(), info.round()));
  // Over: no more strokes.
  v1::PlayStrokeRequest more;
  more.set_round_id(made->round_id());
  more.set_token(made->seats(0).token());
  more.set_putt_speed_mps(1);
  EXPECT_EQ(reg_->Stroke(more).status().code(), absl::StatusCode::kFailedPrecondition);
  return info.round();
}

TEST_F(RoundsTest, AWholeRoundMatchesTheOfflineRefereeAndItsRecordReplays) {
  const v1::RoundState round = WholeRound(TwoPlayers());
  EXPECT_EQ(round.play(), "stroke");
  EXPECT_EQ(round.result(), "finished");
  for (const v1::RoundPlayerState& p : round.players()) {
    ASSERT_EQ(p.scores_size(), 3);
    EXPECT_EQ(p.total(), p.scores(0) + p.scores(1) + p.scores(2));
    for (uint32_t score : p.scores()) EXPECT_GE(score, 1u);
  }
}

// Match play with handicaps, whole, over the registry: each hole to the fewer net strokes, the
// result the holes' tally ("N and M" when it ended early, "N up", or halved).
TEST_F(RoundsTest, AWholeMatchWithHandicapsIsWonByTheRules) {
  v1::CreateRoundRequest create = TwoPlayers();
  create.set_play("match");
  create.mutable_players(0)->set_handicap_index(4.0);
  create.mutable_players(1)->set_handicap_index(28.0);
  const v1::RoundState round = WholeRound(create);
  EXPECT_EQ(round.play(), "match");
  EXPECT_TRUE(round.handicaps());
  EXPECT_EQ(round.players(0).playing_handicap(), 0);
  EXPECT_GT(round.players(1).playing_handicap(), 0);
  int won[2] = {0, 0}, left = 0;
  for (int h = 0; h < round.hole_winners_size(); ++h) {
    const int w = round.hole_winners(h);
    if (w == -2) {
      ++left;
      continue;
    }
    auto net = [&](int seat) {
      const v1::RoundPlayerState& p = round.players(seat);
      return p.no_score(h) ? 1000 : static_cast<int>(p.scores(h)) - p.received(h);
    };
    EXPECT_EQ(w, net(0) < net(1) ? 0 : (net(1) < net(0) ? 1 : -1)) << "hole " << h + 1;
    if (w >= 0) ++won[w];
  }
  const int up = std::abs(won[0] - won[1]);
  if (up == 0) {
    EXPECT_EQ(round.result(), "halved");
  } else {
    EXPECT_EQ(round.winner(), won[0] > won[1] ? 0 : 1);
    EXPECT_EQ(round.result(), left == 0 ? absl::StrCat(up, " up") : absl::StrCat(up, " and ", left));
  }
  EXPECT_THAT(round.match_status(), HasSubstr(up == 0 ? "halved" : "won"));
}

// Stableford with handicaps, whole: the points are Rule 21.1b's from the net scores, the
// winner has the most.
TEST_F(RoundsTest, AWholeStablefordRoundIsWonOnPoints) {
  v1::CreateRoundRequest create = TwoPlayers();
  create.set_play("stableford");
  create.mutable_players(1)->set_handicap_index(20.0);
  const v1::RoundState round = WholeRound(create);
  EXPECT_EQ(round.result(), "finished");
  const golf::Course& c = **golf::BuiltinCourse("sportsim_links");
  uint32_t best = 0;
  for (const v1::RoundPlayerState& p : round.players()) {
    uint32_t sum = 0;
    for (int h = 0; h < 3; ++h) {
      const int par = c.Hole(h + 1)->par;
      const uint32_t expected =
          p.no_score(h) ? 0 : static_cast<uint32_t>(golf::StablefordPoints(p.scores(h), par, p.received(h)));
      EXPECT_EQ(p.points(h), expected) << p.name() << " hole " << h + 1;
      sum += p.points(h);
    }
    EXPECT_EQ(p.points_total(), sum);
    best = std::max(best, sum);
  }
  for (uint32_t w : round.winners()) EXPECT_EQ(round.players(w).points_total(), best);
}

// Match play's concessions over the registry: the seat not to play concedes the next stroke;
// a stroke cannot be conceded while a ball moves; only a seat of the round concedes; the
// concession is in the record.
TEST_F(RoundsTest, APuttIsConcededInMatchPlay) {
  v1::CreateRoundRequest create = TwoPlayers(2, 3);
  create.set_play("match");
  absl::StatusOr<v1::CreateRoundResponse> made = reg_->Create(create);
  ASSERT_TRUE(made.ok()) << made.status();
  const golf::Course& c = **golf::BuiltinCourse("sportsim_links");
  const golf::RoundSettings s = *RoundSettingsFromProto(create, c);
  golf::RoundState st = *golf::StartRound(c, s);
  // Play until the one to play is on the green and the other's ball is not holed.
  for (int n = 0; n < 30; ++n) {
    const int next = golf::ToPlay(c, s, st);
    if (st.hole == 2 && !st.decision && st.players[next].ball.lie == golf::Terrain::kGreen &&
        st.players[next].strokes > 0 && !st.players[1 - next].ball.holed) {
      break;
    }
    st = PlayOn(*made, c, s, st, 1);
  }
  ASSERT_EQ(st.hole, 2);
  const int next = golf::ToPlay(c, s, st);
  v1::DecideRoundRequest q;
  q.set_round_id(made->round_id());
  q.set_choice("concede_stroke");
  q.set_token(made->admin_token());
  EXPECT_FALSE(reg_->Decide(q).ok()) << "the admin is not a player";
  q.set_token(made->seats(1 - next).token());
  absl::StatusOr<v1::DecideRoundResponse> r = reg_->Decide(q);
  ASSERT_TRUE(r.ok()) << r.status();
  absl::StatusOr<golf::RoundStep> off = golf::Decide(c, s, st, 1 - next, {"concede_stroke", std::nullopt});
  ASSERT_TRUE(off.ok()) << off.status();
  EXPECT_TRUE(MessageDifferencer::Equals(Offline(c, s, off->state), r->round()));
  EXPECT_TRUE(r->round().hole() == 3 || r->round().players(next).ball().holed());
  // In stroke play the same choice is refused naming the Rule.
  absl::StatusOr<v1::CreateRoundResponse> stroke = reg_->Create(TwoPlayers(2, 3));
  ASSERT_TRUE(stroke.ok());
  q.set_round_id(stroke->round_id());
  q.set_token(stroke->seats(1).token());
  absl::StatusOr<v1::DecideRoundResponse> refused = reg_->Decide(q);
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(refused.status().message(), HasSubstr("3.2b"));
  v1::GetRoundRecordRequest rr;
  rr.set_round_id(made->round_id());
  absl::StatusOr<v1::RoundRecord> record = reg_->Record(rr);
  ASSERT_TRUE(record.ok());
  EXPECT_EQ(record->commands(record->commands_size() - 1).decide().choice(), "concede_stroke");
}

// A swing stroke (the chapter's golfer with a 7-iron) is played as the offline referee plays it;
// an unknown club and a swing that never reaches the ball are refused naming the field.
TEST_F(RoundsTest, ASwingStrokeIsPlayedAsOffline) {
  const v1::CreateRoundRequest create = TwoPlayers(2, 2);
  absl::StatusOr<v1::CreateRoundResponse> made = reg_->Create(create);
  ASSERT_TRUE(made.ok()) << made.status();
  const golf::Course& c = **golf::BuiltinCourse("sportsim_links");
  const golf::RoundSettings s = *RoundSettingsFromProto(create, c);
  golf::RoundState st = *golf::StartRound(c, s);
  v1::PlayStrokeRequest q;
  q.set_round_id(made->round_id());
  q.set_token(made->seats(0).token());
  q.mutable_swing()->set_club("7-iron");
  absl::StatusOr<v1::PlayStrokeResponse> r = reg_->Stroke(q);
  ASSERT_TRUE(r.ok()) << r.status();
  absl::StatusOr<golf::RoundStep> off = golf::PlayStroke(c, s, st, 0, *RoundStrokeFromProto(q));
  ASSERT_TRUE(off.ok()) << off.status();
  ASSERT_TRUE(WaitFor([&] { return AtRest(made->round_id()); }));
  EXPECT_TRUE(MessageDifferencer::Equals(Offline(c, s, off->state), Get(made->round_id()).round()));
  EXPECT_GT(off->state.players[0].ball.position_m.y() - st.players[0].ball.position_m.y(), 50.0)
      << "a 7-iron flies north toward the pin";
  v1::PlayStrokeRequest bad = q;
  bad.set_token(made->seats(1).token());
  bad.mutable_swing()->set_club("putter9");
  EXPECT_THAT(reg_->Stroke(bad).status().message(), HasSubstr("swing.club"));
  bad.mutable_swing()->set_club("driver");
  bad.mutable_swing()->set_face_angle_deg(60);
  absl::StatusOr<v1::PlayStrokeResponse> open = reg_->Stroke(bad);
  EXPECT_EQ(open.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(open.status().message(), HasSubstr("face_angle_deg"));
  // A shoulder torque past a human's (the realistic profile).
  bad.mutable_swing()->set_face_angle_deg(0);
  v1::TorqueKnot* knot = bad.mutable_swing()->mutable_torques()->mutable_qalpha()->add_knots();
  knot->set_t_s(0);
  knot->set_torque_nm(500);
  absl::StatusOr<v1::PlayStrokeResponse> strong = reg_->Stroke(bad);
  EXPECT_EQ(strong.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(strong.status().message(), HasSubstr("qalpha"));
}

// The shot clock: the seat to play takes a penalty stroke when it runs out, the record says so,
// and a restore at that tick replays it.
TEST_F(RoundsTest, TheShotClockPenalizesTheSeatToPlayAndReplays) {
  MemoryJournal journal;
  reg_->SetJournal(&journal);
  v1::CreateRoundRequest create = TwoPlayers(1, 1);
  create.set_shot_clock_s(5);
  absl::StatusOr<v1::CreateRoundResponse> made = reg_->Create(create);
  ASSERT_TRUE(made.ok()) << made.status();
  const std::string id = made->round_id();
  EXPECT_EQ(Get(id).clock_deadline_tick(), 150) << "5 s at 30 Hz";
  ASSERT_TRUE(WaitFor([&] { return Get(id).round().players(0).penalties() >= 1; }));
  v1::GetRoundRecordRequest rr;
  rr.set_round_id(id);
  const v1::RoundRecord record = *reg_->Record(rr);
  ASSERT_GE(record.commands_size(), 1);
  const v1::RoundCommand& first = record.commands(0);
  EXPECT_TRUE(first.shot_clock());
  EXPECT_EQ(first.seat(), 0);
  EXPECT_EQ(first.tick(), 150);
  EXPECT_EQ(Get(id).round().players(1).penalties(), 0u) << "only the seat to play";
  // Restored at that tick: the same penalty, from the creation alone.
  reg_ = std::make_unique<RoundRegistry>(Limits(), nullptr, 2);
  ASSERT_TRUE(reg_->Restore(journal.Stored(id, first.tick())).ok());
  const golf::Course& c = **golf::BuiltinCourse("sportsim_links");
  const golf::RoundSettings s = *RoundSettingsFromProto(create, c);
  const golf::RoundState once = golf::ShotClockExpired(c, s, *golf::StartRound(c, s))->state;
  EXPECT_TRUE(MessageDifferencer::Equals(Offline(c, s, once), Get(id).round()));
  EXPECT_EQ(Get(id).clock_deadline_tick(), 300) << "the clock restarted";
  v1::CreateRoundRequest bad = TwoPlayers();
  bad.set_shot_clock_s(-1);
  EXPECT_THAT(reg_->Create(bad).status().message(), HasSubstr("shot_clock_s"));
}

// The journal: a round restored halfway from its commands is the round it was, and plays on
// to the same end.
TEST_F(RoundsTest, ARoundRestoredFromItsJournalGoesOnAsIfUninterrupted) {
  MemoryJournal journal;
  reg_->SetJournal(&journal);
  const v1::CreateRoundRequest create = TwoPlayers(2, 3);
  absl::StatusOr<v1::CreateRoundResponse> made = reg_->Create(create);
  ASSERT_TRUE(made.ok()) << made.status();
  const golf::Course& c = **golf::BuiltinCourse("sportsim_links");
  const golf::RoundSettings s = *RoundSettingsFromProto(create, c);
  golf::RoundState st = PlayOn(*made, c, s, *golf::StartRound(c, s), 7);
  const v1::RoundInfo before = Get(made->round_id());
  // The first server goes; another restores the round from the journal.
  reg_ = std::make_unique<RoundRegistry>(Limits(), nullptr, 2);
  ASSERT_TRUE(reg_->Restore(journal.Stored(made->round_id(), before.tick())).ok());
  const v1::RoundInfo after = Get(made->round_id());
  EXPECT_TRUE(MessageDifferencer::Equals(before.round(), after.round()));
  EXPECT_EQ(after.sequence(), before.sequence());
  // The same tokens play on.
  st = PlayOn(*made, c, s, st, 200);
  EXPECT_TRUE(st.over);
  EXPECT_EQ(Get(made->round_id()).round().result(), "finished");
}

// The cheating list: each refused, naming why, and the round unchanged.
TEST_F(RoundsTest, CheatsAreRefusedAndChangeNothing) {
  v1::CreateRoundRequest create = TwoPlayers(3, 3);
  create.set_fast_forward(false);
  absl::StatusOr<v1::CreateRoundResponse> made = reg_->Create(create);
  ASSERT_TRUE(made.ok()) << made.status();
  const std::string id = made->round_id();
  auto stroke = [&](int seat_token, double speed, double aim) {
    v1::PlayStrokeRequest q;
    q.set_round_id(id);
    q.set_token(seat_token < 0 ? made->admin_token() : made->seats(seat_token).token());
    q.mutable_launch()->set_ball_speed_mps(speed);
    q.mutable_launch()->set_launch_angle_deg(12);
    q.mutable_launch()->set_spin_rpm(3000);
    q.set_aim_deg(aim);
    return reg_->Stroke(q);
  };
  const v1::RoundInfo start = Get(id);
  auto unchanged = [&](const char* what) {
    const v1::RoundInfo now = Get(id);
    EXPECT_TRUE(MessageDifferencer::Equals(start.round(), now.round())) << what;
    EXPECT_EQ(now.sequence(), start.sequence()) << what;
  };
  // Out of turn: Bob before Ann has teed off.
  absl::StatusOr<v1::PlayStrokeResponse> r = stroke(1, 60, 180);
  EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(r.status().message(), HasSubstr("not your turn"));
  unchanged("out of turn");
  // The admin plays no ball; a made-up token is no seat.
  EXPECT_EQ(stroke(-1, 60, 180).status().code(), absl::StatusCode::kPermissionDenied);
  v1::PlayStrokeRequest forged;
  forged.set_round_id(id);
  forged.set_token("0123456789abcdef0123456789abcdef");
  forged.set_putt_speed_mps(1);
  EXPECT_EQ(reg_->Stroke(forged).status().code(), absl::StatusCode::kPermissionDenied);
  // Beyond a human under the realistic profile.
  r = stroke(0, 110, 180);
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(r.status().message(), HasSubstr("launch.ball_speed_mps"));
  // No stroke named at all; a putt with an aim too.
  v1::PlayStrokeRequest empty;
  empty.set_round_id(id);
  empty.set_token(made->seats(0).token());
  EXPECT_EQ(reg_->Stroke(empty).status().code(), absl::StatusCode::kInvalidArgument);
  unchanged("refused strokes");
  // A seat does not delete the round; only the admin does.
  v1::DeleteRoundRequest del;
  del.set_round_id(id);
  del.set_token(made->seats(0).token());
  EXPECT_EQ(reg_->Delete(del).code(), absl::StatusCode::kPermissionDenied);
  unchanged("delete by a seat");

  // Ann drives into the red creek (the referee's own scenario): while the ball is in play,
  // nothing else; then a decision is pending and only Ann's choice moves the round.
  ASSERT_TRUE(stroke(0, 60, 194).ok());
  r = stroke(1, 60, 180);
  EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
  ASSERT_TRUE(WaitFor([&] { return AtRest(id); }));
  const v1::RoundInfo pending = Get(id);
  ASSERT_TRUE(pending.round().has_decision());
  EXPECT_EQ(pending.round().decision().reason(), "penalty_area");
  for (int seat : {0, 1}) {
    r = stroke(seat, 50, 180);
    EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_THAT(r.status().message(), HasSubstr("decision is pending"));
  }
  v1::DecideRoundRequest decide;
  decide.set_round_id(id);
  decide.set_token(made->seats(1).token());
  decide.set_choice("lateral");
  EXPECT_EQ(reg_->Decide(decide).status().code(), absl::StatusCode::kFailedPrecondition);
  decide.set_token(made->seats(0).token());
  decide.set_choice("teleport\x01");
  absl::StatusOr<v1::DecideRoundResponse> d = reg_->Decide(decide);
  EXPECT_EQ(d.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(d.status().message(), HasSubstr("choice"));
  EXPECT_THAT(d.status().message(), ::testing::Not(HasSubstr("\x01")));
  const v1::RoundInfo still = Get(id);
  EXPECT_TRUE(MessageDifferencer::Equals(pending.round(), still.round()));
  decide.set_choice("lateral");
  d = reg_->Decide(decide);
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_FALSE(d->round().has_decision());
  EXPECT_EQ(d->round().players(0).strokes(), 2u);
  EXPECT_NE(d->round().players(0).ball().lie(), "lateral_water_hazard");
  // The admin deletes.
  del.set_token(made->admin_token());
  EXPECT_TRUE(reg_->Delete(del).ok());
  v1::GetRoundRequest gone;
  gone.set_round_id(id);
  EXPECT_EQ(reg_->Get(gone).status().code(), absl::StatusCode::kNotFound);
}

// A watcher sees the stroke, the ball on its way (frames with the moving ball) and the ruling.
TEST_F(RoundsTest, AWatcherSeesTheBallAndTheRuling) {
  v1::CreateRoundRequest create = TwoPlayers(2, 2);
  create.set_fast_forward(false);
  create.set_tick_hz(60);
  absl::StatusOr<v1::CreateRoundResponse> made = reg_->Create(create);
  ASSERT_TRUE(made.ok()) << made.status();
  FakeSink sink;
  v1::WatchRoundRequest w;
  w.set_round_id(made->round_id());
  absl::StatusOr<std::shared_ptr<RoundWatcher>> watcher = reg_->Watch(w, &sink);
  ASSERT_TRUE(watcher.ok()) << watcher.status();
  sink.StartReading(*watcher, std::chrono::microseconds(100));
  (*watcher)->Pump();
  v1::PlayStrokeRequest q;
  q.set_round_id(made->round_id());
  q.set_token(made->seats(0).token());
  q.mutable_launch()->set_ball_speed_mps(30);  // into the pond
  q.mutable_launch()->set_launch_angle_deg(20);
  q.mutable_launch()->set_spin_rpm(5000);
  q.set_aim_deg(88);
  absl::StatusOr<v1::PlayStrokeResponse> r = reg_->Stroke(q);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_GT(r->rest_tick(), r->start_tick() + 60) << "a few seconds in the air";
  ASSERT_TRUE(WaitFor([&] {
    for (const v1::RoundSnapshot& snap : sink.got()) {
      for (const v1::RoundEvent& e : snap.events()) {
        if (e.kind() == "decision") return true;
      }
    }
    return false;
  }));
  std::vector<std::string> kinds;
  int moving = 0;
  for (const v1::RoundSnapshot& snap : sink.got()) {
    moving += snap.has_ball() ? 1 : 0;
    for (const v1::RoundEvent& e : snap.events()) kinds.push_back(e.kind());
  }
  EXPECT_GT(moving, 3) << "frames with the ball on its way";
  EXPECT_THAT(kinds, ::testing::IsSupersetOf({"stroke", "landing", "penalty_area", "rest", "decision"}));
  EXPECT_LT(std::find(kinds.begin(), kinds.end(), "stroke") - kinds.begin(),
            std::find(kinds.begin(), kinds.end(), "landing") - kinds.begin());
  sink.StopReading();
}

}  // namespace
}  // namespace sportsim::server
