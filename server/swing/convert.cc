#include "server/swing/convert.h"

#include <cmath>
#include <string_view>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "server/world/world.h"
#include "sim/core/cpu_clock.h"
#include "sim/core/units.h"

namespace sportsim::server {
namespace {

using swing::Interpolation;
using swing::SwingIntegrator;

absl::Status CheckAngleDeg(std::string_view name, double deg) {
  if (std::isfinite(deg) && deg >= -360.0 && deg <= 360.0) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrFormat("parameters.%s must be finite and in [-360, 360] deg, got %g", name, deg));
}

absl::StatusOr<swing::TorqueSchedule> ScheduleFromProto(std::string_view name,
                                                        const v1::TorqueSchedule& s) {
  swing::TorqueSchedule out;
  switch (s.interpolation()) {
    case v1::INTERPOLATION_UNSPECIFIED:
    case v1::INTERPOLATION_PIECEWISE_CONSTANT:
      out.interpolation = Interpolation::kPiecewiseConstant;
      break;
    case v1::INTERPOLATION_PIECEWISE_LINEAR:
      out.interpolation = Interpolation::kPiecewiseLinear;
      break;
    default:
      return absl::InvalidArgumentError(absl::StrFormat(
          "torques.%s.interpolation: unknown value %d", name, static_cast<int>(s.interpolation())));
  }
  if (s.knots_size() > swing::TorqueProgram::kMaxKnots) {
    // Refuse before copying an oversized list.
    return absl::InvalidArgumentError(absl::StrFormat("torques.%s.knots must have 1 to %d knots, got %d",
                                                      name, swing::TorqueProgram::kMaxKnots,
                                                      s.knots_size()));
  }
  for (const v1::TorqueKnot& k : s.knots()) out.knots.push_back({k.t_s(), k.torque_nm()});
  return out;
}

}  // namespace

absl::StatusOr<swing::SwingModel> SwingModelFromProto(
    const v1::SwingParameters& p, const google::protobuf::RepeatedField<int>& disabled_effects) {
  swing::SwingParams params;
  if (p.has_arm_inertia_kgm2()) params.arm_inertia_kgm2 = p.arm_inertia_kgm2();
  if (p.has_arm_length_m()) params.arm_length_m = p.arm_length_m();
  if (p.has_arm_first_moment_kgm()) params.arm_first_moment_kgm = p.arm_first_moment_kgm();
  if (p.has_club_inertia_kgm2()) params.club_inertia_kgm2 = p.club_inertia_kgm2();
  if (p.has_club_mass_kg()) params.club_mass_kg = p.club_mass_kg();
  if (p.has_club_length_m()) params.club_length_m = p.club_length_m();
  if (p.has_club_first_moment_kgm()) params.club_first_moment_kgm = p.club_first_moment_kgm();
  if (p.has_gravity_mps2()) params.gravity_mps2 = p.gravity_mps2();
  if (p.has_shoulder_accel_mps2()) params.shoulder_accel_mps2 = p.shoulder_accel_mps2();
  if (p.has_gamma_deg()) {
    if (absl::Status s = CheckAngleDeg("gamma_deg", p.gamma_deg()); !s.ok()) return s;
    params.gamma_rad = DegToRad(p.gamma_deg());
  }
  if (p.has_beta0_deg()) {
    if (absl::Status s = CheckAngleDeg("beta0_deg", p.beta0_deg()); !s.ok()) return s;
    params.beta0_rad = DegToRad(p.beta0_deg());
  }
  uint32_t disabled = 0;
  for (int i = 0; i < disabled_effects.size(); ++i) {
    switch (disabled_effects.Get(i)) {
      case v1::SWING_EFFECT_GRAVITY: disabled |= swing::kSwingDisableGravity; break;
      case v1::SWING_EFFECT_SHOULDER_ACCEL: disabled |= swing::kSwingDisableShoulderAccel; break;
      case v1::SWING_EFFECT_WRIST_TORQUE: disabled |= swing::kSwingDisableWristTorque; break;
      default:
        return absl::InvalidArgumentError(absl::StrFormat(
            "disabled_effects[%d]: unknown effect %d", i, disabled_effects.Get(i)));
    }
  }
  absl::StatusOr<swing::SwingModel> model = swing::SwingModel::Create(params, disabled);
  if (!model.ok()) return PrefixStatus("parameters.", model.status());
  return model;
}

