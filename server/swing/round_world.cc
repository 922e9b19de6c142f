#include "server/swing/round_world.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/match.h"
#include "absl/strings/str_join.h"
#include "server/world/event_log.h"
#include "server/world/watcher_impl.h"
#include "server/world/world.h"
#include "sim/core/check.h"
#include "server/swing/convert.h"
#include "sportsim/store/v1/journal.pb.h"

namespace sportsim::server {

using Eigen::Vector3d;
using RoundEventPtr = RoundWatcher::EventPtr;

namespace {

constexpr double kDefaultTickHz = 30.0;
constexpr char kDefaultCourse[] = "sportsim_links";

void PointToProto(const Vector3d& p, v1::RoundEvent* e) {
  e->set_x_m(p.x());
  e->set_y_m(p.y());
  e->set_z_m(p.z());
}

v1::RoundEvent RefereeEventToProto(const golf::RoundEvent& g, int64_t tick) {
  v1::RoundEvent e;
  e.set_kind(std::string(golf::RoundEventName(g.kind)));
  e.set_seat(g.seat);
  e.set_hole(static_cast<uint32_t>(g.hole));
  e.set_strokes(static_cast<uint32_t>(std::max(0, g.strokes)));
  e.set_tick(tick);
  PointToProto(g.position_m, &e);
  e.set_lie(g.lie);
  e.set_penalty_strokes(static_cast<uint32_t>(g.penalty_strokes));
  e.set_reason(g.reason);
  e.set_rule(g.rule);
  for (const std::string& c : g.choices) e.add_choices(c);
  e.set_choice(g.choice);
  if (g.kind == golf::RoundEventKind::kDrop) {
    e.set_rest_x_m(g.rest_m.x());
    e.set_rest_y_m(g.rest_m.y());
    e.set_rest_z_m(g.rest_m.z());
    e.set_attempt(static_cast<uint32_t>(g.attempt));
    e.set_in_area(g.in_area);
  }
  return e;
}

// The ball's own events of a stroke (the ground's, whose first is the landing for a launch),
// in time order from the strike.
std::vector<v1::RoundEvent> BallEvents(const PlayedStroke& p, int hole) {
  std::vector<v1::RoundEvent> out;
  for (const golf::GroundEvent& g : p.shot.ground.events) {
    v1::RoundEvent& e = out.emplace_back();
    e.set_kind(std::string(golf::GroundEventName(g.kind)));
    e.set_seat(p.seat);
    e.set_hole(static_cast<uint32_t>(hole));
    e.set_t_s(g.t_s);
    PointToProto(g.position_m, &e);
    e.set_lie(g.surface);
    e.set_speed_mps(g.velocity_mps.norm());
  }
  return out;
}

v1::RoundMovingBall BallAt(const PlayedStroke& p, double t) {
  v1::RoundMovingBall b;
  b.set_seat(static_cast<uint32_t>(p.seat));
  b.set_t_s(t);
  const std::vector<golf::GroundSample>& path = p.shot.path;
  Vector3d at = p.shot.ground.rest_m;
  double speed = 0.0;
  if (!path.empty() && t < path.back().t_s) {
    auto it = std::upper_bound(path.begin(), path.end(), t,
                               [](double x, const golf::GroundSample& s) { return x < s.t_s; });
    if (it == path.begin()) {
      at = it->position_m;
      speed = it->speed_mps;
    } else {
      const golf::GroundSample& a = *(it - 1);
      const golf::GroundSample& c = *it;
      const double f = c.t_s > a.t_s ? (t - a.t_s) / (c.t_s - a.t_s) : 1.0;
      at = a.position_m + f * (c.position_m - a.position_m);
      speed = a.speed_mps + f * (c.speed_mps - a.speed_mps);
    }
  }
  b.set_x_m(at.x());
  b.set_y_m(at.y());
  b.set_z_m(at.z());
  b.set_speed_mps(speed);
  return b;
}

// The shot clock starts again at tick `from` (none when the round has none or is over).
void RestartClock(Round& r, int64_t from) ABSL_EXCLUSIVE_LOCKS_REQUIRED(r.mu) {
  if (r.shot_clock_s <= 0.0 || r.state.over) {
    r.clock_deadline.reset();
    return;
  }
  r.clock_deadline = from + std::max<int64_t>(1, std::llround(r.shot_clock_s * r.tick_hz));
}

void Refresh(Round& r) ABSL_EXCLUSIVE_LOCKS_REQUIRED(r.mu) {
  auto p = std::make_shared<v1::RoundState>();
  RoundStateToProto(*r.course, r.settings, r.state, r.stroke.has_value(), p.get());
  r.state_proto = std::move(p);
  ++r.version;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Conversions

void RoundStateToProto(const golf::Course& course, const golf::RoundSettings& settings,
                       const golf::RoundState& st, bool stroke_in_play, v1::RoundState* out) {
  out->set_play(std::string(golf::PlayFormatName(settings.play)));
  out->set_course(course.name);
  out->set_first_hole(static_cast<uint32_t>(settings.first_hole));
  out->set_last_hole(static_cast<uint32_t>(settings.last_hole));
  out->set_hole(static_cast<uint32_t>(st.hole));
  const golf::CourseHole* hole = course.Hole(st.hole);
  out->set_par(static_cast<uint32_t>(hole->par));
  out->set_to_play(stroke_in_play ? -1 : golf::ToPlay(course, settings, st));
  if (!stroke_in_play) {
    for (int seat : golf::MayPlay(course, settings, st)) out->add_may_play(static_cast<uint32_t>(seat));
  }
  for (size_t i = 0; i < st.players.size(); ++i) {
    const golf::RoundPlayer& p = st.players[i];
    v1::RoundPlayerState* ps = out->add_players();
    ps->set_seat(static_cast<uint32_t>(i));
    ps->set_name(p.name);
    ps->set_tee(p.tee);
    ps->set_strokes(static_cast<uint32_t>(p.strokes));
    ps->set_penalties(static_cast<uint32_t>(p.penalties));
    int par = 0;
    for (size_t h = 0; h < p.scores.size(); ++h) {
      ps->add_scores(static_cast<uint32_t>(p.scores[h]));
      if (p.scores[h] > 0) par += course.Hole(settings.first_hole + static_cast<int>(h))->par;
    }
    ps->set_total(static_cast<uint32_t>(p.Total()));
    ps->set_to_par(p.Total() - par);
    ps->set_score(static_cast<uint32_t>(p.Total() + (st.over ? 0 : p.strokes)));
    ps->set_playing_handicap(p.playing_handicap);
    for (int v : p.received) ps->add_received(v);
    for (bool v : p.no_score) ps->add_no_score(v);
    ps->set_net_total(p.NetTotal());
    for (int v : p.points) ps->add_points(static_cast<uint32_t>(v));
    ps->set_points_total(static_cast<uint32_t>(p.Points()));
    v1::RoundBall* b = ps->mutable_ball();
    b->set_x_m(p.ball.position_m.x());
    b->set_y_m(p.ball.position_m.y());
    b->set_z_m(p.ball.position_m.z());
    b->set_lie(std::string(golf::TerrainTag(p.ball.lie)));
    b->set_holed(p.ball.holed);
    b->set_marked(p.ball.marked);
    b->set_picked_up(p.ball.picked_up);
    b->set_distance_to_pin_m(
        p.ball.holed ? 0.0 : (p.ball.position_m.head<2>() - *hole->pin_m).norm());
  }
  if (st.decision) {
    v1::RoundDecision* d = out->mutable_decision();
    d->set_seat(static_cast<uint32_t>(st.decision->seat));
    d->set_reason(st.decision->reason);
    d->set_area(std::string(golf::TerrainTag(st.decision->area)));
    for (const std::string& c : st.decision->choices) d->add_choices(c);
    d->set_x_m(st.decision->reference_m.x());
    d->set_y_m(st.decision->reference_m.y());
    d->set_z_m(st.decision->reference_m.z());
  }
  out->set_stroke_in_play(stroke_in_play);
  out->set_result(st.result);
  for (int w : st.winners) out->add_winners(static_cast<uint32_t>(w));
  out->set_strokes(static_cast<uint64_t>(st.strokes));
  out->set_order(std::string(golf::OrderOfPlayName(settings.order)));
  out->set_profile(std::string(golf::RealismName(settings.realism)));
  out->set_winner(st.winners.size() == 1 ? st.winners.front() : -1);
  const Eigen::Vector2d pin = *hole->pin_m;
  out->set_pin_x_m(pin.x());
  out->set_pin_y_m(pin.y());
  out->set_pin_z_m(course.terrain.HeightAt(pin.x(), pin.y()));
  for (int w : st.hole_winners) out->add_hole_winners(w);
  out->set_match_status(golf::MatchStatusText(settings, st));
  switch (settings.max_score.kind) {
    case golf::MaxScore::Kind::kFixed: out->set_max_score(absl::StrCat(settings.max_score.n)); break;
    case golf::MaxScore::Kind::kParPlus: out->set_max_score(absl::StrCat("par+", settings.max_score.n)); break;
    case golf::MaxScore::Kind::kNetDoubleBogey: out->set_max_score("net_double_bogey"); break;
    case golf::MaxScore::Kind::kNone: break;
  }
  out->set_handicaps(golf::HasHandicaps(settings));
}

absl::StatusOr<golf::RoundSettings> RoundSettingsFromProto(const v1::CreateRoundRequest& r,
                                                           const golf::Course& course) {
  golf::RoundSettings s;
  s.first_hole = r.first_hole() == 0 ? 1 : static_cast<int>(std::min<uint32_t>(r.first_hole(), 1000));
  s.last_hole = r.last_hole() == 0 ? static_cast<int>(course.holes.size())
                                   : static_cast<int>(std::min<uint32_t>(r.last_hole(), 1000));
  if (r.players_size() > 8) {
    return absl::InvalidArgumentError(
        absl::StrFormat("players: a round has 1 to 8 players; got %d", r.players_size()));
  }
  for (const v1::RoundPlayerSpec& p : r.players()) {
    golf::RoundPlayerSpec& spec = s.players.emplace_back();
    spec.name = p.name();
    spec.tee = p.tee();
    if (p.has_handicap_index()) spec.handicap_index = p.handicap_index();
  }
  if (r.play().size() > 32) return absl::InvalidArgumentError("play: stroke, match or stableford");
  absl::StatusOr<golf::PlayFormat> play = golf::PlayFormatFromName(r.play());
  if (!play.ok()) {
    return absl::InvalidArgumentError(
        absl::StrFormat("play: %s is not a form of play (stroke, match, stableford)", Quote(r.play())));
  }
  s.play = *play;
  switch (r.profile()) {
    case v1::REALISM_PROFILE_UNSPECIFIED:
    case v1::REALISM_PROFILE_REALISTIC: s.realism = golf::Realism::kRealistic; break;
    case v1::REALISM_PROFILE_ARCADE: s.realism = golf::Realism::kArcade; break;
    default:
      return absl::InvalidArgumentError(absl::StrFormat("profile: unknown profile %d", r.profile()));
  }
  s.noise = r.noise();
  s.seed = r.seed();
  // In name order (the map's iteration order is not): the same request, the same settings.
  std::vector<std::pair<std::string, std::string>> rules(r.rules().begin(), r.rules().end());
  std::sort(rules.begin(), rules.end());
  for (const auto& [name, value] : rules) {
    if (absl::Status st = golf::SetRoundVariant(name, value, &s); !st.ok()) {
      return PrefixStatus("rules: ", st);
    }
  }
  if (absl::Status st = golf::ValidateRoundSettings(course, s); !st.ok()) return st;
  return s;
}

absl::StatusOr<golf::RoundStroke> RoundStrokeFromProto(const v1::PlayStrokeRequest& r) {
  golf::RoundStroke k;
  if (r.has_aim_deg()) {
    if (absl::Status s = CheckFiniteInRange("aim_deg", r.aim_deg(), -1e4, false, 1e4, false); !s.ok()) {
      return s;
    }
    k.aim_deg = r.aim_deg();
  }
  k.flagstick_in = !r.flagstick_out();
  switch (r.stroke_case()) {
    case v1::PlayStrokeRequest::kLaunch: {
      const v1::LaunchConditions& l = r.launch();
      k.kind = golf::RoundStroke::Kind::kLaunch;
      k.launch = golf::LaunchConditions{.ball_speed_mps = l.ball_speed_mps(),
                                        .launch_angle_deg = l.launch_angle_deg(),
                                        .launch_direction_deg = l.launch_direction_deg(),
                                        .spin_rpm = l.spin_rpm(),
                                        .spin_axis_deg = l.spin_axis_deg()};
      break;
    }
    case v1::PlayStrokeRequest::kPuttSpeedMps:
      k.kind = golf::RoundStroke::Kind::kPutt;
      k.speed_mps = r.putt_speed_mps();
      if (!(k.speed_mps > 0.0 && k.speed_mps <= 15.0)) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "putt_speed_mps: must be in (0, 15] m/s; got %g", k.speed_mps));
      }
      break;
    case v1::PlayStrokeRequest::kSwing: {
      const v1::RoundSwing& w = r.swing();
      k.kind = golf::RoundStroke::Kind::kSwing;
      golf::SwingStroke sw;
      const std::string club = w.club().empty() ? "driver" : w.club();
      if (absl::Status s = CheckId("swing.club", club); !s.ok()) return s;
      absl::StatusOr<golf::ClubSpec> spec = golf::ClubPreset(club);
      if (!spec.ok()) return PrefixStatus("swing.club: ", spec.status());
      sw.club = *spec;
      absl::StatusOr<swing::SwingModel> model =
          SwingModelFromProto(w.parameters(), google::protobuf::RepeatedField<int>());
      if (!model.ok()) return PrefixStatus("swing.", model.status());
      sw.model = std::make_shared<const swing::SwingModel>(*std::move(model));
      absl::StatusOr<swing::TorqueProgram> program = TorqueProgramFromProto(w.torques(), w.has_torques());
      if (!program.ok()) return PrefixStatus("swing.", program.status());
      sw.program = *std::move(program);
      if (w.has_dynamic_loft_deg()) sw.delivery.dynamic_loft_deg = w.dynamic_loft_deg();
      sw.delivery.face_angle_deg = w.face_angle_deg();
      sw.delivery.club_path_deg = w.club_path_deg();
      // The delivery's own limits, with a placeholder speed and a level attack.
      golf::ClubDelivery probe = sw.delivery;
      probe.clubhead_speed_mps = 40.0;
      if (absl::StatusOr<golf::ImpactResult> i = golf::SimulateImpact(probe, sw.club, {}); !i.ok()) {
        return PrefixStatus("swing.", i.status());
      }
      k.swing = std::move(sw);
      break;
    }
    default:
      return absl::InvalidArgumentError("stroke: one of launch, putt_speed_mps or swing is required");
  }
  return k;
}

