// Time integration of the swing: five schemes behind one stepper.
//
//  kBook               The chapter's scheme (Bourg & Bywalec ch. 19): four acceleration
//                      evaluations per step that update only the rates (positions held), an
//                      RK4-weighted rate update, then positions from the new rates. First order.
//  kEuler              Explicit Euler on the full state. First order.
//  kSemiImplicitEuler  Symplectic Euler: rates from the old state, positions from the new
//                      rates. First order.
//  kRk4                Classical fourth-order Runge-Kutta on the full state. Fourth order.
//  kDp45               Dormand & Prince, "A family of embedded Runge-Kutta formulae", J. Comput.
//                      Appl. Math. 6 (1980): fifth-order solution, fourth-order error estimate,
//                      first-same-as-last; step control and the fourth-order continuous
//                      extension as in Hairer, Norsett & Wanner, Solving ODEs I, sec. II.4-6.
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
#include "sim/swing/swing_dynamics.h"
#include "sim/swing/swing_model.h"
#include "sim/swing/torque_program.h"

namespace sportsim::swing {

enum class SwingIntegrator { kBook, kEuler, kSemiImplicitEuler, kRk4, kDp45 };

/// "book", "euler", "semi_implicit_euler", "rk4", "dp45".
std::string_view SwingIntegratorName(SwingIntegrator integrator);
std::optional<SwingIntegrator> SwingIntegratorFromName(std::string_view name);
inline constexpr std::array<SwingIntegrator, 5> kAllSwingIntegrators = {
    SwingIntegrator::kBook, SwingIntegrator::kEuler, SwingIntegrator::kSemiImplicitEuler,
    SwingIntegrator::kRk4, SwingIntegrator::kDp45};

/// Solver choice. Fixed-step schemes take dt_s; dp45 takes tolerance and max_step_s; giving a
/// scheme the other kind's setting is an InvalidArgument error, never silently ignored.
struct SwingSolverOptions {
  SwingIntegrator integrator = SwingIntegrator::kRk4;
  std::optional<double> dt_s;        ///< fixed step (s), in [1e-6, 0.1]; default kDefaultDt
  std::optional<double> tolerance;   ///< dp45 relative and absolute tolerance, [1e-14, 0.1]; default 1e-8
  std::optional<double> max_step_s;  ///< dp45 largest step (s), (0, 0.1]; default 0.01
  /// Fixed steps: the largest angle (rad) any of alpha, beta, phi may turn in one step before the
  /// run is stopped as under-resolved (|omega| dt bound). 0.5 rad keeps explicit Euler's
  /// amplification per step on an oscillator (sqrt(1 + (w dt)^2)) under 12 %.
  double max_turn_per_step_rad = 0.5;

  static constexpr double kDefaultDt = 0.0025;      ///< the chapter's step (s)
  static constexpr double kDefaultTolerance = 1e-8;
  static constexpr double kDefaultMaxStep = 0.01;   ///< (s)
};

/// Checks the options against the accuracy contract above.
absl::Status ValidateSolverOptions(const SwingSolverOptions& options);

/// What one step did: enough to interpolate the state anywhere in [t0, t1].
struct StepRecord {
  double t0 = 0, t1 = 0;
  SwingVec y0 = SwingVec::Zero(), y1 = SwingVec::Zero();
  int segment = 0;                  ///< torque segment in force during the step
  bool dense = false;               ///< dp45: the continuous extension below is valid
  std::array<SwingVec, 5> rcont{};  ///< dp45 continuous-extension coefficients
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
