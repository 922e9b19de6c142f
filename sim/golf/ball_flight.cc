#include "sim/golf/ball_flight.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "sim/core/check.h"
#include "sim/core/effects.h"
#include "sim/core/ode/event.h"
#include "sim/core/ode/hermite.h"
#include "sim/core/ode/runge_kutta.h"

namespace sportsim::golf {

const ode::AccuracyLimits FlightOptions::kLimits = {
    .default_dt_s = kDefaultDt,
    .dt_s = {.lo = 0.0, .lo_open = true, .hi = 0.1},
    .default_tolerance = std::nullopt,  // dp45 requires one
    .tolerance = {.lo = 0.0, .lo_open = true, .hi = 1e-2},
    .default_max_step_s = kDefaultMaxStep,
    .max_step_s = {.lo = 1e-6, .hi = 1.0}};

namespace {

using Eigen::Vector3d;

// State: position (3), velocity (3), spin rate (rad/s).
using State = Eigen::Matrix<double, 7, 1>;

constexpr int kZ = 2;   // index of z
constexpr int kVz = 5;  // index of vz
constexpr int kW = 6;   // index of the spin rate

// Air speeds below this leave no aerodynamic force (m/s). Both forces vanish
// continuously as |u| -> 0: drag ~ (C_D0 |u| + cd_spin r w) u, lift ~
// |u|^(1 - cl_exponent) u.
constexpr double kMinAirSpeedMps = 1e-9;
// RK4's stability interval on the negative real axis is about 2.785; we stop
// before it. The rate is an upper estimate of the aerodynamic Jacobian norm.
constexpr double kRk4StabilityLimit = 2.5;
// Landing and apex are located on the interpolant to this time (s).
constexpr double kEventTimeToleranceS = 1e-12;
// Newton refinements of the apex and landing on the integrator's own step.
constexpr int kMaxRefinements = 6;

// Everything the derivative needs; constant during a flight.
struct Model {
  double gravity = 0.0;
  double k_aero = 0.0;             // rho A / (2 m)  (1/m)
  double radius = 0.0;             // (m)
  double re_per_speed = 0.0;       // rho d / mu  (s/m)
  Vector3d spin_axis = Vector3d::Zero();  // unit
  AeroCoefficients aero;
  bool drag = false;
  bool lift = false;
  bool spin_decay = false;
  bool wind = false;
  bool instantaneous_decay = false;
  bool breakpoints = false;        // the fit in use has kinks to step onto
  double inv_tau_launch = 0.0;     // 1/tau0 (1/s), kLaunchSpeed
  Wind wind_spec;
  Vector3d wind_uniform = Vector3d::Zero();  // uniform profile (m/s)
  Vector3d wind_direction = Vector3d::Zero();  // unit, horizontal
  double log_inv_norm = 0.0;       // 1 / ln(1 + z_ref / z0)
};

Vector3d WindAt(const Model& model, double z) {
  if (model.wind_spec.profile == WindProfile::kUniform) {
    return model.wind_uniform;
  }
  const double zc = std::max(z, 0.0);
  return model.wind_spec.speed_mps *
         std::log1p(zc / model.wind_spec.roughness_length_m) *
         model.log_inv_norm * model.wind_direction;
}

// dy/dt. `rate` (optional) receives an upper estimate of the aerodynamic
// rate |d(accel)/dv| + decay rate (1/s), used for RK4's stability check.
void Derivative(const Model& model, const State& y, State* dy, double* rate) {
  dy->head<3>() = y.segment<3>(3);
  Vector3d accel(0.0, 0.0, -model.gravity);
  double aero_rate = 0.0;
  double air_speed = 0.0;
  const double w = y[kW];

  // Aerodynamics on the air-relative velocity u; skipped entirely when off.
  if (model.drag || model.lift || model.instantaneous_decay) {
    Vector3d u = y.segment<3>(3);
    if (model.wind) u -= WindAt(model, y[kZ]);
    air_speed = u.norm();
    if (air_speed > kMinAirSpeedMps) {
      const double spin_parameter = model.radius * w / air_speed;
      if (model.drag) {
        const double cd = DragCoefficient(
            model.aero, model.re_per_speed * air_speed, spin_parameter);
        accel -= (model.k_aero * cd * air_speed) * u;
        aero_rate += 2.0 * model.k_aero * cd * air_speed;
      }
      if (model.lift && w > 0.0) {
        const double cl = LiftCoefficient(model.aero, spin_parameter);
        accel += (model.k_aero * cl * air_speed) * model.spin_axis.cross(u);
        aero_rate += 2.0 * model.k_aero * cl * air_speed;
      }
    }
  }
  dy->segment<3>(3) = accel;

  // Spin decay: the axis keeps its direction, the rate decays.
  double decay_rate = 0.0;
  if (model.spin_decay) {
    decay_rate = model.instantaneous_decay
                     ? model.aero.spin_decay_coefficient * air_speed /
                           model.radius
                     : model.inv_tau_launch;
    (*dy)[kW] = -decay_rate * w;
  } else {
    (*dy)[kW] = 0.0;
  }
  if (rate != nullptr) *rate = aero_rate + decay_rate;
}

// Air speed |u| = |v - wind(z)| of a state (m/s).
double AirSpeed(const Model& model, const State& y) {
  Vector3d u = y.segment<3>(3);
  if (model.wind) u -= WindAt(model, y[kZ]);
  return u.norm();
}

// The variable whose breakpoints split the fit into smooth pieces: the air
// speed (Re / re_per_speed) for Nathan's C_D0(Re), the spin parameter S for
// Ferguson et al.'s clamped quadratics (infinite when the air is still).
double PieceVariable(const Model& model, const State& y) {
  const double speed = AirSpeed(model, y);
  if (FitVariableOf(model.aero) == FitVariable::kReynolds) return speed;
  return speed > kMinAirSpeedMps ? model.radius * y[kW] / speed
                                 : std::numeric_limits<double>::infinity();
}

// d/dt of PieceVariable along the solution (dy = the derivative at y).
double PieceVariableRate(const Model& model, const State& y, const State& dy) {
  Vector3d u = y.segment<3>(3);
  if (model.wind) u -= WindAt(model, y[kZ]);
  const double speed = u.norm();
  // d|u|/dt ~ u.a / |u| (the wind's height gradient is left out: a Newton
  // slope need not be exact).
  const double speed_rate = u.dot(dy.segment<3>(3)) / speed;
  if (FitVariableOf(model.aero) == FitVariable::kReynolds) return speed_rate;
  return model.radius * (dy[kW] - y[kW] * speed_rate / speed) / speed;
}

// The lower (upper = false) or upper breakpoint of PieceVariable: the fit's
// breakpoint (aero.h), as an air speed for Nathan's Re breakpoints.
double Breakpoint(const Model& model, bool upper) {
  if (FitVariableOf(model.aero) == FitVariable::kReynolds) {
    return FitBreakpoint(model.aero, upper) / model.re_per_speed;
  }
  return FitBreakpoint(model.aero, upper);
}

// Which piece of the fit applies: 0 (at or below the lower breakpoint), 1
// (between), 2 (at or above the upper one). Mirrors the branches of
// DragCoefficient and LiftCoefficient.
int FitPiece(const Model& model, const State& y) {
  const double v = PieceVariable(model, y);
  if (v <= Breakpoint(model, false)) return 0;
  return v >= Breakpoint(model, true) ? 2 : 1;
}

// First theta in (0, 1] where the Hermite interpolant of the step enters
// fit piece `target` (from the adjacent piece; `upward` = toward the higher
// piece). Bisection on a piecewise-constant predicate; the end of the step
// is known to be past the boundary.
double RegimeCrossing(const Model& model, const State& y0, const State& f0,
                      const State& y1, const State& f1, double h, bool upward,
                      int target) {
  const auto reached = [&](double theta) {
    const int r = FitPiece(model, ode::CubicHermite(y0, f0, y1, f1, h, theta));
    return upward ? r >= target : r <= target;
  };
  double lo = 0.0, hi = 1.0;
  if (reached(lo)) return 0.0;
  while ((hi - lo) * h > kEventTimeToleranceS) {
    const double mid = 0.5 * (lo + hi);
    if (reached(mid)) {
      hi = mid;
    } else {
      lo = mid;
    }
  }
  return hi;
}

absl::Status ValidateOptions(const FlightOptions& o) {
  if (o.integrator != ode::Integrator::kRk4 && o.integrator != ode::Integrator::kDp45) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "integrator must be rk4 or dp45, got %s",
        ode::IntegratorName(o.integrator)));
  }
  if (auto s = ode::ValidateAccuracy(o.integrator, o.accuracy, FlightOptions::kLimits);
      !s.ok())
    return s;
  if (o.sample_interval_s != 0.0) {
    if (auto s = CheckFiniteInRange("sample_interval_s (or 0 for none)",
                            o.sample_interval_s, 1e-4, false, 10, false);
        !s.ok())
      return s;
  }
  if (auto s = CheckFiniteInRange("max_flight_time_s", o.max_flight_time_s, 0, true,
                          600, false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("launch_height_m", o.launch_height_m, 0, false, 1000,
                          false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("gravity_mps2", o.gravity_mps2, 0, true, 100, false);
      !s.ok())
    return s;
  if (o.spin_decay_model != SpinDecayModel::kLaunchSpeed &&
      o.spin_decay_model != SpinDecayModel::kInstantaneous) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "spin_decay_model must be kLaunchSpeed or kInstantaneous, got %d",
        static_cast<int>(o.spin_decay_model)));
  }
  if (auto s = ValidateEffectBits("flight effects", o.effects, kFlightEffectBits);
      !s.ok())
    return s;
  return ValidateAero(o.aero);
}

