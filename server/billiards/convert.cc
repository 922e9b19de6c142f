#include "server/billiards/convert.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "server/billiards/game_convert.h"
#include "server/billiards/table_world.h"
#include "server/world/world.h"
#include "sim/billiards/rack.h"
#include "sim/core/check.h"
#include "sim/core/units.h"

namespace sportsim::server {
namespace {

namespace b = ::sportsim::billiards;

std::string DefaultRack(std::string_view preset) {
  if (preset == "snooker") return "snooker";
  if (preset == "carom") return "three-cushion";
  if (preset == "unbounded") return "chapter19";
  return "8ball";
}

}  // namespace

void ShotSummaryToProto(const ShotSummary& s, v1::ShotSummary* out) {
  out->set_shot_id(s.shot_id);
  out->set_seat(s.seat);
  out->set_struck_ball(s.struck_ball);
  out->set_first_ball_hit(s.first_ball_hit);
  out->set_rails_after_contact(s.rails_after_contact);
  out->set_rails(s.rails);
  for (const std::string& id : s.pocketed) out->add_pocketed(id);
  out->set_struck_ball_pocketed(s.struck_ball_pocketed);
  out->set_start_tick(s.start_tick);
  out->set_end_tick(s.end_tick);
  out->set_duration_s(s.duration_s);
  out->set_events(s.events);
  out->set_error(s.error);
  if (s.verdict.has_value()) {
    ShotCallToProto(s.call, out->mutable_call());
    VerdictToProto(*s.verdict, out->mutable_verdict());
  }
}

absl::Status BoundShotWork(int64_t max_reply_bytes, ShotJob* job) {
  // A sample costs each ball about 17 bytes on the wire (two packed doubles and a state) and
  // about 17 in memory; an event about 100 on the wire. Half the reply for each, at most.
  constexpr int64_t kSampleBallBytes = 40;
  constexpr int64_t kEventBytes = 100;
  const int64_t balls = std::max<int64_t>(1, static_cast<int64_t>(job->table.state.balls.size()));
  const int64_t samples = std::max<int64_t>(1, max_reply_bytes / 2 / (balls * kSampleBallBytes));
  job->shot.max_samples = std::min(job->shot.max_samples, samples);
  const int64_t events = std::max<int64_t>(1, max_reply_bytes / 2 / kEventBytes);
  job->solver.max_events = std::min(job->solver.max_events, events);
  if (job->solver.engine == b::Engine::kStepped) {
    const double steps = job->shot.max_time_s / job->solver.dt_s;
    if (steps > 1e9) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "max_time_s / solver.dt_s is %.3g steps, above the stepped engine's 1e9: lower "
          "max_time_s or raise dt_s",
          steps));
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<TableBuild> TableFromProto(const v1::TableSetup& setup) {
  // Names are checked here, before the library sees them (its messages quote what they got).
  if (!setup.preset().empty()) {
    if (absl::Status s = CheckId("table.preset", setup.preset()); !s.ok()) return s;
  }
  if (!setup.rack().empty()) {
    if (absl::Status s = CheckId("table.rack", setup.rack()); !s.ok()) return s;
  }
  for (const auto& [name, value] : setup.params()) {
    if (absl::Status s = CheckId("table.params key", name); !s.ok()) return s;
  }
  const std::string preset = setup.preset().empty() ? "pool-9ft" : setup.preset();
  absl::StatusOr<b::TableSpec> spec = b::MakeTablePreset(preset);
  if (!spec.ok()) return PrefixStatus("table.preset: ", spec.status());
  // Parameters in name order, so the first error reported does not depend on map order.
  std::map<std::string, double> params(setup.params().begin(), setup.params().end());
  for (const auto& [name, value] : params) {
    if (absl::Status s = b::SetParam(name, value, &spec->params); !s.ok()) {
      return PrefixStatus("table.params: ", s);
    }
  }
  switch (setup.cushion_model()) {
    case v1::CUSHION_MODEL_UNSPECIFIED:
    case v1::CUSHION_MODEL_HAN:
      spec->params.cushion_model = b::CushionModel::kHan;
      break;
    case v1::CUSHION_MODEL_MIRROR:
      spec->params.cushion_model = b::CushionModel::kMirror;
      break;
    case v1::CUSHION_MODEL_MATHAVAN_2010:
      spec->params.cushion_model = b::CushionModel::kMathavan2010;
      break;
    case v1::CUSHION_MODEL_STRONGE_COMPLIANT:
      spec->params.cushion_model = b::CushionModel::kStrongeCompliant;
      break;
    default:
      return absl::InvalidArgumentError(
          absl::StrFormat("table.cushion_model: unknown value %d", setup.cushion_model()));
  }
  switch (setup.ball_ball_model()) {
    case v1::BALL_BALL_MODEL_UNSPECIFIED:
    case v1::BALL_BALL_MODEL_ALCIATORE:
      spec->params.ball_ball_model = b::BallBallModel::kAlciatore;
      break;
    case v1::BALL_BALL_MODEL_MATHAVAN_2014:
      spec->params.ball_ball_model = b::BallBallModel::kMathavan2014;
      break;
    default:
      return absl::InvalidArgumentError(
          absl::StrFormat("table.ball_ball_model: unknown value %d", setup.ball_ball_model()));
  }
  // A new ball radius moves the cushion nose with it (where the preset ties the nose to the
  // ball) unless the caller set the height.
  if (params.count("ball_radius_m") && !params.count("cushion_height_m")) {
    b::SetBallRadius(spec->params.ball_radius_m, &*spec);
  }
  absl::StatusOr<b::TableModel> model = b::TableModel::Create(*std::move(spec));
  if (!model.ok()) return PrefixStatus("table.params: ", model.status());
  const std::string rack = setup.rack().empty() ? DefaultRack(preset) : setup.rack();
  if (absl::Status s = CheckFiniteInRange("table.rack_jitter_m", setup.rack_jitter_m(), 0, false,
                                          b::kMaxRackJitterM, false);
      !s.ok()) {
    return s;
  }
  absl::StatusOr<std::vector<b::Ball>> balls =
      b::MakeRack(rack, *model, setup.rack_jitter_m(), setup.rack_seed());
  if (!balls.ok()) return PrefixStatus("table.rack: ", balls.status());
  TableBuild out{.model = *std::move(model), .state = {.balls = *std::move(balls)}, .rack = rack};
  if (setup.balls_size() > kMaxBalls) {
    return absl::InvalidArgumentError(
        absl::StrFormat("table.balls: at most %d balls, got %d", kMaxBalls, setup.balls_size()));
  }
  for (int i = 0; i < setup.balls_size(); ++i) {
    const v1::BallPlacement& p = setup.balls(i);
    const std::string field = absl::StrFormat("table.balls[%d]", i);
    if (absl::Status s = CheckId(field + ".id", p.id()); !s.ok()) return s;
    if (!std::isfinite(p.x_m()) || !std::isfinite(p.y_m())) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: x_m and y_m must be finite, got (%g, %g)", field, p.x_m(), p.y_m()));
    }
    int k = out.state.Find(p.id());
    if (k < 0) {
      out.state.balls.push_back(b::Ball{.id = p.id()});
      k = static_cast<int>(out.state.balls.size()) - 1;
    }
    out.state.balls[k].r = Eigen::Vector3d(p.x_m(), p.y_m(), out.model.radius());
  }
  if (static_cast<int>(out.state.balls.size()) > kMaxBalls) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "table.balls: at most %d balls on a table, got %d", kMaxBalls, out.state.balls.size()));
  }
  if (absl::Status s = b::ValidateLayout(out.model, out.state); !s.ok()) {
    return PrefixStatus("table.balls: ", s);
  }
  return out;
}

