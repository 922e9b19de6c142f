// The event engine (internal; use TableSimulation::Create from engine.h).
//
// Between events every ball follows a closed-form trajectory of its motion state (cloth.h):
// r(t) = r0 + v0 tau + a tau^2 / 2 and w(t) = w0 + alpha tau with constant a and alpha (no air
// drag), tau = t - t0 since the ball's last event. Events are predicted as roots of polynomials
// in time (poly_roots.h): ball-ball contact |dr(t)| = 2R (quartic), a cushion line (quadratic)
// or its rounded ends (quartic), pocket capture (quartic), leaving the table (quadratic), and
// transitions (closed form, cloth.h). See docs/billiards.md, "The event engine".
#ifndef SPORTSIM_SIM_BILLIARDS_EVENT_ENGINE_H_
#define SPORTSIM_SIM_BILLIARDS_EVENT_ENGINE_H_

#include <memory>
#include <vector>

#include "sim/billiards/engine.h"

namespace sportsim::billiards {

/// After a plastic (resting) contact the bodies are set apart by a resting gap (m): this one,
/// or less where the cloth closes the contact faster, so that a contact a ball's spin keeps
/// pushing shut re-forms after sqrt(2 gap / a) (0.2 ms at 4 m/s^2, two sliding balls at the
/// default mu_s) with an approach speed sqrt(2 a gap) below kRestingContactSpeed, plastic again:
/// the push is resolved as a train of plastic hops instead of a Zeno cascade. 0.1 um moves
/// nothing anyone can see.
inline constexpr double kRestingGap = 1e-7;
/// The smallest resting gap (m), for closing accelerations above 200 m/s^2 (extreme mu_s, g).
inline constexpr double kMinRestingGap = 1e-9;

/// A plastic contact between the same two bodies within this time (s) of the previous one
/// continues a push (a train of hops) and is not reported again; the first one is.
inline constexpr double kRestingTrain = 0.01;

/// Predictions look at most this far ahead (s); a ball with nothing predicted within it is
/// re-predicted then (a ball that barely slows: rolling resistance or spin decay off or tiny).
inline constexpr double kPredictionHorizon = 1000.0;

/// Orientation of a ball whose spin axis turns (sliding, or rolling with side spin) is
/// integrated in pieces, 4th-order Magnus per piece, on a grid anchored at the ball's last event
/// (so evaluating at any times gives the same values). A piece turns the ball by at most this
/// angle (rad), so its length is set per segment from the largest |w| in it (pieces are never
/// shorter than 1/8192 s, so above 2048 rad/s they turn further).
inline constexpr double kOrientationTurn = 0.25;

std::unique_ptr<TableSimulation> MakeEventSimulation(const TableModel& model,
                                                     const SolverOptions& options,
                                                     TableState initial);

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_EVENT_ENGINE_H_
