#include "sim/games/three_cushion.h"

#include <algorithm>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "sim/billiards/rack.h"
#include "sim/games/table_marks.h"

namespace sportsim::games {
namespace {

using billiards::Ball;
using billiards::MotionState;

constexpr int kDefaultTarget = 15;
// Balls closer than 2R + this are touching (m).
constexpr double kTouchingGapM = 1e-5;

int Target(const Rules& rules) {
  const int t = rules.VariantInt("target");
  return t > 0 ? t : kDefaultTarget;
}

bool EqualInnings(const Rules& rules) { return rules.Variant("equal_innings") == "on"; }

class ThreeCushion final : public Referee {
 public:
  GameKind game() const override { return GameKind::kThreeCushion; }

  // The opening position for `striker`: the rack, white and yellow swapped for seat 1 (the
  // striker's ball beside the head spot, the opponent's on it). Ball indices are kept when
  // `balls` already holds the three balls.
  static absl::Status SetOpening(const TableModel& model, int striker, TableState* balls) {
    absl::StatusOr<std::vector<Ball>> rack = billiards::MakeRack("three-cushion", model);
    if (!rack.ok()) return rack.status();
    if (striker == 1) std::swap((*rack)[0].r, (*rack)[1].r);  // rack order: cue, yellow, red
    if (balls->balls.size() != rack->size()) {
      balls->balls = *std::move(rack);
      return absl::OkStatus();
    }
    for (const Ball& b : *rack) {
      const int i = balls->Find(b.id);
      if (i < 0) return absl::InternalError("three-cushion: missing ball " + b.id);
      PlaceBall(model, i, b.r.head<2>(), balls);
    }
    return absl::OkStatus();
  }

  absl::Status RackFrame(const Rules& rules, const TableModel& model, GameState* state,
                         TableState* balls) const override {
    (void)rules;
    balls->balls.clear();
    if (absl::Status s = SetOpening(model, state->breaker, balls); !s.ok()) return s;
    state->to_play = state->breaker;
    state->opening = true;
    state->is_break = true;
    state->scores = {};
    state->innings = {};
    state->fouls_in_row = {};
    state->ball_in_hand = BallInHand::kNone;
    state->decision = Decision{};
    state->on = {"red"};
    return absl::OkStatus();
  }

  absl::Status SetUpInPlay(const Rules& rules, const TableModel& model, const TableState& balls,
                           GameState* state) const override {
    (void)rules;
    (void)model;
    if (balls.balls.size() != 3 || balls.Find("cue") < 0 || balls.Find("yellow") < 0 ||
        balls.Find("red") < 0) {
      return absl::InvalidArgumentError(
          "three-cushion needs exactly the balls cue (white), yellow and red");
    }
    for (const Ball& b : balls.balls) {
      if (b.state == MotionState::kPocketed) {
        return absl::InvalidArgumentError("three-cushion: every ball must be on the table");
      }
    }
    state->to_play = 0;
    state->opening = false;
    state->is_break = false;
    state->scores = {};
    state->innings = {};
    state->ball_in_hand = BallInHand::kNone;
    state->on = {"yellow", "red"};
    return absl::OkStatus();
  }

  Judgement Judge(const Rules& rules, const TableModel& model, const GameState& state,
                  const ShotCall& call, const ShotRecord& record, TableState* balls) const override;

  absl::StatusOr<Judgement> Decide(const Rules& rules, const TableModel& model,
                                   const GameState& state, int seat, std::string_view choice,
                                   TableState* balls) const override {
    (void)rules;
    if (!state.decision.pending() || state.decision.seat != seat) {
      return absl::FailedPreconditionError(
          absl::StrFormat("no decision is pending for seat %d", seat));
    }
    if (choice != "play" && choice != "reset") {
      return absl::InvalidArgumentError(
          absl::StrFormat("choice must be one of play, reset; got \"%s\"", choice));
    }
    Judgement j{.state = state};
    j.state.decision = Decision{};
    j.verdict.reason = std::string(choice);
    if (choice == "reset") {
      // UMB: the balls set up as for the opening, the seat to play striking.
      if (absl::Status s = SetOpening(model, seat, balls); !s.ok()) return s;
      j.state.opening = true;
      j.state.on = {"red"};
    }
    return j;
  }

