// The snooker referee: real shots on the event engine from in-play positions, synthetic event
// lists for the instants a real shot rarely produces, and a randomized cross-check against a
// deliberately simple second statement of the basic rules.
#include "sim/games/snooker.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "sim/billiards/cue.h"
#include "sim/billiards/rack.h"
#include "sim/billiards/shot.h"
#include "sim/games/game.h"
#include "sim/games/snooker_geometry.h"

namespace sportsim::games {
namespace {

using billiards::Ball;
using billiards::CueStrike;
using billiards::Event;
using billiards::EventKind;
using billiards::MotionState;
using Eigen::Vector2d;

constexpr double kPosTolM = 1e-9;

struct Table {
  TableModel model = TableModel::Create(*billiards::MakeTablePreset("snooker")).value();
  Rules rules = MakeRules(GameKind::kSnooker).value();
  SnookerGeometry geo = MakeSnookerGeometry(model).value();
  const Referee& ref = SnookerReferee();
};

// The full rack with every red but the first `reds` taken off (pocketed), the colours on their
// spots.
TableState RackWith(const Table& t, int reds) {
  TableState s{.balls = billiards::MakeRack("snooker", t.model).value()};
  for (Ball& b : s.balls) {
    if (IsSnookerRed(b.id) && std::stoi(b.id.substr(3)) > reds) {
      b.state = MotionState::kPocketed;
      b.pocket = 0;
    }
  }
  return s;
}

void Put(TableState* s, const std::string& id, Vector2d xy, double r) {
  Ball& b = s->balls[s->Find(id)];
  b.r = Eigen::Vector3d(xy.x(), xy.y(), r);
  b.state = MotionState::kStationary;
  b.pocket = -1;
}

Vector2d PocketCentre(const TableModel& m, const std::string& name) {
  for (const billiards::Pocket& p : m.spec().pockets) {
    if (p.name == name) return p.centre;
  }
  return Vector2d::Zero();
}

// A strike of the cue ball at `speed` (ball speed, m/s) that sends `target` towards `pocket`
// (ghost-ball aim), with follow `b`.
CueStrike PotStrike(const Table& t, const TableState& s, const std::string& target,
                    const std::string& pocket, double speed, double b = 0.0) {
  const Vector2d cue = s.balls[s.Find("cue")].r.head<2>();
  const Vector2d obj = s.balls[s.Find(target)].r.head<2>();
  const Vector2d u = (PocketCentre(t.model, pocket) - obj).normalized();
  const Vector2d ghost = obj - 2.0 * t.model.radius() * u;
  const Vector2d aim = ghost - cue;
  return CueStrike{.speed_mps = speed, .ball_speed = true,
                   .phi_rad = std::atan2(aim.y(), aim.x()), .b = b};
}

ShotRecord Play(const Table& t, const TableState& before, const CueStrike& strike,
                const std::string& striker = "cue") {
  TableState s = before;
  const int cue = s.Find(striker);
  EXPECT_TRUE(billiards::ApplyStrike(t.model, 0, strike, cue, &s).ok());
  absl::StatusOr<billiards::ShotResult> r =
      billiards::SimulateShot(t.model, billiards::SolverOptions{}, s, billiards::ShotOptions{});
  EXPECT_TRUE(r.ok()) << r.status();
  EXPECT_TRUE(r->at_rest);
  return ShotRecord{.struck = cue, .before = before, .events = r->events, .after = r->final_state};
}

GameState InPlay(const Table& t, TableState* s) {
  return StartMatch(t.rules, t.model, Start::kInPlay, s).value();
}

Judgement JudgeShot(const Table& t, const GameState& st, const ShotCall& call,
                    const ShotRecord& rec, TableState* after) {
  EXPECT_TRUE(t.ref.CheckShot(t.rules, t.model, st, st.to_play, call, rec.before).ok());
  *after = rec.after;
  return t.ref.Judge(t.rules, t.model, st, call, rec, after);
}

bool Down(const TableState& s, const std::string& id) {
  return s.balls[s.Find(id)].state == MotionState::kPocketed;
}

// --- real shots --------------------------------------------------------------------------------

TEST(SnookerScenarioTest, PottingARedScoresOneAndKeepsTheTurn) {
  Table t;
  TableState s = RackWith(t, 2);
  const double r = t.model.radius();
  Put(&s, "red1", {1.3, 0.6}, r);
  Put(&s, "cue", {0.9, 0.25}, r);
  GameState st = InPlay(t, &s);
  ASSERT_EQ(st.phase, "reds");
  const ShotRecord rec = Play(t, s, PotStrike(t, s, "red1", "top_right", 1.8));
  TableState after;
  const Judgement j = JudgeShot(t, st, {}, rec, &after);
  ASSERT_TRUE(Down(after, "red1"));
  ASSERT_FALSE(Down(after, "cue"));
  EXPECT_FALSE(j.verdict.foul) << j.verdict.reason;
  EXPECT_EQ(j.verdict.points, 1);
  EXPECT_FALSE(j.verdict.turn_passes);
  EXPECT_EQ(j.state.scores[0], 1);
  EXPECT_EQ(j.state.to_play, 0);
  EXPECT_EQ(j.state.phase, "colour");
  EXPECT_EQ(j.state.on.size(), 6u);
  // The next stroke must nominate a colour.
  EXPECT_FALSE(t.ref.CheckShot(t.rules, t.model, j.state, 0, {}, after).ok());
  EXPECT_TRUE(t.ref.CheckShot(t.rules, t.model, j.state, 0, {.nominate = "pink"}, after).ok());
  EXPECT_FALSE(t.ref.CheckShot(t.rules, t.model, j.state, 0, {.nominate = "red2"}, after).ok());
}

TEST(SnookerScenarioTest, PottingTheNominatedColourScoresItsValueAndRespotsIt) {
  Table t;
  TableState s = RackWith(t, 2);
  const double r = t.model.radius();
  Put(&s, "pink", {1.3, 0.6}, r);
  Put(&s, "cue", {0.9, 0.25}, r);
  GameState st = InPlay(t, &s);
  st.phase = "colour";  // a red was just potted
  st.on = {"yellow", "green", "brown", "blue", "pink", "black"};
  const ShotRecord rec = Play(t, s, PotStrike(t, s, "pink", "top_right", 1.8));
  ASSERT_TRUE(Down(rec.after, "pink"));
  TableState after;
  const Judgement j = JudgeShot(t, st, {.nominate = "pink"}, rec, &after);
  EXPECT_FALSE(j.verdict.foul) << j.verdict.reason;
  EXPECT_EQ(j.verdict.points, 6);
  EXPECT_EQ(j.state.scores[0], 6);
  EXPECT_FALSE(j.verdict.turn_passes);
  EXPECT_EQ(j.verdict.respotted, std::vector<std::string>{"pink"});
  const Ball& pink = after.balls[after.Find("pink")];
  EXPECT_EQ(pink.state, MotionState::kStationary);
  EXPECT_NEAR((pink.r.head<2>() - t.geo.spots[4]).norm(), 0.0, kPosTolM);
  EXPECT_EQ(j.state.phase, "reds");
  // Nominating the blue and potting the pink instead is a foul worth 6.
  TableState after2;
  const Judgement k = JudgeShot(t, st, {.nominate = "blue"}, rec, &after2);
  EXPECT_TRUE(k.verdict.foul);
  EXPECT_EQ(k.verdict.points, 6);
  EXPECT_EQ(k.state.scores[1], 6);
}

TEST(SnookerScenarioTest, InOffIsAFoulWorthAtLeastFourToTheOpponent) {
  Table t;
  TableState s = RackWith(t, 3);
  const double r = t.model.radius();
  // A red near the corner, the cue ball straight behind it: strong follow takes both in.
  const Vector2d pocket = PocketCentre(t.model, "top_right");
  const Vector2d dir = Vector2d(1.0, 1.0).normalized();
  Put(&s, "red1", pocket - 0.25 * dir, r);
  Put(&s, "cue", pocket - 0.55 * dir, r);
  GameState st = InPlay(t, &s);
  const ShotRecord rec = Play(t, s, PotStrike(t, s, "red1", "top_right", 2.0, 0.45));
  ASSERT_TRUE(Down(rec.after, "cue"));
  ASSERT_TRUE(Down(rec.after, "red1"));
  TableState after;
  const Judgement j = JudgeShot(t, st, {}, rec, &after);
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "scratch");
  EXPECT_EQ(j.verdict.points, 4);
  EXPECT_EQ(j.state.scores, (std::array<int, 2>{0, 4}));
  EXPECT_TRUE(Down(after, "red1"));  // a red potted on a foul stays down
  EXPECT_EQ(j.state.ball_in_hand, BallInHand::kD);
  ASSERT_TRUE(j.state.decision.pending());
  EXPECT_EQ(j.state.decision.seat, 1);
  EXPECT_EQ(j.state.decision.choices, (std::vector<std::string>{"play", "play_again"}));
  // The offended seat makes the offender play again, from the D.
  TableState b2 = after;
  const Judgement d = t.ref.Decide(t.rules, t.model, j.state, 1, "play_again", &b2).value();
  EXPECT_EQ(d.state.to_play, 0);
  EXPECT_EQ(d.state.ball_in_hand, BallInHand::kD);
  EXPECT_FALSE(t.ref.Decide(t.rules, t.model, j.state, 1, "replace", &b2).ok());
  EXPECT_TRUE(t.ref.InZone(t.model, BallInHand::kD, t.geo.spots[2] - Vector2d(0.1, 0.0)));
  EXPECT_FALSE(t.ref.InZone(t.model, BallInHand::kD, t.geo.spots[2] + Vector2d(0.1, 0.0)));
}

TEST(SnookerScenarioTest, HittingAColourFirstWhenARedIsOnIsAFoulValuedAsTheHigher) {
  Table t;
  TableState s = RackWith(t, 2);
  const double r = t.model.radius();
  Put(&s, "cue", {-0.6, 0.0}, r);  // straight at the blue on its spot
  GameState st = InPlay(t, &s);
  const ShotRecord rec =
      Play(t, s, CueStrike{.speed_mps = 1.0, .ball_speed = true, .phi_rad = 0.0});
  TableState after;
  const Judgement j = JudgeShot(t, st, {}, rec, &after);
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "wrong_ball_first");
  EXPECT_EQ(j.verdict.points, 5);
  EXPECT_EQ(j.state.scores[1], 5);
  EXPECT_EQ(j.state.to_play, 1);
  // Aiming at the black instead: 7.
  Put(&s, "blue", {0.0, 0.5}, r);
  const ShotRecord rec2 =
      Play(t, s, CueStrike{.speed_mps = 3.0, .ball_speed = true, .phi_rad = 0.0});
  const Judgement k = JudgeShot(t, st, {}, rec2, &after);
  EXPECT_TRUE(k.verdict.foul);
  EXPECT_GE(k.verdict.points, 6);  // the pink (on the way) or the black
}

