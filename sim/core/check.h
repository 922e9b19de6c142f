// Input validation shared by the factories in sim/: one wording for every range error.
#ifndef SPORTSIM_SIM_CORE_CHECK_H_
#define SPORTSIM_SIM_CORE_CHECK_H_

#include <cmath>
#include <initializer_list>
#include <string_view>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

namespace sportsim {

/// OK when `value` is finite and inside the interval; otherwise InvalidArgument
/// "NAME must be finite and in (lo, hi], got V" (brackets as the ends are open or closed).
inline absl::Status CheckFiniteInRange(std::string_view name, double value, double lo,
                                       bool lo_open, double hi, bool hi_open) {
  const bool ok = std::isfinite(value) && (lo_open ? value > lo : value >= lo) &&
                  (hi_open ? value < hi : value <= hi);
  if (ok) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrFormat("%s must be finite and in %c%g, %g%c, got %g",
                                                    name, lo_open ? '(' : '[', lo, hi,
                                                    hi_open ? ')' : ']', value));
}

/// One field of a CheckFieldsInRange list.
struct FieldRange {
  std::string_view name;
  double value, lo;
  bool lo_open;
  double hi;
  bool hi_open = false;
};

/// CheckFiniteInRange on each field in order: the first failure, or OK.
inline absl::Status CheckFieldsInRange(std::initializer_list<FieldRange> fields) {
  for (const FieldRange& f : fields) {
    if (absl::Status s = CheckFiniteInRange(f.name, f.value, f.lo, f.lo_open, f.hi, f.hi_open);
        !s.ok()) {
      return s;
    }
  }
  return absl::OkStatus();
}

}  // namespace sportsim

#endif  // SPORTSIM_SIM_CORE_CHECK_H_