absl::StatusOr<b::SolverOptions> SolverFromProto(const v1::SolverConfig& solver) {
  b::SolverOptions o;
  switch (solver.engine()) {
    case v1::ENGINE_UNSPECIFIED: o.engine = b::Engine::kEvent; break;  // drag: see below
    case v1::ENGINE_STEPPED: o.engine = b::Engine::kStepped; break;
    case v1::ENGINE_EVENT: o.engine = b::Engine::kEvent; break;
    default:
      return absl::InvalidArgumentError(
          absl::StrFormat("solver.engine: unknown value %d", solver.engine()));
  }
  switch (solver.integrator()) {
    case v1::BILLIARDS_INTEGRATOR_UNSPECIFIED:
    case v1::BILLIARDS_INTEGRATOR_RK4: o.integrator = b::Integrator::kRk4; break;
    case v1::BILLIARDS_INTEGRATOR_EULER: o.integrator = b::Integrator::kEuler; break;
    case v1::BILLIARDS_INTEGRATOR_SEMI_IMPLICIT_EULER:
      o.integrator = b::Integrator::kSemiImplicitEuler;
      break;
    default:
      return absl::InvalidArgumentError(
          absl::StrFormat("solver.integrator: unknown value %d", solver.integrator()));
  }
  if (solver.has_dt_s()) o.dt_s = solver.dt_s();
  o.ccd = !solver.no_ccd();
  if (solver.has_max_events()) o.max_events = solver.max_events();
  uint32_t asked_off = 0;  // what the request disables (the defaults aside: drag is off)
  for (const std::string& name : solver.disable()) {
    const uint32_t bit = b::EffectFromName(name);
    if (bit == 0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "solver.disable: unknown effect %s (GetInfo lists the effects)", Quote(name)));
    }
    asked_off |= bit;
    o.effects = b::WithEffect(o.effects, bit, /*on=*/false);
  }
  for (const std::string& name : solver.enable()) {
    const uint32_t bit = b::EffectFromName(name);
    if (bit == 0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "solver.enable: unknown effect %s (GetInfo lists the effects)", Quote(name)));
    }
    if (asked_off & bit) {
      return absl::InvalidArgumentError(
          absl::StrFormat("solver: effect %s is both enabled and disabled", Quote(name)));
    }
    o.effects = b::WithEffect(o.effects, bit, /*on=*/true);
  }
  // Without an engine named, a scene with air drag (no closed form) gets the stepped engine.
  if (solver.engine() == v1::ENGINE_UNSPECIFIED && b::EffectOn(o.effects, b::kEffectEnableDrag)) {
    o.engine = b::Engine::kStepped;
  }
  if (absl::Status s = b::ValidateSolverOptions(o); !s.ok()) return PrefixStatus("solver.", s);
  return o;
}

