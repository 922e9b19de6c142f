// Accuracy versus cost of every swing integrator on the chapter's swing.
//
// For each integrator and step (dp45: tolerance) it measures, against a converged reference
// (dp45 at tolerance 1e-13, cross-checked with rk4 at 1e-5 s), the error of the impact time, the
// error of the impact clubhead speed, the largest angle error (alpha or beta) at any step up to
// impact, and the CPU time per swing (median of repeated runs, thread CPU clock). Prints CSV on
// stdout; bench/swing_accuracy.py turns it into docs/swing-accuracy.md and its plot.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "sim/core/cpu_clock.h"
#include "sim/swing/swing_simulation.h"
#include "sim/swing/swing_stepper.h"

namespace sportsim::swing {
namespace {

// The reference trajectory as dp45 steps, evaluated anywhere through the continuous extension.
class Reference {
 public:
  Reference(const SwingModel& m, const TorqueProgram& p) {
    SwingSolverOptions o{.integrator = SwingIntegrator::kDp45,
                         .accuracy = {.tolerance = 1e-13, .max_step_s = 1e-3}};
    SwingStepper s = *SwingStepper::Create(&m, &p, o);
    stepper_.emplace(std::move(s));
    StepRecord rec;
    while (stepper_->t() < 0.6) {
      if (!stepper_->Step(0.6, &rec).ok()) std::abort();
      records_.push_back(rec);
    }
  }
  SwingVec At(double t) {
    auto it = std::lower_bound(records_.begin(), records_.end(), t,
                               [](const StepRecord& r, double x) { return r.t1 < x; });
    if (it == records_.end()) it = records_.end() - 1;
    return stepper_->Interpolate(*it, t);
  }

 private:
  std::optional<SwingStepper> stepper_;
  std::vector<StepRecord> records_;
};

void Study() {
  const SwingModel m = *SwingModel::Create(SwingParams{});
  const TorqueProgram p = TorqueProgram::Chapter();
  Reference ref(m, p);
  const SwingRunResult exact = *SimulateSwing(
      m, p, {.integrator = SwingIntegrator::kDp45, .accuracy = {.tolerance = 1e-13}}, {});
  const SwingRunResult check =
      *SimulateSwing(m, p, {.integrator = SwingIntegrator::kRk4, .accuracy = {.dt_s = 1e-5}}, {});
  std::printf("# reference impact t_s=%.15g speed_mps=%.15g ground_speed_mps=%.15g "
              "rk4_1e-5_dt_diff_s=%.3g rk4_1e-5_dv_diff_mps=%.3g\n",
              exact.impact->t_s, exact.impact->clubhead_speed_mps,
              exact.impact->clubhead_speed_ground_mps, check.impact->t_s - exact.impact->t_s,
              check.impact->clubhead_speed_mps - exact.impact->clubhead_speed_mps);
  std::printf("integrator,setting,steps,rhs_evaluations,t_impact_s,t_err_s,speed_err_mps,"
              "max_angle_err_rad,cpu_us_median,status\n");
  const std::vector<double> dts = {0.01, 0.005, 0.0025, 0.001, 0.0005, 0.0001};
  const std::vector<double> tols = {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12};
  for (SwingIntegrator integ : kAllSwingIntegrators) {
    const bool adaptive = integ == SwingIntegrator::kDp45;
    for (double setting : adaptive ? tols : dts) {
      SwingSolverOptions o{.integrator = integ};
      if (adaptive) o.accuracy.tolerance = setting; else o.accuracy.dt_s = setting;
      absl::StatusOr<SwingRunResult> r = SimulateSwing(m, p, o, {});
      if (!r.ok() || !r->impact) {
        std::printf("%s,%g,,,,,,,,\"%s\"\n", std::string(SwingIntegratorName(integ)).c_str(),
                    setting, r.ok() ? "no impact" : std::string(r.status().message()).c_str());
        continue;
      }
      double max_angle_err = 0;
      for (const SwingSample& s : r->samples) {
        const SwingVec e = ref.At(s.t_s);
        max_angle_err = std::max({max_angle_err, std::abs(s.alpha - e[0]), std::abs(s.beta - e[1])});
      }
      // CPU per swing: median over repeats, each repeat long enough to time reliably.
      std::vector<double> times;
      const int reps_per_sample = std::max(1, static_cast<int>(20000 / std::max(1, r->steps)));
      for (int k = 0; k < 15; ++k) {
        const double t0 = ThreadCpuSeconds();
        for (int j = 0; j < reps_per_sample; ++j) {
          absl::StatusOr<SwingRunResult> again = SimulateSwing(m, p, o, {});
          if (!again.ok()) std::abort();
        }
        times.push_back((ThreadCpuSeconds() - t0) / reps_per_sample);
      }
      std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
      std::printf("%s,%g,%d,%d,%.15g,%.3e,%.3e,%.3e,%.3f,ok\n",
                  std::string(SwingIntegratorName(integ)).c_str(), setting, r->steps,
                  r->rhs_evaluations, r->impact->t_s, r->impact->t_s - exact.impact->t_s,
                  r->impact->clubhead_speed_mps - exact.impact->clubhead_speed_mps, max_angle_err,
                  times[times.size() / 2] * 1e6);
    }
  }
}

}  // namespace
}  // namespace sportsim::swing

int main() { sportsim::swing::Study(); }
