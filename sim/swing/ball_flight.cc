#include "sim/swing/ball_flight.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

namespace sportsim::swing {
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

// Physical constants of the air model (sources in ball_flight.h).
constexpr double kKelvinOffset = 273.15;
constexpr double kIsaSeaLevelTemperatureK = 288.15;
constexpr double kIsaLapseRateKpm = 0.0065;
constexpr double kIsaPressureExponent = 5.25588;  // g0 M / (R* L)
constexpr double kDryAirGasConstant = 287.058;    // J / (kg K)
constexpr double kWaterVapourGasConstant = 461.495;  // J / (kg K)
constexpr double kSutherlandReferenceViscosity = 1.716e-5;  // Pa s
constexpr double kSutherlandReferenceTemperatureK = 273.15;
constexpr double kSutherlandConstantK = 110.4;

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

// Cubic Hermite basis on theta in [0, 1] for values y0, y1 and slopes
// h f0, h f1.
State Hermite(const State& y0, const State& f0, const State& y1,
              const State& f1, double h, double theta) {
  const double t2 = theta * theta;
  const double t3 = t2 * theta;
  const double h00 = 2.0 * t3 - 3.0 * t2 + 1.0;
  const double h10 = t3 - 2.0 * t2 + theta;
  const double h01 = -2.0 * t3 + 3.0 * t2;
  const double h11 = t3 - t2;
  return h00 * y0 + (h10 * h) * f0 + h01 * y1 + (h11 * h) * f1;
}

// One scalar component of the Hermite interpolant and its theta-derivative.
struct ScalarHermite {
  double p0, m0, p1, m1;  // values and h * slopes
  double Value(double s) const {
    const double s2 = s * s, s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 +
           (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * m1;
  }
  double Slope(double s) const {
    const double s2 = s * s;
    return (6 * s2 - 6 * s) * p0 + (3 * s2 - 4 * s + 1) * m0 +
           (-6 * s2 + 6 * s) * p1 + (3 * s2 - 2 * s) * m1;
  }
};

// Root of g on [0, 1] given g(0) >= 0 >= g(1): Newton steps kept inside a
// shrinking bracket, bisection when Newton leaves it. Stops when the bracket
// (times h) is below kEventTimeToleranceS.
template <typename G, typename Dg>
double BracketedRoot(const G& g, const Dg& dg, double guess, double h) {
  double lo = 0.0, hi = 1.0;
  double s = std::clamp(guess, 0.0, 1.0);
  for (int i = 0; i < 200 && (hi - lo) * h > kEventTimeToleranceS; ++i) {
    const double value = g(s);
    if (value > 0.0) {
      lo = s;
    } else {
      hi = s;
    }
    const double slope = dg(s);
    double next = (slope != 0.0) ? s - value / slope : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    if (std::abs(next - s) * h < 0.5 * kEventTimeToleranceS) {
      s = next;
      break;
    }
    s = next;
  }
  return s;
}

// Classical RK4 step (k1 given).
State Rk4Step(const Model& model, const State& y, const State& k1, double h,
              int64_t* evals) {
  State k2, k3, k4;
  Derivative(model, y + (0.5 * h) * k1, &k2, nullptr);
  Derivative(model, y + (0.5 * h) * k2, &k3, nullptr);
  Derivative(model, y + h * k3, &k4, nullptr);
  *evals += 3;
  return y + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
}

// Dormand-Prince 5(4) step (k1 given), the tableau of Dormand & Prince
// (1980): c = 0, 1/5, 3/10, 4/5, 8/9, 1, 1; the 5th-order weights advance the
// solution, b5 - b4 gives the error estimate. Returns the 5th-order solution; when
// `error` is given it also receives the embedded estimate y5 - y4 and
// `k7_out` the derivative at y5 (first-same-as-last: the next step's k1).
State Dp45Step(const Model& model, const State& y, const State& k1, double h,
               State* error, State* k7_out, int64_t* evals) {
  State k2, k3, k4, k5, k6, k7;
  Derivative(model, y + h * (1.0 / 5.0) * k1, &k2, nullptr);
  Derivative(model, y + h * ((3.0 / 40.0) * k1 + (9.0 / 40.0) * k2), &k3,
             nullptr);
  Derivative(model,
             y + h * ((44.0 / 45.0) * k1 - (56.0 / 15.0) * k2 +
                      (32.0 / 9.0) * k3),
             &k4, nullptr);
  Derivative(model,
             y + h * ((19372.0 / 6561.0) * k1 - (25360.0 / 2187.0) * k2 +
                      (64448.0 / 6561.0) * k3 - (212.0 / 729.0) * k4),
             &k5, nullptr);
  Derivative(model,
             y + h * ((9017.0 / 3168.0) * k1 - (355.0 / 33.0) * k2 +
                      (46732.0 / 5247.0) * k3 + (49.0 / 176.0) * k4 -
                      (5103.0 / 18656.0) * k5),
             &k6, nullptr);
  const State y5 =
      y + h * ((35.0 / 384.0) * k1 + (500.0 / 1113.0) * k3 +
               (125.0 / 192.0) * k4 - (2187.0 / 6784.0) * k5 +
               (11.0 / 84.0) * k6);
  *evals += 5;
  if (error != nullptr) {
    Derivative(model, y5, &k7, nullptr);
    *evals += 1;
    *k7_out = k7;
    *error = h * ((71.0 / 57600.0) * k1 - (71.0 / 16695.0) * k3 +
                  (71.0 / 1920.0) * k4 - (17253.0 / 339200.0) * k5 +
                  (22.0 / 525.0) * k6 - (1.0 / 40.0) * k7);
  }
  return y5;
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
  if (model.aero.fit == AeroFit::kNathan) return speed;
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
  if (model.aero.fit == AeroFit::kNathan) return speed_rate;
  return model.radius * (dy[kW] - y[kW] * speed_rate / speed) / speed;
}

// The lower (upper = false) or upper breakpoint of PieceVariable.
double Breakpoint(const Model& model, bool upper) {
  if (model.aero.fit == AeroFit::kNathan) {
    return (upper ? model.aero.re_high : model.aero.re_low) / model.re_per_speed;
  }
  return upper ? model.aero.s_max : model.aero.s_min;
}

// Which piece of the fit applies: 0 (at or below the lower breakpoint), 1
// (between), 2 (at or above the upper one). Mirrors the branches of
// DragCoefficient and LiftCoefficient.
int FitPiece(const Model& model, const State& y) {
  const double v = PieceVariable(model, y);
  if (v <= Breakpoint(model, false)) return 0;
  return v >= Breakpoint(model, true) ? 2 : 1;
}

// One step of the chosen scheme without error control (h = 0: no step).
State Advance(const Model& model, bool rk4, const State& y, const State& f,
              double h, int64_t* evals) {
  if (h <= 0.0) return y;
  return rk4 ? Rk4Step(model, y, f, h, evals)
             : Dp45Step(model, y, f, h, nullptr, nullptr, evals);
}

// First theta in (0, 1] where the Hermite interpolant of the step enters
// drag regime `target` (from the adjacent regime; `upward` = toward higher
// Re). Bisection; the end of the step is known to be past the boundary.
double RegimeCrossing(const Model& model, const State& y0, const State& f0,
                      const State& y1, const State& f1, double h, bool upward,
                      int target) {
  const auto reached = [&](double theta) {
    const int r = FitPiece(model, Hermite(y0, f0, y1, f1, h, theta));
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

absl::Status ValidateAtmosphere(const Atmosphere& air) {
  if (auto s = CheckFiniteInRange("temperature_c", air.temperature_c, -60, false, 60,
                          false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("pressure_pa", air.pressure_pa, 80000, false, 110000,
                          false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("relative_humidity", air.relative_humidity, 0, false,
                          1, false);
      !s.ok())
    return s;
  return CheckFiniteInRange("altitude_m", air.altitude_m, -500, false, 5000, false);
}

}  // namespace

absl::Status ValidateWind(const Wind& wind) {
  if (auto s = CheckFiniteInRange("wind speed_mps", wind.speed_mps, 0, false, 50, false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("wind toward_deg", wind.toward_deg, -360, false, 360,
                          false);
      !s.ok())
    return s;
  switch (wind.profile) {
    case WindProfile::kUniform:
      return absl::OkStatus();
    case WindProfile::kLogarithmic:
      if (auto s = CheckFiniteInRange("wind reference_height_m",
                              wind.reference_height_m, 0, true, 1000, false);
          !s.ok())
        return s;
      return CheckFiniteInRange("wind roughness_length_m", wind.roughness_length_m, 0,
                        true, wind.reference_height_m, true);
  }
  return absl::InvalidArgumentError(absl::StrFormat(
      "wind profile must be kUniform or kLogarithmic, got %d",
      static_cast<int>(wind.profile)));
}

namespace {

absl::Status ValidateAero(const AeroCoefficients& a) {
  if (a.fit != AeroFit::kFergusonMcNallyMcPhee2022 && a.fit != AeroFit::kNathan) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "aero fit must be kFergusonMcNallyMcPhee2022 or kNathan, got %d",
        static_cast<int>(a.fit)));
  }
  const struct {
    const char* name;
    double value;
  } poly[] = {{"aero cd_c0", a.cd_c0}, {"aero cd_c1", a.cd_c1}, {"aero cd_c2", a.cd_c2},
              {"aero cl_c0", a.cl_c0}, {"aero cl_c1", a.cl_c1}, {"aero cl_c2", a.cl_c2}};
  for (const auto& c : poly) {
    if (auto s = CheckFiniteInRange(c.name, c.value, -10, false, 10, false); !s.ok()) return s;
  }
  if (auto s = CheckFiniteInRange("aero s_max", a.s_max, 0, true, 10, false); !s.ok()) return s;
  if (auto s = CheckFiniteInRange("aero s_min", a.s_min, 0, true, a.s_max, true); !s.ok())
    return s;
  if (a.fit == AeroFit::kFergusonMcNallyMcPhee2022) {
    // C_D over [s_min, s_max] must not go negative: its minimum is at an end or the vertex.
    double lowest = std::min(DragCoefficient(a, 0, a.s_min), DragCoefficient(a, 0, a.s_max));
    if (a.cd_c2 != 0.0) {
      const double vertex = -a.cd_c1 / (2.0 * a.cd_c2);
      if (vertex > a.s_min && vertex < a.s_max) {
        lowest = std::min(lowest, DragCoefficient(a, 0, vertex));
      }
    }
    if (lowest < 0.0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "aero cd_c0, cd_c1, cd_c2 give a negative C_D (%g) on [s_min, s_max]", lowest));
    }
  }
  if (auto s = CheckFiniteInRange("aero cd_low", a.cd_low, 0, false, 10, false); !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("aero cd_high", a.cd_high, 0, false, 10, false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("aero cd_spin", a.cd_spin, 0, false, 10, false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("aero re_low", a.re_low, 0, true, 1e7, true); !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("aero re_high", a.re_high, a.re_low, true, 1e7, false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("aero cl_amplitude", a.cl_amplitude, 0, false, 10,
                          false);
      !s.ok())
    return s;
  if (auto s = CheckFiniteInRange("aero cl_exponent", a.cl_exponent, 0.1, false, 2,
                          false);
      !s.ok())
    return s;
  return CheckFiniteInRange("aero spin_decay_coefficient", a.spin_decay_coefficient, 0,
                    true, 1e-2, false);
}

absl::Status ValidateOptions(const FlightOptions& o) {
  if (auto s = CheckFiniteInRange("dt_s", o.dt_s, 0, true, 0.1, false); !s.ok()) return s;
  switch (o.integrator) {
    case FlightIntegrator::kRk4:
      if (o.tolerance != 0.0) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "tolerance applies only to the adaptive integrator "
            "kDormandPrince45; the fixed-step kRk4 is controlled by dt_s "
            "alone, so tolerance must be 0, got %g",
            o.tolerance));
      }
      break;
    case FlightIntegrator::kDormandPrince45:
      if (auto s = CheckFiniteInRange("tolerance (required by kDormandPrince45)",
                              o.tolerance, 0, true, 1e-2, false);
          !s.ok())
        return s;
      if (auto s = CheckFiniteInRange("max_step_s", o.max_step_s, o.dt_s, false, 1.0,
                              false);
          !s.ok())
        return s;
      break;
    default:
      return absl::InvalidArgumentError(
          absl::StrFormat("integrator must be kRk4 or kDormandPrince45, got %d",
                          static_cast<int>(o.integrator)));
  }
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
  if ((o.disabled & ~kFlightDisableAll) != 0) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "disabled must only hold FlightDisable bits (mask 0x%x), got 0x%x",
        kFlightDisableAll, o.disabled));
  }
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

}  // namespace