absl::StatusOr<swing::TorqueProgram> TorqueProgramFromProto(const v1::TorqueProgram& program,
                                                            bool has_program) {
  const swing::TorqueProgram chapter = swing::TorqueProgram::Chapter();
  if (!has_program) return chapter;
  swing::TorqueSchedule qa = chapter.q_alpha(), qb = chapter.q_beta();
  if (program.has_qalpha()) {
    absl::StatusOr<swing::TorqueSchedule> s = ScheduleFromProto("qalpha", program.qalpha());
    if (!s.ok()) return s.status();
    qa = *std::move(s);
  }
  if (program.has_qbeta()) {
    absl::StatusOr<swing::TorqueSchedule> s = ScheduleFromProto("qbeta", program.qbeta());
    if (!s.ok()) return s.status();
    qb = *std::move(s);
  }
  absl::StatusOr<swing::TorqueProgram> out = swing::TorqueProgram::Create(qa, qb);
  if (!out.ok()) return PrefixStatus("torques.", out.status());
  return out;
}

absl::StatusOr<swing::SwingSolverOptions> SwingSolverFromProto(const v1::SwingSolver& s) {
  swing::SwingSolverOptions o;
  switch (s.integrator()) {
    case v1::SWING_INTEGRATOR_UNSPECIFIED:
    case v1::SWING_INTEGRATOR_RK4: o.integrator = SwingIntegrator::kRk4; break;
    case v1::SWING_INTEGRATOR_BOOK: o.integrator = SwingIntegrator::kBook; break;
    case v1::SWING_INTEGRATOR_EULER: o.integrator = SwingIntegrator::kEuler; break;
    case v1::SWING_INTEGRATOR_SEMI_IMPLICIT_EULER:
      o.integrator = SwingIntegrator::kSemiImplicitEuler;
      break;
    case v1::SWING_INTEGRATOR_DP45: o.integrator = SwingIntegrator::kDp45; break;
    default:
      return absl::InvalidArgumentError(absl::StrFormat("solver.integrator: unknown value %d",
                                                        static_cast<int>(s.integrator())));
  }
  if (s.has_dt_s()) o.accuracy.dt_s = s.dt_s();
  if (s.has_tolerance()) o.accuracy.tolerance = s.tolerance();
  if (s.has_max_step_s()) o.accuracy.max_step_s = s.max_step_s();
  if (absl::Status st = swing::ValidateSolverOptions(o); !st.ok()) return PrefixStatus("solver.", st);
  return o;
}