// ---------------------------------------------------------------------------------------------
// Watcher

void RoundWatch::Fill(const RoundWatchOptions& /*options*/, const std::string& round_id,
                      const RoundFrame& frame, const RoundFrame* last_sent, bool full,
                      v1::RoundSnapshot* out) {
  out->set_round_id(round_id);
  out->set_tick(frame.tick);
  out->set_heartbeat(frame.heartbeat);
  if (frame.heartbeat) return;
  // The state only when it changed since this reader's last snapshot (each change makes a new
  // one): frames of a moving ball carry the ball alone.
  const bool changed = full || last_sent == nullptr || last_sent->round != frame.round;
  if (frame.round != nullptr && changed) *out->mutable_round() = *frame.round;
  if (frame.ball) *out->mutable_ball() = *frame.ball;
}

template class BasicWatcher<RoundWatch>;

// ---------------------------------------------------------------------------------------------
// The round kind

bool RoundKind::Running(const Round& r) ABSL_NO_THREAD_SAFETY_ANALYSIS { return r.stroke.has_value(); }

uint64_t RoundKind::Runs(const Round& r) ABSL_NO_THREAD_SAFETY_ANALYSIS {
  return static_cast<uint64_t>(r.state.strokes + (r.stroke ? 1 : 0));
}

