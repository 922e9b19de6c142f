#include "sim/billiards/model.h"

#include <array>
#include <cmath>
#include <utility>

#include "absl/strings/str_format.h"
#include "sim/core/check.h"
#include "sim/core/units.h"

namespace sportsim::billiards {
namespace {

constexpr std::array<std::string_view, 8> kEffectNames = {
    "drag", "spin_decay", "rolling_resistance", "ball_friction",
    "cushions", "pockets", "orientation", "squirt"};

constexpr std::array<ParamInfo, 26> kParams = {{
    {"gravity_mps2", "m/s^2", "gravitational acceleration g", &PhysicsParams::gravity_mps2, 0.1, 100},
    {"ball_radius_m", "m", "ball radius R", &PhysicsParams::ball_radius_m, 0.005, 0.1},
    {"ball_mass_kg", "kg", "ball mass m (inertia 2/5 m R^2)", &PhysicsParams::ball_mass_kg, 0.01, 2},
    {"mu_slide", "", "sliding friction coefficient mu_s", &PhysicsParams::mu_slide, 0.01, 1},
    {"slide_fade_speed_mps", "m/s", "slip below which the sliding friction falls with the slip (0: constant friction)", &PhysicsParams::slide_fade_speed_mps, 0, 10},
    {"slide_fade_bands", "", "the slip fade's accuracy: bands of constant friction below slide_fade_speed_mps (a whole number)", &PhysicsParams::slide_fade_bands, 1, 1000},
    {"mu_roll", "", "rolling resistance coefficient mu_r", &PhysicsParams::mu_roll, 0, 0.5},
    {"spin_decel_rps2", "rad/s^2", "spin-down rate of omega_z", &PhysicsParams::spin_decel_rps2, 0, 1000},
    {"e_ball", "", "ball-ball restitution e_b", &PhysicsParams::e_ball, 0, 1},
    {"mu_ball_a", "", "ball-ball friction mu = a + b exp(-c u_slip): a", &PhysicsParams::mu_ball_a, 0, 1},
    {"mu_ball_b", "", "ball-ball friction: b", &PhysicsParams::mu_ball_b, 0, 1},
    {"mu_ball_c_spm", "s/m", "ball-ball friction: c", &PhysicsParams::mu_ball_c_spm, 0, 100},
    {"e_cushion", "", "ball-cushion restitution e_c", &PhysicsParams::e_cushion, 0, 1},
    {"f_cushion", "", "ball-cushion friction coefficient f_c", &PhysicsParams::f_cushion, 0, 2},
    {"e_cushion_mathavan", "", "Mathavan 2010 cushion: energetic restitution at the nose", &PhysicsParams::e_cushion_mathavan, 0, 1},
    {"f_cushion_mathavan", "", "Mathavan 2010 cushion: ball-cushion sliding friction", &PhysicsParams::f_cushion_mathavan, 0, 2},
    {"cushion_impulse_steps", "", "Mathavan 2010 cushion: the fallback's impulse step, 1/N of the impact (where error control fails)", &PhysicsParams::cushion_impulse_steps, 10, 100000},
    {"cushion_poisson_ratio", "", "Stronge compliant cushion: Poisson ratio of the rubber (stiffness ratio)", &PhysicsParams::cushion_poisson_ratio, 0, 0.5},
    {"cushion_restitution_exponent", "", "the cushion restitution's fall with approach speed: e(v) = 1 - (1 - e)(v / 1 m/s)^p (0: constant)", &PhysicsParams::cushion_restitution_exponent, 0, 2},
    {"cushion_height_m", "m", "cushion nose height above the slate h (R < h < 2R)", &PhysicsParams::cushion_height_m, 0.005, 0.2},
    {"cue_mass_kg", "kg", "cue mass M", &PhysicsParams::cue_mass_kg, 0.05, 5},
    {"cue_end_mass_kg", "kg", "cue end mass m_e (squirt)", &PhysicsParams::cue_end_mass_kg, 0.0005, 1},
    {"miscue_limit", "", "largest tip offset sqrt(a^2+b^2)/R without a miscue", &PhysicsParams::miscue_limit, 0, 0.9},
    {"air_density_kgpm3", "kg/m^3", "air density rho (drag)", &PhysicsParams::air_density_kgpm3, 0, 5},
    {"drag_coefficient", "", "drag coefficient C_d", &PhysicsParams::drag_coefficient, 0, 5},
    {"spin_drag_coefficient", "", "rotational drag coefficient C_m", &PhysicsParams::spin_drag_coefficient, 0, 5},
}};

constexpr std::array<std::string_view, 6> kPresets = {"pool-7ft", "pool-8ft", "pool-9ft",
                                                      "snooker", "carom", "unbounded"};

// Pocket geometry of a preset: mouth width between the points, the jaw angle between the rail
// nose and the jaw face (WPA: 142 deg corner, 104 deg side), and how deep the jaws run past the
// mouth line. The capture circle spans the throat between the jaw ends, so no ball centre can
// pass the jaws without entering it.
struct PocketShape {
  double mouth_m;
  double jaw_deg;
  double depth_m;
};

// Adds a pocket with its two jaw segments. `p1`, `p2`: the points (rail ends); `j1`, `j2`: unit
// directions of the jaw faces from each point into the pocket; `axis`: into the pocket.
void AddPocket(TableSpec* t, const std::string& name, Eigen::Vector2d p1, Eigen::Vector2d j1,
               Eigen::Vector2d p2, Eigen::Vector2d j2, Eigen::Vector2d axis, double depth_m) {
  const double len1 = depth_m / j1.dot(axis);
  const double len2 = depth_m / j2.dot(axis);
  const Eigen::Vector2d e1 = p1 + len1 * j1;
  const Eigen::Vector2d e2 = p2 + len2 * j2;
  t->cushions.push_back({p1, e1, "jaw_" + name + "_a"});
  t->cushions.push_back({p2, e2, "jaw_" + name + "_b"});
  t->pockets.push_back({0.5 * (e1 + e2), 0.5 * (e1 - e2).norm(), name});
}

// Six-pocket table: rails between the pockets, jaws, capture circles.
void BuildPocketTable(TableSpec* t, const PocketShape& corner, const PocketShape& side) {
  const double hx = 0.5 * t->length_m;
  const double hy = 0.5 * t->width_m;
  const double qc = corner.mouth_m / std::sqrt(2.0);  // corner point distance along each rail
  const double hs = 0.5 * side.mouth_m;
  // Rails (nose lines), named by side.
  for (int sy : {1, -1}) {
    const std::string s = sy > 0 ? "top" : "bottom";
    t->cushions.push_back({{-hx + qc, sy * hy}, {-hs, sy * hy}, "rail_" + s + "_left"});
    t->cushions.push_back({{hs, sy * hy}, {hx - qc, sy * hy}, "rail_" + s + "_right"});
  }
  for (int sx : {-1, 1}) {
    t->cushions.push_back({{sx * hx, -hy + qc}, {sx * hx, hy - qc}, sx < 0 ? "rail_left" : "rail_right"});
  }
  // Corner pockets: the jaw leaves the rail at (180 - jaw) deg from the rail direction.
  const double ca = DegToRad(180.0 - corner.jaw_deg);
  for (int sy : {1, -1}) {
    for (int sx : {-1, 1}) {
      const std::string name =
          std::string(sy > 0 ? "top" : "bottom") + "_" + (sx < 0 ? "left" : "right");
      AddPocket(t, name, {sx * (hx - qc), sy * hy}, {sx * std::cos(ca), sy * std::sin(ca)},
                {sx * hx, sy * (hy - qc)}, {sx * std::sin(ca), sy * std::cos(ca)},
                Eigen::Vector2d(sx, sy).normalized(), corner.depth_m);
    }
  }
  // Side pockets at x = 0.
  const double sa = DegToRad(180.0 - side.jaw_deg);
  for (int sy : {1, -1}) {
    AddPocket(t, sy > 0 ? "top_side" : "bottom_side", {hs, sy * hy},
              {-std::cos(sa), sy * std::sin(sa)}, {-hs, sy * hy}, {std::cos(sa), sy * std::sin(sa)},
              {0.0, static_cast<double>(sy)}, side.depth_m);
  }
}

void BuildCaromTable(TableSpec* t) {
  const double hx = 0.5 * t->length_m;
  const double hy = 0.5 * t->width_m;
  t->cushions.push_back({{-hx, hy}, {hx, hy}, "rail_top"});
  t->cushions.push_back({{-hx, -hy}, {hx, -hy}, "rail_bottom"});
  t->cushions.push_back({{-hx, -hy}, {-hx, hy}, "rail_left"});
  t->cushions.push_back({{hx, -hy}, {hx, hy}, "rail_right"});
}

// slide_fade_bands counts bands: a whole number (its range is checked with the others').
absl::Status CheckWholeBands(double bands) {
  if (bands == std::floor(bands)) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrFormat("slide_fade_bands must be a whole number of bands, got %g", bands));
}

}  // namespace

