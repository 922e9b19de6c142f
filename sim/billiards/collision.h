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
//   BallBallModel::kMathavan2014 integrates the impact instead (CollideBallsMathavan).
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

/// Resolves a ball-ball contact by the table's BallBallModel. Does nothing (returns false) when
/// the balls are not approaching along the line of centres faster than kMinApproachSpeed.
bool CollideBalls(const TableModel& model, uint32_t effects, Ball* a, Ball* b);

/// TP A-14's ball-ball friction mu = a + b exp(-c slip) at the contact's sliding speed `slip`.
double BallFriction(const PhysicsParams& p, double slip);

/// Mathavan, Jackson and Parkin's (2014) ball-ball impact (BallBallModel::kMathavan2014):
/// integrated over the normal impulse, restitution `e` by the normal work, the contact's
/// sliding friction `mu` against its slip as it evolves (held at zero once it closes), and the
/// cloth's sliding friction `mu_table` at the ball the contact's friction presses into the
/// cloth, against that ball's own slip there. `n` is the horizontal unit normal from a to b;
/// the balls must be approaching along it. Changes v (horizontal after) and w of both.
void CollideBallsMathavan(const TableModel& model, const Eigen::Vector3d& n, double e,
                          double mu, double mu_table, Ball* a, Ball* b);

/// Mathavan, Jackson and Parkin's (2010) cushion impact (CushionModel::kMathavan2010) with the
/// coefficients given: restitution `e` at the nose, sliding friction `mu_cushion` at the nose
/// and `mu_slate` at the slate, integrated under error control with a stuck contact held stuck;
/// the table's cushion_impulse_steps sets the fallback's step. `normal` points from the cushion
/// into the table; the ball must be approaching it. Changes v (horizontal after) and w.
void CollideCushionMathavan(const TableModel& model, const Eigen::Vector3d& normal, double e,
                            double mu_cushion, double mu_slate, Ball* ball);

/// Stronge's compliant impact of a sphere on a rough surface, in its contact's own terms. The
/// contact is a normal spring (a loading stiffness k, unloading k / e^2: the kinematic
/// restitution e) and a tangential spring k_t, sticking while its force is within mu times the
/// normal force and slipping (at that force) when not. Velocities are the contact point's, in
/// units of the approach speed: `slip` >= 0 is the tangential one before; returns the tangential
/// one after, along the same direction (negative: reversed). `beta` is the body's inverse
/// tangential effective mass at the contact over its normal one (7/2 for a free solid sphere);
/// `frequency_ratio` is the tangential over the normal vibration frequency of the contact,
/// sqrt(beta k_t / k) (StrongeFrequencyRatio). Each phase (compression or restitution, stick or
/// slip) has a closed form; the switches between them are found to rounding by bisection.
double CompliantTangentialRebound(double slip, double e, double mu, double beta,
                                  double frequency_ratio);

/// The contact's tangential over normal frequency for a sphere (beta 7/2) on an elastic body of
/// Poisson ratio `poisson`: k_t / k = 2 (1 - nu) / (2 - nu) (Johnson 1985, sec. 7.4, after
/// Mindlin), so sqrt(7/2 * 2 (1 - nu) / (2 - nu)): 1.528 for rubber (0.5), 1.871 at 0.
double StrongeFrequencyRatio(double poisson);

/// Resolves a resting ball-ball contact (approach below kRestingContactSpeed, or below the
/// event engine's kTrainContactSpeed when it continues a sustained contact) as a sustained
/// contact: a finite force, small against the cloth's friction, so a ball that is rolling,
/// spinning or at rest stays on the rolling manifold (w_xy = z^ x v / R) and answers an impulse
/// P at its contact point r_c with dv = 5/(7m) (P_h - z^ x (r_c x P) / R), dw_z = (r_c x P)_z / I:
/// exactly the impulse followed by its slide-to-roll (v - 2/7 u), with the slide's duration
/// (at most 2 |u| / (7 mu_s g), about 0.1 ms) taken as zero. A sliding ball answers as a free
/// ball, and a slide with slip below kRestingContactSpeed (it would end within 0.1 ms) ends at
/// once; the spin about z the contact's friction gives a ball without side spin is taken by the
/// cloth's spin friction at once (side spin is never reversed by it). The normal impulse is the
/// plastic one for these effective masses (7/5 m on the rolling manifold, m sliding: no normal
/// relative velocity after), friction as in CollideBalls (TP A-14, capped at sticking); every
/// part only removes energy. Returns false when the balls are not approaching faster than
/// kMinApproachSpeed. (The event engine, RestingContacts::kSustained in engine.h.) `relax`
/// (in [1, 2)) scales the impulse for the approach: the pair then parts at (relax - 1) times
/// it, as the over-relaxed sweeps over a group of contacts want.
bool CollideBallsResting(const TableModel& model, uint32_t effects, Ball* a, Ball* b,
                         double relax = 1.0);

/// A ball that a sustained contact leaves rolling slower than RestingStopSpeed = sqrt(2 d mu_r
/// g), d = kRestingStopDistance (0.14 mm/s at the defaults), stops at once (StopCreep): rolling
/// resistance would stop it within sqrt(2 d / (mu_r g)) (1.4 ms) after rolling d. Only with
/// rolling resistance on.
inline constexpr double kRestingStopDistance = 1e-7;
double RestingStopSpeed(const TableModel& model);
/// Stops a rolling ball slower than RestingStopSpeed (see above); anything else is unchanged.
void StopCreep(const TableModel& model, uint32_t effects, Ball* ball);

/// The cushion's restitution for an approach at `approach_mps` across the cushion line: `e`
/// where `exponent` is 0, else 1 - (1 - e) approach^exponent (approach in m/s) within [0, 1];
/// 0 (plastic) below kRestingContactSpeed. PhysicsParams::cushion_restitution_exponent.
double CushionRestitution(double e, double exponent, double approach_mps);

/// Resolves a ball-cushion contact; `normal` is the horizontal unit normal pointing from the
/// cushion towards the ball's centre. Does nothing (returns false) when the ball is not moving
/// into the cushion.
bool CollideCushion(const TableModel& model, const Eigen::Vector2d& normal, Ball* ball);

/// Nearest point of segment [a, b] to p.
Eigen::Vector2d ClosestOnSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                 const Eigen::Vector2d& p);

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_COLLISION_H_
