#include "sim/games/snooker.h"

#include <algorithm>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "sim/billiards/rack.h"
#include "sim/games/table_marks.h"

namespace sportsim::games {
namespace {

using billiards::Ball;
using billiards::MotionState;
using Eigen::Vector2d;

bool OnTable(const Ball& b) { return b.state != MotionState::kPocketed; }
Vector2d Xy(const Ball& b) { return b.r.head<2>(); }

bool Contains(const std::vector<int>& v, int x) { return std::find(v.begin(), v.end(), x) != v.end(); }

// Reds on the table, in ball order.
std::vector<int> RedsOn(const TableState& balls) {
  std::vector<int> out;
  for (size_t i = 0; i < balls.balls.size(); ++i) {
    if (IsSnookerRed(balls.balls[i].id) && OnTable(balls.balls[i])) out.push_back(static_cast<int>(i));
  }
  return out;
}

// Colours on the table, in value order.
std::vector<int> ColoursOn(const TableState& balls) {
  std::vector<int> out;
  for (std::string_view c : kSnookerColours) {
    const int i = balls.Find(c);
    if (i >= 0 && OnTable(balls.balls[i])) out.push_back(i);
  }
  return out;
}

std::vector<std::string> Ids(const TableState& balls, const std::vector<int>& idx) {
  std::vector<std::string> out;
  for (int i : idx) out.push_back(balls.balls[i].id);
  return out;
}

// A player coming to the table: a red if any is left, else the lowest colour.
void SetTurnStart(const TableState& balls, GameState* st) {
  st->nominated.clear();
  st->free_ball = false;
  if (st->phase == "respotted_black") {
    st->on = {"black"};
    return;
  }
  const std::vector<int> reds = RedsOn(balls);
  if (!reds.empty()) {
    st->phase = "reds";
    st->on = Ids(balls, reds);
    return;
  }
  st->phase = "colours";
  const std::vector<int> colours = ColoursOn(balls);
  st->on.clear();
  if (!colours.empty()) st->on = {balls.balls[colours.front()].id};
}

// After a red (or a free ball taken as a red) is potted: any colour, nominated.
void SetColourPhase(const TableState& balls, GameState* st) {
  st->phase = "colour";
  st->nominated.clear();
  st->free_ball = false;
  st->on = Ids(balls, ColoursOn(balls));
}

absl::StatusOr<SnookerGeometry> Geometry(const TableModel& model) {
  return MakeSnookerGeometry(model);
}

// Positions of the balls on (ids in st.on) and of every other ball on the table except the cue.
void OnAndNotOn(const TableState& balls, const std::vector<std::string>& on, int cue,
                std::vector<Vector2d>* on_xy, std::vector<Vector2d>* not_on_xy) {
  for (size_t i = 0; i < balls.balls.size(); ++i) {
    const Ball& b = balls.balls[i];
    if (static_cast<int>(i) == cue || !OnTable(b)) continue;
    if (std::find(on.begin(), on.end(), b.id) != on.end()) {
      on_xy->push_back(Xy(b));
    } else {
      not_on_xy->push_back(Xy(b));
    }
  }
}

// The incoming player's cue ball is snookered (in hand: from every position of the D).
bool SnookeredNow(const SnookerGeometry& geo, const GameState& st, const TableState& balls) {
  const int cue = balls.Find("cue");
  if (cue < 0) return false;
  std::vector<Vector2d> on, not_on;
  OnAndNotOn(balls, st.on, cue, &on, &not_on);
  if (st.ball_in_hand == BallInHand::kD || !OnTable(balls.balls[cue])) {
    return IsSnookeredFromD(geo, on, not_on);
  }
  return IsSnookered(geo.radius_m, Xy(balls.balls[cue]), on, not_on);
}

uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

class Snooker final : public Referee {
 public:
  GameKind game() const override { return GameKind::kSnooker; }

  absl::Status RackFrame(const Rules& rules, const TableModel& model, GameState* state,
                         TableState* balls) const override {
    (void)rules;
    absl::StatusOr<std::vector<Ball>> rack = billiards::MakeRack("snooker", model);
    if (!rack.ok()) return rack.status();
    if (absl::StatusOr<SnookerGeometry> g = Geometry(model); !g.ok()) return g.status();
    balls->balls = *std::move(rack);
    state->to_play = state->breaker;
    state->ball_in_hand = BallInHand::kD;  // the rack puts the cue ball in the D
    state->scores = {};
    state->fouls_in_row = {};
    state->decision = Decision{};
    state->is_break = true;
    state->misses_in_row = 0;
    state->replay_position = TableState{};
    state->replay_phase.clear();
    state->phase.clear();
    SetTurnStart(*balls, state);
    return absl::OkStatus();
  }

