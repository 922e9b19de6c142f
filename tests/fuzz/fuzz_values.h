// Decoding numbers "within and slightly beyond" a valid range from fuzz bytes.
#ifndef SPORTSIM_TESTS_FUZZ_FUZZ_VALUES_H_
#define SPORTSIM_TESTS_FUZZ_FUZZ_VALUES_H_

#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <limits>

namespace sportsim::fuzz {

/// Mostly in [lo, hi]; sometimes its ends exactly, a little beyond them (10 % of the width), or
/// a special value (0, -0, NaN, +-inf, huge, denormal).
inline double RangeValue(FuzzedDataProvider& in, double lo, double hi) {
  const uint8_t how = in.ConsumeIntegral<uint8_t>();
  const double w = hi - lo;
  if (how < 200) return in.ConsumeFloatingPointInRange(lo, hi);
  if (how < 215) return how & 1 ? lo : hi;
  if (how < 230) {
    return how & 1 ? in.ConsumeFloatingPointInRange(lo - 0.1 * w, lo)
                   : in.ConsumeFloatingPointInRange(hi, hi + 0.1 * w);
  }
  if (how < 240) return std::nextafter(how & 1 ? lo : hi, how & 2 ? -INFINITY : INFINITY);
  switch (how % 8) {
    case 0: return 0.0;
    case 1: return -0.0;
    case 2: return std::numeric_limits<double>::quiet_NaN();
    case 3: return INFINITY;
    case 4: return -INFINITY;
    case 5: return 1e308;
    case 6: return std::numeric_limits<double>::denorm_min();
    default: return in.ConsumeFloatingPoint<double>();
  }
}

}  // namespace sportsim::fuzz

#endif  // SPORTSIM_TESTS_FUZZ_FUZZ_VALUES_H_
