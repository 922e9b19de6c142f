// The three-cushion referee: UMB World Rules of Carom Billiards, three-cushion, as docs/games.md
// "Three-cushion" lists them. Reached through ThreeCushionReferee() /
// RefereeFor(GameKind::kThreeCushion) (game.h).
//
// Seats: seat 0 plays the white ball (id "cue"), seat 1 the yellow ("yellow"); the red ("red")
// is the third ball. A point (UMB): the striker's ball touches both object balls, and touches
// cushions at least three times before its first contact with the second object ball (any
// cushions, repeats count, contacts before the first object ball count). A point keeps the
// striker at the table; anything else ends the inning.
//
// Opening (UMB): red on the foot spot, the opponent's ball on the head spot, the striker's on
// the head string 18.25 cm to the side (the rack "three-cushion", with white and yellow swapped
// when seat 1 breaks); the red must be hit first (`on` = red), else a foul.
//
// Fouls (end the inning, no point): striking the wrong cue ball, a ball leaving the table (it is
// put back on its spot: red on the foot spot, white on the head spot, yellow on the centre
// spot; a taken spot gives the nearest free place on the long centre line, our choice), the
// opening played without hitting the red first. Double hits and playing before the balls stop
// need a human or cannot happen on the server.
//
// The frame: a race to the variant `target` (default 15). With `equal_innings` on, when the
// seat that broke reaches the target its opponent plays one more inning to level the innings;
// reaching the target too makes the match a draw (UMB: a tie stands as a draw; the
// shoot-out is out of scope). `innings` counts each seat's innings (an inning is counted when
// it starts). A shot clock's expiry ends the inning (reason `shot_clock`, no foul).
//
// Touching balls (UMB): when the ball of the seat to play rests within 2R + 10 um of another
// ball, that seat gets a decision: `play` (play away from it) or `reset` (the balls set up as
// for the opening, with this seat striking and the red to be hit first).
#ifndef SPORTSIM_SIM_GAMES_THREE_CUSHION_H_
#define SPORTSIM_SIM_GAMES_THREE_CUSHION_H_

#include <string_view>

#include "sim/billiards/calibrate.h"
#include "sim/games/game.h"

namespace sportsim::games {

/// The ball a seat strikes: "cue" (seat 0, white) or "yellow" (seat 1).
std::string_view ThreeCushionBall(int seat);

/// The UMB point: ball `own` touched `obj_a` and `obj_b`, with at least three cushion hits of
/// its own before its first contact with the second of them.
bool ThreeCushionPoint(const ShotFacts& facts, int own, int obj_a, int obj_b);

/// The three-cushion player's intent, a prior for fitting a recorded shot's strike from its
/// start (billiards::StrikeBounds::intent): on a table of three balls, the struck ball scores
/// the UMB point on the other two. Never met on another table.
billiards::ShotIntent ThreeCushionIntent();

}  // namespace sportsim::games

#endif  // SPORTSIM_SIM_GAMES_THREE_CUSHION_H_