  absl::Status SetUpInPlay(const Rules& rules, const TableModel& model, const TableState& balls,
                           GameState* state) const override {
    (void)rules;
    if (absl::StatusOr<SnookerGeometry> g = Geometry(model); !g.ok()) return g.status();
    const int cue = balls.Find("cue");
    if (cue < 0) return absl::InvalidArgumentError("snooker needs a ball \"cue\"");
    for (const Ball& b : balls.balls) {
      if (b.id != "cue" && SnookerValue(b.id) == 0) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "snooker balls are cue, red1..red15, yellow, green, brown, blue, pink, black; got "
            "\"%s\"",
            b.id));
      }
    }
    if (RedsOn(balls).empty() && ColoursOn(balls).empty()) {
      return absl::InvalidArgumentError("snooker in play needs at least one object ball on the table");
    }
    state->to_play = 0;
    state->ball_in_hand = OnTable(balls.balls[cue]) ? BallInHand::kNone : BallInHand::kD;
    state->scores = {};
    state->is_break = false;
    state->phase.clear();
    SetTurnStart(balls, state);
    return absl::OkStatus();
  }

  absl::Status CheckShot(const Rules& rules, const TableModel& model, const GameState& state,
                         int seat, const ShotCall& call, const TableState& balls) const override {
    if (absl::Status s = Referee::CheckShot(rules, model, state, seat, call, balls); !s.ok()) {
      return s;
    }
    const int n = call.nominate.empty() ? -1 : balls.Find(call.nominate);
    if (!call.nominate.empty() && (n < 0 || call.nominate == "cue")) {
      return absl::InvalidArgumentError(
          absl::StrFormat("nominate: no object ball \"%s\" on this table", call.nominate));
    }
    if (n >= 0 && !OnTable(balls.balls[n])) {
      return absl::InvalidArgumentError(
          absl::StrFormat("nominate: ball \"%s\" is not on the table", call.nominate));
    }
    const bool nominated_on =
        std::find(state.on.begin(), state.on.end(), call.nominate) != state.on.end();
    if (state.phase == "colour") {
      if (call.nominate.empty() || !nominated_on) {
        return absl::FailedPreconditionError(absl::StrFormat(
            "after a red the striker must nominate a colour (WPBSA 3.12: failure to nominate): "
            "nominate one of %s",
            absl::StrJoin(state.on, ", ")));
      }
      return absl::OkStatus();
    }
    if (!call.nominate.empty() && !nominated_on && !state.free_ball) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "no nomination is due: the ball on is %s (a free ball needs the cue ball snookered "
          "after a foul)",
          state.phase == "reds" ? std::string("a red") : absl::StrJoin(state.on, ", ")));
    }
    return absl::OkStatus();
  }

  bool InZone(const TableModel& model, BallInHand zone, Eigen::Vector2d xy) const override {
    if (zone != BallInHand::kD) return Referee::InZone(model, zone, xy);
    absl::StatusOr<SnookerGeometry> g = Geometry(model);
    return g.ok() && OnCloth(model, xy) && g->InD(xy);
  }

  Judgement Judge(const Rules& rules, const TableModel& model, const GameState& state,
                  const ShotCall& call, const ShotRecord& record, TableState* balls) const override;

  absl::StatusOr<Judgement> Decide(const Rules& rules, const TableModel& model,
                                   const GameState& state, int seat, std::string_view choice,
                                   TableState* balls) const override;

  absl::StatusOr<Judgement> ShotClockExpired(const Rules& rules, const TableModel& model,
                                             const GameState& state,
                                             TableState* balls) const override;

 private:
  // The foul's consequences: penalty to the opponent, colours potted respotted, ball in hand
  // after an in-off, the end of the frame on the last black, else the offended seat's decision.
  absl::Status ApplyFoul(const Rules& rules, const TableModel& model, const SnookerGeometry& geo,
                         int offender, int penalty, const std::string& reason, bool miss,
                         const std::vector<std::string>& colours_down, bool black_only,
                         Judgement* j, TableState* balls) const;
  // Ends the frame on the last black: the higher score wins; a tie re-spots the black and a
  // seeded draw picks who plays it from the D.
  absl::Status FinishFrame(const Rules& rules, const TableModel& model,
                           const SnookerGeometry& geo, Judgement* j, TableState* balls) const;
};

