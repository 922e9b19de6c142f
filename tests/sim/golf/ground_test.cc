// The ground phase (sim/golf/ground.h) against closed forms, its stated conventions, published
// figures and invariants over random runs. References are in each test's comment.
#include "sim/golf/ground.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/golf/ball_flight.h"
#include "sim/golf/surface.h"

namespace sportsim::golf {
namespace {

using ::testing::HasSubstr;
using Eigen::Vector3d;

constexpr double kG = 9.80665;
constexpr double kDeg = std::numbers::pi / 180.0;

GroundOptions NoHole() {
  GroundOptions o;
  o.hole = false;
  return o;
}

GroundResult MustRun(const Surface& surface, const GroundPlane& plane, const GroundStart& start,
                     const GroundOptions& options = NoHole(), const Hole& hole = {}) {
  absl::StatusOr<GroundResult> r = SimulateGround(BallSpec{}, surface, plane, hole, start, options);
  EXPECT_TRUE(r.ok()) << r.status();
  return r.ok() ? *r : GroundResult{};
}

int Count(const GroundResult& r, GroundEventKind kind) {
  int n = 0;
  for (const GroundEvent& e : r.events) n += e.kind == kind;
  return n;
}

const GroundEvent* First(const GroundResult& r, GroundEventKind kind) {
  for (const GroundEvent& e : r.events) {
    if (e.kind == kind) return &e;
  }
  return nullptr;
}

// The USGA Stimpmeter: a ball released at 1.83 m/s rolls S feet on a flat green of reading S.
// The green's rolling resistance is derived from S (surface.h), so this checks the conversion,
// the rolling law and the located rest together.
TEST(GroundTest, AStimpmeterRollStopsAtTheReading) {
  for (const double stimp : {7.0, 10.0, 12.5, 14.0}) {
    const Surface green = *GreenOfStimp(stimp);
    const GroundResult r = MustRun(green, {}, RollingStart(0, 0, kStimpmeterSpeedMps, 30));
    EXPECT_NEAR(r.rest_m.norm(), stimp * kFootToM, 1e-9) << stimp;
    EXPECT_NEAR(green.stimp_ft(), stimp, 1e-12);
    EXPECT_EQ(r.events.back().kind, GroundEventKind::kRest);
    // Constant deceleration v0^2 / (2 S): the time is 2 S / v0.
    EXPECT_NEAR(r.t_rest_s, 2.0 * stimp * kFootToM / kStimpmeterSpeedMps, 1e-9);
  }
}

// A spinless struck ball skids under friction mu g and reaches pure roll at 5/7 of its speed
// after t = 2 v0 / (7 mu g), having gone 12 v0^2 / (49 mu g) (solid sphere, any mu).
TEST(GroundTest, ASpinlessPuttRollsAtFiveSeventhsAfterTheClosedFormSkid) {
  for (const double mu : {0.15, 0.4, 0.9}) {
    Surface green = *GreenOfStimp(11);
    green.sliding_friction = mu;
    const double v0 = 2.5;
    const GroundResult r = MustRun(green, {}, PuttStart(1, -2, v0, 0));
    const GroundEvent* roll = First(r, GroundEventKind::kRoll);
    ASSERT_NE(roll, nullptr);
    EXPECT_NEAR(roll->t_s, 2.0 * v0 / (7.0 * mu * kG), 1e-12);
    EXPECT_NEAR(roll->velocity_mps.norm(), 5.0 / 7.0 * v0, 1e-12);
    EXPECT_NEAR(roll->position_m.x() - 1.0, 12.0 * v0 * v0 / (49.0 * mu * kG), 1e-12);
    // Then it rolls (5/7 v0)^2 / (2 (5/7) rho g) further.
    const double v1 = 5.0 / 7.0 * v0;
    const double roll_out = v1 * v1 / (2.0 * 5.0 / 7.0 * green.rolling_resistance * kG);
    EXPECT_NEAR(r.rest_m.x() - roll->position_m.x(), roll_out, 1e-9);
    EXPECT_NEAR(r.rest_m.y(), -2.0, 1e-12);
    // The rolling ball's spin is v / R about the axis n x v.
    EXPECT_NEAR(roll->spin_radps, v1 / BallSpec{}.radius_m(), 1e-9);
  }
}

// The slope convention: a rolling ball accelerates at (5/7) g sin(alpha) down the fall line and
// the resistance takes (5/7) rho g cos(alpha) against its motion; so rolled straight up the
// fall line it stops after v0^2 / (2 a_up), a_up = (5/7) g (sin + rho cos), and rolled straight
// down after v0^2 / (2 a_down), a_down = (5/7) g (rho cos - sin).
TEST(GroundTest, OnAUniformSlopeTheRollingBallFollowsTheStatedConvention) {
  const Surface green = *GreenOfStimp(10);
  const double rho = green.rolling_resistance;
  for (const double pct : {1.0, 3.0, 6.0}) {
    const GroundPlane plane{.slope_pct = pct, .slope_toward_deg = 120};
    const double alpha = std::atan(pct / 100.0);
    const double v0 = 1.5;
    const double a_up = 5.0 / 7.0 * kG * (std::sin(alpha) + rho * std::cos(alpha));
    const double a_down = 5.0 / 7.0 * kG * (rho * std::cos(alpha) - std::sin(alpha));
    const GroundResult up = MustRun(green, plane, RollingStart(0, 0, v0, 120 + 180));
    EXPECT_NEAR(up.rest_m.norm(), v0 * v0 / (2 * a_up), 1e-9) << pct;
    EXPECT_GT(up.rest_m.z(), 0.0);  // uphill of the start
    const GroundResult down = MustRun(green, plane, RollingStart(0, 0, v0, 120));
    EXPECT_NEAR(down.rest_m.norm(), v0 * v0 / (2 * a_down), 1e-9) << pct;
    EXPECT_LT(down.rest_m.z(), 0.0);
    // At rest on the plane, at its height.
    EXPECT_NEAR(down.rest_m.z(), plane.HeightAt(down.rest_m.x(), down.rest_m.y()), 1e-12);
  }
}

// A plane steeper than the surface holds is refused, naming the slope; one just inside holds
// the ball that stops on it.
TEST(GroundTest, ASlopeTheBallCannotRestOnIsRefused) {
  const Surface green = *GreenOfStimp(12);
  const double limit_pct = 100.0 * green.rolling_resistance;
  const absl::StatusOr<GroundResult> steep =
      SimulateGround(BallSpec{}, green, {.slope_pct = limit_pct * 1.01}, {},
                     RollingStart(0, 0, 1, 0), NoHole());
  ASSERT_FALSE(steep.ok());
  EXPECT_EQ(steep.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(steep.status().message(), HasSubstr("slope_pct"));
  const GroundResult held = MustRun(green, {.slope_pct = limit_pct * 0.99},
                                    RollingStart(0, 0, 1, 180));  // uphill
  EXPECT_EQ(held.events.back().kind, GroundEventKind::kRest);
}

// Across a slope a putt breaks down the fall line, and the fixed-step answer converges: at a
// 1 ms step it rests within a micrometre of the answer at a step 100 times smaller, at the
// default (5 ms) within a tenth of a millimetre.
TEST(GroundTest, APuttAcrossASlopeBreaksDownhillAndConverges) {
  const Surface green = *GreenOfStimp(11);
  const GroundPlane plane{.slope_pct = 3, .slope_toward_deg = -90};  // falls toward -y
  GroundOptions fine = NoHole();
  fine.dt_s = 1e-5;
  GroundOptions one_ms = NoHole();
  one_ms.dt_s = 1e-3;
  const GroundResult coarse = MustRun(green, plane, PuttStart(0, 0, 2.2, 0));
  const GroundResult ms = MustRun(green, plane, PuttStart(0, 0, 2.2, 0), one_ms);
  const GroundResult converged = MustRun(green, plane, PuttStart(0, 0, 2.2, 0), fine);
  EXPECT_LT(coarse.rest_m.y(), -0.1) << "no break";
  EXPECT_GT(coarse.rest_m.x(), 1.0);
  EXPECT_LT((ms.rest_m - converged.rest_m).norm(), 1e-6)
      << ms.rest_m.transpose() << " vs " << converged.rest_m.transpose();
  EXPECT_LT((coarse.rest_m - converged.rest_m).norm(), 1e-4)
      << coarse.rest_m.transpose() << " vs " << converged.rest_m.transpose();
}

// The default step against a step 50 times smaller over random putts toward the hole on random
// greens and slopes (seeded): the same holed or not, rests within a tenth of a millimetre
// (measured: 17 um at worst over 2,000 such putts against a 10 us reference).
TEST(GroundTest, TheDefaultStepRestsWithinATenthOfAMillimetreOfTheConvergedRest) {
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0.0;
  for (int i = 0; i < 100; ++i) {
    const Surface green = *GreenOfStimp(8 + 6 * u(rng));
    const GroundPlane plane{.slope_pct = 100 * green.rolling_resistance * 0.8 * u(rng),
                            .slope_toward_deg = 360 * u(rng)};
    const double x = -(1 + 12 * u(rng)), y = -2 + 4 * u(rng);
    const double heading = std::atan2(-y, -x) / kDeg - 8 + 16 * u(rng);
    const GroundStart putt = PuttStart(x, y, 0.5 + 4 * u(rng), heading);
    GroundOptions o;
    o.sample_interval_s = 0;
    GroundOptions fine = o;
    fine.dt_s = 1e-4;
    const GroundResult a = MustRun(green, plane, putt, o, Hole{});
    const GroundResult b = MustRun(green, plane, putt, fine, Hole{});
    ASSERT_EQ(a.holed, b.holed) << i;
    worst = std::max(worst, (a.rest_m - b.rest_m).norm());
  }
  std::printf("default step vs 0.1 ms over 100 putts: worst rest difference %.2e m\n", worst);
  EXPECT_LT(worst, 1e-4);
}

// Mechanical energy (translation, rotation, height) never rises along a rolling ball's path.
TEST(GroundTest, EnergyNeverRises) {
  const Surface green = *GreenOfStimp(9);
  const GroundPlane plane{.slope_pct = 4, .slope_toward_deg = 30};
  GroundOptions o = NoHole();
  o.sample_interval_s = 0.005;
  const GroundResult r = MustRun(green, plane, RollingStart(0, 0, 2.0, 170), o);
  ASSERT_GT(r.samples.size(), 50u);
  const double k = BallSpec{}.inertia_factor;
  double last = 1e300;
  for (const GroundSample& s : r.samples) {
    // Per unit mass: (1 + k) v^2 / 2 for a rolling sphere, plus g z.
    const double e = 0.5 * (1.0 + k) * s.speed_mps * s.speed_mps + kG * s.position_m.z();
    EXPECT_LE(e, last + 1e-9) << "at t = " << s.t_s;
    last = e;
  }
}

// Penner's restitution curve and critical-angle law at their stated points (surface.h).
TEST(GroundTest, PennersLawsAtTheirStatedPoints) {
  EXPECT_DOUBLE_EQ(PennerRestitution(0), 0.510);
  EXPECT_NEAR(PennerRestitution(10), 0.510 - 0.375 + 0.0903, 1e-12);
  EXPECT_NEAR(PennerRestitution(20), 0.1212, 1e-12);
  EXPECT_DOUBLE_EQ(PennerRestitution(25), 0.120);
  EXPECT_NEAR(PennerCriticalAngle(18.6, 44.4 * kDeg), 15.4 * kDeg, 1e-12);
  EXPECT_NEAR(PennerCriticalAngle(9.3, 44.4 * kDeg), 7.7 * kDeg, 1e-12);
  EXPECT_NEAR(PennerCriticalAngle(18.6, 22.2 * kDeg), 7.7 * kDeg, 1e-12);
}

// One bounce against the bare law: with no critical angle and a flat green, a spinless ball
// dropped straight down rebounds at e(v) v; a ball landing at 45 deg with enough friction
// leaves rolling at (5/7) v_t - (2/7) R w (Penner's rolling exit).
TEST(GroundTest, OneBounceMatchesTheRigidBodyLaw) {
  Surface s = *SurfaceByName("green");
  s.critical_angle_scale = 0;
  s.bounce_friction = 2;
  const double r = BallSpec{}.radius_m();
  GroundOptions o = NoHole();
  o.settle_speed_mps = 1.0;  // one impact, then the plane
  const double vt = 6.0, vn = 3.0, w = 40.0;  // backspin 40 rad/s about +y... see below
  GroundStart start{.kind = GroundStartKind::kLanding,
                    .velocity_mps = Vector3d(vt, 0, -vn),
                    // Backspin for a ball moving +x: the bottom moves forward, w along -y.
                    .spin_radps = Vector3d(0, -w, 0)};
  const GroundResult res = MustRun(s, {}, start, o);
  const GroundEvent* landing = First(res, GroundEventKind::kLanding);
  ASSERT_NE(landing, nullptr);
  EXPECT_NEAR(landing->velocity_mps.z(), PennerRestitution(vn) * vn, 1e-12);
  EXPECT_NEAR(landing->velocity_mps.x(), 5.0 / 7.0 * vt - 2.0 / 7.0 * r * w, 1e-12);
}

// Spin-back: a wedge landing steeply with heavy backspin on a green comes back toward where
// it landed; the same landing with little spin runs on. (Penner's tangential exit speed is
// negative when (2/7) R w exceeds (5/7) v sin(theta_in - theta_c).)
TEST(GroundTest, EnoughBackspinChecksAndSpinsBackOnAGreen) {
  const Surface green = *GreenOfStimp(10);
  const double speed = 18.0, descent = 50 * kDeg;
  auto landing = [&](double rpm) {
    return GroundStart{.kind = GroundStartKind::kLanding,
                       .velocity_mps = speed * Vector3d(std::cos(descent), 0, -std::sin(descent)),
                       .spin_radps = Vector3d(0, -rpm * kRpmToRadPerS, 0)};
  };
  const GroundResult heavy = MustRun(green, {}, landing(9000));
  const GroundResult light = MustRun(green, {}, landing(1500));
  std::printf("wedge landing 18 m/s at 50 deg: 9000 rpm rests at x = %.2f m, 1500 rpm at %.2f m\n",
              heavy.rest_m.x(), light.rest_m.x());
  EXPECT_LT(heavy.rest_m.x(), 0.0) << "no spin-back";
  EXPECT_GT(light.rest_m.x(), 1.0);
  // The spin switch: without the spin the heavy landing runs on like the light one.
  GroundOptions spinless = NoHole();
  spinless.effects = kGroundDisableSpin;
  EXPECT_GT(MustRun(green, {}, landing(9000), spinless).rest_m.x(), light.rest_m.x());
}

// The hole: capture speeds from Penner's fall-one-radius condition, 1.31 m/s on the centre line
// (Holmes 1991's figure); a ball arriving slower drops, a faster one lips out and runs on.
TEST(GroundTest, TheHoleCapturesBelowItsSpeedAndLipsOutAbove) {
  const double rh = 0.054, rb = BallSpec{}.radius_m();
  EXPECT_NEAR(HoleCaptureSpeed(rh, rb, 0, kG), 1.31, 0.01);
  EXPECT_EQ(HoleCaptureSpeed(rh, rb, rh, kG), 0.0);
  const Surface green = *GreenOfStimp(10);
  const double a = 5.0 / 7.0 * green.rolling_resistance * kG;
  GroundOptions o;  // with the hole at the origin
  for (const double offset : {0.0, 0.03}) {
    const double vc = HoleCaptureSpeed(rh, rb, offset, kG);
    const double entry = 3.0 - std::sqrt(rh * rh - offset * offset);  // from x = -3
    for (const double factor : {0.9, 1.1}) {
      const double v_rim = factor * vc;
      const double v0 = std::sqrt(v_rim * v_rim + 2 * a * entry);
      const GroundResult r = MustRun(green, {}, RollingStart(-3, offset, v0, 0), o);
      if (factor < 1) {
        EXPECT_TRUE(r.holed) << offset;
        EXPECT_EQ(r.events.back().kind, GroundEventKind::kHoled);
        EXPECT_NEAR(r.events.back().velocity_mps.norm(), 0.0, 1e-12);
        EXPECT_NEAR(r.events.back().t_s, (v0 - v_rim) / a, 1e-9);
      } else {
        EXPECT_FALSE(r.holed) << offset;
        EXPECT_EQ(Count(r, GroundEventKind::kLipOut), 1);
        EXPECT_GT(r.rest_m.x(), rh);
      }
    }
  }
  // A ball that stops with its centre over the hole drops in (it has lost its support).
  const double offset = 0.053;  // v_c = 0 here: no crossing speed is slow enough
  const double stop_x = -std::sqrt(rh * rh - offset * offset) + 0.001;
  const double v0 = std::sqrt(2 * a * (stop_x + 2.0));
  const GroundResult hang = MustRun(green, {}, RollingStart(-2.0, offset, v0, 0), o);
  EXPECT_TRUE(hang.holed);
}

// The flagstick in: a ball straight at it, too fast for the open hole (1.8 m/s at the rim,
// above the 1.31 m/s capture speed), is stopped by the stick and drops (at 0.1 restitution it
// leaves the stick at 0.18 m/s and has fallen 2.4 mm when it is back at the rim, more than
// v^2 / 2g = 1.7 mm: it cannot climb out); a very fast one (4 m/s) bounces out; one whose line misses
// the stick runs on as with the stick out; a glancing hit at speed is knocked off its line
// and bounces out. A ball that stops against the stick is over the hole: holed.
TEST(GroundTest, TheFlagstickStopsFastBallsItMeets) {
  const Surface green = *GreenOfStimp(10);
  const double a = 5.0 / 7.0 * green.rolling_resistance * kG;
  const double rh = 0.054, rb = BallSpec{}.radius_m();
  Hole in;
  in.flagstick_diameter_m = kFlagstickDiameter;
  auto roll = [&](double offset, double v_rim, const Hole& hole) {
    const double entry = 3.0 - std::sqrt(rh * rh - offset * offset);
    const double v0 = std::sqrt(v_rim * v_rim + 2 * a * entry);
    return MustRun(green, {}, RollingStart(-3, offset, v0, 0), GroundOptions{}, hole);
  };
  EXPECT_FALSE(roll(0.0, 1.8, Hole{}).holed);
  EXPECT_TRUE(roll(0.0, 1.8, in).holed);
  const GroundResult fast = roll(0.0, 4.0, in);
  EXPECT_FALSE(fast.holed);
  EXPECT_EQ(Count(fast, GroundEventKind::kLipOut), 1);
  const GroundEvent* off = First(fast, GroundEventKind::kLipOut);
  EXPECT_LT(off->velocity_mps.x(), 0.0) << "bounced back off the stick";
  EXPECT_NEAR(off->velocity_mps.norm(), 0.4, 1e-9);  // 0.1 of 4 m/s, head-on
  // Outside r_s + R of the centre the stick is not met: the same run to the bit.
  const double miss = 0.5 * kFlagstickDiameter + rb + 0.002;
  const GroundResult open = roll(miss, 2.0, Hole{});
  const GroundResult stick = roll(miss, 2.0, in);
  EXPECT_FALSE(stick.holed);
  EXPECT_EQ(open.rest_m, stick.rest_m);
  // A glancing hit at 4 m/s: deflected, out, off its line.
  const GroundResult glance = roll(0.5 * kFlagstickDiameter + rb - 0.002, 4.0, in);
  EXPECT_FALSE(glance.holed);
  EXPECT_EQ(Count(glance, GroundEventKind::kLipOut), 1);
  EXPECT_GT(std::abs(glance.rest_m.y() - (0.5 * kFlagstickDiameter + rb - 0.002)), 0.05);
  // A slow ball that reaches the stick drops (it was over the hole).
  EXPECT_TRUE(roll(0.0, 0.2, in).holed);
  // The stick's size is checked.
  Hole fat = in;
  fat.flagstick_diameter_m = 0.08;
  EXPECT_FALSE(SimulateGround(BallSpec{}, green, {}, fat, RollingStart(-3, 0, 1, 0),
                              GroundOptions{})
                   .ok());
}

// A ball landing with the whole ball inside the rim is holed at once.
TEST(GroundTest, ALandingInsideTheRimIsHoled) {
  const Surface green = *GreenOfStimp(10);
  GroundStart start{.kind = GroundStartKind::kLanding,
                    .position_m = Vector3d(0.01, 0, 0),
                    .velocity_mps = Vector3d(3, 0, -8)};
  const GroundResult r = MustRun(green, {}, start, GroundOptions{});
  EXPECT_TRUE(r.holed);
  EXPECT_EQ(r.bounces, 0);
}

// Bad inputs are refused naming the field.
TEST(GroundTest, BadInputsNameTheField) {
  const Surface green = *GreenOfStimp(10);
  auto message = [&](const GroundPlane& p, const GroundStart& s, const GroundOptions& o) {
    absl::StatusOr<GroundResult> r = SimulateGround(BallSpec{}, green, p, Hole{}, s, o);
    EXPECT_FALSE(r.ok());
    return std::string(r.status().message());
  };
  GroundOptions o;
  EXPECT_THAT(message({.slope_pct = NAN}, PuttStart(1, 1, 1, 0), o), HasSubstr("slope_pct"));
  EXPECT_THAT(message({}, PuttStart(0.01, 0, 1, 0), o), HasSubstr("starts in the hole"));
  EXPECT_THAT(message({}, PuttStart(1, 1, INFINITY, 0), o), HasSubstr("velocity"));
  GroundStart up{.kind = GroundStartKind::kLanding, .position_m = Vector3d(1, 1, 0),
                 .velocity_mps = Vector3d(1, 0, 1)};
  EXPECT_THAT(message({}, up, o), HasSubstr("move into the plane"));
  o.dt_s = 0;
  EXPECT_THAT(message({}, PuttStart(1, 1, 1, 0), o), HasSubstr("dt_s"));
  o = GroundOptions{};
  o.sample_interval_s = 1e-300;  // a fuzzer's find: unbounded samples
  EXPECT_THAT(message({}, PuttStart(1, 1, 1, 0), o), HasSubstr("sample_interval_s"));
  o = GroundOptions{};
  o.effects = 1u << 7;
  EXPECT_THAT(message({}, PuttStart(1, 1, 1, 0), o), HasSubstr("effects"));
  EXPECT_FALSE(SurfaceByName("ice").ok());
  EXPECT_FALSE(GreenOfStimp(30).ok());
  Surface bad = green;
  bad.rolling_resistance = -1;
  EXPECT_THAT(std::string(ValidateSurface(bad).message()), HasSubstr("rolling_resistance"));
}

// Whole shots: the flight's landing, then the ground on a flat fairway. Published orders of
// magnitude (tour averages): a tour drive (the flight validation's driver launch, TrackMan tour
// averages: 167 mph, 10.9 deg, 2686 rpm) rolls about 15-25 yd on a normal fairway; a pitching
// wedge (102 mph, 24.2 deg, 9304 rpm) a few yards at most; a firm fairway rolls several times
// farther than a soft one.
TEST(GroundTest, WholeShotsRollOutAsPublished) {
  auto total_minus_carry = [](const LaunchConditions& launch, const std::string& fairway) {
    FlightOptions fo;
    fo.sample_interval_s = 0;
    absl::StatusOr<FlightResult> flight =
        SimulateFlight(BallSpec{}, launch, Atmosphere{}, Wind{}, fo);
    EXPECT_TRUE(flight.ok()) << flight.status();
    if (!flight.ok()) return 0.0;
    const GroundResult g =
        MustRun(*SurfaceByName(fairway), {}, LandingFromFlight(*flight), NoHole());
    const double total = std::hypot(g.rest_m.x(), g.rest_m.y());
    return total - flight->carry_m;
  };
  const LaunchConditions driver{.ball_speed_mps = 167 * kMphToMps, .launch_angle_deg = 10.9,
                                .spin_rpm = 2686};
  const LaunchConditions wedge{.ball_speed_mps = 102 * kMphToMps, .launch_angle_deg = 24.2,
                               .spin_rpm = 9304};
  const double drive = total_minus_carry(driver, "fairway") / kYardToM;
  const double firm = total_minus_carry(driver, "fairway_firm") / kYardToM;
  const double soft = total_minus_carry(driver, "fairway_soft") / kYardToM;
  const double pw = total_minus_carry(wedge, "fairway") / kYardToM;
  std::printf("roll-out (total - carry): driver %.1f yd (firm %.1f, soft %.1f), PW %.1f yd\n",
              drive, firm, soft, pw);
  EXPECT_GE(drive, 15.0);
  EXPECT_LE(drive, 25.0);
  EXPECT_LE(std::abs(pw), 4.0);
  EXPECT_GT(firm, 2.0 * soft);
}

// No NaN, no ball below the plane, always a rest or the hole, events in time order: random
// landings, putts and rolling balls on random planes and surfaces (seeded).
TEST(GroundTest, RandomRunsAlwaysEndOnThePlane) {
  std::mt19937_64 rng(20261205);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto surfaces = BuiltinSurfaces();
  for (int i = 0; i < 10000; ++i) {
    const Surface& surface = surfaces[i % surfaces.size()];
    // Up to 80 % of the steepest slope the surface holds a ball on (a ball landing fast on a
    // green tilted just short of that limit rolls for minutes: physics, not a hang).
    const GroundPlane plane{.slope_pct = std::min(100.0 * surface.rolling_resistance, 20.0) *
                                         u(rng) * 0.8,
                            .slope_toward_deg = 360 * u(rng)};
    GroundStart start;
    const double x = -20 + 40 * u(rng), y = -20 + 40 * u(rng);
    if (std::hypot(x, y) < 0.06) continue;
    const double heading = 360 * u(rng) * kDeg;
    switch (i % 3) {
      case 0: {
        const double speed = 1 + 40 * u(rng), descent = (5 + 80 * u(rng)) * kDeg;
        start = GroundStart{
            .kind = GroundStartKind::kLanding, .position_m = Vector3d(x, y, 0),
            .velocity_mps = speed * Vector3d(std::cos(descent) * std::cos(heading),
                                             std::cos(descent) * std::sin(heading),
                                             -std::sin(descent)),
            .spin_radps = Vector3d(-1000 + 2000 * u(rng), -1000 + 2000 * u(rng),
                                   -300 + 600 * u(rng))};
        if (start.velocity_mps.dot(plane.Normal()) >= 0) continue;
        break;
      }
      case 1: start = PuttStart(x, y, 8 * u(rng), heading / kDeg); break;
      default: start = RollingStart(x, y, 8 * u(rng), heading / kDeg); break;
    }
    GroundOptions o;
    o.sample_interval_s = 0.05;
    o.max_time_s = 3600;
    const absl::StatusOr<GroundResult> r =
        SimulateGround(BallSpec{}, surface, plane, Hole{}, start, o);
    ASSERT_TRUE(r.ok()) << i << " " << surface.name << ": " << r.status();
    ASSERT_TRUE(r->rest_m.allFinite()) << i;
    ASSERT_FALSE(r->events.empty());
    const GroundEventKind last = r->events.back().kind;
    EXPECT_TRUE(last == GroundEventKind::kRest || last == GroundEventKind::kHoled) << i;
    EXPECT_NEAR(r->rest_m.z(), plane.HeightAt(r->rest_m.x(), r->rest_m.y()), 1e-9) << i;
    for (size_t j = 1; j < r->events.size(); ++j) {
      ASSERT_LE(r->events[j - 1].t_s, r->events[j].t_s) << i;
    }
    for (const GroundSample& s : r->samples) {
      ASSERT_TRUE(s.position_m.allFinite() && std::isfinite(s.speed_mps)) << i;
      // The contact point never below the plane.
      ASSERT_GE(s.position_m.z() - plane.HeightAt(s.position_m.x(), s.position_m.y()), -1e-9)
          << i;
    }
  }
}

// The same inputs give bit-identical results.
TEST(GroundTest, Deterministic) {
  const Surface green = *GreenOfStimp(10);
  const GroundPlane plane{.slope_pct = 2, .slope_toward_deg = 77};
  const GroundResult a = MustRun(green, plane, PuttStart(-4, 1, 2.3, 10), GroundOptions{});
  const GroundResult b = MustRun(green, plane, PuttStart(-4, 1, 2.3, 10), GroundOptions{});
  EXPECT_EQ(a.rest_m, b.rest_m);
  EXPECT_EQ(a.t_rest_s, b.t_rest_s);
  EXPECT_EQ(a.events.size(), b.events.size());
}

}  // namespace
}  // namespace sportsim::golf

namespace sportsim::golf {
namespace {

// The two integrators against a converged reference (RK4 at 20 us) on putts across slopes:
// RK4's rest error falls with the step, dp45's with its tolerance, and the default (RK4 at
// 5 ms) rests within 1 mm; dp45 refuses a missing tolerance and RK4 a tolerance.
TEST(GroundIntegratorsTest, BothConvergeToTheReferenceOnASlope) {
  const Surface green = *GreenOfStimp(11);
  const GroundPlane plane{.slope_pct = 4, .slope_toward_deg = -70};
  using ode::Integrator;
  auto rest = [&](Integrator integrator, double value, double x, double heading) {
    GroundOptions o;
    o.sample_interval_s = 0;
    o.hole = false;
    o.integrator = integrator;
    if (integrator == Integrator::kDp45) {
      o.tolerance_m = value;
      o.dt_s = 0.05;
    } else {
      o.dt_s = value;
    }
    auto r = SimulateGround(BallSpec{}, green, plane, Hole{}, PuttStart(x, 0, 3.0, heading), o);
    EXPECT_TRUE(r.ok()) << r.status();
    return r.ok() ? r->rest_m : Eigen::Vector3d::Zero();
  };
  double rk4_err[2] = {0, 0}, dp_err[2] = {0, 0};
  for (int i = 0; i < 8; ++i) {
    const double x = -4 + i, heading = 10 + 20 * i;
    const Eigen::Vector3d ref = rest(Integrator::kRk4, 2e-5, x, heading);
    const double e5 = (rest(Integrator::kRk4, 5e-3, x, heading) - ref).norm();
    EXPECT_LT(e5, 1e-3);
    rk4_err[0] = std::max(rk4_err[0], (rest(Integrator::kRk4, 0.01, x, heading) - ref).norm());
    rk4_err[1] = std::max(rk4_err[1], (rest(Integrator::kRk4, 0.0025, x, heading) - ref).norm());
    dp_err[0] = std::max(dp_err[0], (rest(Integrator::kDp45, 1e-5, x, heading) - ref).norm());
    dp_err[1] = std::max(dp_err[1], (rest(Integrator::kDp45, 1e-9, x, heading) - ref).norm());
  }
  EXPECT_LT(rk4_err[1], rk4_err[0]);
  EXPECT_LT(dp_err[1], dp_err[0]);
  EXPECT_LT(dp_err[1], 1e-6);
  GroundOptions bad;
  bad.integrator = Integrator::kDp45;
  EXPECT_THAT(std::string(ValidateGround(BallSpec{}, green, plane, Hole{}, PuttStart(1, 0, 1, 0), bad)
                              .message()),
              ::testing::HasSubstr("tolerance_m"));
  bad.integrator = Integrator::kRk4;
  bad.tolerance_m = 1e-6;
  EXPECT_THAT(std::string(ValidateGround(BallSpec{}, green, plane, Hole{}, PuttStart(1, 0, 1, 0), bad)
                              .message()),
              ::testing::HasSubstr("tolerance_m"));
  bad.integrator = Integrator::kEuler;
  bad.tolerance_m = 0;
  EXPECT_THAT(std::string(ValidateGround(BallSpec{}, green, plane, Hole{}, PuttStart(1, 0, 1, 0), bad)
                              .message()),
              ::testing::HasSubstr("integrator"));
}

}  // namespace
}  // namespace sportsim::golf
