// The forms of play of a round (round.h): the World Handicap System's arithmetic against its
// published formulas, Stableford's points table, and match play, Stableford, maximum score and
// net stroke play on rounds whose strokes the engine really plays on the built-in course.
#include <algorithm>
#include <cmath>
#include <numeric>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "sim/golf/round.h"

namespace sportsim::golf {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

const Course& Links() { return **BuiltinCourse("sportsim_links"); }

RoundSettings Settings(PlayFormat play, int first = 1, int last = 3) {
  RoundSettings s;
  s.first_hole = first;
  s.last_hole = last;
  s.players = {{"Ann", ""}, {"Bob", ""}};
  s.play = play;
  s.seed = 11;
  return s;
}

RoundStroke Launch(double speed, double angle, double spin) {
  RoundStroke k;
  k.launch = LaunchConditions{.ball_speed_mps = speed, .launch_angle_deg = angle,
                              .launch_direction_deg = 0, .spin_rpm = spin, .spin_axis_deg = 0};
  return k;
}

// A tiny chip: the ball moves a few metres at most (a wasted stroke).
RoundStroke Dribble() { return Launch(3.0, 20.0, 1000.0); }

// The reference player's stroke for the seat's ball.
RoundStroke Policy(const RoundState& st, int seat) {
  const RoundBall& b = st.players[seat].ball;
  const double d = (b.position_m.head<2>() - *Links().Hole(st.hole)->pin_m).norm();
  return ReferenceStroke(d, b.lie == Terrain::kGreen,
                         st.players[seat].strokes - Links().Hole(st.hole)->par);
}

RoundState Step(const RoundSettings& s, const RoundState& st, int seat, const RoundStroke& k,
                std::vector<RoundEvent>* events = nullptr) {
  absl::StatusOr<RoundStep> step = PlayStroke(Links(), s, st, seat, k);
  EXPECT_TRUE(step.ok()) << step.status();
  if (!step.ok()) return st;
  if (events) events->insert(events->end(), step->events.begin(), step->events.end());
  return step->state;
}

RoundState Choose(const RoundSettings& s, const RoundState& st, int seat, const std::string& c,
                  std::vector<RoundEvent>* events = nullptr) {
  absl::StatusOr<RoundStep> step = Decide(Links(), s, st, seat, {c, std::nullopt});
  EXPECT_TRUE(step.ok()) << c << ": " << step.status();
  if (!step.ok()) return st;
  if (events) events->insert(events->end(), step->events.begin(), step->events.end());
  return step->state;
}

// Plays on by the policy (relief: the last choice offered) until the round is over, or until
// `stop` says so. `waste[seat]` tiny chips open each of that seat's holes.
RoundState PlayOn(const RoundSettings& s, RoundState st, std::vector<int> waste = {0, 0},
                  const std::function<bool(const RoundState&)>& stop = {}) {
  for (int n = 0; n < 400 && !st.over && !(stop && stop(st)); ++n) {
    if (st.decision) {
      st = Choose(s, st, st.decision->seat, st.decision->choices.back());
      continue;
    }
    const int seat = ToPlay(Links(), s, st);
    const bool wasting = st.players[seat].strokes < waste[seat];
    st = Step(s, st, seat, wasting ? Dribble() : Policy(st, seat));
  }
  return st;
}

// Plays the others' strokes by the policy (relief: the last choice) until `seat` is to play.
RoundState PlayUntilTurn(const RoundSettings& s, RoundState st, int seat) {
  for (int n = 0; n < 100 && !st.over && ToPlay(Links(), s, st) != seat; ++n) {
    if (st.decision) {
      st = Choose(s, st, st.decision->seat, st.decision->choices.back());
      continue;
    }
    const int next = ToPlay(Links(), s, st);
    st = Step(s, st, next, Policy(st, next));
  }
  return st;
}

int Count(const std::vector<RoundEvent>& events, RoundEventKind kind) {
  return static_cast<int>(std::count_if(events.begin(), events.end(),
                                        [&](const RoundEvent& e) { return e.kind == kind; }));
}

// --- the arithmetic -----------------------------------------------------------------------------

// Rules of Handicapping 6.1: index x slope / 113 + (course rating - par), here scaled from 18
// holes to the course's three.
TEST(HandicapTest, CourseHandicapIsTheWorldHandicapSystemFormula) {
  const Course& c = Links();
  const CourseRating white = c.RatingOf("white");
  EXPECT_EQ(white.slope, 128.0);
  EXPECT_EQ(c.Par(), 12);
  EXPECT_NEAR(CourseHandicap(c, "white", 18.0), 18.0 * (3.0 / 18.0) * 128.0 / 113.0 + 0.6, 1e-12);
  EXPECT_NEAR(CourseHandicap(c, "", 18.0), CourseHandicap(c, "white", 18.0), 0.0);  // first tee
  EXPECT_NEAR(CourseHandicap(c, "red", 0.0), 12.1 - 12.0, 1e-12);
  // A plus handicap is a negative index: the course gives strokes back.
  EXPECT_LT(CourseHandicap(c, "white", -6.0), 0.0);
  // An unrated tee set rates as standard: the index scaled to the holes.
  Course unrated = c;
  unrated.ratings.clear();
  EXPECT_NEAR(CourseHandicap(unrated, "white", 12.0), 2.0, 1e-12);
}

// Appendix E: strokes by stroke index, one a hole round and round; plus handicaps give back
// from the highest index. The strokes over the holes always sum to the handicap.
TEST(HandicapTest, StrokesGoByStrokeIndexAndSumToTheHandicap) {
  EXPECT_EQ(StrokesReceived(20, 1, 18), 2);
  EXPECT_EQ(StrokesReceived(20, 2, 18), 2);
  EXPECT_EQ(StrokesReceived(20, 3, 18), 1);
  EXPECT_EQ(StrokesReceived(20, 18, 18), 1);
  EXPECT_EQ(StrokesReceived(5, 5, 18), 1);
  EXPECT_EQ(StrokesReceived(5, 6, 18), 0);
  EXPECT_EQ(StrokesReceived(-2, 18, 18), -1);
  EXPECT_EQ(StrokesReceived(-2, 17, 18), -1);
  EXPECT_EQ(StrokesReceived(-2, 16, 18), 0);
  for (int holes : {3, 9, 18}) {
    for (int ph = -10; ph <= 60; ++ph) {
      int sum = 0;
      for (int si = 1; si <= holes; ++si) sum += StrokesReceived(ph, si, holes);
      EXPECT_EQ(sum, ph) << holes << " holes, handicap " << ph;
    }
  }
}

// Rule 21.1b's table: 0 for two or more over the fixed score, 1 for one over, 2 at it, 3 to 6
// for one to four under; a stroke received raises the fixed score by one.
TEST(StablefordTest, PointsFollowRule21_1b) {
  const int par = 4;
  std::vector<int> points;
  for (int gross = 8; gross >= 0; --gross) points.push_back(StablefordPoints(gross, par, 0));
  EXPECT_THAT(points, ElementsAre(0, 0, 0, 1, 2, 3, 4, 5, 6));
  EXPECT_EQ(StablefordPoints(5, par, 1), 2);  // a net par
  EXPECT_EQ(StablefordPoints(4, par, -1), 1);  // a plus handicap's gross par is a net bogey
  EXPECT_EQ(MaxScoreOf({MaxScore::Kind::kNetDoubleBogey, 0}, 4, 1), 7);
  EXPECT_EQ(MaxScoreOf({MaxScore::Kind::kParPlus, 3}, 5, 2), 8);
  EXPECT_EQ(MaxScoreOf({MaxScore::Kind::kFixed, 9}, 3, 0), 9);
  EXPECT_EQ(MaxScoreOf({}, 3, 0), 0);
}

TEST(RoundFormatsTest, SettingsOfTheFormatsAreValidated) {
  auto error = [](const RoundSettings& s) { return std::string(ValidateRoundSettings(Links(), s).message()); };
  RoundSettings three = Settings(PlayFormat::kMatch);
  three.players.push_back({"Cat", ""});
  EXPECT_THAT(error(three), HasSubstr("match play is between two players"));
  RoundSettings index = Settings(PlayFormat::kStroke);
  index.players[1].handicap_index = 60;
  EXPECT_THAT(error(index), HasSubstr("players[1].handicap_index"));
  RoundSettings max = Settings(PlayFormat::kStableford);
  ASSERT_TRUE(SetRoundVariant("max_score", "par+3", &max).ok());
  EXPECT_THAT(error(max), HasSubstr("max_score"));
  RoundSettings s;
  EXPECT_FALSE(SetRoundVariant("max_score", "par+0", &s).ok());
  EXPECT_FALSE(SetRoundVariant("max_score", "2", &s).ok());
  EXPECT_FALSE(SetRoundVariant("allowance", "120", &s).ok());
  EXPECT_TRUE(SetRoundVariant("max_score", "net_double_bogey", &s).ok());
  EXPECT_EQ(s.max_score.kind, MaxScore::Kind::kNetDoubleBogey);
  EXPECT_TRUE(SetRoundVariant("allowance", "85", &s).ok());
  EXPECT_EQ(*s.allowance_pct, 85.0);
  EXPECT_FALSE(PlayFormatFromName("skins").ok());
}

// Playing handicaps: 95 % of the course handicap in stroke play; in match play 100 %, the
// lower player off scratch and the other the difference (Appendix C).
TEST(RoundFormatsTest, PlayingHandicapsFollowTheFormatsAllowance) {
  RoundSettings stroke = Settings(PlayFormat::kStroke);
  stroke.players[0].handicap_index = 10.0;
  stroke.players[1].handicap_index = 36.0;
  const RoundState a = *StartRound(Links(), stroke);
  EXPECT_EQ(a.players[0].playing_handicap,
            static_cast<int>(std::floor(0.95 * CourseHandicap(Links(), "", 10.0) + 0.5)));
  EXPECT_EQ(a.players[1].playing_handicap,
            static_cast<int>(std::floor(0.95 * CourseHandicap(Links(), "", 36.0) + 0.5)));
  for (const RoundPlayer& p : a.players) {
    EXPECT_EQ(std::accumulate(p.received.begin(), p.received.end(), 0), p.playing_handicap);
  }
  RoundSettings match = stroke;
  match.play = PlayFormat::kMatch;
  const RoundState m = *StartRound(Links(), match);
  const int diff = static_cast<int>(std::floor(CourseHandicap(Links(), "", 36.0) + 0.5)) -
                   static_cast<int>(std::floor(CourseHandicap(Links(), "", 10.0) + 0.5));
  EXPECT_EQ(m.players[0].playing_handicap, 0);
  EXPECT_EQ(m.players[1].playing_handicap, diff);
  // Hole 3 is stroke index 1: the first stroke received falls there.
  EXPECT_GE(m.players[1].received[2], m.players[1].received[0]);
  EXPECT_THAT(m.hole_winners, ElementsAre(-2, -2, -2));
}

// --- match play on the engine -----------------------------------------------------------------

// Conceding two holes loses a three-hole match "2 and 1" (Rule 3.2a(3)): it ends at once, with
// the third hole unplayed. After the first the winner is one up, and the honour is theirs.
TEST(MatchPlayTest, ConcededHolesDecideTheMatchEarly) {
  const RoundSettings s = Settings(PlayFormat::kMatch);
  RoundState st = *StartRound(Links(), s);
  std::vector<RoundEvent> events;
  st = Step(s, st, 0, Policy(st, 0), &events);  // Ann drives, then concedes the hole
  st = Choose(s, st, 0, "concede_hole", &events);
  EXPECT_EQ(st.hole, 2);
  EXPECT_THAT(st.hole_winners, ElementsAre(1, -2, -2));
  EXPECT_EQ(MatchStatusText(s, st), "Bob 1 up with 2 to play");
  EXPECT_THAT(st.tee_order, ElementsAre(1, 0));  // the hole's winner has the honour (6.4a)
  EXPECT_EQ(ToPlay(Links(), s, st), 1);
  EXPECT_TRUE(st.players[0].no_score[0]);
  EXPECT_EQ(Count(events, RoundEventKind::kConceded), 1);
  st = Choose(s, st, 0, "concede_hole", &events);
  EXPECT_TRUE(st.over);
  EXPECT_EQ(st.result, "2 and 1");
  EXPECT_THAT(st.winners, ElementsAre(1));
  EXPECT_EQ(MatchStatusText(s, st), "Bob won 2 and 1");
  EXPECT_EQ(Count(events, RoundEventKind::kRoundEnd), 1);
  // Final once made: nothing more may be played or conceded.
  EXPECT_FALSE(PlayStroke(Links(), s, st, 1, Policy(st, 1)).ok());
  EXPECT_FALSE(Decide(Links(), s, st, 1, {"concede_hole", std::nullopt}).ok());
}

// Dormie: as many holes up as are left.
TEST(MatchPlayTest, DormieIsAsManyUpAsAreLeft) {
  const RoundSettings s = Settings(PlayFormat::kMatch, 2, 3);
  RoundState st = *StartRound(Links(), s);
  st = Choose(s, st, 1, "concede_hole");
  const MatchStatus m = MatchStatusOf(s, st);
  EXPECT_EQ(m.leader, 0);
  EXPECT_EQ(m.up, 1);
  EXPECT_EQ(m.to_play, 1);
  EXPECT_TRUE(m.dormie);
  EXPECT_EQ(MatchStatusText(s, st), "Ann 1 up with 1 to play (dormie)");
}

// A conceded putt (Rule 3.2b(1)): the opponent's ball is holed with their next stroke, counted;
// a player who can then no longer halve the hole is picked up, and the hole goes by the
// strokes: the hole's result is the fewer strokes.
TEST(MatchPlayTest, AConcededPuttHolesTheBallAndDecidesTheHole) {
  const RoundSettings s = Settings(PlayFormat::kMatch, 2, 3);
  RoundState st = *StartRound(Links(), s);
  // Both play on until the one to play is on the green with the other's ball still in play.
  st = PlayOn(s, st, {0, 0}, [&](const RoundState& x) {
    const int n = ToPlay(Links(), s, x);
    return x.hole != 2 || (n >= 0 && x.players[n].ball.lie == Terrain::kGreen &&
                           x.players[n].strokes > 0 && !x.players[1 - n].ball.holed);
  });
  ASSERT_EQ(st.hole, 2) << "a putt on hole 2's green should come";
  const int next = ToPlay(Links(), s, st);
  const int other = 1 - next;
  // The player not to play concedes the next stroke of the one who is.
  std::vector<RoundEvent> events;
  const int before = st.players[next].strokes;
  const int other_strokes = st.players[other].strokes;
  st = Choose(s, st, other, "concede_stroke", &events);
  ASSERT_GE(Count(events, RoundEventKind::kConceded), 1);
  EXPECT_EQ(Count(events, RoundEventKind::kHoled), 1);
  const int score = before + 1;
  if (other_strokes >= score) {
    // Lost: picked up, the hole over, won by the conceded player.
    EXPECT_EQ(Count(events, RoundEventKind::kPickedUp), 1);
    EXPECT_EQ(st.hole, 3);
    EXPECT_EQ(st.hole_winners[0], next);
    EXPECT_EQ(st.players[next].scores[0], score);
  } else {
    // Still alive: the other plays on, the conceded ball holed with `score`.
    EXPECT_TRUE(st.players[next].ball.holed);
    EXPECT_EQ(st.players[next].strokes, score);
    EXPECT_EQ(ToPlay(Links(), s, st), other);
    st = PlayOn(s, st, {0, 0}, [](const RoundState& x) { return x.hole != 2; });
    const int o = st.players[other].scores[0];
    const int w = st.hole_winners[0];
    EXPECT_EQ(w, o < score ? other : (o == score ? -1 : next));
  }
}

// A whole three-hole match by the policy, with handicaps: every hole's result is the fewer net
// strokes, and the result is the holes' tally.
TEST(MatchPlayTest, AWholeMatchIsWonByTheHolesNetTally) {
  RoundSettings s = Settings(PlayFormat::kMatch);
  s.players[0].handicap_index = 2.0;
  s.players[1].handicap_index = 30.0;
  RoundState st = PlayOn(s, *StartRound(Links(), s), {0, 1});
  ASSERT_TRUE(st.over);
  int won[2] = {0, 0}, played = 0;
  for (size_t h = 0; h < st.hole_winners.size(); ++h) {
    const int w = st.hole_winners[h];
    if (w == -2) continue;
    ++played;
    auto net = [&](int seat) {
      const RoundPlayer& p = st.players[seat];
      return p.no_score[h] ? 1000 : p.scores[h] - p.received[h];
    };
    EXPECT_EQ(w, net(0) < net(1) ? 0 : (net(1) < net(0) ? 1 : -1)) << "hole " << h + 1;
    if (w >= 0) ++won[w];
  }
  const int left = 3 - played;
  if (won[0] == won[1]) {
    EXPECT_EQ(st.result, "halved");
    EXPECT_THAT(st.winners, ElementsAre(0, 1));
  } else {
    const int leader = won[0] > won[1] ? 0 : 1, up = std::abs(won[0] - won[1]);
    EXPECT_THAT(st.winners, ElementsAre(leader));
    EXPECT_EQ(st.result, left == 0 ? absl::StrCat(up, " up") : absl::StrCat(up, " and ", left));
    EXPECT_GT(up, left);
  }
}

// --- Stableford and maximum score ---------------------------------------------------------------

// With no point left to score (Rule 21.1c) the ball is picked up at once; a ball picked up by
// choice scores nothing either; the other player's points are the table's.
TEST(StablefordTest, NoPointLeftPicksUpAndAPickedUpHoleScoresNothing) {
  const RoundSettings s = Settings(PlayFormat::kStableford, 2, 3);  // hole 2 is a par 3
  RoundState st = *StartRound(Links(), s);
  std::vector<RoundEvent> events;
  // Ann dribbles: after three strokes a point is still possible (a 4 is one over), after four
  // it is not.
  for (int k = 0; k < 3; ++k) {
    st = PlayUntilTurn(s, st, 0);
    st = Step(s, st, 0, Dribble(), &events);
    EXPECT_FALSE(st.players[0].ball.picked_up) << k;
  }
  st = PlayUntilTurn(s, st, 0);
  st = Step(s, st, 0, Dribble(), &events);
  ASSERT_EQ(Count(events, RoundEventKind::kPickedUp), 1);
  const RoundEvent& up = *std::find_if(events.begin(), events.end(),
                                       [](const RoundEvent& e) { return e.kind == RoundEventKind::kPickedUp; });
  EXPECT_EQ(up.reason, "stableford");
  EXPECT_EQ(up.strokes, 4);
  st = PlayOn(s, st, {0, 0}, [](const RoundState& x) { return x.hole != 2; });
  EXPECT_TRUE(st.players[0].no_score[0]);
  EXPECT_EQ(st.players[0].points[0], 0);
  const RoundPlayer& bob = st.players[1];
  EXPECT_EQ(bob.points[0], StablefordPoints(bob.scores[0], 3, 0));
  // Hole 3: Bob has the honour and picks up by choice after his drive, on his next turn (any
  // time would do).
  ASSERT_EQ(ToPlay(Links(), s, st), 1);
  st = Step(s, st, 1, Policy(st, 1));
  st = PlayUntilTurn(s, st, 1);
  ASSERT_EQ(ToPlay(Links(), s, st), 1);
  st = Choose(s, st, 1, "pick_up");
  EXPECT_TRUE(st.players[1].ball.picked_up);
  st = PlayOn(s, st);
  ASSERT_TRUE(st.over);
  EXPECT_TRUE(st.players[1].no_score[1]);
  EXPECT_EQ(st.players[1].points[1], 0);
  const int ann = st.players[0].Points(), bobs = st.players[1].Points();
  EXPECT_THAT(st.winners, ElementsAre(ann > bobs ? 0 : 1)) << ann << " vs " << bobs;
}

// Stroke play with a maximum score (Rule 21.2): the ball comes up at the maximum, which is the
// hole's score; without one, picking up is refused (3.3c).
TEST(StrokePlayTest, AMaximumScoreEndsTheHoleThere) {
  RoundSettings s = Settings(PlayFormat::kStroke, 2, 2);
  s.players.resize(1);
  RoundState plain = *StartRound(Links(), s);
  plain = Step(s, plain, 0, Dribble());
  absl::StatusOr<RoundStep> refused = Decide(Links(), s, plain, 0, {"pick_up", std::nullopt});
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(refused.status().message(), HasSubstr("3.3c"));
  ASSERT_TRUE(SetRoundVariant("max_score", "par+2", &s).ok());
  RoundState st = *StartRound(Links(), s);
  for (int k = 0; k < 5; ++k) st = Step(s, st, 0, Dribble());
  EXPECT_TRUE(st.over);
  EXPECT_THAT(st.players[0].scores, ElementsAre(5));
  EXPECT_FALSE(st.players[0].no_score[0]);
}

// Net stroke play: the higher handicap's strokes turn a lost gross round into a net win.
TEST(StrokePlayTest, NetScoresChangeTheWinner) {
  RoundSettings s = Settings(PlayFormat::kStroke);
  RoundState gross = PlayOn(s, *StartRound(Links(), s), {0, 1});
  ASSERT_TRUE(gross.over);
  ASSERT_GT(gross.players[1].Total(), gross.players[0].Total());
  EXPECT_THAT(gross.winners, ElementsAre(0));
  s.players[0].handicap_index = 0.0;
  s.players[1].handicap_index = 40.0;
  RoundState net = PlayOn(s, *StartRound(Links(), s), {0, 1});
  ASSERT_TRUE(net.over);
  // The same strokes (handicaps change no stroke), the other winner.
  EXPECT_EQ(net.players[0].scores, gross.players[0].scores);
  EXPECT_EQ(net.players[1].scores, gross.players[1].scores);
  EXPECT_LT(net.players[1].NetTotal(), net.players[0].NetTotal());
  EXPECT_THAT(net.winners, ElementsAre(1));
}

}  // namespace
}  // namespace sportsim::golf