// --- synthetic event lists ---------------------------------------------------------------------

Event Hit(double t_s, int a, int b) {
  return Event{.t_s = t_s, .kind = EventKind::kBallBall, .a = a, .b = b};
}
Event Pot(double t_s, int a, int pocket) {
  return Event{.t_s = t_s, .kind = EventKind::kBallPocket, .a = a, .other = pocket};
}

// A record whose `after` is `before` with the pocketed balls taken off.
ShotRecord Synthetic(const TableState& before, std::vector<Event> events) {
  ShotRecord rec{.struck = before.Find("cue"), .before = before, .events = events, .after = before};
  for (const Event& e : events) {
    if (e.kind == EventKind::kBallPocket) {
      rec.after.balls[e.a].state = MotionState::kPocketed;
      rec.after.balls[e.a].pocket = e.other;
    }
  }
  return rec;
}

TEST(SnookerSyntheticTest, TwoRedsAtTheSameInstantAreLegal) {
  Table t;
  TableState s = RackWith(t, 15);
  Put(&s, "cue", {-1.2, 0.1}, t.model.radius());
  GameState st = InPlay(t, &s);
  const int cue = s.Find("cue"), r1 = s.Find("red1"), r2 = s.Find("red2");
  TableState after;
  const Judgement j =
      JudgeShot(t, st, {}, Synthetic(s, {Hit(0.5, cue, r1), Hit(0.5, cue, r2), Pot(1.0, r1, 1),
                                         Pot(1.2, r2, 2)}),
                &after);
  EXPECT_FALSE(j.verdict.foul) << j.verdict.reason;
  EXPECT_EQ(j.verdict.points, 2);
  EXPECT_EQ(j.state.phase, "colour");
}

