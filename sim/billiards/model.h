// Billiards model: ball, cloth, collision and cue parameters, and table geometry (playing area,
// cushion segments, pockets). Constant during a simulation; the changing part is TableState.
//
// Frame: origin at the centre of the playing surface, x along the long axis, y across, z up. A
// ball on the cloth has its centre at z = R. All values SI (m, s, kg, rad).
//
// Sources for the values (see also docs/billiards.md):
// - WPA equipment specifications (pool table playing areas, pocket mouths and jaw angles, ball
//   57.15 mm / 156-170 g, cushion nose height 62.5-64.5 % of the ball diameter).
// - WPBSA table specification (snooker playing area 3569 x 1778 mm, balls 52.5 mm).
// - UMB (carom match table 2840 x 1420 mm, balls 61-61.5 mm, 205-220 g).
// - D. Alciatore, technical proofs TP A-14 (ball-ball friction), TP A-30/A-31 (cue strike,
//   squirt), and the "typical values" FAQ (billiards.colostate.edu): mu_s 0.2, mu_r 0.01,
//   spin-down about 10 rad/s^2, e_b 0.95, e_c 0.85.
// - W. Leckie, M. Greenspan, "An event-based pool physics simulator", ACG 11 (2006).
// - I. Han, "Dynamics in carom and three cushion billiards", J. Mech. Sci. Tech. 19 (2005).
// - S. Mathavan, M. R. Jackson, R. M. Parkin, "A theoretical analysis of billiard ball dynamics
//   under cushion impacts", Proc. IMechE Part C 224 (2010): restitution 0.98 and ball-cushion
//   friction 0.14 fitted to their snooker cushion experiments (normal speeds up to ~2.5 m/s).
// - W. J. Stronge, "Planar impact of rough compliant bodies", Int. J. Impact Eng. 15 (1994), and
//   "Impact Mechanics" (Cambridge, 2000), ch. 5: a contact with normal and tangential springs.
// - K. L. Johnson, "Contact Mechanics" (Cambridge, 1985), sec. 7.4 (after Mindlin 1949): the
//   tangential to normal stiffness of a contact on an elastic body, 2 (1 - nu) / (2 - nu).
#ifndef SPORTSIM_SIM_BILLIARDS_MODEL_H_
#define SPORTSIM_SIM_BILLIARDS_MODEL_H_

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "Eigen/Core"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "sim/core/effects.h"

