// The swing model, torque program, solver and run options decoded from the bytes, within and
// slightly beyond their valid ranges (plus NaN, infinities, zeros): the validators
// (SwingModel::Create, TorqueProgram::Create, ValidateSolverOptions, ValidateRunOptions) must
// refuse the invalid ones cleanly; an accepted swing runs (at most ~20k steps: the run's cancel
// hook stops it) and must give finite samples in time order, a finite impact inside the run, and
// bit-identical results when run twice.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "sim/swing/swing_model.h"
#include "sim/swing/swing_simulation.h"
#include "sim/swing/swing_stepper.h"
#include "sim/swing/torque_program.h"
#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/fuzz_values.h"

namespace s = sportsim::swing;
using sportsim::fuzz::Bits;
using sportsim::fuzz::RangeValue;

namespace {

s::TorqueSchedule Schedule(FuzzedDataProvider& in) {
  s::TorqueSchedule out;
  out.interpolation = in.ConsumeBool() ? s::Interpolation::kPiecewiseLinear
                                       : s::Interpolation::kPiecewiseConstant;
  const int n = in.ConsumeIntegralInRange(0, 7) == 0 ? in.ConsumeIntegralInRange(0, 70)
                                                      : in.ConsumeIntegralInRange(1, 5);
  double t = 0;
  for (int i = 0; i < n; ++i) {
    // Mostly increasing times; sometimes any value (refused unless increasing, in [0, 1e3]).
    t = in.ConsumeIntegralInRange(0, 15) == 0 ? RangeValue(in, -1, 1e3 + 1)
                                               : t + in.ConsumeFloatingPointInRange(0.0, 0.3);
    const double q = in.ConsumeIntegralInRange(0, 15) == 0
                         ? RangeValue(in, -s::TorqueProgram::kMaxTorqueNm,
                                      s::TorqueProgram::kMaxTorqueNm)
                         : RangeValue(in, -300, 300);
    out.knots.push_back({t, q});
  }
  return out;
}

bool SameSample(const s::SwingSample& a, const s::SwingSample& b) {
  const double x[] = {a.t_s, a.alpha, a.beta, a.theta, a.phi, a.alpha_dot, a.beta_dot,
                      a.clubhead_speed_mps, a.clubhead_speed_ground_mps, a.clubhead_x_m,
                      a.clubhead_y_m, a.clubhead_vx_mps, a.clubhead_vy_mps,
                      a.clubhead_vx_ground_mps, a.clubhead_vy_ground_mps};
  const double y[] = {b.t_s, b.alpha, b.beta, b.theta, b.phi, b.alpha_dot, b.beta_dot,
                      b.clubhead_speed_mps, b.clubhead_speed_ground_mps, b.clubhead_x_m,
                      b.clubhead_y_m, b.clubhead_vx_mps, b.clubhead_vy_mps,
                      b.clubhead_vx_ground_mps, b.clubhead_vy_ground_mps};
  for (size_t i = 0; i < std::size(x); ++i) {
    if (Bits(x[i]) != Bits(y[i])) return false;
  }
  return true;
}

void CheckSample(const s::SwingSample& a, const char* what) {
  const double x[] = {a.t_s, a.alpha, a.beta, a.theta, a.phi, a.alpha_dot, a.beta_dot,
                      a.clubhead_speed_mps, a.clubhead_speed_ground_mps, a.clubhead_x_m,
                      a.clubhead_y_m, a.clubhead_vx_mps, a.clubhead_vy_mps,
                      a.clubhead_vx_ground_mps, a.clubhead_vy_ground_mps};
  for (double v : x) FUZZ_CHECK(std::isfinite(v), "%s at t = %g: a value is %g", what, a.t_s, v);
  FUZZ_CHECK(a.clubhead_speed_mps >= 0 && a.clubhead_speed_ground_mps >= 0, "%s: speed < 0", what);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  s::SwingParams p;
  // Each parameter: kept at the chapter's value, or decoded around its valid range.
  auto maybe = [&](double* field, double lo, double hi) {
    if (in.ConsumeBool()) *field = RangeValue(in, lo, hi);
  };
  maybe(&p.arm_inertia_kgm2, 0, 100);
  maybe(&p.arm_length_m, 0, 5);
  maybe(&p.arm_first_moment_kgm, 0, 100);
  maybe(&p.club_inertia_kgm2, 0, 100);
  maybe(&p.club_mass_kg, 0, 100);
  maybe(&p.club_length_m, 0, 5);
  maybe(&p.club_first_moment_kgm, 0, 100);
  maybe(&p.gravity_mps2, 0, 100);
  maybe(&p.gamma_rad, -2 * M_PI, 2 * M_PI);
  maybe(&p.beta0_rad, -2 * M_PI, 2 * M_PI);
  maybe(&p.shoulder_accel_mps2, 0, 100);
  uint32_t effects = in.ConsumeIntegral<uint8_t>();
  if (effects < 224) effects &= s::kSwingEffectBits;  // sometimes unknown bits
  absl::StatusOr<s::SwingModel> model = s::SwingModel::Create(p, effects);
  if (!model.ok()) {
    sportsim::fuzz::CheckMessage("SwingModel::Create", model.status());
    FUZZ_CHECK(model.status().code() == absl::StatusCode::kInvalidArgument, "SwingModel: %s",
               std::string(model.status().message()).c_str());
    return 0;
  }

  absl::StatusOr<s::TorqueProgram> program = s::TorqueProgram::Chapter();
  if (in.ConsumeBool()) {
    const s::TorqueSchedule qa = Schedule(in);
    const s::TorqueSchedule qb = Schedule(in);
    program = s::TorqueProgram::Create(qa, qb);
    if (!program.ok()) {
      sportsim::fuzz::CheckMessage("TorqueProgram::Create", program.status());
      return 0;
    }
  }

  s::SwingSolverOptions solver;
  solver.integrator = s::kAllSwingIntegrators[in.ConsumeIntegralInRange<size_t>(
      0, s::kAllSwingIntegrators.size() - 1)];
  if (in.ConsumeBool()) solver.accuracy.dt_s = RangeValue(in, 1e-4, 0.1);
  if (in.ConsumeBool()) solver.accuracy.tolerance = RangeValue(in, 1e-12, 0.1);
  if (in.ConsumeBool()) solver.accuracy.max_step_s = RangeValue(in, 1e-4, 0.1);
  if (in.ConsumeIntegralInRange(0, 7) == 0) solver.max_turn_per_step_rad = RangeValue(in, 0, 3);
  if (absl::Status st = s::ValidateSolverOptions(solver); !st.ok()) {
    sportsim::fuzz::CheckMessage("ValidateSolverOptions", st);
    return 0;
  }
  s::SwingRunOptions run;
  run.stop = in.ConsumeBool() ? s::SwingStop::kImpact : s::SwingStop::kDuration;
  run.duration_s = RangeValue(in, 1e-6, 10);
  run.sample_stride = in.ConsumeIntegralInRange(0, 5) == 0 ? in.ConsumeIntegral<int>()
                                                          : in.ConsumeIntegralInRange(1, 50);
  if (in.ConsumeBool()) run.sample_interval_s = RangeValue(in, 0, 1);
  if (absl::Status st = s::ValidateRunOptions(solver, run); !st.ok()) {
    sportsim::fuzz::CheckMessage("ValidateRunOptions", st);
    return 0;
  }
  // Bounded work: the run polls `cancelled` every kCancelPollSteps steps.
  auto run_once = [&](int* polls) {
    s::SwingRunOptions r = run;
    r.cancelled = [polls] { return ++*polls > 20; };
    return s::SimulateSwing(*model, *program, solver, r);
  };
  int polls1 = 0, polls2 = 0;
  const absl::StatusOr<s::SwingRunResult> r1 = run_once(&polls1);
  const absl::StatusOr<s::SwingRunResult> r2 = run_once(&polls2);
  FUZZ_CHECK(r1.ok() == r2.ok() && r1.status().code() == r2.status().code(),
             "two runs differ: %s vs %s", r1.status().ToString().c_str(),
             r2.status().ToString().c_str());
  if (!r1.ok()) {
    sportsim::fuzz::CheckMessage("SimulateSwing", r1.status());
    FUZZ_CHECK(r1.status().code() != absl::StatusCode::kInternal &&
                   r1.status().code() != absl::StatusCode::kUnknown,
               "SimulateSwing: %s", r1.status().ToString().c_str());
    return 0;
  }
  const s::SwingRunResult& a = *r1;
  FUZZ_CHECK(!a.samples.empty(), "no samples");
  FUZZ_CHECK(a.samples.size() <= static_cast<size_t>(s::SwingRunOptions::kMaxSamples) + 2,
             "%zu samples", a.samples.size());
  double t_prev = -INFINITY;
  for (const s::SwingSample& x : a.samples) {
    CheckSample(x, "sample");
    FUZZ_CHECK(x.t_s >= t_prev && x.t_s >= 0 && x.t_s <= run.duration_s * (1 + 1e-12),
               "sample at t = %g (previous %g, duration %g)", x.t_s, t_prev, run.duration_s);
    t_prev = x.t_s;
  }
  FUZZ_CHECK(std::isfinite(a.end_t_s) && a.end_t_s <= run.duration_s * (1 + 1e-12) &&
                 a.end_t_s >= 0,
             "end_t_s %g, duration %g", a.end_t_s, run.duration_s);
  FUZZ_CHECK(a.steps >= 0 && a.rejected_steps >= 0 && a.rhs_evaluations >= 0, "counters");
  if (a.impact) {
    CheckSample(*a.impact, "impact");
    FUZZ_CHECK(a.impact->t_s >= 0 && a.impact->t_s <= a.end_t_s * (1 + 1e-12) + 1e-15,
               "impact at %g, run ended at %g", a.impact->t_s, a.end_t_s);
  }
  const s::SwingRunResult& b = *r2;
  FUZZ_CHECK(a.samples.size() == b.samples.size() && a.steps == b.steps &&
                 a.rhs_evaluations == b.rhs_evaluations && Bits(a.end_t_s) == Bits(b.end_t_s) &&
                 a.impact.has_value() == b.impact.has_value(),
             "two runs differ (%zu vs %zu samples)", a.samples.size(), b.samples.size());
  for (size_t i = 0; i < std::min(a.samples.size(), b.samples.size()); ++i) {
    FUZZ_CHECK(SameSample(a.samples[i], b.samples[i]), "two runs differ at sample %zu", i);
  }
  if (a.impact && b.impact) FUZZ_CHECK(SameSample(*a.impact, *b.impact), "impacts differ");
  return 0;
}
