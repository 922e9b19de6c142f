// Instantaneous collisions: ball-ball, ball-cushion, pocket capture. Each takes the balls at the
// moment of contact and changes only velocities, spins and motion states.
//
// Ball-ball (equal balls, contact normal n from a to b, horizontal):
//   normal impulse J_n = (1 + e_b) (m/2) (v_a - v_b).n;
//   contact slip u_t = tangential part of v_a - v_b + R (w_a + w_b) x n;
//   friction impulse opposing u_t of magnitude min(mu J_n, m |u_t| / 7), mu = a + b exp(-c
//   |u_t|) (Alciatore, TP A-14: mu falls with the sliding speed of the two surfaces at the
//   contact; for a stun cut |u_t| = v sin(cut)): never more than the impulse that stops the
//   slip, 7 being the two balls' combined effective inverse mass at the contact
//   (1 + 1 + 5/2 + 5/2).
//   The vertical part of the velocity change goes into the slate.
// Ball-cushion: see CushionModel in model.h and docs/billiards.md.
#ifndef SPORTSIM_SIM_BILLIARDS_COLLISION_H_
#define SPORTSIM_SIM_BILLIARDS_COLLISION_H_

#include <cstdint>

#include "Eigen/Core"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"

namespace sportsim::billiards {

/// Normal approach speeds below this (m/s) are rounding, not motion: such contacts are not
/// collisions. Without it an impulse smaller than an ulp of the velocity changes nothing and
/// the same contact repeats forever.
inline constexpr double kMinApproachSpeed = 1e-9;

/// Below this normal approach speed (m/s) a contact is a resting contact and is perfectly
/// plastic (e = 0). A ball driven into a jammed cluster by its spin (follow into a frozen
/// group, english against a cushion) otherwise bounces ever faster in smaller hops, like a ball
/// bouncing on a floor: the Zeno cascade of event-driven mechanics. With it, the hops stop
/// after about log(v0 / 1e-3) / log(1 / e) collisions and the contact then re-forms every few
/// tens of microseconds while the drive lasts. A 1 mm/s collision moves nothing a player
/// can see (a ball at 1 mm/s rolls 5 um before it stops).
inline constexpr double kRestingContactSpeed = 1e-3;

/// Resolves a ball-ball contact. Does nothing (returns false) when the balls are not
/// approaching along the line of centres faster than kMinApproachSpeed.
bool CollideBalls(const TableModel& model, uint32_t effects, Ball* a, Ball* b);

/// Resolves a ball-cushion contact; `normal` is the horizontal unit normal pointing from the
/// cushion towards the ball's centre. Does nothing (returns false) when the ball is not moving
/// into the cushion.
bool CollideCushion(const TableModel& model, const Eigen::Vector2d& normal, Ball* ball);

/// Nearest point of segment [a, b] to p.
Eigen::Vector2d ClosestOnSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                 const Eigen::Vector2d& p);

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_COLLISION_H_
