// Ground surfaces for the golf ball's ground phase (ground.h): the named constants of a bounce,
// a skid and a roll, with units and sources, and the built-in surfaces.
//
// The laws the constants enter (ground.h has the whole model):
// - Bounce (A. R. Penner, "The run of a golf ball", Can. J. Phys. 80, 931 (2002); also "The
//   physics of golf: The optimum loft of a driver", Am. J. Phys. 69, 563 (2001)): turf acts like
//   a rigid plane tilted toward the incoming ball by a critical angle
//     theta_c = 15.4 deg * (v_in / 18.6 m/s) * (theta_in / 44.4 deg),
//   theta_in the descent angle below the surface, v_in the impact speed; the normal coefficient
//   of restitution falls with the normal speed v_n against that plane:
//     e = 0.510 - 0.0375 v_n + 0.000903 v_n^2 (v_n in m/s, v_n <= 20), 0.120 above
//   (continuous at 20 m/s: 0.1212). Penner fitted both to Haake's measured bounces on greens;
//   a surface scales them: e * restitution_scale, theta_c * critical_angle_scale.
// - Skid: Coulomb friction mu (sliding_friction) between ball and grass while the contact point
//   slips. A spinless struck ball reaches pure roll at 5/7 of its speed whatever mu is; mu sets
//   how soon (after 2 v0 / (7 mu g)).
// - Roll: a resisting torque rho m g_n R (rolling_resistance rho, g_n gravity's normal part), so
//   a rolling ball decelerates at (5/7) rho g on the flat (I = (2/5) m R^2) and stays at rest
//   where the slope's tangent is at most rho. A green's rho follows from its Stimpmeter reading
//   S: the ball leaves the Stimpmeter's bar rolling at 1.83 m/s (6 ft/s; USGA, "Stimpmeter
//   Instruction Booklet") and rolls S on the flat, so (5/7) rho g = v0^2 / (2 S).
// - Bounce friction: the tangential impulse of a bounce is at most bounce_friction times the
//   normal one. Penner assumes the ball leaves every bounce rolling (enough friction); a finite
//   cap lets a light, fast bounce leave slipping, as Biber et al. (Sports Eng. 26, 2023,
//   arXiv 2302.02758) measured for most bounces.
//
// The surfaces' constants are Penner's where he gives them (a green), and otherwise our
// estimates, stated as such in surface.cc with the evidence they rest on: no published
// measurement gives a fairway's or a rough's bounce and roll as constants of this model.
#ifndef SPORTSIM_SIM_GOLF_SURFACE_H_
#define SPORTSIM_SIM_GOLF_SURFACE_H_

#include <span>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace sportsim::golf {

/// The Stimpmeter's release speed (m/s): 6.00 ft/s, USGA Stimpmeter booklet.
inline constexpr double kStimpmeterSpeedMps = 1.83;
inline constexpr double kFootToM = 0.3048;  ///< exact

/// One ground surface (units in the names; ranges in ValidateSurface).
struct Surface {
  std::string name = "green";  ///< lower case; the built-in names below
  /// Multiplies Penner's restitution curve e(v_n); (0, 1.5]. 1 on a green.
  double restitution_scale = 1.0;
  /// Multiplies Penner's critical angle theta_c; [0, 5]. 1 on a green; softer turf more.
  double critical_angle_scale = 1.0;
  /// Tangential impulse / normal impulse at most, in a bounce; [0, 2].
  double bounce_friction = 0.4;
  /// Coulomb sliding friction while the ball skids; (0, 2].
  double sliding_friction = 0.4;
  /// Rolling resistance rho: the rolling decel on the flat is (5/7) rho g; (0, 2].
  double rolling_resistance = 0.0784;
  /// The Stimpmeter reading this rolling resistance gives (ft), for display; derived.
  double stimp_ft() const;
};

/// rho of a green of Stimpmeter reading `stimp_ft` (ft), for a ball of inertia factor 2/5
/// and gravity g: rho = (7/5) v0^2 / (2 S g). InvalidArgument unless stimp_ft is in [1, 20].
absl::StatusOr<double> RollingResistanceFromStimp(double stimp_ft, double gravity_mps2 = 9.80665);

/// Penner's normal restitution at normal speed v_n (m/s; >= 0), before a surface's scale.
double PennerRestitution(double normal_speed_mps);
/// Penner's critical angle (rad) for impact speed v (m/s) and descent angle theta (rad), before
/// a surface's scale.
double PennerCriticalAngle(double impact_speed_mps, double descent_angle_rad);

/// Checks every field; InvalidArgument names the first bad one.
absl::Status ValidateSurface(const Surface& surface);

/// The built-in surfaces, in order: green (Stimp 10), fringe, fairway_firm, fairway,
/// fairway_soft, rough, bunker, first_cut, cartpath.
std::span<const Surface> BuiltinSurfaces();
/// A built-in surface by name ("fairway_normal" is "fairway"); InvalidArgument naming the known
/// ones otherwise.
absl::StatusOr<Surface> SurfaceByName(std::string_view name);
/// A green of Stimpmeter reading `stimp_ft` (the "green" surface with its rolling resistance).
absl::StatusOr<Surface> GreenOfStimp(double stimp_ft);

}  // namespace sportsim::golf

#endif  // SPORTSIM_SIM_GOLF_SURFACE_H_
