#include "sim/core/poly_roots.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdio>
#include <initializer_list>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <unsupported/Eigen/Polynomials>

#include "gtest/gtest.h"

namespace sportsim {
namespace {

// Tolerances below are written in units of kEps = 2^-52 (the unit roundoff is u = kEps / 2).
//
// The one error model used throughout: a simple root r of p, computed in double precision,
// can only be located to within the region where the computed sign of p is unreliable. Horner's
// rule for degree d has forward error at most gamma_2d * S(x), S(x) = sum_k |c_k| |x|^k,
// gamma_2d = 2d u / (1 - 2d u) < 4.01 kEps for d <= 4 (Higham, Accuracy and Stability, 5.1).
// Expanding a product of d linear factors into coefficients perturbs each c_k by at most about
// gamma_d |c_k|-ish terms, i.e. moves p(r) by at most ~2 kEps S(r). So the exact root of the
// stored coefficients is within ~6 kEps S(r) / |p'(r)| of the intended root, to first order, and
// Refine stops within a rounding-level step (<= 4 kEps |x|, or adjacent floats). RootTol uses
// 16 kEps S / |p'| + 8 kEps |r|: about 2.5x the first-order sum, to cover second-order terms.
constexpr double kEps = std::numeric_limits<double>::epsilon();
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Poly {
  std::array<double, kMaxPolyDegree + 1> c{};
  int degree = 0;
};

Poly FromRoots(std::initializer_list<double> roots, double lead = 1.0) {
  Poly p;
  p.c[0] = lead;
  for (double r : roots) {  // multiply by (x - r)
    ++p.degree;
    for (int k = p.degree; k >= 1; --k) p.c[k] = p.c[k - 1] - r * p.c[k];
    p.c[0] = -r * p.c[0];
  }
  return p;
}

Poly FromCoeffs(std::initializer_list<double> c) {
  Poly p;
  int k = 0;
  for (double v : c) p.c[k++] = v;
  p.degree = k - 1;
  return p;
}

// S(x) = sum |c_k| |x|^k: the scale of the rounding error in p(x).
double AbsSum(const Poly& p, double x) {
  double s = 0.0;
  for (int k = p.degree; k >= 0; --k) s = s * std::abs(x) + std::abs(p.c[k]);
  return s;
}

long double EvalLong(const Poly& p, long double x) {
  long double f = p.c[p.degree];
  for (int k = p.degree - 1; k >= 0; --k) f = f * x + p.c[k];
  return f;
}

long double DerivLong(const Poly& p, long double x) {
  long double d = 0.0L;
  for (int k = p.degree; k >= 1; --k) d = d * x + static_cast<long double>(k) * p.c[k];
  return d;
}

// How far the computed root may be from the exact root r (see the error model at the top).
double RootTol(const Poly& p, double r) {
  return 16.0 * kEps * AbsSum(p, r) / std::abs(static_cast<double>(DerivLong(p, r))) +
         8.0 * kEps * std::abs(r);
}

// Near a double root r, p(x) ~ (p''(r)/2) (x - r)^2, and the computed p can be exactly 0 (or of
// either sign) wherever that is below the evaluation noise 4.01 kEps S(x); the coefficients of
// the double-root tests are exact, so that is the only error: |x - r| <= sqrt(4 kEps S /
// |p''/2|). DoubleRootTol doubles the radicand for margin.
double DoubleRootTol(const Poly& p, double r) {
  long double d2 = 0.0L;
  for (int k = p.degree; k >= 2; --k) d2 = d2 * r + static_cast<long double>(k) * (k - 1) * p.c[k];
  return std::sqrt(8.0 * kEps * AbsSum(p, r) / std::abs(0.5 * static_cast<double>(d2)));
}

// Calls PolyRootsIn with a buffer much larger than `degree` pre-filled with NaN, and checks the
// contract on the way out: at most `degree` roots (the caller only has to provide that much
// room), nothing written past the count, ascending, inside [lo, hi].
std::vector<double> Roots(const Poly& p, double lo, double hi) {
  std::array<double, 16> buf;
  buf.fill(std::numeric_limits<double>::quiet_NaN());
  const int n = PolyRootsIn(p.c.data(), p.degree, lo, hi, buf.data());
  EXPECT_GE(n, 0);
  EXPECT_LE(n, p.degree) << "more roots than the caller's buffer (degree " << p.degree << ") holds";
  for (int k = std::max(n, 0); k < static_cast<int>(buf.size()); ++k) {
    EXPECT_TRUE(std::isnan(buf[k])) << "wrote past the returned count at index " << k;
  }
  std::vector<double> out(buf.begin(), buf.begin() + std::clamp(n, 0, 16));
  for (size_t k = 0; k < out.size(); ++k) {
    EXPECT_GE(out[k], lo);
    EXPECT_LE(out[k], hi);
    if (k > 0) {
      EXPECT_LT(out[k - 1], out[k]) << "roots not strictly ascending";
    }
  }
  return out;
}

double FirstDown(const Poly& p, double lo, double hi) {
  return FirstDownCrossing(p.c.data(), p.degree, lo, hi);
}

// Every expected root found (each within RootTol), nothing else reported.
void ExpectRoots(const Poly& p, double lo, double hi, std::vector<double> expected) {
  SCOPED_TRACE(testing::Message() << "degree " << p.degree << " on [" << lo << ", " << hi << "]");
  const std::vector<double> got = Roots(p, lo, hi);
  ASSERT_EQ(got.size(), expected.size());
  std::sort(expected.begin(), expected.end());
  for (size_t k = 0; k < got.size(); ++k) {
    EXPECT_NEAR(got[k], expected[k], RootTol(p, expected[k])) << "root " << k;
  }
}

// ---------------------------------------------------------------------------------------------
// PolyEval

TEST(PolyEvalTest, HornerMatchesHandExpansion) {
  const double c[] = {1.0, 2.0, 3.0, -4.0, 0.5};
  // 1 + 2*2 + 3*4 - 4*8 + 0.5*16 = -7, exactly representable at every step.
  EXPECT_EQ(PolyEval(c, 4, 2.0), -7.0);
  EXPECT_EQ(PolyEval(c, 0, 123.0), 1.0);
  EXPECT_EQ(PolyEval(c, 2, -1.0), 2.0);  // 1 - 2 + 3
}

// ---------------------------------------------------------------------------------------------
// Polynomials with known roots

TEST(PolyRootsInTest, KnownRootsDegreesOneToFour) {
  ExpectRoots(FromRoots({0.3}), 0.0, 1.0, {0.3});
  ExpectRoots(FromRoots({0.3}, -7.5), -2.0, 2.0, {0.3});
  ExpectRoots(FromRoots({0.3, 0.9}), 0.0, 1.0, {0.3, 0.9});
  ExpectRoots(FromRoots({-1.7, 0.3, 2.9}), -3.0, 3.0, {-1.7, 0.3, 2.9});
  ExpectRoots(FromRoots({-1.7, 0.3, 2.9}, -0.01), -3.0, 3.0, {-1.7, 0.3, 2.9});
  ExpectRoots(FromRoots({0.11, 0.37, 0.59, 0.83}), 0.0, 1.0, {0.11, 0.37, 0.59, 0.83});
  ExpectRoots(FromRoots({0.11, 0.37, 0.59, 0.83}, 3e5), 0.0, 1.0, {0.11, 0.37, 0.59, 0.83});
  // Sub-interval picks out the middle roots only.
  ExpectRoots(FromRoots({0.11, 0.37, 0.59, 0.83}), 0.2, 0.7, {0.37, 0.59});
  // No roots at all: positive-definite quadratic and quartic.
  ExpectRoots(FromCoeffs({1.0, 0.0, 1.0}), -10.0, 10.0, {});
  ExpectRoots(FromCoeffs({2.0, -1.0, 0.0, 0.0, 1.0}), -10.0, 10.0, {});
}

TEST(PolyRootsInTest, ClusteredRootsOneMicroApartAreBothFound) {
  // Each pair is resolvable: between the two roots |p| reaches (5e-7)^2 * |product of the other
  // factors|, and for these cases that is >= 10x the evaluation noise 4 kEps S(x) (checked).
  const struct {
    std::vector<double> roots;
    double pair;  // the lower root of the clustered pair
    double lo, hi;
  } cases[] = {
      {{0.1, 0.1 + 1e-6}, 0.1, 0.0, 1.0},
      {{0.1, 0.1 + 1e-6, 0.5, 0.9}, 0.1, 0.0, 1.0},
      {{1.0, 1.0 + 1e-6, 3.0}, 1.0, 0.0, 4.0},
      {{1.0, 1.0 + 1e-6, 3.0, 5.0}, 1.0, 0.0, 6.0},
      {{-2.0, 0.25, 0.25 + 1e-6, 2.0}, 0.25, -3.0, 3.0},
  };
  for (const auto& tc : cases) {
    Poly p;
    p.c[0] = 1.0;
    for (double r : tc.roots) {  // same expansion as FromRoots
      ++p.degree;
      for (int k = p.degree; k >= 1; --k) p.c[k] = p.c[k - 1] - r * p.c[k];
      p.c[0] = -r * p.c[0];
    }
    SCOPED_TRACE(testing::Message() << "pair at " << tc.pair << ", degree " << p.degree);
    // The resolvability premise of the test itself: the dip between the pair is >= 10x noise.
    const double mid = tc.pair + 0.5e-6;
    ASSERT_GT(std::abs(static_cast<double>(EvalLong(p, mid))), 10.0 * 4.0 * kEps * AbsSum(p, mid))
        << "test premise";
    ExpectRoots(p, tc.lo, tc.hi, tc.roots);
    // The tolerance must be small enough to tell the pair apart, or the test proves nothing.
    EXPECT_LT(RootTol(p, tc.pair), 0.1e-6);
    EXPECT_LT(RootTol(p, tc.pair + 1e-6), 0.1e-6);
  }
}

TEST(PolyRootsInTest, RootsAtIntervalEndsAreReportedExactly) {
  // Dyadic roots: the coefficients and Horner evaluations at the roots are exact, so p is
  // exactly 0 at the interval ends and the ends themselves must be returned.
  EXPECT_EQ(Roots(FromRoots({1.0, 3.0}), 1.0, 3.0), (std::vector<double>{1.0, 3.0}));
  EXPECT_EQ(Roots(FromRoots({1.0, 3.0}), 1.0, 2.0), (std::vector<double>{1.0}));
  EXPECT_EQ(Roots(FromRoots({1.0, 3.0}), 2.0, 3.0), (std::vector<double>{3.0}));
  EXPECT_EQ(Roots(FromRoots({0.5}), 0.5, 0.5), (std::vector<double>{0.5}));  // lo == hi
  const std::vector<double> q = Roots(FromRoots({0.5, 2.0, 4.0, 8.0}), 0.5, 4.0);
  ASSERT_EQ(q.size(), 3u);
  EXPECT_EQ(q[0], 0.5);
  EXPECT_NEAR(q[1], 2.0, RootTol(FromRoots({0.5, 2.0, 4.0, 8.0}), 2.0));
  EXPECT_EQ(q[2], 4.0);
  // Degenerate interval not on a root: nothing.
  EXPECT_TRUE(Roots(FromRoots({0.5}), 0.25, 0.25).empty());
  // lo > hi: nothing (and FirstDownCrossing never).
  EXPECT_TRUE(Roots(FromRoots({0.5}), 1.0, 0.0).empty());
  EXPECT_EQ(FirstDown(FromRoots({0.5}, -1.0), 1.0, 0.0), kInf);
}

TEST(PolyRootsInTest, RootsOutsideTheIntervalAreNotReported) {
  ExpectRoots(FromRoots({-1.0, 2.0, 5.0, 11.0}), 0.0, 10.0, {2.0, 5.0});
  ExpectRoots(FromRoots({-1.0, 2.0, 5.0, 11.0}), 5.5, 10.0, {});
  ExpectRoots(FromRoots({-3.0, -2.0, 12.0}), 0.0, 10.0, {});
  // Just outside: 1e-7 beyond each end, where RootTol is ~1e-14, so which side is not in doubt.
  const Poly p = FromRoots({-1e-7, 3.0, 10.0 + 1e-7});
  ASSERT_LT(RootTol(p, 10.0 + 1e-7), 1e-9);
  ASSERT_LT(RootTol(p, -1e-7), 1e-9);
  ExpectRoots(p, 0.0, 10.0, {3.0});
  ExpectRoots(p, -1.0, 11.0, {-1e-7, 3.0, 10.0 + 1e-7});
}

TEST(PolyRootsInTest, ExactlyRepresentableDoubleRootsAreReportedOnce) {
  // Dyadic double roots: exact coefficients, p(r) == 0 exactly. PolyRootsIn finds a double root
  // only through a critical point where the computed p is exactly 0, so it must report exactly
  // one value near r, p must evaluate to exactly 0 there, and it is within DoubleRootTol.
  const auto expect_double = [](const Poly& p, double lo, double hi, std::vector<double> expected,
                                double double_root) {
    SCOPED_TRACE(testing::Message() << "double root " << double_root << " on [" << lo << ", "
                                    << hi << "]");
    ASSERT_EQ(PolyEval(p.c.data(), p.degree, double_root), 0.0) << "test premise";
    const std::vector<double> got = Roots(p, lo, hi);
    ASSERT_EQ(got.size(), expected.size());
    for (size_t k = 0; k < got.size(); ++k) {
      if (expected[k] == double_root) {
        EXPECT_EQ(PolyEval(p.c.data(), p.degree, got[k]), 0.0);
        EXPECT_NEAR(got[k], expected[k], DoubleRootTol(p, expected[k]));
      } else {
        EXPECT_NEAR(got[k], expected[k], RootTol(p, expected[k]));
      }
    }
  };
  // (x - 0.5)^2 (x - 2) = x^3 - 3x^2 + 2.25x - 0.5.
  const Poly p3 = FromRoots({0.5, 0.5, 2.0});
  ASSERT_EQ(p3.c[1], 2.25);
  expect_double(p3, 0.0, 3.0, {0.5, 2.0}, 0.5);
  expect_double(p3, 0.0, 1.0, {0.5}, 0.5);
  expect_double(p3, 0.5, 1.0, {0.5}, 0.5);  // double root at the interval end
  expect_double(p3, 0.0, 0.5, {0.5}, 0.5);
  // Quartics: a double root among simple ones, and two double roots (p >= 0, touches twice).
  expect_double(FromRoots({-1.0, 0.5, 0.5, 2.0}), -2.0, 3.0, {-1.0, 0.5, 2.0}, 0.5);
  expect_double(FromRoots({0.25, 0.25, 0.75, 0.75}), 0.0, 0.5, {0.25}, 0.25);
  expect_double(FromRoots({0.25, 0.25, 0.75, 0.75}), 0.5, 1.0, {0.75}, 0.75);
  {
    const Poly p = FromRoots({0.25, 0.25, 0.75, 0.75});
    const std::vector<double> got = Roots(p, 0.0, 1.0);
    ASSERT_EQ(got.size(), 2u);
    EXPECT_NEAR(got[0], 0.25, DoubleRootTol(p, 0.25));
    EXPECT_NEAR(got[1], 0.75, DoubleRootTol(p, 0.75));
  }
  expect_double(FromRoots({1.0, 1.0}), 0.0, 3.0, {1.0}, 1.0);
  expect_double(FromRoots({1.0, 1.0}, -2.0), 0.0, 3.0, {1.0}, 1.0);
  expect_double(FromRoots({-3.0, 1.0, 1.0, 4.0}, 0.5), -4.0, 5.0, {-3.0, 1.0, 4.0}, 1.0);
}

TEST(PolyRootsInTest, FlatZeroRegionNeverReportsMoreThanDegreeRoots) {
  // Contract: `roots` needs room for `degree` values only. Near a multiple root (or a tight
  // cluster) the computed p is exactly 0 on a whole interval, e.g. for p = (x - 1)^2 =
  // x^2 - 2x + 1 Horner gives exactly 0 for |x - 1| < ~1e-8 (1 - d^2 rounds to 1). When the
  // interval ends and the critical points all lie in that region, every breakpoint is a "root".
  // Roots() checks n <= degree and that nothing is written past n (its buffer has room for 16).
  const Poly p = FromRoots({1.0, 1.0});
  ASSERT_EQ(PolyEval(p.c.data(), 2, 1.0 - 1e-9), 0.0) << "test premise: flat in floating point";
  ASSERT_EQ(PolyEval(p.c.data(), 2, 1.0 + 1e-9), 0.0) << "test premise: flat in floating point";
  std::vector<double> got = Roots(p, 1.0 - 1e-9, 1.0 + 1e-9);
  EXPECT_FALSE(got.empty());
  for (double x : got) EXPECT_EQ(PolyEval(p.c.data(), 2, x), 0.0);  // zeros of the computed p

  // A cubic and a quartic with a cluster of roots ~1e-7 apart (found by random search; the
  // coefficients are FromRoots of the cluster, written exactly): same failure mode.
  const Poly cubic = FromCoeffs(
      {-0x1.261ca52989563p-1, 0x1.095abaa1c5dd3p+1, -0x1.3f36305790c11p+1, 0x1p+0});
  got = Roots(cubic, 0x1.a99d50ee78e7fp-1, 0x1.a99da8d73949p-1);
  EXPECT_FALSE(got.empty());
  const Poly quartic = FromCoeffs({0x1.8190cc952fa74p+1, -0x1.24ab2d5a33fc8p+3,
                                   0x1.4d3b22c8f3084p+3, -0x1.51420187a6a64p+2, 0x1p+0});
  got = Roots(quartic, 0x1.5141d1c5fe715p+0, 0x1.51426d9f91016p+0);
  EXPECT_FALSE(got.empty());
}

TEST(PolyRootsInTest, ScaleRanges) {
  // Roots ~1e-4: coefficients span 1e-15 .. 1; relative accuracy must not suffer.
  const Poly small = FromRoots({1e-4, 2.5e-4, 6e-4, 9e-4});
  ExpectRoots(small, 0.0, 1e-3, {1e-4, 2.5e-4, 6e-4, 9e-4});
  for (double r : {1e-4, 2.5e-4, 6e-4, 9e-4}) EXPECT_LT(RootTol(small, r), 1e-12 * r);
  // Roots ~1e3: coefficients span 1 .. 1e13.
  const Poly large = FromRoots({1000.0, 1300.0, 2500.0, 4000.0}, 1e-9);
  ExpectRoots(large, 0.0, 5000.0, {1000.0, 1300.0, 2500.0, 4000.0});
  for (double r : {1000.0, 1300.0, 2500.0, 4000.0}) EXPECT_LT(RootTol(large, r), 1e-12 * r);
  // Both scales in one polynomial.
  const Poly mixed = FromRoots({1e-4, 3e-4, 1e3, 2e3});
  ExpectRoots(mixed, 0.0, 3000.0, {1e-4, 3e-4, 1e3, 2e3});
  ExpectRoots(mixed, 0.0, 1.0, {1e-4, 3e-4});
  ExpectRoots(mixed, 0.0, 2e-4, {1e-4});
  for (double r : {1e-4, 3e-4, 1e3, 2e3}) EXPECT_LT(RootTol(mixed, r), 1e-11 * r);
}

// ---------------------------------------------------------------------------------------------
// Degenerate degrees

TEST(PolyRootsInTest, ZeroLeadingCoefficientsLowerTheDegree) {
  // A quartic array that is really a quadratic / cubic / linear polynomial gives the same
  // answer, bit for bit, as the lower-degree call (it is the same polynomial).
  const Poly quad = FromRoots({0.3, 1.7}, 2.0);
  Poly quad4 = quad;
  quad4.degree = 4;  // c[3] == c[4] == 0
  EXPECT_EQ(Roots(quad4, 0.0, 2.0), Roots(quad, 0.0, 2.0));
  ExpectRoots(quad4, 0.0, 2.0, {0.3, 1.7});
  EXPECT_EQ(FirstDown(quad4, 0.0, 2.0), FirstDown(quad, 0.0, 2.0));

  const Poly cubic = FromRoots({-0.4, 0.3, 1.7});
  Poly cubic4 = cubic;
  cubic4.degree = 4;
  ExpectRoots(cubic4, -1.0, 2.0, {-0.4, 0.3, 1.7});

  Poly lin4 = FromCoeffs({-0.3, 2.0, 0.0, 0.0, 0.0});
  ExpectRoots(lin4, 0.0, 1.0, {0.15});
  ExpectRoots(lin4, 0.2, 1.0, {});
  EXPECT_NEAR(FirstDown(FromCoeffs({0.3, -2.0, 0.0, 0.0, 0.0}), 0.0, 1.0), 0.15,
              RootTol(lin4, 0.15));

  // Negative zeros are zeros too.
  ExpectRoots(FromCoeffs({-0.3, 2.0, -0.0, 0.0, -0.0}), 0.0, 1.0, {0.15});

  // Constant and zero polynomials have no roots and no crossings.
  EXPECT_TRUE(Roots(FromCoeffs({1.0, 0.0, 0.0, 0.0, 0.0}), -1.0, 1.0).empty());
  EXPECT_TRUE(Roots(FromCoeffs({-1.0, 0.0, 0.0}), -1.0, 1.0).empty());
  EXPECT_TRUE(Roots(FromCoeffs({0.0, 0.0, 0.0, 0.0, 0.0}), -1.0, 1.0).empty());
  EXPECT_EQ(FirstDown(FromCoeffs({1.0, 0.0, 0.0, 0.0, 0.0}), -1.0, 1.0), kInf);
  EXPECT_EQ(FirstDown(FromCoeffs({-1.0, 0.0, 0.0, 0.0, 0.0}), -1.0, 1.0), kInf);
}

TEST(PolyRootsInTest, TinyLeadingCoefficientsActLikeTheLowerDegree) {
  // Adding eps4 x^4 + eps3 x^3 with |eps| = 1e-30 moves a root in [0, 2] by at most
  // ~1e-30 * 16 / |p'| ~ 1e-29: far below RootTol, so the answer is the quadratic's.
  const Poly quad = FromRoots({0.3, 1.7}, 2.0);
  for (double e4 : {1e-30, -1e-30, 0.0}) {
    for (double e3 : {1e-30, -1e-30, 0.0}) {
      if (e4 == 0.0 && e3 == 0.0) continue;
      Poly p = quad;
      p.c[3] = e3;
      p.c[4] = e4;
      p.degree = 4;
      SCOPED_TRACE(testing::Message() << "e3 " << e3 << " e4 " << e4);
      ExpectRoots(p, 0.0, 2.0, {0.3, 1.7});
      ExpectRoots(p, -100.0, 100.0, {0.3, 1.7});
      EXPECT_NEAR(FirstDown(p, 0.0, 2.0), 0.3, RootTol(quad, 0.3));
      EXPECT_EQ(FirstDown(p, 1.0, 2.0), kInf);  // only the up-crossing at 1.7 there
    }
  }
  // Linear plus 1e-30 x^4: one root at 0.15 in a modest interval. The quartic also has a real
  // root at -(2e30)^(1/3) ~ -1.26e10; it must appear only when the interval reaches that far.
  const Poly lin = FromCoeffs({-0.3, 2.0, 0.0, 0.0, 1e-30});
  ExpectRoots(lin, -1.0, 1.0, {0.15});
  ExpectRoots(lin, -1e3, 1e3, {0.15});
  // Far root: 1e-30 x^4 + 2x - 0.3 = 0, x^3 = -(2 - 0.3/x)/1e-30; two fixed-point steps from
  // -cbrt(2e30) are exact to far below RootTol (the correction is 1e-11 relative).
  double far = -std::cbrt(2e30);
  for (int i = 0; i < 3; ++i) far = -std::cbrt((2.0 - 0.3 / far) / 1e-30);
  ExpectRoots(lin, -1e11, 1e11, {far, 0.15});
}

// ---------------------------------------------------------------------------------------------
// Randomized cross-check against Eigen's companion-matrix solver

TEST(PolyRootsInTest, RandomizedAgainstEigenPolynomialSolver) {
  std::mt19937_64 rng(0x5eed2024);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int checked_roots = 0, checked_crossings = 0;
  double worst_ratio = 0.0, worst_residual = 0.0;
  for (int trial = 0; trial < 4000; ++trial) {
    const int degree = 1 + static_cast<int>(rng() % 4);
    const int n_real = 1 + static_cast<int>(rng() % degree);
    // Cofactor of degree (degree - n_real) with random coefficients in [-10, 10] (its roots may
    // be real or complex, inside or outside the interval), times the real-root factors.
    std::vector<double> cof(degree - n_real + 1);
    for (double& v : cof) v = -10.0 + 20.0 * unit(rng);
    while (std::abs(cof.back()) < 0.1) cof.back() = -10.0 + 20.0 * unit(rng);
    Poly p;
    p.degree = degree - n_real;
    for (int k = 0; k <= p.degree; ++k) p.c[k] = cof[k];
    for (int j = 0; j < n_real; ++j) {
      const double r = 10.0 * unit(rng);
      ++p.degree;
      for (int k = p.degree; k >= 1; --k) p.c[k] = p.c[k - 1] - r * p.c[k];
      p.c[0] = -r * p.c[0];
    }
    const double scale = (rng() % 2 ? 1.0 : -1.0) * std::pow(10.0, -6.0 + 12.0 * unit(rng));
    for (int k = 0; k <= p.degree; ++k) p.c[k] *= scale;
    const double lo = -1.0 + 7.0 * unit(rng);
    const double hi = lo + 0.5 + 7.5 * unit(rng);
    SCOPED_TRACE(testing::Message() << "trial " << trial);

    const std::vector<double> got = Roots(p, lo, hi);

    // Every returned root is a root: |p(x)| (evaluated in long double, so the check adds no
    // noise of its own) <= 16 kEps S(x). Derivation: the sign of the computed p is unreliable
    // only where |p| <= 4.01 kEps S; Refine returns a Newton step from such a point (residual
    // ~ evaluation noise) or one of two adjacent floats bracketing the sign change (residual
    // <= |p'| ulp(x) <= 2 kEps |x p'(x)| <= 8 kEps S for degree 4). 4 + 8 < 16.
    for (double x : got) {
      const double res = std::abs(static_cast<double>(EvalLong(p, x))) / AbsSum(p, x);
      worst_residual = std::max(worst_residual, res / kEps);
      EXPECT_LE(res, 16.0 * kEps) << "x = " << x;
    }

    Eigen::VectorXd ec(p.degree + 1);
    for (int k = 0; k <= p.degree; ++k) ec[k] = p.c[k];
    Eigen::PolynomialSolver<double, Eigen::Dynamic> solver;
    solver.compute(ec);
    bool all_clean = true;  // every root near [lo, hi] is either clearly complex or checked
    std::vector<double> reference;
    for (int i = 0; i < solver.roots().size(); ++i) {
      const std::complex<double> z = solver.roots()[i];
      const double span = hi - lo;
      const bool near_interval = z.real() > lo - 0.1 * span && z.real() < hi + 0.1 * span;
      if (std::abs(z.imag()) > 1e-3 * std::max(1.0, std::abs(z.real()))) continue;  // complex
      if (std::abs(z.imag()) > 1e-9 * std::max(1.0, std::abs(z.real()))) {
        if (near_interval) all_clean = false;  // nearly real: ambiguous, don't judge
        continue;
      }
      // Polish Eigen's root with Newton in long double (64-bit mantissa): the reference is then
      // accurate to ~1e-19 S / |p'|, far below the double-precision tolerance being tested.
      long double r = z.real();
      for (int it = 0; it < 4; ++it) {
        const long double d = DerivLong(p, r);
        if (d == 0.0L) break;
        r -= EvalLong(p, r) / d;
      }
      const double rr = static_cast<double>(r);
      // Simple and well-conditioned: the relative condition number S / |r p'(r)| <= 1e6, i.e.
      // the root is at least ~1e-6 relative away from any other root; and well inside [lo, hi]
      // (1e-6 of the span, >> RootTol, so "inside" is not decided by rounding).
      const double deriv = std::abs(static_cast<double>(DerivLong(p, rr)));
      const bool simple = deriv > 0.0 && AbsSum(p, rr) <= 1e6 * deriv * std::max(std::abs(rr), 1e-3) &&
                          std::abs(rr - z.real()) <= 1e-6 * std::max(1.0, std::abs(rr));
      const bool inside = rr > lo + 1e-6 * span && rr < hi - 1e-6 * span;
      if (!simple) {
        if (near_interval) all_clean = false;
        continue;
      }
      if (!inside) {
        if (std::abs(rr - lo) <= 1e-6 * span || std::abs(rr - hi) <= 1e-6 * span) all_clean = false;
        continue;
      }
      reference.push_back(rr);
      const double tol = RootTol(p, rr);
      double best = kInf;
      for (double x : got) best = std::min(best, std::abs(x - rr));
      worst_ratio = std::max(worst_ratio, best / tol);
      EXPECT_LE(best, tol) << "Eigen root " << rr << " (rel tol " << tol / std::abs(rr)
                           << ") not found; degree " << p.degree << " on [" << lo << ", " << hi
                           << "]";
      ++checked_roots;
    }

    // FirstDownCrossing on the same polynomial: when all roots in and near [lo, hi] are simple
    // and well inside, the answer is the first reference root where p' < 0 (a down-crossing;
    // with simple interior roots p is positive just before it), or +infinity.
    if (all_clean) {
      std::sort(reference.begin(), reference.end());
      double expected = kInf;
      for (double r : reference) {
        if (DerivLong(p, r) < 0.0L) {
          expected = r;
          break;
        }
      }
      const double fdc = FirstDown(p, lo, hi);
      if (expected == kInf) {
        EXPECT_EQ(fdc, kInf);
      } else {
        EXPECT_NEAR(fdc, expected, RootTol(p, expected));
      }
      ++checked_crossings;
    }
  }
  // The filters must leave most of the sample in play, or the cross-check is hollow.
  EXPECT_GT(checked_roots, 2500);
  EXPECT_GT(checked_crossings, 3000);
  RecordProperty("checked_roots", checked_roots);
  RecordProperty("checked_crossings", checked_crossings);
  std::printf("[ info ] %d roots, %d crossings checked; worst |err|/RootTol %.3g, worst residual "
              "%.3g kEps*S\n",
              checked_roots, checked_crossings, worst_ratio, worst_residual);
}

// ---------------------------------------------------------------------------------------------
// FirstDownCrossing

TEST(FirstDownCrossingTest, ReturnsFirstPositiveToNonpositiveCrossing) {
  // (x - 1)(x - 3): positive, down at 1, up at 3.
  const Poly p = FromRoots({1.0, 3.0});
  EXPECT_NEAR(FirstDown(p, -0.5, 5.0), 1.0, RootTol(p, 1.0));
  EXPECT_EQ(FirstDown(p, 2.0, 5.0), kInf);  // only the up-crossing at 3
  // Quartic with two down-crossings (0.4 and 2.6): the first one.
  const Poly q = FromRoots({0.4, 1.3, 2.6, 3.9});
  EXPECT_NEAR(FirstDown(q, 0.0, 5.0), 0.4, RootTol(q, 0.4));
  EXPECT_NEAR(FirstDown(q, 0.5, 5.0), 2.6, RootTol(q, 2.6));
  // Negative leading coefficient: p > 0 on (0.4, 1.3), so from 0.5 the first down is 1.3.
  const Poly nq = FromRoots({0.4, 1.3, 2.6, 3.9}, -1.0);
  EXPECT_NEAR(FirstDown(nq, 0.5, 5.0), 1.3, RootTol(nq, 1.3));
  // Down-crossing at the interval end, p exactly zero there.
  EXPECT_EQ(FirstDown(FromRoots({1.0, 3.0}), 0.0, 1.0), 1.0);
}

TEST(FirstDownCrossingTest, InfinityWhenPStaysPositive) {
  EXPECT_EQ(FirstDown(FromCoeffs({1.0, 0.0, 1.0}), -10.0, 10.0), kInf);
  // (x - 1)^2 + 1e-12: minimum 1e-12 at x = 1, far above the ~1e-16 evaluation noise there.
  EXPECT_EQ(FirstDown(FromCoeffs({1.0 + 1e-12, -2.0, 1.0}), 0.0, 3.0), kInf);
  EXPECT_EQ(FirstDown(FromCoeffs({3.0, 0.0, -1.0, 0.0, 0.25}), -10.0, 10.0), kInf);  // min 2
  // Roots exist but outside the interval.
  EXPECT_EQ(FirstDown(FromRoots({1.0, 3.0}), 3.5, 10.0), kInf);
  EXPECT_EQ(FirstDown(FromRoots({1.0, 3.0}), -5.0, 0.5), kInf);
}

TEST(FirstDownCrossingTest, SkipsInitialNonpositiveRegion) {
  // (x-1)(x-2)(x-3): negative before 1, positive on (1, 2), negative on (2, 3).
  const Poly c = FromRoots({1.0, 2.0, 3.0});
  EXPECT_NEAR(FirstDown(c, 0.0, 4.0), 2.0, RootTol(c, 2.0));   // p(0) < 0: skip the up at 1
  EXPECT_NEAR(FirstDown(c, 1.0, 4.0), 2.0, RootTol(c, 2.0));   // p(lo) == 0 exactly
  EXPECT_EQ(FirstDown(c, 2.5, 4.0), kInf);                     // p(lo) < 0, only an up
  EXPECT_EQ(FirstDown(c, 2.0, 4.0), kInf);                     // p(lo) == 0 then negative
  // Quartic: negative at 1.5, up at 2, down at 3.
  const Poly q = FromRoots({1.0, 2.0, 3.0, 4.0});
  EXPECT_NEAR(FirstDown(q, 1.5, 5.0), 3.0, RootTol(q, 3.0));
  EXPECT_EQ(FirstDown(q, 3.5, 5.0), kInf);
  // p(lo) == 0 with p going negative is not a crossing "from positive".
  EXPECT_EQ(FirstDown(FromRoots({1.0, 3.0}), 1.0, 2.5), kInf);
}

TEST(FirstDownCrossingTest, TangentialTouchFromAboveWithExactZeroCounts) {
  // (x - 1)^2: positive, touches 0 exactly at the critical point 1.
  EXPECT_EQ(FirstDown(FromRoots({1.0, 1.0}), 0.0, 3.0), 1.0);
  // -(x - 0.5)^2 (x - 2): positive except a touch at 0.5 and a real down-crossing at 2.
  EXPECT_EQ(FirstDown(FromRoots({0.5, 0.5, 2.0}, -1.0), 0.0, 3.0), 0.5);
  // (x - 0.25)^2 (x - 0.75)^2 >= 0 touches twice. The computed critical point need not be the
  // dyadic root itself (here Newton on p' lands 1 ulp above 0.25, where p' and p both evaluate
  // to exactly 0), so: p exactly 0 at the answer, and within DoubleRootTol of the touch.
  const Poly two = FromRoots({0.25, 0.25, 0.75, 0.75});
  for (const auto& [lo, touch] : {std::pair{0.0, 0.25}, std::pair{0.3, 0.75}}) {
    const double x = FirstDown(two, lo, 1.0);
    EXPECT_NEAR(x, touch, DoubleRootTol(two, touch));
    EXPECT_EQ(PolyEval(two.c.data(), 4, x), 0.0);
  }
  // A touch from below (p <= 0 around it) is not a downward crossing.
  EXPECT_EQ(FirstDown(FromRoots({1.0, 1.0}, -1.0), 0.0, 3.0), kInf);
  EXPECT_EQ(FirstDown(FromRoots({0.5, 0.5, 2.0}), 0.0, 1.9), kInf);
}

TEST(FirstDownCrossingTest, UpCrossingIsNeverReturned) {
  EXPECT_EQ(FirstDown(FromRoots({1.0}), 0.0, 2.0), kInf);
  EXPECT_EQ(FirstDown(FromRoots({1.0, 1.0, 1.0}), 0.0, 2.0), kInf);  // triple root, up
  EXPECT_EQ(FirstDown(FromRoots({1.0, 1.0, 1.0}, -1.0), 0.0, 2.0), 1.0);  // triple, down
  EXPECT_EQ(FirstDown(FromRoots({0.3, 0.7}, -1.0), 0.0, 0.5), kInf);  // up at 0.3
  const Poly q = FromRoots({0.3, 0.6, 0.9, 1.2}, -1.0);                   // up 0.3, down 0.6
  EXPECT_NEAR(FirstDown(q, 0.0, 0.9), 0.6, RootTol(q, 0.6));
  EXPECT_EQ(FirstDown(q, 0.7, 1.0), kInf);  // up at 0.9 only
}

// The Bernstein proof on hand-made cases: a clear minimum is proved, one at the margin's scale
// or below zero is not, and neither is a touch (a double root) nor a root at an end.
TEST(ProvablyPositiveTest, ProvesClearMinimaOnly) {
  const auto proved = [](const Poly& p, double hi) {
    return ProvablyPositive(p.c.data(), p.degree, hi);
  };
  EXPECT_TRUE(proved(FromCoeffs({0.55, -1.0, 1.0}), 1.0));          // (x - 0.5)^2 + 0.3
  // (x - 0.5)^2 + 0.01 > 0 too, but its control polygon dips below zero: not proved (a bound).
  EXPECT_FALSE(proved(FromCoeffs({0.26, -1.0, 1.0}), 1.0));
  EXPECT_TRUE(proved(FromCoeffs({1.0, 2.0, 3.0, 4.0, 5.0}), 10.0));  // all coefficients > 0
  EXPECT_TRUE(proved(FromCoeffs({2.0, 0.0, -1.0, 0.0, 0.25}), 1.5));  // (x^2 - 2)^2 / 4 + 1
  // (x - 0.5)^2 + e on [0, 0.5]: its Bernstein coefficients there are 0.25 + e, e, e, so only
  // the minimum's height decides (the margin is 1e-12 of the largest scaled coefficient, 0.5).
  EXPECT_FALSE(proved(FromCoeffs({0.25 - 1e-14, -1.0, 1.0}), 0.5));   // min just below zero
  EXPECT_FALSE(proved(FromCoeffs({0.25, -1.0, 1.0}), 0.5));           // a touch at 0.5
  EXPECT_FALSE(proved(FromCoeffs({0.25 + 1e-13, -1.0, 1.0}), 0.5));   // above zero, in the margin
  EXPECT_TRUE(proved(FromCoeffs({0.25 + 1e-11, -1.0, 1.0}), 0.5));    // above the margin
  // The margin itself (1e-12 of the largest coefficient): 1e-13 + x is positive on [0, 1], but
  // its least Bernstein coefficient does not clear the margin; 1e-11 + x does.
  EXPECT_FALSE(proved(FromCoeffs({1e-13, 1.0}), 1.0));
  EXPECT_TRUE(proved(FromCoeffs({1e-11, 1.0}), 1.0));
  EXPECT_FALSE(proved(FromRoots({2.0, 3.0}), 2.0));                   // a root at the end
  EXPECT_FALSE(proved(FromCoeffs({-1.0, 0.0, 5.0}), 1.0));            // negative at 0
  EXPECT_FALSE(proved(FromCoeffs({1.0, kInf}), 1.0));                 // not finite
}

// Pairs of balls passing near each other (the engine's common case: a neighbour moving apart,
// or missing by a little): whether a contact is found must match the quartic's true minimum
// over the window, computed from the real roots of p' by Eigen. FirstDownCrossing skips the
// search where the Bernstein coefficients prove p > 0; a pair it skips wrongly would show here
// as a contact missed.
TEST(FirstDownCrossingTest, NearMissesAndNearHitsAgainstTheTrueMinimum) {
  std::mt19937_64 rng(0x6e6172);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int hits = 0, misses = 0, proofs = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    // Relative position 2R plus a gap of 1 nm to 10 cm, speeds up to 5 m/s, accelerations of
    // the cloth (up to 5 m/s^2), windows of 1 ms to 2 s.
    const double gap = std::pow(10.0, -9.0 + 8.0 * (0.5 + 0.5 * unit(rng)));
    const double angle = 3.141592653589793 * unit(rng);
    const Eigen::Vector2d dp = (0.05715 + gap) * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    const Eigen::Vector2d dv = 5.0 * std::pow(10.0, -4.0 * (0.5 + 0.5 * unit(rng))) *
                               Eigen::Vector2d(unit(rng), unit(rng));
    const Eigen::Vector2d da = 5.0 * Eigen::Vector2d(unit(rng), unit(rng));
    const double S = std::pow(10.0, -3.0 + 3.3 * (0.5 + 0.5 * unit(rng)));
    const double d = 0.05715;
    const double c[5] = {(dp.norm() - d) * (dp.norm() + d), 2.0 * dv.dot(dp),
                         dv.squaredNorm() + da.dot(dp), da.dot(dv), 0.25 * da.squaredNorm()};
    // The true minimum over [0, S]: at an end or at a real root of p' inside.
    double lowest = std::min(PolyEval(c, 4, 0.0), PolyEval(c, 4, S));
    Eigen::Matrix<double, 4, 1> deriv;
    for (int k = 1; k <= 4; ++k) deriv[k - 1] = k * c[k];
    if (deriv[3] != 0.0) {
      Eigen::PolynomialSolver<double, 3> solver(deriv);
      for (const auto& z : solver.roots()) {
        if (std::abs(z.imag()) <= 1e-12 * (1.0 + std::abs(z.real())) && z.real() > 0.0 &&
            z.real() < S) {
          lowest = std::min(lowest, PolyEval(c, 4, z.real()));
        }
      }
    }
    // Clear cases only: a minimum well away from zero against the size of the terms.
    double scale = 0.0;
    for (int k = 0; k <= 4; ++k) scale = std::max(scale, std::abs(c[k]) * std::pow(S, k));
    const double x = FirstDownCrossing(c, 4, 0.0, S);
    const bool proved = ProvablyPositive(c, 4, S);
    if (proved) {
      // A proof of p > 0 must never meet a p that goes negative (or a crossing found).
      EXPECT_GT(lowest, 0.0) << "trial " << trial << ": proved positive, min " << lowest;
      ++proofs;
    }
    if (lowest > 1e-9 * scale) {
      EXPECT_EQ(x, kInf) << "trial " << trial << ": p > 0 on the window, min " << lowest;
      ++misses;
    } else if (lowest < -1e-9 * scale) {
      EXPECT_LT(x, kInf) << "trial " << trial << ": p reaches " << lowest << " on [0, " << S
                         << "], yet no crossing";
      if (x < kInf) {
        EXPECT_LE(std::abs(PolyEval(c, 4, x)), 1e-9 * scale) << "trial " << trial;
      }
      ++hits;
    }
  }
  // Both kinds must be well represented for the test to mean anything, and the early-out must
  // answer most misses (it is what makes them cheap).
  EXPECT_GT(hits, 2000);
  EXPECT_GT(misses, 2000);
  EXPECT_GT(proofs, 0.85 * misses);  // measured 93 %
  std::printf("near passes: %d contacts, %d misses checked, %d proved positive\n", hits, misses,
              proofs);
}

// A decelerating approach, x(s) = x0 - v s + a s^2 / 2 with a lateral offset h: p = x^2 + h^2
// - d^2 is convex while x > 0 (p'' = 2 (x'^2 + a x)), the case FirstDownCrossing answers by
// Newton's method from 0 without critical points. Against the closed form of the first contact,
// x = L = sqrt(d^2 - h^2) at s = 2 (x0 - L) / (v + sqrt(v^2 - 2 a (x0 - L))) (the root of the
// stored coefficients, near it, is the reference); and misses (the approach stops short of L),
// both down to grazes 1e-6 of the speed either side.
TEST(FirstDownCrossingTest, ConvexApproachesMatchTheClosedForm) {
  std::mt19937_64 rng(0x636f6e76);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double d = 0.05715;
  for (int trial = 0; trial < 5000; ++trial) {
    const double h = d * 0.99 * unit(rng);
    const double L = std::sqrt(d * d - h * h);
    const double x0 = L + std::pow(10.0, -7.0 + 6.0 * unit(rng));  // 0.1 um to 10 cm to go
    const double a = 0.01 + 5.0 * unit(rng);
    // x > 0 up to the stop keeps p convex on the whole window [0, v / a]: v < v_max.
    const double v_hit = std::sqrt(2.0 * a * (x0 - L)), v_max = std::sqrt(2.0 * a * x0);
    const bool hit = trial % 2 == 0;
    // Speeds 1e-6 to 0.1 of v_hit above it (a hit, grazing at the near end) or below it (a
    // miss, as near): log-spaced, so that grazes are well represented. 1.1 v_hit < v_max.
    const double v = v_hit * (1.0 + (hit ? 1.0 : -1.0) * std::pow(10.0, -6.0 + 5.0 * unit(rng)));
    ASSERT_LT(v, v_max) << "trial " << trial << ": test premise (x > 0 on the window)";
    const double S = v / a;
    const Poly p = FromCoeffs({(x0 - d) * (x0 + d) + h * h, -2.0 * x0 * v, v * v + a * x0,
                               -a * v, 0.25 * a * a});
    const double d2[3] = {2.0 * p.c[2], 6.0 * p.c[3], 12.0 * p.c[4]};
    ASSERT_TRUE(ProvablyPositive(d2, 2, S)) << "trial " << trial << ": not the convex case";
    const double x = FirstDown(p, 0.0, S);
    if (hit) {
      // The closed form, then polished by Newton in long double on the stored coefficients,
      // whose rounding moves the root (by about 1e-11 of it for a contact 0.1 um away, and up
      // to 4e-9 for a graze 1e-6 of the speed inside: near a double root it is ill-conditioned).
      // That the polish stays near the closed form only checks the reference (the same root,
      // not the next one); the code is held to the reference itself, below.
      const double closed = 2.0 * (x0 - L) / (v + std::sqrt(v * v - 2.0 * a * (x0 - L)));
      long double r = closed;
      for (int it = 0; it < 4; ++it) {
        long double f = p.c[4], df = 0.0L;
        for (int k = 3; k >= 0; --k) {
          df = df * r + f;
          f = f * r + p.c[k];
        }
        r -= f / df;
      }
      const double want = static_cast<double>(r);
      ASSERT_NEAR(want, closed, 1e-7 * closed) << "trial " << trial << ": test premise";
      EXPECT_NEAR(x, want, RootTol(p, want)) << "trial " << trial;
    } else {
      EXPECT_EQ(x, kInf) << "trial " << trial << ": stops " << x0 - v * v / (2.0 * a) - L
                         << " m short";
    }
  }
  // A cubic: -(x - 1)(x - 2)(x - 3) is positive at 0 with p'' = 12 - 6x > 0 on [0, 1.5], so
  // the same path answers its first root, 1; over [0, 0.9] there is none.
  const Poly cubic = FromRoots({1.0, 2.0, 3.0}, -1.0);
  const double d2[2] = {2.0 * cubic.c[2], 6.0 * cubic.c[3]};
  ASSERT_TRUE(ProvablyPositive(d2, 1, 1.5));
  EXPECT_NEAR(FirstDown(cubic, 0.0, 1.5), 1.0, RootTol(cubic, 1.0));
  EXPECT_EQ(FirstDown(cubic, 0.0, 0.9), kInf);
}

// ---------------------------------------------------------------------------------------------
// The physical case: ball-ball contact times

constexpr double kR = 0.028575;  // pool ball radius, m
constexpr double kD = 2.0 * kR;  // center distance at contact

// |dp + dv s + 0.5 da s^2|^2 - (2R)^2 as a quartic in s.
Poly GapQuartic(const Eigen::Vector3d& dp, const Eigen::Vector3d& dv, const Eigen::Vector3d& da) {
  const Eigen::Vector3d half_a = 0.5 * da;
  return FromCoeffs({dp.squaredNorm() - kD * kD, 2.0 * dp.dot(dv),
                     dv.squaredNorm() + 2.0 * dp.dot(half_a), 2.0 * dv.dot(half_a),
                     half_a.squaredNorm()});
}

TEST(BallContactTest, HeadOnApproachFromTenCentimetres) {
  // Surface gap 0.1 m, closing at 1 m/s, no acceleration: the center distance kD + 0.1 - s
  // reaches kD at s = 0.1. The quartic is really (kD + 0.1 - s)^2 - kD^2 (c3 = c4 = 0 exactly).
  const Poly p = GapQuartic({kD + 0.1, 0.0, 0.0}, {-1.0, 0.0, 0.0}, Eigen::Vector3d::Zero());
  ASSERT_EQ(p.c[3], 0.0);
  ASSERT_EQ(p.c[4], 0.0);
  // Tolerance: kD + 0.1 and c0 are rounded (moves the root by <= ~1 u, as |p'(0.1)| = 2 kD and
  // |dc0| <= ~3 u S); evaluation noise 2 u S / |p'| with S(0.1) ~ 0.063, |p'| = 0.1143, i.e.
  // ~1.1 u; plus <= 4 kEps |s| from Refine's stopping rule. Sum ~ 12 u |s| = 6 kEps * 0.1 ->
  // 4e-15 relative, generously rounded up from the expected ~1e-15.
  const double s = FirstDown(p, 0.0, 1.0);
  EXPECT_NEAR(s, 0.1, 4e-15 * 0.1);
  // The other root (separating after passing through) is at 0.1 + 2 kD = 0.2143.
  const std::vector<double> roots = Roots(p, 0.0, 1.0);
  ASSERT_EQ(roots.size(), 2u);
  EXPECT_NEAR(roots[0], 0.1, 4e-15 * 0.1);
  EXPECT_NEAR(roots[1], 0.1 + 2.0 * kD, RootTol(p, 0.1 + 2.0 * kD));
  // Interval ending before contact: no contact.
  EXPECT_EQ(FirstDown(p, 0.0, 0.0999), kInf);

  // Same, decelerating at 0.5 m/s^2 (true quartic in s via the |.|^2 of a parabola):
  // kD + 0.1 - s + 0.25 s^2 = kD  ->  s = (1 - sqrt(1 - 0.1)) / 0.5 = 0.2 / (1 + sqrt(0.9)).
  const Poly pa = GapQuartic({kD + 0.1, 0.0, 0.0}, {-1.0, 0.0, 0.0}, {0.5, 0.0, 0.0});
  const double sa = 0.2 / (1.0 + std::sqrt(0.9));
  EXPECT_NEAR(FirstDown(pa, 0.0, 1.0), sa, RootTol(pa, sa));
}

TEST(BallContactTest, EqualAccelerationsReduceToAQuadratic) {
  // Both balls decelerate identically (same cloth, same direction of motion is not needed: only
  // the accelerations being equal), so da = a2 - a1 is exactly 0 and the quartic is a quadratic
  // |A + B s|^2 - kD^2 with closed form s = (|A|^2 - kD^2) / (-(A.B) + sqrt((A.B)^2 -
  // |B|^2 (|A|^2 - kD^2))) (the cancellation-free form of the smaller root).
  const Eigen::Vector3d a1(-0.35, 0.12, 0.0), a2 = a1;
  const Eigen::Vector3d dp(0.4, 0.03, 0.0), dv(-1.5, 0.02, 0.0);
  const Poly p = GapQuartic(dp, dv, a2 - a1);
  ASSERT_EQ(p.c[3], 0.0);
  ASSERT_EQ(p.c[4], 0.0);
  const double ab = dp.dot(dv), bb = dv.squaredNorm(), c = dp.squaredNorm() - kD * kD;
  const double s_closed = c / (-ab + std::sqrt(ab * ab - bb * c));
  // RootTol bounds the solver's error; the closed form (a handful of well-conditioned
  // operations) adds a few u relative, covered by RootTol's 8 kEps |r| term.
  const double s = FirstDown(p, 0.0, 1.0);
  EXPECT_NEAR(s, s_closed, RootTol(p, s_closed));
  EXPECT_GT(s, 0.2);  // sanity on the geometry: ~0.34 m to close at ~1.5 m/s
  Poly quad = p;
  quad.degree = 2;
  EXPECT_EQ(s, FirstDown(quad, 0.0, 1.0));  // same polynomial, same answer
}

// Grazing geometry for (c) and (d): ball 2 at perpendicular offset b from ball 1's line,
// relative motion along x: x(s) = -0.5 + 2 s - 0.2 s^2 (decelerating), y = b. The center
// distance is minimal (= b) when x(s) = 0, at s* = (2 - sqrt(3.6)) / 0.4 ~ 0.2566.
Poly GrazeQuartic(double b) {
  return GapQuartic({-0.5, b, 0.0}, {2.0, 0.0, 0.0}, {-0.4, 0.0, 0.0});
}

TEST(BallContactTest, GrazingMissByOneNanometre) {
  // Closest approach kD + 1e-9: min of p is b^2 - kD^2 ~ 2 kD 1e-9 = 1.1e-10, against evaluation
  // noise ~4 kEps S ~ 1e-15 (S ~ 1 near s*): clearly positive, so no contact and no roots.
  const Poly p = GrazeQuartic(kD + 1e-9);
  ASSERT_NE(p.c[4], 0.0);  // a genuine quartic
  EXPECT_EQ(FirstDown(p, 0.0, 1.0), kInf);
  EXPECT_TRUE(Roots(p, 0.0, 1.0).empty());
  EXPECT_EQ(FirstDown(p, 0.0, 20.0), kInf);  // also past the second x(s) = 0 at s ~ 9.74
}

TEST(BallContactTest, NearGrazeHitByOneNanometre) {
  // Closest approach b = kD - 1e-9: contact when |x(s)| = h = sqrt(kD^2 - b^2), first on the
  // approach side x(s) = -h: 0.2 s^2 - 2 s + (0.5 - h) = 0, smaller root (cancellation-free)
  // s = 2 (0.5 - h) / (2 + sqrt(4 - 0.8 (0.5 - h))). h^2 = (kD - b)(kD + b) is computed from the
  // actual double b, with kD - b exact (Sterbenz), so the closed form is accurate to a few u.
  const double b = kD - 1e-9;
  const Poly p = GrazeQuartic(b);
  const double h = std::sqrt((kD - b) * (kD + b));
  const double s_closed = 2.0 * (0.5 - h) / (2.0 + std::sqrt(4.0 - 0.8 * (0.5 - h)));
  // Tolerance derivation: p'(s) = 2 x(s) x'(s) = 2 h |x'| ~ 2 * 1.07e-5 * 1.9 ~ 4e-5 at the
  // contact, S(s) ~ 1, so double-precision evaluation noise (4 kEps S) and coefficient rounding
  // (c0 = 0.25 + b^2 - kD^2 rounds at ~kEps * 0.25, the b^2 - kD^2 cancellation at ~kEps * 3e-3)
  // move the root by ~(4 + 0.3) kEps / 4e-5 ~ 2.4e-11 s: that is RootTol's first term with
  // 16 -> ~4. We use RootTol (~9e-11 s, 3.5e-10 relative) and check it is that small, i.e. the
  // test still distinguishes this time from the closest-approach time s* (~1e-5 s away).
  const double tol = RootTol(p, s_closed);
  EXPECT_LT(tol, 2e-10);
  const double s_star = (2.0 - std::sqrt(3.6)) / 0.4;
  ASSERT_GT(s_star - s_closed, 1e-6);
  const double s = FirstDown(p, 0.0, 1.0);
  EXPECT_NEAR(s, s_closed, tol);
  // Both contact roots (entering and leaving overlap) are found, symmetric about s*.
  const std::vector<double> roots = Roots(p, 0.0, 1.0);
  ASSERT_EQ(roots.size(), 2u);
  EXPECT_NEAR(roots[0], s_closed, tol);
  const double s_leave = 2.0 * (0.5 + h) / (2.0 + std::sqrt(4.0 - 0.8 * (0.5 + h)));
  EXPECT_NEAR(roots[1], s_leave, RootTol(p, s_leave));
}

}  // namespace
}  // namespace sportsim
