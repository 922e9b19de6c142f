// A swing on a server's clock: advanced tick by tick, with torques from a schedule or from a
// driver's timestamped commands, the impact searched in every step, and the realism check.
// What a tick produces is reported as domain events and an end reason; no server, no protobuf.
//
// A scheduled swing steps exactly as SimulateSwing does (the same Step calls, the same impact
// search), so its states and impact are bit-identical to SimulateSwing's whatever the ticks; a
// tick reports the state at its time, interpolated when a step overshoots it. A driven swing
// never steps past the last tick (a command may still come for the next one); with a fixed step
// that divides the tick period it too is bit-identical to SimulateSwing with the same torques as
// a schedule.
#ifndef SPORTSIM_SIM_SWING_LIVE_SWING_H_
#define SPORTSIM_SIM_SWING_LIVE_SWING_H_

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "sim/swing/swing_model.h"
#include "sim/swing/swing_simulation.h"
#include "sim/swing/swing_stepper.h"
#include "sim/swing/torque_program.h"

namespace sportsim::swing {

/// Why a live swing ended.
enum class SwingEnd : uint8_t {
  kImpact,    ///< the club met the ball and the swing stops there
  kDuration,  ///< the swing's duration ran out
  kError,     ///< the solver failed (the state stays the last good one)
  kReset,     ///< the session was reset
  kDeleted,   ///< the session was deleted
};
std::string_view SwingEndName(SwingEnd e);  ///< "impact", "duration", "error", "reset", "deleted"

struct LiveSwingEnd {
  SwingEnd reason = SwingEnd::kImpact;
  std::string error;  ///< kError: what the solver said
  /// "impact", "duration", "error: ...", "reset", "deleted".
  std::string Describe() const;
};

struct LiveSwingOptions {
  SwingStop stop = SwingStop::kImpact;
  double duration_s = 2.0;  ///< the swing ends at the first tick at or after this time (s)
  double tick_hz = 400.0;   ///< the clock's rate: swing tick n is at n / tick_hz (s)
  bool driven = false;      ///< torques from commands (Queue) instead of the program
  bool realistic = true;    ///< report a clubhead beyond human reach once
};

/// A driver's torque command, waiting for its tick.
struct QueuedTorque {
  int64_t n = 0;  ///< the swing tick from which it applies
  double t_s = 0.0, qalpha_nm = 0.0, qbeta_nm = 0.0;
  uint64_t index = 0;  ///< 1, 2, ... in the order received
  bool late = false;   ///< asked for a time already simulated; applied at the next tick
};

/// Something a tick of a live swing reports.
struct LiveSwingEvent {
  enum class Kind : uint8_t {
    kTorque,       ///< a queued command took effect (at `t_s`, reported at tick n)
    kImpact,       ///< the club met the ball (`impact`)
    kBeyondHuman,  ///< realistic profile: the clubhead passed a human's reach
  };
  Kind kind = Kind::kTorque;
  int64_t n = 0;      ///< the swing tick it is reported at
  double t_s = 0.0;   ///< swing time (s)
  QueuedTorque command;   ///< kTorque
  SwingSample impact;     ///< kImpact
  double clubhead_speed_mps = 0.0;  ///< kBeyondHuman
};

class LiveSwing {
 public:
  /// `qalpha_nm`/`qbeta_nm`: a driven swing's starting torques. The solver must be valid.
  static absl::StatusOr<std::unique_ptr<LiveSwing>> Create(const SwingModel& model,
                                                           TorqueProgram program,
                                                           const SwingSolverOptions& solver,
                                                           const LiveSwingOptions& options,
                                                           double qalpha_nm = 0.0,
                                                           double qbeta_nm = 0.0);

  /// Advances to swing tick n (>= 1, one more than the last): applies the commands due, steps,
  /// finds the impact, and sets state() and the torques in force. Returns the end, if it ended.
  std::optional<LiveSwingEnd> Advance(int64_t n, std::vector<LiveSwingEvent>* out);

  /// The state at the last tick advanced (at 0 before the first).
  const SwingSample& state() const { return state_; }
  double qalpha_nm() const { return qalpha_; }  ///< the torques in force at state()
  double qbeta_nm() const { return qbeta_; }
  const std::optional<SwingSample>& impact() const { return impact_; }
  const SwingModel& model() const { return model_; }
  const LiveSwingOptions& options() const { return options_; }
  /// Driven: commands waiting for their ticks, in time order.
  std::deque<QueuedTorque>& pending() { return pending_; }
  /// The last swing tick whose commands can still act (the swing ends at the first tick at or
  /// after its duration).
  int64_t LastCommandTick() const;
  /// The swing tick a command at `t_s` applies from (the first tick at or after it).
  int64_t CommandTick(double t_s) const;

 private:
  LiveSwing(const SwingModel& model, TorqueProgram program, const SwingSolverOptions& solver,
            const LiveSwingOptions& options);
  void ApplyDueCommands(int64_t n, std::vector<LiveSwingEvent>* out);
  void SetTorques();

  const SwingModel model_;
  TorqueProgram program_;
  const SwingSolverOptions solver_;
  const LiveSwingOptions options_;
  std::optional<SwingStepper> stepper_;
  StepRecord record_;
  std::optional<SwingSample> impact_;
  bool impact_reported_ = false;
  bool beyond_flagged_ = false;
  std::deque<QueuedTorque> pending_;
  double driven_qalpha_ = 0.0, driven_qbeta_ = 0.0;  // driven: the commanded torques
  SwingSample state_;
  double qalpha_ = 0.0, qbeta_ = 0.0;
};

}  // namespace sportsim::swing

#endif  // SPORTSIM_SIM_SWING_LIVE_SWING_H_
