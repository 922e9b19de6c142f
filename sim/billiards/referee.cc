#include "sim/billiards/referee.h"

namespace sportsim::billiards {

void ShotReferee::Observe(const Event& e) {
  switch (e.kind) {
    case EventKind::kBallBall:
      if (facts_.first_hit < 0) {
        if (e.a == facts_.struck) facts_.first_hit = e.b;
        if (e.b == facts_.struck) facts_.first_hit = e.a;
      }
      break;
    case EventKind::kBallCushion:
      ++facts_.rails;
      if (facts_.first_hit >= 0) ++facts_.rails_after_contact;
      break;
    case EventKind::kBallPocket:
      facts_.pocketed.push_back(e.a);
      if (e.a == facts_.struck) facts_.struck_pocketed = true;
      break;
    case EventKind::kTransition:
      break;
  }
}

}  // namespace sportsim::billiards
