// Edge cases hard to build with a cue, judged from event lists written by hand: split hits,
// the 8 with the last group ball, the 8 on the break, three fouls with and without the
// warning, the 10 on the break and early, balls off the table, the kitchen, concessions and
// the shot clock.
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/sim/games/pool_test_util.h"

namespace sportsim::games::testing {
namespace {

using billiards::Event;
using billiards::EventKind;
using billiards::MotionState;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr double kSpotTolM = 1e-9;  // (m)

Event Hit(double t, int a, int b) { return {.t_s = t, .kind = EventKind::kBallBall, .a = a, .b = b}; }
// A cushion hit of ball a on segment seg, the ball's centre then at `at`.
Event Rail(double t, int a, int seg = 0, Eigen::Vector2d at = Eigen::Vector2d::Zero()) {
  return {.t_s = t, .kind = EventKind::kBallCushion, .a = a, .other = seg, .ra = at};
}
Event Drop(double t, int a, int pocket) {
  return {.t_s = t, .kind = EventKind::kBallPocket, .a = a, .other = pocket};
}

// Judges a synthetic shot on table t: `after` is `before` with the pocketed balls down.
Judgement JudgeEvents(Table& t, const ShotCall& call, std::vector<Event> events) {
  ShotRecord rec;
  rec.struck = t.balls.Find("cue");
  rec.before = t.balls;
  rec.events = std::move(events);
  rec.after = t.balls;
  for (const Event& e : rec.events) {
    if (e.kind == EventKind::kBallPocket) {
      rec.after.balls[e.a].state = MotionState::kPocketed;
      rec.after.balls[e.a].pocket = e.other;
    }
  }
  EXPECT_TRUE(t.referee->CheckShot(t.rules, t.model, t.state, t.state.to_play, call, t.balls).ok());
  TableState after = rec.after;
  Judgement j = t.referee->Judge(t.rules, t.model, t.state, call, rec, &after);
  t.state = j.state;
  t.balls = after;
  return j;
}

int Idx(const Table& t, std::string_view id) { return t.balls.Find(id); }

TEST(SplitHit, FavoursTheShooter) {
  Table t = MakeTable(GameKind::kNineBall,
                      {{"cue", -0.5, 0}, {"1", 0.3, 0.03}, {"2", 0.3, -0.03}, {"3", 0.5, 0.3}, {"9", 0.8, -0.3}});
  const Judgement legal =
      JudgeEvents(t, {}, {Hit(0.4, 0, Idx(t, "2")), Hit(0.4, Idx(t, "1"), 0), Rail(0.9, Idx(t, "1"))});
  EXPECT_FALSE(legal.verdict.foul) << legal.verdict.reason;

  Table u = MakeTable(GameKind::kNineBall,
                      {{"cue", -0.5, 0}, {"1", 0.3, 0.3}, {"2", 0.3, 0.03}, {"3", 0.3, -0.03}, {"9", 0.8, -0.3}});
  const Judgement foul =
      JudgeEvents(u, {}, {Hit(0.4, 0, Idx(u, "2")), Hit(0.4, 0, Idx(u, "3")), Rail(0.9, Idx(u, "2"))});
  EXPECT_TRUE(foul.verdict.foul);
  EXPECT_EQ(foul.verdict.reason, "wrong_ball_first");
}

// The 8 down on the stroke that pockets the last solid: lost (WPA 3.?), though the call was
// made and the first contact legal.
TEST(EightBall, EightWithTheLastGroupBallLoses) {
  Table t = MakeTable(GameKind::kEightBall, {{"cue", -0.5, 0}, {"7", 0.3, 0.2}, {"8", 0.6, -0.2}, {"12", 0.0, 0.4}});
  t.state.groups = {Group::kSolids, Group::kStripes};
  const int tr = PocketIdx(t.model, "top_right"), br = PocketIdx(t.model, "bottom_right");
  const Judgement j = JudgeEvents(t, {.ball = "7", .pocket = "top_right"},
                                  {Hit(0.4, 0, Idx(t, "7")), Hit(0.6, Idx(t, "7"), Idx(t, "8")),
                                   Drop(1.0, Idx(t, "7"), tr), Drop(1.2, Idx(t, "8"), br)});
  EXPECT_FALSE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "eight_early");
  EXPECT_EQ(t.state.winner, 1);
}

// A foul on the stroke that pockets the 8 loses, even as the shooter's legal ball.
TEST(EightBall, EightWithAScratchLoses) {
  Table t = MakeTable(GameKind::kEightBall, {{"cue", -0.5, 0}, {"8", 0.6, -0.2}, {"12", 0.0, 0.4}});
  t.state.groups = {Group::kSolids, Group::kStripes};
  const int tr = PocketIdx(t.model, "top_right");
  const Judgement j = JudgeEvents(t, {.ball = "8", .pocket = "top_right"},
                                  {Hit(0.4, 0, Idx(t, "8")), Drop(1.0, Idx(t, "8"), tr), Drop(1.3, 0, 2)});
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "scratch");
  EXPECT_EQ(t.state.winner, 1);
}

