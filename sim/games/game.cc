#include "sim/games/game.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <string>

#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "sim/games/table_marks.h"

namespace sportsim::games {
namespace {

constexpr std::array<std::string_view, 6> kGameNames = {"free",    "8ball",   "9ball",
                                                        "10ball",  "snooker", "three-cushion"};
constexpr std::array<std::string_view, 4> kBallInHandNames = {"none", "anywhere", "kitchen", "d"};

// The variants of every game. Sources in the descriptions.
const std::vector<VariantInfo>& Registry() {
  static const std::vector<VariantInfo>* const kVariants = new std::vector<VariantInfo>{
      {.name = "break",
       .games = {"8ball", "9ball", "10ball", "snooker", "three-cushion"},
       .values = {"alternate", "winner"},
       .default_value = "alternate",
       .description = "who breaks the next frame of a match: alternate seats, or the frame's "
                      "winner (WPA leaves it to the event)"},
      {.name = "break_scratch_in_hand",
       .games = {"8ball"},
       .values = {"anywhere", "kitchen"},
       .default_value = "anywhere",
       .description = "cue ball in hand after a scratch on a legal break: anywhere (WPA 2016) "
                      "or behind the head string (older WPA and league rules)"},
      {.name = "eight_first_on_open",
       .games = {"8ball"},
       .values = {"foul", "bca"},
       .default_value = "foul",
       .description = "hitting the 8 first on an open table: a foul (WPA), or legal but the "
                      "turn ends (old BCA)"},
      {.name = "miss_rule",
       .games = {"snooker"},
       .values = {"off", "on"},
       .default_value = "off",
       .description = "WPBSA miss rule, objective part only (a clear line to a ball on); the "
                      "'best ability' judgement is not modelled"},
      {.name = "target",
       .games = {"three-cushion"},
       .values = {},
       .lo = 1,
       .hi = 1000,
       .default_value = "15",
       .description = "points to win a frame (UMB: set by the event)"},
      {.name = "equal_innings",
       .games = {"three-cushion"},
       .values = {"off", "on"},
       .default_value = "off",
       .description = "the opponent of a player who reached the target gets the same number "
                      "of innings; a tie is a draw (UMB)"},
  };
  return *kVariants;
}

// Joins std::string_views (absl::StrJoin takes absl::string_view, a distinct type here).
template <typename Views>
std::string JoinViews(const Views& views) {
  std::string out;
  for (std::string_view v : views) {
    if (!out.empty()) out += ", ";
    out += v;
  }
  return out;
}

bool Applies(const VariantInfo& v, GameKind g) {
  return std::find(v.games.begin(), v.games.end(), GameName(g)) != v.games.end();
}

bool ParseInt(std::string_view s, int* out) {
  if (s.empty()) return false;
  const char* end = s.data() + s.size();
  auto [p, ec] = std::from_chars(s.data(), end, *out);
  return ec == std::errc() && p == end;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Names

std::span<const std::string_view> GameNames() { return kGameNames; }
std::string_view GameName(GameKind g) { return kGameNames[static_cast<size_t>(g)]; }
absl::StatusOr<GameKind> GameFromName(std::string_view name) {
  for (size_t i = 0; i < kGameNames.size(); ++i) {
    if (kGameNames[i] == name) return static_cast<GameKind>(i);
  }
  return absl::InvalidArgumentError(absl::StrFormat(
      "game must be one of %s; got \"%s\"", JoinViews(kGameNames), name));
}

std::string_view BallInHandName(BallInHand b) { return kBallInHandNames[static_cast<size_t>(b)]; }
absl::StatusOr<BallInHand> BallInHandFromName(std::string_view name) {
  for (size_t i = 0; i < kBallInHandNames.size(); ++i) {
    if (kBallInHandNames[i] == name) return static_cast<BallInHand>(i);
  }
  return absl::InvalidArgumentError(absl::StrFormat(
      "ball_in_hand must be one of %s; got \"%s\"", JoinViews(kBallInHandNames), name));
}

std::string_view BreakRotationName(BreakRotation r) {
  return r == BreakRotation::kAlternate ? "alternate" : "winner";
}
std::string_view StartName(Start s) { return s == Start::kBreak ? "break" : "in-play"; }
absl::StatusOr<Start> StartFromName(std::string_view name) {
  if (name == "break") return Start::kBreak;
  if (name == "in-play") return Start::kInPlay;
  return absl::InvalidArgumentError(
      absl::StrFormat("start must be one of break, in-play; got \"%s\"", name));
}

std::string_view GroupName(Group g) {
  switch (g) {
    case Group::kNone: return "";
    case Group::kSolids: return "solids";
    case Group::kStripes: return "stripes";
  }
  return "";
}

std::string_view MatchResultName(MatchResult r) {
  switch (r) {
    case MatchResult::kNone: return "";
    case MatchResult::kWon: return "won";
    case MatchResult::kConceded: return "conceded";
    case MatchResult::kThreeFouls: return "three_fouls";
    case MatchResult::kDraw: return "draw";
    case MatchResult::kAbandoned: return "abandoned";
  }
  return "";
}

std::string_view GameEventKindName(GameEventKind k) {
  switch (k) {
    case GameEventKind::kFoul: return "foul";
    case GameEventKind::kScore: return "score";
    case GameEventKind::kRespot: return "respot";
    case GameEventKind::kDecision: return "decision";
    case GameEventKind::kWarning: return "warning";
    case GameEventKind::kFrameEnd: return "frame_end";
    case GameEventKind::kMatchEnd: return "match_end";
  }
  return "";
}

// ---------------------------------------------------------------------------------------------
// Rules

std::span<const VariantInfo> AllVariants() { return Registry(); }

std::vector<const VariantInfo*> VariantsFor(GameKind g) {
  std::vector<const VariantInfo*> out;
  for (const VariantInfo& v : Registry()) {
    if (Applies(v, g)) out.push_back(&v);
  }
  return out;
}

std::string_view Rules::Variant(std::string_view name) const {
  if (auto it = variants.find(name); it != variants.end()) return it->second;
  for (const VariantInfo& v : Registry()) {
    if (v.name == name && Applies(v, game)) return v.default_value;
  }
  return "";
}

int Rules::VariantInt(std::string_view name) const {
  int out = 0;
  return ParseInt(Variant(name), &out) ? out : 0;
}

absl::Status SetVariant(std::string_view name, std::string_view value, Rules* rules) {
  const VariantInfo* info = nullptr;
  for (const VariantInfo* v : VariantsFor(rules->game)) {
    if (v->name == name) info = v;
  }
  if (info == nullptr) {
    std::vector<std::string_view> names;
    for (const VariantInfo* v : VariantsFor(rules->game)) names.push_back(v->name);
    return absl::InvalidArgumentError(absl::StrFormat(
        "game %s has no rule \"%s\"%s", GameName(rules->game), name,
        names.empty() ? std::string(" (it has no variants)")
                      : absl::StrFormat(" (its rules: %s)", JoinViews(names))));
  }
  if (info->values.empty()) {
    int n = 0;
    if (!ParseInt(value, &n) || n < info->lo || n > info->hi) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "rule %s must be an integer in [%d, %d]; got \"%s\"", name, info->lo, info->hi, value));
    }
  } else if (std::find(info->values.begin(), info->values.end(), value) == info->values.end()) {
    return absl::InvalidArgumentError(absl::StrFormat("rule %s must be one of %s; got \"%s\"",
                                                      name, JoinViews(info->values),
                                                      value));
  }
  rules->variants[std::string(name)] = std::string(value);
  if (name == "break") {
    rules->break_rotation = value == "winner" ? BreakRotation::kWinner : BreakRotation::kAlternate;
  }
  return absl::OkStatus();
}