FlightSample MakeSample(double t, const State& y) {
  return FlightSample{.t_s = t,
                      .x_m = y[0],
                      .y_m = y[1],
                      .z_m = y[2],
                      .vx_mps = y[3],
                      .vy_mps = y[4],
                      .vz_mps = y[5],
                      .speed_mps = y.segment<3>(3).norm(),
                      .spin_rpm = y[kW] / kRpmToRadPerS};
}

// Launch frame, model constants and the initial state.
Model BuildModel(const BallSpec& ball, const LaunchConditions& launch,
                 const AirProperties* air, const Wind& wind,
                 const FlightOptions& options, State* y0) {
  Model model;
  // Launch frame: direction d, right = d x z, up' = right x d.
  const double elevation = launch.launch_angle_deg * kDegToRad;
  const double azimuth = launch.launch_direction_deg * kDegToRad;
  const Vector3d d(std::cos(elevation) * std::cos(azimuth),
                   -std::cos(elevation) * std::sin(azimuth),
                   std::sin(elevation));
  Vector3d right = d.cross(Vector3d::UnitZ());
  if (right.norm() < 1e-12) {
    // Vertical launch: "right" is the horizontal right of the aim direction.
    right = Vector3d(-std::sin(azimuth), -std::cos(azimuth), 0.0);
  }
  right.normalize();
  const Vector3d up = right.cross(d);
  const double tilt = launch.spin_axis_deg * kDegToRad;

  // The model: constants of the flight, effects resolved to booleans.
  const uint32_t off = options.effects;
  model.gravity = options.gravity_mps2;
  model.k_aero = 0.5 * air->density_kgpm3 * ball.area_m2() / ball.mass_kg;
  model.radius = ball.radius_m();
  model.re_per_speed =
      air->density_kgpm3 * ball.diameter_m / air->viscosity_pas;
  model.spin_axis = std::cos(tilt) * right - std::sin(tilt) * up;
  model.aero = options.aero;
  model.drag = (off & kFlightDisableDrag) == 0;
  model.lift = (off & kFlightDisableLift) == 0;
  model.breakpoints = FitHasKinks(options.aero, model.drag, model.lift);
  model.spin_decay = (off & kFlightDisableSpinDecay) == 0;
  model.wind = (off & kFlightDisableWind) == 0 && wind.speed_mps > 0.0;
  model.instantaneous_decay =
      model.spin_decay &&
      options.spin_decay_model == SpinDecayModel::kInstantaneous;
  model.wind_spec = wind;
  model.wind_direction = WindVelocity(
      Wind{.speed_mps = 1.0, .toward_deg = wind.toward_deg}, 0.0);
  model.wind_uniform = wind.speed_mps * model.wind_direction;
  if (wind.profile == WindProfile::kLogarithmic) {
    model.log_inv_norm =
        1.0 / std::log1p(wind.reference_height_m / wind.roughness_length_m);
  }

  // Initial state.
  State& y = *y0;
  y.head<3>() = Vector3d(0.0, 0.0, options.launch_height_m);
  y.segment<3>(3) = launch.ball_speed_mps * d;
  y[kW] = launch.spin_rpm * kRpmToRadPerS;
  if (model.spin_decay && !model.instantaneous_decay) {
    Vector3d u0 = y.segment<3>(3);
    if (model.wind) u0 -= WindAt(model, options.launch_height_m);
    model.inv_tau_launch =
        options.aero.spin_decay_coefficient * u0.norm() / model.radius;
  }

  return model;
}