std::span<const std::string_view> EffectNames() { return kEffectNames; }

uint32_t EffectFromName(std::string_view name) {
  for (size_t i = 0; i < kEffectNames.size(); ++i) {
    if (kEffectNames[i] == name) return 1u << i;
  }
  return 0;
}

std::span<const ParamInfo> ParamInfos() { return kParams; }

absl::Status SetParam(std::string_view name, double value, PhysicsParams* params) {
  for (const ParamInfo& p : kParams) {
    if (p.name != name) continue;
    if (absl::Status s = CheckFiniteInRange(p.name, value, p.lo, false, p.hi, false); !s.ok()) {
      return s;
    }
    if (p.field == &PhysicsParams::slide_fade_bands) {
      if (absl::Status s = CheckWholeBands(value); !s.ok()) return s;
    }
    params->*p.field = value;
    return absl::OkStatus();
  }
  return absl::InvalidArgumentError(
      absl::StrFormat("unknown parameter \"%s\" (GetInfo lists the parameters)", name));
}

absl::Status ValidateParams(const PhysicsParams& p) {
  for (const ParamInfo& info : kParams) {
    if (absl::Status s =
            CheckFiniteInRange(info.name, p.*info.field, info.lo, false, info.hi, false);
        !s.ok()) {
      return s;
    }
  }
  if (absl::Status s = CheckWholeBands(p.slide_fade_bands); !s.ok()) return s;
  const double r = p.ball_radius_m;
  if (!(p.cushion_height_m > r && p.cushion_height_m < 2.0 * r)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "cushion_height_m must be between the ball radius and diameter (%g, %g), got %g", r,
        2.0 * r, p.cushion_height_m));
  }
  return absl::OkStatus();
}

