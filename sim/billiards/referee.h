// What a referee needs to know about one shot, gathered from the engine's events: the first
// ball the struck ball touched, cushion hits before and after that contact, balls pocketed in
// order. The rules of games (fouls, ball in hand, who plays next) are the caller's.
#ifndef SPORTSIM_SIM_BILLIARDS_REFEREE_H_
#define SPORTSIM_SIM_BILLIARDS_REFEREE_H_

#include <vector>

#include "sim/billiards/state.h"

namespace sportsim::billiards {

struct ShotFacts {
  int struck = -1;              ///< ball index of the struck ball
  int first_hit = -1;           ///< first ball the struck ball touched, -1 if none
  int rails = 0;                ///< ball-cushion hits by any ball
  int rails_after_contact = 0;  ///< ... after the struck ball's first ball contact
  std::vector<int> pocketed;    ///< in the order they dropped
  bool struck_pocketed = false;
};

/// Feed it every event of one shot, in time order.
class ShotReferee {
 public:
  explicit ShotReferee(int struck) { facts_.struck = struck; }
  void Observe(const Event& e);
  const ShotFacts& facts() const { return facts_; }

 private:
  ShotFacts facts_;
};

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_REFEREE_H_
