// Real roots of low-degree polynomials on an interval, for event prediction (collision times are
// roots of quadratics and quartics in time).
//
// Method: the roots of p' split [lo, hi] into pieces on which p is monotone (found the same way,
// recursively, down to degree 1), and each piece with a sign change holds exactly one root,
// refined by Newton's method kept inside the bracket by bisection. A line's root is one
// division, a quadratic's Newton starts from its stable closed form (confirmed in one step).
// No closed-form cubic or quartic formulas (they lose digits exactly where contacts are
// delicate: grazing, touching, equal accelerations), and degenerate degrees need no special
// case: a zero leading coefficient just lowers the degree, a tiny one puts extra critical
// points far outside the interval. FirstDownCrossing from 0 first tries two shortcuts: a p
// proved positive on the window (Bernstein coefficients) has no crossing, and a p positive at 0
// and proved convex on the window (the same proof on p'') has its first root where Newton's
// iterates from 0 converge, from below, with no critical points needed.
#ifndef SPORTSIM_SIM_CORE_POLY_ROOTS_H_
#define SPORTSIM_SIM_CORE_POLY_ROOTS_H_

namespace sportsim {

inline constexpr int kMaxPolyDegree = 4;

/// p(x) = c[0] + c[1] x + ... + c[degree] x^degree, by Horner's rule.
double PolyEval(const double* c, int degree, double x);

/// The real roots of p in [lo, hi] (finite, lo <= hi), ascending, written to `roots` (room for
/// `degree` values); returns how many. A root of even multiplicity counts when p reaches exactly
/// zero there in floating point; a stretch where p rounds to exactly zero counts once.
/// degree <= kMaxPolyDegree.
int PolyRootsIn(const double* c, int degree, double lo, double hi, double* roots);

/// The first x in [lo, hi] at which p passes from positive to <= 0 (a downward crossing: for
/// p = |gap vector|^2 - d^2, the first approaching contact), or +infinity. When p(lo) <= 0 the
/// search starts after p has become positive again. degree <= kMaxPolyDegree. From lo = 0 a
/// cubic or quartic that ProvablyPositive accepts is answered without a search, and one positive
/// at 0 whose p'' it accepts (convex on the window) by Newton's method from 0.
double FirstDownCrossing(const double* c, int degree, double lo, double hi);

/// True when p > 0 everywhere on [0, hi] (hi > 0) is proved by its Bernstein coefficients there,
/// each clearing a margin of 1e-12 of the largest scaled coefficient (far above the rounding of
/// the conversion and of evaluating p). False proves nothing. degree <= kMaxPolyDegree.
bool ProvablyPositive(const double* c, int degree, double hi);

}  // namespace sportsim

#endif  // SPORTSIM_SIM_CORE_POLY_ROOTS_H_