absl::Status Snooker::FinishFrame(const Rules& rules, const TableModel& model,
                                  const SnookerGeometry& geo, Judgement* j,
                                  TableState* balls) const {
  GameState& st = j->state;
  j->verdict.frame_over = true;
  const bool tie_break = st.phase == "respotted_black";
  if (st.scores[0] != st.scores[1]) {
    const int winner = st.scores[0] > st.scores[1] ? 0 : 1;
    return EndFrame(*this, rules, model, winner, tie_break ? "respotted_black" : "points",
                    MatchResult::kWon, &st, balls, &j->events);
  }
  // Level on points: the black re-spotted, the player drawn plays it from the D.
  j->verdict.frame_over = false;
  const int black = balls->Find("black");
  const int cue = balls->Find("cue");
  if (black < 0 || cue < 0) return absl::InternalError("snooker: no black or cue ball");
  balls->balls[black].state = MotionState::kPocketed;
  balls->balls[black].pocket = -1;
  std::vector<std::string> placed;
  if (absl::Status s = RespotColours(geo, std::vector<std::string>{"black"}, balls, &placed);
      !s.ok()) {
    return s;
  }
  // The cue ball goes in hand: it must be placed in the D.
  balls->balls[cue].state = MotionState::kPocketed;
  balls->balls[cue].pocket = -1;
  balls->balls[cue].v.setZero();
  balls->balls[cue].w.setZero();
  const int drawn = SnookerRespottedBlackDraw(st.seed, st.frame);
  j->verdict.respotted.push_back("black");
  j->events.push_back({.kind = GameEventKind::kRespot, .seat = drawn,
                       .reason = "respotted_black_draw", .ball = "black"});
  st.phase = "respotted_black";
  st.on = {"black"};
  st.to_play = drawn;
  st.ball_in_hand = BallInHand::kD;
  st.decision = Decision{};
  st.free_ball = false;
  st.nominated.clear();
  j->verdict.turn_passes = drawn != st.last_shooter;
  return absl::OkStatus();
}

absl::Status Snooker::ApplyFoul(const Rules& rules, const TableModel& model,
                                const SnookerGeometry& geo, int offender, int penalty,
                                const std::string& reason, bool miss,
                                const std::vector<std::string>& colours_down, bool black_only,
                                Judgement* j, TableState* balls) const {
  GameState& st = j->state;
  const int offended = Other(offender);
  j->verdict.foul = true;
  j->verdict.reason = reason;
  j->verdict.points = penalty;
  j->verdict.turn_passes = true;
  st.scores[offended] += penalty;
  ++st.fouls_in_row[offender];
  j->events.push_back(
      {.kind = GameEventKind::kFoul, .seat = offender, .reason = reason, .points = penalty});
  if (black_only) {
    // The last black: the foul ends the frame (or starts the re-spotted black).
    return FinishFrame(rules, model, geo, j, balls);
  }
  // Colours potted on a foul are respotted; reds stay down.
  std::vector<std::string> placed;
  if (absl::Status s = RespotColours(geo, colours_down, balls, &placed); !s.ok()) return s;
  for (const std::string& id : placed) {
    j->verdict.respotted.push_back(id);
    j->events.push_back({.kind = GameEventKind::kRespot, .seat = offender, .ball = id});
  }
  const int cue = balls->Find("cue");
  st.ball_in_hand =
      cue >= 0 && !OnTable(balls->balls[cue]) ? BallInHand::kD : BallInHand::kNone;
  st.to_play = offended;
  SetTurnStart(*balls, &st);
  st.free_ball = SnookeredNow(geo, st, *balls);
  st.decision = Decision{.seat = offended, .choices = {"play", "play_again"}};
  if (miss) st.decision.choices.push_back("replace");
  j->events.push_back({.kind = GameEventKind::kDecision, .seat = offended,
                       .choices = st.decision.choices});
  return absl::OkStatus();
}

