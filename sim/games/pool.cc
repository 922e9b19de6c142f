#include "sim/games/pool.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <string>

#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "sim/billiards/rack.h"
#include "sim/games/table_marks.h"

namespace sportsim::games {
namespace {

using billiards::Ball;
using billiards::MotionState;

bool IsDown(const Ball& b) { return b.state == MotionState::kPocketed; }

// Index of the pocket with this name, or -1.
int PocketIndex(const TableModel& model, std::string_view name) {
  const auto& pockets = model.spec().pockets;
  for (size_t i = 0; i < pockets.size(); ++i) {
    if (pockets[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

std::vector<std::string> PocketNames(const TableModel& model) {
  std::vector<std::string> names;
  for (const billiards::Pocket& p : model.spec().pockets) names.push_back(p.name);
  return names;
}

// Object ball numbers on the table, ascending.
std::vector<int> NumbersOnTable(const TableState& balls) {
  std::vector<int> out;
  for (const Ball& b : balls.balls) {
    const int n = PoolNumber(b.id);
    if (n > 0 && !IsDown(b)) out.push_back(n);
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool Contains(const std::vector<int>& v, int x) { return std::find(v.begin(), v.end(), x) != v.end(); }

class PoolReferee final : public Referee {
 public:
  explicit PoolReferee(GameKind game) : game_(game) {}
  GameKind game() const override { return game_; }

  absl::Status RackFrame(const Rules& rules, const TableModel& model, GameState* state,
                         TableState* balls) const override;
  absl::Status SetUpInPlay(const Rules& rules, const TableModel& model, const TableState& balls,
                           GameState* state) const override;
  absl::Status CheckShot(const Rules& rules, const TableModel& model, const GameState& state,
                         int seat, const ShotCall& call, const TableState& balls) const override;
  Judgement Judge(const Rules& rules, const TableModel& model, const GameState& state,
                  const ShotCall& call, const ShotRecord& record,
                  TableState* balls) const override;
  absl::StatusOr<Judgement> Decide(const Rules& rules, const TableModel& model,
                                   const GameState& state, int seat, std::string_view choice,
                                   TableState* balls) const override;
  absl::StatusOr<Judgement> ShotClockExpired(const Rules& rules, const TableModel& model,
                                             const GameState& state,
                                             TableState* balls) const override;

 private:
  bool eight() const { return game_ == GameKind::kEightBall; }
  bool ten() const { return game_ == GameKind::kTenBall; }
  int max_number() const { return eight() ? 15 : ten() ? 10 : 9; }
  // The ball that wins the rack in 9-ball and 10-ball, spotted when pocketed otherwise.
  int money() const { return ten() ? 10 : 9; }
  std::string Name() const { return std::string(GameName(game_)); }

  // Legal first balls of `seat` before a shot (8-ball: group, or the 8 once cleared; 9/10:
  // the lowest; the break: 8-ball any, 9/10 the lowest).
  std::vector<int> LegalFirst(const GameState& state, int seat, const TableState& before) const;
  // The 8-ball seat's group is cleared (or the table is open with only the 8 left).
  bool Cleared(const GameState& state, int seat, const TableState& before) const;
  // Refreshes on, call_required for the seat to play.
  void Refresh(GameState* state, const TableState& balls) const;
  // Puts the money ball (or the 8) back: the foot spot, else the long string (WPA 9-ball 2.?
  // "spotting balls"; 8-ball 3.5).
  void Spot(const TableModel& model, int number, TableState* balls, Judgement* j) const;
  // Counts a foul towards the three-foul rule (9/10-ball); true when it loses the rack.
  bool CountFoul(int seat, Judgement* j) const;
  // Gives the opponent of `seat` ball in hand after a foul.
  void FoulHandOver(int seat, BallInHand zone, Judgement* j) const;
  void Lose(const Rules& rules, const TableModel& model, int loser, std::string_view reason,
            MatchResult result, TableState* balls, Judgement* j) const;
  void Win(const Rules& rules, const TableModel& model, int winner, std::string_view reason,
           TableState* balls, Judgement* j) const;

  Judgement JudgeEightBreak(const Rules& rules, const TableModel& model, const GameState& state,
                            const ShotFacts& f, const ShotRecord& record, TableState* balls) const;
  Judgement JudgeEight(const Rules& rules, const TableModel& model, const GameState& state,
                       const ShotCall& call, const ShotFacts& f, const ShotRecord& record,
                       TableState* balls) const;
  Judgement JudgeRotation(const Rules& rules, const TableModel& model, const GameState& state,
                          const ShotCall& call, const ShotFacts& f, const ShotRecord& record,
                          TableState* balls) const;

  GameKind game_;
};

// ---------------------------------------------------------------------------------------------
// Setup

absl::Status PoolReferee::RackFrame(const Rules& rules, const TableModel& model,
                                    GameState* state, TableState* balls) const {
  (void)rules;
  absl::StatusOr<std::vector<Ball>> rack = PoolRack(game_, model);
  if (!rack.ok()) return rack.status();
  balls->balls = *std::move(rack);
  state->game = game_;
  state->is_break = true;
  state->to_play = state->breaker;
  state->ball_in_hand = BallInHand::kKitchen;
  state->groups = {};
  state->fouls_in_row = {};
  state->warned = {};
  state->push_out_available = false;
  state->pushed_out = false;
  state->decision = Decision{};
  Refresh(state, *balls);
  return absl::OkStatus();
}

absl::Status PoolReferee::SetUpInPlay(const Rules& rules, const TableModel& model,
                                      const TableState& balls, GameState* state) const {
  (void)rules;
  (void)model;
  if (balls.Find("cue") < 0) {
    return absl::InvalidArgumentError(Name() + " in play needs a ball \"cue\"");
  }
  for (const Ball& b : balls.balls) {
    const int n = PoolNumber(b.id);
    if (n < 0 || n > max_number()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s balls are \"cue\" and \"1\"..\"%d\"; got \"%s\"", Name(), max_number(), b.id));
    }
  }
  const int key = eight() ? 8 : money();
  const int k = balls.Find(std::to_string(key));
  if (k < 0 || IsDown(balls.balls[k])) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s in play needs the %d on the table", Name(), key));
  }
  state->game = game_;
  state->is_break = false;
  state->to_play = 0;
  state->breaker = 0;
  const int cue = balls.Find("cue");
  state->ball_in_hand = IsDown(balls.balls[cue]) ? BallInHand::kAnywhere : BallInHand::kNone;
  state->groups = {};
  state->push_out_available = false;
  Refresh(state, balls);
  return absl::OkStatus();
}

void PoolReferee::Refresh(GameState* state, const TableState& balls) const {
  state->on.clear();
  if (state->match_over()) {
    state->call_required = false;
    return;
  }
  for (int n : LegalFirst(*state, state->to_play, balls)) state->on.push_back(std::to_string(n));
  state->call_required = !state->is_break && (eight() || ten());
}

std::vector<int> PoolReferee::LegalFirst(const GameState& state, int seat,
                                         const TableState& before) const {
  const std::vector<int> on_table = NumbersOnTable(before);
  if (on_table.empty()) return {};
  if (!eight()) return {on_table.front()};
  if (state.is_break) return on_table;
  std::vector<int> out;
  if (Cleared(state, seat, before)) {
    if (Contains(on_table, 8)) out.push_back(8);
    return out;
  }
  for (int n : on_table) {
    if (n == 8) continue;
    if (state.groups[seat] == Group::kNone || GroupOf(n) == state.groups[seat]) out.push_back(n);
  }
  return out;
}

bool PoolReferee::Cleared(const GameState& state, int seat, const TableState& before) const {
  for (int n : NumbersOnTable(before)) {
    if (n == 8) continue;
    if (state.groups[seat] == Group::kNone || GroupOf(n) == state.groups[seat]) return false;
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Refusals

absl::Status PoolReferee::CheckShot(const Rules& rules, const TableModel& model,
                                    const GameState& state, int seat, const ShotCall& call,
                                    const TableState& balls) const {
  if (absl::Status s = Referee::CheckShot(rules, model, state, seat, call, balls); !s.ok()) {
    return s;
  }
  if (!call.nominate.empty()) {
    return absl::InvalidArgumentError("nominate: only snooker nominates a ball");
  }
  if (call.push_out) {
    if (eight()) return absl::InvalidArgumentError("push-out: 8-ball has no push-out");
    if (!state.push_out_available) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "push-out: only on the shot right after a legal break (WPA %s)", Name()));
    }
    if (call.safety) {
      return absl::InvalidArgumentError("push-out: a push-out is not also a safety");
    }
  }
  if (call.safety && (!call.ball.empty() || !call.pocket.empty())) {
    return absl::InvalidArgumentError("call: a shot is either called or declared a safety");
  }
  if (call.safety && rules.game == GameKind::kNineBall) {
    return absl::InvalidArgumentError(
        "safety: 9-ball has no declared safety (WPA 9-ball calls nothing): a shot that "
        "pockets nothing passes the turn anyway");
  }
  if (!call.ball.empty() || !call.pocket.empty()) {
    if (call.ball.empty() || call.pocket.empty()) {
      return absl::InvalidArgumentError("call: name one ball and one pocket (BALL:POCKET)");
    }
    const int n = PoolNumber(call.ball);
    const int k = balls.Find(call.ball);
    if (n < 1 || k < 0 || IsDown(balls.balls[k])) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "call: \"%s\" is not an object ball on the table", call.ball));
    }
    if (PocketIndex(model, call.pocket) < 0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("call: pocket must be one of %s; got \"%s\"",
                          absl::StrJoin(PocketNames(model), ", "), call.pocket));
    }
  }
  if (state.call_required && !state.is_break && !call.push_out && call.ball.empty() &&
      !call.safety) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "%s: every shot after the break must be called (--call BALL:POCKET) or declared a "
        "safety (WPA)",
        Name()));
  }
  return absl::OkStatus();
}

