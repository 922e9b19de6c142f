// Time integration of the swing: five schemes behind one stepper.
//
//  kBook               The chapter's scheme (Bourg & Bywalec ch. 19): four acceleration
//                      evaluations per step that update only the rates (positions held), an
//                      RK4-weighted rate update, then positions from the new rates. First order.
//                      It is not a Runge-Kutta tableau (positions are held through the
//                      stages), so it stays here, written out.
//  kEuler              Explicit Euler on the full state (sim/core/ode/runge_kutta.h). First
//                      order.
//  kSemiImplicitEuler  Symplectic Euler: rates from the old state, positions from the new
//                      rates. First order. A partitioned scheme (not one tableau for the whole
//                      state), written here for the swing's (angles, rates) split.
//  kRk4                Classical fourth-order Runge-Kutta on the full state
//                      (sim/core/ode/runge_kutta.h). Fourth order.
//  kDp45               Dormand & Prince 5(4) with error control (RMS norm) and the
//                      fourth-order continuous extension (sim/core/ode/runge_kutta.h, which
//                      cites the tableau and the controller).
//
// Fixed-step schemes step on the grid t_k = k dt (k an integer, never an accumulated sum). A
// torque breakpoint or stop time inside a grid step splits it, so every scheme honours switch
// times exactly; dp45 clamps its step to land on them. Each step reports a StepRecord from which
// the state anywhere inside the step can be interpolated (cubic Hermite for first-order schemes, quintic for rk4, the
// continuous extension for dp45) to locate impact.
#ifndef SPORTSIM_SIM_SWING_SWING_STEPPER_H_
#define SPORTSIM_SIM_SWING_SWING_STEPPER_H_

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "sim/core/ode/integrator.h"
#include "sim/core/ode/runge_kutta.h"
#include "sim/swing/swing_dynamics.h"
#include "sim/swing/swing_model.h"
#include "sim/swing/torque_program.h"

namespace sportsim::swing {

/// The swing's integrators are sim/core/ode's (the one enum); the swing supports all five.
using SwingIntegrator = ode::Integrator;

/// "book", "euler", "semi_implicit_euler", "rk4", "dp45" (ode::IntegratorName).
std::string_view SwingIntegratorName(SwingIntegrator integrator);
std::optional<SwingIntegrator> SwingIntegratorFromName(std::string_view name);
/// The schemes the swing supports, in the order the tools list them.
inline constexpr std::array<SwingIntegrator, 5> kAllSwingIntegrators = {
    SwingIntegrator::kBook, SwingIntegrator::kEuler, SwingIntegrator::kSemiImplicitEuler,
    SwingIntegrator::kRk4, SwingIntegrator::kDp45};

/// Solver choice and the accuracy contract (sim/core/ode/integrator.h): fixed-step schemes take
/// accuracy.dt_s (s, [1e-6, 0.1], default kDefaultDt); dp45 takes accuracy.tolerance ([1e-14,
/// 0.1], default kDefaultTolerance) and accuracy.max_step_s (s, [1e-6, 0.1], default
/// kDefaultMaxStep). Giving a scheme the other kind's setting is an InvalidArgument error.
struct SwingSolverOptions {
  SwingIntegrator integrator = SwingIntegrator::kRk4;
  ode::Accuracy accuracy;  ///< dt_s, or tolerance and max_step_s (see above)
  /// Fixed steps: the largest angle (rad) any of alpha, beta, phi may turn in one step before the
  /// run is stopped as under-resolved (|omega| dt bound). 0.5 rad keeps explicit Euler's
  /// amplification per step on an oscillator (sqrt(1 + (w dt)^2)) under 12 %.
  double max_turn_per_step_rad = 0.5;

  static constexpr double kDefaultDt = 0.0025;      ///< the chapter's step (s)
  static constexpr double kDefaultTolerance = 1e-8;
  static constexpr double kDefaultMaxStep = 0.01;   ///< (s)
  /// The swing's defaults and ranges for the contract.
  static const ode::AccuracyLimits kLimits;
  /// The fixed step in use (s): accuracy.dt_s or kDefaultDt (0 for dp45).
  double dt() const { return ode::ResolveAccuracy(integrator, accuracy, kLimits).dt_s; }
};

/// Checks the options against the accuracy contract above.
absl::Status ValidateSolverOptions(const SwingSolverOptions& options);

/// What one step did: enough to interpolate the state anywhere in [t0, t1].
struct StepRecord {
  double t0 = 0, t1 = 0;
  SwingVec y0 = SwingVec::Zero(), y1 = SwingVec::Zero();
  int segment = 0;                  ///< torque segment in force during the step
  bool dense = false;               ///< dp45: the continuous extension below is valid
  ode::Dp45Dense<SwingVec> continuous{};  ///< dp45 continuous extension
};

/// Steps one swing forward from the top of the backswing. Holds pointers to the model and the
/// program, which must outlive it.
class SwingStepper {
 public:
  static absl::StatusOr<SwingStepper> Create(const SwingModel* model, const TorqueProgram* program,
                                             const SwingSolverOptions& options);

  /// Advances one step, never past t_limit (s). Errors: a non-finite state, a fixed step that
  /// turns an angle by more than max_turn_per_step_rad, dp45 step-size underflow.
  absl::Status Step(double t_limit, StepRecord* record);

  /// For live input: the program (same object, or `program`) now holds different torques from
  /// the current time on. Re-derives the segment at t() (right-continuous) and drops dp45's
  /// first-same-as-last derivative. The program must not change before t(): records already
  /// made are interpolated with the program in force when they are interpolated.
  void ProgramChanged(const TorqueProgram* program);

  /// The state at time t in [record.t0, record.t1].
  SwingVec Interpolate(const StepRecord& record, double t);

  double t() const { return t_; }
  const SwingVec& y() const { return y_; }
  int steps() const { return steps_; }
  int rejected_steps() const { return rejected_; }
  int rhs_evaluations() const { return rhs_evals_; }
  const SwingModel& model() const { return *model_; }
  /// The initial state: at rest at alpha = 0, beta = beta0.
  static SwingVec InitialState(const SwingModel& model);

 private:
  SwingStepper(const SwingModel* model, const TorqueProgram* program,
               const SwingSolverOptions& options);
  SwingVec F(int segment, double t, const SwingVec& y) {
    ++rhs_evals_;
    return SwingDerivative(*model_, y, program_->At(segment, t));
  }
  absl::Status FixedStep(double t_limit, StepRecord* record);
  absl::Status Dp45Step(double t_limit, StepRecord* record);
  double Dp45InitialStep(double t_end);
  // The end of the current segment (next breakpoint) or +inf.
  double SegmentEnd() const;

  const SwingModel* model_;
  const TorqueProgram* program_;
  SwingIntegrator integrator_;
  double dt_ = 0, tol_ = 0, max_step_ = 0, max_turn_ = 0;
  double t_ = 0;
  int64_t grid_ = 0;  // fixed steps: index of the last grid point at or before t_
  int segment_ = 0;
  SwingVec y_;
  // dp45 state.
  double h_ = 0;
  bool fsal_valid_ = false;
  SwingVec k1_ = SwingVec::Zero();
  int steps_ = 0, rejected_ = 0, rhs_evals_ = 0;
};

}  // namespace sportsim::swing

#endif  // SPORTSIM_SIM_SWING_SWING_STEPPER_H_
