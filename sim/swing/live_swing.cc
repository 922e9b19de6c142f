#include "sim/swing/live_swing.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/strings/str_format.h"
#include "sim/swing/realism.h"

namespace sportsim::swing {

namespace {

// A tick time and a step end closer than this fraction of a tick period are the same instant.
constexpr double kSnapTicks = 1e-9;

}  // namespace

std::string_view SwingEndName(SwingEnd e) {
  switch (e) {
    case SwingEnd::kImpact: return "impact";
    case SwingEnd::kDuration: return "duration";
    case SwingEnd::kError: return "error";
    case SwingEnd::kReset: return "reset";
    case SwingEnd::kDeleted: return "deleted";
  }
  return "unknown";
}

std::string LiveSwingEnd::Describe() const {
  if (reason == SwingEnd::kError) return absl::StrFormat("error: %s", error);
  return std::string(SwingEndName(reason));
}

LiveSwing::LiveSwing(const SwingModel& model, TorqueProgram program,
                     const SwingSolverOptions& solver, const LiveSwingOptions& options)
    : model_(model), program_(std::move(program)), solver_(solver), options_(options) {}

absl::StatusOr<std::unique_ptr<LiveSwing>> LiveSwing::Create(const SwingModel& model,
                                                             TorqueProgram program,
                                                             const SwingSolverOptions& solver,
                                                             const LiveSwingOptions& options,
                                                             double qalpha_nm, double qbeta_nm) {
  // Not movable once made: the stepper points at the model and the program.
  std::unique_ptr<LiveSwing> s(new LiveSwing(model, std::move(program), solver, options));
  absl::StatusOr<SwingStepper> stepper = SwingStepper::Create(&s->model_, &s->program_, solver);
  if (!stepper.ok()) return stepper.status();
  s->stepper_.emplace(*std::move(stepper));
  s->driven_qalpha_ = qalpha_nm;
  s->driven_qbeta_ = qbeta_nm;
  s->state_ = MakeSample(s->model_, 0.0, s->stepper_->y());
  s->SetTorques();
  return s;
}

int64_t LiveSwing::CommandTick(double t_s) const {
  return static_cast<int64_t>(std::ceil(t_s * options_.tick_hz - kSnapTicks));
}

int64_t LiveSwing::LastCommandTick() const { return CommandTick(options_.duration_s) - 1; }

void LiveSwing::SetTorques() {
  if (options_.driven) {
    qalpha_ = driven_qalpha_;
    qbeta_ = model_.wrist_torque_on() ? driven_qbeta_ : 0.0;
  } else {
    const Torques q = program_.At(program_.SegmentAt(state_.t_s), state_.t_s);
    qalpha_ = q.q_alpha;
    qbeta_ = model_.wrist_torque_on() ? q.q_beta : 0.0;
  }
}

// Commands queued for the tick that ends here (they act from the previous tick's time on).
void LiveSwing::ApplyDueCommands(int64_t n, std::vector<LiveSwingEvent>* out) {
  while (options_.driven && !pending_.empty() && pending_.front().n <= n - 1) {
    const QueuedTorque c = pending_.front();
    pending_.pop_front();
    program_ = TorqueProgram::Constant(c.qalpha_nm, c.qbeta_nm);
    stepper_->ProgramChanged(&program_);
    driven_qalpha_ = c.qalpha_nm;
    driven_qbeta_ = c.qbeta_nm;
    out->push_back(LiveSwingEvent{
        .kind = LiveSwingEvent::Kind::kTorque, .n = n - 1, .t_s = stepper_->t(), .command = c});
  }
}

std::optional<LiveSwingEnd> LiveSwing::Advance(int64_t n, std::vector<LiveSwingEvent>* out) {
  SwingStepper& stepper = *stepper_;
  const double period_s = 1.0 / options_.tick_hz;
  const double tau = static_cast<double>(n) * period_s;
  const double snap = kSnapTicks * period_s;
  ApplyDueCommands(n, out);
  std::optional<LiveSwingEnd> ended;
  bool at_impact = false;
  // An impact is reported at the first tick at or after its time (a step may carry past the
  // tick it was taken for: dp45, or a step that does not divide the tick period).
  const auto report_impact = [&] {
    out->push_back(LiveSwingEvent{
        .kind = LiveSwingEvent::Kind::kImpact, .n = n, .t_s = impact_->t_s, .impact = *impact_});
    impact_reported_ = true;
    if (options_.stop == SwingStop::kImpact) {
      ended = LiveSwingEnd{.reason = SwingEnd::kImpact};
      at_impact = true;
    }
  };
  if (impact_ && !impact_reported_ && impact_->t_s <= tau + snap) report_impact();
  const double limit = options_.driven ? std::min(tau, options_.duration_s) : options_.duration_s;
  while (!ended && stepper.t() < tau - snap && stepper.t() < options_.duration_s) {
    if (absl::Status st = stepper.Step(limit, &record_); !st.ok()) {
      ended = LiveSwingEnd{.reason = SwingEnd::kError, .error = std::string(st.message())};
      break;
    }
    // Checked where SimulateSwing checks it (every kCancelPollSteps steps), so that a swing
    // its dry run accepted never fails here.
    if (solver_.integrator == SwingIntegrator::kDp45 &&
        stepper.steps() % SwingRunOptions::kCancelPollSteps == 0 &&
        stepper.steps() >= SwingRunOptions::kMaxAdaptiveSteps) {
      ended = LiveSwingEnd{
          .reason = SwingEnd::kError,
          .error = absl::StrFormat("the swing took %d steps by t = %.6g s: loosen the tolerance "
                                   "or raise max_step_s",
                                   stepper.steps(), stepper.t())};
      break;
    }
    if (!impact_) {
      if (auto hit = FindImpactInStep(stepper, record_)) {
        impact_ = MakeSample(model_, hit->first, hit->second);
        if (hit->first <= tau + snap) report_impact();
        // Stopping at impact, SimulateSwing takes no step after this one; neither do we.
        if (options_.stop == SwingStop::kImpact) break;
      }
    }
  }
  // The duration's end, at the first tick at or after it.
  if (!ended && stepper.t() >= options_.duration_s && options_.duration_s <= tau + snap) {
    ended = LiveSwingEnd{.reason = SwingEnd::kDuration};
  }
  if (at_impact) {
    state_ = *impact_;
  } else if (ended && ended->reason == SwingEnd::kError) {
    // The state stays the last good one.
  } else if (stepper.t() <= tau + snap) {
    state_ = MakeSample(model_, stepper.t(), stepper.y());
  } else {
    // A step overshot the tick (dp45, or a step that does not divide the tick period): the
    // state at the tick's time, on the step's interpolant.
    state_ = MakeSample(model_, tau, stepper.Interpolate(record_, tau));
  }
  SetTorques();
  if (options_.realistic && !beyond_flagged_ &&
      state_.clubhead_speed_ground_mps > kHumanLimits.max_clubhead_speed_mps) {
    beyond_flagged_ = true;
    out->push_back(LiveSwingEvent{.kind = LiveSwingEvent::Kind::kBeyondHuman,
                                  .n = n,
                                  .t_s = state_.t_s,
                                  .clubhead_speed_mps = state_.clubhead_speed_ground_mps});
  }
  return ended;
}

}  // namespace sportsim::swing
