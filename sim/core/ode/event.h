// Event location inside one step: where a scalar function of the state (a height, an angle, a
// fit variable) crosses zero.
//
// Two stages, in the manner of Hairer, Norsett & Wanner (Solving ODEs I, sec. II.6, "dense
// output and event location") and Shampine & Thompson ("Event location for ordinary
// differential equations", Comput. Math. Appl. 39, 43 (2000)):
//  1. Locate: a bracketed root of g on the step's interpolant (dense output or Hermite), with
//     sim/core/root_find.h. The interpolant is cheap and never leaves the step.
//  2. Refine (optional): Newton on the length of the integrator's own partial step from the
//     step start, so the reported event state is the scheme's solution rather than the
//     interpolant's. Each iteration re-takes the partial step.
#ifndef SPORTSIM_SIM_CORE_ODE_EVENT_H_
#define SPORTSIM_SIM_CORE_ODE_EVENT_H_

#include <algorithm>
#include <optional>

#include "sim/core/root_find.h"

namespace sportsim::ode {

/// Stage 1: the crossing of g in [a, b], given ga = g(a) and gb = g(b) of opposite signs (or
/// one zero), to `tol` (same unit as a and b). g evaluates the step's interpolant.
template <typename G>
double LocateOnInterpolant(G&& g, double a, double b, double ga, double gb, double tol) {
  return FindBracketedRoot(g, a, b, ga, gb, tol);
}

/// The residual of the event condition at the end of a re-taken partial step and its time
/// derivative there.
struct EventResidual {
  double value = 0.0;  ///< g at the end of the partial step
  double rate = 0.0;   ///< dg/dt there
};

/// Stage 2: Newton on the partial-step length h in [0, h_max], starting from `h`.
/// `retake(h)` re-takes the partial step of length h (the caller keeps its state);
/// `residual()` reads that state and returns the EventResidual, or nullopt to stop (rate of the
/// wrong sign, non-finite value). Stops after `max_iterations` Newton updates, when an update
/// changes nothing or would reach 0. retake() has always been called last with the returned h.
template <typename Retake, typename Residual>
double RefineOnStep(double h, double h_max, int max_iterations, Retake&& retake,
                    Residual&& residual) {
  for (int iter = 0;; ++iter) {
    retake(h);
    if (iter == max_iterations) break;
    const std::optional<EventResidual> r = residual();
    if (!r) break;
    const double h_next = std::clamp(h - r->value / r->rate, 0.0, h_max);
    if (h_next == h || h_next <= 0.0) break;
    h = h_next;
  }
  return h;
}

}  // namespace sportsim::ode

#endif  // SPORTSIM_SIM_CORE_ODE_EVENT_H_