// The derivative as sim/core/ode wants it, counting evaluations and keeping
// the largest aerodynamic rate of the states it was asked about (a step's
// stages: RK4's stability check).
struct CountedRhs {
  const Model* model;
  int64_t* evaluations;
  double* largest_rate;
  State operator()(double /*t*/, const State& y) const {
    State dy;
    double rate = 0.0;
    Derivative(*model, y, &dy, &rate);
    ++*evaluations;
    *largest_rate = std::max(*largest_rate, rate);
    return dy;
  }
};

// One flight from launch to landing: the state between steps and the
// stages of a step.
class Flight {
 public:
  Flight(const Model& model, const FlightOptions& options, const State& y0,
         FlightResult* result)
      : model_(model),
        o_(options),
        rk4_(options.integrator == ode::Integrator::kRk4),
        settings_(ode::ResolveAccuracy(options.integrator, options.accuracy,
                                       FlightOptions::kLimits)),
        result_(result),
        y_(y0) {
    Derivative(model_, y_, &f_, &rate_);
    result_->rhs_evaluations = 1;
    piece_ = model_.breakpoints ? FitPiece(model_, y_) : 0;
    if (!rk4_) {
      h_try_ = ode::Dp45InitialStep(Rhs(), 0.0, y_, f_, settings_.tolerance,
                                    settings_.max_step_s,
                                    options.max_flight_time_s);
    }
  }