absl::StatusOr<b::CueStrike> StrikeFromProto(const v1::CueStrike& strike) {
  b::CueStrike s;
  switch (strike.speed_case()) {
    case v1::CueStrike::kSpeedMps:
      s.speed_mps = strike.speed_mps();
      break;
    case v1::CueStrike::kBallSpeedMps:
      s.speed_mps = strike.ball_speed_mps();
      s.ball_speed = true;
      break;
    case v1::CueStrike::SPEED_NOT_SET:
      return absl::InvalidArgumentError("strike: set speed_mps (cue speed) or ball_speed_mps");
  }
  s.phi_rad = DegToRad(strike.phi_deg());
  s.theta_rad = DegToRad(strike.theta_deg());
  s.a = strike.a();
  s.b = strike.b();
  s.noise = strike.noise();
  s.seed = strike.seed();
  return s;
}

void StrikeToProto(const b::CueStrike& s, v1::CueStrike* out) {
  if (s.ball_speed) {
    out->set_ball_speed_mps(s.speed_mps);
  } else {
    out->set_speed_mps(s.speed_mps);
  }
  out->set_phi_deg(RadToDeg(s.phi_rad));
  out->set_theta_deg(RadToDeg(s.theta_rad));
  out->set_a(s.a);
  out->set_b(s.b);
}