absl::StatusOr<SwingJob> SwingJobFromProto(const v1::SimulateSwingRequest& r) {
  absl::StatusOr<swing::SwingModel> model = SwingModelFromProto(r.parameters(), r.disabled_effects());
  if (!model.ok()) return model.status();
  absl::StatusOr<swing::TorqueProgram> program = TorqueProgramFromProto(r.torques(), r.has_torques());
  if (!program.ok()) return program.status();
  absl::StatusOr<swing::SwingSolverOptions> solver = SwingSolverFromProto(r.solver());
  if (!solver.ok()) return solver.status();

  swing::SwingRunOptions run;
  switch (r.stop()) {
    case v1::SWING_STOP_UNSPECIFIED:
    case v1::SWING_STOP_IMPACT: run.stop = swing::SwingStop::kImpact; break;
    case v1::SWING_STOP_DURATION: run.stop = swing::SwingStop::kDuration; break;
    default:
      return absl::InvalidArgumentError(
          absl::StrFormat("stop: unknown value %d", static_cast<int>(r.stop())));
  }
  run.duration_s = r.has_duration_s() ? r.duration_s()
                   : run.stop == swing::SwingStop::kDuration ? 0.5
                                                              : 2.0;
  if (r.sample_stride() > 1'000'000) {
    return absl::InvalidArgumentError(
        absl::StrFormat("sample_stride must be in [0, 1000000], got %d", r.sample_stride()));
  }
  // Automatic sampling keeps about kAutoSamples samples: a stride for fixed steps, a time
  // interval for dp45. Checked after the duration is known to be in range.
  constexpr double kAutoSamples = 5000;
  if (absl::Status s = swing::ValidateDuration(run.duration_s); !s.ok()) return s;
  if (r.sample_stride() > 0) {
    run.sample_stride = static_cast<int>(r.sample_stride());
  } else if (solver->integrator == SwingIntegrator::kDp45) {
    run.sample_interval_s = run.duration_s / kAutoSamples;
  } else {
    const double steps = run.duration_s / solver->dt();
    run.sample_stride = std::max(1, static_cast<int>(std::ceil(steps / kAutoSamples)));
  }
  if (absl::Status s = swing::ValidateRunOptions(*solver, run); !s.ok()) return s;
  SwingJob job{*std::move(model), *std::move(program), *solver, run, std::nullopt};
  if (r.has_ball()) {
    absl::StatusOr<StrikeJob> strike = StrikeJobFromProto(r.ball());
    if (!strike.ok()) return strike.status();
    job.strike = *std::move(strike);
  }
  return job;
}

void SampleToProto(const swing::SwingSample& s, v1::SwingSample* out) {
  out->set_t_s(s.t_s);
  out->set_theta_deg(RadToDeg(s.theta));
  out->set_alpha_deg(RadToDeg(s.alpha));
  out->set_beta_deg(RadToDeg(s.beta));
  out->set_phi_deg(RadToDeg(s.phi));
  out->set_clubhead_speed_mps(s.clubhead_speed_mps);
  out->set_alpha_dot_rps(s.alpha_dot);
  out->set_beta_dot_rps(s.beta_dot);
  out->set_clubhead_speed_ground_mps(s.clubhead_speed_ground_mps);
  out->set_clubhead_x_m(s.clubhead_x_m);
  out->set_clubhead_y_m(s.clubhead_y_m);
  out->set_clubhead_vx_mps(s.clubhead_vx_mps);
  out->set_clubhead_vy_mps(s.clubhead_vy_mps);
}

void ImpactToProto(const swing::SwingSample& s, v1::SwingImpact* out) {
  out->set_t_s(s.t_s);
  out->set_alpha_deg(RadToDeg(s.alpha));
  out->set_beta_deg(RadToDeg(s.beta));
  out->set_theta_deg(RadToDeg(s.theta));
  out->set_phi_deg(RadToDeg(s.phi));
  out->set_alpha_dot_rps(s.alpha_dot);
  out->set_beta_dot_rps(s.beta_dot);
  out->set_clubhead_speed_mps(s.clubhead_speed_mps);
  out->set_clubhead_speed_ground_mps(s.clubhead_speed_ground_mps);
  out->set_clubhead_vx_ground_mps(s.clubhead_vx_ground_mps);
  out->set_clubhead_vy_ground_mps(s.clubhead_vy_ground_mps);
  // Angle above the horizontal of the velocity, measured toward the target (-x).
  out->set_clubhead_direction_deg(
      RadToDeg(std::atan2(s.clubhead_vy_ground_mps, -s.clubhead_vx_ground_mps)));
}

void SwingResultToProto(const swing::SwingRunResult& r, double cpu_s,
                        v1::SimulateSwingResponse* out) {
  if (r.impact) ImpactToProto(*r.impact, out->mutable_impact());
  out->mutable_samples()->Reserve(static_cast<int>(r.samples.size()));
  for (const swing::SwingSample& s : r.samples) SampleToProto(s, out->add_samples());
  out->set_steps(static_cast<uint32_t>(r.steps));
  out->set_cpu_s(cpu_s);
  out->set_rejected_steps(static_cast<uint32_t>(r.rejected_steps));
  out->set_rhs_evaluations(static_cast<uint32_t>(r.rhs_evaluations));
  out->set_end_t_s(r.end_t_s);
}

