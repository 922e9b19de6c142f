// The golf ball's ground phase on a plane of any tilt (SimulateGround) or on a course's terrain
// and surfaces (SimulateGroundOnCourse, below): from a landing (or a putt, or a ball already
// rolling) through bounces, the skid, the roll, the hole, to rest.
//
// Frame: x, y horizontal, z up (metres); the plane passes through the origin and falls toward
// the heading `slope_toward_deg` (counter-clockwise from +x) at `slope_pct` percent:
//   z(x, y) = -(slope_pct / 100) (x cos D + y sin D).
// Positions reported are the ball's contact point with the plane (its centre minus R times the
// plane's unit normal n), so a ball at rest is at the plane's height.
//
// The model (surface.h has the laws' constants and their sources):
// 1. Impact (Penner 2001, 2002): the turf is a rigid plane whose normal is tilted toward the
//    incoming ball by the critical angle theta_c (Penner's law, times the surface's scale,
//    capped so that the ball still meets the tilted plane). Against it the normal velocity
//    reverses with restitution e(v_n) (Penner's curve, times the surface's scale, at most 1)
//    and a tangential impulse stops the contact point's slip, as a rigid sphere leaving
//    rolling does (Penner's assumption), but never more than bounce_friction times the normal
//    impulse (Coulomb; then the ball leaves slipping). Spin enters through that slip: with
//    enough backspin the tangential velocity reverses and the ball checks or spins back.
// 2. Hops between impacts are ballistic under gravity alone (no air: hops are short and slow;
//    the flight's aerodynamics end at the landing). An impact whose rebound leaves less normal
//    speed than settle_speed_mps (a hop of about a millimetre), or no less than the rebound
//    before it (a ball skipping down a slope, fed by the slope between impacts), ends the
//    bouncing: the ball stays on the plane.
// 3. On the plane, while the contact point slips (speed s) the ball skids under Coulomb friction
//    mu g_n against the slip and the slope's pull g_t = gravity's component along the plane:
//      dv/dt = g_t - mu g_n s^,   ds/dt = g_t - mu g_n (1 + 1/k) s^,   k = I / (m R^2);
//    a spinless struck ball on the flat reaches pure roll after 2 v0 / (7 mu g), at 5/7 v0,
//    12 v0^2 / (49 mu g) from its start (k = 2/5).
// 4. Rolling: a resisting torque rho m g_n R and the slope's pull give
//      dv/dt = (g_t - rho g_n v^) / (1 + k),
//    i.e. (5/7) g sin(alpha) down the fall line and (5/7) rho g cos(alpha) against the motion
//    for a solid sphere (Penner, "The physics of putting", Can. J. Phys. 80, 83 (2002), treats
//    the rolling ball this way; the convention is stated here and tested). A ball whose speed
//    reaches zero rests where |g_t| <= rho g_n (tan(alpha) <= rho), otherwise it rolls on
//    down the fall line.
// 5. The hole (Rules of Golf, definitions: 108 mm across, at least 101.6 mm deep): a ball whose
//    centre crosses the rim while on the plane, on a line passing b from the hole's centre at
//    speed v, drops in when v <= v_c(b) = (L - R) sqrt(g / (2 R)), L = 2 sqrt(r_h^2 - b^2) the
//    chord its centre travels over the hole: it must fall its own radius before meeting the far
//    rim (Penner 2002, putting, after Holmes, "Putting: how a golf ball and hole interact",
//    Am. J. Phys. 59, 129 (1991); on the centre line v_c = 1.31 m/s, Holmes' figure). A faster
//    ball crosses: a lip_out event, and it goes on unchanged. A hop that lands with the whole
//    ball inside the rim (centre within r_h - R of the hole's centre) is holed.
//    With the flagstick in, a crossing ball whose line passes within r_s + R of the centre
//    meets the stick (a vertical cylinder; the normal velocity reverses with
//    flagstick_restitution), unsupported since the near rim: it drops if, by the time its
//    leading side reaches the rim again, it has fallen its radius or has too little speed to
//    climb back over the drop (v^2 < 2 g d); otherwise it bounces out (lip_out) and goes on
//    from the stick. A ball at rest against the stick rests over the hole: holed (Rule 13.2c).
//    The restitution is an estimate (0.1): a flagstick is a rod held loosely in a ferrule and
//    gives; putting tests at the flagstick (Pelz, 2019) found it keeps more putts in than it
//    knocks out, which a lively stick would not. We know no measurement of it.
//
// Integration: without a pull along the plane (flat, or the slope switched off) the skid and
// the roll are each at constant acceleration in a fixed direction and are solved exactly, one
// piece each. Otherwise they are integrated by classical RK4 at the fixed step dt_s (or by
// Dormand-Prince 5(4) under a tolerance: GroundOptions::integrator); near the
// slip's or the roll's end, where the direction turns ever faster, the steps halve with the
// time left until a last piece of 0.1 ms, which is cut at the zero (the slip's end exactly
// through the invariant v - k/(1+k) s, the roll's at constant acceleration): the transitions
// and the rest are located, not stepped over. Along the fall line the result
// is exact to rounding; across a slope the rest converges with the step (docs/golf-ground.md).
// The rim's crossing and the path's samples are taken on each step's cubic Hermite
// interpolant.
//
// Deterministic: no clocks, no randomness; the same inputs give bit-identical results.
#ifndef SPORTSIM_SIM_GOLF_GROUND_H_
#define SPORTSIM_SIM_GOLF_GROUND_H_

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Dense>

