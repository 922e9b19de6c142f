// A golf stroke made by a swing: the chapter's swing model (sim/swing: Jorgensen's double
// pendulum, Bourg & Bywalec ch. 19) with a torque program, run to impact; the clubhead's speed
// and attack angle there, with the club's face angle, path and loft, make the club's delivery;
// the club-ball impact model (club_ball_impact.h) turns it into the ball's launch conditions.
// The same chain `swing simulate --club` runs on the server, as a pure function here so that a
// round's referee can play it (and replay it) like any other stroke.
#ifndef SPORTSIM_SIM_GOLF_SWING_STROKE_H_
#define SPORTSIM_SIM_GOLF_SWING_STROKE_H_

#include <functional>
#include <memory>

#include "absl/status/statusor.h"
#include "sim/golf/club_ball_impact.h"
#include "sim/golf/golf_ball.h"
#include "sim/swing/swing_model.h"
#include "sim/swing/torque_program.h"

namespace sportsim::golf {

struct SwingStroke {
  std::shared_ptr<const swing::SwingModel> model;  ///< the golfer and club shaft (required)
  swing::TorqueProgram program = swing::TorqueProgram::Chapter();
  ClubSpec club;
  /// The face angle, path and dynamic loft; its speed and attack angle come from the swing.
  ClubDelivery delivery;
};

struct SwingLaunch {
  LaunchConditions launch;          ///< relative to the aim (+ right)
  double clubhead_speed_mps = 0.0;  ///< at impact, over the ground
  double attack_angle_deg = 0.0;    ///< the clubhead's path at impact, + up
  double impact_t_s = 0.0;          ///< from the top of the backswing
};

/// Runs the swing to impact (RK4 at the chapter's 2.5 ms, at most 2 s) and the impact.
/// InvalidArgument naming "torques" when the swing never reaches the ball; the impact model's
/// own errors (a delivery it refuses) pass through; Cancelled when `cancelled` says so.
absl::StatusOr<SwingLaunch> LaunchFromSwing(const SwingStroke& stroke, const BallSpec& ball,
                                            const std::function<bool()>& cancelled = {});

}  // namespace sportsim::golf

#endif  // SPORTSIM_SIM_GOLF_SWING_STROKE_H_