  // Runs to the landing.
  absl::Status Run() {
    while (true) {
      if (t_ >= o_.max_flight_time_s) return NotLandedError();
      if (auto s = TakeStep(); !s.ok()) return s;
      const bool on_grid = StepOntoBreakpoint();
      ++result_->steps;
      if (result_->steps % FlightOptions::kCancelPollSteps == 0) {
        if (auto s = CheckBudget(); !s.ok()) return s;
      }
      if (rk4_ && on_grid) ++grid_index_;
      LocateApex();
      const bool lands = y_new_[kZ] <= 0.0;
      if (lands) {
        if (auto s = LocateLanding(); !s.ok()) return s;
      }
      const double t_end = lands ? t_ + h_land_ : t_ + h_;
      // The step that crosses max_flight_time_s may still land inside it;
      // a landing found past it is as much a miss as no landing at all.
      if (lands && t_end > o_.max_flight_time_s) return NotLandedError();
      EmitSamples(t_end);
      if (lands) {
        Land(t_end);
        return absl::OkStatus();
      }
      y_ = y_new_;
      f_ = f_new_;
      rate_ = rate_new_;
      t_ = t_ + h_;
    }
  }

 private:
  CountedRhs Rhs() {
    return {&model_, &result_->rhs_evaluations, &stage_rate_};
  }

