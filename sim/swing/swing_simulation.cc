#include "sim/swing/swing_simulation.h"

#include <cmath>

#include "absl/strings/str_format.h"
#include "sim/core/ode/event.h"
#include "sim/swing/swing_dynamics.h"

namespace sportsim::swing {
namespace {

// Impact time resolution on the interpolant (s): far below the 1e-9 s the contract asks.
constexpr double kImpactTimeTol = 1e-13;

double Phi(const SwingModel& m, const SwingVec& y) { return m.params().gamma_rad - y[0] + y[1]; }

}  // namespace

SwingSample MakeSample(const SwingModel& model, double t_s, const SwingVec& y) {
  const ClubheadKinematics k = Clubhead(model, y, t_s);
  SwingSample s;
  s.t_s = t_s;
  s.alpha = y[0];
  s.beta = y[1];
  s.theta = model.params().gamma_rad - y[0];
  s.phi = s.theta + y[1];
  s.alpha_dot = y[2];
  s.beta_dot = y[3];
  s.clubhead_speed_mps = k.speed_mps;
  s.clubhead_speed_ground_mps = k.ground_speed_mps;
  s.clubhead_x_m = k.position_m.x();
  s.clubhead_y_m = k.position_m.y();
  s.clubhead_vx_mps = k.velocity_mps.x();
  s.clubhead_vy_mps = k.velocity_mps.y();
  s.clubhead_vx_ground_mps = k.ground_velocity_mps.x();
  s.clubhead_vy_ground_mps = k.ground_velocity_mps.y();
  return s;
}

std::optional<std::pair<double, SwingVec>> FindImpactInStep(SwingStepper& stepper,
                                                            const StepRecord& r) {
  const SwingModel& m = stepper.model();
  const double phi0 = Phi(m, r.y0), phi1 = Phi(m, r.y1);
  // The largest multiple of 2 pi strictly below phi0; a crossing takes phi to or below it.
  const double target = kTwoPi * (std::ceil(phi0 / kTwoPi) - 1.0);
  if (!(phi1 <= target)) return std::nullopt;
  auto g = [&](double t) { return Phi(m, stepper.Interpolate(r, t)) - target; };
  const double t =
      ode::LocateOnInterpolant(g, r.t0, r.t1, phi0 - target, phi1 - target, kImpactTimeTol);
  return std::make_pair(t, stepper.Interpolate(r, t));
}

absl::Status ValidateDuration(double duration_s) {
  if (std::isfinite(duration_s) && duration_s >= 1e-6 && duration_s <= 10) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrFormat("duration_s must be finite and in [1e-06, 10] s, got %g", duration_s));
}

absl::Status ValidateRunOptions(const SwingSolverOptions& solver, const SwingRunOptions& run) {
  if (absl::Status s = ValidateDuration(run.duration_s); !s.ok()) return s;
  if (run.sample_stride < 1) {
    return absl::InvalidArgumentError(
        absl::StrFormat("sample_stride must be at least 1, got %d", run.sample_stride));
  }
  if (!(std::isfinite(run.sample_interval_s) && run.sample_interval_s >= 0)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "sample_interval_s must be finite and >= 0 s, got %g", run.sample_interval_s));
  }
  // Fixed steps: refuse too many samples before running (dp45's count is unknown; the run
  // itself stops at kMaxSamples).
  const double samples =
      solver.integrator == SwingIntegrator::kDp45
          ? 0.0
          : run.duration_s / solver.dt() / run.sample_stride;
  if (samples > SwingRunOptions::kMaxSamples) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "the run would keep about %.0f samples, more than %d: raise sample_stride (or "
        "sample_interval_s for dp45)",
        samples, SwingRunOptions::kMaxSamples));
  }
  return absl::OkStatus();
}

absl::StatusOr<SwingRunResult> SimulateSwing(const SwingModel& model, const TorqueProgram& program,
                                             const SwingSolverOptions& solver,
                                             const SwingRunOptions& run) {
  if (absl::Status s = ValidateRunOptions(solver, run); !s.ok()) return s;
  absl::StatusOr<SwingStepper> stepper_or = SwingStepper::Create(&model, &program, solver);
  if (!stepper_or.ok()) return stepper_or.status();
  SwingStepper& stepper = *stepper_or;

  SwingRunResult result;
  result.samples.push_back(MakeSample(model, 0.0, stepper.y()));
  const double t_end = run.duration_s;
  StepRecord rec;
  bool last_sampled = true;
  double last_sample_t = 0.0;
  while (stepper.t() < t_end) {
    if (absl::Status s = stepper.Step(t_end, &rec); !s.ok()) return s;
    last_sampled = false;
    if (stepper.steps() % SwingRunOptions::kCancelPollSteps == 0) {
      if (run.cancelled && run.cancelled()) {
        return absl::CancelledError(
            absl::StrFormat("swing cancelled at t = %.6g s after %d steps", stepper.t(),
                            stepper.steps()));
      }
      if (solver.integrator == SwingIntegrator::kDp45 &&
          stepper.steps() >= SwingRunOptions::kMaxAdaptiveSteps) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "the run took %d steps by t = %.6g s without finishing: loosen the tolerance, raise "
            "max_step_s or shorten duration_s",
            stepper.steps(), stepper.t()));
      }
    }
    if (!result.impact) {
      if (auto hit = FindImpactInStep(stepper, rec)) {
        result.impact = MakeSample(model, hit->first, hit->second);
        if (run.stop == SwingStop::kImpact) break;
      }
    }
    if (stepper.steps() % run.sample_stride == 0 &&
        stepper.t() - last_sample_t >= run.sample_interval_s) {
      if (result.samples.size() >= SwingRunOptions::kMaxSamples) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "the run kept %d samples by t = %.6g s: raise sample_stride or sample_interval_s",
            SwingRunOptions::kMaxSamples, stepper.t()));
      }
      result.samples.push_back(MakeSample(model, stepper.t(), stepper.y()));
      last_sample_t = stepper.t();
      last_sampled = true;
    }
  }
  if (run.stop == SwingStop::kImpact && result.impact) {
    result.samples.push_back(*result.impact);
    result.end_t_s = result.impact->t_s;
  } else {
    if (!last_sampled) result.samples.push_back(MakeSample(model, stepper.t(), stepper.y()));
    result.end_t_s = stepper.t();
  }
  result.steps = stepper.steps();
  result.rejected_steps = stepper.rejected_steps();
  result.rhs_evaluations = stepper.rhs_evaluations();
  return result;
}

}  // namespace sportsim::swing
