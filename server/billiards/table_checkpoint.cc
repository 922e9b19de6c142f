#include "server/billiards/table_checkpoint.h"

#include <array>
#include <optional>
#include <vector>

#include "absl/strings/str_format.h"
#include "server/world/checkpoint_codec.h"
#include "sportsim/store/v1/table_state.pb.h"

namespace sportsim::server {

namespace b = ::sportsim::billiards;
namespace g = ::sportsim::games;
namespace st = ::sportsim::store::v1;

namespace {

// ---------------------------------------------------------------------------------------------
// Errors. Every message starts with "table checkpoint: " and names the field by its path in
// TableRestState ("record[3].applied.v"); the framing is checkpoint_codec.h's.

using checkpoint::Differ;
using checkpoint::Index;
using checkpoint::Member;

constexpr std::string_view kWhat = "table checkpoint: ";

absl::Status Corrupt(std::string_view path, std::string_view what) {
  return checkpoint::Corrupt(kWhat, path, what);
}

absl::Status Missing(std::string_view path) { return Corrupt(path, "missing"); }

// ---------------------------------------------------------------------------------------------
// Enums: the stored numbers are table_state.proto's, mapped value by value (no default case,
// so that -Wswitch names a value added to a C++ enum and not mapped here). A value outside its
// C++ enum is written as -1, which no reader accepts.

st::Ball::MotionState MotionStateToProto(b::MotionState s) {
  switch (s) {
    case b::MotionState::kStationary: return st::Ball::MOTION_STATE_STATIONARY;
    case b::MotionState::kSpinning: return st::Ball::MOTION_STATE_SPINNING;
    case b::MotionState::kSliding: return st::Ball::MOTION_STATE_SLIDING;
    case b::MotionState::kRolling: return st::Ball::MOTION_STATE_ROLLING;
    case b::MotionState::kAirborne: return st::Ball::MOTION_STATE_AIRBORNE;
    case b::MotionState::kPocketed: return st::Ball::MOTION_STATE_POCKETED;
  }
  return static_cast<st::Ball::MotionState>(-1);
}

absl::StatusOr<b::MotionState> MotionStateFromProto(int v, std::string_view path) {
  switch (v) {
    case st::Ball::MOTION_STATE_STATIONARY: return b::MotionState::kStationary;
    case st::Ball::MOTION_STATE_SPINNING: return b::MotionState::kSpinning;
    case st::Ball::MOTION_STATE_SLIDING: return b::MotionState::kSliding;
    case st::Ball::MOTION_STATE_ROLLING: return b::MotionState::kRolling;
    case st::Ball::MOTION_STATE_AIRBORNE: return b::MotionState::kAirborne;
    case st::Ball::MOTION_STATE_POCKETED: return b::MotionState::kPocketed;
    default: return Corrupt(path, absl::StrFormat("unknown motion state %d", v));
  }
}

st::GameState::GameKind GameKindToProto(g::GameKind k) {
  switch (k) {
    case g::GameKind::kFree: return st::GameState::GAME_KIND_FREE;
    case g::GameKind::kEightBall: return st::GameState::GAME_KIND_EIGHT_BALL;
    case g::GameKind::kNineBall: return st::GameState::GAME_KIND_NINE_BALL;
    case g::GameKind::kTenBall: return st::GameState::GAME_KIND_TEN_BALL;
    case g::GameKind::kSnooker: return st::GameState::GAME_KIND_SNOOKER;
    case g::GameKind::kThreeCushion: return st::GameState::GAME_KIND_THREE_CUSHION;
  }
  return static_cast<st::GameState::GameKind>(-1);
}

absl::StatusOr<g::GameKind> GameKindFromProto(int v, std::string_view path) {
  switch (v) {
    case st::GameState::GAME_KIND_FREE: return g::GameKind::kFree;
    case st::GameState::GAME_KIND_EIGHT_BALL: return g::GameKind::kEightBall;
    case st::GameState::GAME_KIND_NINE_BALL: return g::GameKind::kNineBall;
    case st::GameState::GAME_KIND_TEN_BALL: return g::GameKind::kTenBall;
    case st::GameState::GAME_KIND_SNOOKER: return g::GameKind::kSnooker;
    case st::GameState::GAME_KIND_THREE_CUSHION: return g::GameKind::kThreeCushion;
    default: return Corrupt(path, absl::StrFormat("unknown game %d", v));
  }
}

st::GameState::BallInHand BallInHandToProto(g::BallInHand h) {
  switch (h) {
    case g::BallInHand::kNone: return st::GameState::BALL_IN_HAND_NONE;
    case g::BallInHand::kAnywhere: return st::GameState::BALL_IN_HAND_ANYWHERE;
    case g::BallInHand::kKitchen: return st::GameState::BALL_IN_HAND_KITCHEN;
    case g::BallInHand::kD: return st::GameState::BALL_IN_HAND_D;
  }
  return static_cast<st::GameState::BallInHand>(-1);
}

absl::StatusOr<g::BallInHand> BallInHandFromProto(int v, std::string_view path) {
  switch (v) {
    case st::GameState::BALL_IN_HAND_NONE: return g::BallInHand::kNone;
    case st::GameState::BALL_IN_HAND_ANYWHERE: return g::BallInHand::kAnywhere;
    case st::GameState::BALL_IN_HAND_KITCHEN: return g::BallInHand::kKitchen;
    case st::GameState::BALL_IN_HAND_D: return g::BallInHand::kD;
    default: return Corrupt(path, absl::StrFormat("unknown ball in hand %d", v));
  }
}

st::GameState::Group GroupToProto(g::Group group) {
  switch (group) {
    case g::Group::kNone: return st::GameState::GROUP_NONE;
    case g::Group::kSolids: return st::GameState::GROUP_SOLIDS;
    case g::Group::kStripes: return st::GameState::GROUP_STRIPES;
  }
  return static_cast<st::GameState::Group>(-1);
}

absl::StatusOr<g::Group> GroupFromProto(int v, std::string_view path) {
  switch (v) {
    case st::GameState::GROUP_NONE: return g::Group::kNone;
    case st::GameState::GROUP_SOLIDS: return g::Group::kSolids;
    case st::GameState::GROUP_STRIPES: return g::Group::kStripes;
    default: return Corrupt(path, absl::StrFormat("unknown group %d", v));
  }
}

st::GameState::MatchResult MatchResultToProto(g::MatchResult r) {
  switch (r) {
    case g::MatchResult::kNone: return st::GameState::MATCH_RESULT_NONE;
    case g::MatchResult::kWon: return st::GameState::MATCH_RESULT_WON;
    case g::MatchResult::kConceded: return st::GameState::MATCH_RESULT_CONCEDED;
    case g::MatchResult::kThreeFouls: return st::GameState::MATCH_RESULT_THREE_FOULS;
    case g::MatchResult::kDraw: return st::GameState::MATCH_RESULT_DRAW;
    case g::MatchResult::kAbandoned: return st::GameState::MATCH_RESULT_ABANDONED;
  }
  return static_cast<st::GameState::MatchResult>(-1);
}

absl::StatusOr<g::MatchResult> MatchResultFromProto(int v, std::string_view path) {
  switch (v) {
    case st::GameState::MATCH_RESULT_NONE: return g::MatchResult::kNone;
    case st::GameState::MATCH_RESULT_WON: return g::MatchResult::kWon;
    case st::GameState::MATCH_RESULT_CONCEDED: return g::MatchResult::kConceded;
    case st::GameState::MATCH_RESULT_THREE_FOULS: return g::MatchResult::kThreeFouls;
    case st::GameState::MATCH_RESULT_DRAW: return g::MatchResult::kDraw;
    case st::GameState::MATCH_RESULT_ABANDONED: return g::MatchResult::kAbandoned;
    default: return Corrupt(path, absl::StrFormat("unknown match result %d", v));
  }
}

st::MatchEntry::Kind EntryKindToProto(MatchEntry::Kind k) {
  switch (k) {
    case MatchEntry::Kind::kShoot: return st::MatchEntry::KIND_SHOOT;
    case MatchEntry::Kind::kPlace: return st::MatchEntry::KIND_PLACE;
    case MatchEntry::Kind::kDecide: return st::MatchEntry::KIND_DECIDE;
    case MatchEntry::Kind::kConcede: return st::MatchEntry::KIND_CONCEDE;
    case MatchEntry::Kind::kShotClock: return st::MatchEntry::KIND_SHOT_CLOCK;
    case MatchEntry::Kind::kReset: return st::MatchEntry::KIND_RESET;
  }
  return static_cast<st::MatchEntry::Kind>(-1);
}

absl::StatusOr<MatchEntry::Kind> EntryKindFromProto(int v, std::string_view path) {
  switch (v) {
    case st::MatchEntry::KIND_SHOOT: return MatchEntry::Kind::kShoot;
    case st::MatchEntry::KIND_PLACE: return MatchEntry::Kind::kPlace;
    case st::MatchEntry::KIND_DECIDE: return MatchEntry::Kind::kDecide;
    case st::MatchEntry::KIND_CONCEDE: return MatchEntry::Kind::kConcede;
    case st::MatchEntry::KIND_SHOT_CLOCK: return MatchEntry::Kind::kShotClock;
    case st::MatchEntry::KIND_RESET: return MatchEntry::Kind::kReset;
    default: return Corrupt(path, absl::StrFormat("unknown entry kind %d", v));
  }
}

// ---------------------------------------------------------------------------------------------
// Encoding.

void Vec3ToProto(const Eigen::Vector3d& v, st::Vec3* out) {
  out->set_x(v.x());
  out->set_y(v.y());
  out->set_z(v.z());
}

void BallToProto(const b::Ball& ball, st::Ball* out) {
  out->set_id(ball.id);
  Vec3ToProto(ball.r, out->mutable_r());
  Vec3ToProto(ball.v, out->mutable_v());
  Vec3ToProto(ball.w, out->mutable_w());
  st::Quaternion* q = out->mutable_q();
  q->set_w(ball.q.w());
  q->set_x(ball.q.x());
  q->set_y(ball.q.y());
  q->set_z(ball.q.z());
  out->set_state(MotionStateToProto(ball.state));
  out->set_pocket(ball.pocket);
}

void TableStateToProto(const b::TableState& s, st::TableState* out) {
  for (const b::Ball& ball : s.balls) BallToProto(ball, out->add_balls());
  out->set_t_s(s.t_s);
}

void CallToProto(const g::ShotCall& call, st::ShotCall* out) {
  out->set_ball(call.ball);
  out->set_pocket(call.pocket);
  out->set_safety(call.safety);
  out->set_push_out(call.push_out);
  out->set_nominate(call.nominate);
}

void VerdictToProto(const g::Verdict& v, st::Verdict* out) {
  out->set_foul(v.foul);
  out->set_reason(v.reason);
  out->set_points(v.points);
  out->set_turn_passes(v.turn_passes);
  for (const std::string& id : v.respotted) out->add_respotted(id);
  out->set_frame_over(v.frame_over);
}

void GameStateToProto(const g::GameState& s, st::GameState* out) {
  out->set_game(GameKindToProto(s.game));
  out->set_frame(s.frame);
  out->set_race_to(s.race_to);
  for (int n : s.frames_won) out->add_frames_won(n);
  out->set_to_play(s.to_play);
  out->set_ball_in_hand(BallInHandToProto(s.ball_in_hand));
  for (const std::string& id : s.on) out->add_on(id);
  for (g::Group group : s.groups) out->add_groups(GroupToProto(group));
  for (int n : s.scores) out->add_scores(n);
  for (int n : s.fouls_in_row) out->add_fouls_in_row(n);
  for (bool w : s.warned) out->add_warned(w);
  out->set_call_required(s.call_required);
  out->set_push_out_available(s.push_out_available);
  st::Decision* d = out->mutable_decision();
  d->set_seat(s.decision.seat);
  for (const std::string& c : s.decision.choices) d->add_choices(c);
  out->set_winner(s.winner);
  out->set_result(MatchResultToProto(s.result));
  out->set_breaker(s.breaker);
  out->set_is_break(s.is_break);
  out->set_shot(s.shot);
  for (int n : s.innings) out->add_innings(n);
  out->set_last_shooter(s.last_shooter);
  out->set_pushed_out(s.pushed_out);
  out->set_phase(s.phase);
  out->set_nominated(s.nominated);
  out->set_free_ball(s.free_ball);
  out->set_misses_in_row(s.misses_in_row);
  TableStateToProto(s.replay_position, out->mutable_replay_position());
  out->set_opening(s.opening);
  out->set_replay_phase(s.replay_phase);
  out->set_seed(s.seed);
}

void StrikeOutcomeToProto(const b::StrikeOutcome& o, st::StrikeOutcome* out) {
  st::CueStrike* a = out->mutable_applied();
  a->set_speed_mps(o.applied.speed_mps);
  a->set_ball_speed(o.applied.ball_speed);
  a->set_phi_rad(o.applied.phi_rad);
  a->set_theta_rad(o.applied.theta_rad);
  a->set_a(o.applied.a);
  a->set_b(o.applied.b);
  a->set_noise(o.applied.noise);
  a->set_seed(o.applied.seed);
  out->set_cue_speed_mps(o.cue_speed_mps);
  out->set_squirt_rad(o.squirt_rad);
  Vec3ToProto(o.v, out->mutable_v());
  Vec3ToProto(o.w, out->mutable_w());
}

void ShotSummaryToProto(const ShotSummary& s, st::ShotSummary* out) {
  out->set_shot_id(s.shot_id);
  out->set_seat(s.seat);
  out->set_struck_ball(s.struck_ball);
  out->set_first_ball_hit(s.first_ball_hit);
  out->set_rails(s.rails);
  out->set_rails_after_contact(s.rails_after_contact);
  for (const std::string& id : s.pocketed) out->add_pocketed(id);
  out->set_struck_ball_pocketed(s.struck_ball_pocketed);
  out->set_start_tick(s.start_tick);
  out->set_end_tick(s.end_tick);
  out->set_duration_s(s.duration_s);
  out->set_events(s.events);
  out->set_error(s.error);
  CallToProto(s.call, out->mutable_call());
  if (s.verdict.has_value()) VerdictToProto(*s.verdict, out->mutable_verdict());
}

void MatchEntryToProto(const MatchEntry& e, st::MatchEntry* out) {
  out->set_kind(EntryKindToProto(e.kind));
  out->set_tick(e.tick);
  out->set_seat(e.seat);
  out->set_strike(e.strike);
  CallToProto(e.call, out->mutable_call());
  out->set_shot_id(e.shot_id);
  out->set_seed(e.seed);
  StrikeOutcomeToProto(e.applied, out->mutable_applied());
  out->set_ball(e.ball);
  out->set_x_m(e.x_m);
  out->set_y_m(e.y_m);
  out->set_choice(e.choice);
  if (e.verdict.has_value()) VerdictToProto(*e.verdict, out->mutable_verdict());
}

// ---------------------------------------------------------------------------------------------
// Decoding: structure only (presence, array lengths, enum values); the values are the
// encoder's, taken as they are.

std::vector<std::string> Strings(const google::protobuf::RepeatedPtrField<std::string>& in) {
  return std::vector<std::string>(in.begin(), in.end());
}

template <typename T, typename Repeated>
absl::Status PairFromProto(const Repeated& in, std::string_view path, std::array<T, 2>* out) {
  if (in.size() != 2) {
    return Corrupt(path, absl::StrFormat("%d values, want 2 (one per seat)", in.size()));
  }
  (*out)[0] = static_cast<T>(in.Get(0));
  (*out)[1] = static_cast<T>(in.Get(1));
  return absl::OkStatus();
}

absl::Status BallFromProto(const st::Ball& in, std::string_view path, b::Ball* out) {
  out->id = in.id();
  if (!in.has_r()) return Missing(Member(path, "r"));
  if (!in.has_v()) return Missing(Member(path, "v"));
  if (!in.has_w()) return Missing(Member(path, "w"));
  if (!in.has_q()) return Missing(Member(path, "q"));
  out->r = Eigen::Vector3d(in.r().x(), in.r().y(), in.r().z());
  out->v = Eigen::Vector3d(in.v().x(), in.v().y(), in.v().z());
  out->w = Eigen::Vector3d(in.w().x(), in.w().y(), in.w().z());
  out->q = Eigen::Quaterniond(in.q().w(), in.q().x(), in.q().y(), in.q().z());
  absl::StatusOr<b::MotionState> state = MotionStateFromProto(in.state(), Member(path, "state"));
  if (!state.ok()) return state.status();
  out->state = *state;
  out->pocket = in.pocket();
  return absl::OkStatus();
}

absl::Status TableStateFromProto(const st::TableState& in, std::string_view path,
                                 b::TableState* out) {
  out->balls.clear();
  out->balls.resize(static_cast<size_t>(in.balls_size()));
  for (int i = 0; i < in.balls_size(); ++i) {
    if (absl::Status s = BallFromProto(in.balls(i),
                                       Index(Member(path, "balls"), static_cast<size_t>(i)),
                                       &out->balls[static_cast<size_t>(i)]);
        !s.ok()) {
      return s;
    }
  }
  out->t_s = in.t_s();
  return absl::OkStatus();
}

g::ShotCall CallFromProto(const st::ShotCall& in) {
  return g::ShotCall{.ball = in.ball(),
                     .pocket = in.pocket(),
                     .safety = in.safety(),
                     .push_out = in.push_out(),
                     .nominate = in.nominate()};
}

g::Verdict VerdictFromProto(const st::Verdict& in) {
  return g::Verdict{.foul = in.foul(),
                    .reason = in.reason(),
                    .points = in.points(),
                    .turn_passes = in.turn_passes(),
                    .respotted = Strings(in.respotted()),
                    .frame_over = in.frame_over()};
}

absl::Status GameStateFromProto(const st::GameState& in, std::string_view path,
                                g::GameState* out) {
  absl::StatusOr<g::GameKind> game = GameKindFromProto(in.game(), Member(path, "game"));
  if (!game.ok()) return game.status();
  out->game = *game;
  out->frame = in.frame();
  out->race_to = in.race_to();
  if (absl::Status s = PairFromProto(in.frames_won(), Member(path, "frames_won"),
                                     &out->frames_won);
      !s.ok()) {
    return s;
  }
  out->to_play = in.to_play();
  absl::StatusOr<g::BallInHand> hand =
      BallInHandFromProto(in.ball_in_hand(), Member(path, "ball_in_hand"));
  if (!hand.ok()) return hand.status();
  out->ball_in_hand = *hand;
  out->on = Strings(in.on());
  if (in.groups_size() != 2) {
    return Corrupt(Member(path, "groups"),
                   absl::StrFormat("%d values, want 2 (one per seat)", in.groups_size()));
  }
  for (size_t seat = 0; seat < 2; ++seat) {
    absl::StatusOr<g::Group> group =
        GroupFromProto(in.groups(static_cast<int>(seat)), Index(Member(path, "groups"), seat));
    if (!group.ok()) return group.status();
    out->groups[seat] = *group;
  }
  if (absl::Status s = PairFromProto(in.scores(), Member(path, "scores"), &out->scores);
      !s.ok()) {
    return s;
  }
  if (absl::Status s = PairFromProto(in.fouls_in_row(), Member(path, "fouls_in_row"),
                                     &out->fouls_in_row);
      !s.ok()) {
    return s;
  }
  if (absl::Status s = PairFromProto(in.warned(), Member(path, "warned"), &out->warned);
      !s.ok()) {
    return s;
  }
  out->call_required = in.call_required();
  out->push_out_available = in.push_out_available();
  if (!in.has_decision()) return Missing(Member(path, "decision"));
  out->decision.seat = in.decision().seat();
  out->decision.choices = Strings(in.decision().choices());
  out->winner = in.winner();
  absl::StatusOr<g::MatchResult> result =
      MatchResultFromProto(in.result(), Member(path, "result"));
  if (!result.ok()) return result.status();
  out->result = *result;
  out->breaker = in.breaker();
  out->is_break = in.is_break();
  out->shot = in.shot();
  if (absl::Status s = PairFromProto(in.innings(), Member(path, "innings"), &out->innings);
      !s.ok()) {
    return s;
  }
  out->last_shooter = in.last_shooter();
  out->pushed_out = in.pushed_out();
  out->phase = in.phase();
  out->nominated = in.nominated();
  out->free_ball = in.free_ball();
  out->misses_in_row = in.misses_in_row();
  if (!in.has_replay_position()) return Missing(Member(path, "replay_position"));
  if (absl::Status s = TableStateFromProto(in.replay_position(), Member(path, "replay_position"),
                                           &out->replay_position);
      !s.ok()) {
    return s;
  }
  out->opening = in.opening();
  out->replay_phase = in.replay_phase();
  out->seed = in.seed();
  return absl::OkStatus();
}

absl::Status StrikeOutcomeFromProto(const st::StrikeOutcome& in, std::string_view path,
                                    b::StrikeOutcome* out) {
  if (!in.has_applied()) return Missing(Member(path, "applied"));
  if (!in.has_v()) return Missing(Member(path, "v"));
  if (!in.has_w()) return Missing(Member(path, "w"));
  const st::CueStrike& a = in.applied();
  out->applied = b::CueStrike{.speed_mps = a.speed_mps(),
                              .ball_speed = a.ball_speed(),
                              .phi_rad = a.phi_rad(),
                              .theta_rad = a.theta_rad(),
                              .a = a.a(),
                              .b = a.b(),
                              .noise = a.noise(),
                              .seed = a.seed()};
  out->cue_speed_mps = in.cue_speed_mps();
  out->squirt_rad = in.squirt_rad();
  out->v = Eigen::Vector3d(in.v().x(), in.v().y(), in.v().z());
  out->w = Eigen::Vector3d(in.w().x(), in.w().y(), in.w().z());
  return absl::OkStatus();
}

absl::Status ShotSummaryFromProto(const st::ShotSummary& in, std::string_view path,
                                  ShotSummary* out) {
  out->shot_id = in.shot_id();
  out->seat = in.seat();
  out->struck_ball = in.struck_ball();
  out->first_ball_hit = in.first_ball_hit();
  out->rails = in.rails();
  out->rails_after_contact = in.rails_after_contact();
  out->pocketed = Strings(in.pocketed());
  out->struck_ball_pocketed = in.struck_ball_pocketed();
  out->start_tick = in.start_tick();
  out->end_tick = in.end_tick();
  out->duration_s = in.duration_s();
  out->events = in.events();
  out->error = in.error();
  if (!in.has_call()) return Missing(Member(path, "call"));
  out->call = CallFromProto(in.call());
  out->verdict.reset();
  if (in.has_verdict()) out->verdict = VerdictFromProto(in.verdict());
  return absl::OkStatus();
}

absl::Status MatchEntryFromProto(const st::MatchEntry& in, std::string_view path,
                                 MatchEntry* out) {
  absl::StatusOr<MatchEntry::Kind> kind = EntryKindFromProto(in.kind(), Member(path, "kind"));
  if (!kind.ok()) return kind.status();
  out->kind = *kind;
  out->tick = in.tick();
  out->seat = in.seat();
  out->strike = in.strike();
  if (!in.has_call()) return Missing(Member(path, "call"));
  out->call = CallFromProto(in.call());
  out->shot_id = in.shot_id();
  out->seed = in.seed();
  if (!in.has_applied()) return Missing(Member(path, "applied"));
  if (absl::Status s = StrikeOutcomeFromProto(in.applied(), Member(path, "applied"),
                                              &out->applied);
      !s.ok()) {
    return s;
  }
  out->ball = in.ball();
  out->x_m = in.x_m();
  out->y_m = in.y_m();
  out->choice = in.choice();
  out->verdict.reset();
  if (in.has_verdict()) out->verdict = VerdictFromProto(in.verdict());
  return absl::OkStatus();
}

// ---------------------------------------------------------------------------------------------
// Comparison: the first difference, by field path.

// A vector's three components by their bits.
void Bits(Differ& d, const std::string& path, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  d.Bits(Member(path, "x"), a.x(), b.x());
  d.Bits(Member(path, "y"), a.y(), b.y());
  d.Bits(Member(path, "z"), a.z(), b.z());
}

void DiffBall(Differ& d, const std::string& p, const b::Ball& a, const b::Ball& b) {
  d.Same(Member(p, "id"), a.id, b.id);
  Bits(d, Member(p, "r"), a.r, b.r);
  Bits(d, Member(p, "v"), a.v, b.v);
  Bits(d, Member(p, "w"), a.w, b.w);
  d.Bits(Member(p, "q.w"), a.q.w(), b.q.w());
  d.Bits(Member(p, "q.x"), a.q.x(), b.q.x());
  d.Bits(Member(p, "q.y"), a.q.y(), b.q.y());
  d.Bits(Member(p, "q.z"), a.q.z(), b.q.z());
  d.Same(Member(p, "state"), a.state, b.state);
  d.Same(Member(p, "pocket"), a.pocket, b.pocket);
}

void DiffTableState(Differ& d, const std::string& p, const b::TableState& a,
                    const b::TableState& b) {
  const std::string balls = Member(p, "balls");
  if (d.Size(balls, a.balls.size(), b.balls.size())) {
    for (size_t i = 0; i < a.balls.size(); ++i) {
      DiffBall(d, Index(balls, i), a.balls[i], b.balls[i]);
    }
  }
  d.Bits(Member(p, "t_s"), a.t_s, b.t_s);
}

void DiffCall(Differ& d, const std::string& p, const g::ShotCall& a, const g::ShotCall& b) {
  d.Same(Member(p, "ball"), a.ball, b.ball);
  d.Same(Member(p, "pocket"), a.pocket, b.pocket);
  d.Same(Member(p, "safety"), a.safety, b.safety);
  d.Same(Member(p, "push_out"), a.push_out, b.push_out);
  d.Same(Member(p, "nominate"), a.nominate, b.nominate);
}

void DiffVerdict(Differ& d, const std::string& p, const std::optional<g::Verdict>& a,
                 const std::optional<g::Verdict>& b) {
  if (!d.Presence(p, a, b)) return;
  d.Same(Member(p, "foul"), a->foul, b->foul);
  d.Same(Member(p, "reason"), a->reason, b->reason);
  d.Same(Member(p, "points"), a->points, b->points);
  d.Same(Member(p, "turn_passes"), a->turn_passes, b->turn_passes);
  d.Same(Member(p, "respotted"), a->respotted, b->respotted);
  d.Same(Member(p, "frame_over"), a->frame_over, b->frame_over);
}

void DiffGame(Differ& d, const std::string& p, const g::GameState& a, const g::GameState& b) {
  d.Same(Member(p, "game"), a.game, b.game);
  d.Same(Member(p, "frame"), a.frame, b.frame);
  d.Same(Member(p, "race_to"), a.race_to, b.race_to);
  d.Same(Member(p, "frames_won"), a.frames_won, b.frames_won);
  d.Same(Member(p, "to_play"), a.to_play, b.to_play);
  d.Same(Member(p, "ball_in_hand"), a.ball_in_hand, b.ball_in_hand);
  d.Same(Member(p, "on"), a.on, b.on);
  d.Same(Member(p, "groups"), a.groups, b.groups);
  d.Same(Member(p, "scores"), a.scores, b.scores);
  d.Same(Member(p, "fouls_in_row"), a.fouls_in_row, b.fouls_in_row);
  d.Same(Member(p, "warned"), a.warned, b.warned);
  d.Same(Member(p, "call_required"), a.call_required, b.call_required);
  d.Same(Member(p, "push_out_available"), a.push_out_available, b.push_out_available);
  d.Same(Member(p, "decision.seat"), a.decision.seat, b.decision.seat);
  d.Same(Member(p, "decision.choices"), a.decision.choices, b.decision.choices);
  d.Same(Member(p, "winner"), a.winner, b.winner);
  d.Same(Member(p, "result"), a.result, b.result);
  d.Same(Member(p, "breaker"), a.breaker, b.breaker);
  d.Same(Member(p, "is_break"), a.is_break, b.is_break);
  d.Same(Member(p, "shot"), a.shot, b.shot);
  d.Same(Member(p, "innings"), a.innings, b.innings);
  d.Same(Member(p, "last_shooter"), a.last_shooter, b.last_shooter);
  d.Same(Member(p, "pushed_out"), a.pushed_out, b.pushed_out);
  d.Same(Member(p, "phase"), a.phase, b.phase);
  d.Same(Member(p, "nominated"), a.nominated, b.nominated);
  d.Same(Member(p, "free_ball"), a.free_ball, b.free_ball);
  d.Same(Member(p, "misses_in_row"), a.misses_in_row, b.misses_in_row);
  DiffTableState(d, Member(p, "replay_position"), a.replay_position, b.replay_position);
  d.Same(Member(p, "opening"), a.opening, b.opening);
  d.Same(Member(p, "replay_phase"), a.replay_phase, b.replay_phase);
  d.Same(Member(p, "seed"), a.seed, b.seed);
}

void DiffOutcome(Differ& d, const std::string& p, const b::StrikeOutcome& a,
                 const b::StrikeOutcome& b) {
  const std::string s = Member(p, "applied");
  d.Bits(Member(s, "speed_mps"), a.applied.speed_mps, b.applied.speed_mps);
  d.Same(Member(s, "ball_speed"), a.applied.ball_speed, b.applied.ball_speed);
  d.Bits(Member(s, "phi_rad"), a.applied.phi_rad, b.applied.phi_rad);
  d.Bits(Member(s, "theta_rad"), a.applied.theta_rad, b.applied.theta_rad);
  d.Bits(Member(s, "a"), a.applied.a, b.applied.a);
  d.Bits(Member(s, "b"), a.applied.b, b.applied.b);
  d.Bits(Member(s, "noise"), a.applied.noise, b.applied.noise);
  d.Same(Member(s, "seed"), a.applied.seed, b.applied.seed);
  d.Bits(Member(p, "cue_speed_mps"), a.cue_speed_mps, b.cue_speed_mps);
  d.Bits(Member(p, "squirt_rad"), a.squirt_rad, b.squirt_rad);
  Bits(d, Member(p, "v"), a.v, b.v);
  Bits(d, Member(p, "w"), a.w, b.w);
}

void DiffSummary(Differ& d, const std::string& p, const ShotSummary& a, const ShotSummary& b) {
  d.Same(Member(p, "shot_id"), a.shot_id, b.shot_id);
  d.Same(Member(p, "seat"), a.seat, b.seat);
  d.Same(Member(p, "struck_ball"), a.struck_ball, b.struck_ball);
  d.Same(Member(p, "first_ball_hit"), a.first_ball_hit, b.first_ball_hit);
  d.Same(Member(p, "rails"), a.rails, b.rails);
  d.Same(Member(p, "rails_after_contact"), a.rails_after_contact, b.rails_after_contact);
  d.Same(Member(p, "pocketed"), a.pocketed, b.pocketed);
  d.Same(Member(p, "struck_ball_pocketed"), a.struck_ball_pocketed, b.struck_ball_pocketed);
  d.Same(Member(p, "start_tick"), a.start_tick, b.start_tick);
  d.Same(Member(p, "end_tick"), a.end_tick, b.end_tick);
  d.Bits(Member(p, "duration_s"), a.duration_s, b.duration_s);
  d.Same(Member(p, "events"), a.events, b.events);
  d.Same(Member(p, "error"), a.error, b.error);
  DiffCall(d, Member(p, "call"), a.call, b.call);
  DiffVerdict(d, Member(p, "verdict"), a.verdict, b.verdict);
}

void DiffEntry(Differ& d, const std::string& p, const MatchEntry& a, const MatchEntry& b) {
  d.Same(Member(p, "kind"), a.kind, b.kind);
  d.Same(Member(p, "tick"), a.tick, b.tick);
  d.Same(Member(p, "seat"), a.seat, b.seat);
  d.Same(Member(p, "strike"), a.strike, b.strike);
  DiffCall(d, Member(p, "call"), a.call, b.call);
  d.Same(Member(p, "shot_id"), a.shot_id, b.shot_id);
  d.Same(Member(p, "seed"), a.seed, b.seed);
  DiffOutcome(d, Member(p, "applied"), a.applied, b.applied);
  d.Same(Member(p, "ball"), a.ball, b.ball);
  d.Bits(Member(p, "x_m"), a.x_m, b.x_m);
  d.Bits(Member(p, "y_m"), a.y_m, b.y_m);
  d.Same(Member(p, "choice"), a.choice, b.choice);
  DiffVerdict(d, Member(p, "verdict"), a.verdict, b.verdict);
}

}  // namespace

std::string EncodeTableRestState(const TableRestState& state) {
  st::TableRestState out;
  out.set_version(kTableCheckpointVersion);
  out.set_tick(state.tick);
  out.set_sequence(state.sequence);
  out.set_turn(state.turn);
  TableStateToProto(state.rest, out.mutable_rest());
  ShotSummaryToProto(state.last_shot, out.mutable_last_shot());
  out.set_shots(state.shots);
  GameStateToProto(state.game, out.mutable_game());
  out.set_placed(state.placed);
  if (state.clock_deadline.has_value()) out.set_clock_deadline(*state.clock_deadline);
  for (const MatchEntry& e : state.record) MatchEntryToProto(e, out.add_record());
  return checkpoint::Seal(out);
}

absl::StatusOr<TableRestState> DecodeTableRestState(std::string_view bytes) {
  st::TableRestState in;
  if (absl::Status s = checkpoint::Open(bytes, kWhat, kTableCheckpointVersion, &in); !s.ok()) {
    return s;
  }
  TableRestState out;
  out.tick = in.tick();
  out.sequence = in.sequence();
  out.turn = in.turn();
  if (!in.has_rest()) return Missing("rest");
  if (absl::Status s = TableStateFromProto(in.rest(), "rest", &out.rest); !s.ok()) return s;
  if (!in.has_last_shot()) return Missing("last_shot");
  if (absl::Status s = ShotSummaryFromProto(in.last_shot(), "last_shot", &out.last_shot);
      !s.ok()) {
    return s;
  }
  out.shots = in.shots();
  if (!in.has_game()) return Missing("game");
  if (absl::Status s = GameStateFromProto(in.game(), "game", &out.game); !s.ok()) return s;
  out.placed = in.placed();
  if (in.has_clock_deadline()) out.clock_deadline = in.clock_deadline();
  out.record.resize(static_cast<size_t>(in.record_size()));
  for (int i = 0; i < in.record_size(); ++i) {
    if (absl::Status s = MatchEntryFromProto(in.record(i), Index("record", static_cast<size_t>(i)),
                                             &out.record[static_cast<size_t>(i)]);
        !s.ok()) {
      return s;
    }
  }
  return out;
}

std::string RestStateDifference(const TableRestState& a, const TableRestState& b) {
  Differ d;
  d.Same("tick", a.tick, b.tick);
  d.Same("sequence", a.sequence, b.sequence);
  d.Same("turn", a.turn, b.turn);
  DiffTableState(d, "rest", a.rest, b.rest);
  DiffSummary(d, "last_shot", a.last_shot, b.last_shot);
  d.Same("shots", a.shots, b.shots);
  DiffGame(d, "game", a.game, b.game);
  d.Same("placed", a.placed, b.placed);
  if (d.Presence("clock_deadline", a.clock_deadline, b.clock_deadline)) {
    d.Same("clock_deadline", *a.clock_deadline, *b.clock_deadline);
  }
  if (d.Size("record", a.record.size(), b.record.size())) {
    for (size_t i = 0; i < a.record.size(); ++i) {
      DiffEntry(d, Index("record", i), a.record[i], b.record[i]);
    }
  }
  return d.first();
}

bool SameRestState(const TableRestState& a, const TableRestState& b) {
  return RestStateDifference(a, b).empty();
}

}  // namespace sportsim::server
