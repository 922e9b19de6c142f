#include "server/billiards/game_convert.h"

#include <algorithm>
#include <map>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "server/world/world.h"
#include "sim/core/check.h"

namespace sportsim::server {

namespace g = ::sportsim::games;

absl::StatusOr<GameSetup> GameSetupFromProto(const v1::GameConfig& game) {
  GameSetup setup;
  if (!game.name().empty()) {
    if (absl::Status s = CheckId("game.name", game.name()); !s.ok()) return s;
  }
  if (!game.start().empty()) {
    if (absl::Status s = CheckId("game.start", game.start()); !s.ok()) return s;
  }
  const std::string name = game.name().empty() ? "free" : game.name();
  absl::StatusOr<g::GameKind> kind = g::GameFromName(name);
  if (!kind.ok()) return PrefixStatus("game.name: ", kind.status());
  if (game.race_to() > 99) {
    return absl::InvalidArgumentError(
        absl::StrFormat("game.race_to must be in [1, 99] (0: 1), got %d", game.race_to()));
  }
  if (absl::Status s = CheckFiniteInRange("game.shot_clock_s", game.shot_clock_s(), 0, false,
                                          3600, false);
      !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckFiniteInRange("game.noise", game.noise(), 0, false, 100, false);
      !s.ok()) {
    return s;
  }
  const std::string start = game.start().empty() ? "break" : game.start();
  absl::StatusOr<g::Start> st = g::StartFromName(start);
  if (!st.ok()) return PrefixStatus("game.start: ", st.status());
  if (*kind == g::GameKind::kFree &&
      (game.race_to() > 1 || game.shot_clock_s() > 0 || !game.start().empty() ||
       game.rules_size() > 0 || game.noise() > 0 || game.has_seed())) {
    return absl::InvalidArgumentError(
        "game: race_to, shot_clock_s, start, rules, noise and seed apply to ruled games, not to "
        "free play");
  }
  // Variants in name order, so the first error reported does not depend on map order.
  std::vector<std::pair<std::string, std::string>> settings(game.rules().begin(),
                                                            game.rules().end());
  std::sort(settings.begin(), settings.end());
  for (const auto& [k, v] : settings) {
    if (absl::Status s = CheckId("game.rules key", k); !s.ok()) return s;
    if (absl::Status s = CheckId(absl::StrFormat("game.rules[%s]", k), v); !s.ok()) return s;
  }
  absl::StatusOr<g::Rules> rules = g::MakeRules(
      *kind, game.race_to() == 0 ? 1 : static_cast<int>(game.race_to()), game.shot_clock_s(),
      settings);
  if (!rules.ok()) return PrefixStatus("game.rules: ", rules.status());
  setup.rules = *std::move(rules);
  setup.start = *st;
  setup.noise = game.noise();
  if (game.has_seed()) setup.seed = game.seed();
  return setup;
}

std::string GamePreset(g::GameKind game) {
  switch (game) {
    case g::GameKind::kSnooker: return "snooker";
    case g::GameKind::kThreeCushion: return "carom";
    default: return "pool-9ft";
  }
}

std::string GameRack(g::GameKind game) {
  switch (game) {
    case g::GameKind::kEightBall: return "8ball";
    case g::GameKind::kNineBall: return "9ball";
    case g::GameKind::kTenBall: return "10ball";
    case g::GameKind::kSnooker: return "snooker";
    case g::GameKind::kThreeCushion: return "three-cushion";
    case g::GameKind::kFree: break;
  }
  return "";
}

absl::StatusOr<g::ShotCall> ShotCallFromProto(const v1::ShotCall& call) {
  for (const auto& [field, value] : {std::pair{"call.ball", &call.ball()},
                                     std::pair{"call.pocket", &call.pocket()},
                                     std::pair{"call.nominate", &call.nominate()}}) {
    if (value->empty()) continue;
    if (absl::Status s = CheckId(field, *value); !s.ok()) return s;
  }
  return g::ShotCall{.ball = call.ball(),
                     .pocket = call.pocket(),
                     .safety = call.safety(),
                     .push_out = call.push_out(),
                     .nominate = call.nominate()};
}

void ShotCallToProto(const g::ShotCall& call, v1::ShotCall* out) {
  out->set_ball(call.ball);
  out->set_pocket(call.pocket);
  out->set_safety(call.safety);
  out->set_push_out(call.push_out);
  out->set_nominate(call.nominate);
}

void VerdictToProto(const g::Verdict& verdict, v1::Verdict* out) {
  out->set_foul(verdict.foul);
  out->set_reason(verdict.reason);
  out->set_points(verdict.points);
  out->set_turn_passes(verdict.turn_passes);
  for (const std::string& id : verdict.respotted) out->add_respotted(id);
  out->set_frame_over(verdict.frame_over);
}

void GameStateToProto(const g::GameState& s, std::optional<double> deadline_s,
                      v1::GameState* out) {
  const bool pool = s.game == g::GameKind::kEightBall || s.game == g::GameKind::kNineBall ||
                    s.game == g::GameKind::kTenBall;
  const bool rotation = s.game == g::GameKind::kNineBall || s.game == g::GameKind::kTenBall;
  const bool points = s.game == g::GameKind::kSnooker || s.game == g::GameKind::kThreeCushion;
  out->set_name(std::string(g::GameName(s.game)));
  out->set_frame(static_cast<uint32_t>(s.frame));
  out->set_race_to(static_cast<uint32_t>(s.race_to));
  for (int w : s.frames_won) out->add_frames_won(static_cast<uint32_t>(w));
  out->set_to_play(static_cast<uint32_t>(s.to_play));
  if (s.game != g::GameKind::kThreeCushion) {
    out->set_ball_in_hand(std::string(g::BallInHandName(s.ball_in_hand)));
  }
  for (const std::string& id : s.on) out->add_on(id);
  if (s.game == g::GameKind::kEightBall) {
    for (int seat = 0; seat < 2; ++seat) {
      if (s.groups[static_cast<size_t>(seat)] != g::Group::kNone) {
        (*out->mutable_groups())[absl::StrFormat("%d", seat)] =
            std::string(g::GroupName(s.groups[static_cast<size_t>(seat)]));
      }
    }
  }
  if (points) {
    for (int p : s.scores) out->add_scores(p);
  }
  if (pool || s.game == g::GameKind::kSnooker) {
    for (int f : s.fouls_in_row) out->add_fouls_in_row(static_cast<uint32_t>(f));
  }
  if (rotation) {
    for (bool w : s.warned) out->add_warned(w);
    out->set_push_out_available(s.push_out_available);
  }
  if (s.game != g::GameKind::kThreeCushion) out->set_call_required(s.call_required);
  if (s.decision.pending()) {
    out->mutable_decision()->set_seat(static_cast<uint32_t>(s.decision.seat));
    for (const std::string& c : s.decision.choices) out->mutable_decision()->add_choices(c);
  }
  if (s.match_over() && s.winner >= 0) out->set_winner(static_cast<uint32_t>(s.winner));
  if (s.match_over()) out->set_result(std::string(g::MatchResultName(s.result)));
  if (deadline_s.has_value()) out->set_shot_clock_deadline_s(*deadline_s);
  out->set_breaker(static_cast<uint32_t>(s.breaker));
  out->set_is_break(s.is_break);
  if (s.game == g::GameKind::kThreeCushion) {
    for (int i : s.innings) out->add_innings(static_cast<uint32_t>(i));
  }
  if (s.game == g::GameKind::kSnooker) {
    out->set_phase(s.phase);
    out->set_free_ball(s.free_ball);
  }
  out->set_shot(static_cast<uint32_t>(s.shot));
}

v1::TableEvent GameEventToProto(const g::GameEvent& e, double t_s, uint64_t shot_id) {
  v1::TableEvent out;
  switch (e.kind) {
    case g::GameEventKind::kFoul: out.set_kind(v1::foul); break;
    case g::GameEventKind::kScore: out.set_kind(v1::score); break;
    case g::GameEventKind::kRespot: out.set_kind(v1::respot); break;
    case g::GameEventKind::kDecision: out.set_kind(v1::decision); break;
    case g::GameEventKind::kWarning: out.set_kind(v1::warning); break;
    case g::GameEventKind::kFrameEnd: out.set_kind(v1::frame_end); break;
    case g::GameEventKind::kMatchEnd: out.set_kind(v1::match_end); break;
  }
  out.set_t_s(t_s);
  out.set_shot_id(shot_id);
  if (e.seat >= 0) out.set_seat(static_cast<uint32_t>(e.seat));
  out.set_reason(e.reason);
  out.set_points(e.points);
  if (e.winner >= 0) out.set_winner(static_cast<uint32_t>(e.winner));
  if (!e.ball.empty()) out.add_balls(e.ball);
  for (const std::string& c : e.choices) out.add_choices(c);
  return out;
}

void GamesToProto(google::protobuf::RepeatedPtrField<v1::GameInfo>* out) {
  for (size_t i = 0; i < g::GameNames().size(); ++i) {
    const auto kind = static_cast<g::GameKind>(i);
    v1::GameInfo* info = out->Add();
    info->set_name(std::string(g::GameName(kind)));
    info->set_default_rack(GameRack(kind));
    for (const g::VariantInfo* v : g::VariantsFor(kind)) {
      v1::GameVariant* p = info->add_variants();
      p->set_name(std::string(v->name));
      for (std::string_view value : v->values) p->add_values(std::string(value));
      p->set_min(v->lo);
      p->set_max(v->hi);
      p->set_default_value(std::string(v->default_value));
      p->set_description(std::string(v->description));
    }
  }
}

}  // namespace sportsim::server
