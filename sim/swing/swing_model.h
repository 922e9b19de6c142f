// Golf swing model: Jorgensen's driven double pendulum.
//
// Sources: T. P. Jorgensen, The Physics of Golf (2nd ed., 1999); D. M. Bourg & B. Bywalec,
// Physics for Game Developers (2nd ed.), ch. 19 (parameter values below are that chapter's).
//
// Frame (shoulder frame): the shoulder pivot at the origin, x horizontal toward the backswing
// side (the target lies toward -x), y up. theta is the arm angle from the downward vertical,
// counter-clockwise positive: wrist = R (sin theta, -cos theta). beta is the wrist cock and
// phi = theta + beta the club-shaft angle: clubhead = wrist + L (sin phi, -cos phi).
// alpha = gamma - theta is the angle the arm has swept since the top of the backswing.
// The shoulder may accelerate horizontally toward the target with A (m/s^2), a uniform
// pseudo-force field in the shoulder frame. Docs: docs/swing.md.
#ifndef SPORTSIM_SIM_SWING_SWING_MODEL_H_
#define SPORTSIM_SIM_SWING_SWING_MODEL_H_

#include <cstdint>

#include "absl/status/statusor.h"
#include "sim/core/units.h"

namespace sportsim::swing {

/// Golfer and club, with the chapter's defaults. SI units; angles in radians.
struct SwingParams {
  double arm_inertia_kgm2 = 1.15;              ///< J: arm moment of inertia about the shoulder (kg m^2)
  double arm_length_m = 0.62;                  ///< R: shoulder to wrists (m)
  double arm_first_moment_kgm = 7.3 * 0.62 * 0.5;  ///< S_A: arm mass x its centre's distance from the shoulder (kg m)
  double club_inertia_kgm2 = 0.08;             ///< I: club moment of inertia about the wrists (kg m^2)
  double club_mass_kg = 0.4;                   ///< Mc: club mass (kg)
  double club_length_m = 1.1;                  ///< L: wrists to clubhead (m)
  double club_first_moment_kgm = 0.4 * 1.1 * 0.75;  ///< S: club mass x its centre's distance from the wrists (kg m)
  double gravity_mps2 = 9.8;                   ///< g (m/s^2)
  double gamma_rad = DegToRad(135.0);          ///< theta at the top of the backswing (rad)
  double beta0_rad = DegToRad(120.0);          ///< initial wrist cock (rad)
  double shoulder_accel_mps2 = 0.98;           ///< A: shoulder acceleration toward the target, 0.1 g (m/s^2)
};

/// Effect bits (the convention of sim/core/effects.h): 0 = full physics; every swing effect is
/// on by default, so each bit switches one off. A switched-off effect is skipped in the force
/// evaluation, not multiplied by zero.
enum SwingEffect : uint32_t {
  kSwingDisableGravity = 1u << 0,        ///< no gravity terms
  kSwingDisableShoulderAccel = 1u << 1,  ///< the shoulder does not accelerate
  kSwingDisableWristTorque = 1u << 2,    ///< Q_beta is zero whatever the program says (free hinge)
  kSwingEffectBits = (1u << 3) - 1,      ///< every known bit
};

/// A validated, immutable swing model with the constants the dynamics need precomputed.
class SwingModel {
 public:
  /// Validates `params`: every value finite; lengths in (0, 5] m; inertias, masses in (0, 100];
  /// first moments in [0, 100]; g and A in [0, 100] m/s^2; gamma and beta0 in [-2 pi, 2 pi]; the
  /// mass matrix positive definite at every wrist angle: I (J + Mc R^2) > R^2 S^2.
  static absl::StatusOr<SwingModel> Create(const SwingParams& params, uint32_t effects = 0);

  const SwingParams& params() const { return params_; }
  uint32_t effects() const { return effects_; }
  bool gravity_on() const { return g_ != 0.0 || a_ != 0.0; }
  double g() const { return g_; }              ///< gravity in use (0 when switched off)
  double a() const { return a_; }              ///< shoulder acceleration in use (0 when off)
  bool wrist_torque_on() const { return (effects_ & kSwingDisableWristTorque) == 0; }
  double arm_static_moment() const { return arm_static_; }  ///< S_A + Mc R (kg m)

 private:
  SwingModel(const SwingParams& params, uint32_t effects);

  SwingParams params_;
  uint32_t effects_ = 0;
  double g_ = 0.0;
  double a_ = 0.0;
  double arm_static_ = 0.0;
};

}  // namespace sportsim::swing

#endif  // SPORTSIM_SIM_SWING_SWING_MODEL_H_