TEST(EightBall, EightOnTheBreakIsSpottedOrRebroken) {
  // Clean break with the 8 down: the breaker chooses.
  for (const char* choice : {"spot_eight", "rebreak"}) {
    Table t = MakeTable(GameKind::kEightBall, {});
    const int eight = Idx(t, "8");
    const Judgement j = JudgeEvents(t, {}, {Hit(0.2, 0, Idx(t, "1")), Drop(0.8, eight, 0)});
    EXPECT_FALSE(j.verdict.foul);
    EXPECT_FALSE(t.state.match_over());
    EXPECT_EQ(t.state.decision.seat, 0);
    EXPECT_THAT(t.state.decision.choices, ElementsAre("spot_eight", "rebreak"));
    absl::StatusOr<Judgement> d = t.Decide(0, choice);
    ASSERT_TRUE(d.ok()) << d.status();
    EXPECT_EQ(t.state.to_play, 0);
    if (std::string(choice) == "spot_eight") {
      EXPECT_THAT(d->verdict.respotted, ElementsAre("8"));
      EXPECT_EQ(t.balls.balls[eight].state, MotionState::kStationary);
      EXPECT_FALSE(t.state.is_break);
      EXPECT_EQ(t.state.ball_in_hand, BallInHand::kNone);
      EXPECT_TRUE(IsFreeSpot(t.model, t.balls, eight, Pos(t.balls, "8")));
    } else {
      EXPECT_TRUE(t.state.is_break);
      EXPECT_EQ(t.state.breaker, 0);
    }
  }
  // With a scratch: the opponent chooses; spotting gives ball in hand in the kitchen.
  Table t = MakeTable(GameKind::kEightBall, {});
  const Judgement j = JudgeEvents(t, {}, {Hit(0.2, 0, Idx(t, "1")), Drop(0.8, Idx(t, "8"), 0), Drop(1.0, 0, 3)});
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(t.state.decision.seat, 1);
  ASSERT_TRUE(t.Decide(1, "spot_eight").ok());
  EXPECT_EQ(t.state.to_play, 1);
  EXPECT_EQ(t.state.ball_in_hand, BallInHand::kKitchen);
}