absl::StatusOr<ShotJob> ShotJobFromProto(const v1::SimulateShotRequest& request) {
  absl::StatusOr<TableBuild> table = TableFromProto(request.table());
  if (!table.ok()) return table.status();
  absl::StatusOr<b::SolverOptions> solver = SolverFromProto(request.solver());
  if (!solver.ok()) return solver.status();
  b::ShotOptions shot;
  if (request.max_time_s() != 0) shot.max_time_s = request.max_time_s();
  if (request.sample_rate_hz() != 0) {
    if (absl::Status s = CheckFiniteInRange("sample_rate_hz", request.sample_rate_hz(), 1, false,
                                            10000, false);
        !s.ok()) {
      return s;
    }
    shot.sample_interval_s = 1.0 / request.sample_rate_hz();
  }
  if (absl::Status s = b::ValidateShotOptions(shot); !s.ok()) return s;
  ShotJob job{.table = *std::move(table), .solver = *solver, .shot = shot,
              .include_geometry = request.include_geometry()};
  b::TableState& state = job.table.state;
  if (request.has_strike() && request.motions_size() > 0) {
    return absl::InvalidArgumentError("give either strike or motions, not both");
  }
  if (request.has_strike()) {
    absl::StatusOr<b::CueStrike> strike = StrikeFromProto(request.strike());
    if (!strike.ok()) return strike.status();
    const std::string id = request.strike().ball().empty() ? "cue" : request.strike().ball();
    const int cue = state.Find(id);
    if (cue < 0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "strike.ball: no ball %s on the table (place it with table.balls)", Quote(id)));
    }
    absl::StatusOr<b::StrikeOutcome> out =
        b::ApplyStrike(job.table.model, job.solver.effects, *strike, cue, &state);
    if (!out.ok()) return PrefixStatus("strike.", out.status());
    job.strike = *out;
  } else if (request.motions_size() > 0) {
    if (request.motions_size() > kMaxBalls) {
      return absl::InvalidArgumentError(absl::StrFormat("motions: at most %d", kMaxBalls));
    }
    for (int i = 0; i < request.motions_size(); ++i) {
      const v1::BallMotion& m = request.motions(i);
      const std::string field = absl::StrFormat("motions[%d]", i);
      const int k = state.Find(m.id());
      if (k < 0) {
        return absl::InvalidArgumentError(
            absl::StrFormat("%s.id: no ball %s on the table", field, Quote(m.id())));
      }
      const double vals[] = {m.vx_mps(), m.vy_mps(), m.wx_rps(), m.wy_rps(), m.wz_rps()};
      const char* names[] = {"vx_mps", "vy_mps", "wx_rps", "wy_rps", "wz_rps"};
      const double limits[] = {b::kMaxStrikeSpeed, b::kMaxStrikeSpeed, 2000, 2000, 2000};
      for (int j = 0; j < 5; ++j) {
        if (absl::Status s = CheckFiniteInRange(absl::StrCat(field, ".", names[j]), vals[j],
                                                -limits[j], false, limits[j], false);
            !s.ok()) {
          return s;
        }
      }
      state.balls[k].v = Eigen::Vector3d(m.vx_mps(), m.vy_mps(), 0.0);
      state.balls[k].w = Eigen::Vector3d(m.wx_rps(), m.wy_rps(), m.wz_rps());
    }
  } else {
    return absl::InvalidArgumentError("give a strike or motions: nothing would move");
  }
  return job;
}

v1::MotionState MotionStateToProto(b::MotionState s) {
  switch (s) {
    case b::MotionState::kStationary: return v1::stationary;
    case b::MotionState::kSpinning: return v1::spinning;
    case b::MotionState::kSliding: return v1::sliding;
    case b::MotionState::kRolling: return v1::rolling;
    case b::MotionState::kAirborne: return v1::airborne;
    case b::MotionState::kPocketed: return v1::pocketed;
  }
  return v1::motion_state_unspecified;
}

void BallToProto(const b::TableModel& model, const b::Ball& ball, v1::BallState* out) {
  out->set_id(ball.id);
  out->set_x_m(ball.r.x());
  out->set_y_m(ball.r.y());
  out->set_state(MotionStateToProto(ball.state));
  out->set_vx_mps(ball.v.x());
  out->set_vy_mps(ball.v.y());
  out->set_wx_rps(ball.w.x());
  out->set_wy_rps(ball.w.y());
  out->set_wz_rps(ball.w.z());
  out->set_qw(ball.q.w());
  out->set_qx(ball.q.x());
  out->set_qy(ball.q.y());
  out->set_qz(ball.q.z());
  if (ball.state == b::MotionState::kPocketed) {
    out->set_pocket(ball.pocket >= 0 ? model.spec().pockets[ball.pocket].name : "off_table");
  }
}

void EventToProto(const b::TableModel& model, const b::TableState& state, const b::Event& e,
                  v1::TableEvent* out) {
  out->set_t_s(e.t_s);
  const auto add_velocity = [out, &state](int ball, const Eigen::Vector2d& v) {
    v1::BallVelocity* bv = out->add_after();
    bv->set_id(state.balls[ball].id);
    bv->set_vx_mps(v.x());
    bv->set_vy_mps(v.y());
  };
  out->add_balls(state.balls[e.a].id);
  switch (e.kind) {
    case b::EventKind::kBallBall:
      out->set_kind(v1::ball_ball);
      out->add_balls(state.balls[e.b].id);
      add_velocity(e.a, e.va);
      add_velocity(e.b, e.vb);
      break;
    case b::EventKind::kBallCushion:
      out->set_kind(v1::ball_cushion);
      out->set_cushion(model.spec().cushions[e.other].name);
      add_velocity(e.a, e.va);
      break;
    case b::EventKind::kBallPocket:
      out->set_kind(v1::ball_pocket);
      out->set_pocket(e.other >= 0 ? model.spec().pockets[e.other].name : "off_table");
      break;
    case b::EventKind::kTransition:
      out->set_kind(v1::transition);
      out->set_from(MotionStateToProto(e.from));
      out->set_to(MotionStateToProto(e.to));
      break;
  }
}

