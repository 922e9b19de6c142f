#include "sim/swing/swing_dynamics.h"

#include <algorithm>
#include <cmath>

namespace sportsim::swing {

double SwingEnergy(const SwingModel& m, const SwingVec& y) {
  const SwingParams& p = m.params();
  const double theta = p.gamma_rad - y[0];
  const double phi = theta + y[1];
  const double ad = y[2], bd = y[3];
  const double rs = p.arm_length_m * p.club_first_moment_kgm;
  const double cb = std::cos(y[1]);
  const double m11 = p.arm_inertia_kgm2 + p.club_inertia_kgm2 +
                     p.club_mass_kg * p.arm_length_m * p.arm_length_m + 2.0 * rs * cb;
  const double m12 = -(p.club_inertia_kgm2 + rs * cb);
  const double kinetic = 0.5 * (m11 * ad * ad + 2.0 * m12 * ad * bd + p.club_inertia_kgm2 * bd * bd);
  const double potential =
      -m.arm_static_moment() * (m.g() * std::cos(theta) + m.a() * std::sin(theta)) -
      p.club_first_moment_kgm * (m.g() * std::cos(phi) + m.a() * std::sin(phi));
  return kinetic + potential;
}

double JorgensenSpeed(const SwingParams& p, double beta, double alpha_dot, double beta_dot) {
  const double r = p.arm_length_m, l = p.club_length_m, cb = std::cos(beta);
  const double v2 = (r * r + l * l + 2.0 * r * l * cb) * alpha_dot * alpha_dot +
                    l * l * beta_dot * beta_dot - 2.0 * (l * l + r * l * cb) * alpha_dot * beta_dot;
  return std::sqrt(std::max(v2, 0.0));  // v2 >= 0 up to rounding
}

ClubheadKinematics Clubhead(const SwingModel& m, const SwingVec& y, double t_s) {
  const SwingParams& p = m.params();
  const double theta = p.gamma_rad - y[0];
  const double phi = theta + y[1];
  const double theta_dot = -y[2];
  const double phi_dot = y[3] - y[2];
  const double r = p.arm_length_m, l = p.club_length_m;
  ClubheadKinematics k;
  k.position_m = {r * std::sin(theta) + l * std::sin(phi), -r * std::cos(theta) - l * std::cos(phi)};
  k.velocity_mps = {r * theta_dot * std::cos(theta) + l * phi_dot * std::cos(phi),
                    r * theta_dot * std::sin(theta) + l * phi_dot * std::sin(phi)};
  k.ground_velocity_mps = k.velocity_mps + Eigen::Vector2d(-m.a() * t_s, 0.0);
  k.speed_mps = JorgensenSpeed(p, y[1], y[2], y[3]);
  k.ground_speed_mps = k.ground_velocity_mps.norm();
  return k;
}

}  // namespace sportsim::swing
