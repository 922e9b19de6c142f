// Shared helpers for the swing tests.
#ifndef SPORTSIM_TESTS_SIM_SWING_SWING_TEST_UTIL_H_
#define SPORTSIM_TESTS_SIM_SWING_SWING_TEST_UTIL_H_

#include "gtest/gtest.h"
#include "sim/swing/swing_model.h"
#include "sim/swing/swing_simulation.h"
#include "sim/swing/swing_stepper.h"

namespace sportsim::swing::testing {

inline SwingModel ChapterModel(uint32_t effects = 0) {
  return *SwingModel::Create(SwingParams{}, effects);
}

/// Solver options for an integrator: a fixed step, or dp45 at a tolerance.
inline SwingSolverOptions Solver(SwingIntegrator i, double dt_or_tol) {
  SwingSolverOptions o{.integrator = i};
  if (i == SwingIntegrator::kDp45) {
    o.accuracy.tolerance = dt_or_tol;
  } else {
    o.accuracy.dt_s = dt_or_tol;
  }
  return o;
}

/// The chapter swing to impact; fails the test on error.
inline SwingRunResult RunToImpact(const SwingModel& model, const TorqueProgram& program,
                                  const SwingSolverOptions& solver) {
  absl::StatusOr<SwingRunResult> r = SimulateSwing(model, program, solver, SwingRunOptions{});
  EXPECT_TRUE(r.ok()) << r.status();
  EXPECT_TRUE(r.ok() && r->impact.has_value());
  return r.ok() ? *r : SwingRunResult{};
}

}  // namespace sportsim::swing::testing

#endif  // SPORTSIM_TESTS_SIM_SWING_SWING_TEST_UTIL_H_
