#include "sim/golf/club_ball_impact.h"

#include <algorithm>
#include <cmath>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

namespace sportsim::golf {
namespace {

using Eigen::Vector3d;

// Unit vector with elevation `elevation_rad` above the horizon and azimuth
// `azimuth_rad` to the right of +x, in the x-target, y-left, z-up frame.
Vector3d DirectionFromAngles(double elevation_rad, double azimuth_rad) {
  return Vector3d(std::cos(elevation_rad) * std::cos(azimuth_rad),
                  -std::cos(elevation_rad) * std::sin(azimuth_rad),
                  std::sin(elevation_rad));
}

absl::Status ValidateDelivery(const ClubDelivery& d) {
  // At least 0.1 m/s: a slower clubhead is no swing, and speeds near zero (subnormal ones
  // included) turned the impact's ratios into NaN.
  if (auto s = CheckFiniteInRange("clubhead_speed_mps", d.clubhead_speed_mps,
                                    0.1, false, 100, false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("attack_angle_deg", d.attack_angle_deg, -45,
                                    false, 45, false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("club_path_deg", d.club_path_deg, -45,
                                    false, 45, false);
      !s.ok())
    return s;
  if (d.dynamic_loft_deg.has_value()) {
    if (auto s = CheckFiniteInRange("dynamic_loft_deg", *d.dynamic_loft_deg,
                                      -30, false, 90, true);
        !s.ok())
      return s;
  }
  return CheckFiniteInRange("face_angle_deg", d.face_angle_deg, -45, false,
                              45, false);
}

}  // namespace

absl::StatusOr<ImpactResult> SimulateImpact(const ClubDelivery& delivery,
                                            const ClubSpec& club,
                                            const BallSpec& ball,
                                            const ImpactOptions& options) {
  // Validate everything once, here.
  if (auto s = ValidateDelivery(delivery); !s.ok()) return s;
  if (auto s = ValidateClubSpec(club); !s.ok()) return s;
  if (auto s = ValidateBallSpec(ball); !s.ok()) return s;
  const double mu = options.friction_coefficient;
  if (std::isnan(mu) || mu < 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "friction_coefficient must be in [0, inf] (inf = always rolling), "
        "got %g",
        mu));
  }

  const double m = ball.mass_kg;
  const double r = ball.radius_m();
  const double k = ball.inertia_factor;
  const double big_m = club.head_mass_kg;
  const double e = club.cor;
  const double loft_deg = delivery.dynamic_loft_deg.value_or(club.loft_deg);

  // Geometry: face normal and club velocity.
  const Vector3d n = DirectionFromAngles(loft_deg * kDegToRad,
                                         delivery.face_angle_deg * kDegToRad);
  const Vector3d club_v =
      delivery.clubhead_speed_mps *
      DirectionFromAngles(delivery.attack_angle_deg * kDegToRad,
                          delivery.club_path_deg * kDegToRad);
  const double v_n = club_v.dot(n);
  const double spin_loft_deg =
      std::acos(std::clamp(v_n / delivery.clubhead_speed_mps, -1.0, 1.0)) /
      kDegToRad;
  if (!(v_n > 0)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "spin loft (angle between the club velocity and the face normal, from "
        "attack_angle_deg, club_path_deg, dynamic_loft_deg and face_angle_deg) "
        "must be in [0, 90), got %g",
        spin_loft_deg));
  }
  const Vector3d v_t = club_v - v_n * n;
  const double v_t_norm = v_t.norm();

  // Normal impulse: Newton restitution on the approach speed.
  const double inv_mass_sum = 1.0 / m + 1.0 / big_m;
  const double j_n = (1.0 + e) * v_n / inv_mass_sum;

  // Tangential impulse: the rolling value, capped by Coulomb friction.
  double j_t = v_t_norm / (1.0 / m + 1.0 / (k * m) + 1.0 / big_m);
  bool sliding = false;
  if (j_t > mu * j_n) {
    j_t = mu * j_n;
    sliding = true;
  }
  const Vector3d t_hat =
      v_t_norm > 0 ? Vector3d(v_t / v_t_norm) : Vector3d::Zero();
  const Vector3d impulse = j_n * n + j_t * t_hat;

  // Velocities and spin after the impact.
  ImpactResult out;
  out.face_normal = n;
  out.spin_loft_deg = spin_loft_deg;
  out.ball_sliding = sliding;
  out.normal_impulse_ns = j_n;
  out.tangential_impulse_ns = j_t;
  out.club_velocity_before_mps = club_v;
  out.ball_velocity_mps = impulse / m;
  out.ball_spin_radps = (j_t * t_hat).cross(n) / (k * m * r);
  out.club_velocity_after_mps = club_v - impulse / big_m;
  const double inertia = k * m * r * r;
  out.kinetic_energy_before_j = 0.5 * big_m * club_v.squaredNorm();
  out.kinetic_energy_after_j =
      0.5 * big_m * out.club_velocity_after_mps.squaredNorm() +
      0.5 * m * out.ball_velocity_mps.squaredNorm() +
      0.5 * inertia * out.ball_spin_radps.squaredNorm();

  // Launch angles: elevation and azimuth (+ right) of the ball velocity.
  const Vector3d& v = out.ball_velocity_mps;
  const double speed = v.norm();
  const double horizontal = std::hypot(v.x(), v.y());
  out.smash_factor = speed / delivery.clubhead_speed_mps;
  // Valid but extreme inputs (a head or ball of a few 1e-324 kg) make the
  // impulse underflow to zero or the spin overflow: no launch to describe.
  if (!(speed > 0) || !std::isfinite(speed) ||
      !out.ball_spin_radps.allFinite()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "the impact gives the ball no finite launch (speed %g m/s): "
        "head_mass_kg = %g, mass_kg = %g and clubhead_speed_mps = %g are too "
        "small to resolve in double precision",
        speed, big_m, m, delivery.clubhead_speed_mps));
  }

  // Spin split in the launch frame: right = d x z, up' = right x d.
  // Backspin is the component along `right`; a tilt toward -up' curves the
  // ball right (see golf_ball.h).
  const Vector3d d = v / speed;
  Vector3d right = d.cross(Vector3d::UnitZ());
  if (right.norm() < 1e-12) right = -Vector3d::UnitY();  // vertical launch
  right.normalize();
  const Vector3d up = right.cross(d);
  const double back_radps = out.ball_spin_radps.dot(right);
  const double side_radps = -out.ball_spin_radps.dot(up);

  out.backspin_rpm = back_radps / kRpmToRadPerS;
  out.sidespin_rpm = side_radps / kRpmToRadPerS;
  out.launch = LaunchConditions{
      .ball_speed_mps = speed,
      .launch_angle_deg = std::atan2(v.z(), horizontal) / kDegToRad,
      .launch_direction_deg = std::atan2(-v.y(), v.x()) / kDegToRad,
      .spin_rpm = out.ball_spin_radps.norm() / kRpmToRadPerS,
      .spin_axis_deg = std::atan2(side_radps, back_radps) / kDegToRad,
  };
  return out;
}

}  // namespace sportsim::golf
