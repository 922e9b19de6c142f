// Fast-forwarding one swing: integrate from the top of the backswing to impact (or a duration),
// sample the state, and locate impact on the step's interpolant.
//
// Impact is the first downward crossing of phi = theta + beta through a multiple of 2 pi (the
// shaft pointing straight down), located to better than 1e-12 s on the interpolant of the step
// in which it happens (cubic Hermite for first-order schemes, quintic for rk4, the continuous extension for dp45).
#ifndef SPORTSIM_SIM_SWING_SWING_SIMULATION_H_
#define SPORTSIM_SIM_SWING_SWING_SIMULATION_H_

#include <functional>
#include <optional>
#include <vector>

#include "absl/status/statusor.h"
#include "sim/swing/swing_model.h"
#include "sim/swing/swing_stepper.h"
#include "sim/swing/torque_program.h"

namespace sportsim::swing {

enum class SwingStop {
  kImpact,    ///< end at impact, or at duration_s if it never comes
  kDuration,  ///< run to duration_s; the torque program applies throughout
};

struct SwingRunOptions {
  SwingStop stop = SwingStop::kImpact;
  double duration_s = 2.0;  ///< end (kDuration) or cap (kImpact) of the run (s), [1e-6, 10]
  int sample_stride = 1;    ///< keep every n-th step's state, >= 1 (first and last always kept)
  /// Keep a step's state only if at least this much simulated time (s) passed since the last
  /// kept one; 0 = off. Bounds the samples of adaptive runs, whose step count is not known.
  double sample_interval_s = 0.0;
  /// Polled every kCancelPollSteps steps; returning true stops the run with kCancelled.
  std::function<bool()> cancelled;

  static constexpr int kCancelPollSteps = ode::kPollSteps;
  static constexpr int kMaxSamples = 200'000;  ///< fixed steps: refused up front; dp45: stops
  static constexpr int kMaxAdaptiveSteps = 2'000'000;  ///< dp45 runs stop with an error here
};
// With dt_s >= 1e-6 s and duration_s <= 10 s a fixed-step run is at most 1e7 steps (~2.5 s of
// CPU for rk4 here); a dp45 run at most kMaxAdaptiveSteps accepted steps (~1 s). Samples are at
// most kMaxSamples (~20 MB on the wire).

/// The state at one instant, with derived quantities. SI units, angles in radians.
struct SwingSample {
  double t_s = 0;
  double alpha = 0, beta = 0, theta = 0, phi = 0;  ///< (rad); phi unwrapped
  double alpha_dot = 0, beta_dot = 0;              ///< (rad/s)
  double clubhead_speed_mps = 0;                   ///< relative to the shoulder
  double clubhead_speed_ground_mps = 0;            ///< relative to the ground
  double clubhead_x_m = 0, clubhead_y_m = 0;       ///< shoulder frame
  double clubhead_vx_mps = 0, clubhead_vy_mps = 0; ///< relative to the shoulder
  double clubhead_vx_ground_mps = 0, clubhead_vy_ground_mps = 0;
};

struct SwingRunResult {
  std::vector<SwingSample> samples;
  std::optional<SwingSample> impact;
  int steps = 0;
  int rejected_steps = 0;
  int rhs_evaluations = 0;
  double end_t_s = 0;
};

/// Derived quantities for state y at time t.
SwingSample MakeSample(const SwingModel& model, double t_s, const SwingVec& y);

/// duration_s must be finite and in [1e-6, 10] s.
absl::Status ValidateDuration(double duration_s);
/// Validates the run options against the solver (sample counts are bounded up front).
absl::Status ValidateRunOptions(const SwingSolverOptions& solver, const SwingRunOptions& run);

/// Runs one swing. Deterministic: the same inputs give bit-identical results.
absl::StatusOr<SwingRunResult> SimulateSwing(const SwingModel& model, const TorqueProgram& program,
                                             const SwingSolverOptions& solver,
                                             const SwingRunOptions& run);

/// If phi falls through a multiple of 2 pi inside the step, the crossing time and state.
/// `stepper` supplies the interpolant (and counts its evaluations).
std::optional<std::pair<double, SwingVec>> FindImpactInStep(SwingStepper& stepper,
                                                            const StepRecord& record);

}  // namespace sportsim::swing

#endif  // SPORTSIM_SIM_SWING_SWING_SIMULATION_H_
