#include "sim/core/poly_roots.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sportsim {
namespace {

// p and p' at x.
void EvalWithDerivative(const double* c, int degree, double x, double* p, double* dp) {
  double f = c[degree];
  double d = 0.0;
  for (int k = degree - 1; k >= 0; --k) {
    d = d * x + f;
    f = f * x + c[k];
  }
  *p = f;
  *dp = d;
}

// sum |c_k| |x|^k: the scale of the rounding in evaluating p at x.
double AbsEval(const double* c, int degree, double x) {
  const double ax = std::abs(x);
  double f = std::abs(c[degree]);
  for (int k = degree - 1; k >= 0; --k) f = f * ax + std::abs(c[k]);
  return f;
}

// The root of a quadratic (c[2] != 0) in [l, h], where it is monotone, by the stable form of
// the quadratic formula (Press et al., Numerical Recipes, 3rd ed., section 5.6): both roots
// without cancellation. A starting point only: near a double root, where the discriminant
// rounds below zero, it gives the vertex. NaN when neither root lies in [l, h].
double QuadraticRootIn(const double* c, double l, double h) {
  const double disc = std::max(0.0, c[1] * c[1] - 4.0 * c[2] * c[0]);
  const double q = -0.5 * (c[1] + std::copysign(std::sqrt(disc), c[1]));
  const double r1 = q / c[2];
  if (r1 >= l && r1 <= h) return r1;
  const double r2 = c[0] / q;
  if (r2 >= l && r2 <= h) return r2;
  return std::numeric_limits<double>::quiet_NaN();
}

// The root of p in [a, b] (a < b), where p is monotone and p(a) = fa, p(b) = fb have opposite
// signs. `to_noise`: stop where p(x) is within its rounding (a crossing time); otherwise run to
// a rounding-level step (a critical point, where p' must reach exactly 0 for a double root of
// p to show as p == 0).
double Refine(const double* c, int degree, double a, double b, double fa, double fb,
              bool to_noise) {
  // A line's root is one division (rounded once), kept in the bracket.
  if (degree == 1) return std::clamp(-c[0] / c[1], a, b);
  // Keep lo on the side where p has the sign of p(a).
  double lo = a, hi = b;
  const bool neg_at_lo = fa < 0;
  // Newton starts from the chord's root (regula falsi): on a monotone piece it is inside the
  // bracket and, unlike the midpoint, already near a root that is near an end.
  double x = a - fa * ((b - a) / (fb - fa));
  if (!(x > a && x < b)) x = 0.5 * (lo + hi);
  // A quadratic's Newton iterations start from its closed-form root: at most a few units in
  // the last place off, so that one step confirms it.
  if (degree == 2) {
    const double r = QuadraticRootIn(c, a, b);
    if (r > a && r < b) x = r;
  }
  for (int it = 0; it < 200; ++it) {
    double f, df;
    EvalWithDerivative(c, degree, x, &f, &df);
    if (f == 0.0) return x;
    // Below Horner's rounding bound (2d u sum |c_k| |x|^k, Higham 5.1) the sign of p(x) says
    // nothing: x is as good a root as the arithmetic can tell, and bisecting on noise would
    // only spend iterations.
    if (to_noise &&
        std::abs(f) <= degree * std::numeric_limits<double>::epsilon() * AbsEval(c, degree, x)) {
      return x;
    }
    if ((f < 0) == neg_at_lo) {
      lo = x;
    } else {
      hi = x;
    }
    double next = df != 0.0 ? x - f / df : 0.5 * (lo + hi);
    const double l = std::min(lo, hi), h = std::max(lo, hi);
    if (!(next > l && next < h)) next = 0.5 * (lo + hi);  // Newton left the bracket: bisect
    // Converged when the step is at rounding level or the bracket has no room left.
    if (std::abs(next - x) <= 4.0 * std::numeric_limits<double>::epsilon() * std::abs(x) ||
        next == l || next == h) {
      return next;
    }
    x = next;
  }
  return x;
}

int Degree(const double* c, int degree) {
  while (degree > 0 && c[degree] == 0.0) --degree;
  return degree;
}

// Breakpoints lo = x_0 < ... < x_m = hi between which p (of exact degree >= 1) is monotone.
int MonotonePieces(const double* c, int degree, double lo, double hi, double* x) {
  int m = 0;
  x[m++] = lo;
  if (degree == 2) {
    // A quadratic's one critical point, its vertex, directly.
    const double v = -c[1] / (2.0 * c[2]);
    if (v > lo && v < hi) x[m++] = v;
  } else if (degree > 2) {
    double d[kMaxPolyDegree];
    for (int k = 1; k <= degree; ++k) d[k - 1] = k * c[k];
    double crit[kMaxPolyDegree];
    const int nc = PolyRootsIn(d, degree - 1, lo, hi, crit);
    for (int k = 0; k < nc; ++k) {
      if (crit[k] > x[m - 1] && crit[k] < hi) x[m++] = crit[k];
    }
  }
  x[m++] = hi;
  return m;
}

}  // namespace

