// The referee of a round (round.h): scenarios on the built-in course whose strokes the engine
// really plays (out of bounds, red and yellow penalty areas, an unplayable ball in a bunker, a
// holed chip, the order of play), the relief areas each option drops in, the refusals.
#include "sim/golf/round.h"

#include "sim/swing/swing_simulation.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace sportsim::golf {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kR = 0.04267 / 2;

const Course& Links() { return **BuiltinCourse("sportsim_links"); }

RoundSettings Settings(int first, int last, int players = 2) {
  RoundSettings s;
  s.first_hole = first;
  s.last_hole = last;
  const char* names[] = {"Ann", "Bob", "Cat", "Dan"};
  for (int i = 0; i < players; ++i) s.players.push_back({names[i], ""});
  s.seed = 7;
  return s;
}

RoundStroke Launch(double speed, double angle, double spin, std::optional<double> aim) {
  RoundStroke k;
  k.kind = RoundStroke::Kind::kLaunch;
  k.launch = LaunchConditions{.ball_speed_mps = speed, .launch_angle_deg = angle,
                              .launch_direction_deg = 0, .spin_rpm = spin, .spin_axis_deg = 0};
  k.aim_deg = aim;
  return k;
}

RoundStroke Putt(double speed, double aim) {
  RoundStroke k;
  k.kind = RoundStroke::Kind::kPutt;
  k.speed_mps = speed;
  k.aim_deg = aim;
  return k;
}

Vector2d Pin(int hole) { return *Links().Hole(hole)->pin_m; }
Vector2d Tee(int hole) { return Links().Hole(hole)->tees.front().position_m; }
double ToPin(int hole, const Vector3d& p) { return (p.head<2>() - Pin(hole)).norm(); }
double Heading(Vector2d from, Vector2d to) {
  return std::atan2(to.y() - from.y(), to.x() - from.x()) / kDeg;
}

bool Has(const std::vector<RoundEvent>& events, RoundEventKind kind) {
  return std::any_of(events.begin(), events.end(), [&](const RoundEvent& e) { return e.kind == kind; });
}
const RoundEvent& First(const std::vector<RoundEvent>& events, RoundEventKind kind) {
  return *std::find_if(events.begin(), events.end(), [&](const RoundEvent& e) { return e.kind == kind; });
}

// Perpendicular distance of p from the line through a and b.
double FromLine(const Vector2d& p, const Vector2d& a, const Vector2d& b) {
  const Vector2d u = (b - a).normalized();
  const Vector2d d = p - a;
  return std::abs(u.x() * d.y() - u.y() * d.x());
}

class RoundTest : public ::testing::Test {
 protected:
  RoundStep Play(const RoundSettings& s, const RoundState& st, int seat, const RoundStroke& k,
                 CourseShotResult* shot = nullptr) {
    absl::StatusOr<RoundStep> step = PlayStroke(Links(), s, st, seat, k, shot);
    EXPECT_TRUE(step.ok()) << step.status();
    return step.ok() ? *step : RoundStep{st, {}};
  }
  RoundStep Choose(const RoundSettings& s, const RoundState& st, int seat, std::string choice,
                   std::optional<double> back_m = std::nullopt) {
    absl::StatusOr<RoundStep> step = Decide(Links(), s, st, seat, RoundChoice{choice, back_m});
    EXPECT_TRUE(step.ok()) << choice << ": " << step.status();
    return step.ok() ? *step : RoundStep{st, {}};
  }
  // Putts until holed: each time the first of a fan of candidates (speeds and aims around the
  // pin) that holes, else the one that ends nearest.
  RoundState HoleOut(const RoundSettings& s, RoundState st, int seat, std::vector<RoundEvent>* events) {
    for (int stroke = 0; stroke < 6 && !st.players[seat].ball.holed; ++stroke) {
      const Vector3d b = st.players[seat].ball.position_m;
      const double d = ToPin(st.hole, b);
      const double aim0 = Heading(b.head<2>(), Pin(st.hole));
      std::optional<RoundStep> best;
      double best_d = 1e9;
      for (double f : {1.0, 1.05, 0.95, 1.1, 0.9, 1.2, 0.8}) {
        for (double da : {0.0, 1.0, -1.0, 2.0, -2.0, 4.0, -4.0}) {
          // Struck, a putt rolls at 5/7 of its speed; a stimp-10 green takes about 0.6 m/s^2.
          const double speed = std::min(12.0, 1.4 * f * std::sqrt(1.2 * (d + 0.3)));
          absl::StatusOr<RoundStep> step = PlayStroke(Links(), s, st, seat, Putt(speed, aim0 + da));
          if (!step.ok()) continue;
          const RoundPlayer& p = step->state.players[seat];
          const double left = p.ball.holed ? 0.0 : ToPin(st.hole, p.ball.position_m);
          if (left < best_d) {
            best_d = left;
            best = *step;
          }
          if (p.ball.holed) break;
        }
        if (best_d == 0.0) break;
      }
      if (!best) break;
      events->insert(events->end(), best->events.begin(), best->events.end());
      st = best->state;
      // Rule 13.1b: every other ball on the green is marked and lifted while one plays.
      const int next = ToPlay(Links(), s, st);
      for (size_t i = 0; i < st.players.size(); ++i) {
        const RoundBall& b = st.players[i].ball;
        const bool on_green = !b.holed && b.lie == Terrain::kGreen && best_d > 0.0;
        EXPECT_EQ(b.marked, on_green && static_cast<int>(i) != next) << "seat " << i;
      }
      if (best_d == 0.0) break;
    }
    return st;
  }
};

