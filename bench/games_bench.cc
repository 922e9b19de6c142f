// Google Benchmark: what the referee costs beside the physics.
//
// (a) Per shot, for 9-ball and 8-ball on a 9-ft table: the break from the game's own rack, and
//     two sets of 32 shots from the position after that break (aimed: ghost-ball aim at a legal
//     ball toward its best pocket, seeded random speed; random: seeded random heading, speed,
//     elevation and tip offset, declared a safety). Each shot is simulated ONCE in setup; then
//     BM_Facts times games::ExtractFacts, BM_Referee times Referee::Judge (which calls
//     ExtractFacts itself, so BM_Referee is the referee's whole CPU per shot, facts included), and
//     BM_Physics times SimulateShot (event engine, default physics) on the same shots. The set's
//     shots per second are items_per_second; us/shot = 1e6 / items_per_second.
// (b) A whole 9-ball match, race to 2, played by a seeded bot purely in sim/: StartMatch, the
//     bot's strike (ghost-ball aim as in (a), random speed), SimulateShot, Judge, Decide (first
//     choice) when a decision is pending, the cue ball placed behind the object ball (else the
//     head spot, else the first free spot of a grid) when in hand. Capped at kMaxShots shots
//     (counter cap_hit). Counters: shots, frames, and the thread CPU split physics / referee
//     (per match, ms). BM_NineBallMatch/SEED plays one seeded match per iteration (the same
//     match every iteration: everything is deterministic); BM_NineBallMatches plays seeds 1..32.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "sim/billiards/cue.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/model.h"
#include "sim/billiards/shot.h"
#include "sim/core/cpu_clock.h"
#include "sim/games/game.h"
#include "sim/games/pool.h"
#include "sim/games/table_marks.h"

