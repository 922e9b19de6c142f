// The integrator choice and the accuracy contract shared by every stepped model in sim/.
//
// One enum names every scheme; each domain states which it supports (the billiards stepped
// engine: euler, semi_implicit_euler, rk4; the swing: all five; golf flight: rk4, dp45).
//
// The accuracy contract (after Drake's separate fixed-step and error-controlled modes,
// systems/analysis/integrator_base.h: set_fixed_step_mode / set_target_accuracy): a
// fixed-step scheme is controlled by its step alone, an error-controlled scheme (dp45) by a
// tolerance and a largest step. Giving a scheme the other kind's setting is an InvalidArgument
// error, never silently ignored. Unset fields take the domain's defaults (AccuracyLimits).
#ifndef SPORTSIM_SIM_CORE_ODE_INTEGRATOR_H_
#define SPORTSIM_SIM_CORE_ODE_INTEGRATOR_H_

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "absl/status/status.h"

namespace sportsim::ode {

/// Time-stepping schemes. The values index IntegratorName's table and must not change (the
/// billiards engine's names are the first three in order).
enum class Integrator : uint8_t {
  kEuler = 0,              ///< explicit Euler, order 1 (runge_kutta.h)
  kSemiImplicitEuler = 1,  ///< symplectic Euler, order 1: rates first, positions from the new
                           ///< rates; partitioned, so each domain writes it for its own state
  kRk4 = 2,                ///< classical Runge-Kutta, order 4 (runge_kutta.h)
  kDp45 = 3,               ///< Dormand-Prince 5(4), error-controlled, dense output (runge_kutta.h)
  kBook = 4,               ///< the swing chapter's scheme (Bourg & Bywalec ch. 19), order 1; swing
                           ///< only (it is not a Runge-Kutta tableau: see swing_stepper.h)
};

/// Every scheme, in enum order.
inline constexpr std::array<Integrator, 5> kAllIntegrators = {
    Integrator::kEuler, Integrator::kSemiImplicitEuler, Integrator::kRk4, Integrator::kDp45,
    Integrator::kBook};

/// "euler", "semi_implicit_euler", "rk4", "dp45", "book".
std::string_view IntegratorName(Integrator integrator);
/// The scheme of a name above; nullopt for an unknown name.
std::optional<Integrator> IntegratorFromName(std::string_view name);
/// Every stepped run in sim/ (a swing, live or offline; a golf ball's flight) polls its
/// caller's cancellation, and checks an error-controlled run's step cap, after every
/// kPollSteps-th step: 0.2-0.3 ms of CPU apart for RK4 in a release build (a flight step takes
/// ~0.2 us, a swing step ~0.25 us), at the cost of one modulo a step.
inline constexpr int kPollSteps = 1024;

/// True for the error-controlled schemes (dp45), which take a tolerance instead of a step.
constexpr bool IsErrorControlled(Integrator integrator) {
  return integrator == Integrator::kDp45;
}

/// The accuracy contract: a fixed step OR a tolerance (with an optional largest step), never
/// both. Which one applies follows from the integrator; unset fields take the domain's defaults.
struct Accuracy {
  std::optional<double> dt_s;        ///< fixed-step schemes only: the step (s)
  std::optional<double> tolerance;   ///< dp45 only: relative and absolute error bound per step
                                     ///< (dimensionless; errors are scaled by 1 + |y_i|)
  std::optional<double> max_step_s;  ///< dp45 only: largest step (s)
};

/// A closed or open interval for one setting.
struct Range {
  double lo = 0.0;
  bool lo_open = false;
  double hi = 0.0;
  bool hi_open = false;
};

/// A domain's defaults and ranges for the contract.
struct AccuracyLimits {
  double default_dt_s = 0.0;                 ///< fixed step when dt_s is unset (s)
  Range dt_s;                                ///< allowed dt_s (s)
  std::optional<double> default_tolerance;   ///< nullopt: dp45 requires a tolerance
  Range tolerance;                           ///< allowed tolerance
  double default_max_step_s = 0.0;           ///< dp45 largest step when unset (s)
  Range max_step_s;                          ///< allowed max_step_s (s)
};

/// The contract with the defaults filled in. Fields that do not apply to the scheme are 0.
struct StepSettings {
  double dt_s = 0.0;        ///< fixed-step schemes (s)
  double tolerance = 0.0;   ///< dp45
  double max_step_s = 0.0;  ///< dp45 (s)
};

/// InvalidArgument when a setting of the other kind is given ("tolerance applies only to dp45;
/// rk4 is a fixed-step integrator: set dt_s", "dt_s does not apply to dp45: ..."), when dp45
/// needs a tolerance and has none, or when a value is out of its range.
absl::Status ValidateAccuracy(Integrator integrator, const Accuracy& accuracy,
                              const AccuracyLimits& limits);

/// The settings in use (call after ValidateAccuracy).
StepSettings ResolveAccuracy(Integrator integrator, const Accuracy& accuracy,
                             const AccuracyLimits& limits);

}  // namespace sportsim::ode

#endif  // SPORTSIM_SIM_CORE_ODE_INTEGRATOR_H_