double PolyEval(const double* c, int degree, double x) {
  double f = c[degree];
  for (int k = degree - 1; k >= 0; --k) f = f * x + c[k];
  return f;
}

namespace {

// C(i, k) / C(n, k) for every degree n, i <= n and k <= i (each the quotient of two exact
// integers, rounded once).
struct BernsteinRatios {
  double r[kMaxPolyDegree + 1][kMaxPolyDegree + 1][kMaxPolyDegree + 1] = {};
  constexpr BernsteinRatios() {
    double c[kMaxPolyDegree + 1][kMaxPolyDegree + 1] = {};  // C(i, k)
    for (int i = 0; i <= kMaxPolyDegree; ++i) {
      c[i][0] = 1.0;
      for (int k = 1; k <= i; ++k) c[i][k] = c[i - 1][k - 1] + (k < i ? c[i - 1][k] : 0.0);
    }
    for (int n = 0; n <= kMaxPolyDegree; ++n) {
      for (int i = 0; i <= n; ++i) {
        for (int k = 0; k <= i; ++k) r[n][i][k] = c[i][k] / c[n][k];
      }
    }
  }
  const auto& operator[](int n) const { return r[n]; }
};
constexpr BernsteinRatios kBernsteinRatios;

// ProvablyPositive for a degree known at compile time (the loops unroll).
template <int kDegree>
bool ProvablyPositiveOf(const double* c, double hi) {
  double a[kDegree + 1];  // p(hi t) = sum a_k t^k, t in [0, 1]
  double scale = 1.0, largest = 0.0;
  for (int k = 0; k <= kDegree; ++k) {
    a[k] = c[k] * scale;
    scale *= hi;
    largest = std::max(largest, std::abs(a[k]));
  }
  if (!(largest < std::numeric_limits<double>::infinity())) return false;
  const double margin = 1e-12 * largest;
  // b_i = sum_{k <= i} C(i, k) / C(n, k) a_k, every one checked without a branch (one
  // data-dependent branch at the end instead of one per coefficient; a NaN fails its check).
  const auto& ratio = kBernsteinRatios[kDegree];
  bool all = true;
  for (int i = 0; i <= kDegree; ++i) {
    double b = 0.0;
    for (int k = 0; k <= i; ++k) b += ratio[i][k] * a[k];
    all &= b > margin;
  }
  return all;
}

}  // namespace

// True when p > 0 everywhere on [0, hi], shown by its Bernstein coefficients there: p lies in
// their convex hull (Farouki and Rajan, "On the numerical condition of polynomials in Bernstein
// form", CAGD 4, 1987), so all of them positive proves it. Each must clear a margin far above
// the rounding of this conversion and of evaluating p (1e-12 of the largest), so that a p this
// call passes has no sign change the search below could have found either: it only saves the
// search. Most predictions in a billiards shot are such pairs (near, but moving apart).
bool ProvablyPositive(const double* c, int degree, double hi) {
  // The first two Bernstein coefficients, p(0) and p(0) + p'(0) hi / n (here times n), decide
  // most failures (an approach) before the scaling; a margin never rescues one <= 0.
  if (!(c[0] > 0.0) || (degree >= 1 && !(degree * c[0] + c[1] * hi > 0.0))) return false;
  switch (degree) {
    case 0:
      return ProvablyPositiveOf<0>(c, hi);
    case 1:
      return ProvablyPositiveOf<1>(c, hi);
    case 2:
      return ProvablyPositiveOf<2>(c, hi);
    case 3:
      return ProvablyPositiveOf<3>(c, hi);
    default:
      return ProvablyPositiveOf<4>(c, hi);
  }
}

