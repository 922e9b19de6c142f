// The ode toolkit against closed forms: observed convergence ORDER of every Runge-Kutta scheme
// (one typed suite), the DP45 error estimator's order, the interpolants' orders, event location
// on a ballistic arc, and the accuracy contract's refusals.
#include <cmath>
#include <optional>

#include <Eigen/Dense>

#include "absl/strings/match.h"
#include "gtest/gtest.h"
#include "sim/core/effects.h"
#include "sim/core/ode/event.h"
#include "sim/core/ode/hermite.h"
#include "sim/core/ode/integrator.h"
#include "sim/core/ode/runge_kutta.h"

namespace sportsim::ode {
namespace {

using Vec2 = Eigen::Vector2d;

// A damped rotation y' = A y, A = [[-a, w], [-w, -a]]: y(t) = e^(-a t) R(-w t) y0.
constexpr double kA = 0.3, kW = 2.0;
Vec2 Rhs(double /*t*/, const Vec2& y) { return {-kA * y[0] + kW * y[1], -kW * y[0] - kA * y[1]}; }
Vec2 Exact(double t) {
  const Vec2 y0(1.0, 0.5);
  const double c = std::cos(kW * t), s = std::sin(kW * t), e = std::exp(-kA * t);
  return e * Vec2(c * y0[0] + s * y0[1], -s * y0[0] + c * y0[1]);
}

// Observed orders are log2 of successive error ratios; allowed slack (dimensionless).
constexpr double kOrderSlack = 0.25;

struct EulerScheme {
  static constexpr int kOrder = 1;
  static Vec2 Step(double t, double h, const Vec2& y) { return EulerStep(h, y, Rhs(t, y)); }
};
struct Rk4Scheme {
  static constexpr int kOrder = Rk4Tableau::kOrder;
  static Vec2 Step(double t, double h, const Vec2& y) { return Rk4Step(Rhs, t, h, y, Rhs(t, y)); }
};
struct Dp45Scheme {
  static constexpr int kOrder = Dp45Tableau::kOrder;
  static Vec2 Step(double t, double h, const Vec2& y) {
    Dp45Stages<Vec2> s;
    return Dp45Solution(Rhs, t, h, y, Rhs(t, y), &s, t + h);
  }
};

template <typename Scheme>
class RungeKuttaOrderTest : public ::testing::Test {};
using Schemes = ::testing::Types<EulerScheme, Rk4Scheme, Dp45Scheme>;
TYPED_TEST_SUITE(RungeKuttaOrderTest, Schemes);

// Global error at t = 2 with n fixed steps.
template <typename Scheme>
double GlobalError(int n) {
  const double t_end = 2.0, h = t_end / n;
  Vec2 y = Exact(0.0);
  for (int k = 0; k < n; ++k) y = Scheme::Step(k * h, h, y);
  return (y - Exact(t_end)).norm();
}

TYPED_TEST(RungeKuttaOrderTest, GlobalErrorConvergesAtTheSchemesOrder) {
  // Coarse enough that round-off stays far below the error (DP45 at n = 80: ~1e-11).
  const int base = TypeParam::kOrder == 1 ? 200 : 10;
  double previous = GlobalError<TypeParam>(base);
  for (int n = 2 * base; n <= 8 * base; n *= 2) {
    const double e = GlobalError<TypeParam>(n);
    const double order = std::log2(previous / e);
    EXPECT_NEAR(order, TypeParam::kOrder, kOrderSlack) << "n = " << n;
    previous = e;
  }
}

TEST(Dp45Test, EmbeddedEstimateIsFourthOrder) {
  // The estimate y5 - y4 is the local error of the fourth-order solution: O(h^5) per step.
  const Vec2 y0 = Exact(0.0), k1 = Rhs(0.0, y0);
  double previous = 0.0;
  for (double h = 0.2; h >= 0.2 / 8; h /= 2) {
    Dp45Stages<Vec2> s;
    const Vec2 y1 = Dp45Solution(Rhs, 0.0, h, y0, k1, &s, h);
    const double e = Dp45Error(h, k1, s, Rhs(h, y1)).norm();
    if (previous > 0.0) {
      EXPECT_NEAR(std::log2(previous / e), Dp45Tableau::kEmbeddedOrder + 1, kOrderSlack);
    }
    previous = e;
  }
}

TEST(Dp45Test, DenseOutputIsFourthOrderAndExactAtTheEnds) {
  // Interpolation error at mid-step against the closed form, over one step: O(h^5).
  const Vec2 y0 = Exact(0.0), k1 = Rhs(0.0, y0);
  double previous = 0.0;
  for (double h = 0.4; h >= 0.4 / 8; h /= 2) {
    Dp45Stages<Vec2> s;
    const Vec2 y1 = Dp45Solution(Rhs, 0.0, h, y0, k1, &s, h);
    const Dp45Dense<Vec2> d = MakeDp45Dense(h, y0, y1, k1, s, Rhs(h, y1));
    EXPECT_EQ(d(0.0), y0);
    EXPECT_EQ(d(1.0), y1);
    const double e = (d(0.5) - Exact(0.5 * h)).norm();
    if (previous > 0.0) EXPECT_NEAR(std::log2(previous / e), 5.0, 0.5);
    previous = e;
  }
}

TEST(Dp45Test, ErrorControlledRunMeetsTighterTolerancesWithMoreSteps) {
  int previous_steps = 0;
  double previous_error = 1.0;
  for (double tol : {1e-5, 1e-7, 1e-9}) {
    double t = 0.0;
    Vec2 y = Exact(0.0), k1 = Rhs(0.0, y);
    double h = Dp45InitialStep(Rhs, t, y, k1, tol, 0.5, 2.0);
    int steps = 0;
    bool rejected = false;
    while (t < 2.0) {
      h = std::min(h, 2.0 - t);
      Dp45Stages<Vec2> s;
      const Vec2 y1 = Dp45Solution(Rhs, t, h, y, k1, &s, t + h);
      const Vec2 k7 = Rhs(t + h, y1);
      const double e = Dp45ErrorNorm(Dp45Error(h, k1, s, k7), y, y1, tol, ErrorNorm::kRms);
      const double factor = Dp45StepFactor(e, rejected);
      if (e <= 1.0) {
        t += h;
        y = y1;
        k1 = k7;
        ++steps;
        rejected = false;
      } else {
        rejected = true;
      }
      h *= factor;
    }
    const double error = (y - Exact(2.0)).norm();
    EXPECT_LT(error, 100 * tol) << "tol " << tol;
    EXPECT_LT(error, previous_error);
    EXPECT_GT(steps, previous_steps);
    previous_error = error;
    previous_steps = steps;
  }
}

TEST(HermiteTest, CubicIsFourthOrderQuinticSixth) {
  // One step [0, h] of the closed form; error at s = 0.3 shrinks as h^4 (cubic), h^6 (quintic,
  // on the position of x'' = -x, x = cos t).
  double prev_cubic = 0.0, prev_quintic = 0.0;
  for (double h = 0.8; h >= 0.8 / 8; h /= 2) {
    const double s = 0.3;
    const Vec2 c = CubicHermite(Exact(0.0), Rhs(0, Exact(0.0)), Exact(h), Rhs(h, Exact(h)), h, s);
    const double e_cubic = (c - Exact(s * h)).norm();
    using V1 = Eigen::Matrix<double, 1, 1>;
    V1 p, v;
    QuinticHermite<V1>(V1(1.0), V1(0.0), V1(-1.0), V1(std::cos(h)), V1(-std::sin(h)),
                       V1(-std::cos(h)), h, s, &p, &v);
    const double e_quintic = std::abs(p[0] - std::cos(s * h));
    if (prev_cubic > 0.0) {
      EXPECT_NEAR(std::log2(prev_cubic / e_cubic), 4.0, kOrderSlack);
      EXPECT_NEAR(std::log2(prev_quintic / e_quintic), 6.0, kOrderSlack);
    }
    prev_cubic = e_cubic;
    prev_quintic = e_quintic;
  }
}

TEST(EventTest, BallisticLandingToRoundOff) {
  // z'' = -g from z0 = 2 m, vz0 = 15 m/s: lands at t* = (v0 + sqrt(v0^2 + 2 g z0)) / g. RK4 and
  // the cubic Hermite are exact on a quadratic, so located and refined times agree with t*.
  constexpr double kG = 9.81, kZ0 = 2.0, kV0 = 15.0;
  constexpr double kLandingTolS = 1e-12;  // event time tolerance (s)
  const auto f = [](double, const Vec2& y) { return Vec2(y[1], -kG); };
  const double t_star = (kV0 + std::sqrt(kV0 * kV0 + 2 * kG * kZ0)) / kG;
  const double h = 0.25;
  double t = 0.0;
  Vec2 y(kZ0, kV0);
  while (true) {
    const Vec2 k1 = f(t, y);
    const Vec2 y1 = Rk4Step(f, t, h, y, k1);
    if (y1[0] <= 0.0) {
      const ScalarCubicHermite z{y[0], h * k1[0], y1[0], h * f(t + h, y1)[0]};
      const double theta = LocateOnInterpolant([&](double q) { return z.Value(q); }, 0.0, 1.0,
                                               y[0], y1[0], kLandingTolS / h);
      EXPECT_NEAR(t + theta * h, t_star, 10 * kLandingTolS);
      Vec2 y_land;
      const double h_land = RefineOnStep(
          theta * h, h, 6, [&](double hh) { y_land = Rk4Step(f, t, hh, y, k1); },
          [&]() -> std::optional<EventResidual> {
            if (!(y_land[1] < 0.0)) return std::nullopt;
            return EventResidual{y_land[0], y_land[1]};
          });
      EXPECT_NEAR(t + h_land, t_star, 10 * kLandingTolS);
      EXPECT_NEAR(y_land[0], 0.0, 1e-10);
      break;
    }
    y = y1;
    t += h;
  }
}

TEST(AccuracyTest, FixedStepOrToleranceNeverBoth) {
  const AccuracyLimits limits{.default_dt_s = 0.01,
                              .dt_s = {.lo = 1e-6, .hi = 0.1},
                              .default_tolerance = std::nullopt,
                              .tolerance = {.lo = 0.0, .lo_open = true, .hi = 1e-2},
                              .default_max_step_s = 0.05,
                              .max_step_s = {.lo = 1e-6, .hi = 1.0}};
  EXPECT_TRUE(ValidateAccuracy(Integrator::kRk4, {}, limits).ok());
  EXPECT_TRUE(ValidateAccuracy(Integrator::kRk4, {.dt_s = 0.001}, limits).ok());
  const absl::Status tol_on_rk4 = ValidateAccuracy(Integrator::kRk4, {.tolerance = 1e-6}, limits);
  EXPECT_EQ(tol_on_rk4.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_TRUE(absl::StrContains(tol_on_rk4.message(), "tolerance applies only to dp45"));
  const absl::Status dt_on_dp45 =
      ValidateAccuracy(Integrator::kDp45, {.dt_s = 0.001, .tolerance = 1e-6}, limits);
  EXPECT_TRUE(absl::StrContains(dt_on_dp45.message(), "dt_s does not apply to dp45"));
  EXPECT_TRUE(absl::StrContains(ValidateAccuracy(Integrator::kDp45, {}, limits).message(),
                                "tolerance is required"));
  EXPECT_TRUE(absl::StrContains(
      ValidateAccuracy(Integrator::kEuler, {.max_step_s = 0.1}, limits).message(), "max_step_s"));
  EXPECT_FALSE(ValidateAccuracy(Integrator::kRk4, {.dt_s = 0.5}, limits).ok());
  const StepSettings dp = ResolveAccuracy(Integrator::kDp45, {.tolerance = 1e-6}, limits);
  EXPECT_EQ(dp.tolerance, 1e-6);
  EXPECT_EQ(dp.max_step_s, 0.05);
  EXPECT_EQ(ResolveAccuracy(Integrator::kRk4, {}, limits).dt_s, 0.01);
  for (Integrator i : kAllIntegrators) EXPECT_EQ(IntegratorFromName(IntegratorName(i)), i);
}

TEST(EffectsTest, ZeroIsTheDefaultAndEnableBitsSwitchOn) {
  constexpr uint32_t kEnable = 1u << 0, kDisable = 1u << 1;
  EXPECT_FALSE(EffectOn(0, kEnable, kEnable));  // off by default
  EXPECT_TRUE(EffectOn(0, kDisable, kEnable));  // on by default
  EXPECT_EQ(WithEffect(0, kEnable, true, kEnable), kEnable);
  EXPECT_EQ(WithEffect(0, kDisable, false, kEnable), kDisable);
  EXPECT_EQ(WithEffect(kEnable | kDisable, kEnable, false, kEnable), kDisable);
  EXPECT_FALSE(ValidateEffectBits("effects", 1u << 5, 3u).ok());
}

// A cubic in time is reproduced exactly by the Hermite interpolant of its ends, and so is its
// rate; the position agrees with CubicHermite.
TEST(HermiteTest, CubicHermiteRateReproducesACubicAndItsRate) {
  auto x = [](double t) { return Eigen::Vector2d(1 + 2 * t - 3 * t * t + 0.5 * t * t * t, -t * t * t); };
  auto v = [](double t) { return Eigen::Vector2d(2 - 6 * t + 1.5 * t * t, -3 * t * t); };
  const double t0 = 0.4, h = 0.7;
  for (double s : {0.0, 0.25, 0.6, 1.0}) {
    Eigen::Vector2d p, rate;
    CubicHermiteRate(x(t0), v(t0), x(t0 + h), v(t0 + h), h, s, &p, &rate);
    EXPECT_LT((p - x(t0 + s * h)).norm(), 1e-12) << s;
    EXPECT_LT((rate - v(t0 + s * h)).norm(), 1e-12) << s;
    EXPECT_LT((p - CubicHermite(x(t0), v(t0), x(t0 + h), v(t0 + h), h, s)).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace sportsim::ode