  absl::StatusOr<Judgement> ShotClockExpired(const Rules& rules, const TableModel& model,
                                             const GameState& state,
                                             TableState* balls) const override {
    if (state.match_over()) return absl::FailedPreconditionError("the match is over");
    Judgement j{.state = state};
    GameState& st = j.state;
    const int seat = state.to_play;
    if (state.is_break || state.last_shooter != seat) ++st.innings[seat];
    st.last_shooter = seat;
    st.is_break = false;
    st.opening = false;
    j.verdict.reason = "shot_clock";
    EndInning(rules, model, seat, &j, balls);
    OfferTouching(model, *balls, &j);
    return j;
  }

 private:
  // The striker's inning ends: the other seat plays, unless the frame is decided (equal
  // innings: the opponent's levelling inning is over).
  void EndInning(const Rules& rules, const TableModel& model, int striker, Judgement* j,
                 TableState* balls) const {
    GameState& st = j->state;
    const int other = Other(striker);
    const int target = Target(rules);
    j->verdict.turn_passes = true;
    if (EqualInnings(rules) && striker != st.breaker && st.scores[other] >= target) {
      // The levelling inning ended short of the target: the breaker wins.
      j->verdict.frame_over = true;
      (void)EndFrame(*this, rules, model, other, "target", MatchResult::kWon, &st, balls,
                     &j->events);
      return;
    }
    st.to_play = other;
    st.on = {std::string(ThreeCushionBall(striker)), "red"};
  }

  // The striker reached the target.
  void Reached(const Rules& rules, const TableModel& model, int striker, Judgement* j,
               TableState* balls) const {
    GameState& st = j->state;
    const int other = Other(striker);
    if (EqualInnings(rules)) {
      if (striker == st.breaker && st.innings[other] < st.innings[striker]) {
        // The opponent gets the innings level.
        EndInning(rules, model, striker, j, balls);
        return;
      }
      if (striker != st.breaker && st.scores[other] >= Target(rules)) {
        j->verdict.frame_over = true;
        EndMatchDraw(&st, &j->events);
        return;
      }
    }
    j->verdict.frame_over = true;
    (void)EndFrame(*this, rules, model, striker, "target", MatchResult::kWon, &st, balls,
                   &j->events);
  }

  // Balls i and j touch (within kTouchingGapM): the test of both the offer below and the foul
  // of playing into the touching ball.
  static bool Touching(const TableModel& model, const TableState& balls, int i, int j) {
    const double d = (balls.balls[i].r - balls.balls[j].r).head<2>().norm();
    return d <= 2.0 * model.radius() + kTouchingGapM;
  }

  // The seat to play finds its ball touching another (UMB): it may play away or have the balls
  // set up as for the opening.
  static void OfferTouching(const TableModel& model, const TableState& balls, Judgement* j) {
    GameState& st = j->state;
    if (st.match_over() || j->verdict.frame_over) return;
    const int own = balls.Find(ThreeCushionBall(st.to_play));
    if (own < 0) return;
    for (int i = 0; i < static_cast<int>(balls.balls.size()); ++i) {
      if (i != own && Touching(model, balls, i, own)) {
        st.decision = Decision{.seat = st.to_play, .choices = {"play", "reset"}};
        j->events.push_back({.kind = GameEventKind::kDecision, .seat = st.to_play,
                             .choices = st.decision.choices});
        return;
      }
    }
  }

  // UMB: a striker whose ball touches another plays away from it (or has the balls set up as
  // for the opening). Playing into it is a foul: the struck ball's first contact is a ball it
  // touched before the stroke, with no cushion of its own in between (coming back to it off a
  // cushion is playing away; so is reaching the other ball first).
  static bool PlayedIntoTouchingBall(const TableModel& model, const TableState& before,
                                     const ShotFacts& f) {
    if (f.struck < 0 || f.first_contacts.empty()) return false;
    if (f.CushionHitsBefore(f.struck, f.first_contact_t_s) > 0) return false;
    for (int b : f.first_contacts) {
      if (Touching(model, before, b, f.struck)) return true;
    }
    return false;
  }