TEST(SnookerSyntheticTest, RedAndColourAtTheSameInstantIsAFoul) {
  Table t;
  TableState s = RackWith(t, 15);
  Put(&s, "cue", {-1.2, 0.1}, t.model.radius());
  GameState st = InPlay(t, &s);
  const int cue = s.Find("cue"), r1 = s.Find("red1"), pink = s.Find("pink");
  TableState after;
  const Judgement j =
      JudgeShot(t, st, {}, Synthetic(s, {Hit(0.5, cue, r1), Hit(0.5, cue, pink), Pot(1.0, r1, 1)}),
                &after);
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "wrong_ball_first");
  EXPECT_EQ(j.verdict.points, 6);
  EXPECT_TRUE(Down(after, "red1"));  // stays down
  // One nanosecond and more apart, the red first: legal.
  const Judgement k = JudgeShot(
      t, st, {}, Synthetic(s, {Hit(0.5, cue, r1), Hit(0.5 + 1e-6, cue, pink), Pot(1.0, r1, 1)}),
      &after);
  EXPECT_FALSE(k.verdict.foul) << k.verdict.reason;
}

TEST(SnookerSyntheticTest, ColoursPottedOnAFoulAreRespottedAndTheHighestPenaltyApplies) {
  Table t;
  TableState s = RackWith(t, 15);
  Put(&s, "cue", {-1.2, 0.1}, t.model.radius());
  GameState st = InPlay(t, &s);
  const int cue = s.Find("cue"), r1 = s.Find("red1"), blue = s.Find("blue"),
            black = s.Find("black");
  TableState after;
  const Judgement j = JudgeShot(
      t, st, {},
      Synthetic(s, {Hit(0.5, cue, r1), Pot(1.0, blue, 4), Pot(1.5, black, 1), Pot(2.0, cue, 2)}),
      &after);
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.points, 7);
  EXPECT_EQ(j.verdict.respotted, (std::vector<std::string>{"black", "blue"}));
  EXPECT_FALSE(Down(after, "black"));
  EXPECT_FALSE(Down(after, "blue"));
  EXPECT_EQ(j.state.ball_in_hand, BallInHand::kD);
}