namespace sportsim::games {
namespace {

using billiards::MotionState;
using billiards::TableModel;
using billiards::TableState;

constexpr int kMaxShots = 2000;

void Die(const char* what, const absl::Status& s) {
  std::fprintf(stderr, "games_bench: %s: %s\n", what, s.ToString().c_str());
  std::abort();
}

const TableModel& Model() {
  static const TableModel* const m = [] {
    absl::StatusOr<billiards::TableSpec> spec = billiards::MakeTablePreset("pool-9ft");
    if (!spec.ok()) Die("preset", spec.status());
    absl::StatusOr<TableModel> model = TableModel::Create(*spec);
    if (!model.ok()) Die("model", model.status());
    return new TableModel(*std::move(model));
  }();
  return *m;
}

bool Down(const billiards::Ball& b) { return b.state == MotionState::kPocketed; }
Eigen::Vector2d Xy(const TableState& s, int k) { return s.balls[k].r.head<2>(); }

// ---------------------------------------------------------------------------------------------
// The bot

/// A planned shot: heading from the cue ball, the object ball and pocket aimed at (-1: none).
struct Plan {
  double phi_rad = 0.0;
  int ball = -1;
  int pocket = -1;
  Eigen::Vector2d cue_spot = Eigen::Vector2d::Zero();  ///< where a placed cue ball would go
};

/// Ghost-ball aim at the legal ball (state.on) and pocket with the smallest cut angle from the
/// cue ball at `cue_xy`; a straight hit at the first legal ball when no cut is under 75 deg.
Plan Aim(const TableModel& m, const GameState& g, const TableState& s, Eigen::Vector2d cue_xy) {
  const double two_r = 2.0 * m.radius();
  Plan best;
  double best_cut = 75.0 * M_PI / 180.0;
  int first = -1;
  for (const std::string& id : g.on) {
    const int k = s.Find(id);
    if (k < 0 || Down(s.balls[k])) continue;
    if (first < 0) first = k;
    const Eigen::Vector2d obj = Xy(s, k);
    const auto& pockets = m.spec().pockets;
    for (size_t p = 0; p < pockets.size(); ++p) {
      const Eigen::Vector2d to_pocket = (pockets[p].centre - obj).normalized();
      const Eigen::Vector2d ghost = obj - two_r * to_pocket;
      const Eigen::Vector2d aim = ghost - cue_xy;
      if (aim.norm() < 1e-6) continue;
      const double cut = std::acos(std::clamp(aim.normalized().dot(to_pocket), -1.0, 1.0));
      if (cut < best_cut) {
        best_cut = cut;
        best = {.phi_rad = std::atan2(aim.y(), aim.x()), .ball = k, .pocket = static_cast<int>(p),
                .cue_spot = ghost - 0.25 * to_pocket};
      }
    }
  }
  if (best.ball < 0 && first >= 0) {
    const Eigen::Vector2d d = Xy(s, first) - cue_xy;
    best.phi_rad = std::atan2(d.y(), d.x());
    best.ball = first;
  }
  return best;
}

/// A free spot for the cue ball in the zone: `preferred`, else the head spot, else the first
/// accepted point of a 5 cm grid. Uses the referee's own CheckPlacement.
Eigen::Vector2d PlaceCue(const Referee& ref, const Rules& rules, const TableModel& m,
                         const GameState& g, const TableState& s, Eigen::Vector2d preferred) {
  const int seat = g.to_play;
  auto ok = [&](Eigen::Vector2d xy) {
    return IsFreeSpot(m, s, s.Find("cue"), xy) &&
           ref.CheckPlacement(rules, m, g, seat, s, "cue", xy).ok();
  };
  if (ok(preferred)) return preferred;
  const Eigen::Vector2d head = PoolTableMarks(m).head_spot;
  if (ok(head)) return head;
  const double hl = 0.5 * m.spec().length_m, hw = 0.5 * m.spec().width_m;
  for (double x = -hl + 0.05; x < hl; x += 0.05) {
    for (double y = -hw + 0.05; y < hw; y += 0.05) {
      if (ok({x, y})) return {x, y};
    }
  }
  std::fprintf(stderr, "games_bench: no free spot for the cue ball\n");
  std::abort();
}

struct BotShot {
  ShotCall call;
  billiards::CueStrike strike;
  std::optional<Eigen::Vector2d> place;  ///< cue ball placed here first
};

/// The bot's next shot for the seat to play (the cue ball's placement included).
BotShot ChooseShot(const Referee& ref, const Rules& rules, const TableModel& m, const GameState& g,
                   const TableState& s, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  BotShot out;
  const int cue = s.Find("cue");
  Eigen::Vector2d cue_xy = Xy(s, cue);
  if (g.is_break) {
    // The rack leaves the cue ball on the head spot, in hand behind the head string.
    if (Down(s.balls[cue])) {
      cue_xy = PlaceCue(ref, rules, m, g, s, PoolTableMarks(m).head_spot);
      out.place = cue_xy;
    }
    const Eigen::Vector2d d = PoolTableMarks(m).foot_spot - cue_xy;
    out.strike = {.speed_mps = 7.0 + 2.0 * unit(rng), .ball_speed = true,
                  .phi_rad = std::atan2(d.y(), d.x()) + 0.004 * (unit(rng) - 0.5)};
    return out;
  }
  if (g.ball_in_hand != BallInHand::kNone) {
    const Plan from_here = Aim(m, g, s, cue_xy);  // gives the spot behind the best ball
    Eigen::Vector2d pref = from_here.pocket >= 0 ? from_here.cue_spot : PoolTableMarks(m).head_spot;
    cue_xy = PlaceCue(ref, rules, m, g, s, pref);
    out.place = cue_xy;
  }
  const Plan p = Aim(m, g, s, cue_xy);
  out.strike = {.speed_mps = 1.0 + 3.0 * unit(rng), .ball_speed = true, .phi_rad = p.phi_rad,
                .b = 0.2 * (unit(rng) - 0.5)};
  if (g.call_required) {
    if (p.pocket >= 0) {
      out.call = {.ball = s.balls[p.ball].id, .pocket = m.spec().pockets[p.pocket].name};
    } else {
      out.call = {.safety = true};
    }
  }
  return out;
}

/// When ValidateLayout (cue.cc) refuses the table, moves every ball outside the rectangle it
/// checks back onto its edge; returns how many moved. Before 77151c9 the engine could leave a
/// ball at rest in a corner pocket's mouth, a fraction of a millimetre beyond |x| <= L/2 -
/// contact distance, and ApplyStrike refused the whole layout; a real player would just play
/// the ball, so the bot nudges it (counted: nudges). Since 77151c9 ValidateLayout accepts a
/// ball in a pocket's mouth, so this should do nothing.
int Nudge(const TableModel& m, TableState* s) {
  if (billiards::ValidateLayout(m, *s).ok()) return 0;
  const double lim_x = 0.5 * m.spec().length_m - m.cushion_contact_distance() - 1e-7;
  const double lim_y = 0.5 * m.spec().width_m - m.cushion_contact_distance() - 1e-7;
  int moved = 0;
  for (billiards::Ball& b : s->balls) {
    if (Down(b)) continue;
    const double x = std::clamp(b.r.x(), -lim_x, lim_x), y = std::clamp(b.r.y(), -lim_y, lim_y);
    if (x != b.r.x() || y != b.r.y()) {
      b.r.x() = x;
      b.r.y() = y;
      ++moved;
    }
  }
  return moved;
}

/// Strikes and simulates: the record the referee reads. `physics_s` gets the thread CPU of
/// ApplyStrike + SimulateShot.
ShotRecord PlayStrike(const TableModel& m, const TableState& before, bool placed,
                      const billiards::CueStrike& strike, double* physics_s) {
  const double c0 = ThreadCpuSeconds();
  ShotRecord rec;
  rec.before = before;
  rec.placed = placed;
  rec.struck = before.Find("cue");
  TableState struck = before;
  absl::StatusOr<billiards::StrikeOutcome> out =
      billiards::ApplyStrike(m, billiards::SolverOptions{}.effects, strike, rec.struck, &struck);
  if (!out.ok()) Die("strike", out.status());
  absl::StatusOr<billiards::ShotResult> r =
      billiards::SimulateShot(m, billiards::SolverOptions{}, struck, billiards::ShotOptions{});
  if (!r.ok()) Die("shot", r.status());
  if (!r->at_rest) {
    std::fprintf(stderr, "games_bench: shot not at rest\n");
    std::abort();
  }
  rec.events = std::move(r->events);
  rec.after = std::move(r->final_state);
  if (physics_s != nullptr) *physics_s += ThreadCpuSeconds() - c0;
  return rec;
}

// ---------------------------------------------------------------------------------------------
// (a) Per-shot sets

struct JudgedShot {
  GameState state;   ///< the game before the shot
  ShotCall call;
  ShotRecord record;
  TableState struck; ///< record.before with the strike applied: SimulateShot's input
};

struct ShotSet {
  const Referee* referee = nullptr;
  Rules rules;
  std::vector<JudgedShot> shots;
};

// kind 0: the break; 1: 32 aimed shots from the position after the break; 2: 32 random ones.
ShotSet MakeSet(GameKind game, int kind) {
  const TableModel& m = Model();
  ShotSet set;
  set.referee = RefereeFor(game);
  absl::StatusOr<Rules> rules = MakeRules(game, 1);
  if (!rules.ok()) Die("rules", rules.status());
  set.rules = *rules;
  TableState balls;
  absl::StatusOr<GameState> g = StartMatch(set.rules, m, Start::kBreak, &balls);
  if (!g.ok()) Die("start", g.status());
  auto add = [&](const GameState& state, const ShotCall& call, const TableState& before,
                 bool placed, const billiards::CueStrike& strike) {
    JudgedShot js{.state = state, .call = call};
    js.record = PlayStrike(m, before, placed, strike, nullptr);
    js.struck = before;
    if (!billiards::ApplyStrike(m, 0, strike, js.struck.Find("cue"), &js.struck).ok()) std::abort();
    set.shots.push_back(std::move(js));
  };
  const billiards::CueStrike brk{.speed_mps = 9.0, .ball_speed = true, .phi_rad = 0.0};
  if (kind == 0) {
    add(*g, {}, balls, false, brk);
    return set;
  }
  // The position after a legal break (the same break as kind 0), decisions answered.
  ShotRecord rec = PlayStrike(m, balls, false, brk, nullptr);
  TableState after = rec.after;
  Judgement j = set.referee->Judge(set.rules, m, *g, {}, rec, &after);
  GameState state = j.state;
  balls = after;
  while (state.decision.pending()) {
    absl::StatusOr<Judgement> d = set.referee->Decide(set.rules, m, state, state.decision.seat,
                                                      state.decision.choices.front(), &balls);
    if (!d.ok()) Die("decide", d.status());
    state = d->state;
  }
  Nudge(m, &balls);
  std::mt19937_64 rng(kind * 1000 + static_cast<int>(game));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // Place the cue ball once (if in hand) so every shot of the set starts from one position.
  bool placed = false;
  if (state.ball_in_hand != BallInHand::kNone) {
    const int cue = balls.Find("cue");
    const Plan p = Aim(m, state, balls, Xy(balls, cue));
    PlaceBall(m, cue, PlaceCue(*set.referee, set.rules, m, state, balls,
                               p.pocket >= 0 ? p.cue_spot : PoolTableMarks(m).head_spot),
              &balls);
    placed = true;
  }
  while (set.shots.size() < 32) {
    if (kind == 1) {
      BotShot b = ChooseShot(*set.referee, set.rules, m, state, balls, rng);
      TableState before = balls;
      if (b.place) PlaceBall(m, before.Find("cue"), *b.place, &before);
      add(state, b.call, before, placed || b.place.has_value(), b.strike);
    } else {
      const billiards::CueStrike strike{
          .speed_mps = 0.5 + 5.5 * unit(rng), .ball_speed = true,
          .phi_rad = 2.0 * M_PI * unit(rng), .theta_rad = 0.2 * unit(rng),
          .a = 0.6 * (unit(rng) - 0.5), .b = 0.6 * (unit(rng) - 0.5)};
      ShotCall call;
      if (state.call_required) call.safety = true;
      add(state, call, balls, placed, strike);
    }
  }
  return set;
}

const ShotSet& Set(GameKind game, int kind) {
  static std::map<std::pair<int, int>, ShotSet>* const cache =
      new std::map<std::pair<int, int>, ShotSet>();
  auto key = std::make_pair(static_cast<int>(game), kind);
  auto it = cache->find(key);
  if (it == cache->end()) it = cache->emplace(key, MakeSet(game, kind)).first;
  return it->second;
}

const char* const kKinds[] = {"break", "aimed", "random"};

GameKind GameArg(int64_t a) { return a == 8 ? GameKind::kEightBall : GameKind::kNineBall; }

void Label(benchmark::State& state, const ShotSet& set) {
  int64_t events = 0;
  for (const JudgedShot& s : set.shots) events += static_cast<int64_t>(s.record.events.size());
  state.SetLabel(absl::StrFormat("%s %s, %d shots", GameName(GameArg(state.range(0))),
                                 kKinds[state.range(1)], set.shots.size()));
  state.counters["events_per_shot"] =
      static_cast<double>(events) / static_cast<double>(set.shots.size());
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(set.shots.size()));
}

// The referee's whole CPU per shot: Judge (ExtractFacts inside), on a copy of the balls at rest
// it may change (respots, a re-rack).
void BM_Referee(benchmark::State& state) {
  const ShotSet& set = Set(GameArg(state.range(0)), static_cast<int>(state.range(1)));
  const TableModel& m = Model();
  TableState balls;
  for (auto _ : state) {
    for (const JudgedShot& s : set.shots) {
      balls = s.record.after;
      Judgement j = set.referee->Judge(set.rules, m, s.state, s.call, s.record, &balls);
      benchmark::DoNotOptimize(j);
    }
  }
  Label(state, set);
}

// ExtractFacts alone (a part of BM_Referee).
void BM_Facts(benchmark::State& state) {
  const ShotSet& set = Set(GameArg(state.range(0)), static_cast<int>(state.range(1)));
  for (auto _ : state) {
    for (const JudgedShot& s : set.shots) {
      ShotFacts f = ExtractFacts(s.record);
      benchmark::DoNotOptimize(f);
    }
  }
  Label(state, set);
}

// The physics of the same shots: SimulateShot from the struck state to rest.
void BM_Physics(benchmark::State& state) {
  const ShotSet& set = Set(GameArg(state.range(0)), static_cast<int>(state.range(1)));
  const TableModel& m = Model();
  for (auto _ : state) {
    for (const JudgedShot& s : set.shots) {
      absl::StatusOr<billiards::ShotResult> r =
          billiards::SimulateShot(m, billiards::SolverOptions{}, s.struck, {});
      benchmark::DoNotOptimize(r);
    }
  }
  Label(state, set);
}

BENCHMARK(BM_Facts)->ArgsProduct({{9, 8}, {0, 1, 2}})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Referee)->ArgsProduct({{9, 8}, {0, 1, 2}})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Physics)->ArgsProduct({{9, 8}, {0, 1, 2}})->Unit(benchmark::kMicrosecond);