absl::StatusOr<Rules> MakeRules(GameKind game, int race_to, double shot_clock_s,
                                const std::vector<std::pair<std::string, std::string>>& settings) {
  if (race_to < 1 || race_to > 99) {
    return absl::InvalidArgumentError(
        absl::StrFormat("race_to must be in [1, 99] frames; got %d", race_to));
  }
  if (!std::isfinite(shot_clock_s) || shot_clock_s < 0 || shot_clock_s > 3600) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "shot_clock_s must be in [0, 3600] s (0 = off); got %g", shot_clock_s));
  }
  Rules rules{.game = game, .race_to = race_to, .shot_clock_s = shot_clock_s};
  for (const VariantInfo* v : VariantsFor(game)) {
    rules.variants[std::string(v->name)] = std::string(v->default_value);
  }
  for (const auto& [name, value] : settings) {
    if (absl::Status s = SetVariant(name, value, &rules); !s.ok()) return s;
  }
  return rules;
}

// ---------------------------------------------------------------------------------------------
// Facts

bool ShotFacts::Touched(int ball) const {
  for (const Contact& c : struck_contacts) {
    if (c.ball == ball) return true;
  }
  return false;
}

bool ShotFacts::Pocketed(int ball) const {
  for (const Pocketing& p : pocketed) {
    if (p.ball == ball) return true;
  }
  return false;
}