// Only the black left, level after a foul on it: the black is re-spotted, the seeded draw
// picks who plays it from the D, and the next score ends the frame.
TEST(SnookerSyntheticTest, TieOnTheBlackRespotsItWithASeededDraw) {
  Table t;
  TableState s = RackWith(t, 0);
  const double r = t.model.radius();
  for (const char* c : {"yellow", "green", "brown", "blue", "pink"}) {
    s.balls[s.Find(c)].state = MotionState::kPocketed;
  }
  Put(&s, "black", {1.2, 0.3}, r);
  Put(&s, "cue", {0.0, 0.3}, r);
  GameState st0 = InPlay(t, &s);
  ASSERT_EQ(st0.on, std::vector<std::string>{"black"});
  st0.scores = {63, 56};
  const int cue = s.Find("cue"), black = s.Find("black");
  // Seat 0 misses the black: 7 to seat 1, level at 63.
  for (uint64_t seed : {1ull, 2ull, 3ull, 4ull, 5ull, 6ull}) {
    GameState st = st0;
    st.seed = seed;
    TableState after;
    const Judgement j = JudgeShot(t, st, {}, Synthetic(s, {}), &after);
    EXPECT_TRUE(j.verdict.foul);
    EXPECT_EQ(j.verdict.points, 7);
    EXPECT_EQ(j.state.scores, (std::array<int, 2>{63, 63}));
    EXPECT_FALSE(j.verdict.frame_over);
    EXPECT_EQ(j.state.phase, "respotted_black");
    const int drawn = SnookerRespottedBlackDraw(seed, st.frame);
    EXPECT_EQ(j.state.to_play, drawn);
    EXPECT_EQ(j.state.ball_in_hand, BallInHand::kD);
    EXPECT_FALSE(j.state.decision.pending());
    EXPECT_NEAR((after.balls[black].r.head<2>() - t.geo.spots[5]).norm(), 0.0, kPosTolM);
    EXPECT_TRUE(Down(after, "cue"));  // in hand: to be placed in the D
    const auto ev = std::find_if(j.events.begin(), j.events.end(), [](const GameEvent& e) {
      return e.reason == "respotted_black_draw";
    });
    ASSERT_NE(ev, j.events.end());
    EXPECT_EQ(ev->seat, drawn);
    // The drawn seat places the cue ball in the D and pots the black: frame (and match) won.
    ASSERT_TRUE(t.ref.CheckPlacement(t.rules, t.model, j.state, drawn, after, "cue",
                                     t.geo.spots[2] - Vector2d(0.1, 0.0))
                    .ok());
    EXPECT_FALSE(t.ref.CheckPlacement(t.rules, t.model, j.state, drawn, after, "cue",
                                      Vector2d(0.0, 0.0))
                     .ok());
    TableState placed = after;
    PlaceBall(t.model, cue, t.geo.spots[2] - Vector2d(0.1, 0.0), &placed);
    GameState st2 = j.state;
    st2.ball_in_hand = BallInHand::kNone;
    TableState after2;
    const Judgement k =
        JudgeShot(t, st2, {}, Synthetic(placed, {Hit(1.0, cue, black), Pot(2.0, black, 1)}),
                  &after2);
    EXPECT_EQ(k.verdict.points, 7);
    EXPECT_TRUE(k.verdict.frame_over);
    EXPECT_EQ(k.state.winner, drawn);
  }
  // The draw depends on the seed and is not constant.
  int ones = 0;
  for (uint64_t seed = 0; seed < 64; ++seed) ones += SnookerRespottedBlackDraw(seed, 1);
  EXPECT_GT(ones, 10);
  EXPECT_LT(ones, 54);
}

