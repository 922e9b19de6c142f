#include "server/billiards/preview.h"

#include <algorithm>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "server/billiards/convert.h"
#include "server/world/world.h"

namespace sportsim::server {

namespace b = ::sportsim::billiards;

namespace {

// Sampling of the paths (s of simulated time), and the longest preview (s).
constexpr double kPreviewStepS = 0.005;
constexpr double kMaxPreviewS = 30.0;

void AddPoint(const b::TableState& s, int ball, double t, v1::BallPath* path) {
  v1::PathPoint* p = path->add_points();
  p->set_t_s(t);
  p->set_x_m(s.balls[ball].r.x());
  p->set_y_m(s.balls[ball].r.y());
}

bool Settled(const b::Ball& ball) { return !b::IsMoving(ball.state); }

}  // namespace

absl::Status RunPreview(const PreviewJob& job, const std::function<bool()>& stop,
                        v1::PreviewShotResponse* out) {
  const b::TableModel& model = *job.model;
  b::TableState state = job.balls;
  state.t_s = 0.0;
  absl::StatusOr<b::StrikeOutcome> applied =
      b::ApplyStrike(model, job.solver.effects, job.strike, job.cue, &state);
  if (!applied.ok()) return PrefixStatus("strike.", applied.status());
  const b::TableState start = state;
  std::vector<b::Event> events;
  absl::StatusOr<std::unique_ptr<b::TableSimulation>> created =
      b::TableSimulation::Create(model, job.solver, std::move(state), &events);
  if (!created.ok()) return created.status();
  b::TableSimulation& sim = **created;
  v1::BallPath* struck = out->add_paths();
  struck->set_ball(start.balls[job.cue].id);
  AddPoint(start, job.cue, 0.0, struck);
  v1::BallPath* met = nullptr;
  int target = -1;
  int struck_events = 0, target_events = 0;
  bool struck_done = false, target_done = false;
  double t = 0.0;
  b::TableState before = start;  // the balls at the start of the current 5 ms step
  while (!(struck_done && (target < 0 ? struck_done : target_done)) && !sim.AtRest() &&
         t < kMaxPreviewS) {
    if (stop && stop()) return absl::CancelledError("the preview was stopped");
    t += kPreviewStepS;
    events.clear();
    if (absl::Status s = sim.AdvanceTo(t, &events); !s.ok()) return s;
    const b::TableState& now = sim.state();
    for (const b::Event& e : events) {
      if (e.kind == b::EventKind::kTransition) continue;
      const bool on_struck = e.a == job.cue || e.b == job.cue;
      if (on_struck && target < 0 && e.kind == b::EventKind::kBallBall) {
        target = e.a == job.cue ? e.b : e.a;
        met = out->add_paths();
        met->set_ball(now.balls[target].id);
        // Its path starts where it was met (it stood still until then, or moved less than a
        // step's worth).
        AddPoint(before, target, e.t_s, met);
      }
      const bool on_target = target >= 0 && (e.a == target || e.b == target);
      // An event of a followed ball counts for each followed ball in it; it is reported only
      // while every one of them has events left, so no ball shows more than max_events.
      const bool struck_room = !on_struck || (!struck_done && struck_events < job.max_events);
      const bool target_room = !on_target || (!target_done && target_events < job.max_events);
      if (!(on_struck || on_target) || !struck_room || !target_room) continue;
      if (on_struck) ++struck_events;
      if (on_target) ++target_events;
      EventToProto(model, now, e, out->add_events());
    }
    if (!struck_done) AddPoint(now, job.cue, t, struck);
    if (met != nullptr && !target_done) AddPoint(now, target, t, met);
    struck_done = struck_events >= job.max_events || Settled(now.balls[job.cue]);
    if (target >= 0) {
      target_done = target_events >= job.max_events || Settled(now.balls[target]);
    }
    before = now;
  }
  return absl::OkStatus();
}

}  // namespace sportsim::server
