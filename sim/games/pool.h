// The pool referees: 8-ball, 9-ball and 10-ball under the WPA Rules of Play (2016): general
// rules (split hits favour the shooter), 8-ball (section 3), 9-ball (section 2), 10-ball, fouls
// (section 6). docs/games.md lists every point judged here; the referees are reached through
// RefereeFor() (game.h) and share one implementation (pool.cc).
//
// Decisions (snake_case choices):
// - 8-ball illegal break, to the incoming seat: accept_table, re_rack (the incoming seat breaks),
//   rebreak_by_breaker.
// - 8-ball 8 pocketed on a legal break: spot_eight or rebreak, to the breaker; to the incoming
//   seat when the break also fouled (then spot_eight gives ball in hand behind the head string).
// - 9/10-ball after a push-out, and 10-ball after a ball pocketed in a wrong pocket or a ball
//   other than the called one: shoot or pass_back, to the incoming seat.
//
// Not judged (needs a human; out of scope): touching a ball, double hits, push shots.
#ifndef SPORTSIM_SIM_GAMES_POOL_H_
#define SPORTSIM_SIM_GAMES_POOL_H_

#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "sim/billiards/calibrate.h"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"
#include "sim/games/game.h"

namespace sportsim::games {

/// The WPA rack of a pool game on this table, the cue ball on the head spot (in hand behind
/// the head string for the break). 8-ball: triangle, the 8 in the centre of the third row;
/// 9-ball: diamond, the 1 on the foot spot, the 9 in the centre; 10-ball: triangle of four
/// rows, the 1 on the foot spot, the 10 in the centre of the third row.
absl::StatusOr<std::vector<billiards::Ball>> PoolRack(GameKind game,
                                                      const billiards::TableModel& model);

/// The number of a pool ball id: "1".."15" -> 1..15, "cue" -> 0, anything else -1.
int PoolNumber(std::string_view id);
/// 8-ball group of a ball number: 1-7 solids, 9-15 stripes, else none.
Group GroupOf(int number);

/// The pool player's intent, a prior for fitting a recorded shot's strike from its start
/// (billiards::StrikeBounds::intent): the struck ball pockets another ball and stays on the
/// table. It touches a ball, some other ball drops into a pocket (leaving the table is not a
/// pot), and the struck ball neither drops nor leaves the table. Which ball, in which pocket,
/// and whether the game allowed it (the lowest ball first, a called pocket) are not asked: a
/// recording does not say which game, or which call. Never met on a table without pockets.
billiards::ShotIntent PotIntent();

}  // namespace sportsim::games

#endif  // SPORTSIM_SIM_GAMES_POOL_H_
