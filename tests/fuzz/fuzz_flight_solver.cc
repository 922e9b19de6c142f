// Golf: the club-ball impact and the ball's flight, with the delivery, club, launch conditions,
// air, wind and solver options decoded from the bytes within and slightly beyond their valid
// ranges (plus NaN, infinities, zeros). The validators must refuse the invalid ones cleanly
// (InvalidArgument; OutOfRange only for a flight that does not land in time or goes unstable).
// A flight is cut off after ~40k steps through its cancellation poll. An accepted impact must
// be finite and lose energy; an accepted flight must be finite, land (z = 0 at the last
// sample), and give bit-identical results twice.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "absl/strings/str_format.h"
#include "sim/golf/atmosphere.h"
#include "sim/golf/ball_flight.h"
#include "sim/golf/club_ball_impact.h"
#include "sim/golf/golf_ball.h"
#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/fuzz_values.h"

namespace g = sportsim::golf;
using sportsim::fuzz::Bits;
using sportsim::fuzz::RangeValue;

namespace {

void CheckCode(const char* what, const absl::Status& s, bool out_of_range_ok) {
  sportsim::fuzz::CheckMessage(what, s);
  FUZZ_CHECK(s.code() == absl::StatusCode::kInvalidArgument ||
                 (out_of_range_ok && s.code() == absl::StatusCode::kOutOfRange),
             "%s: %s", what, s.ToString().c_str());
}

// Everything a flight was given, to 17 digits: what a broken invariant prints, so the case can be
// rebuilt in a unit test without the fuzzer.
std::string FlightCase(const g::BallSpec& ball, const g::LaunchConditions& launch,
                       const g::Atmosphere& air, const g::Wind& wind, const g::FlightOptions& o) {
  return absl::StrFormat(
      "integrator %d, dt %.17g, tolerance %.17g, max step %.17g, sample interval %.17g s, max "
      "flight time %.17g s, launch height %.17g m, g %.17g, effects %u, fit %d, decay %d; ball "
      "%.17g kg, %.17g m, inertia %.17g; launch %.17g m/s at %.17g deg, direction %.17g deg, "
      "spin %.17g rpm about %.17g deg; air %.17g C %.17g Pa %.17g rh %.17g m; wind %.17g m/s "
      "toward %.17g deg (profile %d)",
      static_cast<int>(o.integrator), o.accuracy.dt_s.value_or(NAN),
      o.accuracy.tolerance.value_or(NAN), o.accuracy.max_step_s.value_or(NAN),
      o.sample_interval_s, o.max_flight_time_s, o.launch_height_m, o.gravity_mps2, o.effects,
      static_cast<int>(o.aero.fit), static_cast<int>(o.spin_decay_model), ball.mass_kg,
      ball.diameter_m, ball.inertia_factor, launch.ball_speed_mps, launch.launch_angle_deg,
      launch.launch_direction_deg, launch.spin_rpm, launch.spin_axis_deg, air.temperature_c,
      air.pressure_pa, air.relative_humidity, air.altitude_m, wind.speed_mps, wind.toward_deg,
      static_cast<int>(wind.profile));
}

void Fly(FuzzedDataProvider& in, const g::LaunchConditions& launch) {
  g::BallSpec ball;
  if (in.ConsumeIntegralInRange(0, 7) == 0) {
    ball.mass_kg = RangeValue(in, 0, 1);
    ball.diameter_m = RangeValue(in, 0, 0.5);
    ball.inertia_factor = RangeValue(in, 0, 2.0 / 3);
  }
  g::Atmosphere air;
  if (in.ConsumeBool()) {
    air.temperature_c = RangeValue(in, -60, 60);
    air.pressure_pa = RangeValue(in, 80000, 110000);
    air.relative_humidity = RangeValue(in, 0, 1);
    air.altitude_m = RangeValue(in, -500, 5000);
  }
  g::Wind wind;
  if (in.ConsumeBool()) {
    wind.speed_mps = RangeValue(in, 0, 50);
    wind.toward_deg = RangeValue(in, -360, 360);
    wind.profile = in.ConsumeBool() ? g::WindProfile::kLogarithmic : g::WindProfile::kUniform;
    if (in.ConsumeIntegralInRange(0, 3) == 0) {
      wind.reference_height_m = RangeValue(in, 0.1, 100);
      wind.roughness_length_m = RangeValue(in, 0.0001, 1);
    }
  }
  g::FlightOptions o;
  const uint8_t scheme = in.ConsumeIntegral<uint8_t>();
  o.integrator = scheme < 120   ? sportsim::ode::Integrator::kRk4
                 : scheme < 240 ? sportsim::ode::Integrator::kDp45
                                : static_cast<sportsim::ode::Integrator>(scheme % 6);
  if (in.ConsumeBool()) o.accuracy.dt_s = RangeValue(in, 1e-4, 0.1);
  if (o.integrator == sportsim::ode::Integrator::kDp45 || in.ConsumeIntegralInRange(0, 7) == 0) {
    o.accuracy.tolerance = RangeValue(in, 1e-10, 1e-2);
    if (in.ConsumeBool()) o.accuracy.max_step_s = RangeValue(in, 1e-4, 1);
  }
  if (in.ConsumeBool()) o.sample_interval_s = RangeValue(in, 0, 10);
  if (in.ConsumeBool()) o.max_flight_time_s = RangeValue(in, 0.5, 30);
  if (in.ConsumeIntegralInRange(0, 3) == 0) o.launch_height_m = RangeValue(in, 0, 100);
  if (in.ConsumeIntegralInRange(0, 3) == 0) o.gravity_mps2 = RangeValue(in, 1, 30);
  o.spin_decay_model = in.ConsumeBool() ? g::SpinDecayModel::kInstantaneous
                                        : g::SpinDecayModel::kLaunchSpeed;
  o.aero.fit = in.ConsumeBool() ? g::AeroFit::kNathan : g::AeroFit::kFergusonMcNallyMcPhee2022;
  o.effects = in.ConsumeIntegral<uint8_t>();
  if (o.effects < 224) o.effects &= g::kFlightEffectBits;
  // Work bound: skip settings that are valid but would take millions of steps or samples.
  const double t_max = o.max_flight_time_s;
  if (o.accuracy.dt_s && *o.accuracy.dt_s > 0 && t_max / *o.accuracy.dt_s > 1e5) return;
  if (o.accuracy.max_step_s && *o.accuracy.max_step_s > 0 && t_max / *o.accuracy.max_step_s > 1e5) {
    return;
  }
  if (o.accuracy.tolerance && *o.accuracy.tolerance > 0 && *o.accuracy.tolerance < 1e-12) return;
  if (o.sample_interval_s > 0 && t_max / o.sample_interval_s > 1e5) return;
  // And a dp45 flight's step count is not known up front (a light, large ball is stiff): it
  // is stopped after ~40k steps through the cancellation poll, as a server's budget would.
  int polls = 0;
  o.cancelled = [&polls] { return ++polls > 40; };

  const absl::StatusOr<g::FlightResult> r1 = g::SimulateFlight(ball, launch, air, wind, o);
  polls = 0;
  const absl::StatusOr<g::FlightResult> r2 = g::SimulateFlight(ball, launch, air, wind, o);
  // Each check's message ends with the case (evaluated only when the check fails).
  const auto flight_case = [&] { return FlightCase(ball, launch, air, wind, o); };
  FUZZ_CHECK(r1.status() == r2.status(), "two flights differ: %s vs %s; %s",
             r1.status().ToString().c_str(), r2.status().ToString().c_str(),
             flight_case().c_str());
  if (r1.status().code() == absl::StatusCode::kCancelled) return;  // the work bound
  if (!r1.ok()) {
    CheckCode("SimulateFlight", r1.status(), /*out_of_range_ok=*/true);
    return;
  }
  const g::FlightResult& f = *r1;
  for (double v : {f.carry_m, f.carry_downrange_m, f.lateral_m, f.apex_m, f.apex_time_s,
                   f.flight_time_s, f.landing_angle_deg, f.landing_speed_mps, f.landing_spin_rpm,
                   f.air.density_kgpm3}) {
    FUZZ_CHECK(std::isfinite(v), "flight summary value %g; %s", v, flight_case().c_str());
  }
  FUZZ_CHECK(f.landing_position_m.allFinite() && f.landing_velocity_mps.allFinite(),
             "landing; %s", flight_case().c_str());
  // A landing past the limit is refused (OutOfRange), so the bound is exact.
  FUZZ_CHECK(f.flight_time_s >= 0 && f.flight_time_s <= o.max_flight_time_s,
             "flight time %.17g; %s", f.flight_time_s, flight_case().c_str());
  FUZZ_CHECK(f.carry_m >= 0 && f.apex_m >= o.launch_height_m - 1e-9, "carry %g apex %g; %s",
             f.carry_m, f.apex_m, flight_case().c_str());
  double t_prev = -INFINITY;
  for (const g::FlightSample& s : f.samples) {
    for (double v : {s.t_s, s.x_m, s.y_m, s.z_m, s.vx_mps, s.vy_mps, s.vz_mps, s.speed_mps,
                     s.spin_rpm}) {
      FUZZ_CHECK(std::isfinite(v), "flight sample at t = %g: value %g; %s", s.t_s, v,
                 flight_case().c_str());
    }
    FUZZ_CHECK(s.t_s >= t_prev, "samples out of order: %g after %g; %s", s.t_s, t_prev,
               flight_case().c_str());
    t_prev = s.t_s;
  }
  if (!f.samples.empty()) {
    FUZZ_CHECK(std::abs(f.samples.back().z_m) < 1e-6,
               "last sample at z = %g, t = %.17g (%zu samples; flight time %.17g s, %d steps); %s",
               f.samples.back().z_m, f.samples.back().t_s, f.samples.size(), f.flight_time_s,
               static_cast<int>(f.steps), flight_case().c_str());
  }
  const g::FlightResult& h = *r2;
  bool same = f.samples.size() == h.samples.size() && f.steps == h.steps &&
              Bits(f.carry_m) == Bits(h.carry_m) && Bits(f.flight_time_s) == Bits(h.flight_time_s);
  for (size_t i = 0; same && i < f.samples.size(); ++i) {
    same = Bits(f.samples[i].x_m) == Bits(h.samples[i].x_m) &&
           Bits(f.samples[i].z_m) == Bits(h.samples[i].z_m);
  }
  FUZZ_CHECK(same, "two flights differ (carry %.17g vs %.17g); %s", f.carry_m, h.carry_m,
             flight_case().c_str());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  g::LaunchConditions launch;
  if (in.ConsumeBool()) {
    // The launch from a club's impact (what a swing session does).
    absl::StatusOr<g::ClubSpec> club =
        g::ClubPreset(g::internal::kClubPresets[in.ConsumeIntegralInRange<size_t>(
                          0, g::internal::kClubPresets.size() - 1)].name);
    FUZZ_CHECK(club.ok(), "preset");
    if (in.ConsumeBool()) club->cor = RangeValue(in, 0, 1);
    if (in.ConsumeIntegralInRange(0, 3) == 0) club->head_mass_kg = RangeValue(in, 0, 2);
    if (in.ConsumeIntegralInRange(0, 3) == 0) club->loft_deg = RangeValue(in, -30, 90);
    g::ClubDelivery d;
    d.clubhead_speed_mps = RangeValue(in, 0, 100);
    d.attack_angle_deg = RangeValue(in, -45, 45);
    d.club_path_deg = RangeValue(in, -45, 45);
    d.face_angle_deg = RangeValue(in, -45, 45);
    if (in.ConsumeBool()) d.dynamic_loft_deg = RangeValue(in, -30, 90);
    g::ImpactOptions io;
    if (in.ConsumeIntegralInRange(0, 3) == 0) {
      io.friction_coefficient = in.ConsumeBool() ? INFINITY : RangeValue(in, 0, 2);
    }
    absl::StatusOr<g::ImpactResult> hit = g::SimulateImpact(d, *club, g::BallSpec{}, io);
    if (!hit.ok()) {
      CheckCode("SimulateImpact", hit.status(), false);
      return 0;
    }
    const g::ImpactResult& i = *hit;
    for (double v : {i.launch.ball_speed_mps, i.launch.launch_angle_deg,
                     i.launch.launch_direction_deg, i.launch.spin_rpm, i.launch.spin_axis_deg,
                     i.backspin_rpm, i.sidespin_rpm, i.smash_factor, i.spin_loft_deg,
                     i.normal_impulse_ns, i.tangential_impulse_ns, i.kinetic_energy_before_j,
                     i.kinetic_energy_after_j}) {
      FUZZ_CHECK(std::isfinite(v),
                 "impact value %g not finite; SimulateImpact(delivery {speed %.17g, attack %.17g, "
                 "path %.17g, face %.17g, dynamic loft %.17g (set: %d)}, club {%s, head %.17g kg, "
                 "loft %.17g, cor %.17g}, friction %.17g)",
                 v, d.clubhead_speed_mps, d.attack_angle_deg, d.club_path_deg, d.face_angle_deg,
                 d.dynamic_loft_deg.value_or(NAN), d.dynamic_loft_deg.has_value(),
                 club->name.c_str(), club->head_mass_kg, club->loft_deg, club->cor,
                 io.friction_coefficient);
    }
    FUZZ_CHECK(i.ball_velocity_mps.allFinite() && i.ball_spin_radps.allFinite() &&
                   i.club_velocity_after_mps.allFinite(),
               "impact vectors not finite");
    FUZZ_CHECK(i.kinetic_energy_after_j <= i.kinetic_energy_before_j * (1 + 1e-9) + 1e-12,
               "impact gains energy: %.17g J -> %.17g J", i.kinetic_energy_before_j,
               i.kinetic_energy_after_j);
    launch = i.launch;
    if (!g::ValidateLaunchConditions(launch).ok()) return 0;  // LaunchBall reports it
  } else {
    launch.ball_speed_mps = RangeValue(in, 0, 120);
    launch.launch_angle_deg = RangeValue(in, -90, 90);
    launch.launch_direction_deg = RangeValue(in, -90, 90);
    launch.spin_rpm = RangeValue(in, 0, 30000);
    launch.spin_axis_deg = RangeValue(in, -180, 180);
  }
  Fly(in, launch);
  return 0;
}