Judgement Snooker::Judge(const Rules& rules, const TableModel& model, const GameState& state,
                         const ShotCall& call, const ShotRecord& record, TableState* balls) const {
  Judgement j{.state = state};
  GameState& st = j.state;
  const absl::StatusOr<SnookerGeometry> geo_or = Geometry(model);
  const SnookerGeometry geo = geo_or.ok() ? *geo_or : SnookerGeometry{};
  const double radius = model.radius();
  const int striker = state.to_play;
  const int opponent = Other(striker);
  const ShotFacts f = ExtractFacts(record);
  const TableState& before = record.before;
  const int cue = f.struck;
  ++st.shot;
  st.last_shooter = striker;
  st.is_break = false;
  st.decision = Decision{};
  st.ball_in_hand = BallInHand::kNone;
  const auto value = [&](int i) { return SnookerValue(before.balls[i].id); };

  // The balls on for this stroke, and the value of the ball on for penalties.
  std::vector<int> on;
  int on_value = 1;
  const int nominated = call.nominate.empty() ? -1 : before.Find(call.nominate);
  if (state.phase == "colour") {
    if (nominated >= 0) on.push_back(nominated);
    on_value = nominated >= 0 ? value(nominated) : 7;
  } else {
    for (const std::string& id : state.on) {
      const int i = before.Find(id);
      if (i >= 0 && OnTable(before.balls[i])) on.push_back(i);
    }
    on_value = state.phase == "reds" ? 1 : (on.empty() ? 7 : value(on.front()));
  }
  const bool free_stroke = state.free_ball && nominated >= 0 && !Contains(on, nominated);
  if (free_stroke) on.push_back(nominated);
  const bool black_only = state.phase == "respotted_black" ||
                          (state.phase == "colours" && RedsOn(before).empty() &&
                           ColoursOn(before).size() == 1 && state.on == std::vector<std::string>{"black"});

  int penalty = 0;
  std::string reason;
  const auto foul = [&](std::string_view why, int v) {
    v = std::max(v, 4);
    if (v > penalty) {
      penalty = v;
      reason = std::string(why);
    }
  };
  // Balls the cue ball touched before the stroke.
  std::vector<int> touching;
  for (size_t i = 0; i < before.balls.size(); ++i) {
    if (static_cast<int>(i) == cue || !OnTable(before.balls[i])) continue;
    if ((Xy(before.balls[i]) - Xy(before.balls[cue])).norm() <= 2.0 * radius + kTouchBallGapM) {
      touching.push_back(static_cast<int>(i));
    }
  }
  const bool touching_on = std::any_of(touching.begin(), touching.end(),
                                       [&](int i) { return Contains(on, i); });
  // First contact.
  bool failed_to_hit_on = false;
  if (f.first_contacts.empty()) {
    if (!touching_on) {
      foul("no_contact", on_value);
      failed_to_hit_on = true;
    }
  } else {
    bool ok = true;
    int concerned = on_value;
    for (int b : f.first_contacts) {
      if (!Contains(on, b)) {
        ok = false;
        concerned = std::max(concerned, value(b));
      }
    }
    if (state.phase == "reds" && !free_stroke) {
      // Several reds at once are legal; anything else with them is not.
    } else if (free_stroke) {
      ok = ok && Contains(f.first_contacts, nominated);  // the free ball first (or with the ball on)
    } else {
      ok = ok && f.first_contacts.size() == 1;  // a single colour
    }
    if (!ok) {
      foul("wrong_ball_first", concerned);
      failed_to_hit_on = true;
    }
    if (state.phase == "colour" &&
        std::any_of(f.first_contacts.begin(), f.first_contacts.end(),
                    [&](int b) { return IsSnookerRed(before.balls[b].id); })) {
      // WPBSA 3.12: playing at reds (or a free ball then a red) on consecutive strokes: 7.
      foul("played_red_after_red", 7);
    }
    for (int t : touching) {
      if (Contains(f.first_contacts, t) && f.first_contact_t_s - before.t_s <= kPushStrokeS) {
        foul("push_stroke", std::max(on_value, value(t)));
      }
    }
  }
  // Pots and balls off the table.
  std::vector<std::string> colours_down;
  int reds_potted = 0;
  bool free_potted = false, on_colour_potted = false;
  for (const Pocketing& p : f.pocketed) {
    const std::string& id = before.balls[p.ball].id;
    if (p.ball == cue) {
      foul(p.pocket < 0 ? "ball_off_table" : "scratch", on_value);
      continue;
    }
    if (SnookerGeometry::ColourIndex(id) >= 0) colours_down.push_back(id);
    if (p.pocket < 0) {
      foul("ball_off_table", std::max(on_value, value(p.ball)));
      continue;
    }
    if (!Contains(on, p.ball)) {
      foul("wrong_ball_potted", std::max(on_value, value(p.ball)));
      continue;
    }
    if (IsSnookerRed(id)) ++reds_potted;
    if (p.ball == nominated && free_stroke) {
      free_potted = true;
    } else if (SnookerGeometry::ColourIndex(id) >= 0) {
      on_colour_potted = true;
    }
  }
  // A free ball must not leave the opponent snookered behind it (except pink and black only).
  if (free_stroke && penalty == 0 && f.pocketed.empty()) {
    const std::vector<int> reds_after = RedsOn(*balls);
    const std::vector<int> colours_after = ColoursOn(*balls);
    const bool pink_black_only =
        reds_after.empty() && Ids(*balls, colours_after) == std::vector<std::string>{"pink", "black"};
    GameState next = st;
    SetTurnStart(*balls, &next);
    std::vector<Vector2d> on_xy, not_on_xy;
    OnAndNotOn(*balls, next.on, cue, &on_xy, &not_on_xy);
    const std::vector<Vector2d> fb = {Xy(balls->balls[nominated])};
    if (!pink_black_only && IsSnookered(radius, Xy(balls->balls[cue]), on_xy, fb)) {
      foul("free_ball_snooker", on_value);
    }
  }

  if (penalty > 0) {
    // The miss rule (objective part): a clear line to any part of a ball on was there.
    bool miss = false;
    if (rules.Variant("miss_rule") == "on" && failed_to_hit_on) {
      std::vector<Vector2d> not_on_xy;
      for (size_t i = 0; i < before.balls.size(); ++i) {
        const int k = static_cast<int>(i);
        if (k == cue || !OnTable(before.balls[i]) || Contains(on, k)) continue;
        not_on_xy.push_back(Xy(before.balls[i]));
      }
      bool any_clear = false, full_clear = false;
      for (int o : on) {
        any_clear |= AnyPartClear(radius, Xy(before.balls[cue]), Xy(before.balls[o]), not_on_xy);
        full_clear |= FullBallClear(radius, Xy(before.balls[cue]), Xy(before.balls[o]), not_on_xy);
      }
      const int remaining = SnookerPointsRemaining(state, before);
      const int diff = std::abs(state.scores[0] - state.scores[1]);
      const bool needs_snookers = state.scores[0] + remaining < state.scores[1] ||
                                  state.scores[1] + remaining < state.scores[0];
      if (any_clear && !needs_snookers && remaining != diff) {
        miss = true;
        reason = "miss";
        if (state.misses_in_row >= 2 && full_clear) {
          // The third miss from the same position with a full-ball line: the frame is lost.
          j.verdict.foul = true;
          j.verdict.reason = "miss";
          j.verdict.points = penalty;
          j.verdict.turn_passes = true;
          j.verdict.frame_over = true;
          st.scores[opponent] += penalty;
          j.events.push_back({.kind = GameEventKind::kFoul, .seat = striker, .reason = "miss",
                              .points = penalty});
          (void)EndFrame(*this, rules, model, opponent, "three_misses", MatchResult::kWon, &st,
                         balls, &j.events);
          return j;
        }
      }
    }
    st.replay_position = before;
    st.replay_phase = state.phase;
    st.misses_in_row = miss ? state.misses_in_row + 1 : 0;
    (void)ApplyFoul(rules, model, geo, striker, penalty, reason, miss, colours_down, black_only,
                    &j, balls);
    return j;
  }

  // A legal stroke.
  st.fouls_in_row[striker] = 0;
  st.misses_in_row = 0;
  int points = 0;
  std::vector<std::string> respot;
  if (state.phase == "reds") {
    points = reds_potted + (free_potted ? 1 : 0);
  } else if (state.phase == "colour") {
    if (on_colour_potted) points = on_value;
  } else {
    // Colours in order, the re-spotted black: the ball on's value once, the free ball or the
    // ball on (both potted: the ball on only).
    if (on_colour_potted || free_potted) points = on_value;
  }
  // Colours that go back: the colour after a red, a free ball; in "colours" they stay down.
  for (const std::string& id : colours_down) {
    const int i = before.Find(id);
    if (state.phase == "colour" || (free_stroke && i == nominated)) respot.push_back(id);
  }
  std::vector<std::string> placed;
  (void)RespotColours(geo, respot, balls, &placed);
  for (const std::string& id : placed) {
    j.verdict.respotted.push_back(id);
    j.events.push_back({.kind = GameEventKind::kRespot, .seat = striker, .ball = id});
  }
  st.scores[striker] += points;
  j.verdict.points = points;
  if (points > 0) {
    j.events.push_back({.kind = GameEventKind::kScore, .seat = striker, .points = points});
    if (black_only) {
      (void)FinishFrame(rules, model, geo, &j, balls);
      return j;
    }
    st.to_play = striker;
    if (state.phase == "reds") {
      SetColourPhase(*balls, &st);
    } else {
      SetTurnStart(*balls, &st);
    }
    return j;
  }
  j.verdict.turn_passes = true;
  st.to_play = opponent;
  SetTurnStart(*balls, &st);
  return j;
}

