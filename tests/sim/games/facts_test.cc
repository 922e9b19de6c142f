// The common framework: names, rules and their variants, the facts of a shot (from synthetic
// event lists and from a real shot), table landmarks.
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/sim/games/pool_test_util.h"

namespace sportsim::games::testing {
namespace {

using billiards::Event;
using billiards::EventKind;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr double kTolM = 1e-12;  // landmark arithmetic (m)

TEST(Names, RoundTrip) {
  for (std::string_view name : GameNames()) {
    absl::StatusOr<GameKind> g = GameFromName(name);
    ASSERT_TRUE(g.ok());
    EXPECT_EQ(GameName(*g), name);
  }
  EXPECT_EQ(GameName(GameKind::kThreeCushion), "three-cushion");
  EXPECT_EQ(GameName(GameKind::kEightBall), "8ball");
  EXPECT_THAT(GameFromName("pool").status().message(), HasSubstr("8ball, 9ball, 10ball"));
  EXPECT_EQ(BallInHandName(BallInHand::kKitchen), "kitchen");
  EXPECT_EQ(*BallInHandFromName("d"), BallInHand::kD);
  EXPECT_EQ(MatchResultName(MatchResult::kThreeFouls), "three_fouls");
  EXPECT_EQ(GameEventKindName(GameEventKind::kFrameEnd), "frame_end");
}

TEST(Rules, DefaultsAndValidation) {
  absl::StatusOr<Rules> r = MakeRules(GameKind::kEightBall);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->Variant("break_scratch_in_hand"), "anywhere");
  EXPECT_EQ(r->Variant("eight_first_on_open"), "foul");
  EXPECT_EQ(r->break_rotation, BreakRotation::kAlternate);

  r = MakeRules(GameKind::kEightBall, 3, 30, {{"break_scratch_in_hand", "kitchen"}, {"break", "winner"}});
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_EQ(r->Variant("break_scratch_in_hand"), "kitchen");
  EXPECT_EQ(r->break_rotation, BreakRotation::kWinner);
  EXPECT_EQ(r->race_to, 3);

