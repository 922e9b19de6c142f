// Golf ball and club specifications, club presets, and the launch conditions
// that connect club-ball impact (club_ball_impact.h) to ball flight
// (ball_flight.h).
//
// Sources for the figures (the prose and code here are our own):
// - Ball mass 45.93 g (maximum) and diameter 42.67 mm (minimum): Rules of
//   Golf, Equipment Rules, Part 4 (The Ball).
// - Ball moment of inertia factor I / (m r^2) = 0.40: Penner, "The physics of
//   golf: The optimum loft of a driver", Am. J. Phys. 69, 563 (2001) treats
//   the ball as a uniform sphere (2/5); the measured ball inertia in
//   "Adjusting a Momentum-Based Golf Clubhead-Ball Impact Model to Improve
//   Accuracy", Proceedings 49(1), 47 (ISEA 2020), Table 1 (83.63 g cm^2 for a
//   45.9 g ball of radius 21.3 mm) gives 0.40 as well. Multi-layer balls
//   differ from 0.40 by design; override the field for a specific ball.
// - Coefficient of restitution 0.83: the USGA/R&A limit is 0.822 with a test
//   tolerance of 0.008, i.e. 0.830, and it applies to every club except the
//   putter (USGA senior technical director D. Rugge, Golfweek, 2010-07-27).
// - Driver head mass 0.200 kg: MacKenzie, Ryan & Rice,
//   Int. J. Golf Sci. 4, 136 (2015) tested 174-200 g driver heads; the ISEA
//   2020 paper above measured 204 g.
// - Fairway wood heads are about 12-15 g heavier than a driver head (D. Irving,
//   "Clubmaker's Classroom: Proper Wood Fitting", flagstick.com): 3-wood
//   0.213 kg.
// - Iron head masses: "the standard or base head weight for a 5 iron has been
//   around 254 grams with 7 gram increments moving through the set" (Ralph
//   Maltby clubmaking Q&A, ralphmaltby.com). 3-iron 240 g, 5-iron 254 g,
//   7-iron 268 g, 9-iron 282 g, pitching wedge 289 g. The sand wedge (296 g)
//   is one further 7 g step: an extrapolation, not a published figure; many
//   sand wedges are heavier.
// - Lofts (typical "standard" lofts; they vary by maker and era): driver
//   9-12.5 (we use 10.5), 3-wood 15, 3-iron 21, 5-iron 27, 7-iron 34,
//   9-iron 42, pitching wedge 46, sand wedge 56 degrees (loft charts at
//   tellmemoregolf.com and golfah.com agree on these values).
//
// Conventions used by every golf type in sportsim::golf (a right-handed
// golfer, seen from behind the ball looking at the target):
// - World frame: x downrange along the target line, y to the LEFT, z up
//   (right-handed). All angles below are converted to this frame.
// - Horizontal angles (launch direction, club path, face angle, wind) are
//   positive to the RIGHT of the target line (launch-monitor convention).
// - Spin axis tilt is positive when the ball curves to the right (fade or
//   slice for a right-handed golfer); sidespin carries the same sign.
#ifndef SPORTSIM_SIM_GOLF_GOLF_BALL_H_
#define SPORTSIM_SIM_GOLF_GOLF_BALL_H_

#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "sim/core/check.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_format.h"

namespace sportsim::golf {

inline constexpr double kRpmToRadPerS = 2.0 * std::numbers::pi / 60.0;
inline constexpr double kDegToRad = std::numbers::pi / 180.0;
inline constexpr double kMphToMps = 0.44704;  ///< exact (1609.344 m / 3600 s)
inline constexpr double kYardToM = 0.9144;    ///< exact

/// A golf ball. Defaults: the Rules of Golf limits (heaviest, smallest ball).
struct BallSpec {
  double mass_kg = 0.04593;     ///< ball mass (kg); (0, 1]
  double diameter_m = 0.04267;  ///< ball diameter (m); (0, 0.5]
  double inertia_factor = 0.4;  ///< moment of inertia / (m r^2); (0, 2/3]