// ---------------------------------------------------------------------------------------------
// Shared consequences

void PoolReferee::Spot(const TableModel& model, int number, TableState* balls,
                       Judgement* j) const {
  const int k = balls->Find(std::to_string(number));
  if (k < 0 || !IsDown(balls->balls[k])) return;
  const PoolMarks marks = PoolTableMarks(model);
  absl::StatusOr<Eigen::Vector2d> xy =
      FindSpotOnLine(model, *balls, k, marks.foot_spot, marks.long_string_dir);
  if (!xy.ok()) return;  // a full long string cannot happen with at most 16 balls
  PlaceBall(model, k, *xy, balls);
  j->verdict.respotted.push_back(balls->balls[k].id);
  j->events.push_back({.kind = GameEventKind::kRespot, .seat = j->state.last_shooter,
                       .reason = "spotted", .ball = balls->balls[k].id});
}

bool PoolReferee::CountFoul(int seat, Judgement* j) const {
  if (eight()) return false;  // WPA 8-ball has no three-foul rule
  GameState& s = j->state;
  ++s.fouls_in_row[seat];
  // WPA 9-ball: the third foul loses only if the player was warned on two; unwarned, it
  // counts as the second.
  if (s.fouls_in_row[seat] >= 3) {
    if (s.warned[seat]) return true;
    s.fouls_in_row[seat] = 2;
  }
  if (s.fouls_in_row[seat] == 2 && !s.warned[seat]) {
    s.warned[seat] = true;
    j->events.push_back({.kind = GameEventKind::kWarning, .seat = seat, .reason = "two_fouls",
                         .points = 2});
  }
  return false;
}