// The 8 driven off the table on a clean break is the 8 down (spotted or re-broken, the
// breaker's choice), not a ball-off-table foul; another object ball off the table with the 8
// down is a foul: the opponent chooses, and spotting gives ball in hand anywhere (no scratch).
TEST(EightBall, EightOffTheTableOnTheBreak) {
  Table t = MakeTable(GameKind::kEightBall, {});
  std::vector<Event> ev = {Hit(0.2, 0, Idx(t, "1"))};
  for (const char* id : {"2", "3", "4", "5"}) ev.push_back(Rail(0.5, Idx(t, id)));  // legal
  ev.push_back(Drop(0.8, Idx(t, "8"), -1));
  const Judgement j = JudgeEvents(t, {}, ev);
  EXPECT_FALSE(j.verdict.foul) << j.verdict.reason;
  EXPECT_EQ(t.state.decision.seat, 0);
  EXPECT_THAT(t.state.decision.choices, ElementsAre("spot_eight", "rebreak"));
  Table u = MakeTable(GameKind::kEightBall, {});
  const Judgement k = JudgeEvents(u, {}, {Hit(0.2, 0, Idx(u, "1")), Drop(0.8, Idx(u, "8"), 0),
                                          Drop(0.9, Idx(u, "5"), -1)});
  EXPECT_TRUE(k.verdict.foul);
  EXPECT_EQ(k.verdict.reason, "ball_off_table");
  EXPECT_EQ(u.state.decision.seat, 1);
  ASSERT_TRUE(u.Decide(1, "spot_eight").ok());
  EXPECT_EQ(u.state.to_play, 1);
  EXPECT_EQ(u.state.ball_in_hand, BallInHand::kAnywhere);
}

// The break-scratch setting is about scratches: an object ball off the table on a legal break
// (no scratch) gives ball in hand anywhere, whatever the setting.
TEST(EightBall, ObjectBallOffTheTableOnTheBreakIsInHandAnywhere) {
  for (const char* zone : {"anywhere", "kitchen"}) {
    Table t = MakeTable(GameKind::kEightBall, {}, 1, {{"break_scratch_in_hand", zone}});
    std::vector<Event> ev = {Hit(0.2, 0, Idx(t, "1"))};
    for (const char* id : {"2", "3", "4", "5"}) ev.push_back(Rail(0.5, Idx(t, id)));
    ev.push_back(Drop(1.0, Idx(t, "6"), -1));
    const Judgement j = JudgeEvents(t, {}, ev);
    EXPECT_EQ(j.verdict.reason, "ball_off_table");
    EXPECT_EQ(t.state.to_play, 1);
    EXPECT_EQ(t.state.ball_in_hand, BallInHand::kAnywhere) << zone;
  }
}

TEST(EightBall, BreakScratchVariant) {
  for (const char* zone : {"anywhere", "kitchen"}) {
    Table t = MakeTable(GameKind::kEightBall, {}, 1, {{"break_scratch_in_hand", zone}});
    std::vector<Event> ev = {Hit(0.2, 0, Idx(t, "1"))};
    for (const char* id : {"2", "3", "4", "5"}) ev.push_back(Rail(0.5, Idx(t, id)));
    ev.push_back(Drop(1.0, 0, 1));
    const Judgement j = JudgeEvents(t, {}, ev);
    EXPECT_EQ(j.verdict.reason, "scratch");
    EXPECT_EQ(t.state.to_play, 1);
    EXPECT_EQ(BallInHandName(t.state.ball_in_hand), zone);
    EXPECT_FALSE(t.state.decision.pending());
  }
}