bool ShotFacts::OffTable(int ball) const {
  for (const Pocketing& p : pocketed) {
    if (p.ball == ball) return p.pocket < 0;
  }
  return false;
}

int ShotFacts::PocketOf(int ball) const {
  for (const Pocketing& p : pocketed) {
    if (p.ball == ball) return p.pocket;
  }
  return -1;
}

int ShotFacts::CushionHits(int ball) const {
  if (ball < 0 || ball >= static_cast<int>(cushion_t_s.size())) return 0;
  return static_cast<int>(cushion_t_s[ball].size());
}

int ShotFacts::CushionHitsBefore(int ball, double t_s) const {
  if (ball < 0 || ball >= static_cast<int>(cushion_t_s.size())) return 0;
  int n = 0;
  for (double t : cushion_t_s[ball]) n += t < t_s;
  return n;
}

bool ShotFacts::AnyCushionAtOrAfter(double t_s) const {
  for (const std::vector<double>& times : cushion_t_s) {
    for (double t : times) {
      if (t >= t_s - kSimultaneousS) return true;
    }
  }
  return false;
}

int ShotFacts::BallsReachingCushion(int except) const {
  int n = 0;
  for (size_t i = 0; i < cushion_t_s.size(); ++i) {
    n += static_cast<int>(i) != except && !cushion_t_s[i].empty();
  }
  return n;
}

ShotFacts ExtractFacts(const TableState& before, int struck,
                       std::span<const billiards::Event> events) {
  ShotRecord record;
  record.struck = struck;
  record.before = before;
  record.events.assign(events.begin(), events.end());
  return ExtractFacts(record);
}

ShotFacts ExtractFacts(const ShotRecord& record) {
  ShotFacts f;
  f.struck = record.struck;
  const size_t n = std::max(record.before.balls.size(), record.after.balls.size());
  f.cushion_t_s.resize(n);
  if (f.struck >= 0 && f.struck < static_cast<int>(record.before.balls.size())) {
    f.struck_path.push_back(record.before.balls[f.struck].r.head<2>());
  }
  for (const billiards::Event& e : record.events) {
    if (e.a == f.struck && e.kind != billiards::EventKind::kBallBall &&
        f.first_contacts.empty()) {
      f.struck_path.push_back(e.ra);
    }
    switch (e.kind) {
      case billiards::EventKind::kBallBall: {
        if (e.a != f.struck && e.b != f.struck) break;
        const int other = e.a == f.struck ? e.b : e.a;
        if (f.first_contacts.empty()) {
          f.first_contact_t_s = e.t_s;
          f.first_contacts.push_back(other);
        } else if (e.t_s - f.first_contact_t_s <= kSimultaneousS &&
                   std::find(f.first_contacts.begin(), f.first_contacts.end(), other) ==
                       f.first_contacts.end()) {
          f.first_contacts.push_back(other);
        }
        if (!f.Touched(other)) {
          f.struck_contacts.push_back(
              {.ball = other, .t_s = e.t_s,
               .struck_cushions_before = f.CushionHitsBefore(f.struck, e.t_s)});
        }
        break;
      }
      case billiards::EventKind::kBallCushion:
        if (e.a >= 0 && e.a < static_cast<int>(n)) {
          f.cushion_t_s[e.a].push_back(e.t_s);
        }
        break;
      case billiards::EventKind::kBallPocket:
        if (!f.Pocketed(e.a)) f.pocketed.push_back({.ball = e.a, .pocket = e.other, .t_s = e.t_s});
        break;
      case billiards::EventKind::kTransition:
        break;
    }
  }
  std::sort(f.first_contacts.begin(), f.first_contacts.end());
  return f;
}