void PoolReferee::FoulHandOver(int seat, BallInHand zone, Judgement* j) const {
  j->verdict.turn_passes = true;
  j->state.to_play = Other(seat);
  j->state.ball_in_hand = zone;
}

void PoolReferee::Lose(const Rules& rules, const TableModel& model, int loser,
                       std::string_view reason, MatchResult result, TableState* balls,
                       Judgement* j) const {
  j->verdict.frame_over = true;
  j->verdict.turn_passes = true;
  (void)EndFrame(*this, rules, model, Other(loser), reason, result, &j->state, balls, &j->events);
}

void PoolReferee::Win(const Rules& rules, const TableModel& model, int winner,
                      std::string_view reason, TableState* balls, Judgement* j) const {
  j->verdict.frame_over = true;
  (void)EndFrame(*this, rules, model, winner, reason, MatchResult::kWon, &j->state, balls,
                 &j->events);
}

// ---------------------------------------------------------------------------------------------
// Judging

// The standard fouls of one shot (WPA 6), in the order their reasons are reported.
struct FoulCheck {
  bool scratch = false;
  bool no_contact = false;
  bool wrong_first = false;
  bool behind_string = false;
  bool no_rail = false;
  bool off_table = false;
  std::string Reason() const {
    if (scratch) return "scratch";
    if (no_contact) return "no_contact";
    if (wrong_first) return "wrong_ball_first";
    if (behind_string) return "behind_head_string";
    if (no_rail) return "no_rail";
    if (off_table) return "ball_off_table";
    return "";
  }
  bool any() const { return !Reason().empty(); }
};