TEST(SnookerSyntheticTest, FreeBallAfterAFoulThatLeavesTheCueBallSnookered) {
  Table t;
  TableState s = RackWith(t, 1);
  const double r = t.model.radius();
  // After the stroke the cue ball lies fully behind the brown, with the only red beyond.
  Put(&s, "red1", {0.6, -0.5}, r);
  Put(&s, "cue", {-0.8, -0.5}, r);
  Put(&s, "brown", {-0.8 + 2 * r + 0.002, -0.5}, r);
  GameState st = InPlay(t, &s);
  const int cue = s.Find("cue");
  // Seat 0's stroke touches nothing (synthetic): a foul; seat 1 is snookered: free ball.
  TableState after;
  const Judgement j = JudgeShot(t, st, {}, Synthetic(s, {}), &after);
  ASSERT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "no_contact");
  EXPECT_TRUE(j.state.free_ball);
  TableState b = after;
  const Judgement d = t.ref.Decide(t.rules, t.model, j.state, 1, "play", &b).value();
  EXPECT_TRUE(d.state.free_ball);
  // The free ball (the brown) nominated, hit and potted: it scores as a red and is respotted.
  EXPECT_TRUE(t.ref.CheckShot(t.rules, t.model, d.state, 1, {.nominate = "brown"}, b).ok());
  const int brown = s.Find("brown");
  TableState after2;
  const Judgement k = JudgeShot(t, d.state, {.nominate = "brown"},
                                Synthetic(b, {Hit(0.1, cue, brown), Pot(1.0, brown, 0)}), &after2);
  EXPECT_FALSE(k.verdict.foul) << k.verdict.reason;
  EXPECT_EQ(k.verdict.points, 1);
  EXPECT_EQ(k.verdict.respotted, std::vector<std::string>{"brown"});
  EXPECT_EQ(k.state.phase, "colour");
  // Hitting the red first while the brown is nominated: a foul.
  const int red = s.Find("red1");
  const Judgement m = JudgeShot(t, d.state, {.nominate = "brown"},
                                Synthetic(b, {Hit(0.1, cue, red)}), &after2);
  EXPECT_TRUE(m.verdict.foul);
  // Hitting the free ball and leaving the opponent snookered behind it: a foul.
  const Judgement fs = JudgeShot(t, d.state, {.nominate = "brown"},
                                 Synthetic(b, {Hit(0.1, cue, brown)}), &after2);
  EXPECT_TRUE(fs.verdict.foul);
  EXPECT_EQ(fs.verdict.reason, "free_ball_snooker");
  EXPECT_EQ(fs.verdict.points, 4);
  // "play_again": the free ball lapses.
  const Judgement pa = t.ref.Decide(t.rules, t.model, j.state, 1, "play_again", &b).value();
  EXPECT_FALSE(pa.state.free_ball);
  EXPECT_EQ(pa.state.to_play, 0);
  // Without the brown in the way there is no free ball.
  TableState open = s;
  Put(&open, "brown", t.geo.spots[2], r);
  GameState st_open = InPlay(t, &open);
  const Judgement n = JudgeShot(t, st_open, {}, Synthetic(open, {}), &after);
  EXPECT_FALSE(n.state.free_ball);
}