std::optional<RoundKind::End> RoundKind::AdvanceTick(RoundHost& /*host*/, Round& r, int64_t k,
                                                     TickOut* out) ABSL_NO_THREAD_SAFETY_ANALYSIS {
  const double t = static_cast<double>(k - r.start_tick) * r.period_s;
  const bool done = k >= r.rest_tick;
  while (r.next_ball_event < r.ball_events.size() &&
         (done || r.ball_events[r.next_ball_event].t_s() <= t)) {
    v1::RoundEvent e = r.ball_events[r.next_ball_event++];
    e.set_tick(k);
    out->events.push_back(std::move(e));
  }
  if (done) return End{};
  return std::nullopt;
}

void RoundKind::Publish(RoundHost& host, Round& r, TickOut* out,
                        std::vector<RoundEventPtr>* fresh) ABSL_NO_THREAD_SAFETY_ANALYSIS {
  for (v1::RoundEvent& e : out->events) fresh->push_back(r.Log(std::move(e)));
  host.CountEvents(out->events.size());
  out->events.clear();
}

void RoundKind::EndRun(RoundHost& host, Round& r, const End& /*end*/,
                       std::vector<RoundEventPtr>* fresh, Round::Pump* /*pump*/)
    ABSL_NO_THREAD_SAFETY_ANALYSIS {
  PlayedStroke& p = *r.stroke;
  r.state = std::move(p.after.state);
  size_t n = 0;
  for (const golf::RoundEvent& g : p.after.events) {
    if (g.kind == golf::RoundEventKind::kStroke) continue;  // published at the strike
    fresh->push_back(r.Log(RefereeEventToProto(g, r.tick)));
    ++n;
  }
  host.CountEvents(n);
  r.stroke.reset();
  r.ball_events.clear();
  r.next_ball_event = 0;
  host.RunEnded();
  Refresh(r);
  RestartClock(r, r.tick);
}