// From the kitchen, an object ball behind the head string needs the cue ball to cross first.
TEST(EightBall, KitchenCueBallMustCrossTheString) {
  Table t = MakeTable(GameKind::kEightBall, {{"cue", -1.0, 0}, {"3", -0.8, 0.2}, {"8", 0.6, -0.2}, {"12", 0.3, 0.4}});
  t.state.ball_in_hand = BallInHand::kKitchen;
  const Judgement j = JudgeEvents(t, {.safety = true}, {Hit(0.4, 0, Idx(t, "3")), Rail(0.8, Idx(t, "3"))});
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "behind_head_string");
  // The foot rail (segment "rail_right", wholly beyond the string) first: legal.
  int foot = -1;
  for (size_t i = 0; i < t.model.spec().cushions.size(); ++i) {
    if (t.model.spec().cushions[i].name == "rail_right") foot = static_cast<int>(i);
  }
  Table u = MakeTable(GameKind::kEightBall, {{"cue", -1.0, 0}, {"3", -0.8, 0.2}, {"8", 0.6, -0.2}, {"12", 0.3, 0.4}});
  u.state.ball_in_hand = BallInHand::kKitchen;
  const double foot_x = 0.5 * u.model.spec().length_m - u.model.radius();
  const Judgement ok = JudgeEvents(u, {.safety = true}, {Rail(0.3, 0, foot, {foot_x, 0.0}), Hit(1.4, 0, Idx(u, "3")), Rail(1.8, Idx(u, "3"))});
  EXPECT_FALSE(ok.verdict.foul) << ok.verdict.reason;
  // A long rail: its segment from the head corner to the side pocket spans the string, so the
  // place of the hit decides. Beyond the string: crossed, legal; behind it: a foul.
  const double string_x = PoolTableMarks(u.model).head_string_x;
  int side = -1;
  for (size_t i = 0; i < u.model.spec().cushions.size(); ++i) {
    const billiards::CushionSegment& c = u.model.spec().cushions[i];
    if (std::min(c.a.x(), c.b.x()) < string_x && std::max(c.a.x(), c.b.x()) > string_x &&
        c.a.y() == c.b.y()) {
      side = static_cast<int>(i);
    }
  }
  ASSERT_GE(side, 0);
  const double rail_y = u.model.spec().cushions[side].a.y();
  for (const double dx : {0.2, -0.2}) {
    Table w = MakeTable(GameKind::kEightBall, {{"cue", -1.0, 0}, {"3", -0.8, 0.2}, {"8", 0.6, -0.2}, {"12", 0.3, 0.4}});
    w.state.ball_in_hand = BallInHand::kKitchen;
    const Eigen::Vector2d at(string_x + dx, rail_y - std::copysign(w.model.radius(), rail_y));
    const Judgement bank = JudgeEvents(w, {.safety = true}, {Rail(0.3, 0, side, at), Hit(1.4, 0, Idx(w, "3")), Rail(1.8, Idx(w, "3"))});
    EXPECT_EQ(bank.verdict.foul, dx < 0) << dx << " " << bank.verdict.reason;
  }
}

TEST(NineBall, ThirdFoulWithoutTheWarningCountsAsTheSecond) {
  for (bool warned : {false, true}) {
    Table t = MakeTable(GameKind::kNineBall, {{"cue", -0.5, 0}, {"1", 0.3, 0.2}, {"9", 0.8, -0.3}});
    t.state.fouls_in_row = {2, 0};
    t.state.warned = {warned, false};
    const Judgement j = JudgeEvents(t, {}, {});  // no contact
    EXPECT_TRUE(j.verdict.foul);
    if (warned) {
      EXPECT_EQ(j.verdict.reason, "three_fouls");
      EXPECT_EQ(t.state.winner, 1);
      EXPECT_EQ(t.state.result, MatchResult::kThreeFouls);
    } else {
      EXPECT_EQ(j.verdict.reason, "no_contact");
      EXPECT_THAT(EventNames(j), ElementsAre("foul:no_contact", "warning:two_fouls"));
      EXPECT_EQ(t.state.fouls_in_row[0], 2);
      EXPECT_TRUE(t.state.warned[0]);
      EXPECT_FALSE(t.state.match_over());
    }
  }
}

// A warned third foul that also pockets the 9: the foul's event says three_fouls, the respot
// event stays a respot.
TEST(NineBall, ThirdFoulWithTheNineDownLabelsTheFoulEvent) {
  Table t = MakeTable(GameKind::kNineBall, {{"cue", -0.5, 0}, {"1", 0.3, 0.2}, {"9", 0.8, -0.3}});
  t.state.fouls_in_row = {2, 0};
  t.state.warned = {true, false};
  const int tr = PocketIdx(t.model, "top_right");
  const Judgement j = JudgeEvents(t, {}, {Hit(0.4, 0, Idx(t, "9")), Drop(1.0, Idx(t, "9"), tr)});
  EXPECT_EQ(j.verdict.reason, "three_fouls");
  std::vector<std::string> names = EventNames(j);
  EXPECT_NE(std::find(names.begin(), names.end(), "foul:three_fouls"), names.end())
      << ::testing::PrintToString(names);
  for (const std::string& n : names) EXPECT_NE(n.rfind("respot:three_fouls", 0), 0u) << n;
}