// From the kitchen, the cue ball must cross the head string before touching a ball that lies
// behind it (WPA: with the cue ball in hand behind the head string, the first ball it contacts
// must lie beyond the string, or the cue ball must cross the string before that contact). The
// crossing is judged on the cue ball's centre at its own events before the contact (cushion
// hits, slide and roll changes: ShotFacts::struck_path): one beyond the string proves it.
// A path that crosses and comes back between two events (a hard draw off the line, with no
// cushion) is not seen.
bool KitchenViolation(const TableModel& model, const GameState& state, const ShotFacts& f,
                      const TableState& before) {
  if (state.ball_in_hand != BallInHand::kKitchen || f.first_contacts.empty()) return false;
  for (int b : f.first_contacts) {
    if (!BehindHeadString(model, before.balls[b].r.head<2>())) return false;
  }
  const double string_x = PoolTableMarks(model).head_string_x;
  for (const Eigen::Vector2d& p : f.struck_path) {
    if (p.x() > string_x) return false;
  }
  return true;
}

FoulCheck StandardFouls(const TableModel& model, const GameState& state, const ShotFacts& f,
                        const TableState& before, const std::vector<int>& legal_first,
                        bool lift_first_and_rail) {
  FoulCheck c;
  c.scratch = f.Pocketed(f.struck);
  for (const Pocketing& p : f.pocketed) {
    if (p.ball != f.struck && p.pocket < 0) c.off_table = true;
  }
  if (lift_first_and_rail) return c;
  c.no_contact = f.first_contacts.empty();
  if (!c.no_contact) {
    // Split hit: a legal ball among the simultaneous first contacts favours the shooter.
    c.wrong_first = true;
    for (int b : f.first_contacts) {
      if (Contains(legal_first, PoolNumber(before.balls[b].id))) c.wrong_first = false;
    }
    c.behind_string = KitchenViolation(model, state, f, before);
    bool object_pocketed = false;
    for (const Pocketing& p : f.pocketed) object_pocketed |= p.ball != f.struck && p.pocket >= 0;
    c.no_rail = !object_pocketed && !f.AnyCushionAtOrAfter(f.first_contact_t_s);
  }
  return c;
}

Judgement PoolReferee::Judge(const Rules& rules, const TableModel& model, const GameState& state,
                             const ShotCall& call, const ShotRecord& record,
                             TableState* balls) const {
  const ShotFacts f = ExtractFacts(record);
  if (eight()) {
    if (state.is_break) return JudgeEightBreak(rules, model, state, f, record, balls);
    return JudgeEight(rules, model, state, call, f, record, balls);
  }
  return JudgeRotation(rules, model, state, call, f, record, balls);
}

