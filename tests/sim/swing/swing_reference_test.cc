// The swing against an independent reference: a Python implementation whose equations of motion
// were derived from the Lagrangian with sympy (not copied from ours), cross-checked by a
// Newton-Euler derivation, integrated with RK4 at h = 1.25e-5 s with switch times on step
// boundaries, impact by bisection on a partial RK4 step. Its values are good to ~1e-14 s in time
// and ~1e-12 in rates and speeds (~1e-11 for the 1000 N m case). Seven swings, not only the
// chapter's: other torques, a piecewise-linear ramp, other top positions, effects switched off.
#include <cmath>
#include <string>

#include "gtest/gtest.h"
#include "sim/swing/swing_simulation.h"
#include "swing_test_util.h"

namespace sportsim::swing {
namespace {

using testing::Solver;

struct Variant {
  std::string name;
  SwingParams params;
  TorqueSchedule qa, qb;
  // Reference impact (s, rad, rad/s, m/s).
  double t, alpha, beta, alpha_dot, beta_dot, speed, ground_speed;
};

TorqueSchedule Const(double q) { return {Interpolation::kPiecewiseConstant, {{0.0, q}}}; }
TorqueSchedule Until(double q, double t) {
  return {Interpolation::kPiecewiseConstant, {{0.0, q}, {t, 0.0}}};
}

std::vector<Variant> Variants() {
  const SwingParams d;
  SwingParams no_a = d;
  no_a.shoulder_accel_mps2 = 0;
  SwingParams no_ga = no_a;
  no_ga.gravity_mps2 = 0;
  SwingParams top = d;
  top.gamma_rad = DegToRad(120);
  top.beta0_rad = DegToRad(90);
  const TorqueSchedule ramp{Interpolation::kPiecewiseLinear, {{0.0, 0.0}, {0.2, 200.0}}};
  return {
      {"chapter", d, Const(100), Until(-10, 0.1), 0.2913917079530, 2.949866446989,
       0.593671956797, 18.11047372955, -11.65544153699, 42.51627468842, 42.79872568550},
      {"no_shoulder_accel", no_a, Const(100), Until(-10, 0.1), 0.2919944265538, 2.939967415730,
       0.583772925538, 18.27250551799, -10.86247426789, 41.96835602646, 41.96835602646},
      {"no_gravity", no_ga, Const(100), Until(-10, 0.1), 0.3159314607224, 2.843163694673,
       0.486969204480, 15.53467229296, -17.17317355387, 44.71822357234, 44.71822357234},
      {"qalpha_1000", d, Const(1000), Until(-10, 0.1), 0.1021532090349, 3.204732340716,
       0.848537850524, 62.11426002721, -4.46692320525, 102.84088234723, 102.93696354071},
      {"no_wrist_torque", d, Const(100), Const(0), 0.2237103403504, 1.723700181167,
       -0.632494309025, 14.71819082740, -7.21216866182, 31.94225072616, 32.15835911069},
      {"other_top", top, Const(150), Until(-20, 0.05), 0.2123082791178, 2.143499611185,
       0.049104508792, 21.51708994022, 8.54312448764, 27.60364521017, 27.81164921053},
      {"linear_ramp", d, ramp, Until(-10, 0.1), 0.2855788332198, 2.580975365262, 0.224780875070,
       24.28417937260, 3.01781505114, 38.21804906706, 38.49684311499},
  };
}

class SwingIndependentReferenceTest
    : public ::testing::TestWithParam<std::tuple<Variant, SwingIntegrator>> {};

TEST_P(SwingIndependentReferenceTest, ImpactMatches) {
  const auto& [v, integrator] = GetParam();
  const SwingModel m = *SwingModel::Create(v.params);
  const TorqueProgram p = *TorqueProgram::Create(v.qa, v.qb);
  // rk4 at 1e-4 s (error ~1e-13 s on the chapter swing) and dp45 at 1e-11.
  const double setting = integrator == SwingIntegrator::kDp45 ? 1e-11 : 1e-4;
  absl::StatusOr<SwingRunResult> r = SimulateSwing(m, p, Solver(integrator, setting), {});
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->impact);
  const SwingSample& i = *r->impact;
  // The reference is quoted to 13 significant digits; our error at these settings is ~1e-12
  // in time and angle. Rates and speed err by ~1e-10 on the chapter's swings but by up to
  // 3.6e-8 (rk4) and 1.8e-9 (dp45) on the qalpha_1000 swing (the strongest torque)
  // (measured: a 1e-9 tolerance fails there); 1e-7 covers it with 3x margin.
  constexpr double kTimeTolS = 1e-10, kAngleTolRad = 1e-9, kRateTolRps = 1e-7, kSpeedTolMps = 1e-7;
  EXPECT_NEAR(i.t_s, v.t, kTimeTolS);
  EXPECT_NEAR(i.alpha, v.alpha, kAngleTolRad);
  EXPECT_NEAR(i.beta, v.beta, kAngleTolRad);
  EXPECT_NEAR(i.alpha_dot, v.alpha_dot, kRateTolRps);
  EXPECT_NEAR(i.beta_dot, v.beta_dot, kRateTolRps);
  EXPECT_NEAR(i.clubhead_speed_mps, v.speed, kSpeedTolMps);
  EXPECT_NEAR(i.clubhead_speed_ground_mps, v.ground_speed, kSpeedTolMps);
}

INSTANTIATE_TEST_SUITE_P(
    SevenSwings, SwingIndependentReferenceTest,
    ::testing::Combine(::testing::ValuesIn(Variants()),
                       ::testing::Values(SwingIntegrator::kRk4, SwingIntegrator::kDp45)),
    [](const auto& param_info) {
      return std::get<0>(param_info.param).name + "_" +
             std::string(SwingIntegratorName(std::get<1>(param_info.param)));
    });

}  // namespace
}  // namespace sportsim::swing