TEST(SnookerSyntheticTest, TouchingBall) {
  Table t;
  TableState s = RackWith(t, 2);
  const double r = t.model.radius();
  Put(&s, "red1", {0.0, 0.5}, r);
  Put(&s, "cue", {0.0, 0.5 - 2 * r}, r);  // touching a red, a ball on
  GameState st = InPlay(t, &s);
  const int cue = s.Find("cue"), red1 = s.Find("red1"), red2 = s.Find("red2");
  TableState after;
  // Playing away and hitting nothing: no foul, since the touching ball is on.
  const Judgement j = JudgeShot(t, st, {}, Synthetic(s, {}), &after);
  EXPECT_FALSE(j.verdict.foul) << j.verdict.reason;
  EXPECT_TRUE(j.verdict.turn_passes);
  // Moving it at the strike: a push stroke.
  const Judgement k = JudgeShot(t, st, {}, Synthetic(s, {Hit(0.0, cue, red1)}), &after);
  EXPECT_TRUE(k.verdict.foul);
  EXPECT_EQ(k.verdict.reason, "push_stroke");
  EXPECT_EQ(k.verdict.points, 4);
  // Touching the pink (not on): playing away onto a red is legal, into the pink is not.
  Put(&s, "pink", {0.0, 0.5 - 4 * r - 1e-6}, r);
  Put(&s, "red1", {0.5, -0.5}, r);
  GameState st2 = InPlay(t, &s);
  EXPECT_FALSE(JudgeShot(t, st2, {}, Synthetic(s, {Hit(0.4, cue, red2)}), &after).verdict.foul);
  const Judgement m = JudgeShot(t, st2, {}, Synthetic(s, {Hit(0.0, cue, s.Find("pink"))}), &after);
  EXPECT_TRUE(m.verdict.foul);
  EXPECT_EQ(m.verdict.points, 6);
}

TEST(SnookerSyntheticTest, MissRuleOffersReplaceOnlyWhenOn) {
  Table t;
  TableState s = RackWith(t, 3);
  Put(&s, "cue", {-1.2, 0.1}, t.model.radius());
  Put(&s, "red1", {0.0, 0.6}, t.model.radius());  // a full-ball line to it
  GameState st = InPlay(t, &s);
  TableState after;
  const Judgement off = JudgeShot(t, st, {}, Synthetic(s, {}), &after);
  EXPECT_EQ(off.state.decision.choices.size(), 2u);
  Table on;
  on.rules = MakeRules(GameKind::kSnooker, 1, 0.0, {{"miss_rule", "on"}}).value();
  const Judgement j = JudgeShot(on, st, {}, Synthetic(s, {}), &after);
  EXPECT_EQ(j.verdict.reason, "miss");
  ASSERT_EQ(j.state.decision.choices.size(), 3u);
  TableState b = after;
  const Judgement d = on.ref.Decide(on.rules, on.model, j.state, 1, "replace", &b).value();
  EXPECT_EQ(d.state.to_play, 0);
  EXPECT_EQ(d.state.misses_in_row, 1);
  // Third miss with a full-ball line: the frame goes to the opponent.
  GameState st3 = st;
  st3.misses_in_row = 2;
  const Judgement k = JudgeShot(on, st3, {}, Synthetic(s, {}), &after);
  EXPECT_TRUE(k.verdict.frame_over);
  EXPECT_EQ(k.state.frames_won[1], 1);
}