absl::StatusOr<AirProperties> ComputeAirProperties(const Atmosphere& air) {
  if (auto s = ValidateAtmosphere(air); !s.ok()) return s;
  const double t_k = air.temperature_c + kKelvinOffset;
  AirProperties out;
  // ISA barometric reduction from sea level to the course.
  out.station_pressure_pa =
      air.pressure_pa *
      std::pow(1.0 - kIsaLapseRateKpm * air.altitude_m /
                         kIsaSeaLevelTemperatureK,
               kIsaPressureExponent);
  // Buck saturation vapour pressure over water.
  const double tc = air.temperature_c;
  const double saturation_pa =
      611.21 * std::exp((18.678 - tc / 234.5) * (tc / (257.14 + tc)));
  out.vapour_pressure_pa = air.relative_humidity * saturation_pa;
  // Humid air: dry-air and water-vapour partial densities.
  out.density_kgpm3 =
      (out.station_pressure_pa - out.vapour_pressure_pa) /
          (kDryAirGasConstant * t_k) +
      out.vapour_pressure_pa / (kWaterVapourGasConstant * t_k);
  // Sutherland's law.
  out.viscosity_pas =
      kSutherlandReferenceViscosity *
      std::pow(t_k / kSutherlandReferenceTemperatureK, 1.5) *
      (kSutherlandReferenceTemperatureK + kSutherlandConstantK) /
      (t_k + kSutherlandConstantK);
  return out;
}