absl::StatusOr<std::optional<golf::Surface>> FairwayFromProto(std::string_view field,
                                                             const std::string& f) {
  if (f.empty()) return std::optional<golf::Surface>();
  const std::string name = f == "normal" ? "fairway"
                           : f == "firm" ? "fairway_firm"
                           : f == "soft" ? "fairway_soft"
                                         : "";
  if (name.empty()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s must be firm, normal or soft (or empty: no roll-out); got %s", field, Quote(f)));
  }
  return std::optional<golf::Surface>(*golf::SurfaceByName(name));
}

absl::Status RollOutToProto(const FlightJob& job, const golf::FlightResult& flight,
                            v1::SimulateFlightResponse* out) {
  if (!job.fairway.has_value()) return absl::OkStatus();
  golf::GroundOptions o;
  o.hole = false;
  o.sample_interval_s = 0;
  o.cancelled = job.options.cancelled;
  absl::StatusOr<golf::GroundResult> g =
      golf::SimulateGround(job.ball, *job.fairway, golf::GroundPlane{}, golf::Hole{},
                           golf::LandingFromFlight(flight), o);
  if (!g.ok()) return g.status();
  out->set_total_m(std::hypot(g->rest_m.x(), g->rest_m.y()));
  out->set_total_lateral_m(-g->rest_m.y());
  GroundRestToProto(*g, job.fairway->name, out->mutable_rest());
  for (const golf::GroundEvent& e : g->events) GroundEventToProto(e, out->add_ground_events());
  return absl::OkStatus();
}

void GroundEventToProto(const golf::GroundEvent& e, v1::GolfEvent* out) {
  out->set_t_s(e.t_s);
  out->set_kind(std::string(golf::GroundEventName(e.kind)));
  out->set_x_m(e.position_m.x());
  out->set_y_m(e.position_m.y());
  out->set_z_m(e.position_m.z());
  out->set_speed_mps(e.velocity_mps.norm());
  out->set_spin_rpm(e.spin_radps / golf::kRpmToRadPerS);
  out->set_surface(e.surface);
}

void GroundRestToProto(const golf::GroundResult& g, const std::string& surface,
                       v1::GolfRest* out) {
  out->set_x_m(g.rest_m.x());
  out->set_y_m(g.rest_m.y());
  out->set_z_m(g.rest_m.z());
  out->set_surface(surface);
  out->set_holed(g.holed);
}