absl::StatusOr<Judgement> Snooker::Decide(const Rules& rules, const TableModel& model,
                                          const GameState& state, int seat,
                                          std::string_view choice, TableState* balls) const {
  (void)rules;
  (void)model;
  if (!state.decision.pending() || state.decision.seat != seat) {
    return absl::FailedPreconditionError(
        absl::StrFormat("no decision is pending for seat %d", seat));
  }
  const auto& choices = state.decision.choices;
  if (std::find(choices.begin(), choices.end(), choice) == choices.end()) {
    return absl::InvalidArgumentError(absl::StrFormat("choice must be one of %s; got \"%s\"",
                                                      absl::StrJoin(choices, ", "), choice));
  }
  Judgement j{.state = state};
  GameState& st = j.state;
  st.decision = Decision{};
  j.verdict.reason = std::string(choice);
  if (choice == "play") {
    st.to_play = seat;
    st.misses_in_row = 0;
  } else if (choice == "play_again") {
    st.to_play = Other(seat);
    st.misses_in_row = 0;
    SetTurnStart(*balls, &st);  // the free ball lapses
    j.verdict.turn_passes = true;
  } else {  // replace: the balls as before the missed stroke, the offender plays again
    *balls = state.replay_position;
    st.to_play = Other(seat);
    st.ball_in_hand = BallInHand::kNone;
    st.phase = state.replay_phase;
    if (st.phase == "colour") {
      SetColourPhase(*balls, &st);
    } else {
      SetTurnStart(*balls, &st);
    }
    j.verdict.turn_passes = true;
  }
  return j;
}

