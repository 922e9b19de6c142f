// Scenario tests: real shots played on the event engine from in-play positions (and real
// breaks), judged by the pool referees, for every verdict and decision we can set up with a
// cue. Each scenario first asserts that the physics did what the scenario needs (the ball went
// in, the cue ball touched the 2 first), so a change in the engine shows as a broken setup,
// not as a wrong referee.
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/sim/games/pool_test_util.h"

namespace sportsim::games::testing {
namespace {

using ::testing::Contains;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr double kSpotTolM = 1e-9;  // a respotted ball on its spot (m)

// A pot of `ball` into `pocket` from `back_m` behind it, with a stun-ish cue ball.
Judgement PotInto(Table& t, int seat, std::string_view ball, const ShotCall& call,
                  double speed = 1.5) {
  const double phi = Aim(t.balls, "cue", Pos(t.balls, ball));
  return t.Play(seat, call, phi, speed);
}

std::vector<Placed> LinedUp(const TableModel& m, std::string ball, Eigen::Vector2d at,
                            std::string_view pocket, double back_m,
                            std::vector<Placed> others) {
  auto [cue, b] = LineUp(m, at, pocket, back_m);
  others.insert(others.begin(), {{"cue", cue.x(), cue.y()}, {std::move(ball), b.x(), b.y()}});
  return others;
}

// --- 9-ball -----------------------------------------------------------------------------------

TEST(NineBall, WrongBallFirstGivesBallInHandAndTheTurn) {
  Table t = MakeTable(GameKind::kNineBall,
                      {{"cue", -0.5, 0}, {"1", 0.6, 0.4}, {"2", 0, 0}, {"9", 0.8, -0.3}});
  const Judgement j = t.Play(0, {}, 0.0, 1.5);
  ASSERT_THAT(ExtractFacts(t.last_record).first_contacts, ElementsAre(t.balls.Find("2")));
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "wrong_ball_first");
  EXPECT_TRUE(j.verdict.turn_passes);
  EXPECT_EQ(t.state.to_play, 1);
  EXPECT_EQ(t.state.ball_in_hand, BallInHand::kAnywhere);
  EXPECT_EQ(t.state.fouls_in_row[0], 1);
  EXPECT_THAT(EventNames(j), ElementsAre("foul:wrong_ball_first"));
  const absl::Status refused = t.referee->CheckShot(t.rules, t.model, t.state, 0, {}, t.balls);
  EXPECT_EQ(refused.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(refused.message(), HasSubstr("not your turn"));
  EXPECT_TRUE(t.referee->CheckShot(t.rules, t.model, t.state, 1, {}, t.balls).ok());
  EXPECT_TRUE(t.Place(1, {-0.9, 0.3}).ok());
  EXPECT_EQ(t.Place(0, {-0.9, 0.3}).code(), absl::StatusCode::kFailedPrecondition);
}

TEST(NineBall, LegalPotKeepsTheTurn) {
  Table t = MakeTable(GameKind::kNineBall,
                      LinedUp(PoolModel(), "1", {0.9, 0.35}, "top_right", 0.12,
                              {{"2", -0.3, -0.3}, {"9", 0.0, -0.4}}));
  const Judgement j = PotInto(t, 0, "1", {});
  ASSERT_TRUE(ExtractFacts(t.last_record).Pocketed(t.last_record.before.Find("1")));
  ASSERT_FALSE(ExtractFacts(t.last_record).Pocketed(t.last_record.struck));
  EXPECT_FALSE(j.verdict.foul) << j.verdict.reason;
  EXPECT_FALSE(j.verdict.turn_passes);
  EXPECT_EQ(t.state.to_play, 0);
  EXPECT_THAT(t.state.on, ElementsAre("2"));
  EXPECT_EQ(t.state.ball_in_hand, BallInHand::kNone);
}

TEST(NineBall, ScratchThenPlaceBeforeShooting) {
  const TableModel m = PoolModel();
  const Eigen::Vector2d pk = PocketCentre(m, "bottom_left");
  const Eigen::Vector2d in = Eigen::Vector2d(1, 1).normalized();
  const Eigen::Vector2d cue = pk + 0.45 * in;
  Table t = MakeTable(GameKind::kNineBall,
                      {{"cue", cue.x(), cue.y()}, {"1", 0.6, 0.4}, {"9", 0.8, -0.3}});
  const Judgement j = t.Play(0, {}, Aim(t.balls, "cue", pk), 1.2);
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "scratch");
  EXPECT_EQ(t.state.to_play, 1);
  const absl::Status s = t.referee->CheckShot(t.rules, t.model, t.state, 1, {}, t.balls);
  EXPECT_EQ(s.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(s.message(), HasSubstr("place the cue ball"));
  ASSERT_TRUE(t.Place(1, {0.0, 0.0}).ok());
  EXPECT_TRUE(t.referee->CheckShot(t.rules, t.model, t.state, 1, {}, t.balls).ok());
}

TEST(NineBall, NoRailAfterContact) {
  Table t = MakeTable(GameKind::kNineBall, {{"cue", 0, 0}, {"1", 0.3, 0}, {"9", 0.8, -0.3}});
  const Judgement j = t.Play(0, {}, 0.0, 0.4);
  const ShotFacts f = ExtractFacts(t.last_record);
  ASSERT_THAT(f.first_contacts, ElementsAre(1));
  ASSERT_FALSE(f.AnyCushionAtOrAfter(0.0));
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "no_rail");
}

TEST(NineBall, NoContact) {
  Table t = MakeTable(GameKind::kNineBall, {{"cue", 0, 0}, {"1", 0.6, 0.3}, {"9", 0.8, -0.3}});
  const Judgement j = t.Play(0, {}, -M_PI / 2, 0.2);
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "no_contact");
}