absl::StatusOr<FlightJob> FlightJobFromProto(const v1::SimulateFlightRequest& r) {
  FlightJob job;
  absl::StatusOr<std::optional<golf::Surface>> fairway = FairwayFromProto("fairway", r.fairway());
  if (!fairway.ok()) return fairway.status();
  job.fairway = *fairway;
  const v1::LaunchConditions& l = r.launch();
  job.launch = {.ball_speed_mps = l.ball_speed_mps(),
                .launch_angle_deg = l.launch_angle_deg(),
                .launch_direction_deg = l.launch_direction_deg(),
                .spin_rpm = l.spin_rpm(),
                .spin_axis_deg = l.spin_axis_deg()};
  if (absl::Status s = golf::ValidateLaunchConditions(job.launch); !s.ok()) {
    return PrefixStatus("launch.", s);
  }
  const v1::Atmosphere& a = r.atmosphere();
  if (a.has_temperature_c()) job.atmosphere.temperature_c = a.temperature_c();
  if (a.has_sea_level_pressure_pa()) job.atmosphere.pressure_pa = a.sea_level_pressure_pa();
  if (a.has_relative_humidity()) job.atmosphere.relative_humidity = a.relative_humidity();
  if (a.has_altitude_m()) job.atmosphere.altitude_m = a.altitude_m();
  if (absl::StatusOr<golf::AirProperties> air = golf::ComputeAirProperties(job.atmosphere);
      !air.ok()) {
    return PrefixStatus("atmosphere.", air.status());
  }
  job.wind.speed_mps = r.wind().speed_mps();
  job.wind.toward_deg = r.wind().toward_deg();
  job.wind.profile = r.wind().logarithmic_profile() ? golf::WindProfile::kLogarithmic
                                                    : golf::WindProfile::kUniform;
  // (The library names the field: "wind speed_mps must be ...".)
  if (absl::Status s = golf::ValidateWind(job.wind); !s.ok()) return s;
  for (int i = 0; i < r.disabled_effects_size(); ++i) {
    switch (r.disabled_effects(i)) {
      case v1::FLIGHT_EFFECT_DRAG: job.options.effects |= golf::kFlightDisableDrag; break;
      case v1::FLIGHT_EFFECT_LIFT: job.options.effects |= golf::kFlightDisableLift; break;
      case v1::FLIGHT_EFFECT_SPIN_DECAY:
        job.options.effects |= golf::kFlightDisableSpinDecay;
        break;
      case v1::FLIGHT_EFFECT_WIND: job.options.effects |= golf::kFlightDisableWind; break;
      default:
        return absl::InvalidArgumentError(absl::StrFormat(
            "disabled_effects[%d]: unknown effect %d", i, static_cast<int>(r.disabled_effects(i))));
    }
  }
  switch (r.aero_fit()) {
    case v1::AERO_FIT_UNSPECIFIED:
    case v1::AERO_FIT_FERGUSON_2022:
      job.options.aero.fit = golf::AeroFit::kFergusonMcNallyMcPhee2022;
      break;
    case v1::AERO_FIT_NATHAN: job.options.aero.fit = golf::AeroFit::kNathan; break;
    default:
      return absl::InvalidArgumentError(
          absl::StrFormat("aero_fit: unknown fit %d", static_cast<int>(r.aero_fit())));
  }
  switch (r.integrator()) {
    case v1::SWING_INTEGRATOR_UNSPECIFIED:
    case v1::SWING_INTEGRATOR_RK4: job.options.integrator = ode::Integrator::kRk4; break;
    case v1::SWING_INTEGRATOR_DP45: job.options.integrator = ode::Integrator::kDp45; break;
    default:
      return absl::InvalidArgumentError(absl::StrFormat(
          "integrator: a flight is integrated by rk4 or dp45, got %d",
          static_cast<int>(r.integrator())));
  }
  if (r.has_tolerance()) job.options.accuracy.tolerance = r.tolerance();
  if (r.has_max_step_s()) job.options.accuracy.max_step_s = r.max_step_s();
  if (job.options.integrator == ode::Integrator::kDp45 && r.has_dt_s()) {
    return absl::InvalidArgumentError(
        "dt_s does not apply to dp45 (an error-controlled integrator): set tolerance");
  }
  // Tighter than the library's own limits: a request must stay cheap and its answer small
  // (a flight lasts at most 60 s: at most 6e6 steps and 6e4 samples).
  if (r.has_dt_s()) {
    if (!(std::isfinite(r.dt_s()) && r.dt_s() >= 1e-5 && r.dt_s() <= 0.1)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("dt_s must be finite and in [1e-05, 0.1] s, got %g", r.dt_s()));
    }
    job.options.accuracy.dt_s = r.dt_s();
  }
  if (r.has_sample_interval_s()) {
    if (!(std::isfinite(r.sample_interval_s()) && r.sample_interval_s() >= 1e-3 &&
          r.sample_interval_s() <= 10)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "sample_interval_s must be finite and in [0.001, 10] s, got %g", r.sample_interval_s()));
    }
    job.options.sample_interval_s = r.sample_interval_s();
  }
  return job;
}

