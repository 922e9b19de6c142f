#include "sim/golf/swing_stroke.h"

#include <cmath>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "sim/swing/swing_simulation.h"

namespace sportsim::golf {

absl::StatusOr<SwingLaunch> LaunchFromSwing(const SwingStroke& stroke, const BallSpec& ball,
                                            const std::function<bool()>& cancelled) {
  if (stroke.model == nullptr) return absl::InvalidArgumentError("swing: no golfer model");
  swing::SwingRunOptions run;
  run.stop = swing::SwingStop::kImpact;
  run.duration_s = 2.0;
  run.sample_stride = 1 << 20;  // the first and last states only; the impact is located apart
  run.cancelled = cancelled;
  absl::StatusOr<swing::SwingRunResult> swung =
      swing::SimulateSwing(*stroke.model, stroke.program, swing::SwingSolverOptions{}, run);
  if (!swung.ok()) return swung.status();
  if (!swung->impact) {
    return absl::InvalidArgumentError(
        "torques: the swing never reaches the ball (no impact within 2 s of the top of the "
        "backswing)");
  }
  const swing::SwingSample& at = *swung->impact;
  SwingLaunch out;
  out.impact_t_s = at.t_s;
  out.clubhead_speed_mps = at.clubhead_speed_ground_mps;
  // The clubhead's ground-frame velocity above the horizontal, toward the target (-x in the
  // swing's frame), as `swing simulate --club` takes it.
  out.attack_angle_deg =
      std::atan2(at.clubhead_vy_ground_mps, -at.clubhead_vx_ground_mps) * 180.0 / std::numbers::pi;
  ClubDelivery d = stroke.delivery;
  d.clubhead_speed_mps = out.clubhead_speed_mps;
  d.attack_angle_deg = out.attack_angle_deg;
  absl::StatusOr<ImpactResult> hit = SimulateImpact(d, stroke.club, ball);
  if (!hit.ok()) return hit.status();
  out.launch = hit->launch;
  return out;
}

}  // namespace sportsim::golf