TEST(SnookerSyntheticTest, ShotClockIsAFoulWorthTheBallOn) {
  Table t;
  TableState s = RackWith(t, 0);
  for (const char* c : {"yellow", "green"}) s.balls[s.Find(c)].state = MotionState::kPocketed;
  Put(&s, "cue", {-1.2, 0.1}, t.model.radius());
  GameState st = InPlay(t, &s);
  ASSERT_EQ(st.on, std::vector<std::string>{"brown"});
  const Judgement j = t.ref.ShotClockExpired(t.rules, t.model, st, &s).value();
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "shot_clock");
  EXPECT_EQ(j.verdict.points, 4);
  EXPECT_EQ(j.state.scores[1], 4);
  st.on = {"pink"};
  st.phase = "colours";
  EXPECT_EQ(t.ref.ShotClockExpired(t.rules, t.model, st, &s)->verdict.points, 6);
}

// --- randomized cross-check --------------------------------------------------------------------

// The basic rules, stated once more as simply as possible: which balls are on, the first
// contact, pots, and the penalty (at least 4; the highest of the ball on and the balls
// concerned; 7 for a red first straight after a red).
struct Simple {
  bool foul = false;
  int value = 0;   // penalty if foul, else points scored
};

Simple SimpleRules(const std::string& phase, const std::string& nominated,
                   const std::string& lowest, const ShotRecord& rec) {
  const TableState& b = rec.before;
  const int cue = rec.struck;
  const auto val = [&](int i) { return SnookerValue(b.balls[i].id); };
  const auto is_on = [&](int i) {
    const std::string& id = b.balls[i].id;
    if (phase == "reds") return IsSnookerRed(id);
    if (phase == "colour") return id == nominated;
    return id == lowest;
  };
  const int on_value =
      phase == "reds" ? 1 : SnookerValue(phase == "colour" ? nominated : lowest);
  Simple out;
  int pen = 0;
  // First contact: the struck ball's first ball-ball events at one instant.
  std::vector<int> first;
  double t_first = -1;
  for (const Event& e : rec.events) {
    if (e.kind != EventKind::kBallBall || (e.a != cue && e.b != cue)) continue;
    const int o = e.a == cue ? e.b : e.a;
    if (t_first < 0) t_first = e.t_s;
    if (e.t_s - t_first > 1e-9) break;
    if (std::find(first.begin(), first.end(), o) == first.end()) first.push_back(o);
  }
  if (first.empty()) pen = std::max(pen, on_value);
  for (int o : first) {
    if (!is_on(o)) pen = std::max({pen, on_value, val(o)});
    if (phase == "colour" && IsSnookerRed(b.balls[o].id)) pen = std::max(pen, 7);
  }
  if (phase != "reds" && first.size() > 1) pen = std::max(pen, on_value);
  int points = 0;
  for (const Event& e : rec.events) {
    if (e.kind != EventKind::kBallPocket) continue;
    if (e.a == cue) {
      pen = std::max(pen, on_value);
    } else if (!is_on(e.a) || e.other < 0) {
      pen = std::max({pen, on_value, val(e.a)});
    } else {
      points += phase == "reds" ? 1 : on_value;
    }
  }
  out.foul = pen > 0;
  out.value = out.foul ? std::max(pen, 4) : points;
  return out;
}

