// The cue strike: from cue speed, heading, elevation and tip offset to the cue ball's velocity
// and spin (Leckie & Greenspan 2006; Alciatore TP ).
//
// Model: the tip hits the ball at a point offset from the cue axis by (a R, b R), measured in
// the plane perpendicular to the cue as the shooter sees the ball (a > 0 right of centre,
// b > 0 above). The impulse J runs along the cue axis d (heading phi counter-clockwise from +x,
// pointing down at elevation theta). An elastic tip gives
//   J = 2 V0 / (1/M + 1/m + R^2 (a^2 + b^2) / I),   v = J d / m,   w = J (r_c x d) / I,
// so for theta = 0: v = 2 V0 / (1 + m/M + 5/2 (a^2 + b^2)), w_top R / v = 5/2 b (natural roll
// at b = 0.4), w_z R / v = 5/2 a (right english spins counter-clockwise seen from above).
// Measuring the offset perpendicular to the cue makes the miscue test the angle between the
// cue axis and the surface normal, sin = sqrt(a^2 + b^2), whatever the elevation.
// The vertical part of v goes into the slate (jumps are not modelled). Squirt turns v away from
// the side of english by alpha = atan(5/2 a sqrt(1 - a^2) / (1 + m/m_e + 5/2 (1 - a^2))).
#ifndef SPORTSIM_SIM_BILLIARDS_CUE_H_
#define SPORTSIM_SIM_BILLIARDS_CUE_H_

#include <cstdint>

#include "Eigen/Core"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"

namespace sportsim::billiards {

/// A cue strike. Angles in radians here; the API edges speak degrees.
struct CueStrike {
  double speed_mps = 2.0;       ///< cue speed V0, or the ball's speed when ball_speed is set (m/s)
  bool ball_speed = false;      ///< speed_mps is the cue ball's speed just after the strike
  double phi_rad = 0.0;         ///< heading in the table plane, counter-clockwise from +x
  double theta_rad = 0.0;       ///< cue elevation above the table, [0, 89 deg]
  double a = 0.0;               ///< side offset, fraction of R (> 0: right of centre)
  double b = 0.0;               ///< vertical offset, fraction of R (> 0: above centre)
  double noise = 0.0;           ///< scale of Gaussian noise; 1 = FastFiz's sigmas (see below)
  uint64_t seed = 0;            ///< seed of the noise
};

/// Largest cue speed and cue-ball speed accepted (m/s): the fastest measured breaks give the
/// cue ball about 13-14 m/s; 20 leaves room for arcade play without inviting nonsense.
inline constexpr double kMaxStrikeSpeed = 20.0;
inline constexpr double kMaxElevationDeg = 89.0;

/// FastFiz's noise at magnitude 1 (Archibald et al.): sigma of a and b 0.5 mm (as offsets),
/// theta 0.1 deg, phi 0.125 deg, V0 0.075 m/s.
inline constexpr double kNoiseOffsetM = 0.5e-3;
inline constexpr double kNoiseThetaDeg = 0.1;
inline constexpr double kNoisePhiDeg = 0.125;
inline constexpr double kNoiseSpeedMps = 0.075;

struct StrikeOutcome {
  CueStrike applied;            ///< the strike after noise
  double cue_speed_mps = 0.0;   ///< V0 actually used
  double squirt_rad = 0.0;      ///< deflection applied (0 when squirt is off)
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d w = Eigen::Vector3d::Zero();
};

/// Validates a strike (finite, in range, no miscue) and computes the ball's velocity and spin.
absl::StatusOr<StrikeOutcome> ComputeStrike(const TableModel& model, uint32_t effects,
                                            const CueStrike& strike);

/// True when a ball centred at `xy` (m) rests in a pocket's mouth: near a pocket (within its
/// capture radius plus a diameter of its centre), between its jaws (on the pocket's side of
/// both jaw lines), and clear of every cushion and jaw segment by the cushion contact distance
/// (a ball resting against a jaw is that far from it). The engine can leave a ball there, on
/// the lip or against a jaw, outside the rail lines.
bool InPocketMouth(const TableModel& model, const Eigen::Vector2d& xy);

/// Checks a layout: every ball finite, on the cloth (centre inside the cushions by the contact
/// distance, or resting in a pocket's mouth), not pocketed twice, no two balls overlapping by
/// more than 1 um, unique ids.
absl::Status ValidateLayout(const TableModel& model, const TableState& state);

/// Validates the layout and the strike, then sets the velocity and spin of ball `cue` (which
/// must be at rest, like every other ball) and its motion state. Changes nothing on error.
absl::StatusOr<StrikeOutcome> ApplyStrike(const TableModel& model, uint32_t effects,
                                          const CueStrike& strike, int cue, TableState* state);

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_CUE_H_
