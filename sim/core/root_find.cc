#include "sim/core/root_find.h"

#include <cmath>

namespace sportsim {

double FindBracketedRoot(absl::FunctionRef<double(double)> f, double a, double b, double fa,
                         double fb, double t_tol) {
  if (fa == 0.0) return a;
  if (fb == 0.0) return b;
  int side = 0;  // which end was kept last time (Illinois halving)
  for (int i = 0; i < 200 && std::abs(b - a) > t_tol; ++i) {
    double t = (a * fb - b * fa) / (fb - fa);
    // Fall back to bisection when the secant lands outside or on the bracket.
    if (!(t > std::fmin(a, b) && t < std::fmax(a, b))) t = 0.5 * (a + b);
    const double ft = f(t);
    if (ft == 0.0) return t;
    if ((ft > 0) == (fb > 0)) {
      b = t;
      fb = ft;
      if (side == -1) fa *= 0.5;
      side = -1;
    } else {
      a = t;
      fa = ft;
      if (side == +1) fb *= 0.5;
      side = +1;
    }
  }
  // The root lies in [a, b]; return the midpoint of what is left.
  return 0.5 * (a + b);
}

}  // namespace sportsim
