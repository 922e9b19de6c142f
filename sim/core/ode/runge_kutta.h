// Explicit Runge-Kutta schemes, templated on the state type, so a step costs what the
// hand-written formulas cost (no virtual calls, no heap).
//
// State types: fixed-size Eigen column vectors (Eigen::Matrix<double, N, 1>, the swing's
// 4-vector, a ball's 7- or 9-vector). A derivative is any callable `Vec f(double t, const Vec& y)`;
// a model that needs more (counters, side outputs) captures them in a lambda.
//
// Schemes (Butcher tableaux below, c | A over b):
//
//  Explicit Euler, order 1 (Euler 1768; Hairer, Norsett & Wanner, Solving ODEs I, sec. II.1):
//      0 |
//      --+--
//        | 1
//
//  Classical Runge-Kutta, order 4 (Kutta 1901; Hairer, Norsett & Wanner, table II.1.2):
//      0   |
//      1/2 | 1/2
//      1/2 | 0    1/2
//      1   | 0    0    1
//      ----+-------------------
//          | 1/6  1/3  1/3  1/6
//    Rk4Step evaluates it in the factored form y + (h/6)(k1 + 2 k2 + 2 k3 + k4).
//
//  Dormand-Prince 5(4), "DOPRI5" (J. R. Dormand and P. J. Prince, "A family of embedded
//  Runge-Kutta formulae", J. Comput. Appl. Math. 6, 19-26 (1980); Hairer, Norsett & Wanner,
//  table II.5.2): seven stages, the fifth-order weights advance the solution (local
//  extrapolation), the fifth- minus fourth-order weights give the error estimate, and the last
//  stage is the derivative at the new point (first same as last, FSAL: the next step's k1).
//  Coefficients in kDp45 below. Dense output: the fourth-order continuous extension of Hairer,
//  Norsett & Wanner (sec. II.6, code DOPRI5, after L. F. Shampine, "Interpolation for
//  Runge-Kutta methods", SIAM J. Numer. Anal. 22, 1014 (1985)), evaluated in the nested form
//  y0 + s (r1 + (1-s) (r2 + s (r3 + (1-s) r4))).
//
//  Error control (Dp45ErrorNorm, Dp45StepFactor): scaled error e with sc_i = tol (1 +
//  max(|y0_i|, |y1_i|)), the root-mean-square norm of Hairer, Norsett & Wanner (II.4.11) or the
//  stricter max norm; accept when e <= 1; next step h * clamp(0.9 e^(-1/5), 0.2, 5), with no
//  growth right after a rejection (Hairer, Norsett & Wanner, sec. II.4). Starting step:
//  Dp45InitialStep (Hairer, Norsett & Wanner, sec. II.4, "starting step size").
#ifndef SPORTSIM_SIM_CORE_ODE_RUNGE_KUTTA_H_
#define SPORTSIM_SIM_CORE_ODE_RUNGE_KUTTA_H_

#include <algorithm>
#include <array>
#include <cmath>