namespace sportsim::billiards {

/// Effect bits of SolverOptions::effects (the convention of sim/core/effects.h): 0 = the default
/// physics, which has everything on except air drag. A Disable bit switches an effect that is on
/// by default off (it is skipped, not multiplied by zero); the Enable bit switches air drag,
/// which is off by default, on.
enum Effect : uint32_t {
  kEffectEnableDrag = 1u << 0,                ///< air drag on the ball (stepped engine only)
  kEffectDisableSpinDecay = 1u << 1,          ///< no spin-down of the vertical spin component
  kEffectDisableRollingResistance = 1u << 2,  ///< no rolling resistance (a rolling ball never slows)
  kEffectDisableBallFriction = 1u << 3,       ///< no ball-ball friction (frictionless collisions)
  kEffectDisableCushions = 1u << 4,           ///< no cushions and jaws (balls leave the table)
  kEffectDisablePockets = 1u << 5,            ///< no pocket capture
  kEffectDisableOrientation = 1u << 6,        ///< no orientation (quaternion) tracking
  kEffectDisableSquirt = 1u << 7,             ///< no cue-ball squirt (deflection with english)
  kEffectKnownBits = (1u << 8) - 1,           ///< every known bit
};
/// The bits that switch an effect ON (the others switch one off).
inline constexpr uint32_t kEffectEnableBits = kEffectEnableDrag;

/// Whether the effect of `bit` (any Effect bit) is on in `effects`.
constexpr bool EffectOn(uint32_t effects, uint32_t bit) {
  return sportsim::EffectOn(effects, bit, kEffectEnableBits);
}
/// `effects` with the effect of `bit` switched on or off (sets or clears the bit as its kind
/// says): what a "disable" or "enable" list in a request does.
constexpr uint32_t WithEffect(uint32_t effects, uint32_t bit, bool on) {
  return sportsim::WithEffect(effects, bit, on, kEffectEnableBits);
}

/// Names of the effects, in bit order ("drag", "spin_decay", ...).
std::span<const std::string_view> EffectNames();
/// The bit of an effect name; 0 for an unknown name.
uint32_t EffectFromName(std::string_view name);

/// How a ball bounces off a cushion.
enum class CushionModel : uint8_t {
  /// Rigid-body impulse at the cushion nose (above the ball's centre): restitution e_c along the
  /// contact normal, Coulomb friction f_c capped at sticking, the slate absorbing the vertical
  /// part. The geometry is Han's (2005); the impulse law is written in vector form in
  /// docs/billiards.md.
  kHan,
  /// Mirror: the normal velocity component reverses, nothing else changes (tests).
  kMirror,
  /// Mathavan, Jackson and Parkin (2010): the impact integrated over the normal impulse at the
  /// nose, with sliding friction at the nose (f_cushion_mathavan) and at the slate (mu_slide),
  /// each in the direction of its own slip as it evolves, until the nose's normal work gives
  /// back e_cushion_mathavan^2 of the compression's (an energetic restitution).
  /// Integrated under error control, a contact whose slip reaches zero held there while its
  /// friction can; cushion_impulse_steps sets the fallback's step (docs/billiards.md).
  kMathavan2010,
  /// Stronge's compliant contact at Han's nose: the same restitution e_c and normal impulse as
  /// kHan, but the nose is a pair of springs, normal and tangential, whose stiffness ratio is
  /// the cushion rubber's (cushion_poisson_ratio). The tangential spring sticks while the
  /// friction f_c can hold it and slips when not; what it stored comes back as the ball leaves,
  /// so a grazing contact can reverse its slip (tangential restitution). Solved exactly in
  /// time, stick and slip phases alike (docs/billiards.md).
  kStrongeCompliant,
};

/// How two balls' impact is resolved.
enum class BallBallModel : uint8_t {
  /// One impulse: restitution e_ball along the line of centres and TP A-14's friction (mu_ball_a,
  /// _b, _c_spm at the contact's sliding speed) capped where it stops the slip (CollideBalls).
  kAlciatore,
  /// Mathavan, Jackson and Parkin (2014): the impact integrated over the normal impulse, the
  /// contact's friction (TP A-14's at the slip it starts with) against its slip as that
  /// evolves, and the cloth's sliding friction (mu_slide) at the ball the contact's friction
  /// presses into the cloth; restitution e_ball by the normal work. Where the contact's slip
  /// is horizontal (no spin about the contact's horizontal tangent) nothing presses either
  /// ball and it is kAlciatore (docs/billiards.md).
  kMathavan2014,
};

/// Numeric model parameters, with the typical pool values as defaults. Every field can be set by
/// name (see ParamInfos()).
struct PhysicsParams {
  double gravity_mps2 = 9.81;          ///< g (m/s^2)
  double ball_radius_m = 0.028575;     ///< R (m): WPA pool ball, 57.15 mm diameter
  double ball_mass_kg = 0.170;         ///< m (kg); inertia I = 2/5 m R^2
  double mu_slide = 0.2;               ///< sliding friction: dv/dt = -mu_s g u^ while sliding
  /// u_c (m/s): below this slip the sliding friction falls with the slip, to nothing at none
  /// (Cross's measurement); 0, the default, keeps it constant. Below u_c rolling resistance
  /// also slows the rolling part of the sliding ball's motion (docs/billiards.md, "Slip-speed
  /// friction").
  double slide_fade_speed_mps = 0.0;
  /// The fade's accuracy: it is taken as this many bands of constant friction below u_c, each
  /// at the fade's value at the band's middle slip (a whole number).
  double slide_fade_bands = 16;
  double mu_roll = 0.01;               ///< rolling resistance: dv/dt = -mu_r g v^ while rolling
  double spin_decel_rps2 = 10.0;       ///< spin-down: d(omega_z)/dt = -this sgn(omega_z) (rad/s^2)
  double e_ball = 0.95;                ///< ball-ball restitution e_b
  double mu_ball_a = 0.00995;          ///< ball-ball friction mu = a + b exp(-c |u_t|) (TP A-14),
                                       ///< u_t the sliding speed of the surfaces at the contact
  double mu_ball_b = 0.108;            ///< (see mu_ball_a)
  double mu_ball_c_spm = 1.088;        ///< c (s/m) (see mu_ball_a)
  double e_cushion = 0.85;             ///< ball-cushion restitution e_c (along the contact normal)
  double f_cushion = 0.2;              ///< ball-cushion friction coefficient f_c
  double e_cushion_mathavan = 0.98;    ///< kMathavan2010: energetic restitution at the nose
  double f_cushion_mathavan = 0.14;    ///< kMathavan2010: ball-cushion sliding friction
  double cushion_impulse_steps = 500;  ///< kMathavan2010: fallback step, 1/N of a (1+e) m v_n impact
  double cushion_poisson_ratio = 0.5;  ///< kStrongeCompliant: the cushion rubber's Poisson ratio
  /// p: the cushion's restitution falls with the approach speed v_n across the cushion line,
  /// e(v_n) = 1 - (1 - e) (v_n / 1 m/s)^p clamped to [0, 1], e being the model's restitution
  /// (e_cushion, or e_cushion_mathavan) read as its value at 1 m/s. 0, the default, keeps it
  /// constant; 1/5 is a viscoelastic sphere's law (docs/billiards.md, "Restitution that falls
  /// with speed"). Every cushion model but the mirror.
  double cushion_restitution_exponent = 0.0;
  double cushion_height_m = 0.036;     ///< h: cushion nose above the slate (m); R < h < 2R
  double cue_mass_kg = 0.54;           ///< M: cue mass (kg), 19 oz
  double cue_end_mass_kg = 0.170 / 30; ///< m_e: the cue's effective end mass for squirt (kg)
  double miscue_limit = 0.5;           ///< largest sqrt(a^2 + b^2) (fraction of R) that is no miscue
  double air_density_kgpm3 = 1.2;      ///< rho for air drag (kg/m^3)
  double drag_coefficient = 0.5;       ///< C_d: F = -1/2 rho C_d pi R^2 |v| v (sphere, Re ~ 1e4)
  double spin_drag_coefficient = 0.01; ///< C_m: torque = -1/2 rho C_m R^5 |w| w (order of magnitude)
  CushionModel cushion_model = CushionModel::kHan;
  BallBallModel ball_ball_model = BallBallModel::kAlciatore;
};

/// One named numeric parameter: what `--param NAME=VALUE` and GetInfo expose.
struct ParamInfo {
  std::string_view name;
  std::string_view unit;
  std::string_view description;
  double PhysicsParams::*field;
  double lo, hi;  ///< allowed closed range, checked by ValidateParams
};
std::span<const ParamInfo> ParamInfos();
/// Sets a parameter by name; InvalidArgument for unknown names or values out of range.
absl::Status SetParam(std::string_view name, double value, PhysicsParams* params);
/// Every parameter in range, and the cushion nose between R and 2R.
absl::Status ValidateParams(const PhysicsParams& p);

/// A straight cushion (rail or jaw) at the nose height, from `a` to `b`. A ball touches it when
/// its centre is the contact distance from the segment (endpoints included: rounded points).
struct CushionSegment {
  Eigen::Vector2d a, b;
  std::string name;  ///< e.g. "rail_top_left", "jaw_top_right_corner_a"
};

/// A pocket: a ball whose centre enters the capture circle falls in.
struct Pocket {
  Eigen::Vector2d centre;
  double radius_m = 0.0;
  std::string name;  ///< "top_left", "bottom_side", ...
};

/// Table geometry. `length_m` x `width_m` is the playing area between cushion noses; an
/// unbounded table has no cushions or pockets (the chapter's scene).
struct TableSpec {
  std::string name;
  bool bounded = true;
  double length_m = 2.54;
  double width_m = 1.27;
  std::vector<CushionSegment> cushions;
  std::vector<Pocket> pockets;
  PhysicsParams params;  ///< the preset's defaults (ball size, cushion height)
  /// Pool and snooker cushion noses sit at this fraction of the ball diameter (WPA: 62.5-64.5
  /// %), so another ball size moves the nose with it (SetBallRadius); 0: a fixed height
  /// (carom's 37 mm).
  double nose_fraction_of_diameter = 0.0;
};

/// Sets the ball radius, and the cushion nose height with it where the spec ties the nose to
/// the ball (nose_fraction_of_diameter > 0).
void SetBallRadius(double radius_m, TableSpec* spec);

/// Preset names: pool-7ft, pool-8ft, pool-9ft, snooker, carom, unbounded.
std::span<const std::string_view> TablePresetNames();
/// Builds a preset's geometry and default parameters. NotFound-style InvalidArgument for an
/// unknown name.
absl::StatusOr<TableSpec> MakeTablePreset(std::string_view name);

/// A validated, immutable model: geometry, parameters and the constants the engines use.
class TableModel {
 public:
  /// Validates the parameters (ranges above) and the geometry against the ball size.
  static absl::StatusOr<TableModel> Create(TableSpec spec);

  const TableSpec& spec() const { return spec_; }
  const PhysicsParams& params() const { return spec_.params; }
  double radius() const { return spec_.params.ball_radius_m; }
  double mass() const { return spec_.params.ball_mass_kg; }
  double inertia() const { return inertia_; }  ///< I = 2/5 m R^2 (kg m^2)
  /// Horizontal distance from a ball's centre to a cushion nose line at contact:
  /// sqrt(R^2 - (h - R)^2), since the nose touches the ball above its equator.
  double cushion_contact_distance() const { return cushion_contact_; }
  /// sin of the angle of the cushion contact point above the ball's equator: (h - R) / R.
  double cushion_sin() const { return cushion_sin_; }

 private:
  explicit TableModel(TableSpec spec);
  TableSpec spec_;
  double inertia_ = 0.0;
  double cushion_contact_ = 0.0;
  double cushion_sin_ = 0.0;
};

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_MODEL_H_
