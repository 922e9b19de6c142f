#include "sim/golf/surface.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "sim/core/check.h"

namespace sportsim::golf {

namespace {

constexpr double kStandardGravity = 9.80665;

// rho of a Stimpmeter reading (ft) for I = (2/5) m R^2: (5/7) rho g = v0^2 / (2 S).
constexpr double RhoOfStimp(double stimp_ft, double g = kStandardGravity) {
  return 1.4 * kStimpmeterSpeedMps * kStimpmeterSpeedMps / (2.0 * stimp_ft * kFootToM * g);
}

// The built-in surfaces. Sources and the reasoning for each estimate:
// - green: Penner's bounce as fitted (scales 1); Stimp 10 ft, a members' green (USGA: 8-10 for
//   members, 12-14 for tournaments); friction 0.4 in a bounce and a skid (an estimate: Penner's
//   rolling exit needs only that the impulse cap is not reached for ordinary approaches).
// - fringe (collar): cut higher than the green, rolls like a Stimp of about 7 ft (estimate),
//   bounces like the green.
// - fairway (normal): rolls like a Stimpmeter reading of about 3.1 ft (rho 0.25; fairway
//   readings of 3-6 ft are commonly reported), and takes a deeper pitch mark than Penner's
//   greens (critical angle x1.35). Firm: faster (rho 0.15, ~5.2 ft), livelier (restitution
//   x1.1), shallower (x1.1); soft: slower (rho 0.35, ~2.2 ft), deader (x0.8), deeper (x1.8).
//   These are calibrated, not measured: the bounce scales were chosen (the run is most
//   sensitive to the critical angle) so that the flight validation's tour drive (167 mph,
//   10.9 deg, 2686 rpm) rolls about 21 yd on the normal fairway, inside the 15-25 yd that
//   tour averages give (about 275 yd carry, 295-300 yd total), and so that a firm fairway
//   rolls several times farther than a soft one. The same constants give a tour 7-iron about
//   no roll and a tour pitching wedge a check of 2-3 yd back, inside "a few yards at most".
// - rough: long grass takes energy and grips (restitution x0.7, critical angle x2, skid
//   friction 0.6, rho 0.45: ~1.7 ft); estimates.
// - bunker: sand, the ball plugs or barely rolls (restitution x0.3, critical angle x4, friction
//   1.0, rho 1.2); estimates.
// - first_cut (the intermediate cut between fairway and rough): halfway between the fairway and
//   the rough in every constant; an estimate.
// - cartpath (asphalt or concrete): a hard surface the ball barely dents (critical angle x0.3)
//   and leaves lively (restitution x1.5, the most a surface may scale; Penner's curve times 1.5
//   gives about 0.6 at 10 m/s normal speed, a golf ball's restitution on concrete at that speed
//   is about 0.7-0.8, so this is, if anything, dead), friction 0.6, rolling fast (rho 0.03,
//   about a Stimp of 26 ft); estimates.
const std::array<Surface, 9>& Builtins() {
  static const std::array<Surface, 9> kSurfaces = {{
      {.name = "green", .restitution_scale = 1.0, .critical_angle_scale = 1.0,
       .bounce_friction = 0.4, .sliding_friction = 0.4, .rolling_resistance = RhoOfStimp(10.0)},
      {.name = "fringe", .restitution_scale = 1.0, .critical_angle_scale = 1.0,
       .bounce_friction = 0.4, .sliding_friction = 0.4, .rolling_resistance = 0.11},
      {.name = "fairway_firm", .restitution_scale = 1.1, .critical_angle_scale = 1.1,
       .bounce_friction = 0.4, .sliding_friction = 0.4, .rolling_resistance = 0.15},
      {.name = "fairway", .restitution_scale = 1.0, .critical_angle_scale = 1.35,
       .bounce_friction = 0.4, .sliding_friction = 0.4, .rolling_resistance = 0.25},
      {.name = "fairway_soft", .restitution_scale = 0.8, .critical_angle_scale = 1.8,
       .bounce_friction = 0.4, .sliding_friction = 0.4, .rolling_resistance = 0.35},
      {.name = "rough", .restitution_scale = 0.7, .critical_angle_scale = 2.0,
       .bounce_friction = 0.6, .sliding_friction = 0.6, .rolling_resistance = 0.45},
      {.name = "bunker", .restitution_scale = 0.3, .critical_angle_scale = 4.0,
       .bounce_friction = 1.0, .sliding_friction = 1.0, .rolling_resistance = 1.2},
      {.name = "first_cut", .restitution_scale = 0.85, .critical_angle_scale = 1.7,
       .bounce_friction = 0.5, .sliding_friction = 0.5, .rolling_resistance = 0.35},
      {.name = "cartpath", .restitution_scale = 1.5, .critical_angle_scale = 0.3,
       .bounce_friction = 0.6, .sliding_friction = 0.6, .rolling_resistance = 0.03},
  }};
  return kSurfaces;
}

}  // namespace

double Surface::stimp_ft() const {
  return 1.4 * kStimpmeterSpeedMps * kStimpmeterSpeedMps /
         (2.0 * rolling_resistance * kStandardGravity) / kFootToM;
}

absl::StatusOr<double> RollingResistanceFromStimp(double stimp_ft, double gravity_mps2) {
  if (auto s = CheckFiniteInRange("stimp_ft", stimp_ft, 1, false, 20, false); !s.ok()) return s;
  if (auto s = CheckFiniteInRange("gravity_mps2", gravity_mps2, 0, true, 100, false); !s.ok()) {
    return s;
  }
  return RhoOfStimp(stimp_ft, gravity_mps2);
}

double PennerRestitution(double vn) {
  if (vn > 20.0) return 0.120;
  vn = std::max(vn, 0.0);
  return 0.510 - 0.0375 * vn + 0.000903 * vn * vn;
}

double PennerCriticalAngle(double v, double descent_rad) {
  constexpr double kDeg = std::numbers::pi / 180.0;
  return 15.4 * kDeg * (v / 18.6) * (descent_rad / (44.4 * kDeg));
}

absl::Status ValidateSurface(const Surface& s) {
  if (s.name.empty()) return absl::InvalidArgumentError("surface name must not be empty");
  if (absl::Status st = CheckFieldsInRange({
          {"restitution_scale", s.restitution_scale, 0, true, 1.5},
          {"critical_angle_scale", s.critical_angle_scale, 0, false, 5},
          {"bounce_friction", s.bounce_friction, 0, false, 2},
          {"sliding_friction", s.sliding_friction, 0, true, 2},
          {"rolling_resistance", s.rolling_resistance, 0, true, 2},
      });
      !st.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("surface ", s.name, ": ", st.message()));
  }
  return absl::OkStatus();
}

std::span<const Surface> BuiltinSurfaces() { return Builtins(); }

absl::StatusOr<Surface> SurfaceByName(std::string_view name) {
  if (name == "fairway_normal") name = "fairway";
  for (const Surface& s : Builtins()) {
    if (s.name == name) return s;
  }
  std::vector<std::string> names;
  for (const Surface& s : Builtins()) names.push_back(s.name);
  return absl::InvalidArgumentError(absl::StrFormat("surface must be one of %s; got \"%s\"",
                                                    absl::StrJoin(names, ", "), name));
}

absl::StatusOr<Surface> GreenOfStimp(double stimp_ft) {
  absl::StatusOr<double> rho = RollingResistanceFromStimp(stimp_ft);
  if (!rho.ok()) return rho.status();
  Surface green = Builtins()[0];
  green.rolling_resistance = *rho;
  return green;
}

}  // namespace sportsim::golf
