// Solver options shared by the billiards engines, and Advance(): move a table to a later time.
#ifndef SPORTSIM_SIM_BILLIARDS_ENGINE_H_
#define SPORTSIM_SIM_BILLIARDS_ENGINE_H_

#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "sim/billiards/model.h"
#include "sim/core/ode/integrator.h"
#include "sim/billiards/state.h"

namespace sportsim::billiards {

enum class Engine : uint8_t {
  kStepped,  ///< fixed step, an integrator, continuous collision detection (can model drag)
  kEvent,    ///< exact, event-driven (closed-form trajectories between events)
};

/// Integrators of the stepped engine (sim/core/ode's one enum), for (r, v, w) in a fixed motion
/// state. Transitions and collisions split steps, so each scheme only ever integrates a smooth
/// law; without drag that law has constant accelerations, which rk4 integrates exactly. The
/// stepped engine supports three:
///   kEuler              explicit Euler, order 1: r += v h, v += a h (the chapter's scheme;
///                       sim/core/ode/runge_kutta.h)
///   kSemiImplicitEuler  symplectic Euler, order 1: v += a h, then r += v h (partitioned; written
///                       in engine.cc for the ball's (r; v, w) split)
///   kRk4                classical Runge-Kutta, order 4 (sim/core/ode/runge_kutta.h)
using Integrator = ode::Integrator;

std::span<const std::string_view> EngineNames();      ///< "event", "stepped"
std::span<const std::string_view> IntegratorNames();  ///< "euler", "semi_implicit_euler", "rk4"
std::string_view EngineName(Engine e);
using ode::IntegratorName;  ///< "euler", "semi_implicit_euler", "rk4" (and the others)

/// Event engine: the treatment of resting ball-ball contacts (approach below
/// kRestingContactSpeed, collision.h). See docs/billiards.md, "Resting contacts".
enum class RestingContacts : uint8_t {
  /// A sustained contact: a finite force, which the cloth answers. The plastic impulse acts
  /// through the rolling constraint on a ball that rolls or rests (CollideBallsResting: the
  /// impulse followed at once by the slide-to-roll it would cause), the cloth's other fast
  /// answers (short slides, creeping rolls, side spin from the contact) are applied at once,
  /// and the group of balls in contact is resolved together as one event (event_engine.h):
  /// no micro-slides, no trains of transitions.
  kSustained,
  /// The free-ball plastic impulse (CollideBalls with e = 0): each hop of a push makes the
  /// balls slide for microseconds (the behaviour before 2026-12, kept for comparison).
  kHops,
};

struct SolverOptions {
  Engine engine = Engine::kEvent;
  Integrator integrator = Integrator::kRk4;
  double dt_s = 1.0 / 960.0;   ///< stepped engine: fixed step (s), in [1e-6, 0.1] (the engine
                               ///< has fixed-step schemes only, so its accuracy is dt_s alone)
  bool ccd = true;             ///< stepped engine: continuous collision detection
  uint32_t effects = 0;        ///< Effect bits (model.h); 0 = default physics (no air drag;
                               ///< kEffectEnableDrag switches it on, stepped engine only)
  /// A run that handles more events stops with ResourceExhausted. The stepped engine counts the
  /// events it records; the event engine counts every event it processes (collisions,
  /// transitions and the resting-contact pushes it does not report).
  int64_t max_events = 200000;
  /// Event engine: how a ball-ball contact slower than kRestingContactSpeed is resolved.
  RestingContacts resting_contacts = RestingContacts::kSustained;
};

/// Checks ranges, and that the engine can model the enabled effects.
absl::Status ValidateSolverOptions(const SolverOptions& options);

/// A table moving under one engine, advanced by the caller to later times (a server's ticks)
/// or to rest. The event engine keeps every ball's closed-form trajectory since its last event,
/// so the state at a time is a function of the events alone: advancing in any chunks gives
/// bit-identical states and events. The stepped engine steps on the grid t = k dt.
class TableSimulation {
 public:
  /// Validates the options, starts balls that were given a velocity moving (StartMoving: their
  /// transitions go to `events`) and predicts what happens next. The model must outlive the
  /// simulation.
  static absl::StatusOr<std::unique_ptr<TableSimulation>> Create(const TableModel& model,
                                                                 const SolverOptions& options,
                                                                 TableState initial,
                                                                 std::vector<Event>* events);
  virtual ~TableSimulation() = default;

  /// Moves to `t_s` (>= time()), appending the events up to and including t_s in time order.
  /// Errors: InvalidArgument for a bad time, ResourceExhausted at the event cap, Internal if the
  /// state turns non-finite. After an error the simulation must not be advanced again.
  virtual absl::Status AdvanceTo(double t_s, std::vector<Event>* events) = 0;
  /// The table at time().
  virtual const TableState& state() = 0;
  virtual double time() const = 0;
  /// Every ball stationary or pocketed: nothing happens until a ball is given a velocity.
  virtual bool AtRest() const = 0;
  /// Events handled so far, reported or not (what max_events caps).
  virtual int64_t events_processed() const = 0;
};

/// Advances `state` to `t_end_s` (>= state->t_s), appending what happens to `events` in time
/// order: TableSimulation::Create, then AdvanceTo. The stepped engine steps on the grid
/// t = k dt_s (a t_end off the grid ends with a partial step), so chunked calls that end on grid
/// points give bit-identical results; the event engine restarts its trajectories from the
/// state given, so chunked calls agree to rounding only (keep a TableSimulation to get
/// bit-identical chunks). A table at rest costs nothing. Balls given a velocity start moving first (StartMoving). Errors:
/// InvalidArgument for bad options, ResourceExhausted at the event cap, Internal if the state
/// turns non-finite (with the time).
absl::Status Advance(const TableModel& model, const SolverOptions& options, double t_end_s,
                     TableState* state, std::vector<Event>* events);

/// Balls that are stationary or spinning but have been given a velocity from outside (a
/// strike, explicit motions) start moving: their motion state is re-derived, with a transition
/// event. Advance does this on entry; SimulateShot before it asks whether the table is at rest.
void StartMoving(const TableModel& model, TableState* state, std::vector<Event>* events);

/// Total kinetic energy of the balls on the cloth (J).
double TotalKineticEnergy(const TableModel& model, const TableState& state);

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_ENGINE_H_