#include "absl/status/statusor.h"
#include "sim/golf/ball_flight.h"
#include "sim/core/ode/integrator.h"
#include "sim/golf/course.h"
#include "sim/golf/golf_ball.h"
#include "sim/golf/surface.h"

namespace sportsim::golf {

/// Effect bits (sim/core/effects.h's convention: 0 is full physics; each bit switches one off).
enum GroundEffect : uint32_t {
  kGroundDisableSpin = 1u << 0,   ///< the landing's spin is ignored (the ball lands spinless)
  kGroundDisableSlope = 1u << 1,  ///< gravity's pull along the plane is ignored
};
inline constexpr uint32_t kGroundEffectBits = kGroundDisableSpin | kGroundDisableSlope;

/// The plane: its grade and the heading its fall line points toward.
struct GroundPlane {
  double slope_pct = 0.0;          ///< rise over run along the fall line (%); [0, 20]
  double slope_toward_deg = 0.0;   ///< heading of the fall line (deg, ccw from +x); finite
  Eigen::Vector3d Normal() const;  ///< unit, upward
  double HeightAt(double x_m, double y_m) const;
};

/// The hole, on the plane.
struct Hole {
  double x_m = 0.0, y_m = 0.0;  ///< its centre (m)
  double diameter_m = 0.108;    ///< (m); (ball diameter, 1]
  double depth_m = 0.1016;      ///< (m); (0, 1]
  /// The flagstick, centred in the hole: 0 when it is out; in, its diameter at the hole (m),
  /// [0.005, diameter_m / 2]. kFlagstickDiameter is the USGA's recommended largest.
  double flagstick_diameter_m = 0.0;
  /// Normal restitution of the ball against the flagstick; [0, 1]. An estimate (see above).
  double flagstick_restitution = 0.1;
};
/// 3/4 inch: the USGA's recommended largest flagstick diameter near the hole.
inline constexpr double kFlagstickDiameter = 0.01905;

/// How the ball meets the ground.
enum class GroundStartKind {
  kLanding,  ///< arriving from the air (a flight's landing): it bounces first
  kPutt,     ///< struck along the plane without spin: it skids first
  kRolling,  ///< already rolling without slip (as off a Stimpmeter)
};

struct GroundStart {
  GroundStartKind kind = GroundStartKind::kLanding;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< x, y (z: the plane's height there)
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();  ///< world frame; kPutt/kRolling:
                                                           ///< projected onto the plane
  Eigen::Vector3d spin_radps = Eigen::Vector3d::Zero();  ///< angular velocity (kLanding only)
  double time_s = 0.0;  ///< the clock at the start (a flight's landing time)
};

/// The landing of `flight` (its frame: x downrange, y left, z up; the ball lands at z = 0, where
/// the plane's contact point is put): its position, velocity, spin and time.
GroundStart LandingFromFlight(const FlightResult& flight);
/// A putt (struck, spinless) at `speed_mps` toward heading `direction_deg`, from (x, y).
GroundStart PuttStart(double x_m, double y_m, double speed_mps, double direction_deg);
/// A ball already rolling at `speed_mps` toward heading `direction_deg`, from (x, y).
GroundStart RollingStart(double x_m, double y_m, double speed_mps, double direction_deg);

struct GroundOptions {
  double gravity_mps2 = 9.80665;   ///< (m/s^2); (0, 100]
  /// The skid's and the roll's integrator where they are not closed form: kRk4 (fixed step
  /// dt_s) or kDp45 (Dormand-Prince 5(4), error-controlled by tolerance_m, dt_s its largest
  /// step). Both locate the ends of the skid and the roll and every surface change.
  ode::Integrator integrator = ode::Integrator::kRk4;
  double dt_s = 5e-3;              ///< rk4: the step (s), [1e-6, 0.01]; dp45: the largest
                                   ///< step, [1e-6, 0.1]
  /// dp45 only (rk4: 0): a step's error bound (m): its position error, and its velocity and
  /// slip errors times 0.1 s, at most this; (0, 0.1].
  double tolerance_m = 0.0;
  double sample_interval_s = 0.02; ///< path samples (s); 0 = none, else [0.001, 10] and at
                                   ///< most 1e6 of them in max_time_s
  double max_time_s = 300.0;       ///< give up after (s, from the start); (0, 3600]
  /// A rebound with less normal speed than this ends the bouncing (m/s); [0.001, 1].
  /// 0.14 m/s is a hop of 1 mm.
  double settle_speed_mps = 0.14;
  bool hole = true;                ///< false: no hole on the plane
  uint32_t effects = 0;            ///< GroundEffect bits
  /// Polled every ode::kPollSteps steps; true stops the run with kCancelled.
  std::function<bool()> cancelled;
};

/// The options a course's shots use unless told otherwise: dp45 at 1e-8 m, its largest step
/// 50 ms. On terrain it rests within a tenth of a millimetre of a converged run at a third of
/// RK4's cost at 5 ms, which rests within millimetres there (docs/golf-ground-accuracy.md);
/// on the plane RK4 at 5 ms (GroundOptions' own default) is as good.
GroundOptions CourseGroundOptions();

enum class GroundEventKind {
  kLanding,
  kBounce,
  kRoll,
  kHoled,
  kLipOut,
  kRest,
  kSurface,      ///< (courses) the ball's centre crossed onto another surface
  kOutOfBounds,  ///< (courses) all of the ball went out of bounds (or off the map)
  kPenaltyArea,  ///< (courses) the ball entered water (a penalty area): the run ends there
};
/// "landing", "bounce", "roll", "holed", "lip_out", "rest", "surface", "out_of_bounds",
/// "penalty_area".
std::string_view GroundEventName(GroundEventKind kind);

struct GroundEvent {
  double t_s = 0.0;
  GroundEventKind kind = GroundEventKind::kRest;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< contact point (see above)
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();  ///< the centre's, after the event
  double spin_radps = 0.0;  ///< |angular velocity| after the event
  /// (courses) the surface class under the ball after the event (course.h's tags); empty on a
  /// plane.
  std::string surface;
};

struct GroundSample {
  double t_s = 0.0;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< contact point (see above)
  double speed_mps = 0.0;
};

struct GroundResult {
  Eigen::Vector3d rest_m = Eigen::Vector3d::Zero();  ///< where it rests (the hole's centre at
                                                     ///< the plane's height when holed)
  double t_rest_s = 0.0;         ///< the clock at rest
  bool holed = false;
  int bounces = 0;               ///< impacts, the landing included
  std::vector<GroundEvent> events;   ///< in time order; the last is kHoled or kRest
  std::vector<GroundSample> samples; ///< every sample_interval_s from the start, then the rest
  int64_t steps = 0;             ///< accepted steps on the ground
  int64_t rejected_steps = 0;    ///< dp45: steps rejected for their error
  // Courses only (a plane leaves them empty and false):
  std::string rest_surface;      ///< the surface class under the ball at rest
  bool out_of_bounds = false;    ///< at rest out of bounds (all of the ball), or off the map
  bool penalty_area = false;     ///< in water: the run ended where the ball entered it
};

/// OK where the surface holds a ball at rest on the plane (tan(alpha) <= rolling_resistance);
/// else InvalidArgument naming slope_pct.
absl::Status CheckSlopeHolds(const GroundPlane& plane, const Surface& surface);

/// Checks the inputs; InvalidArgument names the first bad field. A plane steeper than the
/// surface can hold a ball at rest (tan(alpha) > rolling_resistance) is refused: the ball would
/// never stop.
absl::Status ValidateGround(const BallSpec& ball, const Surface& surface,
                            const GroundPlane& plane, const Hole& hole,
                            const GroundStart& start, const GroundOptions& options);

/// Runs the ground phase to rest (or into the hole). InvalidArgument for bad inputs (see
/// ValidateGround), OutOfRange when no rest comes within max_time_s, kCancelled when
/// options.cancelled says so.
absl::StatusOr<GroundResult> SimulateGround(const BallSpec& ball, const Surface& surface,
                                            const GroundPlane& plane, const Hole& hole,
                                            const GroundStart& start,
                                            const GroundOptions& options);

/// The ground phase on a course: its terrain (the ball lands on the terrain's height and
/// normal; bounces, skid and roll follow the local slope), its surfaces (each zone's constants;
/// a surface event where the centre crosses onto another, out_of_bounds where all of the ball
/// is out, penalty_area where it enters water, which ends the run there) and hole
/// `hole_number`'s pin (the hole's size and flagstick from `hole`; its x_m and y_m are not
/// used). The start's x and y are on the course; its z is the terrain's there.
///
/// On terrain the ball is kept on the ground's tangent plane at its centre after each step.
/// Where the ground falls away faster than gravity can hold the ball to it (the step's turn of
/// the normal takes more normal speed than gravity gives back) it takes off and hops; where
/// the ground rises into it by more than settle_speed_mps it bounces (Penner's impact), less
/// is absorbed. Hops over uneven ground land where the ball first touches the local tangent
/// plane (probed every 0.1 m of travel, then bisected). A surface change cuts the step where
/// the centre crosses it (bisection on the step's length, to 1 ns).
absl::StatusOr<GroundResult> SimulateGroundOnCourse(const BallSpec& ball, const Course& course,
                                                    int hole_number, const Hole& hole,
                                                    const GroundStart& start,
                                                    const GroundOptions& options);

/// The capture speed of the hole for a ball crossing it with its centre's line b from the
/// hole's centre (m/s; 0 when it cannot drop): (L - R) sqrt(g / (2 R)), L = 2 sqrt(r_h^2 - b^2).
double HoleCaptureSpeed(double hole_radius_m, double ball_radius_m, double offset_m,
                        double gravity_mps2);

}  // namespace sportsim::golf

#endif  // SPORTSIM_SIM_GOLF_GROUND_H_
