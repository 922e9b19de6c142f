// Unit conversions used at API edges. Inside sim/ everything is SI (m, s, kg, rad).
#ifndef SPORTSIM_SIM_CORE_UNITS_H_
#define SPORTSIM_SIM_CORE_UNITS_H_

#include <numbers>

namespace sportsim {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kTwoPi = 2.0 * std::numbers::pi;

constexpr double DegToRad(double deg) { return deg * (kPi / 180.0); }
constexpr double RadToDeg(double rad) { return rad * (180.0 / kPi); }

}  // namespace sportsim

#endif  // SPORTSIM_SIM_CORE_UNITS_H_
