// Effect bits: one convention for every model in sim/ (after MuJoCo's mjDSBL_* disable flags,
// mjModel.opt.disableflags, extended to effects that are off by default).
//
// Each domain keeps an `effects` word whose ZERO value is that domain's default physics. A bit
// named k<Domain>Disable<Effect> switches off an effect that is on by default; a bit named
// k<Domain>Enable<Effect> switches on an effect that is off by default (billiards air drag:
// kEffectEnableDrag). No default ever needs a bit set, so `effects = 0` always means "as
// shipped", and a switched-off effect is skipped in the hot loop, not multiplied by zero.
#ifndef SPORTSIM_SIM_CORE_EFFECTS_H_
#define SPORTSIM_SIM_CORE_EFFECTS_H_

#include <cstdint>
#include <string_view>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

namespace sportsim {

/// Whether the effect of `bit` is on in `effects`, given which of the domain's bits are
/// enable bits (`enable_bits`; the others are disable bits).
constexpr bool EffectOn(uint32_t effects, uint32_t bit, uint32_t enable_bits) {
  return ((effects & bit) != 0) == ((enable_bits & bit) != 0);
}

/// `effects` with the effect of `bit` switched on or off.
constexpr uint32_t WithEffect(uint32_t effects, uint32_t bit, bool on, uint32_t enable_bits) {
  const bool set = on == ((enable_bits & bit) != 0);
  return set ? (effects | bit) : (effects & ~bit);
}

/// InvalidArgument "FIELD: unknown effect bits 0x.. (known 0x..)" for bits outside `known`.
inline absl::Status ValidateEffectBits(std::string_view field, uint32_t effects, uint32_t known) {
  if ((effects & ~known) == 0) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrFormat(
      "%s: unknown effect bits 0x%x (known bits 0x%x)", field, effects & ~known, known));
}

}  // namespace sportsim

#endif  // SPORTSIM_SIM_CORE_EFFECTS_H_
