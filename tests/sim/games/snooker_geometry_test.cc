// Snooker markings, the geometric "snookered" test and the occupied-spot respotting order.
#include "sim/games/snooker_geometry.h"

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "sim/billiards/cue.h"
#include "sim/billiards/rack.h"

namespace sportsim::games {
namespace {

using billiards::Ball;
using billiards::MotionState;
using billiards::TableModel;
using billiards::TableState;
using Eigen::Vector2d;

constexpr double kPosTolM = 1e-9;  // exact arithmetic on the spots

TableModel SnookerModel() {
  return TableModel::Create(*billiards::MakeTablePreset("snooker")).value();
}

Ball At(std::string id, double x, double y, double r) {
  Ball b;
  b.id = std::move(id);
  b.r = Eigen::Vector3d(x, y, r);
  return b;
}

Ball Down(std::string id) {
  Ball b;
  b.id = std::move(id);
  b.state = MotionState::kPocketed;
  b.pocket = 0;
  return b;
}

TEST(SnookerGeometryTest, FullSizeTableHasTheWpbsaFigures) {
  const TableModel model = SnookerModel();
  const SnookerGeometry g = MakeSnookerGeometry(model).value();
  EXPECT_NEAR(g.baulk_x_m, -3.569 / 2 + 0.737, kPosTolM);
  EXPECT_NEAR(g.d_radius_m, 0.292, kPosTolM);
  EXPECT_NEAR(g.spots[5].x(), 3.569 / 2 - 0.324, kPosTolM);  // black
  EXPECT_NEAR(g.spots[4].x(), 3.569 / 4, kPosTolM);          // pink
  EXPECT_NEAR(g.spots[0].y(), -0.292, kPosTolM);             // yellow on the right
  // The rack puts every colour on its spot.
  const std::vector<Ball> rack = billiards::MakeRack("snooker", model).value();
  for (int c = 0; c < 6; ++c) {
    for (const Ball& b : rack) {
      if (b.id == kSnookerColours[c]) {
        EXPECT_NEAR((b.r.head<2>() - g.spots[c]).norm(), 0.0, kPosTolM) << b.id;
      }
    }
  }
  EXPECT_TRUE(g.InD(Vector2d(g.baulk_x_m - 0.1, 0.1)));
  EXPECT_TRUE(g.InD(Vector2d(g.baulk_x_m, -0.292)));
  EXPECT_FALSE(g.InD(Vector2d(g.baulk_x_m + 0.01, 0.0)));
  EXPECT_FALSE(g.InD(Vector2d(g.baulk_x_m - 0.25, 0.2)));
  EXPECT_EQ(SnookerValue("red7"), 1);
  EXPECT_EQ(SnookerValue("black"), 7);
  EXPECT_EQ(SnookerValue("cue"), 0);
  EXPECT_FALSE(IsSnookerRed("redx"));
}

TEST(SnookerGeometryTest, SmallerTableScalesTheMarkings) {
  billiards::TableSpec spec = *billiards::MakeTablePreset("snooker");
  spec.length_m = 3.569 / 2;
  spec.width_m = 1.778 / 2;
  spec.cushions.clear();
  spec.pockets.clear();
  const TableModel model = TableModel::Create(spec).value();
  const SnookerGeometry g = MakeSnookerGeometry(model).value();
  EXPECT_NEAR(g.d_radius_m, 0.146, kPosTolM);
  EXPECT_NEAR(g.baulk_x_m, -3.569 / 4 + 0.737 / 2, kPosTolM);
}

// --- snookered -------------------------------------------------------------------------------

TEST(SnookeredTest, ClearLineIsNotSnookered) {
  const double r = 0.02625;
  const std::vector<Vector2d> on = {{0.5, 0.0}};
  const std::vector<Vector2d> not_on = {{0.0, 0.5}, {0.2, -0.3}};
  EXPECT_FALSE(IsSnookered(r, Vector2d(-0.5, 0.0), on, not_on));
}

TEST(SnookeredTest, BallFullyBehindABallNotOnIsSnookered) {
  const double r = 0.02625;
  const std::vector<Vector2d> on = {{0.5, 0.0}};
  const std::vector<Vector2d> not_on = {{0.5 - 2 * r - 0.001, 0.0}};  // just in front of it
  EXPECT_TRUE(IsSnookered(r, Vector2d(-0.5, 0.0), on, not_on));
  EXPECT_FALSE(AnyPartClear(r, Vector2d(-0.5, 0.0), on[0], not_on));
  // The same ball, if it were on too, obstructs nothing.
  EXPECT_FALSE(IsSnookered(r, Vector2d(-0.5, 0.0), std::vector<Vector2d>{on[0], not_on[0]}, {}));
}

TEST(SnookeredTest, PartlyObstructedIsSnookeredOnlyWithoutAFullWidthLineElsewhere) {
  const double r = 0.02625;
  const Vector2d cue(-0.5, 0.0);
  const Vector2d red(0.5, 0.0);
  // A ball not on halfway, 2.5 R off the line of centres: the full-ball line and one edge are
  // free, the other extreme edge (the cue ball passing at 2R beside the red's centre line) is
  // not.
  const std::vector<Vector2d> blocker = {{0.0, 2.5 * r}};
  EXPECT_TRUE(FullBallClear(r, cue, red, blocker));
  EXPECT_TRUE(AnyPartClear(r, cue, red, blocker));
  EXPECT_FALSE(BothEdgesClear(r, cue, red, blocker));
  EXPECT_TRUE(IsSnookered(r, cue, std::vector<Vector2d>{red}, blocker));
  // 4.1 R off the line: both edges pass (the edge path sits at most 2R off the line).
  const std::vector<Vector2d> wide = {{0.0, 4.1 * r}};
  EXPECT_FALSE(IsSnookered(r, cue, std::vector<Vector2d>{red}, wide));
  // A second red with a full-width line: not snookered.
  const std::vector<Vector2d> reds = {red, {0.3, -0.6}};
  EXPECT_FALSE(IsSnookered(r, cue, reds, blocker));
}

// A wall of balls not on across the table between the D and a red hides it from the whole D.
TEST(SnookeredTest, InHandSnookeredOnlyIfObstructedFromEveryPositionOfTheD) {
  const TableModel model = SnookerModel();
  const SnookerGeometry g = MakeSnookerGeometry(model).value();
  const double r = g.radius_m;
  const std::vector<Vector2d> on = {{1.0, 0.0}};
  std::vector<Vector2d> wall;
  for (int k = -5; k <= 5; ++k) wall.push_back(Vector2d(-0.6, k * (2 * r + 0.001)));
  EXPECT_TRUE(IsSnookeredFromD(g, on, wall));
  // Take away the wall's +y end: the +y side of the D sees the red past it.
  std::vector<Vector2d> short_wall(wall.begin(), wall.end() - 3);
  EXPECT_FALSE(IsSnookeredFromD(g, on, short_wall));
  // ... although the D's centre is still snookered.
  EXPECT_TRUE(IsSnookered(r, Vector2d(g.baulk_x_m, 0.0), on, short_wall));
  // The sampling covers the D's edges: the chord's ends are among the positions.
  const std::vector<Vector2d> pos = DSamplePositions(g);
  bool yellow_end = false;
  for (const Vector2d& p : pos) {
    EXPECT_TRUE(g.InD(p));
    yellow_end |= (p - g.spots[0]).norm() < kPosTolM;
  }
  EXPECT_TRUE(yellow_end);
  EXPECT_GT(pos.size(), 10000u);  // h = R/8 over a half-disc of radius 292 mm
}

// --- respotting ------------------------------------------------------------------------------

TEST(RespotTest, FreeOwnSpot) {
  const TableModel model = SnookerModel();
  const SnookerGeometry g = MakeSnookerGeometry(model).value();
  TableState s{.balls = {At("cue", -1.2, 0.1, g.radius_m), Down("blue")}};
  std::vector<std::string> placed;
  ASSERT_TRUE(RespotColours(g, std::vector<std::string>{"blue"}, &s, &placed).ok());
  EXPECT_EQ(s.balls[1].state, MotionState::kStationary);
  EXPECT_NEAR((s.balls[1].r.head<2>() - g.spots[3]).norm(), 0.0, kPosTolM);
  EXPECT_EQ(placed, std::vector<std::string>{"blue"});
}

TEST(RespotTest, OccupiedOwnSpotGoesToTheHighestFreeSpot) {
  const TableModel model = SnookerModel();
  const SnookerGeometry g = MakeSnookerGeometry(model).value();
  const double r = g.radius_m;
  // A red lies on the pink spot (touching it counts: 1.5 R away); the black spot is free.
  TableState s{.balls = {At("cue", -1.2, 0.1, r), At("red1", g.spots[4].x() + 1.5 * r, 0.0, r),
                         Down("pink"), Down("green")}};
  ASSERT_TRUE(RespotColours(g, std::vector<std::string>{"green", "pink"}, &s, nullptr).ok());
  EXPECT_NEAR((s.balls[2].r.head<2>() - g.spots[5]).norm(), 0.0, kPosTolM);  // on the black spot
  EXPECT_NEAR((s.balls[3].r.head<2>() - g.spots[1]).norm(), 0.0, kPosTolM);  // own spot
  // With the black spot taken as well, the pink goes to the blue spot.
  TableState t{.balls = {At("red1", g.spots[4].x() + 1.5 * r, 0.0, r),
                         At("red2", g.spots[5].x(), 0.03, r), Down("pink")}};
  ASSERT_TRUE(RespotColours(g, std::vector<std::string>{"pink"}, &t, nullptr).ok());
  EXPECT_NEAR((t.balls[2].r.head<2>() - g.spots[3]).norm(), 0.0, kPosTolM);
}

TEST(RespotTest, HigherValueTakesTheFreeSpotFirst) {
  const TableModel model = SnookerModel();
  const SnookerGeometry g = MakeSnookerGeometry(model).value();
  const double r = g.radius_m;
  // Pink and black both wait, both own spots taken, only the brown spot free (the others
  // covered by reds): the black gets the brown spot.
  TableState s{.balls = {At("red1", g.spots[0].x(), g.spots[0].y(), r),
                         At("red2", g.spots[1].x(), g.spots[1].y(), r),
                         At("red3", g.spots[3].x(), g.spots[3].y(), r),
                         At("red4", g.spots[4].x(), g.spots[4].y(), r),
                         At("red5", g.spots[5].x(), g.spots[5].y(), r), Down("pink"),
                         Down("black")}};
  std::vector<std::string> placed;
  ASSERT_TRUE(RespotColours(g, std::vector<std::string>{"pink", "black"}, &s, &placed).ok());
  EXPECT_EQ(placed, (std::vector<std::string>{"black", "pink"}));
  EXPECT_NEAR((s.balls[6].r.head<2>() - g.spots[2]).norm(), 0.0, kPosTolM);
  // No spot left for the pink: on the line towards the top cushion, touching red4.
  EXPECT_NEAR(s.balls[5].r.y(), 0.0, kPosTolM);
  EXPECT_NEAR(s.balls[5].r.x(), g.spots[4].x() + 2 * r + kTouchGapM, 1e-8);
}

TEST(RespotTest, AllSpotsAndTheTopLineTakenGoesBelowTheSpot) {
  const TableModel model = SnookerModel();
  const SnookerGeometry g = MakeSnookerGeometry(model).value();
  const double r = g.radius_m;
  std::vector<Ball> balls;
  int k = 1;
  for (int c = 0; c < 5; ++c) {
    balls.push_back(At("red" + std::to_string(k++), g.spots[c].x(), g.spots[c].y(), r));
  }
  // Reds from the black spot to the top cushion, touching.
  for (double x = g.spots[5].x(); x <= g.x_limit_m; x += 2 * r + 1e-4) {
    balls.push_back(At("red" + std::to_string(k++), x, 0.0, r));
  }
  balls.push_back(Down("black"));
  TableState s{.balls = balls};
  ASSERT_TRUE(RespotColours(g, std::vector<std::string>{"black"}, &s, nullptr).ok());
  const Ball& black = s.balls.back();
  EXPECT_NEAR(black.r.y(), 0.0, kPosTolM);
  EXPECT_NEAR(black.r.x(), g.spots[5].x() - 2 * r - kTouchGapM, 1e-8);
}

TEST(RespotTest, RandomLayoutsNeverOverlap) {
  const TableModel model = SnookerModel();
  const SnookerGeometry g = MakeSnookerGeometry(model).value();
  const double r = g.radius_m;
  std::mt19937_64 rng(20240611);
  std::uniform_real_distribution<double> ux(-g.x_limit_m, g.x_limit_m);
  std::uniform_real_distribution<double> uy(-g.y_limit_m, g.y_limit_m);
  std::normal_distribution<double> near(0.0, 2 * r);
  for (int trial = 0; trial < 500; ++trial) {
    TableState s;
    // Reds crowded round the spots, then random ones, rejecting overlaps.
    int k = 1;
    for (int tries = 0; tries < 400 && k <= 15; ++tries) {
      Vector2d p;
      if (tries % 2 == 0) {
        const Vector2d spot = g.spots[tries / 2 % 6];
        p = spot + Vector2d(near(rng), near(rng));
      } else {
        p = Vector2d(ux(rng), uy(rng));
      }
      if (std::abs(p.x()) > g.x_limit_m || std::abs(p.y()) > g.y_limit_m) continue;
      bool ok = true;
      for (const Ball& b : s.balls) ok &= (b.r.head<2>() - p).norm() >= 2 * r;
      if (ok) s.balls.push_back(At("red" + std::to_string(k++), p.x(), p.y(), r));
    }
    std::vector<std::string> colours;
    for (int c = 0; c < 6; ++c) {
      if (rng() % 2) {
        s.balls.push_back(Down(std::string(kSnookerColours[c])));
        colours.push_back(std::string(kSnookerColours[c]));
      }
    }
    ASSERT_TRUE(RespotColours(g, colours, &s, nullptr).ok());
    ASSERT_TRUE(billiards::ValidateLayout(model, s).ok()) << "trial " << trial;
    for (const Ball& b : s.balls) {
      ASSERT_NE(b.state, MotionState::kPocketed) << b.id;
      for (const Ball& o : s.balls) {
        if (&o == &b) continue;
        ASSERT_GE((o.r - b.r).head<2>().norm(), 2 * r) << b.id << " " << o.id;
      }
    }
  }
}

}  // namespace
}  // namespace sportsim::games