std::optional<int64_t> RoundKind::RestDeadline(const Round& r) ABSL_NO_THREAD_SAFETY_ANALYSIS {
  if (r.stroke) return std::nullopt;
  return r.clock_deadline;
}

void RoundKind::AtRestDeadline(RoundHost& /*host*/, Round& r, std::vector<RoundEventPtr>* fresh)
    ABSL_NO_THREAD_SAFETY_ANALYSIS {
  absl::StatusOr<golf::RoundStep> step = golf::ShotClockExpired(*r.course, r.settings, r.state);
  if (step.ok()) {
    r.state = std::move(step->state);
    for (const golf::RoundEvent& g : step->events) fresh->push_back(r.Log(RefereeEventToProto(g, r.tick)));
    v1::RoundCommand& c = r.commands.emplace_back();
    c.set_tick(r.tick);
    c.set_seat(step->events.empty() ? -1 : step->events.front().seat);
    c.set_shot_clock(true);
    Refresh(r);
  }
  RestartClock(r, r.tick);
}

std::shared_ptr<const RoundFrame> RoundKind::MakeFrame(const Round& r, int64_t k, bool heartbeat,
                                                       SteadyClock::time_point published)
    ABSL_NO_THREAD_SAFETY_ANALYSIS {
  auto f = std::make_shared<RoundFrame>();
  f->sequence = r.sequence;
  f->tick = k;
  f->heartbeat = heartbeat;
  f->published = published;
  f->round = r.state_proto;
  if (r.stroke) f->ball = BallAt(*r.stroke, static_cast<double>(k - r.start_tick) * r.period_s);
  return f;
}

// ---------------------------------------------------------------------------------------------
// Registry

RoundRegistry::RoundRegistry(RoundLimits limits, TickScheduler* scheduler, int workers)
    : limits_(limits), host_([&] {
        WorldLimits w = limits.world;
        w.checkpoint_every_runs = 0;
        if (workers != 0) w.workers = workers;
        return w;
      }(), scheduler) {}

