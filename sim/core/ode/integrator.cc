#include "sim/core/ode/integrator.h"

#include <cmath>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

namespace sportsim::ode {
namespace {

constexpr std::array<std::string_view, 5> kNames = {"euler", "semi_implicit_euler", "rk4",
                                                    "dp45", "book"};

// "NAME must be finite and in [lo, hi] UNIT, got V".
absl::Status CheckRange(std::string_view name, double value, const Range& r,
                        std::string_view unit) {
  const bool ok = std::isfinite(value) && (r.lo_open ? value > r.lo : value >= r.lo) &&
                  (r.hi_open ? value < r.hi : value <= r.hi);
  if (ok) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrFormat(
      "%s must be finite and in %c%g, %g%c%s, got %g", name, r.lo_open ? '(' : '[', r.lo, r.hi,
      r.hi_open ? ')' : ']', unit, value));
}

}  // namespace

std::string_view IntegratorName(Integrator integrator) {
  const auto i = static_cast<size_t>(integrator);
  return i < kNames.size() ? kNames[i] : "unknown";
}

std::optional<Integrator> IntegratorFromName(std::string_view name) {
  for (Integrator i : kAllIntegrators) {
    if (IntegratorName(i) == name) return i;
  }
  return std::nullopt;
}

absl::Status ValidateAccuracy(Integrator integrator, const Accuracy& a,
                              const AccuracyLimits& limits) {
  const std::string_view name = IntegratorName(integrator);
  if (IsErrorControlled(integrator)) {
    // dp45: a tolerance (and a largest step), never a fixed step.
    if (a.dt_s.has_value()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "dt_s does not apply to %s: it is error-controlled; set tolerance (and max_step_s)",
          name));
    }
    if (!a.tolerance.has_value() && !limits.default_tolerance.has_value()) {
      return absl::InvalidArgumentError(
          absl::StrFormat("tolerance is required by %s (in %c%g, %g%c)", name,
                          limits.tolerance.lo_open ? '(' : '[', limits.tolerance.lo,
                          limits.tolerance.hi, limits.tolerance.hi_open ? ')' : ']'));
    }
    if (a.tolerance) {
      if (absl::Status s = CheckRange("tolerance", *a.tolerance, limits.tolerance, ""); !s.ok()) {
        return s;
      }
    }
    if (a.max_step_s) {
      if (absl::Status s = CheckRange("max_step_s", *a.max_step_s, limits.max_step_s, " s"); !s.ok()) {
        return s;
      }
    }
    return absl::OkStatus();
  }
  // Fixed-step schemes: the step alone.
  if (a.tolerance.has_value()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "tolerance applies only to dp45; %s is a fixed-step integrator: set dt_s", name));
  }
  if (a.max_step_s.has_value()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "max_step_s applies only to dp45; %s is a fixed-step integrator: set dt_s", name));
  }
  if (a.dt_s) return CheckRange("dt_s", *a.dt_s, limits.dt_s, " s");
  return absl::OkStatus();
}

StepSettings ResolveAccuracy(Integrator integrator, const Accuracy& a,
                             const AccuracyLimits& limits) {
  if (IsErrorControlled(integrator)) {
    return {.tolerance = a.tolerance.value_or(limits.default_tolerance.value_or(0.0)),
            .max_step_s = a.max_step_s.value_or(limits.default_max_step_s)};
  }
  return {.dt_s = a.dt_s.value_or(limits.default_dt_s)};
}

}  // namespace sportsim::ode
