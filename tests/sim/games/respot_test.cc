// Respotting: the foot spot, else the nearest free place on the long string towards the foot
// rail, else towards the head; never touching a ball, never in a pocket; and the zone checks
// of ball in hand.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/sim/games/pool_test_util.h"

namespace sportsim::games::testing {
namespace {

using ::testing::HasSubstr;

constexpr double kOnLineM = 1e-9;  // distance from the long string (m)

TEST(Respot, FreeFootSpot) {
  const TableModel m = PoolModel();
  const PoolMarks marks = PoolTableMarks(m);
  TableState s = Layout(m, {{"cue", -0.5, 0.2}, {"9", 0, 0}});
  absl::StatusOr<Eigen::Vector2d> xy = FindSpotOnLine(m, s, 1, marks.foot_spot, marks.long_string_dir);
  ASSERT_TRUE(xy.ok());
  EXPECT_NEAR((*xy - marks.foot_spot).norm(), 0.0, kOnLineM);
}

// A ball on the foot spot: the 9 goes frozen behind it, towards the foot rail.
TEST(Respot, TakenSpotGoesTowardsTheFootRail) {
  const TableModel m = PoolModel();
  const PoolMarks marks = PoolTableMarks(m);
  const double d = 2 * m.radius();
  TableState s = Layout(m, {{"cue", -0.5, 0.2}, {"1", marks.foot_spot.x(), 0.01}, {"9", 0, 0}});
  absl::StatusOr<Eigen::Vector2d> xy = FindSpotOnLine(m, s, 2, marks.foot_spot, marks.long_string_dir);
  ASSERT_TRUE(xy.ok());
  EXPECT_GT(xy->x(), marks.foot_spot.x());
  EXPECT_NEAR(xy->y(), 0.0, kOnLineM);
  const double dist = (*xy - Pos(s, "1")).norm();
  EXPECT_GE(dist, d + kSpotGapM * 0.999);
  EXPECT_LE(dist, d + 2 * kSpotGapM);  // frozen: the nearest place
}

// The whole string to the foot rail taken: towards the head from the foot spot.
TEST(Respot, FullStringGoesTowardsTheHead) {
  const TableModel m = PoolModel();
  const PoolMarks marks = PoolTableMarks(m);
  const double d = 2 * m.radius();
  std::vector<Placed> layout = {{"cue", -0.8, 0.3}};
  int n = 1;
  for (double x = marks.foot_spot.x(); x < marks.foot_rail_x - m.radius(); x += d + 1e-4) {
    layout.push_back({std::to_string(n++), x, 0.0});
  }
  layout.push_back({"spotted", -0.5, -0.3});
  TableState s = Layout(m, layout);
  const int nine = s.Find("spotted");
  absl::StatusOr<Eigen::Vector2d> xy =
      FindSpotOnLine(m, s, nine, marks.foot_spot, marks.long_string_dir);
  ASSERT_TRUE(xy.ok()) << xy.status();
  EXPECT_LT(xy->x(), marks.foot_spot.x());
  EXPECT_TRUE(IsFreeSpot(m, s, nine, *xy));
  EXPECT_NEAR(marks.foot_spot.x() - xy->x(), d + kSpotGapM, 2e-5);
}

// Random crowds around the foot spot: the found place is free, on the line, and no free place
// lies closer to the spot on the first ray searched.
TEST(Respot, RandomCrowdsNeverOverlap) {
  const TableModel m = PoolModel();
  const PoolMarks marks = PoolTableMarks(m);
  const double d = 2 * m.radius();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> ux(marks.foot_spot.x() - 0.3, marks.foot_rail_x - 0.03);
  std::uniform_real_distribution<double> uy(-0.1, 0.1);
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<Placed> layout;
    for (int i = 1; i <= 12; ++i) {
      // Rejection sampling: keep balls apart.
      for (int tries = 0; tries < 100; ++tries) {
        const double x = ux(rng), y = uy(rng);
        bool ok = true;
        for (const Placed& p : layout) ok &= std::hypot(p.x - x, p.y - y) > d + 1e-6;
        if (ok) {
          layout.push_back({std::to_string(i), x, y});
          break;
        }
      }
    }
    layout.push_back({"cue", -1.0, 0.0});
    TableState s = Layout(m, layout);
    const int cue = s.Find("cue");
    absl::StatusOr<Eigen::Vector2d> xy = FindSpotOnLine(m, s, cue, marks.foot_spot, marks.long_string_dir);
    ASSERT_TRUE(xy.ok()) << trial;
    EXPECT_NEAR(xy->y(), 0.0, kOnLineM);
    for (const Ball& b : s.balls) {
      if (b.id == "cue") continue;
      EXPECT_GE((b.r.head<2>() - *xy).norm(), d + kSpotGapM * 0.999) << trial << " " << b.id;
    }
    // Nothing free nearer the spot on the ray towards the foot rail (1 mm grid).
    if (xy->x() >= marks.foot_spot.x()) {
      for (double x = marks.foot_spot.x(); x < xy->x() - 1e-3; x += 1e-3) {
        EXPECT_FALSE(IsFreeSpot(m, s, cue, {x, 0.0})) << trial << " x=" << x;
      }
    }
  }
}

TEST(Respot, PocketsAndCushionsAreNotFree) {
  const TableModel m = PoolModel();
  TableState s = Layout(m, {{"cue", 0, 0}});
  for (const billiards::Pocket& p : m.spec().pockets) EXPECT_FALSE(IsFreeSpot(m, s, 0, p.centre));
  EXPECT_FALSE(IsFreeSpot(m, s, 0, {0.5 * m.spec().length_m, 0.0}));
  EXPECT_TRUE(IsFreeSpot(m, s, 0, {0.3, 0.3}));
}

TEST(Placement, Zones) {
  Table t = MakeTable(GameKind::kEightBall, {});  // the break: in hand in the kitchen
  const PoolMarks marks = PoolTableMarks(t.model);
  EXPECT_EQ(t.state.ball_in_hand, BallInHand::kKitchen);
  EXPECT_TRUE(t.Place(0, {marks.head_string_x - 0.1, 0.2}).ok());
  absl::Status s = t.Place(0, {marks.head_string_x + 0.01, 0.2});
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(s.message(), HasSubstr("behind the head string"));
  EXPECT_EQ(t.Place(1, {marks.head_string_x - 0.1, 0.2}).code(),
            absl::StatusCode::kFailedPrecondition);
  // On a ball: refused.
  EXPECT_FALSE(t.referee->CheckPlacement(t.rules, t.model, t.state, 0, t.balls, "cue",
                                         Pos(t.balls, "1")).ok());
  EXPECT_FALSE(t.referee->CheckPlacement(t.rules, t.model, t.state, 0, t.balls, "1",
                                         {-1.0, 0.0}).ok());
}

}  // namespace
}  // namespace sportsim::games::testing