absl::StatusOr<StrikeJob> StrikeJobFromProto(const v1::BallStrike& b) {
  StrikeJob job;
  if (!b.club().empty()) {
    if (absl::Status s = CheckId("ball.club", b.club()); !s.ok()) return s;
  }
  const std::string club = b.club().empty() ? "driver" : b.club();
  absl::StatusOr<golf::ClubSpec> spec = golf::ClubPreset(club);
  if (!spec.ok()) return PrefixStatus("ball.club: ", spec.status());
  job.club = *spec;
  if (b.has_cor()) job.club.cor = b.cor();
  if (absl::Status s = golf::ValidateClubSpec(job.club); !s.ok()) return PrefixStatus("ball.", s);
  if (b.has_dynamic_loft_deg()) job.delivery.dynamic_loft_deg = b.dynamic_loft_deg();
  job.delivery.face_angle_deg = b.face_angle_deg();
  job.delivery.club_path_deg = b.club_path_deg();
  // The delivery's own limits, checked now with a placeholder speed and a level attack, so a
  // bad face or loft is refused before any swing runs.
  golf::ClubDelivery probe = job.delivery;
  probe.clubhead_speed_mps = 40.0;
  if (absl::StatusOr<golf::ImpactResult> i = golf::SimulateImpact(probe, job.club, {});
      !i.ok()) {
    return PrefixStatus("ball.", i.status());
  }
  // The flight settings, validated as SimulateFlight's request would be, with a placeholder
  // launch that each impact replaces.
  for (int i = 0; i < b.disabled_flight_effects_size(); ++i) {
    const int e = b.disabled_flight_effects(i);
    if (e < v1::FLIGHT_EFFECT_DRAG || e > v1::FLIGHT_EFFECT_WIND) {
      return absl::InvalidArgumentError(
          absl::StrFormat("ball.disabled_flight_effects[%d]: unknown effect %d", i, e));
    }
  }
  v1::SimulateFlightRequest flight;
  *flight.mutable_atmosphere() = b.atmosphere();
  *flight.mutable_wind() = b.wind();
  *flight.mutable_disabled_effects() = b.disabled_flight_effects();
  flight.set_aero_fit(b.aero_fit());
  if (b.has_sample_interval_s()) flight.set_sample_interval_s(b.sample_interval_s());
  flight.set_fairway(b.fairway());
  flight.mutable_launch()->set_ball_speed_mps(60.0);
  absl::StatusOr<FlightJob> flight_job = FlightJobFromProto(flight);
  if (!flight_job.ok()) return PrefixStatus("ball.", flight_job.status());
  job.flight = *std::move(flight_job);
  return job;
}

void LaunchBall(const StrikeJob& job, const swing::SwingSample& impact, v1::BallLaunch* out) {
  golf::ClubDelivery delivery = job.delivery;
  delivery.clubhead_speed_mps = impact.clubhead_speed_ground_mps;
  // The ground-frame velocity's angle above the horizontal, toward the target (-x).
  delivery.attack_angle_deg =
      RadToDeg(std::atan2(impact.clubhead_vy_ground_mps, -impact.clubhead_vx_ground_mps));
  out->set_club(job.club.name);
  out->set_clubhead_speed_mps(delivery.clubhead_speed_mps);
  out->set_attack_angle_deg(delivery.attack_angle_deg);
  absl::StatusOr<golf::ImpactResult> hit = golf::SimulateImpact(delivery, job.club, {});
  if (!hit.ok()) {
    out->set_error(absl::StrCat("impact: ", hit.status().message()));
    return;
  }
  v1::LaunchConditions* l = out->mutable_launch();
  l->set_ball_speed_mps(hit->launch.ball_speed_mps);
  l->set_launch_angle_deg(hit->launch.launch_angle_deg);
  l->set_launch_direction_deg(hit->launch.launch_direction_deg);
  l->set_spin_rpm(hit->launch.spin_rpm);
  l->set_spin_axis_deg(hit->launch.spin_axis_deg);
  out->set_smash_factor(hit->smash_factor);
  out->set_backspin_rpm(hit->backspin_rpm);
  out->set_sidespin_rpm(hit->sidespin_rpm);
  out->set_spin_loft_deg(hit->spin_loft_deg);
  FlightJob flight = job.flight;
  flight.launch = hit->launch;  // SimulateFlight validates it
  const double cpu0 = ThreadCpuSeconds();
  absl::StatusOr<golf::FlightResult> result = golf::SimulateFlight(
      flight.ball, flight.launch, flight.atmosphere, flight.wind, flight.options);
  if (!result.ok()) {
    out->set_error(absl::StrCat("flight: ", result.status().message()));
    return;
  }
  FlightResultToProto(*result, 0.0, out->mutable_flight());
  if (absl::Status rolled = RollOutToProto(flight, *result, out->mutable_flight()); !rolled.ok()) {
    out->set_error(absl::StrCat("roll-out: ", rolled.message()));
  }
  out->mutable_flight()->set_cpu_s(ThreadCpuSeconds() - cpu0);
}

