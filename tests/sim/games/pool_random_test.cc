// Randomized cross-check: thousands of random real shots per pool game (seeded), each judged by
// the referee and by a deliberately simple second statement of the basic foul rules written
// here from the WPA rules, straight over the raw events. The two must agree on foul or not.
#include <algorithm>
#include <iostream>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "gtest/gtest.h"
#include "tests/sim/games/pool_test_util.h"

namespace sportsim::games::testing {
namespace {

using billiards::Event;
using billiards::EventKind;

constexpr int kShotsPerGame = 3000;

int Num(const std::string& id) { return id == "cue" ? 0 : std::stoi(id); }

// The basic fouls, stated once more: cue ball down; nothing hit; the first ball hit (any of
// several hit at the same instant) not a legal one; after the first hit no ball pocketed and
// no cushion touched; an object ball off the table.
bool SimpleFoul(GameKind game, Group group, const ShotRecord& rec) {
  const int cue = rec.struck;
  std::vector<int> on_table;
  for (const Ball& b : rec.before.balls) {
    if (b.id != "cue" && b.state != billiards::MotionState::kPocketed) on_table.push_back(Num(b.id));
  }
  std::vector<int> legal;
  if (game == GameKind::kEightBall) {
    for (int n : on_table) {
      const bool mine = group == Group::kNone ? n != 8 : (group == Group::kSolids ? n < 8 : n > 8);
      if (mine) legal.push_back(n);
    }
    if (legal.empty()) legal.push_back(8);
  } else {
    legal.push_back(*std::min_element(on_table.begin(), on_table.end()));
  }
  double first_t = -1;
  bool legal_first = false;
  bool pocketed = false;
  bool cushion_after = false;
  for (const Event& e : rec.events) {
    if (e.kind == EventKind::kBallPocket) {
      if (e.a == cue) return true;
      if (e.other < 0) return true;
      pocketed = true;
    }
    if (e.kind == EventKind::kBallBall && (e.a == cue || e.b == cue)) {
      const int other = e.a == cue ? e.b : e.a;
      if (first_t < 0) first_t = e.t_s;
      if (e.t_s == first_t &&
          std::count(legal.begin(), legal.end(), Num(rec.before.balls[other].id)) > 0) {
        legal_first = true;
      }
    }
    if (e.kind == EventKind::kBallCushion && first_t >= 0) cushion_after = true;
  }
  if (first_t < 0 || !legal_first) return true;
  return !pocketed && !cushion_after;
}

struct Tally {
  int shots = 0, fouls = 0, agree = 0;
  std::map<std::string, int> reasons;
};

Tally RunShots(GameKind game, uint64_t seed) {
  const TableModel m = PoolModel();
  const int max_n = game == GameKind::kEightBall ? 15 : game == GameKind::kNineBall ? 9 : 10;
  const int key = game == GameKind::kEightBall ? 8 : max_n;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ux(-1.15, 1.15), uy(-0.52, 0.52), uphi(-M_PI, M_PI),
      uspeed(0.2, 4.0), u01(0, 1);
  const double d = 2 * m.radius();
  Tally tally;
  for (int shot = 0; shot < kShotsPerGame; ++shot) {
    // Random ids: the key ball and a few others.
    std::vector<std::string> ids = {"cue", std::to_string(key)};
    const int extra = 1 + static_cast<int>(rng() % 5);
    for (int k = 0; k < extra; ++k) {
      const std::string id = std::to_string(1 + rng() % max_n);
      if (std::find(ids.begin(), ids.end(), id) == ids.end()) ids.push_back(id);
    }
    std::vector<Placed> layout;
    for (const std::string& id : ids) {
      for (int tries = 0; tries < 200; ++tries) {
        const double x = ux(rng), y = uy(rng);
        bool ok = true;
        for (const Placed& p : layout) ok &= std::hypot(p.x - x, p.y - y) > d + 1e-4;
        TableState probe = Layout(m, {{"probe", x, y}});
        ok &= IsFreeSpot(m, probe, 0, {x, y});
        if (ok) {
          layout.push_back({id, x, y});
          break;
        }
      }
    }
    if (layout.size() != ids.size() || layout[0].id != "cue") continue;
    Table t = MakeTable(game, layout);
    Group group = Group::kNone;
    if (game == GameKind::kEightBall) {
      const int g = static_cast<int>(rng() % 3);
      group = static_cast<Group>(g);
      if (group != Group::kNone) {
        t.state.groups = {group, group == Group::kSolids ? Group::kStripes : Group::kSolids};
      }
    }
    // A random call (or a safety) where the game needs one.
    ShotCall call;
    if (t.state.call_required) {
      if (u01(rng) < 0.2) {
        call.safety = true;
      } else {
        call.ball = ids[1 + rng() % (ids.size() - 1)];
        call.pocket = m.spec().pockets[rng() % m.spec().pockets.size()].name;
      }
    }
    EXPECT_TRUE(t.referee->CheckShot(t.rules, t.model, t.state, 0, call, t.balls).ok());
    // Mostly aimed at a random object ball (thin and full hits, split hits), else anywhere.
    double phi = uphi(rng);
    if (u01(rng) < 0.75) {
      const std::string target = ids[1 + rng() % (ids.size() - 1)];
      phi = Aim(t.balls, "cue", Pos(t.balls, target)) + 0.06 * (u01(rng) - 0.5);
    }
    const ShotRecord rec = Shoot(m, t.balls, phi, uspeed(rng));
    TableState after = rec.after;
    const Judgement j = t.referee->Judge(t.rules, t.model, t.state, call, rec, &after);
    const bool simple = SimpleFoul(game, group, rec);
    ++tally.shots;
    tally.fouls += j.verdict.foul;
    tally.agree += simple == j.verdict.foul;
    ++tally.reasons[j.verdict.reason];
    EXPECT_EQ(simple, j.verdict.foul) << GameName(game) << " shot " << shot << " reason "
                                      << j.verdict.reason;
    // Whatever happened, the table after is a valid layout (respots never overlap).
    for (size_t a = 0; a < after.balls.size(); ++a) {
      for (size_t b = a + 1; b < after.balls.size(); ++b) {
        if (after.balls[a].state == billiards::MotionState::kPocketed ||
            after.balls[b].state == billiards::MotionState::kPocketed) {
          continue;
        }
        if (j.verdict.respotted.empty()) continue;
        EXPECT_GE((after.balls[a].r - after.balls[b].r).norm(), d - 1e-6);
      }
    }
  }
  return tally;
}

class PoolRandom : public ::testing::TestWithParam<GameKind> {};

TEST_P(PoolRandom, RefereeAgreesWithTheSimpleStatement) {
  const Tally t = RunShots(GetParam(), 20240601 + static_cast<uint64_t>(GetParam()));
  EXPECT_GT(t.shots, kShotsPerGame * 9 / 10);
  EXPECT_EQ(t.agree, t.shots);
  // The generator must exercise both outcomes and the main reasons.
  EXPECT_GT(t.fouls, t.shots / 10);
  EXPECT_LT(t.fouls, t.shots * 9 / 10);
  for (const char* r : {"scratch", "no_contact", "wrong_ball_first", "no_rail"}) {
    EXPECT_GT(t.reasons.count(r), 0u) << r;
  }
  std::string summary;
  for (const auto& [r, n] : t.reasons) summary += (r.empty() ? "legal" : r) + "=" + std::to_string(n) + " ";
  RecordProperty("reasons", summary);
  std::cout << GameName(GetParam()) << ": " << summary << "\n";
}

INSTANTIATE_TEST_SUITE_P(Games, PoolRandom,
                         ::testing::Values(GameKind::kEightBall, GameKind::kNineBall,
                                           GameKind::kTenBall),
                         [](const auto& info) { return std::string(GameName(info.param)).substr(0, 2) == "10" ? std::string("TenBall") : std::string(GameName(info.param)) == "8ball" ? std::string("EightBall") : std::string("NineBall"); });

}  // namespace
}  // namespace sportsim::games::testing