std::span<const std::string_view> TablePresetNames() { return kPresets; }

absl::StatusOr<TableSpec> MakeTablePreset(std::string_view name) {
  TableSpec t;
  t.nose_fraction_of_diameter = 0.635;  // WPA, mid-range; carom sets a fixed height
  t.name = std::string(name);
  // WPA pool: 57.15 mm balls, nose height 63.5 % of the diameter; mouths 4.5-4.625 in (corner)
  // and 5-5.125 in (side); jaws run about 5 cm, the depth of a cushion.
  const PocketShape pool_corner{0.116, 142.0, 0.05};
  const PocketShape pool_side{0.129, 104.0, 0.05};
  if (name == "pool-9ft" || name == "pool-8ft" || name == "pool-7ft") {
    // WPA playing surfaces: 100 x 50, 92 x 46 and 78 x 39 in (within 1/8 in).
    if (name == "pool-9ft") { t.length_m = 2.54; t.width_m = 1.27; }
    if (name == "pool-8ft") { t.length_m = 2.3368; t.width_m = 1.1684; }
    if (name == "pool-7ft") { t.length_m = 1.9812; t.width_m = 0.9906; }
    SetBallRadius(t.params.ball_radius_m, &t);
    BuildPocketTable(&t, pool_corner, pool_side);
  } else if (name == "snooker") {
    // WPBSA: 3569 x 1778 mm, 52.5 mm balls of about 142 g. Pocket openings follow the
    // published templates approximately (corner about 86 mm, middle about 105 mm); real
    // snooker jaws are rounded, here they are straight at the pool angles.
    t.length_m = 3.569;
    t.width_m = 1.778;
    t.params.ball_radius_m = 0.02625;
    t.params.ball_mass_kg = 0.142;
    t.params.cue_end_mass_kg = 0.142 / 30;
    // The cloth and cushion of a measured snooker table (Mathavan, Jackson and Parkin, Am. J.
    // Phys. 77 (2009) 788, a Riley table tracked at up to 1000 frames a second): rolling balls
    // slowed at 0.124-0.126 m/s^2 and sliding ones at 1.75-2.40 (mu_s 0.212 as their 2010
    // cushion model took the slate's); Han's restitution is the one whose square rebound of a
    // rolling ball fits their fit to 31 measured rebounds best (bench/billiards_snooker_study.cc).
    t.params.mu_roll = 0.0127;
    t.params.mu_slide = 0.212;
    t.params.e_cushion = 0.924;
    SetBallRadius(t.params.ball_radius_m, &t);
    BuildPocketTable(&t, {0.086, 142.0, 0.04}, {0.105, 104.0, 0.04});
  } else if (name == "carom") {
    // UMB match table 2840 x 1420 mm, balls 61.5 mm and about 210 g, cushion nose 37 mm.
    t.length_m = 2.84;
    t.width_m = 1.42;
    t.params.ball_radius_m = 0.03075;
    t.params.ball_mass_kg = 0.21;
    t.params.cue_end_mass_kg = 0.21 / 30;
    t.nose_fraction_of_diameter = 0.0;
    t.params.cushion_height_m = 0.037;
    // The cloth of a match-size carom table, read from its tracks alone (ReadCloth): four
    // public tracked shots (tailuge/billiards' history, SS_max_spin_02-06; docs/billiards.md,
    // "The cloth read from the tracks") roll at 0.0047 (quartiles 0.0043-0.0052 over 17
    // stretches) and slide at 0.175 (0.166-0.185 over 10), where pool cloth is 0.01 and 0.2.
    t.params.mu_roll = 0.0047;
    t.params.mu_slide = 0.175;
    // The cushion's restitution falls with the approach speed, as its 0.47th power: what
    // Mathavan's model reads on all four shots (0.47 +- 0.013; the pairs and the other models
    // read 0.29-0.70), and at which every model's held-out shots come closer than at a
    // constant restitution (docs/billiards.md, "The restitution's fall with speed, read on the
    // same shots").
    t.params.cushion_restitution_exponent = 0.47;
    // Han's cushion and the side spin's decay on that cloth and that law, calibrated on the
    // same shots with the cloth held (`table calibrate --param cushion_restitution_exponent=0.47
    // --fit e_cushion,f_cushion,spin_decel_rps2`): 0.896 / 0.197 / 4.29 on all four; 0.901 /
    // 0.195 / 4.68 and 0.883 / 0.206 / 3.83 on two pairs, each scored on the other, the
    // held-out shots' median 16.2 and 19.0 mm (21.2 and 21.3 at a constant restitution).
    t.params.e_cushion = 0.896;
    t.params.f_cushion = 0.197;
    t.params.spin_decel_rps2 = 4.3;
    // Mathavan's cushion on the same shots, the cloth, spin-down and law held: 0.894 / 0.182
    // on all four; 0.899 / 0.179 and 0.886 / 0.185 on two pairs, the held-out shots' median
    // 15.6 and 15.8 mm (22.2 and 21.8 at a constant restitution, the spin-down fitted).
    t.params.e_cushion_mathavan = 0.894;
    t.params.f_cushion_mathavan = 0.182;
    BuildCaromTable(&t);
  } else if (name == "unbounded") {
    // The chapter's scene: an endless cloth, no cushions, no pockets.
    t.bounded = false;
    t.length_m = 0.0;
    t.width_m = 0.0;
    SetBallRadius(t.params.ball_radius_m, &t);
  } else {
    return absl::InvalidArgumentError(absl::StrFormat(
        "table preset must be one of pool-7ft, pool-8ft, pool-9ft, snooker, carom, unbounded; "
        "got \"%s\"",
        name));
  }
  return t;
}

