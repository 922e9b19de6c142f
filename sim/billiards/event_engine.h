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

/// After a plastic (resting) contact the balls are set this far apart (m), so that a contact
/// that a ball's spin keeps pushing closed re-forms after sqrt(2 gap / a) (0.2 ms at 4 m/s^2,
/// the most two sliding balls can close at) with an approach speed sqrt(2 a gap) <= 0.9 mm/s,
/// again below kRestingContactSpeed: the push is resolved as a train of plastic hops instead of
/// a Zeno cascade. 0.1 um moves nothing anyone can see.
inline constexpr double kRestingGap = 1e-7;

/// A plastic contact between the same two bodies within this time (s) of the previous one
/// continues a push (a train of hops) and is not reported again; the first one is.
inline constexpr double kRestingTrain = 0.01;

/// Predictions look at most this far ahead (s); a ball with nothing predicted within it is
/// re-predicted then (only an unbounded table without rolling resistance gets there).
inline constexpr double kPredictionHorizon = 1000.0;

/// Orientation of a ball whose spin axis turns (sliding, or rolling with side spin) is
/// integrated in pieces, 4th-order Magnus per piece, on a grid anchored at the ball's last event
/// (so evaluating at any times gives the same values). A piece turns the ball by at most this
/// angle (rad), so its length is set per segment from the largest |w| in it.
inline constexpr double kOrientationTurn = 0.25;

std::unique_ptr<TableSimulation> MakeEventSimulation(const TableModel& model,
                                                     const SolverOptions& options,
                                                     TableState initial);

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_EVENT_ENGINE_H_
