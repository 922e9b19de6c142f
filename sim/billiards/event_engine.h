// The event engine (internal; use TableSimulation::Create from engine.h).
//
// Between events every ball follows a closed-form trajectory of its motion state (cloth.h):
// r(t) = r0 + v0 tau + a tau^2 / 2 and w(t) = w0 + alpha tau with constant a and alpha (no air
// drag), tau = t - t0 since the ball's last event. Events are predicted as roots of polynomials
// in time (poly_roots.h): ball-ball contact |dr(t)| = 2R (quartic), a cushion line (quadratic)
// or its rounded ends (quartic), pocket capture (quartic), leaving the table (quadratic), and
// transitions (closed form, cloth.h). See docs/billiards.md, "The event engine".
//
// Resting contacts (RestingContacts::kSustained, the default; docs/billiards.md, "Resting
// contacts"). A ball-ball contact closing slower than kRestingContactSpeed is not a collision
// but a sustained contact: a finite force between balls that move together. Two ideas from the
// event-driven literature carry it:
// - A contact that recurs faster than the time scale of the contact itself cannot be treated as
//   a sequence of independent instantaneous binary collisions: in a dissipative hard-sphere gas
//   that sequence collapses (S. McNamara and W. R. Young, "Inelastic collapse in two
//   dimensions", Phys. Rev. E 50, R28 (1994)), and the TC model of S. Luding and S. McNamara
//   ("How to handle the inelastic collapse of a dissipative hard-sphere gas with the TC model",
//   Granular Matter 1, 113 (1998)) changes the treatment of every collision that follows
//   another of the same particle within a contact duration t_c. Here t_c is the time the cloth
//   takes to answer a resting contact (a slide with less than 1 mm/s of slip ends within
//   2 |u| / (7 mu_s g) < 0.1 ms; a 0.14 mm/s roll stops within 1.4 ms after 0.1 um; the side
//   spin such a contact gives dies as fast): those answers are applied at the contact instant
//   (CollideBallsResting, StopCreep), so they produce no events. Unlike TC we do not switch
//   dissipation off (that would turn the plastic resting contacts elastic and make clusters
//   bounce); we collapse the fast cloth answers, which only dissipates.
// - The balls in contact are resolved together, as one event: every approaching pair of the
//   group (balls linked by gaps below kSustainedRestingGap) by over-relaxed sweeps of contact
//   impulses (sequential impulses, the simultaneous treatment of a resting contact group in
//   rigid-body simulation, with successive over-relaxation), which moves a group pushed slowly
//   as one body.
// - Within kRestingTrain of a pair's last plastic contact, a contact of the pair continues it
//   (TC's rule, per pair): plastic below kTrainContactSpeed, with the resting gap sized for
//   that (kSustainedRestingGap at most), so a push re-forms its contact a few times less often.
//   A pair whose gap cannot open (a ball wedged between two at rest) is jammed for its train:
//   the balls at rest move too.
// The previous treatment, free-ball plastic hops each followed by micro-slides, stays
// reachable as RestingContacts::kHops.
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
/// The largest resting gap (m) with sustained contacts (RestingContacts::kSustained). A push
/// re-forms its contact after sqrt(2 gap / a) (a: the cloth's closing acceleration), so the
/// number of contacts in a push falls as 1/sqrt(gap) and its error (the gaps opened, the
/// impulses standing in for a force) grows as sqrt(gap): a sliding ball pushing another 2 cm
/// in line ends 4.8 um from the continuous contact's closed form at 1 um, 8.9 um at 3 um
/// (event_engine_test). Bounds: a contact the cloth closes fast enough to re-form above
/// kRestingContactSpeed (0.9 mm/s from this gap) must re-form inside its train (kRestingTrain),
/// within 2 gap / 0.9 mm/s: 6.7 ms at 3 um, a third under the 10 ms; and balls left at rest in
/// a sustained contact stay within the snooker referee's touching distance (10 um).
inline constexpr double kSustainedRestingGap = 3e-6;
/// The smallest resting gap (m), for closing accelerations above 200 m/s^2 (extreme mu_s, g).
inline constexpr double kMinRestingGap = 1e-9;