  double radius_m() const { return 0.5 * diameter_m; }  ///< r = d / 2 (m)
  double area_m2() const {  ///< cross-section pi r^2 (m^2)
    return std::numbers::pi * radius_m() * radius_m();
  }
};

/// A club head as the impact model sees it: a free rigid mass with a flat,
/// lofted face.
struct ClubSpec {
  std::string name = "driver";  ///< label only
  double head_mass_kg = 0.200;  ///< clubhead mass (kg); (0, 2]
  double loft_deg = 10.5;       ///< static loft (deg); used when the delivery
                                ///< gives no dynamic loft; [0, 90)
  double cor = 0.83;            ///< normal coefficient of restitution; (0, 1]
};

/// The ball's state just after impact: the input of ball flight.
struct LaunchConditions {
  double ball_speed_mps = 0.0;        ///< ball speed (m/s); (0, 120]
  double launch_angle_deg = 0.0;      ///< vertical launch angle, + up (deg);
                                      ///< [-90, 90]
  double launch_direction_deg = 0.0;  ///< horizontal launch direction, + right
                                      ///< of the target line (deg); [-90, 90]
  double spin_rpm = 0.0;              ///< total spin rate (rpm); [0, 30000]
  double spin_axis_deg = 0.0;         ///< spin-axis tilt, + curves right (deg);
                                      ///< [-180, 180]. Backspin = spin
                                      ///< cos(tilt), sidespin = spin sin(tilt);
                                      ///< |tilt| > 90 means topspin.
};

/// Backspin component of a launch (rpm): spin_rpm cos(spin_axis).
inline double BackspinRpm(const LaunchConditions& launch) {
  return launch.spin_rpm * std::cos(launch.spin_axis_deg * kDegToRad);
}

/// Sidespin component of a launch (rpm), + curves right: spin_rpm sin(axis).
inline double SidespinRpm(const LaunchConditions& launch) {
  return launch.spin_rpm * std::sin(launch.spin_axis_deg * kDegToRad);
}

/// Builds launch conditions from backspin and sidespin (+ curves right).
inline LaunchConditions LaunchFromBackAndSideSpin(double ball_speed_mps,
                                                  double launch_angle_deg,
                                                  double launch_direction_deg,
                                                  double backspin_rpm,
                                                  double sidespin_rpm) {
  return LaunchConditions{
      .ball_speed_mps = ball_speed_mps,
      .launch_angle_deg = launch_angle_deg,
      .launch_direction_deg = launch_direction_deg,
      .spin_rpm = std::hypot(backspin_rpm, sidespin_rpm),
      .spin_axis_deg = std::atan2(sidespin_rpm, backspin_rpm) / kDegToRad,
  };
}


/// Checks every BallSpec field; InvalidArgument names the first bad field.
inline absl::Status ValidateBallSpec(const BallSpec& ball) {
  if (auto s = CheckFiniteInRange("mass_kg", ball.mass_kg, 0, true, 1, false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("diameter_m", ball.diameter_m, 0, true, 0.5,
                                    false);
      !s.ok())
    return s;
  return CheckFiniteInRange("inertia_factor", ball.inertia_factor, 0, true,
                              2.0 / 3.0, false);
}

/// Checks every ClubSpec field; InvalidArgument names the first bad field.
inline absl::Status ValidateClubSpec(const ClubSpec& club) {
  if (auto s = CheckFiniteInRange("head_mass_kg", club.head_mass_kg, 0, true,
                                    2, false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("loft_deg", club.loft_deg, 0, false, 90,
                                    true);
      !s.ok())
    return s;
  return CheckFiniteInRange("cor", club.cor, 0, true, 1, false);
}

/// Checks every LaunchConditions field.
inline absl::Status ValidateLaunchConditions(const LaunchConditions& launch) {
  if (auto s = CheckFiniteInRange("ball_speed_mps", launch.ball_speed_mps, 0,
                                    true, 120, false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("launch_angle_deg", launch.launch_angle_deg,
                                    -90, false, 90, false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("launch_direction_deg",
                                    launch.launch_direction_deg, -90, false, 90,
                                    false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("spin_rpm", launch.spin_rpm, 0, false,
                                    30000, false);
      !s.ok())
    return s;
  return CheckFiniteInRange("spin_axis_deg", launch.spin_axis_deg, -180,
                              false, 180, false);
}

namespace internal {

struct ClubPresetRow {
  std::string_view name;
  double head_mass_kg;
  double loft_deg;
};

// Sources in the file comment.
inline constexpr std::array<ClubPresetRow, 8> kClubPresets = {{
    {"driver", 0.200, 10.5},
    {"3-wood", 0.213, 15.0},
    {"3-iron", 0.240, 21.0},
    {"5-iron", 0.254, 27.0},
    {"7-iron", 0.268, 34.0},
    {"9-iron", 0.282, 42.0},
    {"pitching-wedge", 0.289, 46.0},
    {"sand-wedge", 0.296, 56.0},
}};

inline constexpr std::array<std::string_view, kClubPresets.size()>
MakeClubPresetNames() {
  std::array<std::string_view, kClubPresets.size()> names{};
  for (size_t i = 0; i < kClubPresets.size(); ++i) {
    names[i] = kClubPresets[i].name;
  }
  return names;
}

}  // namespace internal

/// Names accepted by ClubPreset, from the longest club to the shortest.
inline constexpr std::array<std::string_view, internal::kClubPresets.size()>
    kClubPresetNames = internal::MakeClubPresetNames();

/// The preset club `name` (exact, lower case; see kClubPresetNames), with
/// cor = 0.83. InvalidArgument for an unknown name.
inline absl::StatusOr<ClubSpec> ClubPreset(std::string_view name) {
  for (const internal::ClubPresetRow& row : internal::kClubPresets) {
    if (row.name == name) {
      return ClubSpec{.name = std::string(row.name),
                      .head_mass_kg = row.head_mass_kg,
                      .loft_deg = row.loft_deg,
                      .cor = 0.83};
    }
  }
  std::string names;
  for (std::string_view preset : kClubPresetNames) {
    if (!names.empty()) names += ", ";
    names += preset;
  }
  return absl::InvalidArgumentError(absl::StrFormat(
      "club_preset must be one of %s; got \"%s\"", names, name));
}

}  // namespace sportsim::golf

#endif  // SPORTSIM_SIM_GOLF_GOLF_BALL_H_