RoundRegistry::~RoundRegistry() { Shutdown(absl::UnavailableError("the server is shutting down")); }

absl::StatusOr<v1::CreateRoundResponse> RoundRegistry::MakeRound(
    const v1::CreateRoundRequest& request, Round& made, std::vector<std::string>* tokens) {
  const double tick_hz = request.tick_hz() == 0 ? kDefaultTickHz : request.tick_hz();
  if (absl::Status s = CheckFiniteInRange("tick_hz", tick_hz, 1, false, 240, false); !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckFiniteInRange("shot_clock_s", request.shot_clock_s(), 0, false, 3600, false);
      !s.ok()) {
    return s;
  }
  const std::string name = request.course().empty() ? kDefaultCourse : request.course();
  absl::StatusOr<std::shared_ptr<const golf::Course>> course = golf::BuiltinCourse(name);
  if (!course.ok()) return PrefixStatus("course: ", course.status());
  absl::StatusOr<golf::RoundSettings> settings = RoundSettingsFromProto(request, **course);
  if (!settings.ok()) return settings.status();
  absl::StatusOr<golf::RoundState> state = golf::StartRound(**course, *settings);
  if (!state.ok()) return state.status();
  if (made.seats.empty()) {  // a restore keeps its own
    for (const golf::RoundPlayerSpec& p : settings->players) {
      const std::string token = RandomHex(16);
      made.seats.push_back(SeatEntry{.name = p.name, .token_hash = HashToken(token)});
      tokens->push_back(token);
    }
  }
  made.course = *course;
  made.settings = *settings;
  made.setup = request;
  made.fast_forward = request.fast_forward();
  made.shot_clock_s = request.shot_clock_s();
  made.tick_hz = tick_hz;
  made.period_s = 1.0 / tick_hz;
  v1::CreateRoundResponse response;
  {
    absl::MutexLock lock(&made.mu);
    made.clock.tick_hz = tick_hz * host_.limits().clock_rate;
    made.clock.origin = SteadyClock::now();
    made.state = *std::move(state);
    Refresh(made);
    RestartClock(made, 0);
    *response.mutable_round() = *made.state_proto;
  }
  response.set_tick_hz(tick_hz);
  return response;
}

absl::StatusOr<v1::CreateRoundResponse> RoundRegistry::Create(const v1::CreateRoundRequest& request) {
  const std::shared_ptr<Round> round = host_.Make();
  std::vector<std::string> tokens;
  absl::StatusOr<v1::CreateRoundResponse> made = MakeRound(request, *round, &tokens);
  if (!made.ok()) return made.status();
  v1::CreateRoundResponse response = *std::move(made);
  const std::string admin = RandomHex(16);
  round->admin_token_hash = HashToken(admin);
  SeatsToProto(round->seats, &tokens, response.mutable_seats());
  ::sportsim::store::v1::RoundCreated created;
  created.set_request(request.SerializeAsString());
  if (absl::Status s = host_.Add(round, created.SerializeAsString()); !s.ok()) return s;
  response.set_round_id(round->id);
  response.set_admin_token(admin);
  if (round->shot_clock_s > 0) {  // a clock that runs while nobody plays needs a wake
    absl::MutexLock lock(&round->mu);
    host_.ScheduleRest(*round);
  }
  return response;
}

absl::StatusOr<v1::RoundInfo> RoundRegistry::Get(const v1::GetRoundRequest& request) {
  absl::StatusOr<std::shared_ptr<Round>> found = host_.Find(request.round_id());
  if (!found.ok()) return found.status();
  Round& r = **found;
  absl::MutexLock lock(&r.mu);
  v1::RoundInfo info;
  info.set_round_id(r.id);
  info.set_tick_hz(r.tick_hz);
  info.set_tick(r.NowTick());
  info.set_sequence(r.sequence);
  *info.mutable_round() = *r.state_proto;
  SeatsToProto(r.seats, nullptr, info.mutable_seats());
  info.set_watchers(static_cast<uint32_t>(r.watchers.size()));
  info.set_noise(r.settings.noise);
  info.set_seed(r.settings.seed);
  info.set_fast_forward(r.fast_forward);
  info.set_shot_clock_s(r.shot_clock_s);
  info.set_clock_deadline_tick(r.clock_deadline && !r.stroke ? *r.clock_deadline : 0);
  return info;
}

absl::StatusOr<v1::ListRoundsResponse> RoundRegistry::List(const v1::ListRoundsRequest& request) {
  v1::ListRoundsResponse response;
  absl::StatusOr<uint32_t> total = host_.List(
      PageRequest{.page_size = request.page_size(), .page_token = request.page_token()},
      response.mutable_next_page_token(), [&](const Round& r) ABSL_NO_THREAD_SAFETY_ANALYSIS {
        v1::RoundBrief* brief = response.add_rounds();
        brief->set_round_id(r.id);
        brief->set_course(r.course->name);
        brief->set_hole(static_cast<uint32_t>(r.state.hole));
        for (const golf::RoundPlayer& p : r.state.players) brief->add_players(p.name);
        brief->set_result(r.state.result);
        brief->set_play(std::string(golf::PlayFormatName(r.settings.play)));
        brief->set_tick(r.NowTick());
        brief->set_watchers(static_cast<uint32_t>(r.watchers.size()));
      });
  if (!total.ok()) return total.status();
  response.set_total(*total);
  return response;
}