// ---------------------------------------------------------------------------------------------
// Placement and respotting

void PlaceBall(const TableModel& model, int index, Eigen::Vector2d xy, TableState* balls) {
  billiards::Ball& b = balls->balls[index];
  b.r = Eigen::Vector3d(xy.x(), xy.y(), model.radius());
  b.v.setZero();
  b.w.setZero();
  b.state = billiards::MotionState::kStationary;
  b.pocket = -1;
}

namespace {

// Distance from p to the segment [a, b] (m).
double SegmentDistance(Eigen::Vector2d p, Eigen::Vector2d a, Eigen::Vector2d b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

// The t >= 0 where the ray p0 + t dir is `dist` from c.
void CircleCrossings(Eigen::Vector2d p0, Eigen::Vector2d dir, Eigen::Vector2d c, double dist,
                     std::vector<double>* out) {
  const Eigen::Vector2d p = p0 - c;
  const double b = p.dot(dir);
  const double disc = b * b - (p.squaredNorm() - dist * dist);
  if (disc < 0) return;
  const double s = std::sqrt(disc);
  for (double t : {-b - s, -b + s}) {
    if (t >= 0) out->push_back(t);
  }
}

// The nearest free point on one ray, if any.
bool SearchRay(const TableModel& model, const TableState& balls, int index, Eigen::Vector2d spot,
               Eigen::Vector2d dir, Eigen::Vector2d* found) {
  const double d = 2.0 * model.radius();
  std::vector<double> ts = {0.0};
  for (size_t i = 0; i < balls.balls.size(); ++i) {
    const billiards::Ball& b = balls.balls[i];
    if (static_cast<int>(i) == index || b.state == billiards::MotionState::kPocketed) continue;
    // A little beyond the free distance, so rounding cannot put the candidate inside it.
    CircleCrossings(spot, dir, b.r.head<2>(), d + 1.5 * kSpotGapM, &ts);
  }
  for (const billiards::Pocket& p : model.spec().pockets) {
    CircleCrossings(spot, dir, p.centre, p.radius_m + kSpotGapM, &ts);
  }
  std::sort(ts.begin(), ts.end());
  for (double t : ts) {
    const Eigen::Vector2d xy = spot + t * dir;
    if (!OnCloth(model, xy)) break;
    if (IsFreeSpot(model, balls, index, xy)) {
      *found = xy;
      return true;
    }
  }
  return false;
}

}  // namespace

bool IsFreeSpot(const TableModel& model, const TableState& balls, int index, Eigen::Vector2d xy) {
  if (!OnCloth(model, xy)) return false;
  for (const billiards::Pocket& p : model.spec().pockets) {
    if ((xy - p.centre).norm() <= p.radius_m) return false;
  }
  for (const billiards::CushionSegment& c : model.spec().cushions) {
    if (SegmentDistance(xy, c.a, c.b) < model.cushion_contact_distance() - 1e-12) return false;
  }
  const double d = 2.0 * model.radius() + kSpotGapM;
  for (size_t i = 0; i < balls.balls.size(); ++i) {
    const billiards::Ball& b = balls.balls[i];
    if (static_cast<int>(i) == index || b.state == billiards::MotionState::kPocketed) continue;
    if ((b.r.head<2>() - xy).norm() < d) return false;
  }
  return true;
}

absl::StatusOr<Eigen::Vector2d> FindSpotOnLine(const TableModel& model, const TableState& balls,
                                               int index, Eigen::Vector2d spot,
                                               Eigen::Vector2d dir) {
  Eigen::Vector2d found;
  if (SearchRay(model, balls, index, spot, dir, &found)) return found;
  if (SearchRay(model, balls, index, spot, -dir, &found)) return found;
  return absl::NotFoundError(absl::StrFormat(
      "no free place for ball %s on the line through (%.3f, %.3f)",
      index >= 0 && index < static_cast<int>(balls.balls.size()) ? balls.balls[index].id : "?",
      spot.x(), spot.y()));
}

// ---------------------------------------------------------------------------------------------
// Referee defaults

absl::Status Referee::CheckShot(const Rules& rules, const TableModel& model,
                                const GameState& state, int seat, const ShotCall& call,
                                const TableState& balls) const {
  (void)rules;
  (void)model;
  (void)call;
  if (seat != 0 && seat != 1) {
    return absl::InvalidArgumentError(absl::StrFormat("seat must be 0 or 1; got %d", seat));
  }
  if (state.match_over()) {
    return absl::FailedPreconditionError(
        absl::StrFormat("the match is over (%s)", MatchResultName(state.result)));
  }
  if (state.decision.pending()) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "a decision is pending: seat %d must choose one of %s first", state.decision.seat,
        absl::StrJoin(state.decision.choices, ", ")));
  }
  if (seat != state.to_play) {
    return absl::FailedPreconditionError(
        absl::StrFormat("not your turn: seat %d is to play", state.to_play));
  }
  if (state.ball_in_hand != BallInHand::kNone) {
    const int cue = balls.Find("cue");
    if (cue >= 0 && balls.balls[cue].state == billiards::MotionState::kPocketed) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "ball in hand (%s): place the cue ball before shooting",
          BallInHandName(state.ball_in_hand)));
    }
  }
  return absl::OkStatus();
}