int PolyRootsIn(const double* c, int degree, double lo, double hi, double* roots) {
  degree = Degree(c, degree);
  if (degree == 0 || !(lo <= hi)) return 0;
  double x[kMaxPolyDegree + 1];
  const int m = MonotonePieces(c, degree, lo, hi, x);
  int n = 0;
  double fa = PolyEval(c, degree, x[0]);
  if (fa == 0.0) roots[n++] = x[0];
  for (int k = 1; k < m && n < degree; ++k) {
    const double fb = PolyEval(c, degree, x[k]);
    if (fb == 0.0) {
      // Near a multiple root p can round to exactly zero over a stretch: breakpoints in a row
      // with p == 0 are one root (the first of them), so there are never more than `degree`.
      if (fa != 0.0) roots[n++] = x[k];
    } else if (fa != 0.0 && (fa < 0) != (fb < 0)) {
      roots[n++] = Refine(c, degree, x[k - 1], x[k], fa, fb, /*to_noise=*/false);
    }
    fa = fb;
  }
  return n;
}

double FirstDownCrossing(const double* c, int degree, double lo, double hi) {
  constexpr double kNever = std::numeric_limits<double>::infinity();
  degree = Degree(c, degree);
  if (degree == 0 || !(lo <= hi)) return kNever;
  // From lo = 0 only (every engine search): a shift to another lo would add rounding the
  // margin does not bound. Not for a line or a quadratic: their search is as cheap as the proof.
  if (lo == 0.0 && degree > 2 && ProvablyPositive(c, degree, hi)) return kNever;
  // A p that is positive at 0 and provably convex on [0, hi] (p'' passes ProvablyPositive)
  // needs no critical points: Newton's iterates from 0 rise to its first root, never past it
  // (each tangent lies under a convex p, so the tangent's zero comes no later than p's), and
  // without a root in [0, hi] they pass hi or p's minimum (p' >= 0 there, p still positive).
  // Two thirds of the pair searches that reach this point are such (a contact ahead, or a
  // near miss, of two balls whose relative path bends away from neither).
  if (lo == 0.0 && degree >= 3 && c[0] > 0.0) {
    double d2[kMaxPolyDegree - 1];
    for (int k = 2; k <= degree; ++k) d2[k - 2] = k * (k - 1) * c[k];
    if (ProvablyPositive(d2, degree - 2, hi)) {
      double x = 0.0, f = c[0], df = c[1];
      for (int it = 0; it < 64; ++it) {
        if (!(df < 0.0)) return kNever;
        const double next = x - f / df;
        if (!(next <= hi)) return kNever;
        if (next - x <= 4.0 * std::numeric_limits<double>::epsilon() * next) return next;
        x = next;
        EvalWithDerivative(c, degree, x, &f, &df);
        if (f <= 0.0) return x;  // at the root, within rounding
        if (!(f > 0.0)) return kNever;  // NaN: no answer to give
      }
      // Slow convergence (a grazing double root): the general search below decides.
    }
  }
  double x[kMaxPolyDegree + 1];
  const int m = MonotonePieces(c, degree, lo, hi, x);
  double fa = PolyEval(c, degree, x[0]);
  for (int k = 1; k < m; ++k) {
    const double fb = PolyEval(c, degree, x[k]);
    if (fa > 0.0 && fb <= 0.0) {
      return fb == 0.0 ? x[k] : Refine(c, degree, x[k - 1], x[k], fa, fb, /*to_noise=*/true);
    }
    fa = fb;
  }
  return kNever;
}

}  // namespace sportsim
