#include "sim/golf/atmosphere.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_format.h"
#include "sim/core/check.h"
#include "sim/golf/golf_ball.h"

namespace sportsim::golf {
namespace {

using Eigen::Vector3d;

// Physical constants of the air model (sources in atmosphere.h).
constexpr double kKelvinOffset = 273.15;
constexpr double kIsaSeaLevelTemperatureK = 288.15;
constexpr double kIsaLapseRateKpm = 0.0065;
constexpr double kIsaPressureExponent = 5.25588;  // g0 M / (R* L)
constexpr double kDryAirGasConstant = 287.058;    // J / (kg K)
constexpr double kWaterVapourGasConstant = 461.495;  // J / (kg K)
constexpr double kSutherlandReferenceViscosity = 1.716e-5;  // Pa s
constexpr double kSutherlandReferenceTemperatureK = 273.15;
constexpr double kSutherlandConstantK = 110.4;

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

}  // namespace sportsim::golf
