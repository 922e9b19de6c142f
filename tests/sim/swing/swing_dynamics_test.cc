#include "sim/swing/swing_dynamics.h"

#include <cmath>
#include <random>

#include "gtest/gtest.h"
#include "sim/swing/swing_model.h"

namespace sportsim::swing {
namespace {

// Random states and torques over a wide range (rad, rad/s, N m): the identities below are exact,
// so they must hold everywhere, not only along the chapter's swing.
struct Sample {
  SwingVec y;
  Torques q;
  double t;
};

std::vector<Sample> RandomSamples(int n, uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> angle(-7.0, 7.0), rate(-60.0, 60.0), torque(-300, 300),
      time(0.0, 0.5);
  std::vector<Sample> out;
  for (int i = 0; i < n; ++i) {
    out.push_back({SwingVec(angle(rng), angle(rng), rate(rng), rate(rng)),
                   Torques{torque(rng), torque(rng)}, time(rng)});
  }
  return out;
}

// Central difference along the flow: d/dt g(y(t)) ~ (g(y + e f) - g(y - e f)) / (2 e).
// Truncation ~ e^2 |g'''|, rounding ~ 1e-16 |g| / e: e = 1e-6 s balances them near 1e-10.
constexpr double kFlowStepS = 1e-6;

TEST(SwingDynamicsTest, JorgensenSpeedIsTheDerivativeOfTheClubheadPosition) {
  const SwingModel m = *SwingModel::Create(SwingParams{});
  for (const Sample& s : RandomSamples(200, 7)) {
    const SwingVec f = SwingDerivative(m, s.y, s.q);
    const SwingVec yp = s.y + kFlowStepS * f, ym = s.y - kFlowStepS * f;
    const Eigen::Vector2d v_fd =
        (Clubhead(m, yp, 0).position_m - Clubhead(m, ym, 0).position_m) / (2 * kFlowStepS);
    const ClubheadKinematics k = Clubhead(m, s.y, 0);
    // Speeds here reach ~150 m/s: 1e-6 relative is far above the difference's own error.
    const double tol = 1e-6 * std::max(1.0, v_fd.norm());
    EXPECT_NEAR(k.speed_mps, v_fd.norm(), tol);
    EXPECT_NEAR((k.velocity_mps - v_fd).norm(), 0.0, tol);
  }
}

TEST(SwingDynamicsTest, GroundSpeedAddsTheShoulderVelocity) {
  const SwingModel m = *SwingModel::Create(SwingParams{});
  const SwingVec y(1.0, 0.5, 10.0, -5.0);
  const ClubheadKinematics k = Clubhead(m, y, 0.25);
  EXPECT_DOUBLE_EQ(k.ground_velocity_mps.x(), k.velocity_mps.x() - 0.98 * 0.25);
  EXPECT_DOUBLE_EQ(k.ground_velocity_mps.y(), k.velocity_mps.y());
}

// Work-energy theorem: dE/dt = Qa alpha_dot + Qb beta_dot for every state, with gravity and the
// shoulder's acceleration on (E includes the pseudo-force potential), and with them off.
TEST(SwingDynamicsTest, EnergyRateEqualsTorquePower) {
  for (uint32_t disabled : {0u, uint32_t{kSwingDisableGravity | kSwingDisableShoulderAccel}, uint32_t{kSwingDisableShoulderAccel}}) {
    const SwingModel m = *SwingModel::Create(SwingParams{}, disabled);
    for (const Sample& s : RandomSamples(200, 11 + disabled)) {
      const SwingVec f = SwingDerivative(m, s.y, s.q);
      const double de_dt = (SwingEnergy(m, s.y + kFlowStepS * f) -
                            SwingEnergy(m, s.y - kFlowStepS * f)) /
                           (2 * kFlowStepS);
      const double power = s.q.q_alpha * s.y[2] + s.q.q_beta * s.y[3];
      // Energies reach ~1e3 J here: rounding in the difference is ~1e-16 * 1e3 / 1e-6 = 1e-7 W.
      EXPECT_NEAR(de_dt, power, 1e-5 * std::max(1.0, std::abs(power))) << "disabled " << disabled;
    }
  }
}

TEST(SwingDynamicsTest, SwitchedOffWristTorqueIsIgnored) {
  const SwingModel off = *SwingModel::Create(SwingParams{}, kSwingDisableWristTorque);
  const SwingVec y(0.3, 2.0, 4.0, -3.0);
  EXPECT_EQ(SwingAccelerations(off, y, {100, -50}), SwingAccelerations(off, y, {100, 0}));
  const SwingModel on = *SwingModel::Create(SwingParams{});
  EXPECT_NE(SwingAccelerations(on, y, {100, -50}), SwingAccelerations(on, y, {100, 0}));
}

}  // namespace
}  // namespace sportsim::swing