absl::Status RoundRegistry::Delete(const v1::DeleteRoundRequest& request) {
  return host_.Delete(
      request.round_id(), request.token(),
      [](const Round&, int seat) {
        if (seat == kAdminSeat) return absl::OkStatus();
        return absl::PermissionDeniedError(
            "token: only the round's admin token (CreateRound's admin_token) deletes it");
      },
      [&](Round& r, std::vector<RoundEventPtr>* /*fresh*/, Round::Pump* /*pump*/)
          ABSL_NO_THREAD_SAFETY_ANALYSIS {
        if (r.stroke) {
          r.stroke.reset();
          host_.RunEnded();
        }
      },
      static_cast<uint32_t>(RoundCommandType::kDelete), JournalBody(request));
}

namespace {

absl::Status CheckSeat(int seat) {
  if (seat == kAdminSeat) {
    return absl::PermissionDeniedError(
        "token: the admin token plays no ball; a seat's token plays its own");
  }
  return absl::OkStatus();
}

absl::Status StrokeInPlay(const Round& r) ABSL_NO_THREAD_SAFETY_ANALYSIS {
  if (!r.stroke) return absl::OkStatus();
  return absl::FailedPreconditionError(absl::StrFormat(
      "a stroke is in play: %s's ball comes to rest at tick %d", r.state.players[r.stroke->seat].name,
      r.rest_tick));
}

// The stroke played on a copy of the state (pure: the same inputs, the same stroke).
absl::StatusOr<PlayedStroke> Play(const golf::Course& course, const golf::RoundSettings& settings,
                                  const golf::RoundState& state, int seat,
                                  const golf::RoundStroke& stroke, uint64_t version,
                                  const std::function<bool()>& cancelled) {
  PlayedStroke p;
  p.seat = seat;
  p.version = version;
  absl::StatusOr<golf::RoundStep> step =
      golf::PlayStroke(course, settings, state, seat, stroke, &p.shot, cancelled);
  if (!step.ok()) return step.status();
  p.after = *std::move(step);
  return p;
}

}  // namespace

absl::StatusOr<v1::PlayStrokeResponse> RoundRegistry::Stroke(const v1::PlayStrokeRequest& request,
                                                             const std::function<bool()>& cancelled) {
  if (absl::Status s = CheckToken(request.token(), RoundKind::kCreateRpc); !s.ok()) return s;
  absl::StatusOr<golf::RoundStroke> stroke = RoundStrokeFromProto(request);
  if (!stroke.ok()) return stroke.status();
  absl::StatusOr<std::shared_ptr<Round>> found = host_.Find(request.round_id());
  if (!found.ok()) return found.status();
  Round& r = **found;
  golf::RoundState state;
  uint64_t version = 0;
  int seat = 0;
  {
    absl::MutexLock lock(&r.mu);
    absl::StatusOr<int> authorized = r.Authorize(request.token());
    if (!authorized.ok()) return authorized.status();
    if (absl::Status s = CheckSeat(*authorized); !s.ok()) return s;
    if (absl::Status s = StrokeInPlay(r); !s.ok()) return s;
    seat = *authorized;
    state = r.state;
    version = r.version;
  }
  // Checked (PlayStroke checks first) and simulated off the round's lock; it takes effect only
  // on the state it was computed on.
  absl::StatusOr<PlayedStroke> played = Play(*r.course, r.settings, state, seat, *stroke, version, cancelled);
  if (!played.ok()) return played.status();
  return host_.Act<v1::PlayStrokeResponse>(
      request.round_id(), request.token(),
      [&](const std::shared_ptr<Round>& ptr, int s, Round::Pump& pump) {
        return StrokeOn(*ptr, s, request, *std::move(played), pump);
      });
}