Judgement PoolReferee::JudgeEightBreak(const Rules& rules, const TableModel& model,
                                       const GameState& state, const ShotFacts& f,
                                       const ShotRecord& record, TableState* balls) const {
  (void)model;
  Judgement j{.state = state};
  GameState& s = j.state;
  Verdict& v = j.verdict;
  const int seat = state.to_play;
  s.last_shooter = seat;
  ++s.shot;
  s.is_break = false;
  s.groups = {};
  const TableState& before = record.before;
  const int eight_idx = before.Find("8");
  int object_pocketed = 0;
  for (const Pocketing& p : f.pocketed) object_pocketed += p.ball != f.struck && p.pocket >= 0;
  const int object_rails = f.BallsReachingCushion(f.struck);
  const bool scratch = f.Pocketed(f.struck);
  // The 8 driven off the table on the break is not a ball-off-table foul: like the 8 pocketed,
  // it is spotted or the rack re-broken (WPA 3.5; RULES: "the 8 off the table (except on the
  // break ...)").
  bool object_off = false;
  for (const Pocketing& p : f.pocketed) {
    object_off |= p.ball != f.struck && p.ball != eight_idx && p.pocket < 0;
  }
  const bool eight_down = eight_idx >= 0 && f.Pocketed(eight_idx);
  const BallInHand scratch_zone = rules.Variant("break_scratch_in_hand") == "kitchen"
                                      ? BallInHand::kKitchen
                                      : BallInHand::kAnywhere;
  // WPA 3.3: a ball pocketed, or four object balls driven to a cushion.
  const bool legal = object_pocketed > 0 || object_rails >= 4;
  if (!legal) {
    v.foul = true;
    v.reason = "illegal_break";
    v.turn_passes = true;
    s.to_play = Other(seat);
    s.ball_in_hand = BallInHand::kNone;
    s.decision = {.seat = Other(seat), .choices = {"accept_table", "re_rack", "rebreak_by_breaker"}};
    j.events.push_back({.kind = GameEventKind::kFoul, .seat = seat, .reason = v.reason});
    j.events.push_back({.kind = GameEventKind::kDecision, .seat = Other(seat),
                        .reason = v.reason, .choices = s.decision.choices});
  } else if (eight_down) {
    // WPA 3.5: the 8 on the break is spotted or the rack re-broken, never a loss.
    const bool fouled = scratch || object_off;
    const int chooser = fouled ? Other(seat) : seat;
    v.foul = fouled;
    v.reason = scratch ? "scratch" : object_off ? "ball_off_table" : "eight_on_break";
    v.turn_passes = fouled;
    s.to_play = chooser;
    s.ball_in_hand = BallInHand::kNone;
    s.decision = {.seat = chooser, .choices = {"spot_eight", "rebreak"}};
    if (fouled) j.events.push_back({.kind = GameEventKind::kFoul, .seat = seat, .reason = v.reason});
    j.events.push_back({.kind = GameEventKind::kDecision, .seat = chooser, .reason = "eight_on_break",
                        .choices = s.decision.choices});
  } else if (scratch || object_off) {
    v.foul = true;
    v.reason = scratch ? "scratch" : "ball_off_table";
    // The break-scratch setting is about a scratch; an object ball off the table is a standard
    // foul: ball in hand anywhere.
    FoulHandOver(seat, scratch ? scratch_zone : BallInHand::kAnywhere, &j);
    j.events.push_back({.kind = GameEventKind::kFoul, .seat = seat, .reason = v.reason});
  } else {
    v.turn_passes = object_pocketed == 0;
    s.to_play = v.turn_passes ? Other(seat) : seat;
    s.ball_in_hand = BallInHand::kNone;
  }
  Refresh(&s, *balls);
  return j;
}

Judgement PoolReferee::JudgeEight(const Rules& rules, const TableModel& model,
                                  const GameState& state, const ShotCall& call,
                                  const ShotFacts& f, const ShotRecord& record,
                                  TableState* balls) const {
  Judgement j{.state = state};
  GameState& s = j.state;
  Verdict& v = j.verdict;
  const int seat = state.to_play;
  s.last_shooter = seat;
  ++s.shot;
  const TableState& before = record.before;
  const std::vector<int> legal = LegalFirst(state, seat, before);
  FoulCheck c = StandardFouls(model, state, f, before, legal, false);
  // Old BCA: the 8 first on an open table is no foul, but the turn ends.
  bool bca_turn_end = false;
  if (c.wrong_first && state.groups[seat] == Group::kNone &&
      rules.Variant("eight_first_on_open") == "bca") {
    bool only_eight = true;
    for (int b : f.first_contacts) only_eight &= PoolNumber(before.balls[b].id) == 8;
    if (only_eight) {
      c.wrong_first = false;
      bca_turn_end = true;
    }
  }
  const bool foul = c.any();
  v.foul = foul;
  v.reason = c.Reason();
  const int eight_idx = before.Find("8");
  const bool eight_down = eight_idx >= 0 && f.Pocketed(eight_idx);
  if (foul) j.events.push_back({.kind = GameEventKind::kFoul, .seat = seat, .reason = v.reason});

  // WPA 3.? loss of game: the 8 with a foul, before the group is cleared (also with the last
  // group ball on the same stroke), in an uncalled pocket, or off the table.
  if (eight_down) {
    const bool cleared = Cleared(state, seat, before);
    const int eight_pocket = f.PocketOf(eight_idx);
    const bool called = !call.safety && call.ball == "8" &&
                        eight_pocket >= 0 && PocketIndex(model, call.pocket) == eight_pocket;
    if (foul) {
      Lose(rules, model, seat, v.reason, MatchResult::kWon, balls, &j);
    } else if (!cleared) {
      v.reason = "eight_early";
      Lose(rules, model, seat, v.reason, MatchResult::kWon, balls, &j);
    } else if (!called) {
      v.reason = "eight_wrong_pocket";
      Lose(rules, model, seat, v.reason, MatchResult::kWon, balls, &j);
    } else {
      v.reason = "eight_pocketed";
      Win(rules, model, seat, v.reason, balls, &j);
    }
    Refresh(&s, *balls);
    return j;
  }
  if (foul) {
    FoulHandOver(seat, BallInHand::kAnywhere, &j);
    Refresh(&s, *balls);
    return j;
  }
  // A called ball in its called pocket.
  const int called_idx = call.ball.empty() ? -1 : before.Find(call.ball);
  const bool called_in = !call.safety && called_idx >= 0 && f.PocketOf(called_idx) >= 0 &&
                         f.PocketOf(called_idx) == PocketIndex(model, call.pocket);
  const int called_num = called_idx >= 0 ? PoolNumber(call.ball) : -1;
  // WPA 3.?: groups are set by the first called ball legally pocketed after the break.
  if (state.groups[seat] == Group::kNone && called_in && GroupOf(called_num) != Group::kNone &&
      !bca_turn_end) {
    s.groups[seat] = GroupOf(called_num);
    s.groups[Other(seat)] = GroupOf(called_num) == Group::kSolids ? Group::kStripes : Group::kSolids;
  }
  const bool keeps = called_in && !bca_turn_end && GroupOf(called_num) == s.groups[seat];
  v.turn_passes = !keeps;
  if (call.safety) v.reason = "safety";
  s.to_play = keeps ? seat : Other(seat);
  s.ball_in_hand = BallInHand::kNone;
  Refresh(&s, *balls);
  return j;
}