// ---------------------------------------------------------------------------------------------
// (b) A whole 9-ball match

struct MatchStats {
  int shots = 0;
  int frames = 0;
  int decisions = 0;
  int placements = 0;
  int fouls = 0;
  int refused_layouts = 0; ///< shots whose final state ValidateLayout refuses
  int nudges = 0;          ///< balls moved back onto the cloth ValidateLayout accepts (Nudge)
  bool cap_hit = false;
  int winner = -1;
  double physics_s = 0.0;  ///< ApplyStrike + SimulateShot
  double referee_s = 0.0;  ///< CheckPlacement/IsFreeSpot, CheckShot, Judge, Decide
  double bot_s = 0.0;      ///< the bot's aim
};

MatchStats PlayNineBallMatch(uint64_t seed) {
  const TableModel& m = Model();
  MatchStats st;
  const double c_start = ThreadCpuSeconds();
  absl::StatusOr<Rules> rules = MakeRules(GameKind::kNineBall, 2);
  if (!rules.ok()) Die("rules", rules.status());
  const Referee& ref = *RefereeFor(GameKind::kNineBall);
  TableState balls;
  absl::StatusOr<GameState> g0 = StartMatch(*rules, m, Start::kBreak, &balls);
  if (!g0.ok()) Die("start", g0.status());
  GameState g = *g0;
  std::mt19937_64 rng(seed);
  const double c_setup = ThreadCpuSeconds();
  st.referee_s += c_setup - c_start;
  while (!g.match_over()) {
    if (st.shots >= kMaxShots) {
      st.cap_hit = true;
      break;
    }
    double c0 = ThreadCpuSeconds();
    if (g.decision.pending()) {
      absl::StatusOr<Judgement> d =
          ref.Decide(*rules, m, g, g.decision.seat, g.decision.choices.front(), &balls);
      if (!d.ok()) Die("decide", d.status());
      g = d->state;
      ++st.decisions;
      st.referee_s += ThreadCpuSeconds() - c0;
      continue;
    }
    st.nudges += Nudge(m, &balls);
    // The bot's choice (its placement search calls the referee's CheckPlacement: counted as
    // the bot's; it is microseconds).
    BotShot b = ChooseShot(ref, *rules, m, g, balls, rng);
    double c1 = ThreadCpuSeconds();
    st.bot_s += c1 - c0;
    c0 = c1;
    const int seat = g.to_play;
    if (b.place) {
      if (absl::Status s = ref.CheckPlacement(*rules, m, g, seat, balls, "cue", *b.place); !s.ok()) {
        Die("placement", s);
      }
      PlaceBall(m, balls.Find("cue"), *b.place, &balls);
      ++st.placements;
    }
    if (absl::Status s = ref.CheckShot(*rules, m, g, seat, b.call, balls); !s.ok()) {
      Die("check shot", s);
    }
    c1 = ThreadCpuSeconds();
    st.referee_s += c1 - c0;
    ShotRecord rec = PlayStrike(m, balls, b.place.has_value(), b.strike, &st.physics_s);
    if (!billiards::ValidateLayout(m, rec.after).ok()) ++st.refused_layouts;  // (not timed)
    c0 = ThreadCpuSeconds();
    TableState after = rec.after;
    Judgement j = ref.Judge(*rules, m, g, b.call, rec, &after);
    st.referee_s += ThreadCpuSeconds() - c0;
    if (j.verdict.foul) ++st.fouls;
    if (j.state.frame != g.frame || j.state.match_over()) ++st.frames;
    g = std::move(j.state);
    balls = std::move(after);
    ++st.shots;
  }
  st.winner = g.winner;
  return st;
}