namespace sportsim::ode {

/// Explicit Euler: order 1, one evaluation (k1 given).
template <typename Vec>
Vec EulerStep(double h, const Vec& y, const Vec& k1) {
  return y + h * k1;
}

/// The four stage derivatives of one classical RK4 step (k1 = f(t, y) given).
template <typename Vec>
struct Rk4Stages {
  Vec k1, k2, k3, k4;
  /// y + (h/6)(k1 + 2 k2 + 2 k3 + k4): the step's result.
  Vec Combine(double h, const Vec& y) const {
    return y + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  }
};

/// The stages of a classical RK4 step: for a partitioned state whose other part follows from
/// the stages (a ball's position integrated with the stage velocities, r' = v, needs only
/// (v, w) as the ODE's state: the same arithmetic as RK4 on (r; v, w), with 6 components a
/// stage instead of 9).
template <typename Vec, typename F>
Rk4Stages<Vec> Rk4StagesOf(F&& f, double t, double h, const Vec& y, const Vec& k1) {
  Rk4Stages<Vec> k{.k1 = k1};
  k.k2 = f(t + 0.5 * h, y + (0.5 * h) * k1);
  k.k3 = f(t + 0.5 * h, y + (0.5 * h) * k.k2);
  k.k4 = f(t + h, y + h * k.k3);
  return k;
}

/// Classical RK4: order 4, three new evaluations (k1 = f(t, y) given).
template <typename Vec, typename F>
Vec Rk4Step(F&& f, double t, double h, const Vec& y, const Vec& k1) {
  return Rk4StagesOf(f, t, h, y, k1).Combine(h, y);
}

/// The RK4 tableau (for tests and documentation; Rk4Step uses the factored form).
struct Rk4Tableau {
  static constexpr int kStages = 4;
  static constexpr int kOrder = 4;
  static constexpr std::array<double, 4> c = {0.0, 0.5, 0.5, 1.0};
  static constexpr std::array<double, 4> b = {1.0 / 6, 1.0 / 3, 1.0 / 3, 1.0 / 6};
};

/// Dormand & Prince (1980) 5(4) coefficients (Hairer, Norsett & Wanner, table II.5.2).
struct Dp45Tableau {
  static constexpr int kStages = 7;
  static constexpr int kOrder = 5;           ///< of the solution that is kept
  static constexpr int kEmbeddedOrder = 4;   ///< of the error estimator
  static constexpr double c2 = 1.0 / 5, c3 = 3.0 / 10, c4 = 4.0 / 5, c5 = 8.0 / 9;
  static constexpr double a21 = 1.0 / 5;
  static constexpr double a31 = 3.0 / 40, a32 = 9.0 / 40;
  static constexpr double a41 = 44.0 / 45, a42 = -56.0 / 15, a43 = 32.0 / 9;
  static constexpr double a51 = 19372.0 / 6561, a52 = -25360.0 / 2187, a53 = 64448.0 / 6561,
                          a54 = -212.0 / 729;
  static constexpr double a61 = 9017.0 / 3168, a62 = -355.0 / 33, a63 = 46732.0 / 5247,
                          a64 = 49.0 / 176, a65 = -5103.0 / 18656;
  // Fifth-order weights b (= the last row of A: FSAL; b2 = 0).
  static constexpr double b1 = 35.0 / 384, b3 = 500.0 / 1113, b4 = 125.0 / 192,
                          b5 = -2187.0 / 6784, b6 = 11.0 / 84;
  // Fifth-order minus fourth-order weights (e2 = 0): the error estimate.
  static constexpr double e1 = 71.0 / 57600, e3 = -71.0 / 16695, e4 = 71.0 / 1920,
                          e5 = -17253.0 / 339200, e6 = 22.0 / 525, e7 = -1.0 / 40;
  // Continuous extension (Hairer, Norsett & Wanner, DOPRI5 dense output; d2 = 0).
  static constexpr double d1 = -12715105075.0 / 11282082432, d3 = 87487479700.0 / 32700410799,
                          d4 = -10690763975.0 / 1880347072,
                          d5 = 701980252875.0 / 199316789632, d6 = -1453857185.0 / 822651844,
                          d7 = 69997945.0 / 29380423;
};

/// The inner stages of one Dormand-Prince step (k1 is the caller's, k7 = f(t1, y1)).
template <typename Vec>
struct Dp45Stages {
  Vec k2, k3, k4, k5, k6;
};

/// The fifth-order Dormand-Prince solution at t + h from k1 = f(t, y): five new evaluations.
/// `t_end` is the time of the last stage, normally t + h; a caller landing on a breakpoint
/// passes the breakpoint itself so the stage sees it exactly.
template <typename Vec, typename F>
Vec Dp45Solution(F&& f, double t, double h, const Vec& y, const Vec& k1, Dp45Stages<Vec>* s,
                 double t_end) {
  using T = Dp45Tableau;
  s->k2 = f(t + T::c2 * h, y + h * (T::a21 * k1));
  s->k3 = f(t + T::c3 * h, y + h * (T::a31 * k1 + T::a32 * s->k2));
  s->k4 = f(t + T::c4 * h, y + h * (T::a41 * k1 + T::a42 * s->k2 + T::a43 * s->k3));
  s->k5 = f(t + T::c5 * h,
            y + h * (T::a51 * k1 + T::a52 * s->k2 + T::a53 * s->k3 + T::a54 * s->k4));
  s->k6 = f(t_end, y + h * (T::a61 * k1 + T::a62 * s->k2 + T::a63 * s->k3 + T::a64 * s->k4 +
                            T::a65 * s->k5));
  return y + h * (T::b1 * k1 + T::b3 * s->k3 + T::b4 * s->k4 + T::b5 * s->k5 + T::b6 * s->k6);
}

/// The embedded error estimate y5 - y4 of a step (k7 = f(t + h, y5)).
template <typename Vec>
Vec Dp45Error(double h, const Vec& k1, const Dp45Stages<Vec>& s, const Vec& k7) {
  using T = Dp45Tableau;
  return h * (T::e1 * k1 + T::e3 * s.k3 + T::e4 * s.k4 + T::e5 * s.k5 + T::e6 * s.k6 +
              T::e7 * k7);
}

/// Dense output of one accepted Dormand-Prince step on [t0, t0 + h]: a fourth-order continuous
/// extension, exact at both ends.
template <typename Vec>
struct Dp45Dense {
  std::array<Vec, 5> r;
  /// The state at s = (t - t0) / h in [0, 1].
  Vec operator()(double s) const {
    const double s1 = 1.0 - s;
    return r[0] + s * (r[1] + s1 * (r[2] + s * (r[3] + s1 * r[4])));
  }
};

template <typename Vec>
Dp45Dense<Vec> MakeDp45Dense(double h, const Vec& y0, const Vec& y1, const Vec& k1,
                             const Dp45Stages<Vec>& s, const Vec& k7) {
  using T = Dp45Tableau;
  Dp45Dense<Vec> d;
  d.r[0] = y0;
  d.r[1] = y1 - y0;
  d.r[2] = h * k1 - d.r[1];
  d.r[3] = d.r[1] - h * k7 - d.r[2];
  d.r[4] = h * (T::d1 * k1 + T::d3 * s.k3 + T::d4 * s.k4 + T::d5 * s.k5 + T::d6 * s.k6 +
                T::d7 * k7);
  return d;
}

/// How the per-component scaled errors err_i / sc_i combine into one number.
enum class ErrorNorm {
  kRms,  ///< sqrt(mean of squares) (Hairer, Norsett & Wanner II.4.11)
  kMax,  ///< the largest component: every component meets the tolerance
};

/// Scaled error of a step: sc_i = tol (1 + max(|y0_i|, |y1_i|)). Non-finite when the step is.
template <typename Vec>
double Dp45ErrorNorm(const Vec& err, const Vec& y0, const Vec& y1, double tol, ErrorNorm norm) {
  if (norm == ErrorNorm::kRms) {
    const Vec sk = tol * (Vec::Ones() + y0.cwiseAbs().cwiseMax(y1.cwiseAbs()));
    return std::sqrt(err.cwiseQuotient(sk).squaredNorm() / static_cast<double>(err.size()));
  }
  double ratio = 0.0;
  for (int i = 0; i < static_cast<int>(err.size()); ++i) {
    const double scale = tol * (1.0 + std::max(std::abs(y0[i]), std::abs(y1[i])));
    ratio = std::max(ratio, std::abs(err[i]) / scale);
  }
  return ratio;
}

/// The factor on h for the next attempt (rejected, e > 1 or not finite: at most 1) or the
/// next step (accepted: at most 5, or 1 right after a rejection).
inline double Dp45StepFactor(double e, bool rejected_before) {
  if (!std::isfinite(e)) return 0.2;
  const double fac = 0.9 * std::pow(std::max(e, 1e-10), -0.2);
  if (e > 1.0) return std::clamp(fac, 0.2, 1.0);
  return std::clamp(fac, 0.2, rejected_before ? 1.0 : 5.0);
}

/// Starting step from f0 = f(t, y) (Hairer, Norsett & Wanner, sec. II.4), for order 5: one new
/// evaluation; never above max_step or t_end - t.
template <typename Vec, typename F>
double Dp45InitialStep(F&& f, double t, const Vec& y, const Vec& f0, double tol, double max_step,
                       double t_end) {
  const double n = static_cast<double>(y.size());
  const Vec sk = tol * (Vec::Ones() + y.cwiseAbs());
  const double d0 = std::sqrt((y.cwiseQuotient(sk)).squaredNorm() / n);
  const double d1 = std::sqrt((f0.cwiseQuotient(sk)).squaredNorm() / n);
  double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
  h0 = std::min({h0, max_step, t_end - t});
  const Vec f1 = f(t + h0, y + h0 * f0);
  const double d2 = std::sqrt(((f1 - f0).cwiseQuotient(sk)).squaredNorm() / n) / h0;
  const double dm = std::max(d1, d2);
  const double h1 = dm <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / dm, 1.0 / 5.0);
  return std::min({100.0 * h0, h1, max_step});
}

}  // namespace sportsim::ode

#endif  // SPORTSIM_SIM_CORE_ODE_RUNGE_KUTTA_H_