  // The height is the last state inside the limit: the step start.
  absl::Status NotLandedError() const {
    return absl::OutOfRangeError(absl::StrFormat(
        "the ball did not land within max_flight_time_s = %g s (height %g m "
        "at t = %.6f s)",
        o_.max_flight_time_s, y_[kZ], t_));
  }

  // Every kCancelPollSteps steps: the caller's cancellation, and dp45's
  // step budget (its step count is not known up front).
  absl::Status CheckBudget() const {
    if (o_.cancelled && o_.cancelled()) {
      return absl::CancelledError(absl::StrFormat(
          "flight cancelled at t = %.6f s after %d steps", t_, result_->steps));
    }
    const int64_t tried = result_->steps + result_->rejected_steps;
    if (!rk4_ && tried >= FlightOptions::kMaxAdaptiveSteps) {
      return absl::OutOfRangeError(absl::StrFormat(
          "the flight took %d dp45 steps by t = %.6f s without landing "
          "(aerodynamic rate %g 1/s: the ball's drag makes the equations "
          "stiff, or the tolerance is too tight)",
          tried, t_, rate_));
    }
    return absl::OkStatus();
  }

  // One step of the scheme from the step start, without error control (h =
  // 0: no step): the partial steps that breakpoints and events re-take.
  State Advance(double h) {
    if (h <= 0.0) return y_;
    if (rk4_) return ode::Rk4Step(Rhs(), t_, h, y_, f_);
    ode::Dp45Stages<State> st;
    return ode::Dp45Solution(Rhs(), t_, h, y_, f_, &st, t_ + h);
  }

  // Stage 1: take a step (RK4 to the next grid point; DP45 until its error
  // test passes). Sets h_, y_new_, f_new_, rate_new_.
  absl::Status TakeStep() {
    if (rk4_) {
      h_ = static_cast<double>(grid_index_ + 1) * settings_.dt_s - t_;
      stage_rate_ = 0.0;
      y_new_ = ode::Rk4Step(Rhs(), t_, h_, y_, f_);
      Derivative(model_, y_new_, &f_new_, &rate_new_);
      ++result_->rhs_evaluations;
      // The bound must hold along the step, not only at its start: a ball too
      // slow to feel the air (below kMinAirSpeedMps) can meet a stiff drag
      // inside its first step, and the stages then run away.
      const double rate = std::max({rate_, stage_rate_, rate_new_});
      if (rate * h_ > kRk4StabilityLimit) {
        return absl::OutOfRangeError(absl::StrFormat(
            "dt_s = %g s is too large for RK4 in the step from t = %.6f s: "
            "aerodynamic rate %g 1/s x dt = %g exceeds the stability bound %g; "
            "reduce dt_s or use dp45",
            settings_.dt_s, t_, rate, rate * h_, kRk4StabilityLimit));
      }
    } else {
      bool rejected = false;
      while (true) {
        h_ = std::min(h_try_, settings_.max_step_s);
        ode::Dp45Stages<State> st;
        y_new_ = ode::Dp45Solution(Rhs(), t_, h_, y_, f_, &st, t_ + h_);
        Derivative(model_, y_new_, &f_new_, &rate_new_);
        ++result_->rhs_evaluations;
        const double e = ode::Dp45ErrorNorm(ode::Dp45Error(h_, f_, st, f_new_), y_,
                                            y_new_, settings_.tolerance,
                                            ode::ErrorNorm::kMax);
        const double factor = ode::Dp45StepFactor(e, rejected);
        h_try_ = h_ * factor;
        if (e <= 1.0) break;
        ++result_->rejected_steps;
        rejected = true;
        if (h_try_ < 1e-12) {
          return absl::OutOfRangeError(absl::StrFormat(
              "step size underflow (%g s) at t = %.6f s", h_try_, t_));
        }
      }
    }
    if (!y_new_.allFinite() || !f_new_.allFinite()) {
      return absl::OutOfRangeError(absl::StrFormat(
          "non-finite ball state at t = %.6f s (after the step from t = %.6f "
          "s)",
          t_ + h_, t_));
    }
    return absl::OkStatus();
  }