void Report(benchmark::State& state, const MatchStats& sum, int matches) {
  const double n = static_cast<double>(matches);
  state.counters["matches"] = n;
  state.counters["shots"] = sum.shots / n;
  state.counters["frames"] = sum.frames / n;
  state.counters["fouls"] = sum.fouls / n;
  state.counters["placements"] = sum.placements / n;
  state.counters["decisions"] = sum.decisions / n;
  state.counters["cap_hit"] = sum.cap_hit ? 1 : 0;
  state.counters["nudges"] = sum.nudges / n;
  state.counters["refused_layouts"] = sum.refused_layouts / n;
  state.counters["physics_ms"] = 1e3 * sum.physics_s / n;
  state.counters["referee_ms"] = 1e3 * sum.referee_s / n;
  state.counters["bot_ms"] = 1e3 * sum.bot_s / n;
  state.counters["referee_pct"] =
      100.0 * sum.referee_s / (sum.referee_s + sum.physics_s + sum.bot_s);
  state.counters["referee_us_per_shot"] = 1e6 * sum.referee_s / sum.shots;
  state.counters["physics_us_per_shot"] = 1e6 * sum.physics_s / sum.shots;
}

void Add(MatchStats* sum, const MatchStats& s) {
  sum->shots += s.shots;
  sum->frames += s.frames;
  sum->decisions += s.decisions;
  sum->placements += s.placements;
  sum->fouls += s.fouls;
  sum->nudges += s.nudges;
  sum->refused_layouts += s.refused_layouts;
  sum->cap_hit |= s.cap_hit;
  sum->physics_s += s.physics_s;
  sum->referee_s += s.referee_s;
  sum->bot_s += s.bot_s;
}