Vector3d WindVelocity(const Wind& wind, double height_m) {
  const double b = wind.toward_deg * kDegToRad;
  const Vector3d direction(std::cos(b), -std::sin(b), 0.0);
  if (wind.profile == WindProfile::kUniform) {
    return wind.speed_mps * direction;
  }
  const double z = std::max(height_m, 0.0);
  return wind.speed_mps * std::log1p(z / wind.roughness_length_m) /
         std::log1p(wind.reference_height_m / wind.roughness_length_m) *
         direction;
}

double DragCoefficient(const AeroCoefficients& aero, double reynolds,
                       double spin_parameter) {
  if (aero.fit == AeroFit::kFergusonMcNallyMcPhee2022) {
    const double sp = std::clamp(spin_parameter, aero.s_min, aero.s_max);
    return aero.cd_c0 + sp * (aero.cd_c1 + sp * aero.cd_c2);
  }
  double cd0;
  if (reynolds <= aero.re_low) {
    cd0 = aero.cd_low;
  } else if (reynolds >= aero.re_high) {
    cd0 = aero.cd_high;
  } else {
    cd0 = aero.cd_low + (aero.cd_high - aero.cd_low) *
                            (reynolds - aero.re_low) /
                            (aero.re_high - aero.re_low);
  }
  return cd0 + aero.cd_spin * spin_parameter;
}