  // A ball that left the table goes back on its spot.
  void Respot(const TableModel& model, int index, TableState* balls) const {
    const PoolMarks m = PoolTableMarks(model);
    const std::string& id = balls->balls[index].id;
    const Eigen::Vector2d spot =
        id == "red" ? m.foot_spot : (id == "cue" ? m.head_spot : m.centre_spot);
    Eigen::Vector2d xy = spot;
    if (!IsFreeSpot(model, *balls, index, spot)) {
      absl::StatusOr<Eigen::Vector2d> found =
          FindSpotOnLine(model, *balls, index, spot, m.long_string_dir);
      if (found.ok()) xy = *found;
    }
    PlaceBall(model, index, xy, balls);
  }
};

Judgement ThreeCushion::Judge(const Rules& rules, const TableModel& model, const GameState& state,
                              const ShotCall& call, const ShotRecord& record,
                              TableState* balls) const {
  (void)call;
  Judgement j{.state = state};
  GameState& st = j.state;
  const int striker = state.to_play;
  const int own = record.before.Find(ThreeCushionBall(striker));
  const int opp = record.before.Find(ThreeCushionBall(Other(striker)));
  const int red = record.before.Find("red");
  const ShotFacts f = ExtractFacts(record);
  if (state.is_break || state.last_shooter != striker) ++st.innings[striker];
  ++st.shot;
  st.last_shooter = striker;
  st.is_break = false;
  st.decision = Decision{};
  const bool opening = state.opening;
  st.opening = false;

  std::string foul;
  if (f.struck != own) foul = "wrong_cue_ball";
  if (foul.empty() && !f.pocketed.empty()) foul = "ball_off_table";
  if (foul.empty() && PlayedIntoTouchingBall(model, record.before, f)) foul = "touching_ball";
  if (foul.empty() && opening && !f.first_contacts.empty() &&
      std::find(f.first_contacts.begin(), f.first_contacts.end(), red) == f.first_contacts.end()) {
    foul = "wrong_ball_first";
  }
  for (const Pocketing& p : f.pocketed) {
    Respot(model, p.ball, balls);
    j.verdict.respotted.push_back(balls->balls[p.ball].id);
    j.events.push_back({.kind = GameEventKind::kRespot, .seat = striker,
                        .ball = balls->balls[p.ball].id});
  }
  if (!foul.empty()) {
    j.verdict.foul = true;
    j.verdict.reason = foul;
    ++st.fouls_in_row[striker];
    j.events.push_back({.kind = GameEventKind::kFoul, .seat = striker, .reason = foul});
    EndInning(rules, model, striker, &j, balls);
    OfferTouching(model, *balls, &j);
    return j;
  }
  st.fouls_in_row[striker] = 0;
  if (ThreeCushionPoint(f, own, opp, red)) {
    ++st.scores[striker];
    j.verdict.points = 1;
    j.events.push_back({.kind = GameEventKind::kScore, .seat = striker, .points = 1});
    st.on = {std::string(ThreeCushionBall(Other(striker))), "red"};
    if (st.scores[striker] >= Target(rules)) Reached(rules, model, striker, &j, balls);
    OfferTouching(model, *balls, &j);
    return j;
  }
  EndInning(rules, model, striker, &j, balls);
  OfferTouching(model, *balls, &j);
  return j;
}

}  // namespace

std::string_view ThreeCushionBall(int seat) { return seat == 1 ? "yellow" : "cue"; }

bool ThreeCushionPoint(const ShotFacts& facts, int own, int obj_a, int obj_b) {
  if (facts.struck != own) return false;
  // The distinct balls touched, in order of first touch; the second object ball's entry
  // carries the striker's cushion hits before it.
  int seen = 0;
  for (const Contact& c : facts.struck_contacts) {
    if (c.ball != obj_a && c.ball != obj_b) continue;
    if (++seen == 2) return c.struck_cushions_before >= 3;
  }
  return false;
}

billiards::ShotIntent ThreeCushionIntent() {
  return [](const TableState& before, int cue, std::span<const billiards::Event> events) {
    if (before.balls.size() != 3 || cue < 0 || cue > 2) return false;
    return ThreeCushionPoint(ExtractFacts(before, cue, events), cue, (cue + 1) % 3, (cue + 2) % 3);
  };
}

const Referee& ThreeCushionReferee() {
  static const ThreeCushion* const kReferee = new ThreeCushion();
  return *kReferee;
}

}  // namespace sportsim::games