void GeometryToProto(const b::TableModel& model, v1::TableGeometry* out) {
  const b::TableSpec& spec = model.spec();
  out->set_preset(spec.name);
  out->set_bounded(spec.bounded);
  out->set_length_m(spec.length_m);
  out->set_width_m(spec.width_m);
  out->set_ball_radius_m(model.radius());
  out->set_cushion_contact_m(model.cushion_contact_distance());
  for (const b::CushionSegment& c : spec.cushions) {
    v1::CushionLine* l = out->add_cushions();
    l->set_name(c.name);
    l->set_x1_m(c.a.x());
    l->set_y1_m(c.a.y());
    l->set_x2_m(c.b.x());
    l->set_y2_m(c.b.y());
  }
  for (const b::Pocket& p : spec.pockets) {
    v1::PocketCircle* c = out->add_pockets();
    c->set_name(p.name);
    c->set_x_m(p.centre.x());
    c->set_y_m(p.centre.y());
    c->set_radius_m(p.radius_m);
  }
}

void StrikeReportToProto(const b::StrikeOutcome& strike, v1::StrikeReport* s) {
  s->set_cue_speed_mps(strike.cue_speed_mps);
  s->set_ball_speed_mps(strike.v.head<2>().norm());
  s->set_phi_deg(RadToDeg(strike.applied.phi_rad));
  s->set_theta_deg(RadToDeg(strike.applied.theta_rad));
  s->set_a(strike.applied.a);
  s->set_b(strike.applied.b);
  s->set_squirt_deg(RadToDeg(strike.squirt_rad));
}

void ShotResultToProto(const ShotJob& job, const b::ShotResult& result,
                       v1::SimulateShotResponse* out) {
  const b::TableModel& model = job.table.model;
  out->set_t_rest_s(result.t_rest_s);
  out->set_at_rest(result.at_rest);
  for (const b::Ball& ball : result.final_state.balls) BallToProto(model, ball, out->add_balls());
  for (const b::Event& e : result.events) {
    EventToProto(model, result.final_state, e, out->add_events());
  }
  out->set_cpu_s(result.cpu_s);
  if (job.strike) StrikeReportToProto(*job.strike, out->mutable_strike());
  for (const b::Sample& sample : result.samples) {
    v1::ShotSample* ps = out->add_samples();
    ps->set_t_s(sample.t_s);
    for (size_t i = 0; i < sample.r.size(); ++i) {
      ps->add_x_m(sample.r[i].x());
      ps->add_y_m(sample.r[i].y());
      ps->add_state(MotionStateToProto(sample.state[i]));
    }
  }
  out->set_engine(std::string(b::EngineName(job.solver.engine)));
  if (job.solver.engine == b::Engine::kStepped) {  // the event engine has neither
    out->set_integrator(std::string(b::IntegratorName(job.solver.integrator)));
    out->set_dt_s(job.solver.dt_s);
  }
  if (job.include_geometry) GeometryToProto(model, out->mutable_geometry());
}

void AddBilliardsCapabilities(v1::Capabilities* caps) {
  for (std::string_view e : b::EngineNames()) caps->add_engines(std::string(e));  // default first
  for (std::string_view i : b::IntegratorNames()) caps->add_integrators(std::string(i));
  for (std::string_view p : b::TablePresetNames()) caps->add_table_presets(std::string(p));
  for (std::string_view r : b::RackNames()) caps->add_racks(std::string(r));
  for (std::string_view e : b::EffectNames()) caps->add_effects(std::string(e));
  const b::PhysicsParams defaults = b::MakeTablePreset("pool-9ft")->params;
  for (const b::ParamInfo& p : b::ParamInfos()) {
    v1::ParameterInfo* info = caps->add_parameters();
    info->set_name(std::string(p.name));
    info->set_unit(std::string(p.unit));
    info->set_default_value(defaults.*p.field);
    info->set_min_value(p.lo);
    info->set_max_value(p.hi);
    info->set_description(std::string(p.description));
  }
}

}  // namespace sportsim::server
