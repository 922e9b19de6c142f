#include "sim/golf/aero.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_format.h"
#include "sim/core/check.h"

namespace sportsim::golf {

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

}  // namespace sportsim::golf
