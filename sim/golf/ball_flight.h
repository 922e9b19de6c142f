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
// The air and the wind: atmosphere.h. C_D and C_L: aero.h.
//
// Spin decay: tau = r / (2.0e-5 v) (Smits & Smith, Science and Golf II
// (1994), as quoted with SI units by A. M. Nathan, "The effect of spin-down on
// the flight of a baseball" (2008)). Nathan's golf sheet evaluates tau once,
// at the launch speed: SpinDecayModel::kLaunchSpeed (default, air-relative
// launch speed). kInstantaneous integrates dw/dt = -2.0e-5 |u| w / r instead.
//
// Integrators (sim/core/ode; the accuracy contract of
// sim/core/ode/integrator.h):
// - kRk4: classical 4th-order Runge-Kutta at the fixed step accuracy.dt_s
//   (default 1e-3 s, (0, 0.1]). Global error O(dt^4). A tolerance is an
//   InvalidArgument error. A step whose drag/lift rate makes RK4 unstable
//   (rate x dt > 2.5) stops with OutOfRange.
// - kDp45: the embedded 5(4) pair of Dormand & Prince (1980) (local
//   extrapolation, FSAL), with error control per step in the max norm: every
//   component's error estimate must satisfy
//   |err_i| <= tolerance (1 + max(|y_i|, |y_i,new|)) (SI units: m, m/s,
//   rad/s). accuracy.tolerance is required, in (0, 1e-2]; accuracy.max_step_s
//   caps the step (default 0.05 s, (0, 1]); the first trial step comes from
//   the starting-step heuristic of Hairer, Norsett & Wanner. A dt_s is an
//   InvalidArgument error.
// The flight is a sequence of named stages per step (ball_flight.cc):
// TakeStep, StepOntoBreakpoint, LocateApex, LocateLanding, EmitSamples.
// Fit breakpoints (both schemes; aero.h): a step that ends in another piece
// of the fit is cut short onto the crossing (first guess on the step's
// Hermite interpolant, then Newton on the fit variable of the re-taken
// partial step), so no step integrates across a kink; without this RK4 falls
// to order ~1-2 on shots that slow through the drag crisis (Nathan) or whose
// S passes 0.75 near the apex (wedges, Ferguson). An RK4 step cut short is
// followed by the remainder of its grid interval, so the grid k * dt_s is
// kept.
// Landing is the first downward crossing of z = 0: located on the step's
// cubic Hermite interpolant (bracketed root, sim/core/root_find.h, to
// 1e-12 s), then refined by re-taking the partial step from the step start
// (Newton on z; sim/core/ode/event.h), so the reported landing state is the
// integrator's own solution, not the interpolant's. The apex (vz = 0) is
// found the same way.
// Samples between steps are cubic Hermite interpolants of the full state;
// they are exact at step points and O(h^4) accurate in between.
//
// Deterministic: no clocks, no randomness, no unordered containers; the same
// inputs give bit-identical results on the same build.
#ifndef SPORTSIM_SIM_GOLF_BALL_FLIGHT_H_
#define SPORTSIM_SIM_GOLF_BALL_FLIGHT_H_

#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Dense>

#include "absl/status/statusor.h"
#include "sim/core/ode/integrator.h"
#include "sim/golf/aero.h"
#include "sim/golf/atmosphere.h"
#include "sim/golf/golf_ball.h"

namespace sportsim::golf {

/// Effect bits (the convention of sim/core/effects.h): 0 = full physics;
/// every flight effect is on by default, so each bit switches one off. A
/// switched-off effect is skipped, not multiplied by zero.
enum FlightEffect : uint32_t {
  kFlightDisableDrag = 1u << 0,       ///< no aerodynamic drag
  kFlightDisableLift = 1u << 1,       ///< no Magnus lift
  kFlightDisableSpinDecay = 1u << 2,  ///< spin rate stays at its launch value
  kFlightDisableWind = 1u << 3,       ///< still air whatever Wind says
};
/// Every known flight effect bit.
inline constexpr uint32_t kFlightEffectBits =
    kFlightDisableDrag | kFlightDisableLift | kFlightDisableSpinDecay |
    kFlightDisableWind;

enum class SpinDecayModel {
  kLaunchSpeed,    ///< w = w0 exp(-t / tau0), tau0 from the launch air speed
                   ///< (Nathan's golf sheet)
  kInstantaneous,  ///< dw/dt = -c |u| w / r (Smits & Smith's law as an ODE)
};

/// Solver and model options. Defaults: RK4 at 1 ms, full physics.
struct FlightOptions {
  /// kRk4 or kDp45 (the flight supports no other scheme).
  ode::Integrator integrator = ode::Integrator::kRk4;
  /// RK4: dt_s (s; default kDefaultDt, (0, 0.1]). DP45: tolerance (required,
  /// (0, 1e-2]) and max_step_s (s; default kDefaultMaxStep, (0, 1]).
  ode::Accuracy accuracy;
  double sample_interval_s = 0.01;  ///< sample spacing (s); 0 = no samples;
                                    ///< [0, 10]
  double max_flight_time_s = 60.0;  ///< give up (OutOfRange) after (s);
                                    ///< (0, 600]
  double launch_height_m = 0.0;     ///< ball centre height at launch above
                                    ///< the landing plane z = 0 (m); [0, 1000]
  double gravity_mps2 = 9.80665;    ///< g (m/s^2); (0, 100]
  SpinDecayModel spin_decay_model = SpinDecayModel::kLaunchSpeed;
  AeroCoefficients aero = {};       ///< C_D, C_L and decay fit
  uint32_t effects = 0;  ///< FlightEffect bits; 0 = full physics
  /// Polled every kCancelPollSteps steps; returning true stops the flight
  /// with kCancelled (a server's deadline, cancellation or CPU budget).
  std::function<bool()> cancelled;

  /// A dp45 flight's step count is not known up front: it grows with the
  /// aerodynamic rate (a light, large ball is a stiff ODE, and an explicit
  /// pair's step stays near 3.3 / rate). Accepted plus rejected steps stop
  /// here with OutOfRange. Ordinary flights take tens to thousands.
  static constexpr int64_t kMaxAdaptiveSteps = 1'000'000;
  static constexpr int64_t kCancelPollSteps = ode::kPollSteps;

  static constexpr double kDefaultDt = 1e-3;       ///< RK4 step (s)
  static constexpr double kDefaultMaxStep = 0.05;  ///< DP45 largest step (s)
  /// The flight's defaults and ranges for the contract.
  static const ode::AccuracyLimits kLimits;
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
  /// The spin's unit axis (world frame; fixed through the flight): the angular velocity at
  /// landing is landing_spin_rpm * kRpmToRadPerS * spin_axis.
  Eigen::Vector3d spin_axis = Eigen::Vector3d::Zero();
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
/// not landed by max_flight_time_s, if an RK4 step would be unstable, if a
/// dp45 flight needs more than kMaxAdaptiveSteps steps, or if the state
/// becomes non-finite (the message gives the simulated time). kCancelled
/// when options.cancelled says so.
absl::StatusOr<FlightResult> SimulateFlight(const BallSpec& ball,
                                            const LaunchConditions& launch,
                                            const Atmosphere& atmosphere,
                                            const Wind& wind,
                                            const FlightOptions& options);

}  // namespace sportsim::golf

#endif  // SPORTSIM_SIM_GOLF_BALL_FLIGHT_H_
