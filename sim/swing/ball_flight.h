// Golf-ball flight: a 3-D point mass under gravity, aerodynamic drag and
// Magnus lift computed on the wind-relative velocity, with exponential spin
// decay, integrated until the ball comes down to the ground (z = 0).
//
// Equations (world frame x downrange, y left, z up; see golf_ball.h):
//   dr/dt = v
//   dv/dt = -g z^ - K C_D |u| u + K C_L |u| (w^ x u),   u = v - wind(z),
//   K = rho A / (2 m),  A = pi r^2,  w^ = the (fixed) spin-axis unit vector,
//   dw/dt = -w / tau   (spin decay; the axis keeps its direction).
// Spin parameter S = r w / |u|; Reynolds number Re = rho |u| d / mu.
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
// Spin decay: tau = r / (2.0e-5 v) (Smits & Smith, Science and Golf II
// (1994), as quoted with SI units by A. M. Nathan, "The effect of spin-down on
// the flight of a baseball" (2008)). Nathan's golf sheet evaluates tau once,
// at the launch speed: SpinDecayModel::kLaunchSpeed (default, air-relative
// launch speed). kInstantaneous integrates dw/dt = -2.0e-5 |u| w / r instead.
//
// Air: station pressure from the sea-level pressure with the ISA barometric
// formula p = p0 (1 - L h / T0)^(g0 M / (R* L)), L = 0.0065 K/m, T0 =
// 288.15 K (U.S. Standard Atmosphere 1976 / ISO 2533); humid-air density
// rho = (p - e) / (R_d T) + e / (R_v T) with vapour pressure e = RH e_s(T) and
// the Buck saturation pressure e_s = 611.21 exp((18.678 - T/234.5) T /
// (257.14 + T)) Pa, T in deg C (A. L. Buck, J. Appl. Meteorol. 20, 1527
// (1981), 1996 coefficients); dynamic viscosity from Sutherland's law
// mu = 1.716e-5 (T / 273.15)^1.5 (273.15 + 110.4) / (T + 110.4) Pa s
// (F. M. White, Viscous Fluid Flow). The air is uniform along the flight
// (a 50 m apex changes rho by about 0.5 %).
//
// Wind: horizontal, one direction, uniform or with a logarithmic height
// profile w(z) = w_ref ln(1 + z / z0) / ln(1 + z_ref / z0) (the neutral
// surface-layer log law, shifted by z0 so it is smooth and zero at the
// ground); z0 = 0.03 m is the "open flat terrain, grass" class of the
// Davenport-Wieringa roughness classification.
//
// Integrators (an explicit accuracy contract):
// - kRk4: classical 4th-order Runge-Kutta at the fixed step dt_s. Global
//   error O(dt^4). `tolerance` must be 0 (asking a fixed-step scheme for a
//   tolerance is an InvalidArgument error). A step whose drag/lift rate
//   makes RK4 unstable (rate x dt > 2.5) stops with OutOfRange.
// - kDormandPrince45: the embedded 5(4) pair of Dormand & Prince,
//   J. Comput. Appl. Math. 6, 19 (1980) (local extrapolation, FSAL), with
//   error control per step: every component's error estimate must satisfy
//   |err_i| <= tolerance (1 + max(|y_i|, |y_i,new|)) (SI units: m, m/s,
//   rad/s). `tolerance` is required, in (0, 1e-2]; dt_s is the first trial
//   step and max_step_s caps the step.
// Fit breakpoints (both schemes): each fit is smooth between two breakpoints
// of one variable and has kinks at them: Nathan's C_D0(Re) at re_low and
// re_high (the variable is the air speed), Ferguson et al.'s clamps at S =
// s_min and s_max (the variable is S). A step that ends in another piece is
// cut short onto the crossing (first guess on the step's Hermite
// interpolant, then Newton on the variable of the re-taken partial step), so
// no step integrates across a kink; without this RK4 falls to order ~1-2 on
// shots that slow through the drag crisis (Nathan) or whose S passes 0.75
// near the apex (wedges, Ferguson). An RK4 step cut short is followed by the remainder of
// its grid interval, so the grid k * dt_s is kept.
// Landing is the first downward crossing of z = 0: located on the step's
// cubic Hermite interpolant (bracketed Newton, to 1e-12 s), then refined by
// re-taking the partial step from the step start (Newton on z), so the
// reported landing state is the integrator's own solution, not the
// interpolant's. The apex (vz = 0) is found the same way: a root of the
// Hermite interpolant of vz, refined on the re-taken partial step.
// Samples between steps are cubic Hermite interpolants of the full state;
// they are exact at step points and O(h^4) accurate in between.
//
// Deterministic: no clocks, no randomness, no unordered containers; the same
// inputs give bit-identical results on the same build.
#ifndef SPORTSIM_SIM_SWING_BALL_FLIGHT_H_
#define SPORTSIM_SIM_SWING_BALL_FLIGHT_H_

