// Air and wind at the course, for golf-ball flight (ball_flight.h).
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
//
// Wind: horizontal, one direction, uniform or with a logarithmic height
// profile w(z) = w_ref ln(1 + z / z0) / ln(1 + z_ref / z0) (the neutral
// surface-layer log law, shifted by z0 so it is smooth and zero at the
// ground); z0 = 0.03 m is the "open flat terrain, grass" class of the
// Davenport-Wieringa roughness classification.
//
#ifndef SPORTSIM_SIM_GOLF_ATMOSPHERE_H_
#define SPORTSIM_SIM_GOLF_ATMOSPHERE_H_

#include <Eigen/Dense>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace sportsim::golf {

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

}  // namespace sportsim::golf

#endif  // SPORTSIM_SIM_GOLF_ATMOSPHERE_H_