Judgement PoolReferee::JudgeRotation(const Rules& rules, const TableModel& model,
                                     const GameState& state, const ShotCall& call,
                                     const ShotFacts& f, const ShotRecord& record,
                                     TableState* balls) const {
  Judgement j{.state = state};
  GameState& s = j.state;
  Verdict& v = j.verdict;
  const int seat = state.to_play;
  s.last_shooter = seat;
  ++s.shot;
  const TableState& before = record.before;
  const bool is_break = state.is_break;
  const bool push = !is_break && call.push_out && state.push_out_available;
  s.is_break = false;
  s.push_out_available = false;
  s.pushed_out = false;
  const std::vector<int> legal = LegalFirst(state, seat, before);
  FoulCheck c = StandardFouls(model, state, f, before, legal, push);
  const int money_idx = before.Find(std::to_string(money()));
  const bool money_down = money_idx >= 0 && f.Pocketed(money_idx);
  const bool money_pocketed = money_down && f.PocketOf(money_idx) >= 0;
  int object_pocketed = 0;
  for (const Pocketing& p : f.pocketed) object_pocketed += p.ball != f.struck && p.pocket >= 0;
  std::string reason = c.Reason();
  if (is_break) {
    // WPA 9-ball 2.?: the 1 first, and a ball pocketed or four object balls to a cushion.
    const bool enough = object_pocketed > 0 || f.BallsReachingCushion(f.struck) >= 4;
    if (!c.scratch && !c.off_table && (c.no_contact || c.wrong_first || !enough)) {
      reason = "illegal_break";
    } else if (!c.scratch && !c.off_table) {
      reason = "";  // a break needs no cushion after the contact beyond the four balls
    }
  }
  const bool foul = !reason.empty();
  v.foul = foul;
  v.reason = reason;
  if (foul) {
    const size_t foul_event = j.events.size();
    j.events.push_back({.kind = GameEventKind::kFoul, .seat = seat, .reason = reason});
    // The money ball pocketed on a foul or off the table is spotted; the rest stay down.
    if (money_down) Spot(model, money(), balls, &j);
    if (CountFoul(seat, &j)) {
      v.reason = "three_fouls";
      j.events[foul_event].reason = v.reason;  // the foul's own event (a respot may follow it)
      Lose(rules, model, seat, "three_fouls", MatchResult::kThreeFouls, balls, &j);
      Refresh(&s, *balls);
      return j;
    }
    FoulHandOver(seat, BallInHand::kAnywhere, &j);
    Refresh(&s, *balls);
    return j;
  }
  // A legal shot ends the seat's run of fouls.
  s.fouls_in_row[seat] = 0;
  s.warned[seat] = false;
  s.ball_in_hand = BallInHand::kNone;
  if (push) {
    // WPA 9-ball 2.?: after a push-out the incoming player chooses who shoots.
    if (money_down) Spot(model, money(), balls, &j);
    v.reason = "push_out";
    v.turn_passes = true;
    s.pushed_out = true;
    s.to_play = Other(seat);
    s.decision = {.seat = Other(seat), .choices = {"shoot", "pass_back"}};
    j.events.push_back({.kind = GameEventKind::kDecision, .seat = Other(seat),
                        .reason = "push_out", .choices = s.decision.choices});
    Refresh(&s, *balls);
    return j;
  }
  if (is_break) s.push_out_available = true;
  if (!ten()) {
    // 9-ball: the 9 on any legal shot wins, the break included.
    if (money_pocketed) {
      v.reason = "nine_pocketed";
      Win(rules, model, seat, v.reason, balls, &j);
      Refresh(&s, *balls);
      return j;
    }
    v.turn_passes = object_pocketed == 0;
    s.to_play = v.turn_passes ? Other(seat) : seat;
    Refresh(&s, *balls);
    return j;
  }
  // 10-ball.
  if (is_break) {
    if (money_down) Spot(model, money(), balls, &j);
    v.turn_passes = object_pocketed == 0;
    s.to_play = v.turn_passes ? Other(seat) : seat;
    Refresh(&s, *balls);
    return j;
  }
  if (call.safety) {
    if (money_down) Spot(model, money(), balls, &j);
    v.reason = "safety";
    v.turn_passes = true;
    s.to_play = Other(seat);
    Refresh(&s, *balls);
    return j;
  }
  const int called_idx = before.Find(call.ball);
  const bool called_in = called_idx >= 0 && f.PocketOf(called_idx) >= 0 &&
                         f.PocketOf(called_idx) == PocketIndex(model, call.pocket);
  if (called_in) {
    // The 10 wins only as the last ball; earlier (called or not) it is spotted.
    bool others_left = false;
    for (int n : NumbersOnTable(*balls)) others_left |= n != money();
    if (called_idx == money_idx && !others_left) {
      v.reason = "ten_pocketed";
      Win(rules, model, seat, v.reason, balls, &j);
      Refresh(&s, *balls);
      return j;
    }
    if (money_down) Spot(model, money(), balls, &j);
    v.turn_passes = false;
    s.to_play = seat;
    Refresh(&s, *balls);
    return j;
  }
  if (money_down) Spot(model, money(), balls, &j);
  if (object_pocketed > 0) {
    // WPA 10-ball: a ball in an uncalled pocket (or not the called ball) ends the inning; the
    // incoming player chooses to shoot or to hand the shot back.
    v.reason = "wrong_pocket";
    v.turn_passes = true;
    s.to_play = Other(seat);
    s.decision = {.seat = Other(seat), .choices = {"shoot", "pass_back"}};
    j.events.push_back({.kind = GameEventKind::kDecision, .seat = Other(seat),
                        .reason = v.reason, .choices = s.decision.choices});
    Refresh(&s, *balls);
    return j;
  }
  v.turn_passes = true;
  s.to_play = Other(seat);
  Refresh(&s, *balls);
  return j;
}