TEST(NineBall, NineOnALegalShotWinsTheMatch) {
  Table t = MakeTable(GameKind::kNineBall, LinedUp(PoolModel(), "9", {0.9, 0.35}, "top_right", 0.12, {}));
  const Judgement j = PotInto(t, 0, "9", {});
  EXPECT_FALSE(j.verdict.foul);
  EXPECT_TRUE(j.verdict.frame_over);
  EXPECT_THAT(EventNames(j), ElementsAre("frame_end:nine_pocketed", "match_end:won"));
  EXPECT_EQ(t.state.winner, 0);
  EXPECT_EQ(t.state.result, MatchResult::kWon);
  EXPECT_EQ(t.state.frames_won[0], 1);
  const absl::Status s = t.referee->CheckShot(t.rules, t.model, t.state, 1, {}, t.balls);
  EXPECT_THAT(s.message(), HasSubstr("match is over"));
}

TEST(NineBall, RaceToTwoRacksTheNextFrame) {
  for (const char* rotation : {"alternate", "winner"}) {
    Table t = MakeTable(GameKind::kNineBall,
                        LinedUp(PoolModel(), "9", {0.9, 0.35}, "top_right", 0.12, {}), 2,
                        {{"break", rotation}});
    const Judgement j = PotInto(t, 0, "9", {});
    EXPECT_THAT(EventNames(j), ElementsAre("frame_end:nine_pocketed"));
    EXPECT_FALSE(t.state.match_over());
    EXPECT_EQ(t.state.frame, 2);
    EXPECT_EQ(t.state.breaker, std::string(rotation) == "winner" ? 0 : 1);
    EXPECT_EQ(t.state.to_play, t.state.breaker);
    EXPECT_TRUE(t.state.is_break);
    EXPECT_EQ(t.state.ball_in_hand, BallInHand::kKitchen);
    EXPECT_EQ(t.balls.balls.size(), 10u);
    for (const Ball& b : t.balls.balls) EXPECT_NE(b.state, billiards::MotionState::kPocketed);
  }
}

