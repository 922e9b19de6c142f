// Aerodynamic coefficients of a golf ball: the published C_D, C_L fits and
// the breakpoints that split each fit into smooth pieces.
//
// Aerodynamic fits (AeroFit):
// - kFergusonMcNallyMcPhee2022 (default): quadratics in the spin parameter,
//     C_D = 0.1304 + 0.9287 S - 0.8259 S^2,
//     C_L = 0.0504 + 1.2031 S - 1.1490 S^2,
//   from A. Ferguson, W. McNally and J. McPhee, "Golf ball flight dynamics
//   identified from launch-monitor data", Proceedings of the 14th conference
//   of the International Sports Engineering Association (ISEA 2022), doi
//   10.5703/1288284317493: fitted to 1040 measured shots (GCQuad launch
//   conditions, FlightScope X3 carry and apex, Titleist Pro V1) spanning
//   driver to wedge, S = 0.02..0.75. We read the coefficients as printed in
//   a transcription (open-flight/openflight, src/openflight/ballistics.py),
//   not from the paper itself. Outside the fitted range we do not
//   extrapolate the parabolas: S is held at 0.75 above it (both C_D and
//   C_L), C_D is held at its S = 0.02 value below it, and C_L falls
//   linearly to 0 at S = 0 (a ball without spin has no Magnus lift; the
//   quadratic's 0.0504 at S = 0 is a regression intercept, not a measured
//   non-spinning lift). The fit has no Reynolds-number term: it averages
//   over the Re of real shots (about 0.5e5..2.5e5), so the drag crisis
//   below Re ~ 0.7e5 is not modelled separately.
//   With Smits & Smith's spin decay (below), the TrackMan PGA Tour averages
//   (driver to pitching wedge) are matched to ~2-4 % in carry and ~1 yd in
//   apex, with landing angles 1-8 deg shallow; docs/golf-flight.md.
// - kNathan: A. M. Nathan, "Trajectory Calculator: Golf Version"
//   (baseball.physics.illinois.edu/trajectory-calculator-golf.html),
//   workbook TrajectoryCalculatorGolf-v2 (2023-11-29, updated 2025-02-14),
//   which draws on Lyu et al., Proceedings 2(6), 238 (2018) (WSU
//   measurements) and P. Dewhurst, The Science of the Perfect Swing (2015)
//   pp. 34-35, with the parameters "optimized for 7 clubs, driver through
//   5-iron":
//     C_D = C_D0(Re) + 0.2087217 S,
//     C_D0 = 1.9451114 for Re <= 0.5e5, 0.1324800 for Re >= 1.0e5, linear in
//            Re in between (continuous, with kinks at both ends),
//     C_L = 0.2294096 S^0.4.
//   We read the workbook's formulas through a transcription (a "verification
//   gate source log" stored in a public repository, and a second program
//   that tabulates the same C_D0 points); we did not open the workbook.
//   Nathan's sheet evaluates Re from its own air model (Re = 123,638 at 100
//   mph in its default air); we use Re = rho |u| d / mu from the atmosphere
//   below, so the low-speed drag rise starts at a slightly different speed.
//   It fits driver carry (273 yd against TrackMan's 275) with too little
//   lift and drag at once: apex 21 yd against 32, landing 23 deg against 38,
//   and irons 18-37 yd short; kept for comparison and for games tuned on it.
//
// Breakpoints: each fit is smooth between two breakpoints of one variable
// and has kinks at them: Nathan's C_D0(Re) at re_low and re_high (the
// variable is the Reynolds number), Ferguson et al.'s clamps at S = s_min
// and s_max (the variable is S). A flight steps onto them (ball_flight.h).
#ifndef SPORTSIM_SIM_GOLF_AERO_H_
#define SPORTSIM_SIM_GOLF_AERO_H_

#include "absl/status/status.h"

