#include "sim/billiards/state.h"

namespace sportsim::billiards {

std::string_view MotionStateName(MotionState s) {
  switch (s) {
    case MotionState::kStationary: return "stationary";
    case MotionState::kSpinning: return "spinning";
    case MotionState::kSliding: return "sliding";
    case MotionState::kRolling: return "rolling";
    case MotionState::kAirborne: return "airborne";
    case MotionState::kPocketed: return "pocketed";
  }
  return "unknown";
}

std::string_view EventKindName(EventKind k) {
  switch (k) {
    case EventKind::kBallBall: return "ball_ball";
    case EventKind::kBallCushion: return "ball_cushion";
    case EventKind::kBallPocket: return "ball_pocket";
    case EventKind::kTransition: return "transition";
  }
  return "unknown";
}

int TableState::Find(std::string_view id) const {
  for (size_t i = 0; i < balls.size(); ++i) {
    if (balls[i].id == id) return static_cast<int>(i);
  }
  return -1;
}

bool TableState::AtRest() const {
  for (const Ball& b : balls) {
    if (b.state != MotionState::kStationary && b.state != MotionState::kPocketed) return false;
  }
  return true;
}

void RecordTransition(double t_s, int i, MotionState from, const Ball& b,
                      std::vector<Event>* events) {
  if (b.state == from) return;
  events->push_back({.t_s = t_s, .kind = EventKind::kTransition, .a = i, .from = from,
                     .to = b.state, .va = b.v.head<2>(), .ra = b.r.head<2>()});
}

}  // namespace sportsim::billiards