void BM_NineBallMatch(benchmark::State& state) {
  const uint64_t seed = static_cast<uint64_t>(state.range(0));
  MatchStats sum;
  int matches = 0;
  int shots = -1;
  for (auto _ : state) {
    MatchStats s = PlayNineBallMatch(seed);
    if (shots >= 0 && s.shots != shots) {
      std::fprintf(stderr, "games_bench: seed %llu not deterministic\n",
                   static_cast<unsigned long long>(seed));
      std::abort();
    }
    shots = s.shots;
    Add(&sum, s);
    ++matches;
  }
  Report(state, sum, matches);
  state.SetItemsProcessed(static_cast<int64_t>(sum.shots));  // shots per second
}
BENCHMARK(BM_NineBallMatch)->DenseRange(1, 4)->Unit(benchmark::kMillisecond);

void BM_NineBallMatches(benchmark::State& state) {
  MatchStats sum;
  int matches = 0;
  int min_shots = kMaxShots + 1, max_shots = 0;
  for (auto _ : state) {
    for (uint64_t seed = 1; seed <= 32; ++seed) {
      MatchStats s = PlayNineBallMatch(seed);
      min_shots = std::min(min_shots, s.shots);
      max_shots = std::max(max_shots, s.shots);
      Add(&sum, s);
      ++matches;
    }
  }
  Report(state, sum, matches);
  state.counters["min_shots"] = min_shots;
  state.counters["max_shots"] = max_shots;
  state.SetLabel("seeds 1..32; counters are per match");
  state.SetItemsProcessed(static_cast<int64_t>(sum.shots));
}
BENCHMARK(BM_NineBallMatches)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace sportsim::games