/// A plastic (resting or sustained) contact between the same two bodies within this time (s) of
/// the previous one continues a push (a train of hops) and is not reported again; the first one
/// is. This time serves two windows that differ in one way. What is reported: a collision that
/// is not plastic ends every train of its balls, so the next plastic contact of a pair of them
/// is reported again. What is plastic (kTrainContactSpeed): the pair's window runs from its
/// last plastic contact whatever its balls meet meanwhile, since the gap that contact opened
/// was sized for a plastic re-formation (ending it at other collisions turned those
/// re-formations into bounces, and raised the storm batch's reported events from 540 to 762
/// at worst).
inline constexpr double kRestingTrain = 0.01;

/// Within kRestingTrain of a pair's last plastic contact (RestingContacts::kSustained) the pair
/// is in a train: a contact re-forms because the cloth closed the resting gap that the last one
/// opened, so it continues the sustained contact (the TC model's rule: a contact that follows
/// another within the contact time is not a new collision). It is plastic below this approach
/// speed (m/s), not only below kRestingContactSpeed, and its resting gap is sized for it (up to
/// kSustainedRestingGap): a push the cloth closes at 2-4 m/s^2, a sliding ball driving a group,
/// re-forms several times less often than with gaps sized for kRestingContactSpeed. The
/// approach of such a re-formation is sqrt(2 a gap), at most 0.9 of this speed by the gap's
/// size, if nothing else changed the balls' motion; a collision with a third ball in between
/// may bring it anywhere below this speed, where a plastic answer instead of a bounce changes
/// where a ball rolls to by v^2 / (2 mu_r g) = 0.13 mm at most.
inline constexpr double kTrainContactSpeed = 5e-3;

/// Predictions look at most this far ahead (s); a ball with nothing predicted within it is
/// re-predicted then (a ball that barely slows: rolling resistance or spin decay off or tiny).
inline constexpr double kPredictionHorizon = 1000.0;

/// Orientation of a ball whose spin axis turns (sliding, or rolling with side spin) is
/// integrated in pieces, 4th-order Magnus per piece, on a grid anchored at the ball's last event
/// (so evaluating at any times gives the same values). A piece turns the ball by at most this
/// angle (rad), so its length is set per segment from the largest |w| in it (pieces are never
/// shorter than 1/8192 s, so above 2048 rad/s they turn further).
inline constexpr double kOrientationTurn = 0.25;

/// What the event engine handled, by kind (instrumentation: benches and tests read it).
struct EventEngineCounts {
  int64_t ball_ball = 0;          ///< ball-ball contacts handled, of which:
  int64_t ball_ball_plastic = 0;  ///<   approaching slower than kRestingContactSpeed
  int64_t ball_ball_push = 0;     ///<   with no impulse (a touching pair the cloth closes)
  int64_t cushion = 0;            ///< ball-cushion contacts handled, of which:
  int64_t cushion_plastic = 0;    ///<   plastic or pushes
  int64_t pocket = 0;             ///< captures and balls leaving an open table
  int64_t transition = 0;         ///< predicted motion-state transitions (and horizon looks)
  int64_t state_changes = 0;      ///< motion-state changes caused by contacts
  int64_t predictions = 0;        ///< Predict() calls
  int64_t sustained_contacts = 0; ///< pairs resolved as sustained contacts (HandleSustained)
  int64_t sustained_sweeps = 0;   ///< sweeps over the groups of sustained contacts
  int64_t group_balls = 0;        ///< balls in those groups, summed over the contacts
};
/// The counts of an event simulation; nullptr for another engine.
const EventEngineCounts* EventCountsOf(const TableSimulation& sim);

std::unique_ptr<TableSimulation> MakeEventSimulation(const TableModel& model,
                                                     const SolverOptions& options,
                                                     TableState initial);

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_EVENT_ENGINE_H_