bool Referee::InZone(const TableModel& model, BallInHand zone, Eigen::Vector2d xy) const {
  switch (zone) {
    case BallInHand::kAnywhere: return OnCloth(model, xy);
    case BallInHand::kKitchen: return OnCloth(model, xy) && BehindHeadString(model, xy);
    case BallInHand::kNone:
    case BallInHand::kD: return false;
  }
  return false;
}

absl::Status Referee::CheckPlacement(const Rules& rules, const TableModel& model,
                                     const GameState& state, int seat, const TableState& balls,
                                     const std::string& ball_id, Eigen::Vector2d xy) const {
  (void)rules;
  if (state.match_over()) return absl::FailedPreconditionError("the match is over");
  if (state.decision.pending()) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "a decision is pending: seat %d must choose one of %s first", state.decision.seat,
        absl::StrJoin(state.decision.choices, ", ")));
  }
  if (seat != state.to_play) {
    return absl::FailedPreconditionError(
        absl::StrFormat("not your turn: seat %d is to play", state.to_play));
  }
  if (state.ball_in_hand == BallInHand::kNone) {
    return absl::FailedPreconditionError(
        "no ball in hand: the cue ball is played from where it lies");
  }
  if (ball_id != "cue") {
    return absl::InvalidArgumentError(
        absl::StrFormat("ball in hand: only the cue ball may be placed, not \"%s\"", ball_id));
  }
  const int cue = balls.Find("cue");
  if (cue < 0) return absl::InvalidArgumentError("the table has no cue ball");
  if (!InZone(model, state.ball_in_hand, xy)) {
    if (state.ball_in_hand == BallInHand::kKitchen) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "ball in hand behind the head string: x must be <= %.4f m and on the cloth; got "
          "(%.4f, %.4f)",
          PoolTableMarks(model).head_string_x, xy.x(), xy.y()));
    }
    return absl::InvalidArgumentError(
        absl::StrFormat("ball in hand (%s): (%.4f, %.4f) is outside the zone",
                        BallInHandName(state.ball_in_hand), xy.x(), xy.y()));
  }
  if (!IsFreeSpot(model, balls, cue, xy)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "ball in hand: (%.4f, %.4f) touches another ball, a cushion or a pocket", xy.x(), xy.y()));
  }
  return absl::OkStatus();
}

