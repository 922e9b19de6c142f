// Hermite interpolants of one step [t0, t0 + h], in the step fraction s = (t - t0) / h.
//
// - Cubic Hermite from the values and first derivatives at both ends: interpolation error
//   O(h^4) on a smooth solution (Hairer, Norsett & Wanner, Solving ODEs I, sec. II.6; any
//   numerical analysis text, e.g. Burden & Faires, sec. 3.4). Exact at both ends.
// - Quintic Hermite for a second-order system q'' = a: positions from the values, rates and
//   accelerations at both ends, error O(h^6); the rates are its derivative. Used where a
//   fourth-order scheme must not lose its order in the interpolant (a cubic's O(h^4) error is
//   as large as RK4's own).
#ifndef SPORTSIM_SIM_CORE_ODE_HERMITE_H_
#define SPORTSIM_SIM_CORE_ODE_HERMITE_H_

namespace sportsim::ode {

/// Cubic Hermite basis at s: weights of y0, h f0, y1, h f1.
struct CubicHermiteBasis {
  double h00, h10, h01, h11;
  explicit CubicHermiteBasis(double s) {
    const double s2 = s * s, s3 = s2 * s;
    h00 = 2.0 * s3 - 3.0 * s2 + 1.0;
    h10 = s3 - 2.0 * s2 + s;
    h01 = -2.0 * s3 + 3.0 * s2;
    h11 = s3 - s2;
  }
};

/// The cubic Hermite interpolant at s in [0, 1] of a step of length h with values y0, y1 and
/// derivatives f0, f1 (any vector type with + and scalar *).
template <typename Vec>
Vec CubicHermite(const Vec& y0, const Vec& f0, const Vec& y1, const Vec& f1, double h, double s) {
  const CubicHermiteBasis b(s);
  return b.h00 * y0 + (b.h10 * h) * f0 + b.h01 * y1 + (b.h11 * h) * f1;
}

/// The cubic Hermite interpolant at s and its time derivative (the rate, d/dt = (1/h) d/ds).
template <typename Vec>
void CubicHermiteRate(const Vec& y0, const Vec& f0, const Vec& y1, const Vec& f1, double h,
                      double s, Vec* y, Vec* rate) {
  const double s2 = s * s, s3 = s2 * s;
  const Vec m0 = h * f0, m1 = h * f1;
  *y = (2 * s3 - 3 * s2 + 1) * y0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * y1 +
       (s3 - s2) * m1;
  *rate = ((6 * s2 - 6 * s) * y0 + (3 * s2 - 4 * s + 1) * m0 + (-6 * s2 + 6 * s) * y1 +
           (3 * s2 - 2 * s) * m1) /
          h;
}

/// One scalar component of a cubic Hermite interpolant and its s-derivative.
struct ScalarCubicHermite {
  double p0, m0, p1, m1;  ///< values and h * slopes at s = 0 and s = 1
  double Value(double s) const {
    const CubicHermiteBasis b(s);
    return b.h00 * p0 + b.h10 * m0 + b.h01 * p1 + b.h11 * m1;
  }
  double Slope(double s) const {
    const double s2 = s * s;
    return (6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * m0 + (-6 * s2 + 6 * s) * p1 +
           (3 * s2 - 2 * s) * m1;
  }
};

/// Quintic Hermite at s for positions p (values p0, p1, rates v0, v1, accelerations a0, a1 at
/// the ends of a step of length h): writes the position and its time derivative (the rate).
template <typename Vec>
void QuinticHermite(const Vec& p0, const Vec& v0, const Vec& a0, const Vec& p1, const Vec& v1,
                    const Vec& a1, double h, double s, Vec* p, Vec* v) {
  const double s2 = s * s, s3 = s2 * s, s4 = s3 * s, s5 = s4 * s;
  const double h0 = 1 - 10 * s3 + 15 * s4 - 6 * s5, h5 = 1 - h0;
  const double h1 = s - 6 * s3 + 8 * s4 - 3 * s5;
  const double h2 = 0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5;
  const double h3 = 0.5 * s3 - s4 + 0.5 * s5;
  const double h4 = -4 * s3 + 7 * s4 - 3 * s5;
  const double d0 = -30 * s2 + 60 * s3 - 30 * s4, d5 = -d0;
  const double d1 = 1 - 18 * s2 + 32 * s3 - 15 * s4;
  const double d2 = s - 4.5 * s2 + 6 * s3 - 2.5 * s4;
  const double d3 = 1.5 * s2 - 4 * s3 + 2.5 * s4;
  const double d4 = -12 * s2 + 28 * s3 - 15 * s4;
  *p = h0 * p0 + h1 * h * v0 + h2 * h * h * a0 + h3 * h * h * a1 + h4 * h * v1 + h5 * p1;
  *v = (d0 * p0 + d5 * p1) / h + d1 * v0 + d2 * h * a0 + d3 * h * a1 + d4 * v1;
}

}  // namespace sportsim::ode

#endif  // SPORTSIM_SIM_CORE_ODE_HERMITE_H_
