// Bracketed scalar root finding.
#ifndef SPORTSIM_SIM_CORE_ROOT_FIND_H_
#define SPORTSIM_SIM_CORE_ROOT_FIND_H_

#include "absl/functional/function_ref.h"

namespace sportsim {

/// Finds t in [a, b] with f(t) = 0, given f(a) and f(b) of opposite signs (or one of them zero).
/// Illinois-modified regula falsi with a bisection fallback: superlinear on smooth functions and
/// never leaves the bracket. Stops when the bracket is narrower than `t_tol` (same unit as t) or
/// after 200 iterations, returning the end of the final bracket closest to the sign change.
double FindBracketedRoot(absl::FunctionRef<double(double)> f, double a, double b, double fa,
                         double fb, double t_tol);

}  // namespace sportsim

#endif  // SPORTSIM_SIM_CORE_ROOT_FIND_H_