TableModel::TableModel(TableSpec spec) : spec_(std::move(spec)) {
  const PhysicsParams& p = spec_.params;
  inertia_ = 0.4 * p.ball_mass_kg * p.ball_radius_m * p.ball_radius_m;
  cushion_sin_ = (p.cushion_height_m - p.ball_radius_m) / p.ball_radius_m;
  cushion_contact_ = p.ball_radius_m * std::sqrt(1.0 - cushion_sin_ * cushion_sin_);
}

absl::StatusOr<TableModel> TableModel::Create(TableSpec spec) {
  if (absl::Status s = ValidateParams(spec.params); !s.ok()) return s;
  const double d = 2.0 * spec.params.ball_radius_m;
  if (spec.bounded) {
    if (!(std::isfinite(spec.length_m) && std::isfinite(spec.width_m) && spec.length_m >= 4 * d &&
          spec.width_m >= 4 * d && spec.length_m <= 20 && spec.width_m <= 20)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "table playing area must be between 4 ball diameters and 20 m on each side, got "
          "%g x %g m",
          spec.length_m, spec.width_m));
    }
    // The ball must fit through every pocket's throat, or the pocket is a wall.
    for (const Pocket& p : spec.pockets) {
      if (p.radius_m < spec.params.ball_radius_m) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "pocket %s: its throat (%.4f m wide) is narrower than the ball (%.4f m)", p.name,
            2 * p.radius_m, d));
      }
    }
  }
  return TableModel(std::move(spec));
}

void SetBallRadius(double radius_m, TableSpec* spec) {
  spec->params.ball_radius_m = radius_m;
  if (spec->nose_fraction_of_diameter > 0.0) {
    spec->params.cushion_height_m = spec->nose_fraction_of_diameter * 2.0 * radius_m;
  }
}

}  // namespace sportsim::billiards