  // Stage 2: the fit's breakpoints (aero.h). A step that crosses one is cut
  // short onto the crossing so no step integrates across a kink (this keeps
  // RK4 at order 4 and DP45's error estimate honest). Returns whether the
  // step still ends on the RK4 grid.
  bool StepOntoBreakpoint() {
    if (!model_.breakpoints) return true;
    const int piece_end = FitPiece(model_, y_new_);
    while (piece_end != piece_) {
      const int next = piece_ + (piece_end > piece_ ? 1 : -1);
      const double theta = RegimeCrossing(model_, y_, f_, y_new_, f_new_, h_,
                                          next > piece_, next);
      if (theta * h_ <= kEventTimeToleranceS) {
        piece_ = next;  // already on the boundary
        continue;
      }
      const ode::ScalarCubicHermite z{y_[kZ], h_ * f_[kZ], y_new_[kZ],
                                      h_ * f_new_[kZ]};
      if (y_new_[kZ] <= 0.0 && z.Value(theta) <= 0.0) return true;  // lands first
      // The interpolant straddles the kink, so its crossing is only a first
      // guess: refine the partial step's length by Newton on the piece
      // variable until the step ends on the boundary.
      const double boundary = Breakpoint(model_, std::max(piece_, next) == 2);
      const double h_full = h_;
      h_ = ode::RefineOnStep(
          theta * h_full, h_full, kMaxRefinements,
          [&](double h) {
            y_new_ = Advance(h);
            Derivative(model_, y_new_, &f_new_, &rate_new_);
            ++result_->rhs_evaluations;
          },
          [&]() -> std::optional<ode::EventResidual> {
            const double value = PieceVariable(model_, y_new_);
            const double value_rate = PieceVariableRate(model_, y_new_, f_new_);
            if (!(std::abs(value_rate) > 0.0) || !std::isfinite(value)) {
              return std::nullopt;
            }
            return ode::EventResidual{value - boundary, value_rate};
          });
      piece_ = next;
      return false;
    }
    return true;
  }

  // Stage 3: apex, where vz changes sign: root of the Hermite interpolant of
  // vz, refined on the integrator's own partial step.
  void LocateApex() {
    if (!(y_[kVz] > 0.0 && y_new_[kVz] <= 0.0)) return;
    const ode::ScalarCubicHermite vz{y_[kVz], h_ * f_[kVz], y_new_[kVz],
                                     h_ * f_new_[kVz]};
    const double theta = ode::LocateOnInterpolant(
        [&](double q) { return vz.Value(q); }, 0.0, 1.0, y_[kVz], y_new_[kVz],
        kEventTimeToleranceS / h_);
    State y_top, f_top;
    const double h_top = ode::RefineOnStep(
        h_ * theta, h_, kMaxRefinements,
        [&](double h) {
          y_top = Advance(h);
          Derivative(model_, y_top, &f_top, nullptr);
          ++result_->rhs_evaluations;
        },
        [&]() -> std::optional<ode::EventResidual> {
          if (!(f_top[kVz] < 0.0)) return std::nullopt;
          return ode::EventResidual{y_top[kVz], f_top[kVz]};
        });
    if (y_top[kZ] > result_->apex_m) {
      result_->apex_m = y_top[kZ];
      result_->apex_time_s = t_ + h_top;
    }
  }