namespace sportsim::golf {

/// Which published C_D, C_L fit flies the ball (see above).
enum class AeroFit {
  kFergusonMcNallyMcPhee2022,  ///< quadratics in S, driver to wedge (default)
  kNathan,                     ///< C_D0(Re) + k S, C_L = a S^0.4
};

/// Aerodynamic coefficients. `fit` picks the formulas; each fit reads only
/// its own fields. Defaults are the published values (see above).
struct AeroCoefficients {
  AeroFit fit = AeroFit::kFergusonMcNallyMcPhee2022;
  // kFergusonMcNallyMcPhee2022: C = c0 + c1 S + c2 S^2 on [s_min, s_max].
  double cd_c0 = 0.1304, cd_c1 = 0.9287, cd_c2 = -0.8259;  ///< each [-10, 10]
  double cl_c0 = 0.0504, cl_c1 = 1.2031, cl_c2 = -1.1490;  ///< each [-10, 10]
  double s_min = 0.02;  ///< lower end of the fitted S range; (0, s_max)
  double s_max = 0.75;  ///< upper end; (s_min, 10]
  // kNathan:
  double cd_low = 1.9451114;       ///< C_D0 at Re <= re_low; [0, 10]
  double cd_high = 0.1324800;      ///< C_D0 at Re >= re_high; [0, 10]
  double cd_spin = 0.2087217;      ///< dC_D/dS; [0, 10]
  double re_low = 0.5e5;           ///< end of the subcritical plateau; > 0
  double re_high = 1.0e5;          ///< start of the supercritical plateau;
                                   ///< (re_low, 1e7]
  double cl_amplitude = 0.2294096; ///< C_L = cl_amplitude S^cl_exponent;
                                   ///< [0, 10]
  double cl_exponent = 0.4;        ///< [0.1, 2]
  // Both fits (Smits & Smith's spin decay):
  double spin_decay_coefficient = 2.0e-5;  ///< c in tau = r / (c v);
                                           ///< (0, 1e-2]
};

/// C_D(Re, S) of the fit: Ferguson et al.'s quadratic in S (Re unused), or
/// Nathan's piecewise-linear C_D0(Re) plus cd_spin S.
double DragCoefficient(const AeroCoefficients& aero, double reynolds,
                       double spin_parameter);

/// C_L(S) of the fit (0 for S <= 0): Ferguson et al.'s quadratic (linear to
/// 0 below s_min), or Nathan's cl_amplitude S^cl_exponent.
double LiftCoefficient(const AeroCoefficients& aero, double spin_parameter);

/// Checks every field the fit reads (and that Ferguson et al.'s C_D stays
/// non-negative on [s_min, s_max]); InvalidArgument names the first bad one.
absl::Status ValidateAero(const AeroCoefficients& aero);

/// The variable whose breakpoints split a fit into smooth pieces.
enum class FitVariable {
  kReynolds,       ///< Nathan: Re (C_D0 kinks at re_low and re_high)
  kSpinParameter,  ///< Ferguson et al.: S (clamps at s_min and s_max)
};
inline FitVariable FitVariableOf(const AeroCoefficients& aero) {
  return aero.fit == AeroFit::kNathan ? FitVariable::kReynolds : FitVariable::kSpinParameter;
}

/// The lower (upper = false) or upper breakpoint of the fit, in its
/// FitVariable (Re or S).
inline double FitBreakpoint(const AeroCoefficients& aero, bool upper) {
  if (aero.fit == AeroFit::kNathan) return upper ? aero.re_high : aero.re_low;
  return upper ? aero.s_max : aero.s_min;
}

/// Which breakpoints bend the forces in use: Nathan's kinks are in C_D only
/// (so they matter with drag on); Ferguson et al.'s S clamps bend both.
inline bool FitHasKinks(const AeroCoefficients& aero, bool drag, bool lift) {
  return aero.fit == AeroFit::kNathan ? drag : (drag || lift);
}

}  // namespace sportsim::golf

#endif  // SPORTSIM_SIM_GOLF_AERO_H_