TEST_F(RoundTest, TheRoundStartsOnTheTeesInSeatOrder) {
  RoundSettings s = Settings(1, 3, 3);
  s.players[1].tee = "red";
  absl::StatusOr<RoundState> st = StartRound(Links(), s);
  ASSERT_TRUE(st.ok()) << st.status();
  EXPECT_EQ(st->hole, 1);
  EXPECT_THAT(st->tee_order, ElementsAre(0, 1, 2));
  EXPECT_EQ(st->players[0].ball.position_m.head<2>(), Tee(1));
  EXPECT_EQ(st->players[1].ball.position_m.head<2>(), Links().Hole(1)->tees[1].position_m);
  EXPECT_EQ(st->players[0].ball.lie, Terrain::kTee);
  EXPECT_EQ(st->players[0].scores.size(), 3u);
  EXPECT_EQ(ToPlay(Links(), s, *st), 0);
  EXPECT_THAT(MayPlay(Links(), s, *st), ElementsAre(0));
  SetRoundVariant("order", "ready", &s);
  EXPECT_THAT(MayPlay(Links(), s, *st), ElementsAre(0, 1, 2));
}

TEST_F(RoundTest, SettingsAreValidatedNamingTheField) {
  auto error = [](RoundSettings s) { return std::string(ValidateRoundSettings(Links(), s).message()); };
  EXPECT_THAT(error(Settings(0, 1)), HasSubstr("holes"));
  EXPECT_THAT(error(Settings(2, 4)), HasSubstr("holes"));
  EXPECT_THAT(error(Settings(3, 2)), HasSubstr("holes"));
  EXPECT_THAT(error(Settings(1, 1, 0)), HasSubstr("players"));
  RoundSettings nine = Settings(1, 1, 1);
  nine.players.resize(9, nine.players[0]);
  EXPECT_THAT(error(nine), HasSubstr("players"));
  RoundSettings tee = Settings(1, 1);
  tee.players[1].tee = "blue";
  EXPECT_THAT(error(tee), HasSubstr("players[1].tee"));
  RoundSettings name = Settings(1, 1);
  name.players[0].name = "";
  EXPECT_THAT(error(name), HasSubstr("players[0].name"));
  RoundSettings noise = Settings(1, 1);
  noise.noise = 6;
  EXPECT_THAT(error(noise), HasSubstr("noise"));
  EXPECT_TRUE(ValidateRoundSettings(Links(), Settings(1, 3, 4)).ok());
  RoundSettings s;
  EXPECT_FALSE(SetRoundVariant("order", "random", &s).ok());
  EXPECT_FALSE(SetRoundVariant("mulligans", "yes", &s).ok());
}

