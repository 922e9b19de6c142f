// Shared helpers of the referee tests: a pool table, layouts, and real shots played on the
// event engine (no faked events).
#ifndef SPORTSIM_TESTS_SIM_GAMES_POOL_TEST_UTIL_H_
#define SPORTSIM_TESTS_SIM_GAMES_POOL_TEST_UTIL_H_

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "gtest/gtest.h"
#include "sim/billiards/cue.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/model.h"
#include "sim/billiards/shot.h"
#include "sim/games/game.h"
#include "sim/games/pool.h"
#include "sim/games/table_marks.h"

namespace sportsim::games::testing {

using billiards::Ball;
using billiards::TableModel;
using billiards::TableState;

inline TableModel PoolModel(std::string_view preset = "pool-9ft") {
  absl::StatusOr<billiards::TableSpec> spec = billiards::MakeTablePreset(preset);
  EXPECT_TRUE(spec.ok()) << spec.status();
  absl::StatusOr<TableModel> model = TableModel::Create(*spec);
  EXPECT_TRUE(model.ok()) << model.status();
  return *model;
}

struct Placed {
  std::string id;
  double x, y;  // (m)
};

inline TableState Layout(const TableModel& model, const std::vector<Placed>& balls) {
  TableState s;
  for (const Placed& p : balls) {
    Ball b;
    b.id = p.id;
    b.r = Eigen::Vector3d(p.x, p.y, model.radius());
    s.balls.push_back(b);
  }
  return s;
}

inline Eigen::Vector2d Pos(const TableState& s, std::string_view id) {
  return s.balls[s.Find(id)].r.head<2>();
}

inline Eigen::Vector2d PocketCentre(const TableModel& model, std::string_view name) {
  for (const billiards::Pocket& p : model.spec().pockets) {
    if (p.name == name) return p.centre;
  }
  ADD_FAILURE() << "no pocket " << name;
  return Eigen::Vector2d::Zero();
}

inline int PocketIdx(const TableModel& model, std::string_view name) {
  for (size_t i = 0; i < model.spec().pockets.size(); ++i) {
    if (model.spec().pockets[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

/// Heading (rad) from ball `from` to the point `to`.
inline double Aim(const TableState& s, std::string_view from, Eigen::Vector2d to) {
  const Eigen::Vector2d d = to - Pos(s, from);
  return std::atan2(d.y(), d.x());
}

/// A ball `ball_id` lined up for pocket `pocket`: the cue ball `back_m` behind it on the line
/// from the pocket through the ball. Returns the two positions.
inline std::pair<Eigen::Vector2d, Eigen::Vector2d> LineUp(const TableModel& model,
                                                          Eigen::Vector2d ball,
                                                          std::string_view pocket,
                                                          double back_m) {
  const Eigen::Vector2d dir = (PocketCentre(model, pocket) - ball).normalized();
  return {ball - back_m * dir, ball};
}

/// Strikes the cue ball (centre hit, given ball speed and heading) and plays the shot to rest.
inline ShotRecord Shoot(const TableModel& model, const TableState& before, double phi_rad,
                        double speed_mps, bool placed = false, std::string_view cue_id = "cue",
                        double b = 0.0) {
  ShotRecord rec;
  rec.before = before;
  rec.placed = placed;
  rec.struck = before.Find(cue_id);
  TableState struck = before;
  billiards::CueStrike strike{.speed_mps = speed_mps, .ball_speed = true, .phi_rad = phi_rad,
                              .b = b};
  absl::StatusOr<billiards::StrikeOutcome> out =
      billiards::ApplyStrike(model, billiards::SolverOptions{}.effects, strike, rec.struck, &struck);
  EXPECT_TRUE(out.ok()) << out.status();
  absl::StatusOr<billiards::ShotResult> shot =
      billiards::SimulateShot(model, billiards::SolverOptions{}, struck, billiards::ShotOptions{});
  EXPECT_TRUE(shot.ok()) << shot.status();
  EXPECT_TRUE(shot->at_rest);
  rec.events = shot->events;
  rec.after = shot->final_state;
  return rec;
}

/// One turn of a match: CheckShot, then Judge on the table after the shot. Fails the test when
/// the shot is refused.
struct Table {
  explicit Table(TableModel m) : model(std::move(m)) {}
  TableModel model;
  Rules rules;
  GameState state;
  TableState balls;
  const Referee* referee = nullptr;

  Judgement Play(int seat, const ShotCall& call, double phi_rad, double speed_mps) {
    const absl::Status ok = referee->CheckShot(rules, model, state, seat, call, balls);
    EXPECT_TRUE(ok.ok()) << ok;
    ShotRecord rec = Shoot(model, balls, phi_rad, speed_mps, placed_);
    placed_ = false;
    last_record = rec;
    TableState after = rec.after;
    Judgement j = referee->Judge(rules, model, state, call, rec, &after);
    state = j.state;
    balls = after;
    return j;
  }
  absl::Status Place(int seat, Eigen::Vector2d xy) {
    const int cue = balls.Find("cue");
    absl::Status s = referee->CheckPlacement(rules, model, state, seat, balls, "cue", xy);
    if (!s.ok()) return s;
    PlaceBall(model, cue, xy, &balls);
    placed_ = true;
    return s;
  }
  absl::StatusOr<Judgement> Decide(int seat, std::string_view choice) {
    absl::StatusOr<Judgement> j = referee->Decide(rules, model, state, seat, choice, &balls);
    if (j.ok()) state = j->state;
    return j;
  }
  ShotRecord last_record;

 private:
  bool placed_ = false;
};

/// A table for `game` started in play from `layout` (or from the break with an empty layout).
inline Table MakeTable(GameKind game, const std::vector<Placed>& layout, int race_to = 1,
                       const std::vector<std::pair<std::string, std::string>>& rules = {}) {
  Table t{PoolModel()};
  absl::StatusOr<Rules> r = MakeRules(game, race_to, 0.0, rules);
  EXPECT_TRUE(r.ok()) << r.status();
  t.rules = *r;
  t.referee = RefereeFor(game);
  t.balls = Layout(t.model, layout);
  absl::StatusOr<GameState> s =
      StartMatch(t.rules, t.model, layout.empty() ? Start::kBreak : Start::kInPlay, &t.balls);
  EXPECT_TRUE(s.ok()) << s.status();
  t.state = *s;
  return t;
}

/// Ids of the events of a judgement, "kind:reason", for readable assertions.
inline std::vector<std::string> EventNames(const Judgement& j) {
  std::vector<std::string> out;
  for (const GameEvent& e : j.events) {
    out.push_back(std::string(GameEventKindName(e.kind)) + ":" + e.reason);
  }
  return out;
}

}  // namespace sportsim::games::testing

#endif  // SPORTSIM_TESTS_SIM_GAMES_POOL_TEST_UTIL_H_
