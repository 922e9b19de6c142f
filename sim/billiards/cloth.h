// The ball-cloth law shared by every engine (docs/billiards.md; Leckie & Greenspan 2006, Alciatore TP A-4).
//
// Contact-point slip u = v + w x (-R z^) = v + R z^ x w (horizontal part).
// - Sliding (|u| > 0): dv/dt = -mu_s g u^, dw/dt = (5 mu_s g / 2R) (z^ x u^); u^ is constant, so
//   |u| falls at (7/2) mu_s g and the slide ends after 2|u0| / (7 mu_s g).
// - Rolling (u = 0): dv/dt = -mu_r g v^, w_xy = z^ x v / R; stops after |v| / (mu_r g).
// - Every moving state: d(w_z)/dt = -spin_decel sgn(w_z).
// - Slip-speed friction (off unless slide_fade_speed_mps u_c > 0): below u_c the sliding
//   friction is mu_s |u| / u_c, taken as slide_fade_bands bands of constant friction, each at
//   its middle slip's value (band k of K: slips from (k-1) u_c / K to k u_c / K, friction
//   mu_s (k - 1/2) / K), so every band is a constant-acceleration piece whose end is exact.
//   In the fade (slips below u_c) rolling resistance acts too, on the rolling part of the
//   motion v_r = v - 2/7 u (which friction at the contact does not change): dv/dt gains
//   -mu_r g v_r^ and w_xy the matching z^ x dv / R, so the slip is untouched and v_r slows
//   at mu_r g until it stops.
// - Air drag (optional, stepped engine only): F = -1/2 rho C_d pi R^2 |v| v on the centre (a
//   rolling ball feels 5/7 of it, the rest goes into keeping it rolling) and a torque
//   -1/2 rho C_m R^5 |w| w.
#ifndef SPORTSIM_SIM_BILLIARDS_CLOTH_H_
#define SPORTSIM_SIM_BILLIARDS_CLOTH_H_

#include <cstdint>
#include <limits>

#include "Eigen/Core"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"

namespace sportsim::billiards {

/// Below these a speed, slip or spin counts as zero (m/s, m/s, rad/s). They are far below what
/// any rendering or outcome can show, and they keep a ball at rest exactly at rest.
inline constexpr double kRestSpeed = 1e-10;
inline constexpr double kRestSlip = 1e-10;
inline constexpr double kRestSpin = 1e-9;

/// The horizontal slip velocity of the contact point with the cloth (m/s).
inline Eigen::Vector3d Slip(const Eigen::Vector3d& v, const Eigen::Vector3d& w, double radius) {
  return {v.x() - radius * w.y(), v.y() + radius * w.x(), 0.0};
}

/// The motion state that a ball's velocity and spin imply (pocketed balls stay pocketed).
MotionState Classify(const TableModel& model, const Ball& ball);

/// Time derivative of (v, w) in a given motion state.
struct Rates {
  Eigen::Vector3d dv = Eigen::Vector3d::Zero();
  Eigen::Vector3d dw = Eigen::Vector3d::Zero();
};
Rates ClothRates(const TableModel& model, uint32_t effects, MotionState state,
                 const Eigen::Vector3d& v, const Eigen::Vector3d& w);

/// What ends a ball's current smooth motion.
/// kSlideBand: the slip reaches the lower edge of its friction band (slip-speed friction);
/// kGlideStop: the rolling part v - 2/7 u of a sliding ball stops (slip-speed friction).
enum class TransitionKind : uint8_t {
  kNone, kSlideEnd, kRollStop, kSpinStop, kSlideBand, kGlideStop
};
struct NextTransition {
  double dt_s = std::numeric_limits<double>::infinity();
  TransitionKind kind = TransitionKind::kNone;
};
/// Time until the ball's next transition at its current rates: exact without drag (the rates
/// are then constant in every state), an estimate with drag (the engine re-checks). The rates
/// it used go to `rates_out` when given (the engine needs them too).
NextTransition TimeToTransition(const TableModel& model, uint32_t effects, const Ball& ball,
                                Rates* rates_out = nullptr);

/// Time until one quantity (slip, speed or w_z, by `kind`) reaches zero at its current rate;
/// infinity when it is not falling. With drag the engine uses it to re-check a predicted
/// transition before snapping.
double TimeToZero(const TableModel& model, uint32_t effects, const Ball& ball,
                  TransitionKind kind);

/// Snaps a ball whose transition is due: a sliding ball becomes rolling with the velocity that
/// conserves its angular momentum about the contact point (v - 2/7 u), a rolling ball stops, a
/// vanishing w_z becomes zero, a slip at a band's edge is set just inside the band below, a
/// sliding ball's stopping rolling part becomes zero (the slip kept). Then sets the state from
/// Classify.
void ApplyTransition(const TableModel& model, TransitionKind kind, Ball* ball);

/// Translational plus rotational kinetic energy of a ball (J).
double KineticEnergy(const TableModel& model, const Ball& ball);

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_CLOTH_H_