TEST(NineBall, RealBreakThenPushOutFlow) {
  Table t = MakeTable(GameKind::kNineBall, {});
  ASSERT_TRUE(t.state.is_break);
  const Judgement brk = t.Play(0, {}, 0.0, 9.0);
  const ShotFacts f = ExtractFacts(t.last_record);
  ASSERT_THAT(f.first_contacts, ElementsAre(t.last_record.before.Find("1")));
  ASSERT_GE(f.BallsReachingCushion(0), 4);
  ASSERT_FALSE(f.Pocketed(0));
  ASSERT_FALSE(f.Pocketed(t.last_record.before.Find("9")));
  EXPECT_FALSE(brk.verdict.foul) << brk.verdict.reason;
  EXPECT_TRUE(t.state.push_out_available);
  EXPECT_FALSE(t.state.is_break);
  const int pusher = t.state.to_play;
  // A push-out: the cue ball rolled softly, touching nothing: no foul.
  Eigen::Vector2d cue = Pos(t.balls, "cue");
  const double phi = cue.y() > 0 ? -M_PI / 2 : M_PI / 2;
  const Judgement push = t.Play(pusher, {.push_out = true}, phi, 0.15);
  EXPECT_FALSE(push.verdict.foul) << push.verdict.reason;
  EXPECT_EQ(push.verdict.reason, "push_out");
  EXPECT_EQ(t.state.decision.seat, Other(pusher));
  EXPECT_THAT(t.state.decision.choices, ElementsAre("shoot", "pass_back"));
  EXPECT_THAT(t.referee->CheckShot(t.rules, t.model, t.state, Other(pusher), {}, t.balls).message(),
              HasSubstr("decision is pending"));
  EXPECT_EQ(t.Decide(pusher, "shoot").status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(t.Decide(Other(pusher), "accept").status().message(), HasSubstr("shoot, pass_back"));
  ASSERT_TRUE(t.Decide(Other(pusher), "pass_back").ok());
  EXPECT_EQ(t.state.to_play, pusher);
  EXPECT_FALSE(t.state.push_out_available);
  const absl::Status again =
      t.referee->CheckShot(t.rules, t.model, t.state, pusher, {.push_out = true}, t.balls);
  EXPECT_EQ(again.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(again.message(), HasSubstr("right after a legal break"));
}

TEST(NineBall, PushOutPottingTheNineSpotsIt) {
  Table t = MakeTable(GameKind::kNineBall,
                      LinedUp(PoolModel(), "9", {0.9, 0.35}, "top_right", 0.12, {{"1", -0.6, -0.4}}));
  t.state.push_out_available = true;  // the shot after a legal break
  const Judgement j = PotInto(t, 0, "9", {.push_out = true});
  ASSERT_TRUE(ExtractFacts(t.last_record).Pocketed(t.last_record.before.Find("9")));
  EXPECT_FALSE(j.verdict.foul);
  EXPECT_THAT(j.verdict.respotted, ElementsAre("9"));
  EXPECT_NEAR((Pos(t.balls, "9") - PoolTableMarks(t.model).foot_spot).norm(), 0.0, kSpotTolM);
  EXPECT_THAT(EventNames(j), ElementsAre("respot:spotted", "decision:push_out"));
  ASSERT_TRUE(t.Decide(1, "shoot").ok());
  EXPECT_EQ(t.state.to_play, 1);
}

// Both seats foul by rolling the placed cue ball into nothing; seat 0's third foul, after the
// warning at two, loses the rack (and the match).
TEST(NineBall, ThreeFoulsWithTheWarningLose) {
  Table t = MakeTable(GameKind::kNineBall, {{"cue", -0.9, -0.4}, {"1", 0.6, 0.3}, {"9", 0.8, -0.3}});
  std::vector<std::string> all;
  for (int k = 0; k < 5; ++k) {
    const int seat = k % 2;
    ASSERT_EQ(t.state.to_play, seat);
    if (k > 0) ASSERT_TRUE(t.Place(seat, {-0.9, -0.4}).ok());
    const Judgement j = t.Play(seat, {}, M_PI / 2, 0.15);
    EXPECT_EQ(j.verdict.reason, k == 4 ? "three_fouls" : "no_contact");
    for (const GameEvent& e : j.events) {
      all.push_back(std::to_string(e.seat) + ":" + std::string(GameEventKindName(e.kind)) + ":" + e.reason);
    }
    if (k == 2) EXPECT_TRUE(t.state.warned[0]);
  }
  EXPECT_THAT(all, ElementsAre("0:foul:no_contact", "1:foul:no_contact", "0:foul:no_contact",
                               "0:warning:two_fouls", "1:foul:no_contact", "1:warning:two_fouls",
                               "0:foul:three_fouls", "1:frame_end:three_fouls",
                               "1:match_end:three_fouls"));
  EXPECT_EQ(t.state.winner, 1);
  EXPECT_EQ(t.state.result, MatchResult::kThreeFouls);
}

// A legal shot in between resets the count.
TEST(NineBall, LegalShotResetsTheFoulCount) {
  Table t = MakeTable(GameKind::kNineBall,
                      {{"cue", -0.9, -0.4}, {"1", 0.0, 0.0}, {"2", 0.5, 0.45}, {"9", 0.8, -0.3}});
  t.Play(0, {}, M_PI / 2, 0.15);  // foul
  ASSERT_TRUE(t.Place(1, {-0.9, 0.4}).ok());
  t.Play(1, {}, M_PI / 2, 0.15);  // foul
  ASSERT_TRUE(t.Place(0, {-0.5, 0.0}).ok());
  const Judgement legal = t.Play(0, {}, 0.0, 2.0);  // into the 1, which reaches a cushion
  ASSERT_FALSE(legal.verdict.foul) << legal.verdict.reason;
  EXPECT_EQ(t.state.fouls_in_row[0], 0);
  EXPECT_EQ(t.state.fouls_in_row[1], 1);
}

// --- 8-ball -----------------------------------------------------------------------------------

TEST(EightBall, OpenTableCalledPotSetsGroups) {
  Table t = MakeTable(GameKind::kEightBall,
                      LinedUp(PoolModel(), "3", {0.9, 0.35}, "top_right", 0.12,
                              {{"8", 0, -0.3}, {"1", -0.6, 0.4}, {"12", 0.3, -0.45}}));
  EXPECT_TRUE(t.state.call_required);
  const absl::Status uncalled = t.referee->CheckShot(t.rules, t.model, t.state, 0, {}, t.balls);
  EXPECT_EQ(uncalled.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(uncalled.message(), HasSubstr("called"));
  EXPECT_EQ(t.referee->CheckShot(t.rules, t.model, t.state, 0, {.ball = "3", .pocket = "middle"},
                                 t.balls).code(),
            absl::StatusCode::kInvalidArgument);
  const Judgement j = PotInto(t, 0, "3", {.ball = "3", .pocket = "top_right"});
  EXPECT_FALSE(j.verdict.foul);
  EXPECT_FALSE(j.verdict.turn_passes);
  EXPECT_EQ(t.state.groups[0], Group::kSolids);
  EXPECT_EQ(t.state.groups[1], Group::kStripes);
  EXPECT_THAT(t.state.on, ElementsAre("1"));
}

TEST(EightBall, PotInAnotherPocketThanCalledPassesTheTurn) {
  Table t = MakeTable(GameKind::kEightBall,
                      LinedUp(PoolModel(), "3", {0.9, 0.35}, "top_right", 0.12,
                              {{"8", 0, -0.3}, {"1", -0.6, 0.4}, {"12", 0.3, -0.45}}));
  const Judgement j = PotInto(t, 0, "3", {.ball = "3", .pocket = "bottom_left"});
  EXPECT_FALSE(j.verdict.foul);
  EXPECT_TRUE(j.verdict.turn_passes);
  EXPECT_EQ(t.state.groups[0], Group::kNone);  // groups need a called ball in its pocket
  EXPECT_EQ(t.state.to_play, 1);
}

TEST(EightBall, EightFirstOnOpenTable) {
  for (const char* variant : {"foul", "bca"}) {
    Table t = MakeTable(GameKind::kEightBall, {{"cue", -0.5, 0}, {"8", 0.0, 0.0}, {"3", 0.6, 0.4}},
                        1, {{"eight_first_on_open", variant}});
    const Judgement j = t.Play(0, {.safety = true}, 0.0, 2.0);
    ASSERT_FALSE(ExtractFacts(t.last_record).Pocketed(t.last_record.before.Find("8")));
    EXPECT_EQ(j.verdict.foul, std::string(variant) == "foul") << j.verdict.reason;
    EXPECT_TRUE(j.verdict.turn_passes);
    EXPECT_EQ(t.state.ball_in_hand,
              std::string(variant) == "foul" ? BallInHand::kAnywhere : BallInHand::kNone);
  }
}

// A combination 3 -> 8 while the shooter's solids remain: the 8 early loses the rack.
TEST(EightBall, EightEarlyOnACombinationLoses) {
  const TableModel m = PoolModel();
  const Eigen::Vector2d eight(0.95, 0.4);
  const Eigen::Vector2d dir = (PocketCentre(m, "top_right") - eight).normalized();
  const Eigen::Vector2d three = eight - 0.1 * dir;
  const Eigen::Vector2d cue = three - 0.15 * dir;
  Table t = MakeTable(GameKind::kEightBall, {{"cue", cue.x(), cue.y()},
                                              {"3", three.x(), three.y()},
                                              {"8", eight.x(), eight.y()},
                                              {"1", -0.6, -0.4},
                                              {"10", -0.3, 0.45}});
  t.state.groups = {Group::kSolids, Group::kStripes};
  const Judgement j = t.Play(0, {.ball = "3", .pocket = "top_right"},
                             Aim(t.balls, "cue", three), 2.5);
  const ShotFacts f = ExtractFacts(t.last_record);
  ASSERT_THAT(f.first_contacts, ElementsAre(t.last_record.before.Find("3")));
  ASSERT_EQ(f.PocketOf(t.last_record.before.Find("8")), PocketIdx(m, "top_right"));
  EXPECT_FALSE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "eight_early");
  EXPECT_THAT(EventNames(j), ElementsAre("frame_end:eight_early", "match_end:won"));
  EXPECT_EQ(t.state.winner, 1);
}

TEST(EightBall, EightInTheCalledPocketWinsElseLoses) {
  for (const char* called : {"top_right", "bottom_right"}) {
    Table t = MakeTable(GameKind::kEightBall,
                        LinedUp(PoolModel(), "8", {0.9, 0.35}, "top_right", 0.12,
                                {{"10", -0.3, 0.45}}));
    t.state.groups = {Group::kSolids, Group::kStripes};
    t.state.on = {"8"};
    const Judgement j = PotInto(t, 0, "8", {.ball = "8", .pocket = called});
    ASSERT_TRUE(ExtractFacts(t.last_record).Pocketed(t.last_record.before.Find("8")));
    const bool right = std::string(called) == "top_right";
    EXPECT_EQ(j.verdict.reason, right ? "eight_pocketed" : "eight_wrong_pocket");
    EXPECT_EQ(t.state.winner, right ? 0 : 1);
  }
}

TEST(EightBall, RealBreakIsLegal) {
  Table t = MakeTable(GameKind::kEightBall, {});
  const Judgement j = t.Play(0, {}, 0.0, 9.0);
  const ShotFacts f = ExtractFacts(t.last_record);
  int pocketed = 0;
  for (const Pocketing& p : f.pocketed) pocketed += p.ball != 0;
  ASSERT_TRUE(pocketed > 0 || f.BallsReachingCushion(0) >= 4);
  EXPECT_NE(j.verdict.reason, "illegal_break");
  EXPECT_FALSE(t.state.is_break);
  EXPECT_EQ(t.state.groups[0], Group::kNone);  // the table stays open after the break
  EXPECT_EQ(t.state.to_play, pocketed > 0 && !j.verdict.foul ? 0 : 1);
}

TEST(EightBall, SoftBreakIsIllegalWithThreeChoices) {
  for (const char* choice : {"accept_table", "re_rack", "rebreak_by_breaker"}) {
    Table t = MakeTable(GameKind::kEightBall, {});
    const Judgement j = t.Play(0, {}, 0.0, 1.2);
    ASSERT_LT(ExtractFacts(t.last_record).BallsReachingCushion(0), 4);
    EXPECT_TRUE(j.verdict.foul);
    EXPECT_EQ(j.verdict.reason, "illegal_break");
    EXPECT_THAT(EventNames(j), ElementsAre("foul:illegal_break", "decision:illegal_break"));
    EXPECT_EQ(t.state.decision.seat, 1);
    EXPECT_THAT(t.Decide(0, choice).status().message(), HasSubstr("seat 1"));
    ASSERT_TRUE(t.Decide(1, choice).ok());
    const std::string c = choice;
    EXPECT_EQ(t.state.is_break, c != "accept_table");
    EXPECT_EQ(t.state.to_play, c == "rebreak_by_breaker" ? 0 : 1);
    EXPECT_EQ(t.state.ball_in_hand, c == "accept_table" ? BallInHand::kNone : BallInHand::kKitchen);
    if (c != "accept_table") {
      EXPECT_EQ(t.balls.balls.size(), 16u);
      EXPECT_NEAR((Pos(t.balls, "1") - PoolTableMarks(t.model).foot_spot).norm(), 0.0, kSpotTolM);
    }
  }
}

// --- 10-ball ----------------------------------------------------------------------------------

TEST(TenBall, TenPocketedOnAFoulIsSpotted) {
  Table t = MakeTable(GameKind::kTenBall,
                      LinedUp(PoolModel(), "10", {0.9, 0.35}, "top_right", 0.12, {{"1", -0.6, -0.4}}));
  const Judgement j = PotInto(t, 0, "10", {.ball = "10", .pocket = "top_right"});
  EXPECT_TRUE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "wrong_ball_first");
  EXPECT_THAT(j.verdict.respotted, ElementsAre("10"));
  EXPECT_NEAR((Pos(t.balls, "10") - PoolTableMarks(t.model).foot_spot).norm(), 0.0, kSpotTolM);
  EXPECT_THAT(EventNames(j), ElementsAre("foul:wrong_ball_first", "respot:spotted"));
}

TEST(TenBall, WrongPocketGivesTheChoice) {
  Table t = MakeTable(GameKind::kTenBall,
                      LinedUp(PoolModel(), "1", {0.9, 0.35}, "top_right", 0.12, {{"10", -0.6, -0.4}}));
  EXPECT_THAT(t.referee->CheckShot(t.rules, t.model, t.state, 0, {}, t.balls).message(),
              HasSubstr("called"));
  const Judgement j = PotInto(t, 0, "1", {.ball = "1", .pocket = "bottom_right"});
  ASSERT_TRUE(ExtractFacts(t.last_record).Pocketed(t.last_record.before.Find("1")));
  EXPECT_FALSE(j.verdict.foul);
  EXPECT_EQ(j.verdict.reason, "wrong_pocket");
  EXPECT_EQ(t.state.decision.seat, 1);
  ASSERT_TRUE(t.Decide(1, "pass_back").ok());
  EXPECT_EQ(t.state.to_play, 0);
  EXPECT_EQ(t.state.ball_in_hand, BallInHand::kNone);
}

TEST(TenBall, CalledPotContinues) {
  Table t = MakeTable(GameKind::kTenBall,
                      LinedUp(PoolModel(), "1", {0.9, 0.35}, "top_right", 0.12, {{"10", -0.6, -0.4}}));
  const Judgement j = PotInto(t, 0, "1", {.ball = "1", .pocket = "top_right"});
  EXPECT_FALSE(j.verdict.foul);
  EXPECT_FALSE(j.verdict.turn_passes);
  EXPECT_THAT(t.state.on, ElementsAre("10"));
}

}  // namespace
}  // namespace sportsim::games::testing
