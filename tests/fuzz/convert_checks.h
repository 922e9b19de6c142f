// Finite-value checks of the converters' OK results (shared by the converter fuzz targets).
#ifndef SPORTSIM_TESTS_FUZZ_CONVERT_CHECKS_H_
#define SPORTSIM_TESTS_FUZZ_CONVERT_CHECKS_H_

#include "server/billiards/convert.h"
#include "server/billiards/game_convert.h"
#include "server/swing/convert.h"
#include "tests/fuzz/fuzz_util.h"

namespace sportsim::fuzz {

inline void CheckFiniteBalls(const billiards::TableState& s) {
  FUZZ_FINITE(s.t_s);
  for (const billiards::Ball& b : s.balls) {
    FUZZ_CHECK(b.r.allFinite() && b.v.allFinite() && b.w.allFinite() && b.q.coeffs().allFinite(),
               "ball %s has a non-finite position, velocity, spin or orientation", b.id.c_str());
  }
}

inline void CheckFiniteTable(const server::TableBuild& t) {
  const billiards::TableSpec& spec = t.model.spec();
  for (const billiards::ParamInfo& p : billiards::ParamInfos()) {
    const double v = spec.params.*p.field;
    FUZZ_CHECK(std::isfinite(v) && v >= p.lo && v <= p.hi, "param %s = %g outside [%g, %g]",
               std::string(p.name).c_str(), v, p.lo, p.hi);
  }
  FUZZ_FINITE(spec.length_m);
  FUZZ_FINITE(spec.width_m);
  for (const auto& c : spec.cushions) FUZZ_CHECK(c.a.allFinite() && c.b.allFinite(), "cushion");
  for (const auto& p : spec.pockets) FUZZ_CHECK(p.centre.allFinite() && std::isfinite(p.radius_m), "pocket");
  FUZZ_FINITE(t.model.inertia());
  FUZZ_FINITE(t.model.cushion_contact_distance());
  FUZZ_CHECK(static_cast<int>(t.state.balls.size()) <= server::kMaxBalls, "too many balls");
  CheckFiniteBalls(t.state);
}

inline void CheckFiniteSolver(const billiards::SolverOptions& o) {
  FUZZ_CHECK(std::isfinite(o.dt_s) && o.dt_s > 0, "solver dt_s = %g", o.dt_s);
  FUZZ_CHECK(o.max_events >= 1, "max_events = %lld", static_cast<long long>(o.max_events));
}

inline void CheckFiniteStrike(const billiards::StrikeOutcome& s) {
  FUZZ_CHECK(s.v.allFinite() && s.w.allFinite(), "strike outcome v/w not finite");
  FUZZ_FINITE(s.cue_speed_mps);
  FUZZ_FINITE(s.squirt_rad);
  FUZZ_FINITE(s.applied.speed_mps);
  FUZZ_FINITE(s.applied.phi_rad);
  FUZZ_FINITE(s.applied.theta_rad);
  FUZZ_FINITE(s.applied.a);
  FUZZ_FINITE(s.applied.b);
}

inline void CheckFiniteFlightJob(const server::FlightJob& j) {
  FUZZ_FINITE(j.launch.ball_speed_mps);
  FUZZ_FINITE(j.launch.launch_angle_deg);
  FUZZ_FINITE(j.launch.launch_direction_deg);
  FUZZ_FINITE(j.launch.spin_rpm);
  FUZZ_FINITE(j.launch.spin_axis_deg);
  FUZZ_FINITE(j.atmosphere.temperature_c);
  FUZZ_FINITE(j.atmosphere.pressure_pa);
  FUZZ_FINITE(j.atmosphere.relative_humidity);
  FUZZ_FINITE(j.atmosphere.altitude_m);
  FUZZ_FINITE(j.wind.speed_mps);
  FUZZ_FINITE(j.wind.toward_deg);
  FUZZ_FINITE(j.options.sample_interval_s);
  if (j.options.accuracy.dt_s) FUZZ_FINITE(*j.options.accuracy.dt_s);
}

inline void CheckFiniteStrikeJob(const server::StrikeJob& j) {
  FUZZ_FINITE(j.club.head_mass_kg);
  FUZZ_FINITE(j.club.loft_deg);
  FUZZ_FINITE(j.club.cor);
  if (j.delivery.dynamic_loft_deg) FUZZ_FINITE(*j.delivery.dynamic_loft_deg);
  FUZZ_FINITE(j.delivery.face_angle_deg);
  FUZZ_FINITE(j.delivery.club_path_deg);
  CheckFiniteFlightJob(j.flight);
}

inline void CheckFiniteSwingModel(const swing::SwingModel& m) {
  const swing::SwingParams& p = m.params();
  for (double v : {p.arm_inertia_kgm2, p.arm_length_m, p.arm_first_moment_kgm, p.club_inertia_kgm2,
                   p.club_mass_kg, p.club_length_m, p.club_first_moment_kgm, p.gravity_mps2,
                   p.gamma_rad, p.beta0_rad, p.shoulder_accel_mps2, m.g(), m.a(),
                   m.arm_static_moment()}) {
    FUZZ_CHECK(std::isfinite(v), "swing model value %g not finite", v);
  }
}

inline void CheckFiniteSwingSolver(const swing::SwingSolverOptions& o) {
  if (o.integrator != swing::SwingIntegrator::kDp45) {
    FUZZ_CHECK(std::isfinite(o.dt()) && o.dt() > 0, "swing dt %g", o.dt());
  }
  if (o.accuracy.tolerance) FUZZ_FINITE(*o.accuracy.tolerance);
  if (o.accuracy.max_step_s) FUZZ_FINITE(*o.accuracy.max_step_s);
}

}  // namespace sportsim::fuzz

#endif  // SPORTSIM_TESTS_FUZZ_CONVERT_CHECKS_H_