  // Stage 4: landing, the first step that ends at or below z = 0: root of the
  // Hermite interpolant of z, refined on the partial step (Newton on z).
  absl::Status LocateLanding() {
    const ode::ScalarCubicHermite z{y_[kZ], h_ * f_[kZ], y_new_[kZ],
                                    h_ * f_new_[kZ]};
    const double theta = ode::LocateOnInterpolant(
        [&](double q) { return z.Value(q); }, 0.0, 1.0, y_[kZ], y_new_[kZ],
        kEventTimeToleranceS / h_);
    h_land_ = ode::RefineOnStep(
        h_ * theta, h_, kMaxRefinements,
        [&](double h) { y_land_ = Advance(h); },
        [&]() -> std::optional<ode::EventResidual> {
          if (!(y_land_[kVz] < 0.0)) return std::nullopt;
          return ode::EventResidual{y_land_[kZ], y_land_[kVz]};
        });
    if (!y_land_.allFinite()) {
      return absl::OutOfRangeError(absl::StrFormat(
          "non-finite ball state while locating the landing at t = %.6f s",
          t_ + h_land_));
    }
    return absl::OkStatus();
  }

  // Stage 5: samples at k * sample_interval_s inside [t, t_end).
  void EmitSamples(double t_end) {
    const double sample_dt = o_.sample_interval_s;
    if (!(sample_dt > 0.0)) return;
    while (true) {
      const double ts = static_cast<double>(next_sample_) * sample_dt;
      if (ts >= t_end) break;
      const double theta = (ts - t_) / h_;
      result_->samples.push_back(MakeSample(
          ts, theta <= 0.0 ? y_
                           : ode::CubicHermite(y_, f_, y_new_, f_new_, h_, theta)));
      ++next_sample_;
    }
  }

  // The landing summary.
  void Land(double t_end) {
    const Vector3d p = y_land_.head<3>();
    const Vector3d v = y_land_.segment<3>(3);
    FlightResult& r = *result_;
    r.flight_time_s = t_end;
    r.landing_position_m = p;
    r.landing_velocity_mps = v;
    r.carry_m = std::hypot(p.x(), p.y());
    r.carry_downrange_m = p.x();
    r.lateral_m = -p.y();
    r.landing_speed_mps = v.norm();
    r.landing_angle_deg =
        std::atan2(-v.z(), std::hypot(v.x(), v.y())) / kDegToRad;
    r.landing_spin_rpm = y_land_[kW] / kRpmToRadPerS;
    if (o_.sample_interval_s > 0.0) r.samples.push_back(MakeSample(t_end, y_land_));
  }

  const Model& model_;
  const FlightOptions& o_;
  const bool rk4_;
  const ode::StepSettings settings_;
  FlightResult* result_;
  // The step start.
  double t_ = 0.0;
  State y_, f_;
  double rate_ = 0.0;
  int piece_ = 0;             // fit piece at the step start (0, 1, 2)
  int64_t grid_index_ = 0;    // RK4: the last grid point k * dt_s reached
  int64_t next_sample_ = 0;   // index k of the next sample time
  double h_try_ = 0.0;        // DP45 proposal (s)
  // The step being taken.
  double h_ = 0.0;
  State y_new_, f_new_;
  double rate_new_ = 0.0;
  double stage_rate_ = 0.0;  // the largest rate CountedRhs saw (RK4 steps)
  double h_land_ = 0.0;
  State y_land_;
};

}  // namespace

absl::StatusOr<FlightResult> SimulateFlight(const BallSpec& ball,
                                            const LaunchConditions& launch,
                                            const Atmosphere& atmosphere,
                                            const Wind& wind,
                                            const FlightOptions& options) {
  // Validate every input once, here.
  if (auto s = ValidateBallSpec(ball); !s.ok()) return s;
  if (auto s = ValidateLaunchConditions(launch); !s.ok()) return s;
  if (auto s = ValidateWind(wind); !s.ok()) return s;
  if (auto s = ValidateOptions(options); !s.ok()) return s;
  absl::StatusOr<AirProperties> air = ComputeAirProperties(atmosphere);
  if (!air.ok()) return air.status();

  State y0;
  const Model model = BuildModel(ball, launch, &*air, wind, options, &y0);
  FlightResult result;
  result.air = *air;
  result.apex_m = options.launch_height_m;
  result.spin_axis = model.spin_axis;
  Flight flight(model, options, y0, &result);
  if (auto s = flight.Run(); !s.ok()) return s;
  return result;
}

}  // namespace sportsim::golf