double LiftCoefficient(const AeroCoefficients& aero, double spin_parameter) {
  if (!(spin_parameter > 0.0)) return 0.0;
  if (aero.fit == AeroFit::kFergusonMcNallyMcPhee2022) {
    const auto quadratic = [&](double sp) {
      return aero.cl_c0 + sp * (aero.cl_c1 + sp * aero.cl_c2);
    };
    if (spin_parameter < aero.s_min) {
      return quadratic(aero.s_min) * spin_parameter / aero.s_min;
    }
    return std::max(0.0, quadratic(std::min(spin_parameter, aero.s_max)));
  }
  return aero.cl_amplitude * std::pow(spin_parameter, aero.cl_exponent);
}

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
  const uint32_t off = options.disabled;
  Model model;
  model.gravity = options.gravity_mps2;
  model.k_aero = 0.5 * air->density_kgpm3 * ball.area_m2() / ball.mass_kg;
  model.radius = ball.radius_m();
  model.re_per_speed =
      air->density_kgpm3 * ball.diameter_m / air->viscosity_pas;
  model.spin_axis = std::cos(tilt) * right - std::sin(tilt) * up;
  model.aero = options.aero;
  model.drag = (off & kFlightDisableDrag) == 0;
  model.lift = (off & kFlightDisableLift) == 0;
  // Nathan's kinks are in C_D only; Ferguson et al.'s S clamps bend both.
  model.breakpoints = options.aero.fit == AeroFit::kNathan ? model.drag
                                                            : model.drag || model.lift;
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
  State y;
  y.head<3>() = Vector3d(0.0, 0.0, options.launch_height_m);
  y.segment<3>(3) = launch.ball_speed_mps * d;
  y[kW] = launch.spin_rpm * kRpmToRadPerS;
  if (model.spin_decay && !model.instantaneous_decay) {
    Vector3d u0 = y.segment<3>(3);
    if (model.wind) u0 -= WindAt(model, options.launch_height_m);
    model.inv_tau_launch =
        options.aero.spin_decay_coefficient * u0.norm() / model.radius;
  }

  FlightResult result;
  result.air = *air;
  result.apex_m = options.launch_height_m;
  const bool rk4 = options.integrator == FlightIntegrator::kRk4;
  const double sample_dt = options.sample_interval_s;
  int64_t next_sample = 0;  // index k of the next sample time k * sample_dt
  int64_t grid_index = 0;   // RK4: the last grid point k * dt_s reached

  State f;
  double rate = 0.0;
  Derivative(model, y, &f, &rate);
  result.rhs_evaluations = 1;
  int regime = model.breakpoints ? FitPiece(model, y) : 0;

  double t = 0.0;
  double h_try = options.dt_s;  // DP45 proposal
  while (true) {
    if (t >= options.max_flight_time_s) {
      return absl::OutOfRangeError(absl::StrFormat(
          "the ball did not land within max_flight_time_s = %g s (height "
          "%g m at t = %.6f s)",
          options.max_flight_time_s, y[kZ], t));
    }

    // Stage 1: take a step (RK4 to the next grid point; DP45 until its error
    // test passes).
    double h;
    State y_new;
    State f_new;
    double rate_new = 0.0;
    if (rk4) {
      h = static_cast<double>(grid_index + 1) * options.dt_s - t;
      if (rate * h > kRk4StabilityLimit) {
        return absl::OutOfRangeError(absl::StrFormat(
            "dt_s = %g s is too large for RK4 at t = %.6f s: aerodynamic rate "
            "%g 1/s x dt = %g exceeds the stability bound %g; reduce dt_s or "
            "use kDormandPrince45",
            options.dt_s, t, rate, rate * h, kRk4StabilityLimit));
      }
      y_new = Rk4Step(model, y, f, h, &result.rhs_evaluations);
      Derivative(model, y_new, &f_new, &rate_new);
      ++result.rhs_evaluations;
    } else {
      h = std::min(h_try, options.max_step_s);
      State err;
      y_new = Dp45Step(model, y, f, h, &err, &f_new, &result.rhs_evaluations);
      double ratio = 0.0;
      for (int i = 0; i < State::RowsAtCompileTime; ++i) {
        const double scale =
            options.tolerance *
            (1.0 + std::max(std::abs(y[i]), std::abs(y_new[i])));
        ratio = std::max(ratio, std::abs(err[i]) / scale);
      }
      if (!std::isfinite(ratio)) ratio = 1e10;  // shrink hard
      const double factor =
          ratio == 0.0 ? 5.0
                       : std::clamp(0.9 * std::pow(ratio, -0.2), 0.2, 5.0);
      if (ratio > 1.0) {
        ++result.rejected_steps;
        h_try = h * std::min(factor, 1.0);
        if (h_try < 1e-12) {
          return absl::OutOfRangeError(absl::StrFormat(
              "step size underflow (%g s) at t = %.6f s", h_try, t));
        }
        continue;
      }
      h_try = h * factor;
    }
    if (!y_new.allFinite() || !f_new.allFinite()) {
      return absl::OutOfRangeError(absl::StrFormat(
          "non-finite ball state at t = %.6f s (after the step from t = %.6f "
          "s)",
          t + h, t));
    }

    // Stage 2: the fit's breakpoints (Nathan: Re at re_low and re_high;
    // Ferguson et al.: S at s_min and s_max). A step that crosses one is cut
    // short onto the crossing so no step integrates across a kink (this keeps
    // RK4 at order 4 and DP45's error estimate honest).
    bool on_grid = true;
    if (model.breakpoints) {
      const int regime_end = FitPiece(model, y_new);
      while (regime_end != regime) {
        const int next = regime + (regime_end > regime ? 1 : -1);
        const double theta =
            RegimeCrossing(model, y, f, y_new, f_new, h, next > regime, next);
        if (theta * h <= kEventTimeToleranceS) {
          regime = next;  // already on the boundary
          continue;
        }
        const ScalarHermite z{y[kZ], h * f[kZ], y_new[kZ], h * f_new[kZ]};
        if (y_new[kZ] <= 0.0 && z.Value(theta) <= 0.0) break;  // lands first
        // The interpolant straddles the kink, so its crossing is only a first
        // guess: refine the partial step's length by Newton on the piece
        // variable until the step ends on the boundary.
        const double boundary = Breakpoint(model, std::max(regime, next) == 2);
        const double h_full = h;
        h = theta * h_full;
        for (int iter = 0;; ++iter) {
          y_new = Advance(model, rk4, y, f, h, &result.rhs_evaluations);
          Derivative(model, y_new, &f_new, &rate_new);
          ++result.rhs_evaluations;
          if (iter == kMaxRefinements) break;
          const double value = PieceVariable(model, y_new);
          const double value_rate = PieceVariableRate(model, y_new, f_new);
          if (!(std::abs(value_rate) > 0.0) || !std::isfinite(value)) break;
          const double h_next = std::clamp(
              h - (value - boundary) / value_rate, 0.0, h_full);
          if (h_next == h || h_next <= 0.0) break;
          h = h_next;
        }
        on_grid = false;
        regime = next;
        break;
      }
    }
    const double t_new = t + h;
    ++result.steps;
    if (rk4 && on_grid) ++grid_index;

    // Stage 3: apex, where vz changes sign: root of the Hermite interpolant
    // of vz, refined on the integrator's own partial step.
    if (y[kVz] > 0.0 && y_new[kVz] <= 0.0) {
      const ScalarHermite vz{y[kVz], h * f[kVz], y_new[kVz], h * f_new[kVz]};
      double h_top =
          h * BracketedRoot([&](double q) { return vz.Value(q); },
                            [&](double q) { return vz.Slope(q); },
                            y[kVz] / (y[kVz] - y_new[kVz]), h);
      State y_top;
      for (int iter = 0;; ++iter) {
        y_top = Advance(model, rk4, y, f, h_top, &result.rhs_evaluations);
        State f_top;
        Derivative(model, y_top, &f_top, nullptr);
        ++result.rhs_evaluations;
        if (iter == kMaxRefinements || !(f_top[kVz] < 0.0)) break;
        const double h_next =
            std::clamp(h_top - y_top[kVz] / f_top[kVz], 0.0, h);
        if (h_next == h_top) break;
        h_top = h_next;
      }
      if (y_top[kZ] > result.apex_m) {
        result.apex_m = y_top[kZ];
        result.apex_time_s = t + h_top;
      }
    }

    // Stage 4: landing, the first step that ends at or below z = 0: root of
    // the Hermite interpolant of z, refined on the partial step (Newton on z).
    const bool lands = y_new[kZ] <= 0.0;
    double h_land = h;
    State y_land = y_new;
    if (lands) {
      const ScalarHermite z{y[kZ], h * f[kZ], y_new[kZ], h * f_new[kZ]};
      const double guess = y[kZ] > 0.0 ? y[kZ] / (y[kZ] - y_new[kZ]) : 0.0;
      h_land = h * BracketedRoot([&](double q) { return z.Value(q); },
                                 [&](double q) { return z.Slope(q); }, guess,
                                 h);
      for (int iter = 0;; ++iter) {
        y_land = Advance(model, rk4, y, f, h_land, &result.rhs_evaluations);
        const double vz = y_land[kVz];
        if (iter == kMaxRefinements || !(vz < 0.0)) break;
        const double h_next = std::clamp(h_land - y_land[kZ] / vz, 0.0, h);
        if (h_next == h_land) break;
        h_land = h_next;
      }
      if (!y_land.allFinite()) {
        return absl::OutOfRangeError(absl::StrFormat(
            "non-finite ball state while locating the landing at t = %.6f s",
            t + h_land));
      }
    }
    const double t_end = lands ? t + h_land : t_new;

    // Stage 5: samples at k * sample_dt inside [t, t_end).
    if (sample_dt > 0.0) {
      while (true) {
        const double ts = static_cast<double>(next_sample) * sample_dt;
        if (ts >= t_end) break;
        const double theta = (ts - t) / h;
        result.samples.push_back(MakeSample(
            ts, theta <= 0.0 ? y : Hermite(y, f, y_new, f_new, h, theta)));
        ++next_sample;
      }
    }

    if (lands) {
      const Vector3d p = y_land.head<3>();
      const Vector3d v = y_land.segment<3>(3);
      result.flight_time_s = t_end;
      result.landing_position_m = p;
      result.landing_velocity_mps = v;
      result.carry_m = std::hypot(p.x(), p.y());
      result.carry_downrange_m = p.x();
      result.lateral_m = -p.y();
      result.landing_speed_mps = v.norm();
      result.landing_angle_deg =
          std::atan2(-v.z(), std::hypot(v.x(), v.y())) / kDegToRad;
      result.landing_spin_rpm = y_land[kW] / kRpmToRadPerS;
      if (sample_dt > 0.0) result.samples.push_back(MakeSample(t_end, y_land));
      return result;
    }

    y = y_new;
    f = f_new;
    rate = rate_new;
    t = t_new;
  }
}

}  // namespace sportsim::swing
