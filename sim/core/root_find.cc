#include "sim/core/root_find.h"

#include <cmath>

namespace sportsim {

double FindBracketedRoot(absl::FunctionRef<double(double)> f, double a, double b, double fa,
                         double fb, double t_tol) {
  if (fa == 0.0) return a;
  if (fb == 0.0) return b;
  int side = 0;  // which end was kept last time (Illinois halving)
  double width_checkpoint = std::abs(b - a);
  for (int i = 0; i < 400 && std::abs(b - a) > t_tol; ++i) {
    double t = (a * fb - b * fa) / (fb - fa);
    // Bisect when the secant lands outside or on the bracket, and every third step unless the
    // last three halved the bracket: this bounds the cost on flat (multiple) roots.
    const bool stalled = i % 3 == 2 && std::abs(b - a) > 0.5 * width_checkpoint;
    if (i % 3 == 2) width_checkpoint = std::abs(b - a);
    if (stalled || !(t > std::fmin(a, b) && t < std::fmax(a, b))) t = 0.5 * (a + b);
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