// Rule 18.2b: a drive out of bounds right on the par 5 costs a stroke and is replayed from the
// tee; the player then plays after the others have teed off (Rule 6.4c), farthest first.
TEST_F(RoundTest, ADriveOutOfBoundsIsStrokeAndDistance) {
  const RoundSettings s = Settings(3, 3);
  RoundState st = *StartRound(Links(), s);
  CourseShotResult shot;
  RoundStep out = Play(s, st, 0, Launch(70, 11, 2700, 160.0), &shot);
  EXPECT_TRUE(shot.ground.out_of_bounds);
  ASSERT_TRUE(Has(out.events, RoundEventKind::kPenalty));
  const RoundEvent& penalty = First(out.events, RoundEventKind::kPenalty);
  EXPECT_EQ(penalty.reason, "out_of_bounds");
  EXPECT_EQ(penalty.rule, "18.2b");
  EXPECT_EQ(penalty.penalty_strokes, 1);
  const RoundPlayer& ann = out.state.players[0];
  EXPECT_EQ(ann.strokes, 2);
  EXPECT_EQ(ann.penalties, 1);
  EXPECT_EQ(ann.ball.position_m.head<2>(), Tee(3)) << "teed again where it was played from";
  EXPECT_EQ(ann.ball.lie, Terrain::kTee);
  EXPECT_FALSE(out.state.decision);
  EXPECT_EQ(ToPlay(Links(), s, out.state), 1) << "Bob tees off before Ann plays her third";
  // Bob drives down the fairway; Ann, on the tee, is now farthest.
  RoundStep bob = Play(s, out.state, 1, Launch(60, 12, 3000, std::nullopt));
  EXPECT_LT(ToPin(3, bob.state.players[1].ball.position_m), ToPin(3, bob.state.players[0].ball.position_m));
  EXPECT_EQ(ToPlay(Links(), s, bob.state), 0);
  absl::StatusOr<RoundStep> early = PlayStroke(Links(), s, bob.state, 1, Launch(50, 14, 4000, std::nullopt));
  EXPECT_EQ(early.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(early.status().message(), HasSubstr("not your turn"));
  EXPECT_THAT(early.status().message(), HasSubstr("Ann"));
}

// Rule 17.1d: a drive into the red creek on the par 5 offers stroke and distance,
// back-on-the-line and lateral relief; each puts the ball where the rule says.
TEST_F(RoundTest, ARedPenaltyAreaOffersItsOptionsAndEachPutsTheBallWhereTheRuleSays) {
  const RoundSettings s = Settings(3, 3);
  RoundState st = *StartRound(Links(), s);
  CourseShotResult shot;
  RoundStep in = Play(s, st, 0, Launch(60, 12, 3000, 194.0), &shot);
  EXPECT_EQ(in.state.players[0].ball.lie, Terrain::kLateralWaterHazard);
  ASSERT_TRUE(in.state.decision);
  const RoundDecision& d = *in.state.decision;
  EXPECT_EQ(d.seat, 0);
  EXPECT_EQ(d.reason, "penalty_area");
  EXPECT_THAT(d.choices, ElementsAre("stroke_and_distance", "back_on_the_line", "lateral"));
  EXPECT_EQ(First(in.events, RoundEventKind::kDecision).rule, "17.1d");
  // The crossing: on the penalty area's edge (the ball touches it there), on the ball's way.
  const Vector2d x = d.reference_m.head<2>();
  EXPECT_NE(Links().LieAt(x.x(), x.y(), kR), Terrain::kLateralWaterHazard);
  EXPECT_NEAR(Links().DistanceToEdge(x.x(), x.y(), Terrain::kLateralWaterHazard), kR, 1e-3);
  EXPECT_EQ(in.state.players[0].strokes, 1) << "the penalty is counted with the choice";
  EXPECT_EQ(ToPlay(Links(), s, in.state), 0);

  // Nothing else happens until Ann decides.
  for (int seat : {0, 1}) {
    absl::StatusOr<RoundStep> stroke = PlayStroke(Links(), s, in.state, seat, Launch(50, 14, 4000, std::nullopt));
    EXPECT_EQ(stroke.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_THAT(stroke.status().message(), HasSubstr("decision is pending"));
  }
  EXPECT_EQ(Decide(Links(), s, in.state, 1, {"lateral", {}}).status().code(),
            absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(Decide(Links(), s, in.state, 0, {"drop_anywhere", {}}).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(Decide(Links(), s, in.state, 0, {"lateral", 5.0}).status().code(),
            absl::StatusCode::kInvalidArgument);

  const double x_to_pin = ToPin(3, d.reference_m);
  {  // 17.1d(1): back to the tee.
    RoundStep r = Choose(s, in.state, 0, "stroke_and_distance");
    EXPECT_EQ(r.state.players[0].ball.position_m.head<2>(), Tee(3));
    EXPECT_EQ(r.state.players[0].strokes, 2);
    EXPECT_EQ(First(r.events, RoundEventKind::kPenalty).rule, "17.1d(1)");
    EXPECT_FALSE(r.state.decision);
  }
  {  // 17.1d(2): dropped within a club-length of a point on the line from the pin through the
     // crossing, behind it, not nearer the hole than that point, outside the penalty area.
    RoundStep r = Choose(s, in.state, 0, "back_on_the_line");
    const Vector3d b = r.state.players[0].ball.position_m;
    EXPECT_LE(FromLine(b.head<2>(), Pin(3), x), kClubLengthM + 1e-9);
    EXPECT_GE(ToPin(3, b), x_to_pin - 1e-9);
    EXPECT_FALSE(IsPenaltyArea(r.state.players[0].ball.lie));
    EXPECT_EQ(r.state.players[0].strokes, 2);
    EXPECT_EQ(First(r.events, RoundEventKind::kPenalty).rule, "17.1d(2)");
    EXPECT_TRUE(Has(r.events, RoundEventKind::kDrop));
    EXPECT_NEAR(b.z(), Links().terrain.HeightAt(b.x(), b.y()), 1e-6);
  }
  // The line runs back along the creek: 20 m back is still in it, refused naming back_m; 100 m
  // back is past its end.
  absl::StatusOr<RoundStep> wet = Decide(Links(), s, in.state, 0, {"back_on_the_line", 20.0});
  EXPECT_EQ(wet.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(wet.status().message(), HasSubstr("back_m"));
  {
    RoundStep r = Choose(s, in.state, 0, "back_on_the_line", 100.0);
    const Vector2d ref = x + 100.0 * (x - Pin(3)).normalized();
    const Vector3d b = r.state.players[0].ball.position_m;
    EXPECT_LE((b.head<2>() - ref).norm(), kClubLengthM + 1e-9);
    EXPECT_GE(ToPin(3, b), (ref - Pin(3)).norm() - 1e-9);
  }
  {  // 17.1d(3): within two club-lengths of the crossing, not nearer the hole, outside it.
    RoundStep r = Choose(s, in.state, 0, "lateral");
    const Vector3d b = r.state.players[0].ball.position_m;
    EXPECT_LE((b.head<2>() - x).norm(), 2 * kClubLengthM + 1e-9);
    EXPECT_GE(ToPin(3, b), x_to_pin - 1e-9);
    EXPECT_FALSE(IsPenaltyArea(r.state.players[0].ball.lie));
    EXPECT_EQ(First(r.events, RoundEventKind::kPenalty).rule, "17.1d(3)");
    EXPECT_EQ(ToPlay(Links(), s, r.state), 1) << "Bob has not teed off";
    // A drop is a draw from the seed: the same again, another with another seed.
    RoundStep again = Choose(s, in.state, 0, "lateral");
    EXPECT_EQ(again.state.players[0].ball.position_m, b);
    RoundSettings other = s;
    other.seed = 8;
    RoundStep reseeded = Choose(other, in.state, 0, "lateral");
    EXPECT_NE(reseeded.state.players[0].ball.position_m, b);
  }
  // The ball in the creek cannot be declared unplayable (Rule 19.1).
  EXPECT_EQ(Decide(Links(), s, in.state, 0, {"unplayable", {}}).status().code(),
            absl::StatusCode::kFailedPrecondition);
}

// A yellow penalty area (the pond on the par 3) has no lateral relief.
TEST_F(RoundTest, AYellowPenaltyAreaOffersNoLateralRelief) {
  const RoundSettings s = Settings(2, 2, 1);
  RoundState st = *StartRound(Links(), s);
  RoundStep in = Play(s, st, 0, Launch(30, 20, 5000, 88.0));
  ASSERT_TRUE(in.state.decision);
  EXPECT_EQ(in.state.decision->area, Terrain::kWaterHazard);
  EXPECT_THAT(in.state.decision->choices, ElementsAre("stroke_and_distance", "back_on_the_line"));
  EXPECT_EQ(Decide(Links(), s, in.state, 0, {"lateral", {}}).status().code(),
            absl::StatusCode::kInvalidArgument);
  const Vector2d x = in.state.decision->reference_m.head<2>();
  RoundStep r = Choose(s, in.state, 0, "back_on_the_line");
  const Vector3d b = r.state.players[0].ball.position_m;
  EXPECT_LE(FromLine(b.head<2>(), Pin(2), x), kClubLengthM + 1e-9);
  EXPECT_GE(ToPin(2, b), ToPin(2, in.state.decision->reference_m) - 1e-9);
  EXPECT_FALSE(IsPenaltyArea(r.state.players[0].ball.lie));
  EXPECT_LT(b.y(), x.y()) << "behind the pond, on the tee's side";
}

// Rule 19.3: an unplayable ball in a bunker: three options in the bunker for a stroke, or
// back-on-the-line outside it for two.
TEST_F(RoundTest, AnUnplayableBallInABunker) {
  const RoundSettings s = Settings(1, 1, 1);
  RoundState st = *StartRound(Links(), s);
  EXPECT_EQ(Decide(Links(), s, st, 0, {"unplayable", {}}).status().code(),
            absl::StatusCode::kFailedPrecondition)
      << "no ball in play before the tee shot";
  RoundStep in = Play(s, st, 0, Launch(62, 12, 3000, -5.0));
  ASSERT_EQ(in.state.players[0].ball.lie, Terrain::kBunker);
  EXPECT_EQ(Decide(Links(), s, in.state, 0, {"lateral", {}}).status().code(),
            absl::StatusCode::kFailedPrecondition)
      << "no decision is pending";
  RoundStep u = Choose(s, in.state, 0, "unplayable");
  ASSERT_TRUE(u.state.decision);
  EXPECT_EQ(u.state.decision->reason, "unplayable");
  EXPECT_THAT(u.state.decision->choices,
              ElementsAre("stroke_and_distance", "back_on_the_line", "lateral",
                          "back_on_the_line_outside_bunker"));
  const Vector3d spot = in.state.players[0].ball.position_m;
  {
    RoundStep r = Choose(s, u.state, 0, "lateral");
    const RoundBall& b = r.state.players[0].ball;
    EXPECT_EQ(b.lie, Terrain::kBunker);
    EXPECT_LE((b.position_m - spot).head<2>().norm(), 2 * kClubLengthM + 1e-9);
    EXPECT_GE(ToPin(1, b.position_m), ToPin(1, spot) - 1e-9);
    EXPECT_EQ(r.state.players[0].strokes, 2);
    EXPECT_EQ(First(r.events, RoundEventKind::kPenalty).rule, "19.3a");
  }
  {
    RoundStep r = Choose(s, u.state, 0, "back_on_the_line");
    EXPECT_EQ(r.state.players[0].ball.lie, Terrain::kBunker);
    EXPECT_GE(ToPin(1, r.state.players[0].ball.position_m), ToPin(1, spot) - 1e-9);
  }
  {
    RoundStep r = Choose(s, u.state, 0, "back_on_the_line_outside_bunker");
    const RoundBall& b = r.state.players[0].ball;
    EXPECT_NE(b.lie, Terrain::kBunker);
    EXPECT_LE(FromLine(b.position_m.head<2>(), Pin(1), spot.head<2>()), kClubLengthM + 1e-9);
    EXPECT_GT(ToPin(1, b.position_m), ToPin(1, spot));
    EXPECT_EQ(r.state.players[0].strokes, 3) << "two penalty strokes";
    EXPECT_EQ(First(r.events, RoundEventKind::kPenalty).penalty_strokes, 2);
    EXPECT_EQ(First(r.events, RoundEventKind::kPenalty).rule, "19.3b");
  }
  {
    RoundStep r = Choose(s, u.state, 0, "stroke_and_distance");
    EXPECT_EQ(r.state.players[0].ball.position_m.head<2>(), Tee(1));
  }
}

// A chip from the fairway 30 m short of the par 4's pin that finds the hole (Rule 13.2c): the
// hole and the one-hole round end, and the score is the strokes played.
TEST_F(RoundTest, AHoledChipEndsTheHoleAndTheRound) {
  const RoundSettings s = Settings(1, 1, 1);
  RoundState st = *StartRound(Links(), s);
  // Where a tee shot left it (the referee's state is data: a ball where a stroke left it).
  RoundState lying = st;
  const Vector2d pin = Pin(1);
  const Vector2d spot = pin + 30.0 * (Tee(1) - pin).normalized();
  lying.players[0].strokes = 1;
  lying.players[0].ball.position_m = Vector3d(spot.x(), spot.y(), Links().terrain.HeightAt(spot.x(), spot.y()));
  lying.players[0].ball.lie = Links().LieAt(spot.x(), spot.y(), kR);
  ASSERT_EQ(lying.players[0].ball.lie, Terrain::kFairway);
  std::optional<RoundStep> holed;
  CourseShotResult shot;
  for (double speed = 12.0; speed <= 17.0 && !holed; speed += 0.1) {
    for (double da : {0.0, 0.25, -0.25}) {
      absl::StatusOr<RoundStep> r = PlayStroke(Links(), s, lying, 0,
                                               Launch(speed, 35, 4000, Heading(spot, pin) + da), &shot);
      ASSERT_TRUE(r.ok()) << r.status();
      if (r->state.players[0].ball.holed) {
        holed = *r;
        break;
      }
    }
  }
  ASSERT_TRUE(holed) << "no chip of the fan holed";
  EXPECT_TRUE(shot.flight.has_value()) << "a chip flies";
  EXPECT_TRUE(Has(holed->events, RoundEventKind::kHoled));
  EXPECT_TRUE(Has(holed->events, RoundEventKind::kHoleEnd));
  EXPECT_TRUE(Has(holed->events, RoundEventKind::kRoundEnd));
  EXPECT_TRUE(holed->state.over);
  EXPECT_EQ(holed->state.result, "finished");
  EXPECT_THAT(holed->state.players[0].scores, ElementsAre(2));
  EXPECT_THAT(holed->state.winners, ElementsAre(0));
  EXPECT_EQ(ToPlay(Links(), s, holed->state), -1);
  EXPECT_EQ(PlayStroke(Links(), s, holed->state, 0, Putt(1, 0)).status().code(),
            absl::StatusCode::kFailedPrecondition);
}

// Order of play by distance (Rule 6.4b), marks on the green (13.1b), the honour on the next tee
// to the lower score (6.4a).
TEST_F(RoundTest, TheFarthestPlaysFirstAndTheLowestScoreHasTheHonour) {
  const RoundSettings s = Settings(1, 2);
  RoundState st = *StartRound(Links(), s);
  st = Play(s, st, 0, Launch(64, 12, 3000, 0.0)).state;  // Ann long
  EXPECT_EQ(ToPlay(Links(), s, st), 1);
  st = Play(s, st, 1, Launch(45, 12, 3500, 0.0)).state;  // Bob short
  ASSERT_GT(ToPin(1, st.players[1].ball.position_m), ToPin(1, st.players[0].ball.position_m));
  EXPECT_EQ(ToPlay(Links(), s, st), 1) << "Bob is farther";
  absl::StatusOr<RoundStep> early = PlayStroke(Links(), s, st, 0, Launch(40, 20, 6000, std::nullopt));
  EXPECT_EQ(early.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(early.status().message(), HasSubstr("farthest"));

  // Both near the pin on the green: Ann 3 m away in 3 strokes, Bob 6 m away in 2.
  auto put = [&](int seat, double metres, double from_deg, int strokes) {
    const Vector2d p = Pin(1) + metres * Vector2d(std::cos(from_deg * kDeg), std::sin(from_deg * kDeg));
    st.players[seat].strokes = strokes;
    st.players[seat].ball.position_m = Vector3d(p.x(), p.y(), Links().terrain.HeightAt(p.x(), p.y()));
    st.players[seat].ball.lie = Links().LieAt(p.x(), p.y(), kR);
    ASSERT_EQ(st.players[seat].ball.lie, Terrain::kGreen);
  };
  put(0, 3.0, 180, 3);
  put(1, 6.0, 200, 2);
  EXPECT_EQ(ToPlay(Links(), s, st), 1);
  std::vector<RoundEvent> events;
  RoundState after_bob = HoleOut(s, st, 1, &events);
  ASSERT_TRUE(after_bob.players[1].ball.holed) << "Bob could not hole out";
  EXPECT_EQ(ToPlay(Links(), s, after_bob), 0);
  EXPECT_FALSE(after_bob.players[0].ball.marked) << "replaced for her turn";
  RoundState done = HoleOut(s, after_bob, 0, &events);
  ASSERT_EQ(done.hole, 2) << "the hole ended";
  const int ann = done.players[0].scores[0], bob = done.players[1].scores[0];
  EXPECT_GE(ann, 4);
  EXPECT_GE(bob, 3);
  EXPECT_TRUE(Has(events, RoundEventKind::kHoleEnd));
  const int honour = ann < bob ? 0 : (bob < ann ? 1 : 0);
  EXPECT_EQ(done.tee_order.front(), honour);
  EXPECT_EQ(ToPlay(Links(), s, done), honour);
  for (const RoundPlayer& p : done.players) {
    EXPECT_EQ(p.strokes, 0);
    EXPECT_EQ(p.ball.position_m.head<2>(), Tee(2));
  }
}

TEST_F(RoundTest, TheRealisticProfileRefusesWhatNoGolferCanDo) {
  RoundSettings s = Settings(1, 1, 1);
  RoundState st = *StartRound(Links(), s);
  absl::Status fast = CheckStroke(Links(), s, st, 0, Launch(110, 11, 2500, std::nullopt));
  EXPECT_EQ(fast.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(fast.message(), HasSubstr("launch.ball_speed_mps"));
  EXPECT_THAT(CheckStroke(Links(), s, st, 0, Launch(60, 80, 2500, std::nullopt)).message(),
              HasSubstr("launch_angle_deg"));
  EXPECT_THAT(CheckStroke(Links(), s, st, 0, Launch(60, 12, 15000, std::nullopt)).message(),
              HasSubstr("spin_rpm"));
  EXPECT_THAT(CheckStroke(Links(), s, st, 0, Putt(13, 0)).message(), HasSubstr("speed_mps"));
  EXPECT_EQ(CheckStroke(Links(), s, st, 2, Putt(1, 0)).code(), absl::StatusCode::kInvalidArgument);
  s.realism = Realism::kArcade;
  EXPECT_TRUE(CheckStroke(Links(), s, st, 0, Launch(110, 11, 2500, std::nullopt)).ok());
  EXPECT_FALSE(CheckStroke(Links(), s, st, 0, Launch(130, 11, 2500, std::nullopt)).ok())
      << "the flight's own bound stays";
}

TEST_F(RoundTest, NoiseIsDrawnFromTheSeedPerStroke) {
  RoundSettings s = Settings(1, 1, 1);
  RoundState st = *StartRound(Links(), s);
  const RoundStroke k = Launch(60, 12, 3000, 0.0);
  const CourseShot exact = *StrokeShot(Links(), s, st, 0, k);
  EXPECT_EQ(exact.launch.ball_speed_mps, 60.0);
  EXPECT_EQ(exact.aim_deg, 0.0);
  s.noise = 1.0;
  const CourseShot a = *StrokeShot(Links(), s, st, 0, k);
  const CourseShot b = *StrokeShot(Links(), s, st, 0, k);
  EXPECT_EQ(a.launch.ball_speed_mps, b.launch.ball_speed_mps);
  EXPECT_EQ(a.launch.launch_direction_deg, b.launch.launch_direction_deg);
  EXPECT_NE(a.launch.ball_speed_mps, 60.0);
  st.strokes = 1;
  EXPECT_NE(StrokeShot(Links(), s, st, 0, k)->launch.ball_speed_mps, a.launch.ball_speed_mps);
  // The spread matches the settings' scale: 1.5 % of speed at noise 1, over 400 strokes.
  double sum = 0, sum2 = 0;
  for (int i = 0; i < 400; ++i) {
    st.strokes = i;
    const double v = StrokeShot(Links(), s, st, 0, k)->launch.ball_speed_mps / 60.0 - 1.0;
    sum += v;
    sum2 += v * v;
  }
  const double mean = sum / 400, sd = std::sqrt(sum2 / 400 - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.003);
  EXPECT_NEAR(sd, 0.015, 0.0025);
}

}  // namespace
}  // namespace sportsim::golf

namespace sportsim::golf {
namespace {

SwingStroke ChapterSwing(std::string_view club) {
  SwingStroke s;
  s.model = std::make_shared<const swing::SwingModel>(*swing::SwingModel::Create(swing::SwingParams{}));
  s.club = *ClubPreset(club);
  return s;
}

// A swing stroke: the chapter's golfer and program run to impact, the club's impact, then the
// same shot as a launch with those conditions.
TEST(RoundSwingTest, ASwingStrokeIsTheLaunchItsImpactGives) {
  RoundSettings s;
  s.players = {{"Ann", ""}};
  const RoundState st = *StartRound(Links(), s);
  RoundStroke k;
  k.kind = RoundStroke::Kind::kSwing;
  k.swing = ChapterSwing("driver");
  k.aim_deg = 0.0;
  absl::StatusOr<SwingLaunch> launch = LaunchFromSwing(*k.swing, s.ball);
  ASSERT_TRUE(launch.ok()) << launch.status();
  // The clubhead at impact is the swing's own; a driver's smash factor is about 1.45.
  swing::SwingRunOptions run;
  absl::StatusOr<swing::SwingRunResult> swung =
      swing::SimulateSwing(*k.swing->model, k.swing->program, swing::SwingSolverOptions{}, run);
  ASSERT_TRUE(swung.ok() && swung->impact);
  EXPECT_EQ(launch->clubhead_speed_mps, swung->impact->clubhead_speed_ground_mps);
  EXPECT_GT(launch->launch.ball_speed_mps / launch->clubhead_speed_mps, 1.3);
  EXPECT_LT(launch->launch.ball_speed_mps / launch->clubhead_speed_mps, 1.55);
  const CourseShot shot = *StrokeShot(Links(), s, st, 0, k);
  EXPECT_EQ(shot.launch.ball_speed_mps, launch->launch.ball_speed_mps);
  EXPECT_EQ(shot.launch.spin_rpm, launch->launch.spin_rpm);
  RoundStroke as_launch;
  as_launch.launch = launch->launch;
  as_launch.aim_deg = 0.0;
  CourseShotResult a, b;
  ASSERT_TRUE(PlayStroke(Links(), s, st, 0, k, &a).ok());
  ASSERT_TRUE(PlayStroke(Links(), s, st, 0, as_launch, &b).ok());
  EXPECT_EQ(a.ground.rest_m, b.ground.rest_m);
  EXPECT_GT(a.flight->carry_m, 100.0);
  // A wedge goes higher and shorter than the driver.
  k.swing = ChapterSwing("pitching-wedge");
  CourseShotResult w;
  ASSERT_TRUE(PlayStroke(Links(), s, st, 0, k, &w).ok());
  EXPECT_LT(w.flight->carry_m, a.flight->carry_m);
  EXPECT_GT(w.flight->landing_angle_deg, a.flight->landing_angle_deg);
}

TEST(RoundSwingTest, TheRealisticProfileRefusesInhumanTorquesAndClubheads) {
  RoundSettings s;
  s.players = {{"Ann", ""}};
  const RoundState st = *StartRound(Links(), s);
  RoundStroke k;
  k.kind = RoundStroke::Kind::kSwing;
  k.swing = ChapterSwing("driver");
  k.swing->program = swing::TorqueProgram::Constant(400, 0);
  absl::Status torque = CheckStroke(Links(), s, st, 0, k);
  EXPECT_EQ(torque.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(torque.message(), HasSubstr("qalpha"));
  // Within each torque's bound, but together past a human's clubhead speed.
  k.swing->program = swing::TorqueProgram::Constant(340, 25);
  ASSERT_TRUE(CheckStroke(Links(), s, st, 0, k).ok());
  absl::StatusOr<SwingLaunch> fast = LaunchFromSwing(*k.swing, s.ball);
  ASSERT_TRUE(fast.ok()) << fast.status();
  ASSERT_GT(fast->clubhead_speed_mps, 70.0) << "the case needs a swing past the bound";
  absl::StatusOr<CourseShot> refused = StrokeShot(Links(), s, st, 0, k);
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(refused.status().message(), HasSubstr("clubhead"));
  s.realism = Realism::kArcade;
  EXPECT_TRUE(CheckStroke(Links(), s, st, 0, k).ok());
}

}  // namespace
}  // namespace sportsim::golf
