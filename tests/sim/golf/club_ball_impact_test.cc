#include "sim/golf/club_ball_impact.h"

#include <cmath>
#include <limits>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/match.h"
#include "gtest/gtest.h"
#include "sim/golf/ball_flight.h"
#include "sim/golf/golf_ball.h"

namespace sportsim::golf {
namespace {

// The impact is a handful of closed-form expressions evaluated once: every
// comparison with a closed form allows round-off only.
constexpr double kClosedFormRelTol = 1e-12;
// Angles from atan2 of round-off-sized components (deg).
constexpr double kAngleRoundoffDeg = 1e-9;
// Spin from a tangential speed that is round-off (~1e-15 m/s) (rpm).
constexpr double kSpinRoundoffRpm = 1e-9;
// acos(1 - 1e-16) = 1.5e-8 rad = 8.5e-7 deg: acos amplifies round-off.
constexpr double kSpinLoftRoundoffDeg = 1e-5;

ClubSpec Driver() {
  absl::StatusOr<ClubSpec> club = ClubPreset("driver");
  EXPECT_TRUE(club.ok());
  return *club;
}

ImpactResult Hit(const ClubDelivery& delivery, const ClubSpec& club,
                 const ImpactOptions& options = {}) {
  absl::StatusOr<ImpactResult> r =
      SimulateImpact(delivery, club, BallSpec{}, options);
  EXPECT_TRUE(r.ok()) << r.status();
  return r.ok() ? *r : ImpactResult{};
}

TEST(ClubBallImpact, SquareCentredDriverSmashFactor) {
  // Face normal along the club velocity (zero spin loft): the collision is
  // purely normal and smash = (1 + e) M / (M + m) = 1.4882 for e = 0.83,
  // M = 0.200 kg, m = 0.04593 kg. Tour players measure 1.48-1.49.
  constexpr double kSmashLow = 1.48;
  constexpr double kSmashHigh = 1.49;
  const ClubSpec club = Driver();
  ASSERT_EQ(club.cor, 0.83);
  const ImpactResult r = Hit({.clubhead_speed_mps = 50,
                              .attack_angle_deg = club.loft_deg,
                              .dynamic_loft_deg = club.loft_deg},
                             club);
  const double m = BallSpec{}.mass_kg, big_m = club.head_mass_kg;
  const double expected = (1 + club.cor) * big_m / (big_m + m);
  EXPECT_NEAR(r.smash_factor, expected, kClosedFormRelTol * expected);
  EXPECT_GE(r.smash_factor, kSmashLow);
  EXPECT_LE(r.smash_factor, kSmashHigh);
  EXPECT_NEAR(r.launch.spin_rpm, 0.0, kSpinRoundoffRpm);  // no J_t
  EXPECT_NEAR(r.spin_loft_deg, 0.0, kSpinLoftRoundoffDeg);
}

TEST(ClubBallImpact, LoftedSquareHitMatchesClosedForm) {
  // Attack 0, path 0, face 0, loft L: v_n = (1+e) V cos L / (1 + m/M),
  // rolling v_t = V sin L / (1 + 1/k + m/M), spin = v_t / (k r), launch
  // angle = L - atan(v_t / v_n). At the driver's 10.5 deg the smash factor
  // is 1.464: the cos(loft) factor takes it below 1.48 (see the doc).
  const ClubSpec club = Driver();
  const BallSpec ball;
  constexpr double kSpeed = 50.0;
  for (double loft : {5.0, 10.5, 25.0, 45.0}) {
    const ImpactResult r =
        Hit({.clubhead_speed_mps = kSpeed, .dynamic_loft_deg = loft}, club);
    const double L = loft * kDegToRad;
    const double mass_ratio = ball.mass_kg / club.head_mass_kg;
    const double v_n = (1 + club.cor) * kSpeed * std::cos(L) / (1 + mass_ratio);
    const double v_t = kSpeed * std::sin(L) /
                       (1 + 1 / ball.inertia_factor + mass_ratio);
    const double spin_rpm =
        v_t / (ball.inertia_factor * ball.radius_m()) / kRpmToRadPerS;
    const double speed = std::hypot(v_n, v_t);
    EXPECT_NEAR(r.launch.ball_speed_mps, speed, kClosedFormRelTol * speed);
    EXPECT_NEAR(r.launch.launch_angle_deg,
                loft - std::atan2(v_t, v_n) / kDegToRad,
                kClosedFormRelTol * loft);
    EXPECT_NEAR(r.launch.spin_rpm, spin_rpm, kClosedFormRelTol * spin_rpm);
    EXPECT_NEAR(r.backspin_rpm, spin_rpm, kClosedFormRelTol * spin_rpm);
    EXPECT_NEAR(r.launch.spin_axis_deg, 0.0, kAngleRoundoffDeg);
    EXPECT_NEAR(r.launch.launch_direction_deg, 0.0, kAngleRoundoffDeg);
    EXPECT_FALSE(r.ball_sliding);
    if (loft == 10.5) {
      // The value quoted in the docs, to its last printed digit.
      constexpr double kQuotedDigitTol = 5e-5;
      EXPECT_NEAR(r.smash_factor, 1.4641, kQuotedDigitTol);
    }
  }
}

TEST(ClubBallImpact, MomentumConservedEnergyNeverCreated) {
  // m v + M V' = M V exactly (the impulse acts on both bodies). Kinetic
  // energy: e <= 1 plus friction can only dissipate. Round-off bounds.
  const BallSpec ball;
  for (double e : {0.5, 0.83, 1.0}) {
    ClubSpec club = Driver();
    club.cor = e;
    for (double loft = 0; loft <= 60; loft += 7.5) {
      for (double attack : {-5.0, 0.0, 4.0}) {
        for (double face : {-6.0, 0.0, 3.0}) {
          const ImpactResult r = Hit({.clubhead_speed_mps = 45,
                                      .attack_angle_deg = attack,
                                      .club_path_deg = 2.0,
                                      .dynamic_loft_deg = loft,
                                      .face_angle_deg = face},
                                     club);
          const Eigen::Vector3d before =
              club.head_mass_kg * r.club_velocity_before_mps;
          const Eigen::Vector3d after =
              club.head_mass_kg * r.club_velocity_after_mps +
              ball.mass_kg * r.ball_velocity_mps;
          EXPECT_LE((after - before).norm(), kClosedFormRelTol * before.norm());
          EXPECT_LE(r.kinetic_energy_after_j,
                    r.kinetic_energy_before_j * (1 + kClosedFormRelTol))
              << "e " << e << " loft " << loft;
          // The spin axis is perpendicular to the launch (no rifle spin).
          EXPECT_LE(std::abs(r.ball_spin_radps.dot(r.ball_velocity_mps)),
                    kClosedFormRelTol * r.ball_spin_radps.norm() *
                        r.ball_velocity_mps.norm());
        }
      }
    }
  }
}

TEST(ClubBallImpact, ElasticNormalImpactConservesEnergy) {
  ClubSpec club = Driver();
  club.cor = 1.0;
  const ImpactResult r =
      Hit({.clubhead_speed_mps = 50, .dynamic_loft_deg = 0.0}, club);
  EXPECT_NEAR(r.kinetic_energy_after_j, r.kinetic_energy_before_j,
              kClosedFormRelTol * r.kinetic_energy_before_j);
  // With loft the ball must be spun up by friction, which dissipates.
  const ImpactResult lofted =
      Hit({.clubhead_speed_mps = 50, .dynamic_loft_deg = 20.0}, club);
  // Rolling at 20 deg loft turns ~(2/7) of the tangential energy into
  // heat: a loss of order 1 %, far above round-off.
  constexpr double kMinFrictionLossRel = 1e-3;
  EXPECT_LT(lofted.kinetic_energy_after_j,
            lofted.kinetic_energy_before_j * (1 - kMinFrictionLossRel));
}

TEST(ClubBallImpact, MoreLoftMoreLaunchAndSpin) {
  const ClubSpec club = Driver();
  double last_launch = -90, last_spin = -1;
  for (double loft = 2; loft <= 60; loft += 2) {
    const ImpactResult r = Hit({.clubhead_speed_mps = 45,
                                .attack_angle_deg = -2,
                                .dynamic_loft_deg = loft},
                               club);
    EXPECT_GT(r.launch.launch_angle_deg, last_launch) << loft;
    EXPECT_GT(r.launch.spin_rpm, last_spin) << loft;
    last_launch = r.launch.launch_angle_deg;
    last_spin = r.launch.spin_rpm;
  }
}

TEST(ClubBallImpact, FaceAndPathSignConventions) {
  const ClubSpec club = Driver();
  // Open face, straight path: starts right, tilts right (+axis, +sidespin),
  // and in flight curves further right than its start line.
  const ImpactResult open =
      Hit({.clubhead_speed_mps = 50, .face_angle_deg = 3}, club);
  EXPECT_GT(open.launch.launch_direction_deg, 0.0);
  EXPECT_GT(open.launch.spin_axis_deg, 0.0);
  EXPECT_GT(open.sidespin_rpm, 0.0);
  absl::StatusOr<FlightResult> flight =
      SimulateFlight(BallSpec{}, open.launch, {}, {}, {});
  ASSERT_TRUE(flight.ok());
  EXPECT_GT(flight->lateral_m,
            flight->carry_downrange_m *
                std::tan(open.launch.launch_direction_deg * kDegToRad));

  // Closed face: the mirror image.
  const ImpactResult closed =
      Hit({.clubhead_speed_mps = 50, .face_angle_deg = -3}, club);
  EXPECT_NEAR(closed.launch.launch_direction_deg,
              -open.launch.launch_direction_deg, kAngleRoundoffDeg);
  EXPECT_NEAR(closed.launch.spin_axis_deg, -open.launch.spin_axis_deg,
              kAngleRoundoffDeg);

  // In-to-out path with the face square to the target (closed to the
  // path): starts right of target, between face and path, and draws
  // (axis < 0).
  const ImpactResult draw =
      Hit({.clubhead_speed_mps = 50, .club_path_deg = 4}, club);
  EXPECT_GT(draw.launch.launch_direction_deg, 0.0);
  EXPECT_LT(draw.launch.launch_direction_deg, 4.0);
  EXPECT_LT(draw.launch.spin_axis_deg, 0.0);
}

TEST(ClubBallImpact, FrictionLimitsTheTangentialImpulse) {
  const ClubSpec club = Driver();
  const ImpactResult frictionless =
      Hit({.clubhead_speed_mps = 40, .dynamic_loft_deg = 30}, club,
          {.friction_coefficient = 0.0});
  EXPECT_TRUE(frictionless.ball_sliding);
  EXPECT_EQ(frictionless.launch.spin_rpm, 0.0);
  const ImpactResult slipping =
      Hit({.clubhead_speed_mps = 40, .dynamic_loft_deg = 40}, club,
          {.friction_coefficient = 0.1});
  EXPECT_TRUE(slipping.ball_sliding);
  EXPECT_NEAR(slipping.tangential_impulse_ns,
              0.1 * slipping.normal_impulse_ns,
              kClosedFormRelTol * slipping.normal_impulse_ns);
  const ImpactResult rolling =
      Hit({.clubhead_speed_mps = 40, .dynamic_loft_deg = 80}, club,
          {.friction_coefficient = std::numeric_limits<double>::infinity()});
  EXPECT_FALSE(rolling.ball_sliding);
  // The default friction lets every preset roll at a square delivery.
  for (std::string_view name : kClubPresetNames) {
    absl::StatusOr<ClubSpec> c = ClubPreset(name);
    ASSERT_TRUE(c.ok());
    EXPECT_FALSE(Hit({.clubhead_speed_mps = 40}, *c).ball_sliding) << name;
  }
}

TEST(ClubPresets, AllNamesResolveInOrder) {
  ASSERT_EQ(kClubPresetNames.size(), 8u);
  double last_loft = 0, last_mass = 0;
  for (std::string_view name : kClubPresetNames) {
    absl::StatusOr<ClubSpec> c = ClubPreset(name);
    ASSERT_TRUE(c.ok()) << name;
    EXPECT_EQ(c->name, name);
    EXPECT_EQ(c->cor, 0.83);
    EXPECT_GT(c->loft_deg, last_loft);
    EXPECT_GT(c->head_mass_kg, last_mass);
    last_loft = c->loft_deg;
    last_mass = c->head_mass_kg;
    EXPECT_TRUE(ValidateClubSpec(*c).ok());
  }
}

void ExpectInvalid(const absl::Status& status, const std::string& field) {
  ASSERT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << field;
  EXPECT_TRUE(absl::StrContains(status.message(), field)) << status.message();
}

TEST(ClubBallImpactValidation, RejectsBadInputsNamingTheField) {
  const ClubDelivery ok{.clubhead_speed_mps = 45};
  ClubSpec club = Driver();
  for (double cor : {0.0, 1.1, -0.5, std::nan("")}) {
    club.cor = cor;
    ExpectInvalid(SimulateImpact(ok, club, BallSpec{}).status(), "cor");
  }
  club = Driver();
  ExpectInvalid(SimulateImpact({.clubhead_speed_mps = -1}, club, BallSpec{})
                    .status(),
                "clubhead_speed_mps");
  ExpectInvalid(
      SimulateImpact({.clubhead_speed_mps = std::nan("")}, club, BallSpec{})
          .status(),
      "clubhead_speed_mps");
  ExpectInvalid(SimulateImpact({.clubhead_speed_mps = 45,
                                .attack_angle_deg =
                                    std::numeric_limits<double>::infinity()},
                               club, BallSpec{})
                    .status(),
                "attack_angle_deg");
  ExpectInvalid(SimulateImpact({.clubhead_speed_mps = 45,
                                .face_angle_deg = 50},
                               club, BallSpec{})
                    .status(),
                "face_angle_deg");
  ExpectInvalid(SimulateImpact({.clubhead_speed_mps = 45,
                                .attack_angle_deg = -45,
                                .dynamic_loft_deg = 50},
                               club, BallSpec{})
                    .status(),
                "spin loft");
  ExpectInvalid(
      SimulateImpact(ok, club, BallSpec{}, {.friction_coefficient = -1})
          .status(),
      "friction_coefficient");
  ExpectInvalid(SimulateImpact(ok, club, {.inertia_factor = 0.7}).status(),
                "inertia_factor");
  // In range but too small for double precision: the impulse underflows to
  // zero (a denormal head) or the spin overflows (a denormal ball).
  club.head_mass_kg = std::numeric_limits<double>::denorm_min();
  ExpectInvalid(SimulateImpact(ok, club, BallSpec{}).status(), "head_mass_kg");
  club = Driver();
  ExpectInvalid(
      SimulateImpact(ok, club,
                     {.mass_kg = std::numeric_limits<double>::denorm_min()})
          .status(),
      "mass_kg");
  ExpectInvalid(ClubPreset("4-wood").status(), "club_preset");
  ExpectInvalid(ClubPreset("").status(), "club_preset");
}

}  // namespace
}  // namespace sportsim::golf