absl::StatusOr<v1::PlayStrokeResponse> RoundRegistry::StrokeOn(Round& r, int seat,
                                                               const v1::PlayStrokeRequest& request,
                                                               std::optional<PlayedStroke> played,
                                                               Round::Pump& pump) {
  if (absl::Status s = CheckSeat(seat); !s.ok()) return s;
  if (absl::Status s = StrokeInPlay(r); !s.ok()) return s;
  if (played) {
    if (played->version != r.version || played->seat != seat) {
      return absl::FailedPreconditionError(
          "the round changed while this stroke was simulated; play it again");
    }
  } else {
    absl::StatusOr<golf::RoundStroke> stroke = RoundStrokeFromProto(request);
    if (!stroke.ok()) return stroke.status();
    absl::StatusOr<PlayedStroke> made = Play(*r.course, r.settings, r.state, seat, *stroke, r.version, {});
    if (!made.ok()) return made.status();
    played = *std::move(made);
  }
  if (absl::Status st = host_.Commit(r, seat, static_cast<uint32_t>(RoundCommandType::kStroke),
                                     JournalBody(request));
      !st.ok()) {
    return st;
  }
  const int64_t start = r.ClockTick(SteadyClock::now()) + 1;
  v1::RoundCommand& command = r.commands.emplace_back();
  command.set_tick(*r.pinned_tick);
  command.set_seat(seat);
  *command.mutable_stroke() = request;
  command.mutable_stroke()->clear_token();
  r.tick = start;
  r.start_tick = start;
  const double t_rest = played->shot.ground.t_rest_s;
  r.rest_tick = r.fast_forward ? start + 1
                               : start + std::max<int64_t>(1, static_cast<int64_t>(std::ceil(t_rest * r.tick_hz)));
  r.ball_events = BallEvents(*played, r.state.hole);
  r.next_ball_event = 0;
  ++r.sequence;
  std::vector<RoundEventPtr> fresh;
  for (const golf::RoundEvent& g : played->after.events) {
    if (g.kind == golf::RoundEventKind::kStroke) fresh.push_back(r.Log(RefereeEventToProto(g, start)));
  }
  r.stroke = *std::move(played);
  host_.RunStarted();
  host_.CountEvents(fresh.size());
  Refresh(r);
  r.OfferFrameAt(start, fresh, &pump);
  host_.ScheduleNextTick(r);
  v1::PlayStrokeResponse response;
  response.set_stroke(static_cast<uint64_t>(r.state.strokes + 1));
  response.set_start_tick(start);
  response.set_rest_tick(r.rest_tick);
  response.set_sequence(r.sequence);
  return response;
}

absl::StatusOr<v1::DecideRoundResponse> RoundRegistry::Decide(const v1::DecideRoundRequest& request) {
  return host_.Act<v1::DecideRoundResponse>(
      request.round_id(), request.token(),
      [&](const std::shared_ptr<Round>& ptr, int seat, Round::Pump& pump) {
        return DecideOn(*ptr, seat, request, pump);
      });
}

absl::StatusOr<v1::DecideRoundResponse> RoundRegistry::DecideOn(Round& r, int seat,
                                                                const v1::DecideRoundRequest& request,
                                                                Round::Pump& pump) {
  if (absl::Status s = CheckSeat(seat); !s.ok()) return s;
  if (absl::Status s = StrokeInPlay(r); !s.ok()) return s;
  if (request.choice().empty() || request.choice().size() > 64) {
    return absl::InvalidArgumentError(
        "choice: a choice of the pending decision, \"unplayable\", \"pick_up\" or a concession");
  }
  golf::RoundChoice choice{request.choice(), std::nullopt};
  if (request.has_back_m()) choice.back_m = request.back_m();
  // A drop runs the ground physics: a few hundred microseconds, under the lock.
  absl::StatusOr<golf::RoundStep> step = golf::Decide(*r.course, r.settings, r.state, seat, choice);
  if (!step.ok()) {
    if (r.state.decision && step.status().code() == absl::StatusCode::kInvalidArgument &&
        absl::StartsWith(step.status().message(), "choice: ")) {
      return absl::InvalidArgumentError(absl::StrFormat(  // the client's value quoted safely
          "choice: %s is not one of %s", Quote(request.choice()),
          absl::StrJoin(r.state.decision->choices, ", ")));
    }
    return step.status();
  }
  if (absl::Status st = host_.Commit(r, seat, static_cast<uint32_t>(RoundCommandType::kDecide),
                                     JournalBody(request));
      !st.ok()) {
    return st;
  }
  const int64_t tick = r.NowTick();
  v1::RoundCommand& command = r.commands.emplace_back();
  command.set_tick(tick);
  command.set_seat(seat);
  *command.mutable_decide() = request;
  command.mutable_decide()->clear_token();
  r.tick = tick;
  ++r.sequence;
  r.state = std::move(step->state);
  std::vector<RoundEventPtr> fresh;
  for (const golf::RoundEvent& g : step->events) fresh.push_back(r.Log(RefereeEventToProto(g, tick)));
  host_.CountEvents(fresh.size());
  Refresh(r);
  RestartClock(r, tick);
  if (r.clock_deadline) host_.ScheduleRest(r);
  r.OfferFrameAt(tick, fresh, &pump);
  v1::DecideRoundResponse response;
  response.set_sequence(r.sequence);
  *response.mutable_round() = *r.state_proto;
  return response;
}

void RoundRegistry::SetMonitorListen(std::string address) {
  absl::MutexLock lock(&monitors_mu_);
  monitor_listen_ = std::move(address);
}

std::optional<MonitorBinding> RoundRegistry::Monitor(const std::string& device_id) const {
  absl::MutexLock lock(&monitors_mu_);
  auto it = monitors_.find(device_id);
  if (it == monitors_.end()) return std::nullopt;
  return it->second;
}

