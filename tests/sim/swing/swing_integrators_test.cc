// One suite over every integrator: energy, work-energy, convergence order, extremes, determinism.
#include <cmath>
#include <cstring>
#include <string>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/swing/swing_dynamics.h"
#include "sim/swing/swing_simulation.h"
#include "swing_test_util.h"

namespace sportsim::swing {
namespace {

using ::testing::AnyOf;
using ::testing::HasSubstr;
using testing::ChapterModel;
using testing::RunToImpact;
using testing::Solver;

// The converged chapter swing: an independent Python RK4 at h = 1.25e-5 s on equations derived
// from the Lagrangian with sympy (agreeing with a Newton-Euler derivation to 5e-15), good to
// ~1e-14 s and ~1e-12 m/s. ConvergedReference below re-derives it with our own dp45.
constexpr double kRefImpactS = 0.291391707952968;
constexpr double kRefSpeedMps = 42.5162746884201;

std::string Name(const ::testing::TestParamInfo<SwingIntegrator>& info) {
  return std::string(SwingIntegratorName(info.param));
}

// Nominal accuracy setting per integrator for the energy tests: the chapter's step for the
// fixed-step schemes, a modest tolerance for dp45.
double Nominal(SwingIntegrator i) { return i == SwingIntegrator::kDp45 ? 1e-8 : 0.0025; }

class SwingIntegratorTest : public ::testing::TestWithParam<SwingIntegrator> {};

// With no torques and no shoulder acceleration the pendulum falls freely and E is conserved; the
// drift over 0.5 s at the nominal setting ranks the schemes. Bounds are 2x the drift measured on
// this build (book 0.91 J, euler 0.37 J, semi-implicit 1.6 J, rk4 1.5e-5 J, dp45 5.4e-7 J;
// E0 = 18.24 J), so a scheme that gets worse fails.
TEST_P(SwingIntegratorTest, ConservesEnergyWithoutTorques) {
  const SwingModel m = ChapterModel(kSwingDisableShoulderAccel);
  const TorqueProgram free = TorqueProgram::Constant(0, 0);
  const SwingRunOptions run{.stop = SwingStop::kDuration, .duration_s = 0.5};
  absl::StatusOr<SwingRunResult> r = SimulateSwing(m, free, Solver(GetParam(), Nominal(GetParam())), run);
  ASSERT_TRUE(r.ok()) << r.status();
  double e0 = 0, drift = 0;
  for (size_t i = 0; i < r->samples.size(); ++i) {
    const SwingSample& s = r->samples[i];
    const double e = SwingEnergy(m, SwingVec(s.alpha, s.beta, s.alpha_dot, s.beta_dot));
    if (i == 0) e0 = e;
    drift = std::max(drift, std::abs(e - e0));
  }
  RecordProperty("energy_drift_J", std::to_string(drift));
  std::printf("%s: max |E - E0| = %.3g J over 0.5 s (E0 = %.6g J)\n",
              std::string(SwingIntegratorName(GetParam())).c_str(), drift, e0);
  double bound = 0;
  switch (GetParam()) {
    case SwingIntegrator::kBook: bound = 1.8; break;
    case SwingIntegrator::kEuler: bound = 0.8; break;
    case SwingIntegrator::kSemiImplicitEuler: bound = 3.2; break;
    case SwingIntegrator::kRk4: bound = 3e-5; break;
    case SwingIntegrator::kDp45: bound = 1.1e-6; break;
  }
  EXPECT_LT(drift, bound);
}

// Work-energy on the chapter swing: E(impact) - E(0) equals the torques' work, which for this
// piecewise-constant program is exactly 100 alpha_impact - 10 (beta(0.1) - beta0).
TEST_P(SwingIntegratorTest, WorkEnergyResidualShrinksWithTheStep) {
  const SwingModel m = ChapterModel();
  const TorqueProgram p = TorqueProgram::Chapter();
  auto residual = [&](double setting) {
    SwingSolverOptions solver = Solver(GetParam(), setting);
    absl::StatusOr<SwingRunResult> r = SimulateSwing(m, p, solver, SwingRunOptions{});
    EXPECT_TRUE(r.ok() && r->impact);
    double beta_at_switch = NAN;
    for (const SwingSample& s : r->samples) {
      if (s.t_s == 0.1) beta_at_switch = s.beta;  // the step lands on 0.1 exactly
    }
    EXPECT_FALSE(std::isnan(beta_at_switch)) << "no step ended at the switch time 0.1 s";
    const SwingSample& i = *r->impact;
    const double work = 100.0 * i.alpha - 10.0 * (beta_at_switch - m.params().beta0_rad);
    const SwingSample& s0 = r->samples.front();
    const double e0 = SwingEnergy(m, SwingVec(s0.alpha, s0.beta, s0.alpha_dot, s0.beta_dot));
    const double e1 = SwingEnergy(m, SwingVec(i.alpha, i.beta, i.alpha_dot, i.beta_dot));
    return std::abs(e1 - e0 - work);
  };
  const bool adaptive = GetParam() == SwingIntegrator::kDp45;
  const double coarse = residual(adaptive ? 1e-6 : 0.001);
  const double fine = residual(adaptive ? 1e-10 : 0.00025);
  std::printf("%s: work-energy residual %.3g J -> %.3g J\n",
              std::string(SwingIntegratorName(GetParam())).c_str(), coarse, fine);
  // 4x smaller step: first order gives 4x, RK4 256x; dp45 10^4 tighter tolerance.
  EXPECT_LT(fine, coarse / 3.0);
  EXPECT_LT(fine, adaptive || GetParam() == SwingIntegrator::kRk4 ? 1e-6 : 1.0);
}

TEST_P(SwingIntegratorTest, SameInputsGiveBitIdenticalSamples) {
  const SwingModel m = ChapterModel();
  const TorqueProgram p = TorqueProgram::Chapter();
  const SwingRunOptions run{.stop = SwingStop::kDuration, .duration_s = 0.5};
  const SwingSolverOptions solver = Solver(GetParam(), Nominal(GetParam()));
  absl::StatusOr<SwingRunResult> a = SimulateSwing(m, p, solver, run);
  absl::StatusOr<SwingRunResult> b = SimulateSwing(m, p, solver, run);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->samples.size(), b->samples.size());
  EXPECT_EQ(std::memcmp(a->samples.data(), b->samples.data(),
                        a->samples.size() * sizeof(SwingSample)),
            0);
  ASSERT_TRUE(a->impact && b->impact);
  EXPECT_EQ(std::memcmp(&*a->impact, &*b->impact, sizeof(SwingSample)), 0);
}

// Qa = 1000 N m and steps from 1e-5 to 0.05 s: either an answer within the scheme's order of
// accuracy or an InvalidArgument that names dt_s, never silent garbage. First-order schemes at
// 1e-3 s are the loosest that pass the turn bound (euler: 3.4 % in time, 17 % in speed); the
// higher-order ones must be within 0.1 % and 2 % (dp45 at tolerance 1e-2: 0.07 %, 1.5 %).
TEST_P(SwingIntegratorTest, ExtremeTorqueGivesAnAccurateAnswerOrAClearError) {
  constexpr double kRefT = 0.1021532090349, kRefV = 102.84088234723;  // Python RK4, h = 1.25e-5
  const SwingModel m = ChapterModel();
  absl::StatusOr<TorqueProgram> p = TorqueProgram::Create(
      {Interpolation::kPiecewiseConstant, {{0.0, 1000.0}}},
      {Interpolation::kPiecewiseConstant, {{0.0, -10.0}, {0.1, 0.0}}});
  ASSERT_TRUE(p.ok());
  const bool adaptive = GetParam() == SwingIntegrator::kDp45;
  const std::vector<double> settings =
      adaptive ? std::vector<double>{1e-12, 1e-8, 1e-4, 1e-2}
               : std::vector<double>{1e-5, 1e-4, 1e-3, 0.01, 0.05};
  for (double s : settings) {
    absl::StatusOr<SwingRunResult> r = SimulateSwing(m, *p, Solver(GetParam(), s), {});
    if (!r.ok()) {
      EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
      EXPECT_THAT(r.status().message(), AnyOf(HasSubstr("dt_s"), HasSubstr("tolerance")));
      std::printf("  setting %g: %s\n", s, std::string(r.status().message()).c_str());
      continue;
    }
    ASSERT_TRUE(r->impact) << "setting " << s;
    const double et = std::abs(r->impact->t_s - kRefT) / kRefT;
    const double ev = std::abs(r->impact->clubhead_speed_mps - kRefV) / kRefV;
    std::printf("  setting %g: impact %.9f s (rel err %.2g), %.6f m/s (rel err %.2g)\n", s,
                r->impact->t_s, et, r->impact->clubhead_speed_mps, ev);
    const bool high_order = adaptive || GetParam() == SwingIntegrator::kRk4;
    EXPECT_LT(et, high_order ? 1e-3 : 0.05) << "setting " << s;
    EXPECT_LT(ev, high_order ? 0.02 : 0.2) << "setting " << s;
  }
  // The finest setting is accurate to much better than that.
  absl::StatusOr<SwingRunResult> fine =
      SimulateSwing(m, *p, Solver(GetParam(), adaptive ? 1e-12 : 1e-5), {});
  ASSERT_TRUE(fine.ok() && fine->impact);
  const double fine_tol_s = GetParam() == SwingIntegrator::kRk4 || adaptive ? 1e-9 : 1e-4;
  EXPECT_NEAR(fine->impact->t_s, kRefT, fine_tol_s);
}

// The energy ranking the issue asks for: rk4 and dp45 drift orders of magnitude less than the
// chapter's scheme at the chapter's step.
TEST(SwingEnergyRankingTest, HigherOrderSchemesDriftFarLessThanTheBook) {
  const SwingModel m = ChapterModel(kSwingDisableShoulderAccel);
  const TorqueProgram free = TorqueProgram::Constant(0, 0);
  const SwingRunOptions run{.stop = SwingStop::kDuration, .duration_s = 0.5};
  auto drift = [&](SwingIntegrator i) {
    absl::StatusOr<SwingRunResult> r = SimulateSwing(m, free, Solver(i, Nominal(i)), run);
    EXPECT_TRUE(r.ok());
    const SwingSample& a = r->samples.front();
    const double e0 = SwingEnergy(m, SwingVec(a.alpha, a.beta, a.alpha_dot, a.beta_dot));
    double d = 0;
    for (const SwingSample& s : r->samples) {
      d = std::max(d, std::abs(SwingEnergy(m, SwingVec(s.alpha, s.beta, s.alpha_dot, s.beta_dot)) - e0));
    }
    return d;
  };
  const double book = drift(SwingIntegrator::kBook);
  EXPECT_LT(drift(SwingIntegrator::kRk4), 1e-3 * book);
  EXPECT_LT(drift(SwingIntegrator::kDp45), 1e-3 * book);
}

INSTANTIATE_TEST_SUITE_P(AllIntegrators, SwingIntegratorTest,
                         ::testing::ValuesIn(kAllSwingIntegrators), Name);

// Observed order of convergence of the impact time and speed on the chapter swing, halving dt
// in the asymptotic range: ~1 for book, euler and semi-implicit; ~4 for rk4. RK4 is still
// pre-asymptotic at the chapter's step (time-error ratios 11.5, 13.9, 15.1, 15.4 from 5 ms down
// to 0.625 ms; an independent Python RK4 shows the same), so its pair is 1.25 ms -> 0.625 ms.
struct OrderCase {
  SwingIntegrator integrator;
  double dt_s;          // coarse step; dt/2 is the fine one
  double expected;
};

class SwingConvergenceTest : public ::testing::TestWithParam<OrderCase> {};

TEST_P(SwingConvergenceTest, ObservedOrderMatchesTheScheme) {
  const OrderCase c = GetParam();
  const SwingModel m = ChapterModel();
  const TorqueProgram p = TorqueProgram::Chapter();
  const SwingRunResult coarse = RunToImpact(m, p, Solver(c.integrator, c.dt_s));
  const SwingRunResult fine = RunToImpact(m, p, Solver(c.integrator, c.dt_s / 2));
  ASSERT_TRUE(coarse.impact && fine.impact);
  const double order_t = std::log2(std::abs(coarse.impact->t_s - kRefImpactS) /
                                   std::abs(fine.impact->t_s - kRefImpactS));
  const double order_v = std::log2(std::abs(coarse.impact->clubhead_speed_mps - kRefSpeedMps) /
                                   std::abs(fine.impact->clubhead_speed_mps - kRefSpeedMps));
  std::printf("%s dt %g: order %.3f (time), %.3f (speed)\n",
              std::string(SwingIntegratorName(c.integrator)).c_str(), c.dt_s, order_t, order_v);
  // +-0.25 around the nominal order: the pre-asymptotic terms at these steps are below that.
  EXPECT_NEAR(order_t, c.expected, 0.25);
  EXPECT_NEAR(order_v, c.expected, 0.25);
}

INSTANTIATE_TEST_SUITE_P(
    Chapter, SwingConvergenceTest,
    ::testing::Values(OrderCase{SwingIntegrator::kBook, 0.0005, 1},
                      OrderCase{SwingIntegrator::kEuler, 0.0005, 1},
                      OrderCase{SwingIntegrator::kSemiImplicitEuler, 0.0005, 1},
                      OrderCase{SwingIntegrator::kRk4, 0.00125, 4}));

// Our own converged reference: dp45 at 1e-12 agrees with rk4 at 1e-5 s and with the independent
// Python value to 1e-10 s and 1e-8 m/s.
TEST(SwingReferenceTest, ConvergedReference) {
  const SwingModel m = ChapterModel();
  const TorqueProgram p = TorqueProgram::Chapter();
  const SwingRunResult dp = RunToImpact(m, p, Solver(SwingIntegrator::kDp45, 1e-12));
  const SwingRunResult rk = RunToImpact(m, p, Solver(SwingIntegrator::kRk4, 1e-5));
  ASSERT_TRUE(dp.impact && rk.impact);
  EXPECT_NEAR(dp.impact->t_s, kRefImpactS, 1e-10);
  EXPECT_NEAR(rk.impact->t_s, kRefImpactS, 1e-10);
  EXPECT_NEAR(dp.impact->clubhead_speed_mps, kRefSpeedMps, 1e-8);
  EXPECT_NEAR(rk.impact->clubhead_speed_mps, kRefSpeedMps, 1e-8);
}

// dp45 meets its tolerance: the impact error stays within a small multiple of the tolerance.
TEST(SwingReferenceTest, Dp45MeetsItsTolerance) {
  const SwingModel m = ChapterModel();
  const TorqueProgram p = TorqueProgram::Chapter();
  for (double tol : {1e-4, 1e-6, 1e-8, 1e-10}) {
    const SwingRunResult r = RunToImpact(m, p, Solver(SwingIntegrator::kDp45, tol));
    ASSERT_TRUE(r.impact);
    const double et = std::abs(r.impact->t_s - kRefImpactS);
    const double ev = std::abs(r.impact->clubhead_speed_mps - kRefSpeedMps) / kRefSpeedMps;
    std::printf("dp45 tol %g: %d steps, impact err %.2g s, speed rel err %.2g\n", tol, r.steps, et, ev);
    // Local error control bounds the global error by a modest factor over a swing this short.
    EXPECT_LT(et, 10 * tol);
    EXPECT_LT(ev, 10 * tol);
  }
}

// Torque switch times are honoured exactly by fixed steps that do not divide them.
TEST(SwingStepperTest, FixedStepsLandOnTheSwitchTime) {
  const SwingModel m = ChapterModel();
  const TorqueProgram p = TorqueProgram::Chapter();
  for (SwingIntegrator i : {SwingIntegrator::kBook, SwingIntegrator::kEuler,
                            SwingIntegrator::kSemiImplicitEuler, SwingIntegrator::kRk4,
                            SwingIntegrator::kDp45}) {
    absl::StatusOr<SwingStepper> s = SwingStepper::Create(&m, &p, Solver(i, i == SwingIntegrator::kDp45 ? 1e-6 : 0.003));
    ASSERT_TRUE(s.ok());
    bool landed = false;
    StepRecord rec;
    while (s->t() < 0.2) {
      ASSERT_TRUE(s->Step(1.0, &rec).ok());
      if (rec.t1 == 0.1) landed = true;
      // No step straddles the switch: the torque piece is constant over each step.
      EXPECT_FALSE(rec.t0 < 0.1 && rec.t1 > 0.1) << SwingIntegratorName(i);
    }
    EXPECT_TRUE(landed) << SwingIntegratorName(i);
  }
}

TEST(SwingStepperTest, AccuracyContractIsExplicit) {
  const SwingModel m = ChapterModel();
  const TorqueProgram p = TorqueProgram::Chapter();
  SwingSolverOptions rk4_with_tol{.integrator = SwingIntegrator::kRk4,
                                  .accuracy = {.tolerance = 1e-6}};
  EXPECT_THAT(SwingStepper::Create(&m, &p, rk4_with_tol).status().message(),
              HasSubstr("tolerance applies only to dp45"));
  SwingSolverOptions dp45_with_dt{.integrator = SwingIntegrator::kDp45,
                                  .accuracy = {.dt_s = 0.001}};
  EXPECT_THAT(SwingStepper::Create(&m, &p, dp45_with_dt).status().message(),
              HasSubstr("dt_s does not apply to dp45"));
  for (double bad : {0.0, -1.0, 1.0, static_cast<double>(NAN), static_cast<double>(INFINITY)}) {
    EXPECT_EQ(SwingStepper::Create(&m, &p, Solver(SwingIntegrator::kRk4, bad)).status().code(),
              absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(SwingStepper::Create(&m, &p, Solver(SwingIntegrator::kDp45, bad)).status().code(),
              absl::StatusCode::kInvalidArgument);
  }
}

TEST(SwingSimulationTest, ImpactIsTheDownwardCrossingOfPhiZero) {
  const SwingModel m = ChapterModel();
  const SwingRunResult r = RunToImpact(m, TorqueProgram::Chapter(), Solver(SwingIntegrator::kRk4, 0.0025));
  ASSERT_TRUE(r.impact);
  EXPECT_NEAR(r.impact->phi, 0.0, 1e-10);           // on the interpolant
  EXPECT_LT(r.impact->beta_dot - r.impact->alpha_dot, 0.0);  // phi decreasing
  for (size_t i = 0; i + 1 < r.samples.size(); ++i) EXPECT_GT(r.samples[i].phi, 0.0);
  EXPECT_EQ(r.samples.back().t_s, r.impact->t_s);  // the run ends at impact
}

TEST(SwingSimulationTest, DurationRunContinuesPastImpact) {
  const SwingModel m = ChapterModel();
  absl::StatusOr<SwingRunResult> r =
      SimulateSwing(m, TorqueProgram::Chapter(), Solver(SwingIntegrator::kBook, 0.0025),
                    {.stop = SwingStop::kDuration, .duration_s = 0.5});
  ASSERT_TRUE(r.ok());
  EXPECT_TRUE(r->impact);
  EXPECT_EQ(r->steps, 200);  // the chapter's 200 steps
  EXPECT_EQ(r->samples.size(), 201u);
  EXPECT_DOUBLE_EQ(r->end_t_s, 0.5);
}

TEST(SwingSimulationTest, NoImpactWithoutTorqueEndsAtTheCap) {
  // With no torques and no gravity nothing moves: no impact, and that is not an error.
  const SwingModel m = ChapterModel(kSwingDisableGravity | kSwingDisableShoulderAccel);
  absl::StatusOr<SwingRunResult> r =
      SimulateSwing(m, TorqueProgram::Constant(0, 0), Solver(SwingIntegrator::kRk4, 0.01),
                    {.duration_s = 0.3});
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->impact);
  EXPECT_NEAR(r->end_t_s, 0.3, 1e-12);
  EXPECT_EQ(r->samples.back().alpha, 0.0);  // at rest stays exactly at rest
}

TEST(SwingSimulationTest, TooLargeAStepIsAClearError) {
  const SwingModel m = ChapterModel();
  absl::StatusOr<SwingRunResult> r =
      SimulateSwing(m, TorqueProgram::Chapter(), Solver(SwingIntegrator::kRk4, 0.05), {});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(r.status().message(), HasSubstr("dt_s = 0.05 s is too large"));
}

}  // namespace
}  // namespace sportsim::swing