absl::StatusOr<Judgement> Referee::Concede(const Rules& rules, const TableModel& model,
                                           const GameState& state, int seat,
                                           TableState* balls) const {
  if (seat != 0 && seat != 1) {
    return absl::InvalidArgumentError(absl::StrFormat("seat must be 0 or 1; got %d", seat));
  }
  if (state.match_over()) return absl::FailedPreconditionError("the match is over");
  Judgement j;
  j.state = state;
  j.verdict.reason = "conceded";
  j.verdict.frame_over = true;
  if (absl::Status s = EndFrame(*this, rules, model, Other(seat), "conceded",
                                MatchResult::kConceded, &j.state, balls, &j.events);
      !s.ok()) {
    return s;
  }
  return j;
}

// ---------------------------------------------------------------------------------------------
// Dispatch and the match

const Referee* RefereeFor(GameKind game) {
  switch (game) {
    case GameKind::kFree: return nullptr;
    case GameKind::kEightBall: return &EightBallReferee();
    case GameKind::kNineBall: return &NineBallReferee();
    case GameKind::kTenBall: return &TenBallReferee();
    case GameKind::kSnooker:
#ifdef SPORTSIM_GAMES_HAS_SNOOKER
      return &SnookerReferee();
#else
      return nullptr;
#endif
    case GameKind::kThreeCushion:
#ifdef SPORTSIM_GAMES_HAS_THREE_CUSHION
      return &ThreeCushionReferee();
#else
      return nullptr;
#endif
  }
  return nullptr;
}

absl::StatusOr<GameState> StartMatch(const Rules& rules, const TableModel& model, Start start,
                                     TableState* balls) {
  const Referee* referee = RefereeFor(rules.game);
  if (referee == nullptr) {
    return absl::InvalidArgumentError(
        absl::StrFormat("game %s has no referee", GameName(rules.game)));
  }
  GameState state;
  state.game = rules.game;
  state.race_to = rules.race_to;
  state.frame = 1;
  state.breaker = 0;
  state.to_play = 0;
  absl::Status s = start == Start::kBreak
                       ? referee->RackFrame(rules, model, &state, balls)
                       : referee->SetUpInPlay(rules, model, *balls, &state);
  if (!s.ok()) return s;
  return state;
}

absl::Status EndFrame(const Referee& referee, const Rules& rules, const TableModel& model,
                      int winner, std::string_view reason, MatchResult result, GameState* state,
                      TableState* balls, std::vector<GameEvent>* events) {
  events->push_back({.kind = GameEventKind::kFrameEnd, .seat = winner,
                     .reason = std::string(reason), .winner = winner});
  ++state->frames_won[winner];
  state->decision = Decision{};
  state->pushed_out = false;
  state->push_out_available = false;
  if (state->frames_won[winner] >= state->race_to) {
    state->result = result;
    state->winner = winner;
    state->ball_in_hand = BallInHand::kNone;
    state->call_required = false;
    state->on.clear();
    events->push_back({.kind = GameEventKind::kMatchEnd, .seat = winner,
                       .reason = std::string(MatchResultName(result)), .winner = winner});
    return absl::OkStatus();
  }
  // The next frame: per-frame bookkeeping cleared, then the game's rack.
  ++state->frame;
  state->breaker =
      rules.break_rotation == BreakRotation::kWinner ? winner : Other(state->breaker);
  state->to_play = state->breaker;
  state->scores = {};
  state->fouls_in_row = {};
  state->warned = {};
  state->groups = {};
  state->innings = {};
  state->phase.clear();
  state->nominated.clear();
  state->free_ball = false;
  state->misses_in_row = 0;
  state->replay_position = TableState{};
  state->is_break = true;
  return referee.RackFrame(rules, model, state, balls);
}

void EndMatchDraw(GameState* state, std::vector<GameEvent>* events) {
  state->result = MatchResult::kDraw;
  state->winner = -1;
  state->decision = Decision{};
  events->push_back({.kind = GameEventKind::kMatchEnd, .seat = -1,
                     .reason = std::string(MatchResultName(MatchResult::kDraw)), .winner = -1});
}

}  // namespace sportsim::games