// ---------------------------------------------------------------------------------------------
// Decisions and the clock

absl::StatusOr<Judgement> PoolReferee::Decide(const Rules& rules, const TableModel& model,
                                              const GameState& state, int seat,
                                              std::string_view choice, TableState* balls) const {
  if (state.match_over()) return absl::FailedPreconditionError("the match is over");
  if (!state.decision.pending()) return absl::FailedPreconditionError("no decision is pending");
  if (seat != state.decision.seat) {
    return absl::FailedPreconditionError(
        absl::StrFormat("the decision is seat %d's", state.decision.seat));
  }
  const auto& choices = state.decision.choices;
  if (std::find(choices.begin(), choices.end(), choice) == choices.end()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "choice must be one of %s; got \"%s\"", absl::StrJoin(choices, ", "), choice));
  }
  Judgement j{.state = state};
  GameState& s = j.state;
  s.decision = Decision{};
  s.pushed_out = false;
  j.verdict.reason = std::string(choice);
  const int cue = balls->Find("cue");
  const bool cue_down = cue >= 0 && IsDown(balls->balls[cue]);
  absl::Status status;
  if (choice == "accept_table") {
    // The table as it lies; a pocketed cue ball comes back in hand, the 8 on its spot.
    s.to_play = seat;
    s.ball_in_hand = cue_down ? (rules.Variant("break_scratch_in_hand") == "kitchen"
                                     ? BallInHand::kKitchen
                                     : BallInHand::kAnywhere)
                              : BallInHand::kNone;
    Spot(model, 8, balls, &j);
  } else if (choice == "re_rack" || choice == "rebreak") {
    // The chooser breaks a new rack (for the 8 on a clean break, the chooser is the breaker).
    s.breaker = seat;
    status = RackFrame(rules, model, &s, balls);
  } else if (choice == "rebreak_by_breaker") {
    s.breaker = Other(seat);
    status = RackFrame(rules, model, &s, balls);
  } else if (choice == "spot_eight") {
    Spot(model, 8, balls, &j);
    s.to_play = seat;
    // WPA 3.5: after a scratch with the 8 on the break, ball in hand behind the head string.
    // The breaker's opponent chooses only after a foul: without a scratch (an object ball off
    // the table) that foul's ball in hand is anywhere.
    s.ball_in_hand = cue_down             ? BallInHand::kKitchen
                     : seat != s.breaker ? BallInHand::kAnywhere
                                         : BallInHand::kNone;
  } else if (choice == "shoot") {
    s.to_play = seat;
  } else if (choice == "pass_back") {
    s.to_play = Other(seat);
  }
  if (!status.ok()) return status;
  Refresh(&s, *balls);
  return j;
}