absl::StatusOr<Judgement> Snooker::ShotClockExpired(const Rules& rules, const TableModel& model,
                                                    const GameState& state,
                                                    TableState* balls) const {
  if (state.match_over()) return absl::FailedPreconditionError("the match is over");
  if (state.decision.pending()) {
    return absl::FailedPreconditionError("a decision is pending: no shot clock runs");
  }
  absl::StatusOr<SnookerGeometry> geo = Geometry(model);
  if (!geo.ok()) return geo.status();
  Judgement j{.state = state};
  // A foul worth the ball on (at least 4); after a red, with no colour nominated yet, the
  // lowest colour on the table stands for it.
  int on_value = 1;
  if (state.phase == "colour") {
    const std::vector<int> colours = ColoursOn(*balls);
    on_value = colours.empty() ? 7 : SnookerValue(balls->balls[colours.front()].id);
  } else if (state.phase != "reds" && !state.on.empty()) {
    on_value = SnookerValue(state.on.front());
  }
  const bool black_only = state.phase == "respotted_black" ||
                          (state.phase == "colours" && state.on == std::vector<std::string>{"black"});
  j.state.last_shooter = state.to_play;
  j.state.misses_in_row = 0;
  j.state.replay_position = *balls;
  j.state.replay_phase = state.phase;
  if (absl::Status s = ApplyFoul(rules, model, *geo, state.to_play, std::max(4, on_value),
                                 "shot_clock", false, {}, black_only, &j, balls);
      !s.ok()) {
    return s;
  }
  return j;
}

}  // namespace

int SnookerPointsRemaining(const GameState& state, const TableState& balls) {
  int total = 8 * static_cast<int>(RedsOn(balls).size());
  if (state.phase == "colour") total += 7;
  const int from = state.phase == "colours" && !state.on.empty()
                       ? SnookerGeometry::ColourIndex(state.on.front())
                       : 0;
  for (int i : ColoursOn(balls)) {
    const int c = SnookerGeometry::ColourIndex(balls.balls[i].id);
    if (c >= from) total += c + 2;
  }
  return total;
}

int SnookerRespottedBlackDraw(uint64_t seed, int frame) {
  return static_cast<int>(SplitMix64(seed ^ (0x5A17ull * static_cast<uint64_t>(frame))) & 1u);
}

const Referee& SnookerReferee() {
  static const Snooker* const kReferee = new Snooker();
  return *kReferee;
}

}  // namespace sportsim::games
