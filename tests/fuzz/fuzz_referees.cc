// The referees (sim/games) on random matches: a game (8-ball, 9-ball, 10-ball, snooker,
// three-cushion) with random variants and race, started from its rack, then a sequence of
// random actions: shots with a random call and a random ShotRecord (events over the rack in time
// order: contacts, cushion hits, pocketings, transitions; the balls after it moved to free
// spots), placements of the cue ball in hand, decisions (offered or not), concessions and shot
// clock expiries. Every call follows the referee's contract (Judge only after CheckShot
// accepted). Invariants after every judgement: to_play, the decision's seat and winner in
// range; scores, frames won, fouls in a row, points non-negative; frames won at most race_to;
// every id in `on` and every respotted ball on the table; the balls a valid layout (finite, on
// the cloth, no overlap); and Judge a pure function (the same call twice gives the same result).
#include <fuzzer/FuzzedDataProvider.h>

#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "sim/billiards/cue.h"
#include "sim/billiards/model.h"
#include "sim/games/game.h"
#include "sim/games/three_cushion.h"
#include "tests/fuzz/fuzz_util.h"

namespace b = sportsim::billiards;
namespace g = sportsim::games;
using sportsim::fuzz::Bits;

namespace {

const char* Preset(g::GameKind k) {
  switch (k) {
    case g::GameKind::kSnooker: return "snooker";
    case g::GameKind::kThreeCushion: return "carom";
    default: return "pool-9ft";
  }
}

void CheckState(const g::Rules& rules, const b::TableModel& model, const g::GameState& s,
                const b::TableState& balls, const char* after) {
  FUZZ_CHECK(s.to_play == 0 || s.to_play == 1, "after %s: to_play %d", after, s.to_play);
  FUZZ_CHECK(s.frame >= 1, "after %s: frame %d", after, s.frame);
  for (int seat = 0; seat < 2; ++seat) {
    FUZZ_CHECK(s.scores[seat] >= 0, "after %s: seat %d score %d", after, seat, s.scores[seat]);
    FUZZ_CHECK(s.frames_won[seat] >= 0 && s.frames_won[seat] <= rules.race_to,
               "after %s: seat %d frames won %d (race to %d)", after, seat, s.frames_won[seat],
               rules.race_to);
    FUZZ_CHECK(s.fouls_in_row[seat] >= 0, "after %s: fouls in row %d", after, s.fouls_in_row[seat]);
    FUZZ_CHECK(s.innings[seat] >= 0, "after %s: innings %d", after, s.innings[seat]);
  }
  FUZZ_CHECK(s.frame <= s.frames_won[0] + s.frames_won[1] + 1, "after %s: frame %d, won %d+%d",
             after, s.frame, s.frames_won[0], s.frames_won[1]);
  FUZZ_CHECK(s.winner >= -1 && s.winner <= 1, "after %s: winner %d", after, s.winner);
  FUZZ_CHECK(s.breaker == 0 || s.breaker == 1, "after %s: breaker %d", after, s.breaker);
  FUZZ_CHECK(s.decision.seat >= -1 && s.decision.seat <= 1, "after %s: decision seat %d", after,
             s.decision.seat);
  FUZZ_CHECK(!s.decision.pending() || !s.decision.choices.empty(),
             "after %s: a decision with no choices", after);
  if (s.result == g::MatchResult::kWon || s.result == g::MatchResult::kConceded ||
      s.result == g::MatchResult::kThreeFouls) {
    FUZZ_CHECK(s.winner == 0 || s.winner == 1, "after %s: match won by %d", after, s.winner);
  }
  for (const std::string& id : s.on) {
    FUZZ_CHECK(balls.Find(id) >= 0, "after %s: ball on '%s' is not on the table", after,
               id.c_str());
  }
  const absl::Status layout = b::ValidateLayout(model, balls);
  FUZZ_CHECK(layout.ok(), "after %s: balls no valid layout: %s", after,
             std::string(layout.message()).c_str());
  for (const b::Ball& ball : balls.balls) {
    FUZZ_CHECK(ball.state == b::MotionState::kStationary || ball.state == b::MotionState::kPocketed,
               "after %s: ball %s is moving", after, ball.id.c_str());
  }
}

void CheckJudgement(const g::Rules& rules, const b::TableModel& model, const g::Judgement& j,
                    const b::TableState& balls, const char* after) {
  CheckState(rules, model, j.state, balls, after);
  FUZZ_CHECK(j.verdict.points >= 0, "after %s: verdict points %d", after, j.verdict.points);
  for (const std::string& id : j.verdict.respotted) {
    const int k = balls.Find(id);
    FUZZ_CHECK(k >= 0, "after %s: respotted '%s' unknown", after, id.c_str());
  }
  for (const g::GameEvent& e : j.events) {
    FUZZ_CHECK(e.seat >= -1 && e.seat <= 1 && e.winner >= -1 && e.winner <= 1,
               "after %s: game event seat %d winner %d", after, e.seat, e.winner);
    FUZZ_CHECK(e.points >= 0, "after %s: game event points %d", after, e.points);
  }
}

bool SameJudgement(const g::Judgement& x, const g::Judgement& y, const b::TableState& bx,
                   const b::TableState& by) {
  if (x.verdict.foul != y.verdict.foul || x.verdict.reason != y.verdict.reason ||
      x.verdict.points != y.verdict.points || x.verdict.turn_passes != y.verdict.turn_passes ||
      x.verdict.respotted != y.verdict.respotted || x.verdict.frame_over != y.verdict.frame_over ||
      x.events.size() != y.events.size() || x.state.to_play != y.state.to_play ||
      x.state.scores != y.state.scores || x.state.frames_won != y.state.frames_won ||
      x.state.on != y.state.on || x.state.ball_in_hand != y.state.ball_in_hand ||
      x.state.decision.choices != y.state.decision.choices || x.state.phase != y.state.phase ||
      bx.balls.size() != by.balls.size()) {
    return false;
  }
  for (size_t i = 0; i < bx.balls.size(); ++i) {
    if (bx.balls[i].state != by.balls[i].state || Bits(bx.balls[i].r.x()) != Bits(by.balls[i].r.x()) ||
        Bits(bx.balls[i].r.y()) != Bits(by.balls[i].r.y())) {
      return false;
    }
  }
  return true;
}

std::string StrikerBall(g::GameKind k, int seat) {
  return k == g::GameKind::kThreeCushion ? std::string(g::ThreeCushionBall(seat)) : "cue";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const g::GameKind kGames[] = {g::GameKind::kEightBall, g::GameKind::kNineBall,
                                       g::GameKind::kTenBall, g::GameKind::kSnooker,
                                       g::GameKind::kThreeCushion};
  FuzzedDataProvider in(data, size);
  const g::GameKind kind = kGames[in.ConsumeIntegralInRange(0, 4)];
  const g::Referee* referee = g::RefereeFor(kind);
  if (referee == nullptr) return 0;
  static const b::TableModel* models[3] = {};
  const int mi = kind == g::GameKind::kSnooker ? 1 : kind == g::GameKind::kThreeCushion ? 2 : 0;
  if (models[mi] == nullptr) {
    models[mi] = new b::TableModel(*b::TableModel::Create(*b::MakeTablePreset(Preset(kind))));
  }
  const b::TableModel& model = *models[mi];

  // Rules: a race to 1-3 and random variants (valid values mostly).
  std::vector<std::pair<std::string, std::string>> settings;
  for (const g::VariantInfo* v : g::VariantsFor(kind)) {
    if (!in.ConsumeBool()) continue;
    std::string value;
    if (!v->values.empty()) {
      value = std::string(v->values[in.ConsumeIntegralInRange<size_t>(0, v->values.size() - 1)]);
    } else {
      value = std::to_string(in.ConsumeIntegralInRange(v->lo - 1, v->hi + 1));
    }
    settings.emplace_back(std::string(v->name), value);
  }
  absl::StatusOr<g::Rules> rules = g::MakeRules(kind, in.ConsumeIntegralInRange(1, 3), 0.0, settings);
  if (!rules.ok()) {
    sportsim::fuzz::CheckMessage("MakeRules", rules.status());
    return 0;
  }
  b::TableState balls;
  absl::StatusOr<g::GameState> started = g::StartMatch(*rules, model, g::Start::kBreak, &balls);
  FUZZ_CHECK(started.ok(), "StartMatch: %s", started.status().ToString().c_str());
  if (!started.ok()) return 0;
  g::GameState state = *started;
  CheckState(*rules, model, state, balls, "StartMatch");
  std::mt19937_64 rng(in.ConsumeIntegral<uint64_t>());
  const b::TableSpec& spec = model.spec();
  const double lim_x = 0.5 * spec.length_m - model.cushion_contact_distance();
  const double lim_y = 0.5 * spec.width_m - model.cushion_contact_distance();
  auto random_xy = [&] {
    std::uniform_real_distribution<double> ux(-lim_x, lim_x), uy(-lim_y, lim_y);
    return Eigen::Vector2d(ux(rng), uy(rng));
  };
  bool placed = false;

  for (int step = 0; step < 24 && !state.match_over() && in.remaining_bytes() > 0; ++step) {
    const uint8_t action = in.ConsumeIntegral<uint8_t>();
    if (state.decision.pending()) {  // answer it (sometimes with a choice not offered)
      const int seat = action < 240 ? state.decision.seat : g::Other(state.decision.seat);
      const std::string choice =
          action % 16 == 0 ? "nonsense"
                           : state.decision.choices[action % state.decision.choices.size()];
      b::TableState after = balls;
      absl::StatusOr<g::Judgement> j = referee->Decide(*rules, model, state, seat, choice, &after);
      if (!j.ok()) {
        sportsim::fuzz::CheckMessage("Decide", j.status());
        FUZZ_CHECK(action >= 240 || action % 16 == 0, "Decide refused an offered choice: %s",
                   j.status().ToString().c_str());
        continue;
      }
      CheckJudgement(*rules, model, *j, after, "Decide");
      state = j->state;
      balls = after;
      placed = false;
      continue;
    }
    if (action >= 250) {  // concede or the shot clock
      b::TableState after = balls;
      absl::StatusOr<g::Judgement> j =
          action & 1 ? referee->Concede(*rules, model, state, action & 2 ? 1 : 0, &after)
                     : referee->ShotClockExpired(*rules, model, state, &after);
      if (!j.ok()) {
        sportsim::fuzz::CheckMessage("Concede/ShotClockExpired", j.status());
        continue;
      }
      CheckJudgement(*rules, model, *j, after, action & 1 ? "Concede" : "ShotClockExpired");
      state = j->state;
      balls = after;
      placed = false;
      continue;
    }
    const int seat = state.to_play;
    const std::string own = StrikerBall(kind, seat);
    if (state.ball_in_hand != g::BallInHand::kNone && (action < 200 || balls.Find(own) < 0 ||
                                                       balls.balls[balls.Find(own)].state ==
                                                           b::MotionState::kPocketed)) {
      for (int attempt = 0; attempt < 400; ++attempt) {
        const Eigen::Vector2d xy = random_xy();
        if (!referee->InZone(model, state.ball_in_hand, xy) && attempt < 399) continue;
        const absl::Status ok =
            referee->CheckPlacement(*rules, model, state, seat, balls, own, xy);
        sportsim::fuzz::CheckMessage("CheckPlacement", ok);
        if (!ok.ok()) continue;
        const int k = balls.Find(own);
        FUZZ_CHECK(k >= 0, "placement of an unknown ball accepted");
        g::PlaceBall(model, k, xy, &balls);
        placed = true;
        break;
      }
    }
    // The call: random ids, or the first ball on and a pocket.
    g::ShotCall call;
    std::vector<std::string> ids;
    for (const b::Ball& ball : balls.balls) ids.push_back(ball.id);
    if (in.ConsumeBool()) {
      call.ball = state.on.empty() ? ids[in.ConsumeIntegralInRange<size_t>(0, ids.size() - 1)]
                                   : state.on[in.ConsumeIntegralInRange<size_t>(0, state.on.size() - 1)];
    }
    if (!spec.pockets.empty() && in.ConsumeBool()) {
      call.pocket = spec.pockets[in.ConsumeIntegralInRange<size_t>(0, spec.pockets.size() - 1)].name;
    }
    call.safety = in.ConsumeIntegralInRange(0, 5) == 0;
    call.push_out = in.ConsumeIntegralInRange(0, 5) == 0;
    if (in.ConsumeBool()) call.nominate = ids[in.ConsumeIntegralInRange<size_t>(0, ids.size() - 1)];
    absl::Status check = referee->CheckShot(*rules, model, state, seat, call, balls);
    sportsim::fuzz::CheckMessage("CheckShot", check);
    if (!check.ok()) continue;

    // The shot's record: events in time order over the balls on the table.
    g::ShotRecord record;
    record.struck = balls.Find(own);
    FUZZ_CHECK(record.struck >= 0, "no striker ball %s", own.c_str());
    record.placed = placed;
    record.before = balls;
    record.before.t_s = 0;
    b::TableState after = balls;
    const int n = static_cast<int>(balls.balls.size());
    std::vector<bool> gone(n);
    for (int i = 0; i < n; ++i) gone[i] = balls.balls[i].state == b::MotionState::kPocketed;
    double t = 0;
    const int events = in.ConsumeIntegralInRange(0, 14);
    for (int e = 0; e < events; ++e) {
      b::Event ev;
      const uint8_t dt = in.ConsumeIntegral<uint8_t>();
      t += dt < 32 ? 0.0 : dt * 1e-3;  // sometimes simultaneous (a split hit)
      ev.t_s = t;
      const uint8_t k = in.ConsumeIntegral<uint8_t>();
      ev.a = k < 128 ? record.struck : in.ConsumeIntegralInRange(0, n - 1);
      if (gone[ev.a]) continue;
      switch (k % 4) {
        case 0: {
          ev.kind = b::EventKind::kBallBall;
          ev.b = in.ConsumeIntegralInRange(0, n - 1);
          if (ev.b == ev.a || gone[ev.b]) continue;
          break;
        }
        case 1:
          if (spec.cushions.empty()) continue;
          ev.kind = b::EventKind::kBallCushion;
          ev.other = in.ConsumeIntegralInRange(0, static_cast<int>(spec.cushions.size()) - 1);
          break;
        case 2:
          ev.kind = b::EventKind::kBallPocket;
          ev.other = in.ConsumeIntegralInRange(-1, static_cast<int>(spec.pockets.size()) - 1);
          gone[ev.a] = true;
          after.balls[ev.a].state = b::MotionState::kPocketed;
          after.balls[ev.a].pocket = ev.other;
          break;
        default:
          ev.kind = b::EventKind::kTransition;
          ev.from = b::MotionState::kSliding;
          ev.to = b::MotionState::kRolling;
          break;
      }
      record.events.push_back(ev);
    }
    // Balls still on the table may end elsewhere (a free spot).
    for (int i = 0; i < n; ++i) {
      if (gone[i] || !in.ConsumeBool()) continue;
      for (int attempt = 0; attempt < 8; ++attempt) {
        const Eigen::Vector2d xy = random_xy();
        if (g::IsFreeSpot(model, after, i, xy)) {
          after.balls[i].r = Eigen::Vector3d(xy.x(), xy.y(), model.radius());
          break;
        }
      }
    }
    after.t_s = t + 1.0;
    record.after = after;
    b::TableState judged = after, judged2 = after;
    const g::Judgement j = referee->Judge(*rules, model, state, call, record, &judged);
    CheckJudgement(*rules, model, j, judged, "Judge");
    FUZZ_CHECK(j.state.shot == state.shot + 1, "shot counter %d -> %d", state.shot, j.state.shot);
    const g::Judgement j2 = referee->Judge(*rules, model, state, call, record, &judged2);
    FUZZ_CHECK(SameJudgement(j, j2, judged, judged2), "Judge is not a pure function");
    state = j.state;
    balls = judged;
    placed = false;
  }
  return 0;
}