namespace sportsim::swing {
namespace {

using testing::ChapterModel;
using testing::Solver;

// Bounds that keep one request cheap (found in review: an unbounded dp45 run reached 7.9 GB).
TEST(SwingLimitsTest, AdaptiveRunsStopAtTheStepCap) {
  const SwingModel m = ChapterModel();
  SwingSolverOptions o{.integrator = SwingIntegrator::kDp45,
                       .accuracy = {.tolerance = 1e-8, .max_step_s = 1e-6}};
  absl::StatusOr<SwingRunResult> r = SimulateSwing(
      m, TorqueProgram::Chapter(), o,
      {.stop = SwingStop::kDuration, .duration_s = 10, .sample_interval_s = 0.01});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(r.status().message(), HasSubstr("without finishing"));  // checked every 1024 steps
}

TEST(SwingLimitsTest, TooManySamplesAreRefusedBeforeRunning) {
  const SwingModel m = ChapterModel();
  absl::StatusOr<SwingRunResult> r =
      SimulateSwing(m, TorqueProgram::Chapter(), Solver(SwingIntegrator::kRk4, 1e-6),
                    {.stop = SwingStop::kDuration, .duration_s = 10, .sample_stride = 1});
  ASSERT_FALSE(r.ok());
  EXPECT_THAT(r.status().message(), HasSubstr("more than 200000"));
  // dp45's step count is unknown up front: the run stops when it has kept the maximum.
  SwingSolverOptions fine{.integrator = SwingIntegrator::kDp45,
                          .accuracy = {.tolerance = 1e-8, .max_step_s = 1e-5}};
  absl::StatusOr<SwingRunResult> d = SimulateSwing(
      m, TorqueProgram::Chapter(), fine, {.stop = SwingStop::kDuration, .duration_s = 10});
  ASSERT_FALSE(d.ok());
  EXPECT_THAT(d.status().message(), HasSubstr("kept 200000 samples"));
}

TEST(SwingLimitsTest, CancellationStopsTheRun) {
  const SwingModel m = ChapterModel();
  int polls = 0;
  SwingRunOptions run{.stop = SwingStop::kDuration, .duration_s = 1, .sample_stride = 100};
  run.cancelled = [&] { return ++polls >= 2; };
  absl::StatusOr<SwingRunResult> r =
      SimulateSwing(m, TorqueProgram::Chapter(), Solver(SwingIntegrator::kRk4, 1e-5), run);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kCancelled);
  EXPECT_EQ(polls, 2);  // polled every 1024 steps, stopped at the second poll
}

TEST(SwingLimitsTest, TinyDurationIsRefusedNotUnderflowed) {
  const SwingModel m = ChapterModel();
  absl::StatusOr<SwingRunResult> r = SimulateSwing(
      m, TorqueProgram::Chapter(), Solver(SwingIntegrator::kDp45, 1e-8), {.duration_s = 1e-15});
  ASSERT_FALSE(r.ok());
  EXPECT_THAT(r.status().message(), HasSubstr("duration_s must be finite and in [1e-06, 10]"));
}

// Knots one rounding step apart across the two schedules make one breakpoint; dp45 no longer
// fails with a step-size underflow on them, and the answer is the same as with equal knots.
TEST(SwingLimitsTest, NearlyCoincidentKnotsMerge) {
  const SwingModel m = ChapterModel();
  const double t1 = std::nextafter(0.1, 1.0);
  const TorqueSchedule qa{Interpolation::kPiecewiseConstant, {{0.0, 100.0}, {0.1, 120.0}}};
  const TorqueProgram near =
      *TorqueProgram::Create(qa, {Interpolation::kPiecewiseConstant, {{0.0, -10.0}, {t1, 0.0}}});
  const TorqueProgram same =
      *TorqueProgram::Create(qa, {Interpolation::kPiecewiseConstant, {{0.0, -10.0}, {0.1, 0.0}}});
  EXPECT_EQ(near.breakpoints().size(), 1u);
  EXPECT_EQ(near.At(1, 0.2).q_beta, 0.0);  // the merged qbeta switch still happens
  for (SwingIntegrator i : {SwingIntegrator::kDp45, SwingIntegrator::kRk4}) {
    const double setting = i == SwingIntegrator::kDp45 ? 1e-10 : 1e-4;
    absl::StatusOr<SwingRunResult> a = SimulateSwing(m, near, Solver(i, setting), {});
    absl::StatusOr<SwingRunResult> b = SimulateSwing(m, same, Solver(i, setting), {});
    ASSERT_TRUE(a.ok()) << a.status();
    ASSERT_TRUE(b.ok() && a->impact && b->impact);
    EXPECT_EQ(a->impact->t_s, b->impact->t_s);
  }
  // A switch at 1e-300 s is a switch at 0.
  const TorqueProgram at_zero = *TorqueProgram::Create(
      {Interpolation::kPiecewiseConstant, {{0.0, 100.0}}},
      {Interpolation::kPiecewiseConstant, {{0.0, -10.0}, {1e-300, 0.0}}});
  EXPECT_TRUE(at_zero.breakpoints().empty());
  EXPECT_EQ(at_zero.At(0, 0.0).q_beta, 0.0);
}

}  // namespace
}  // namespace sportsim::swing