#include <cstdint>
#include <vector>

#include <Eigen/Dense>

#include "absl/status/statusor.h"
#include "sim/swing/golf_ball.h"

namespace sportsim::swing {

/// Weather at the course. Default: the ISA sea-level standard atmosphere
/// (15 deg C, 101325 Pa, dry), rho = 1.2250 kg/m^3.
struct Atmosphere {
  double temperature_c = 15.0;     ///< air temperature (deg C); [-60, 60]
  double pressure_pa = 101325.0;   ///< sea-level (QNH-style) pressure (Pa);
                                   ///< [80000, 110000]. For a measured
                                   ///< station pressure set altitude_m = 0.
  double relative_humidity = 0.0;  ///< relative humidity (fraction); [0, 1]
  double altitude_m = 0.0;         ///< course elevation above sea level (m);
                                   ///< [-500, 5000]
};

/// Air properties derived from an Atmosphere.
struct AirProperties {
  double density_kgpm3 = 0.0;        ///< rho (kg/m^3)
  double viscosity_pas = 0.0;        ///< dynamic viscosity mu (Pa s)
  double station_pressure_pa = 0.0;  ///< pressure at the course (Pa)
  double vapour_pressure_pa = 0.0;   ///< partial pressure of water (Pa)
};

/// Air density and viscosity at the course; InvalidArgument on bad fields.
absl::StatusOr<AirProperties> ComputeAirProperties(const Atmosphere& air);

enum class WindProfile {
  kUniform,      ///< the same wind at every height
  kLogarithmic,  ///< w(z) = w_ref ln(1 + z/z0) / ln(1 + z_ref/z0)
};

/// Horizontal wind.
struct Wind {
  double speed_mps = 0.0;   ///< wind speed (at reference_height_m for the
                            ///< log profile) (m/s); [0, 50]
  double toward_deg = 0.0;  ///< direction the air moves TOWARD, + right of
                            ///< the target line (deg): 0 tailwind, 180
                            ///< headwind, 90 left-to-right; [-360, 360]
  WindProfile profile = WindProfile::kUniform;  ///< height profile
  double reference_height_m = 10.0;  ///< z_ref, log profile only (m);
                                     ///< (0, 1000]
  double roughness_length_m = 0.03;  ///< z0, log profile only (m);
                                     ///< (0, reference_height_m)
};

/// Wind velocity at height z (m/s, world frame); z < 0 counts as 0. The wind
/// must be valid (SimulateFlight checks it).
Eigen::Vector3d WindVelocity(const Wind& wind, double height_m);

/// Checks every Wind field (as SimulateFlight does); InvalidArgument names
/// the first bad one.
absl::Status ValidateWind(const Wind& wind);

/// Effects that can be switched off (MuJoCo-style disable bits; 0 = full
/// physics). A switched-off effect is skipped, not multiplied by zero.
enum FlightDisable : uint32_t {
  kFlightDisableDrag = 1u << 0,       ///< no aerodynamic drag
  kFlightDisableLift = 1u << 1,       ///< no Magnus lift
  kFlightDisableSpinDecay = 1u << 2,  ///< spin rate stays at its launch value
  kFlightDisableWind = 1u << 3,       ///< still air whatever Wind says
};
inline constexpr uint32_t kFlightDisableAll =
    kFlightDisableDrag | kFlightDisableLift | kFlightDisableSpinDecay |
    kFlightDisableWind;

enum class FlightIntegrator {
  kRk4,             ///< classical RK4, fixed step, order 4
  kDormandPrince45  ///< adaptive embedded 5(4) pair, error per step
};

enum class SpinDecayModel {
  kLaunchSpeed,    ///< w = w0 exp(-t / tau0), tau0 from the launch air speed
                   ///< (Nathan's golf sheet)
  kInstantaneous,  ///< dw/dt = -c |u| w / r (Smits & Smith's law as an ODE)
};

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

/// Solver and model options. Defaults: RK4 at 1 ms, full physics.
struct FlightOptions {
  FlightIntegrator integrator = FlightIntegrator::kRk4;  ///< scheme
  double dt_s = 1e-3;        ///< RK4 step; DP45 first trial step (s);
                             ///< (0, 0.1]
  double tolerance = 0.0;    ///< DP45 per-step error bound (see above);
                             ///< required in (0, 1e-2] for DP45, must be 0
                             ///< for RK4
  double max_step_s = 0.05;  ///< DP45 largest step (s); [dt_s, 1]
  double sample_interval_s = 0.01;  ///< sample spacing (s); 0 = no samples;
                                    ///< [0, 10]
  double max_flight_time_s = 60.0;  ///< give up (OutOfRange) after (s);
                                    ///< (0, 600]
  double launch_height_m = 0.0;     ///< ball centre height at launch above
                                    ///< the landing plane z = 0 (m); [0, 1000]
  double gravity_mps2 = 9.80665;    ///< g (m/s^2); (0, 100]
  SpinDecayModel spin_decay_model = SpinDecayModel::kLaunchSpeed;
  AeroCoefficients aero = {};       ///< C_D, C_L and decay fit
  uint32_t disabled = 0;  ///< FlightDisable bits switched off; 0 = full
                          ///< physics
};

/// One point of the trajectory, world frame (x downrange, y LEFT, z up).
struct FlightSample {
  double t_s = 0.0;          ///< time since launch (s)
  double x_m = 0.0;          ///< downrange (m)
  double y_m = 0.0;          ///< left of the target line (m)
  double z_m = 0.0;          ///< height above the landing plane (m)
  double vx_mps = 0.0;       ///< (m/s)
  double vy_mps = 0.0;       ///< (m/s)
  double vz_mps = 0.0;       ///< (m/s)
  double speed_mps = 0.0;    ///< ground speed |v| (m/s)
  double spin_rpm = 0.0;     ///< spin rate (rpm)
};

/// Flight summary, samples and solver counters.
struct FlightResult {
  double carry_m = 0.0;             ///< horizontal distance launch->landing (m)
  double carry_downrange_m = 0.0;   ///< its component along the target line
                                    ///< (m)
  double lateral_m = 0.0;           ///< landing offset, + RIGHT of the target
                                    ///< line (m) (= -y)
  double apex_m = 0.0;              ///< greatest height above z = 0 (m)
  double apex_time_s = 0.0;         ///< time of the apex (s)
  double flight_time_s = 0.0;       ///< launch to landing (s)
  double landing_angle_deg = 0.0;   ///< descent angle below the horizontal,
                                    ///< ground-frame velocity (deg)
  double landing_speed_mps = 0.0;   ///< ground speed at landing (m/s)
  double landing_spin_rpm = 0.0;    ///< spin rate at landing (rpm)
  Eigen::Vector3d landing_position_m = Eigen::Vector3d::Zero();    ///< (m)
  Eigen::Vector3d landing_velocity_mps = Eigen::Vector3d::Zero();  ///< (m/s)
  AirProperties air;                ///< the air used
  std::vector<FlightSample> samples;  ///< every sample_interval_s from t = 0,
                                      ///< then the landing point
  int64_t steps = 0;            ///< accepted steps (landing step included)
  int64_t rejected_steps = 0;   ///< DP45 rejected trial steps
  int64_t rhs_evaluations = 0;  ///< derivative evaluations
};

/// Flies the ball from launch to landing. Inputs are validated first
/// (InvalidArgument names the first bad field). OutOfRange if the ball has
/// not landed by max_flight_time_s, if an RK4 step would be unstable, or if
/// the state becomes non-finite (the message gives the simulated time).
absl::StatusOr<FlightResult> SimulateFlight(const BallSpec& ball,
                                            const LaunchConditions& launch,
                                            const Atmosphere& atmosphere,
                                            const Wind& wind,
                                            const FlightOptions& options);

}  // namespace sportsim::swing

#endif  // SPORTSIM_SIM_SWING_BALL_FLIGHT_H_
