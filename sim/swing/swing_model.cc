#include "sim/swing/swing_model.h"

#include <cmath>
#include <string_view>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "sim/core/check.h"
#include "sim/core/effects.h"

namespace sportsim::swing {

SwingModel::SwingModel(const SwingParams& params, uint32_t effects)
    : params_(params), effects_(effects) {
  g_ = (effects & kSwingDisableGravity) ? 0.0 : params.gravity_mps2;
  a_ = (effects & kSwingDisableShoulderAccel) ? 0.0 : params.shoulder_accel_mps2;
  arm_static_ = params.arm_first_moment_kgm + params.club_mass_kg * params.arm_length_m;
}

absl::StatusOr<SwingModel> SwingModel::Create(const SwingParams& p, uint32_t effects) {
  struct Check {
    std::string_view name;
    double value, lo, hi;
    bool lo_open;
  };
  const Check checks[] = {
      {"arm_inertia_kgm2", p.arm_inertia_kgm2, 0, 100, true},
      {"arm_length_m", p.arm_length_m, 0, 5, true},
      {"arm_first_moment_kgm", p.arm_first_moment_kgm, 0, 100, false},
      {"club_inertia_kgm2", p.club_inertia_kgm2, 0, 100, true},
      {"club_mass_kg", p.club_mass_kg, 0, 100, true},
      {"club_length_m", p.club_length_m, 0, 5, true},
      {"club_first_moment_kgm", p.club_first_moment_kgm, 0, 100, false},
      {"gravity_mps2", p.gravity_mps2, 0, 100, false},
      {"gamma_rad", p.gamma_rad, -kTwoPi, kTwoPi, false},
      {"beta0_rad", p.beta0_rad, -kTwoPi, kTwoPi, false},
      {"shoulder_accel_mps2", p.shoulder_accel_mps2, 0, 100, false},
  };
  for (const Check& c : checks) {
    if (absl::Status s = CheckFiniteInRange(c.name, c.value, c.lo, c.lo_open, c.hi, false); !s.ok()) {
      return s;
    }
  }
  if (absl::Status s = ValidateEffectBits("swing effects", effects, kSwingEffectBits); !s.ok()) {
    return s;
  }
  // det M(beta) = I (J + Mc R^2) - R^2 S^2 cos^2(beta) is smallest at cos^2 = 1.
  const double r = p.arm_length_m, s = p.club_first_moment_kgm;
  const double scale = p.club_inertia_kgm2 * (p.arm_inertia_kgm2 + p.club_mass_kg * r * r);
  const double det_min = scale - r * r * s * s;
  if (!(det_min > 1e-9 * scale)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "the mass matrix is singular at some wrist angle: club_inertia_kgm2 * (arm_inertia_kgm2 + "
        "club_mass_kg * arm_length_m^2) = %g must exceed (arm_length_m * club_first_moment_kgm)^2 "
        "= %g",
        scale, r * r * s * s));
  }
  return SwingModel(p, effects);
}

}  // namespace sportsim::swing