TEST(NineBall, BallsOffTheTable) {
  Table t = MakeTable(GameKind::kNineBall, {{"cue", -0.5, 0}, {"1", 0.3, 0.0}, {"5", 0.5, 0.3}, {"9", 0.6, -0.3}});
  const Judgement j = JudgeEvents(t, {}, {Hit(0.4, 0, Idx(t, "1")), Rail(0.7, Idx(t, "1")),
                                          Drop(1.0, Idx(t, "9"), -1), Drop(1.1, Idx(t, "5"), -1)});
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "ball_off_table");
  EXPECT_THAT(j.verdict.respotted, ElementsAre("9"));  // the 5 stays off
  EXPECT_EQ(t.balls.balls[Idx(t, "5")].state, MotionState::kPocketed);
  EXPECT_NEAR((Pos(t.balls, "9") - PoolTableMarks(t.model).foot_spot).norm(), 0.0, kSpotTolM);
}

TEST(NineBall, IllegalBreakNoPushOut) {
  Table t = MakeTable(GameKind::kNineBall, {});
  const Judgement j = JudgeEvents(t, {}, {Hit(0.2, 0, Idx(t, "2")), Drop(0.8, Idx(t, "5"), 0)});
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "illegal_break");
  EXPECT_FALSE(t.state.push_out_available);
  EXPECT_EQ(t.state.ball_in_hand, BallInHand::kAnywhere);
  // The 9 on a legal break wins.
  Table u = MakeTable(GameKind::kNineBall, {});
  const Judgement w = JudgeEvents(u, {}, {Hit(0.2, 0, Idx(u, "1")), Drop(0.8, Idx(u, "9"), 0)});
  EXPECT_EQ(w.verdict.reason, "nine_pocketed");
  EXPECT_EQ(u.state.winner, 0);
}

TEST(TenBall, TenOnTheBreakIsSpottedAndTheBreakerContinues) {
  Table t = MakeTable(GameKind::kTenBall, {});
  ASSERT_EQ(t.balls.balls.size(), 11u);
  const Judgement j = JudgeEvents(t, {}, {Hit(0.2, 0, Idx(t, "1")), Drop(0.8, Idx(t, "10"), 4)});
  EXPECT_FALSE(j.verdict.foul);
  EXPECT_THAT(j.verdict.respotted, ElementsAre("10"));
  EXPECT_EQ(t.state.to_play, 0);
  EXPECT_TRUE(t.state.push_out_available);
  EXPECT_TRUE(t.state.call_required);
}

TEST(TenBall, TenEarlyIsSpottedTenLastWins) {
  Table t = MakeTable(GameKind::kTenBall, {{"cue", -0.5, 0}, {"1", 0.3, 0.0}, {"10", 0.6, 0.1}});
  const int tr = PocketIdx(t.model, "top_right");
  const Judgement early = JudgeEvents(t, {.ball = "10", .pocket = "top_right"},
                                      {Hit(0.4, 0, Idx(t, "1")), Hit(0.6, Idx(t, "1"), Idx(t, "10")),
                                       Drop(1.0, Idx(t, "10"), tr)});
  EXPECT_FALSE(early.verdict.foul);
  EXPECT_THAT(early.verdict.respotted, ElementsAre("10"));
  EXPECT_EQ(t.state.to_play, 0);

  Table u = MakeTable(GameKind::kTenBall, {{"cue", -0.5, 0}, {"10", 0.6, 0.1}});
  const Judgement last = JudgeEvents(u, {.ball = "10", .pocket = "top_right"},
                                     {Hit(0.4, 0, Idx(u, "10")), Drop(1.0, Idx(u, "10"), tr)});
  EXPECT_EQ(last.verdict.reason, "ten_pocketed");
  EXPECT_EQ(u.state.winner, 0);
}