absl::StatusOr<Judgement> PoolReferee::ShotClockExpired(const Rules& rules,
                                                        const TableModel& model,
                                                        const GameState& state,
                                                        TableState* balls) const {
  if (state.match_over()) return absl::FailedPreconditionError("the match is over");
  if (state.decision.pending()) {
    return absl::FailedPreconditionError("the shot clock does not run while a decision is pending");
  }
  Judgement j{.state = state};
  GameState& s = j.state;
  const int seat = state.to_play;
  j.verdict.foul = true;
  j.verdict.reason = "shot_clock";
  j.events.push_back({.kind = GameEventKind::kFoul, .seat = seat, .reason = "shot_clock"});
  s.push_out_available = false;
  if (CountFoul(seat, &j)) {
    j.verdict.reason = "three_fouls";
    j.events.front().reason = "three_fouls";
    Lose(rules, model, seat, "three_fouls", MatchResult::kThreeFouls, balls, &j);
    Refresh(&s, *balls);
    return j;
  }
  if (state.is_break) {
    // An unbroken rack: the break passes to the opponent, from the kitchen.
    s.breaker = Other(seat);
    j.verdict.turn_passes = true;
    s.to_play = Other(seat);
    s.ball_in_hand = BallInHand::kKitchen;
  } else {
    FoulHandOver(seat, BallInHand::kAnywhere, &j);
  }
  Refresh(&s, *balls);
  return j;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

int PoolNumber(std::string_view id) {
  if (id == "cue") return 0;
  int n = 0;
  auto [p, ec] = std::from_chars(id.data(), id.data() + id.size(), n);
  if (ec != std::errc() || p != id.data() + id.size() || n < 1 || n > 15 || id[0] == '0') return -1;
  return n;
}

Group GroupOf(int number) {
  if (number >= 1 && number <= 7) return Group::kSolids;
  if (number >= 9 && number <= 15) return Group::kStripes;
  return Group::kNone;
}

absl::StatusOr<std::vector<Ball>> PoolRack(GameKind game, const TableModel& model) {
  switch (game) {
    case GameKind::kEightBall: return billiards::MakeRack("8ball", model);
    case GameKind::kNineBall: return billiards::MakeRack("9ball", model);
    case GameKind::kTenBall: return billiards::MakeRack("10ball", model);
    default:
      return absl::InvalidArgumentError(
          absl::StrFormat("%s is not a pool game", GameName(game)));
  }
}

billiards::ShotIntent PotIntent() {
  return [](const TableState& before, int cue, std::span<const billiards::Event> events) {
    if (cue < 0 || static_cast<size_t>(cue) >= before.balls.size()) return false;
    const ShotFacts facts = ExtractFacts(before, cue, events);
    if (facts.first_contacts.empty() || facts.Pocketed(cue)) return false;
    return std::any_of(facts.pocketed.begin(), facts.pocketed.end(), [&](const Pocketing& p) {
      return p.ball != cue && p.pocket >= 0;
    });
  };
}

const Referee& EightBallReferee() {
  static const PoolReferee* const kReferee = new PoolReferee(GameKind::kEightBall);
  return *kReferee;
}
const Referee& NineBallReferee() {
  static const PoolReferee* const kReferee = new PoolReferee(GameKind::kNineBall);
  return *kReferee;
}
const Referee& TenBallReferee() {
  static const PoolReferee* const kReferee = new PoolReferee(GameKind::kTenBall);
  return *kReferee;
}

}  // namespace sportsim::games
