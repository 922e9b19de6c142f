// Club-ball impact: an oblique rigid-body collision that turns the club's
// delivery (speed, attack angle, path, dynamic loft, face angle) into the
// ball's launch conditions.
//
// Model (impulse-momentum, as in Penner, Am. J. Phys. 69, 563 (2001), and the
// three-dimensional rigid-body treatment of Winfield & Tan, Computers &
// Structures 53, 19 (1994)):
// - The clubhead is a free rigid mass M that only translates during the
//   impact (a centred hit: the impact line passes through its centre of mass,
//   so no head rotation and no gear effect; the shaft is ignored). The ball
//   (mass m, radius r, I = k m r^2) is at rest with no spin.
// - The face is a plane with unit normal n: elevation = dynamic loft above
//   the horizon, azimuth = face angle (+ right = open). The club velocity V
//   has elevation = attack angle (+ up) and azimuth = club path (+ right).
//   Both in the world frame of golf_ball.h (x target, y left, z up).
// - Normal impulse with Newton restitution e on the normal approach speed
//   V_n = V.n:  J_n = (1 + e) V_n / (1/m + 1/M).
//   For a face square to the path (spin loft s = angle(V, n)) the ball's
//   normal speed is (1 + e) M / (M + m) V cos(s): at s = 0 the smash factor
//   is (1 + e) M / (M + m), 1.488 for e = 0.83, M = 0.200 kg, m = 45.93 g.
// - Tangential impulse J_t in the face plane, along the tangential club
//   velocity V_t = V - V_n n. The contact-point slip changes by
//   J_t (1/m + 1/(k m) + 1/M), so the ball leaves the face ROLLING when
//   J_t = |V_t| / (1/m + 1/(k m) + 1/M). If that needs more than Coulomb
//   friction allows (J_t > mu J_n) the ball leaves SLIDING with J_t = mu J_n.
//   For k = 2/5 and M >> m rolling gives the familiar v_t = (2/7) V_t and
//   spin = (5/2) v_t / r.
// - Ball velocity v = (J_n n + J_t t) / m, spin w = (J_t t x n) / (k m r),
//   club velocity after V' = V - (J_n n + J_t t) / M, t = V_t / |V_t|.
//   The spin axis is perpendicular to the launch direction (no rifle spin).
// Energy: with e <= 1 and friction the collision never creates kinetic
// energy; with e = 1 and no tangential impulse (V_t = 0) it conserves it.
//
// What the model leaves out, and how that shows (see docs/golf-flight.md):
// ball deformation and tangential compliance (real balls leave with less
// spin than the rolling value), gear effect and off-centre hits, face bulge
// and roll, shaft effective mass (the ISEA 2020 paper cited in golf_ball.h
// found the rigid model's ball speed is low by an amount equal to adding
// < 3 g to the head), and the speed dependence of e.
#ifndef SPORTSIM_SIM_GOLF_CLUB_BALL_IMPACT_H_
#define SPORTSIM_SIM_GOLF_CLUB_BALL_IMPACT_H_

#include <optional>

#include <Eigen/Dense>

#include "absl/status/statusor.h"
#include "sim/golf/golf_ball.h"

namespace sportsim::golf {

/// How the club arrives at the ball (launch-monitor "club data").
struct ClubDelivery {
  double clubhead_speed_mps = 0.0;  ///< clubhead speed (m/s); [0.1, 100]
  double attack_angle_deg = 0.0;    ///< club velocity elevation, + upward
                                    ///< (deg); [-45, 45]
  double club_path_deg = 0.0;       ///< club velocity azimuth, + right of the
                                    ///< target (in-to-out) (deg); [-45, 45]
  std::optional<double> dynamic_loft_deg =
      std::nullopt;  ///< face normal elevation (deg); [-30, 90); unset =
                     ///< the club's static loft
  double face_angle_deg = 0.0;      ///< face normal azimuth, + right (open)
                                    ///< (deg); [-45, 45]
};

/// Impact model parameters beyond the club and ball specs.
struct ImpactOptions {
  /// Coulomb friction between ball and face (dimensionless); [0, inf].
  /// +infinity = the ball always leaves rolling. The default is an
  /// assumption (no primary measurement found); with it every preset club
  /// at a square delivery leaves rolling (sliding needs a spin loft above
  /// roughly 65 degrees).
  double friction_coefficient = 0.4;
};

/// The impact's outcome. Vectors are in the world frame (x target, y left,
/// z up).
struct ImpactResult {
  LaunchConditions launch;        ///< the flight input
  double backspin_rpm = 0.0;      ///< spin about the horizontal axis
                                  ///< perpendicular to the launch (rpm)
  double sidespin_rpm = 0.0;      ///< tilted component, + curves right (rpm)
  double smash_factor = 0.0;      ///< ball speed / clubhead speed
  double spin_loft_deg = 0.0;     ///< angle between club velocity and face
                                  ///< normal (deg)
  bool ball_sliding = false;      ///< true: friction limited the tangential
                                  ///< impulse (ball left the face sliding)
  double normal_impulse_ns = 0.0;      ///< J_n (N s)
  double tangential_impulse_ns = 0.0;  ///< |J_t| (N s)
  Eigen::Vector3d face_normal = Eigen::Vector3d::Zero();  ///< n (unit)
  Eigen::Vector3d ball_velocity_mps = Eigen::Vector3d::Zero();   ///< v (m/s)
  Eigen::Vector3d ball_spin_radps = Eigen::Vector3d::Zero();     ///< w (rad/s)
  Eigen::Vector3d club_velocity_before_mps = Eigen::Vector3d::Zero();  ///< V
  Eigen::Vector3d club_velocity_after_mps = Eigen::Vector3d::Zero();   ///< V'
  double kinetic_energy_before_j = 0.0;  ///< (1/2) M V^2 (J)
  double kinetic_energy_after_j = 0.0;   ///< club + ball translation + ball
                                         ///< rotation after impact (J)
};

/// Runs the oblique impact. Validates every input first; InvalidArgument
/// names the first bad field (including a spin loft of 90 deg or more, when
/// the club does not move into the face).
absl::StatusOr<ImpactResult> SimulateImpact(const ClubDelivery& delivery,
                                            const ClubSpec& club,
                                            const BallSpec& ball,
                                            const ImpactOptions& options = {});

}  // namespace sportsim::golf

#endif  // SPORTSIM_SIM_GOLF_CLUB_BALL_IMPACT_H_
