// What a human golfer can do, for the "realistic" profile of live sessions (docs/swing-sessions.md;
// the bounds and how they were chosen are in docs/swing-sessions.md).
//
// The binding limit is the clubhead speed: long-drive champions reach about 67 m/s (docs/swing-sessions.md
// section 3, after Bourg & Bywalec ch. 19 and long-drive measurements); tour players average
// about 51 m/s. We allow 70 m/s, 5 % above the record, so that a record swing passes.
//
// The torque bounds are this model's, not measurements: with the chapter's golfer (Jorgensen's
// fitted arm and club), a constant shoulder torque Q_alpha of 300 N m already brings the
// clubhead to about 68 m/s at impact (100 N m: 43 m/s), and a wrist torque Q_beta of +10 N m
// alone (uncocking early) about 67 m/s. We refuse |Q_alpha| > 350 N m and |Q_beta| > 30 N m
// outright (no golfer of any build gets near them in this model), and leave the rest to the
// clubhead-speed check, which covers every combination of torques and golfer parameters.
#ifndef SPORTSIM_SIM_SWING_REALISM_H_
#define SPORTSIM_SIM_SWING_REALISM_H_

#include <cmath>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

namespace sportsim::swing {

struct HumanLimits {
  double max_shoulder_torque_nm = 350.0;
  double max_wrist_torque_nm = 30.0;
  double max_clubhead_speed_mps = 70.0;  ///< ground frame
};

inline constexpr HumanLimits kHumanLimits{};

/// INVALID_ARGUMENT naming `field` when |q| exceeds `limit` (N m).
inline absl::Status CheckHumanTorque(const std::string& field, double q, double limit) {
  if (std::abs(q) <= limit) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrFormat(
      "%s: %g N m is beyond what a human golfer can apply (realistic profile: |torque| <= %g N "
      "m); use the arcade profile to lift the bound",
      field, q, limit));
}

}  // namespace sportsim::swing

#endif  // SPORTSIM_SIM_SWING_REALISM_H_