TEST(SnookerRandomTest, AgreesWithASimpleStatementOfTheRules) {
  Table t;
  std::mt19937_64 rng(0x5EED5);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double r = t.model.radius();
  const double hx = t.geo.x_limit_m, hy = t.geo.y_limit_m;
  int fouls = 0, legal_pots = 0, shots = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    // A random layout: a few reds (or none) and the colours anywhere, not touching.
    const int reds = static_cast<int>(rng() % 5);
    TableState s = RackWith(t, reds);
    std::vector<Vector2d> used;
    for (Ball& b : s.balls) {
      if (b.state == MotionState::kPocketed) continue;
      if (b.id != "cue" && reds == 0 && u01(rng) < 0.3 && b.id != "black") {
        b.state = MotionState::kPocketed;  // colours phase: some colours already gone
        continue;
      }
      for (;;) {
        const Vector2d p(hx * (2 * u01(rng) - 1), hy * (2 * u01(rng) - 1));
        bool ok = true;
        for (const Vector2d& q : used) ok &= (p - q).norm() > 2 * r + 0.01;
        for (const billiards::Pocket& pk : t.model.spec().pockets) {
          ok &= (p - pk.centre).norm() > pk.radius_m + 2 * r;
        }
        if (!ok) continue;
        b.r = Eigen::Vector3d(p.x(), p.y(), r);
        used.push_back(p);
        break;
      }
    }
    GameState st = InPlay(t, &s);
    std::string nominated;
    if (st.phase == "reds" && rng() % 2) {
      st.phase = "colour";
      st.on = {"yellow", "green", "brown", "blue", "pink", "black"};
      nominated = std::string(kSnookerColours[rng() % 6]);
    }
    const std::string lowest = st.phase == "colours" ? st.on.front() : "";
    CueStrike strike{.speed_mps = 0.5 + 3.5 * u01(rng), .ball_speed = true,
                     .phi_rad = 2 * M_PI * u01(rng), .a = 0.4 * (u01(rng) - 0.5),
                     .b = 0.8 * (u01(rng) - 0.5)};
    if (rng() % 2) {
      // Half the shots aim to pot a ball on (or, after a red, any colour) in a random pocket.
      std::vector<std::string> targets = st.on;
      if (!nominated.empty() && rng() % 4 != 0) targets = {nominated};
      const std::string& target = targets[rng() % targets.size()];
      const std::string& pocket = t.model.spec().pockets[rng() % 6].name;
      const CueStrike pot = PotStrike(t, s, target, pocket, 1.0 + 2.0 * u01(rng));
      strike.phi_rad = pot.phi_rad + 0.01 * (u01(rng) - 0.5);
      strike.speed_mps = pot.speed_mps;
      strike.a = 0.0;
    }
    const ShotRecord rec = Play(t, s, strike);
    const Simple want = SimpleRules(st.phase, nominated, lowest, rec);
    TableState after = rec.after;
    const Judgement j = t.ref.Judge(t.rules, t.model, st, {.nominate = nominated}, rec, &after);
    ASSERT_EQ(j.verdict.foul, want.foul) << "trial " << trial << " " << j.verdict.reason;
    ASSERT_EQ(j.verdict.points, want.value) << "trial " << trial << " " << j.verdict.reason;
    // Respotted balls touch nothing (the engine itself may leave a ball resting in a jaw).
    for (const std::string& id : j.verdict.respotted) {
      const Ball& rb = after.balls[after.Find(id)];
      ASSERT_NE(rb.state, MotionState::kPocketed) << "trial " << trial;
      for (const Ball& o : after.balls) {
        if (o.id == id || o.state == MotionState::kPocketed) continue;
        ASSERT_GE((o.r - rb.r).head<2>().norm(), 2 * r) << "trial " << trial << " " << id;
      }
    }
    fouls += want.foul;
    legal_pots += !want.foul && want.value > 0;
    ++shots;
  }
  std::printf("snooker cross-check: %d shots, %d fouls, %d legal pots\n", shots, fouls, legal_pots);
  // The sample exercises both sides.
  EXPECT_GT(fouls, shots / 10);
  EXPECT_GT(legal_pots, 20);
}

}  // namespace
}  // namespace sportsim::games