absl::StatusOr<v1::BindMonitorResponse> RoundRegistry::BindMonitor(const v1::BindMonitorRequest& request) {
  std::string listen;
  {
    absl::MutexLock lock(&monitors_mu_);
    listen = monitor_listen_;
  }
  if (listen.empty()) {
    return absl::FailedPreconditionError(
        "this server has no Open Connect listener (start it with --open_connect_listen HOST:PORT)");
  }
  const std::string& d = request.device_id();
  const bool printable = std::all_of(d.begin(), d.end(), [](char c) {
    return static_cast<unsigned char>(c) >= 0x20 && c != 0x7f;
  });
  if (d.empty() || d.size() > 64 || !printable) {
    return absl::InvalidArgumentError("device_id: the monitor's DeviceID, 1 to 64 printable characters");
  }
  absl::StatusOr<int> seat = host_.Act<int>(
      request.round_id(), request.token(),
      [](const std::shared_ptr<Round>&, int seat, Round::Pump&) -> absl::StatusOr<int> {
        if (absl::Status s = CheckSeat(seat); !s.ok()) return s;
        return seat;
      });
  if (!seat.ok()) return seat.status();
  {
    absl::MutexLock lock(&monitors_mu_);
    // Bounded: eight seats a round. At the cap, bindings of rounds that are gone make room.
    const size_t cap = static_cast<size_t>(std::max(1, limits_.world.max_worlds)) * 8;
    if (monitors_.size() >= cap && !monitors_.contains(d)) {
      for (auto it = monitors_.begin(); it != monitors_.end();) {
        it = host_.Find(it->second.round_id).ok() ? std::next(it) : monitors_.erase(it);
      }
      if (monitors_.size() >= cap) {
        return absl::ResourceExhaustedError(absl::StrFormat("at most %d monitors are bound", cap));
      }
    }
    monitors_[d] = MonitorBinding{request.round_id(), request.token(), *seat};
  }
  v1::BindMonitorResponse response;
  response.set_seat(static_cast<uint32_t>(*seat));
  response.set_listen(listen);
  return response;
}

absl::StatusOr<v1::RoundRecord> RoundRegistry::Record(const v1::GetRoundRecordRequest& request) {
  absl::StatusOr<std::shared_ptr<Round>> found = host_.Find(request.round_id());
  if (!found.ok()) return found.status();
  Round& r = **found;
  absl::MutexLock lock(&r.mu);
  v1::RoundRecord record;
  record.set_round_id(r.id);
  *record.mutable_setup() = r.setup;
  for (const v1::RoundCommand& c : r.commands) *record.add_commands() = c;
  if (r.stroke) {
    // The stroke in play is in the record; the state is the one after it.
    RoundStateToProto(*r.course, r.settings, r.stroke->after.state, false, record.mutable_round());
  } else {
    *record.mutable_round() = *r.state_proto;
  }
  return record;
}

absl::StatusOr<std::shared_ptr<RoundWatcher>> RoundRegistry::Watch(const v1::WatchRoundRequest& request,
                                                                   RoundSink* sink) {
  std::optional<uint64_t> from;
  if (request.has_from_sequence()) from = request.from_sequence();
  return host_.Watch(request.round_id(), request.rate_hz(), RoundWatchOptions{}, from, sink);
}

void RoundRegistry::Unwatch(const std::string& round_id, const RoundWatcher* watcher) {
  host_.Unwatch(round_id, watcher);
}

absl::Status RoundRegistry::Restore(const StoredWorld& stored) {
  return host_.Restore(
      stored,
      [&](Round& r, const std::string& kind_body) -> absl::Status {
        ::sportsim::store::v1::RoundCreated created;
        v1::CreateRoundRequest request;
        if (!created.ParseFromString(kind_body) || !request.ParseFromString(created.request())) {
          return absl::DataLossError("its creation does not parse");
        }
        std::vector<std::string> unused;
        return MakeRound(request, r, &unused).status();
      },
      [&](Round&, const std::string&) {
        return absl::DataLossError("round checkpoint: rounds take none");
      },
      [&](Round& r, const JournalEntry& e, Round::Pump& pump)
          ABSL_NO_THREAD_SAFETY_ANALYSIS -> absl::Status {
        const auto bad = [&] {
          return absl::DataLossError(absl::StrFormat("entry %d: the command does not parse", e.index));
        };
        switch (static_cast<RoundCommandType>(e.type)) {
          case RoundCommandType::kStroke: {
            v1::PlayStrokeRequest q;
            if (!q.ParseFromString(e.body)) return bad();
            return StrokeOn(r, e.seat, q, std::nullopt, pump).status();
          }
          case RoundCommandType::kDecide: {
            v1::DecideRoundRequest q;
            if (!q.ParseFromString(e.body)) return bad();
            return DecideOn(r, e.seat, q, pump).status();
          }
          case RoundCommandType::kCreate:
          case RoundCommandType::kDelete:
            break;
        }
        return absl::DataLossError(
            absl::StrFormat("entry %d: no round command of type %d", e.index, e.type));
      });
}

void RoundRegistry::Shutdown(const absl::Status& status) {
  host_.Shutdown(status, [&](Round& r) ABSL_NO_THREAD_SAFETY_ANALYSIS {
    if (r.stroke) {
      r.stroke.reset();
      host_.RunEnded();
    }
  });
}

}  // namespace sportsim::server