void FlightResultToProto(const golf::FlightResult& f, double cpu_s,
                         v1::SimulateFlightResponse* out) {
  out->set_carry_m(f.carry_m);
  out->set_apex_m(f.apex_m);
  out->set_flight_time_s(f.flight_time_s);
  out->set_landing_angle_deg(f.landing_angle_deg);
  out->set_lateral_m(f.lateral_m);
  out->mutable_samples()->Reserve(static_cast<int>(f.samples.size()));
  for (const golf::FlightSample& s : f.samples) {
    v1::FlightSample* o = out->add_samples();
    o->set_t_s(s.t_s);
    o->set_x_m(s.x_m);
    o->set_y_m(s.y_m);
    o->set_z_m(s.z_m);
    o->set_vx_mps(s.vx_mps);
    o->set_vy_mps(s.vy_mps);
    o->set_vz_mps(s.vz_mps);
    o->set_speed_mps(s.speed_mps);
    o->set_spin_rpm(s.spin_rpm);
  }
  out->set_landing_speed_mps(f.landing_speed_mps);
  out->set_carry_downrange_m(f.carry_downrange_m);
  out->set_apex_time_s(f.apex_time_s);
  out->set_air_density_kgpm3(f.air.density_kgpm3);
  out->set_steps(static_cast<uint32_t>(f.steps));
  out->set_cpu_s(cpu_s);
}

std::vector<v1::ParameterInfo> SwingParameterInfo() {
  const swing::SwingParams d;
  struct Row {
    const char* name;
    const char* unit;
    double def, lo, hi;
    const char* description;
  };
  const Row rows[] = {
      {"arm_inertia_kgm2", "kg m^2", d.arm_inertia_kgm2, 0, 100, "J: arm about the shoulder (> 0)"},
      {"arm_length_m", "m", d.arm_length_m, 0, 5, "R: shoulder to wrists (> 0)"},
      {"arm_first_moment_kgm", "kg m", d.arm_first_moment_kgm, 0, 100, "S_A: arm first moment about the shoulder"},
      {"club_inertia_kgm2", "kg m^2", d.club_inertia_kgm2, 0, 100, "I: club about the wrists (> 0)"},
      {"club_mass_kg", "kg", d.club_mass_kg, 0, 100, "Mc: club mass (> 0)"},
      {"club_length_m", "m", d.club_length_m, 0, 5, "L: wrists to clubhead (> 0)"},
      {"club_first_moment_kgm", "kg m", d.club_first_moment_kgm, 0, 100, "S: club first moment about the wrists"},
      {"gravity_mps2", "m/s^2", d.gravity_mps2, 0, 100, "g"},
      {"gamma_deg", "deg", RadToDeg(d.gamma_rad), -360, 360, "arm angle at the top of the backswing"},
      {"beta0_deg", "deg", RadToDeg(d.beta0_rad), -360, 360, "initial wrist cock"},
      {"shoulder_accel_mps2", "m/s^2", d.shoulder_accel_mps2, 0, 100, "A: shoulder acceleration toward the target"},
  };
  std::vector<v1::ParameterInfo> out;
  for (const Row& r : rows) {
    v1::ParameterInfo& p = out.emplace_back();
    p.set_name(r.name);
    p.set_unit(r.unit);
    p.set_default_value(r.def);
    p.set_min_value(r.lo);
    p.set_max_value(r.hi);
    p.set_description(r.description);
  }
  return out;
}

std::vector<std::string> SwingEffectNames() { return {"gravity", "shoulder_accel", "wrist_torque"}; }

}  // namespace sportsim::server
