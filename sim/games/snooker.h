// The snooker referee: WPBSA Official Rules of the Game of Snooker, section 3 (rules 1-16) and
// the definitions of section 2, as docs/games.md lists them. The table markings, the
// respotting order and the geometric "snookered" test are in snooker_geometry.h. Reached through
// SnookerReferee() / RefereeFor(GameKind::kSnooker) (game.h).
//
// GameState fields used (game.h):
// - phase: "reds" (a red is on; `on` lists the reds), "colour" (after a red or a free ball
//   taken as a red: any colour may be nominated, `on` lists the colours, and the shot must carry
//   ShotCall::nominate), "colours" (the colours in order; `on` holds the lowest), or
//   "respotted_black" (the frame's tie-break: `on` = black, the next score or foul ends it).
// - free_ball: the incoming player, snookered after the opponent's foul, may nominate any ball
//   not on (ShotCall::nominate) as the ball on for this stroke.
// - decision: after a foul the offended seat chooses `play` (from where the cue ball lies, or
//   from the D after an in-off; with a free ball if snookered) or `play_again` (the offender
//   plays again; a free ball lapses); with the miss rule on, after a miss also `replace` (the
//   balls go back to where they were before the stroke and the offender plays again).
// - scores: points in the frame; replay_position / replay_phase / misses_in_row: the miss rule.
// - seed: the seeded draw for the re-spotted black (recorded as a respot event whose reason is
//   `respotted_black_draw` and whose seat is the seat drawn to play).
//
// Verdict: on a foul, `points` is the penalty awarded to the opponent (at least 4) and `reason`
// the foul carrying it (the highest penalty of the stroke; on equal values the first found in
// the order no_contact, wrong_ball_first, played_red_after_red, push_stroke, scratch,
// ball_off_table, wrong_ball_potted, free_ball_snooker); with the miss rule `miss` replaces
// no_contact / wrong_ball_first when the miss applies. Otherwise `points` is what the striker
// scored.
//
// Judged from the engine's events: first contact (two balls at the same instant within
// kSimultaneousS: legal only for two or more reds, or the free ball with the ball on), pots,
// balls off the table, in-offs, the touching ball (the cue ball within 2R + kTouchBallGapM of a
// ball before the stroke: touching it again within kPushStrokeS of the strike is a push stroke;
// a touching ball on needs not be hit), the free-ball snooker (the opponent left snookered with
// the free ball as the only obstruction, except with only pink and black left).
//
// Not modelled: the miss rule's "best ability" judgement (only its objective part, variant
// `miss_rule`, default off), jump shots, double hits and push strokes other than the touching
// ball, the 7-point fouls a server cannot see (a ball off the table used, a measuring device).
// Gaps: after `replace` the cue ball is played from where it lay, even if it had been placed in
// the D; a failure to nominate is refused (CheckShot), not penalised.
#ifndef SPORTSIM_SIM_GAMES_SNOOKER_H_
#define SPORTSIM_SIM_GAMES_SNOOKER_H_

#include <string>
#include <vector>

#include "sim/billiards/model.h"
#include "sim/billiards/state.h"
#include "sim/games/game.h"
#include "sim/games/snooker_geometry.h"

namespace sportsim::games {

/// Cue ball and another ball this close beyond 2R before a stroke are touching (m).
inline constexpr double kTouchBallGapM = 1e-5;
/// Touching the touching ball within this time of the strike is a push stroke (s).
inline constexpr double kPushStrokeS = 1e-3;

/// Points still on the table for the player at the table (WPBSA's "points remaining"): 8 per
/// red (a red and a black), plus 7 for the colour due after a red (phase "colour"), plus the
/// colours on the table (in phase "colours", only those from the ball on up).
int SnookerPointsRemaining(const GameState& state, const billiards::TableState& balls);

/// The seat drawn to play the re-spotted black: a SplitMix64 of (seed, frame), low bit.
int SnookerRespottedBlackDraw(uint64_t seed, int frame);

}  // namespace sportsim::games

#endif  // SPORTSIM_SIM_GAMES_SNOOKER_H_