TEST(TenBall, SafetyPassesTheTurnAndSpotsTheTen) {
  Table t = MakeTable(GameKind::kTenBall, {{"cue", -0.5, 0}, {"1", 0.3, 0.0}, {"10", 0.6, 0.1}});
  const Judgement j = JudgeEvents(t, {.safety = true},
                                  {Hit(0.4, 0, Idx(t, "1")), Hit(0.6, Idx(t, "1"), Idx(t, "10")),
                                   Drop(1.0, Idx(t, "10"), 0)});
  EXPECT_FALSE(j.verdict.foul);
  EXPECT_TRUE(j.verdict.turn_passes);
  EXPECT_THAT(j.verdict.respotted, ElementsAre("10"));
  EXPECT_FALSE(t.state.decision.pending());
}

TEST(Match, ConcessionsAndResults) {
  Table t = MakeTable(GameKind::kEightBall, {}, 2);
  absl::StatusOr<Judgement> c = t.referee->Concede(t.rules, t.model, t.state, 0, &t.balls);
  ASSERT_TRUE(c.ok());
  t.state = c->state;
  EXPECT_THAT(EventNames(*c), ElementsAre("frame_end:conceded"));
  EXPECT_EQ(t.state.frames_won[1], 1);
  EXPECT_EQ(t.state.frame, 2);
  EXPECT_EQ(t.state.breaker, 1);
  c = t.referee->Concede(t.rules, t.model, t.state, 0, &t.balls);
  ASSERT_TRUE(c.ok());
  t.state = c->state;
  EXPECT_THAT(EventNames(*c), ElementsAre("frame_end:conceded", "match_end:conceded"));
  EXPECT_EQ(t.state.winner, 1);
  EXPECT_EQ(t.state.result, MatchResult::kConceded);
  EXPECT_EQ(t.referee->Concede(t.rules, t.model, t.state, 0, &t.balls).status().code(),
            absl::StatusCode::kFailedPrecondition);
}

TEST(Match, ShotClockExpiry) {
  Table t = MakeTable(GameKind::kNineBall, {{"cue", -0.5, 0}, {"1", 0.3, 0.2}, {"9", 0.8, -0.3}});
  absl::StatusOr<Judgement> j = t.referee->ShotClockExpired(t.rules, t.model, t.state, &t.balls);
  ASSERT_TRUE(j.ok());
  EXPECT_TRUE(j->verdict.foul);
  EXPECT_EQ(j->verdict.reason, "shot_clock");
  EXPECT_EQ(j->state.to_play, 1);
  EXPECT_EQ(j->state.ball_in_hand, BallInHand::kAnywhere);
  EXPECT_EQ(j->state.fouls_in_row[0], 1);
}

TEST(Match, FreeHasNoReferee) {
  EXPECT_EQ(RefereeFor(GameKind::kFree), nullptr);
  TableState balls;
  EXPECT_FALSE(StartMatch(*MakeRules(GameKind::kFree), PoolModel(), Start::kBreak, &balls).ok());
  // In play needs the game's balls.
  TableState wrong = Layout(PoolModel(), {{"cue", 0, 0}, {"1", 0.3, 0}});
  EXPECT_THAT(StartMatch(*MakeRules(GameKind::kNineBall), PoolModel(), Start::kInPlay, &wrong)
                  .status().message(),
              HasSubstr("needs the 9"));
}

// Two runs of the same shots give the same states: the referees read no clock and no
// unordered container.
TEST(Determinism, SameInputsSameJudgement) {
  std::vector<std::string> runs[2];
  for (auto& out : runs) {
    Table t = MakeTable(GameKind::kEightBall, {});
    Judgement j = t.Play(0, {}, 0.0, 9.0);
    out.push_back(j.verdict.reason);
    for (const Ball& b : t.balls.balls) out.push_back(std::to_string(b.r.x()) + std::to_string(b.r.y()));
    out.insert(out.end(), t.state.on.begin(), t.state.on.end());
  }
  EXPECT_EQ(runs[0], runs[1]);
}

}  // namespace
}  // namespace sportsim::games::testing