  absl::Status bad = MakeRules(GameKind::kEightBall, 1, 0, {{"break_scratch_in_hand", "d"}}).status();
  EXPECT_EQ(bad.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bad.message(), HasSubstr("break_scratch_in_hand"));
  EXPECT_THAT(bad.message(), HasSubstr("anywhere, kitchen"));
  bad = MakeRules(GameKind::kNineBall, 1, 0, {{"miss_rule", "on"}}).status();
  EXPECT_THAT(bad.message(), HasSubstr("no rule \"miss_rule\""));
  bad = MakeRules(GameKind::kThreeCushion, 1, 0, {{"target", "0"}}).status();
  EXPECT_THAT(bad.message(), HasSubstr("target must be an integer in [1, 1000]"));
  absl::StatusOr<Rules> tc = MakeRules(GameKind::kThreeCushion, 1, 0, {{"target", "25"}});
  ASSERT_TRUE(tc.ok());
  EXPECT_EQ(tc->VariantInt("target"), 25);
  EXPECT_EQ(MakeRules(GameKind::kThreeCushion)->VariantInt("target"), 15);
  EXPECT_FALSE(MakeRules(GameKind::kNineBall, 0).ok());
  EXPECT_FALSE(MakeRules(GameKind::kNineBall, 1, -1).ok());
  EXPECT_TRUE(VariantsFor(GameKind::kFree).empty());
}

TEST(Marks, DerivedFromThePlayingArea) {
  for (std::string_view preset : {"pool-7ft", "pool-9ft", "snooker"}) {
    const TableModel m = PoolModel(preset);
    const PoolMarks marks = PoolTableMarks(m);
    const double len = m.spec().length_m;
    EXPECT_NEAR(marks.head_string_x - marks.head_rail_x, 0.25 * len, kTolM) << preset;
    EXPECT_NEAR(marks.foot_rail_x - marks.foot_spot.x(), 0.25 * len, kTolM) << preset;
    EXPECT_NEAR(marks.foot_spot.y(), 0.0, kTolM);
    EXPECT_TRUE(BehindHeadString(m, {marks.head_string_x, 0.1}));
    EXPECT_FALSE(BehindHeadString(m, {marks.head_string_x + 1e-6, 0.1}));
    EXPECT_NEAR(FromHeadRail(m, 0.737).x(), -0.5 * len + 0.737, kTolM);
  }
}

// An event list built by hand: the cue ball (0) touches 1 and 2 at the same instant.
TEST(Facts, SimultaneousFirstContactsAndCushions) {
  ShotRecord rec;
  rec.struck = 0;
  rec.before.balls.resize(4);
  rec.after.balls.resize(4);
  rec.events = {
      {.t_s = 0.1, .kind = EventKind::kBallCushion, .a = 0, .other = 3},
      {.t_s = 0.5, .kind = EventKind::kBallBall, .a = 0, .b = 2},
      {.t_s = 0.5, .kind = EventKind::kBallBall, .a = 1, .b = 0},
      {.t_s = 0.7, .kind = EventKind::kBallBall, .a = 0, .b = 3},
      {.t_s = 0.9, .kind = EventKind::kBallCushion, .a = 2, .other = 1},
      {.t_s = 1.2, .kind = EventKind::kBallPocket, .a = 1, .other = 4},
      {.t_s = 1.3, .kind = EventKind::kBallPocket, .a = 3, .other = -1},
  };
  const ShotFacts f = ExtractFacts(rec);
  EXPECT_THAT(f.first_contacts, ElementsAre(1, 2));
  EXPECT_DOUBLE_EQ(f.first_contact_t_s, 0.5);
  ASSERT_EQ(f.struck_contacts.size(), 3u);
  EXPECT_EQ(f.struck_contacts[2].ball, 3);
  EXPECT_EQ(f.struck_contacts[2].struck_cushions_before, 1);
  EXPECT_EQ(f.CushionHits(0), 1);
  EXPECT_EQ(f.CushionHitsBefore(0, 0.1), 0);
  EXPECT_EQ(f.CushionHitsBefore(0, 0.2), 1);
  EXPECT_TRUE(f.AnyCushionAtOrAfter(0.5));
  EXPECT_FALSE(f.AnyCushionAtOrAfter(1.0));
  EXPECT_EQ(f.BallsReachingCushion(0), 1);
  EXPECT_TRUE(f.Pocketed(1));
  EXPECT_EQ(f.PocketOf(1), 4);
  EXPECT_TRUE(f.OffTable(3));
  EXPECT_FALSE(f.OffTable(1));
  EXPECT_FALSE(f.Pocketed(2));
}

// Contacts 2 ns apart are not simultaneous.
TEST(Facts, NearlySimultaneousIsNotASplit) {
  ShotRecord rec;
  rec.struck = 0;
  rec.before.balls.resize(3);
  rec.events = {{.t_s = 0.5, .kind = EventKind::kBallBall, .a = 0, .b = 2},
                {.t_s = 0.5 + 2e-9, .kind = EventKind::kBallBall, .a = 0, .b = 1}};
  EXPECT_THAT(ExtractFacts(rec).first_contacts, ElementsAre(2));
}

// The facts of a real shot: a straight pot of the 1 in the top right corner.
TEST(Facts, RealStraightPot) {
  const TableModel m = PoolModel();
  auto [cue, one] = LineUp(m, {0.9, 0.35}, "top_right", 0.5);
  TableState s = Layout(m, {{"cue", cue.x(), cue.y()}, {"1", one.x(), one.y()}});
  const ShotRecord rec = Shoot(m, s, Aim(s, "cue", one), 1.5);
  const ShotFacts f = ExtractFacts(rec);
  EXPECT_THAT(f.first_contacts, ElementsAre(1));
  EXPECT_EQ(f.PocketOf(1), PocketIdx(m, "top_right"));
  EXPECT_FALSE(f.Pocketed(0));
}

}  // namespace
}  // namespace sportsim::games::testing
