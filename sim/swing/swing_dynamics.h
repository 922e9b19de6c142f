// Equations of motion, energy and clubhead kinematics of the swing model (swing_model.h).
//
// Generalised coordinates q = (alpha, beta); state y = (alpha, beta, alpha_dot, beta_dot).
// With theta = gamma - alpha and phi = theta + beta (Jorgensen; Bourg & Bywalec ch. 19):
//   M11 = J + I + Mc R^2 + 2 R S cos(beta),  M12 = -(I + R S cos(beta)),  M22 = I
//   M11 a'' + M12 b'' = Qa - (b'^2 - 2 a' b') R S sin(beta) + S [g sin(phi) - A cos(phi)]
//                        + (S_A + Mc R)(g sin(theta) - A cos(theta))
//   M12 a'' + M22 b'' = Qb - a'^2 R S sin(beta) - S [g sin(phi) - A cos(phi)]
// (the chapter prints "I b'^2" in the second equation; it is I b''). Both follow from the
// Lagrangian T - V with T = 1/2 q'^T M q' and
//   V = -(S_A + Mc R)(g cos(theta) + A sin(theta)) - S (g cos(phi) + A sin(phi)),
// so E = T + V obeys dE/dt = Qa a' + Qb b' exactly (tests/sim/swing check this).
#ifndef SPORTSIM_SIM_SWING_SWING_DYNAMICS_H_
#define SPORTSIM_SIM_SWING_SWING_DYNAMICS_H_

#include <cmath>

#include <Eigen/Core>

#include "sim/swing/swing_model.h"
#include "sim/swing/torque_program.h"

namespace sportsim::swing {

/// (alpha, beta, alpha_dot, beta_dot) in rad and rad/s.
using SwingVec = Eigen::Vector4d;

/// Angular accelerations (alpha_ddot, beta_ddot) in rad/s^2 for the given state and torques.
/// The wrist torque is ignored when the model switches it off.
inline Eigen::Vector2d SwingAccelerations(const SwingModel& m, const SwingVec& y,
                                          const Torques& q) {
  const SwingParams& p = m.params();
  const double beta = y[1], ad = y[2], bd = y[3];
  const double sb = std::sin(beta), cb = std::cos(beta);
  const double rs = p.arm_length_m * p.club_first_moment_kgm;
  const double m11 = p.arm_inertia_kgm2 + p.club_inertia_kgm2 +
                     p.club_mass_kg * p.arm_length_m * p.arm_length_m + 2.0 * rs * cb;
  const double m12 = -(p.club_inertia_kgm2 + rs * cb);
  const double m22 = p.club_inertia_kgm2;
  const double qb = m.wrist_torque_on() ? q.q_beta : 0.0;
  double r1 = q.q_alpha - (bd * bd - 2.0 * ad * bd) * rs * sb;
  double r2 = qb - ad * ad * rs * sb;
  // Gravity and the shoulder's pseudo-force, skipped when both are switched off.
  if (m.gravity_on()) {
    const double theta = p.gamma_rad - y[0];
    const double phi = theta + beta;
    const double club = p.club_first_moment_kgm * (m.g() * std::sin(phi) - m.a() * std::cos(phi));
    r1 += club + m.arm_static_moment() * (m.g() * std::sin(theta) - m.a() * std::cos(theta));
    r2 -= club;
  }
  const double inv_det = 1.0 / (m11 * m22 - m12 * m12);
  return {(m22 * r1 - m12 * r2) * inv_det, (m11 * r2 - m12 * r1) * inv_det};
}

/// dy/dt for the state y under torques q.
inline SwingVec SwingDerivative(const SwingModel& m, const SwingVec& y, const Torques& q) {
  const Eigen::Vector2d acc = SwingAccelerations(m, y, q);
  return {y[2], y[3], acc[0], acc[1]};
}

/// Total mechanical energy T + V in the shoulder frame (J), V including the shoulder's
/// pseudo-force potential. Uses the model's g and A (zero when switched off).
double SwingEnergy(const SwingModel& m, const SwingVec& y);

/// Clubhead position and velocity, and speeds.
struct ClubheadKinematics {
  Eigen::Vector2d position_m;       ///< relative to the shoulder (m)
  Eigen::Vector2d velocity_mps;     ///< relative to the shoulder (m/s)
  Eigen::Vector2d ground_velocity_mps;  ///< relative to the ground (m/s)
  double speed_mps = 0;             ///< Jorgensen's formula, relative to the shoulder (m/s)
  double ground_speed_mps = 0;      ///< |ground_velocity_mps| (m/s)
};

/// Clubhead kinematics at time t_s (the shoulder starts at rest at t = 0 and moves with
/// velocity -A t along x).
ClubheadKinematics Clubhead(const SwingModel& m, const SwingVec& y, double t_s);

/// Jorgensen's clubhead speed relative to the shoulder:
/// V^2 = (R^2 + L^2 + 2 R L cos b) a'^2 + L^2 b'^2 - 2 (L^2 + R L cos b) a' b'.
double JorgensenSpeed(const SwingParams& p, double beta, double alpha_dot, double beta_dot);

}  // namespace sportsim::swing

#endif  // SPORTSIM_SIM_SWING_SWING_DYNAMICS_H_
