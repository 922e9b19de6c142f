// Plain words for ruled games (the referee's state, verdicts, calls and game events), shared by
// the `table` commands and `info`.
#ifndef SPORTSIM_CLIENT_GAME_TEXT_H_
#define SPORTSIM_CLIENT_GAME_TEXT_H_

#include <string>
#include <string_view>
#include <vector>

#include "sportsim/v1/billiards.pb.h"
#include "sportsim/v1/common.pb.h"

namespace sportsim::cli {

/// "foul by seat 0 (wrong_ball_first), turn passes" or "legal shot by seat 1, 1 point, seat 1
/// plays on".
std::string VerdictText(const v1::Verdict& v, uint32_t seat);

/// A ruling that is not a shot's (a concession, the shot clock): "conceded, frame over",
/// "foul (shot_clock), turn passes". A reason equal to `said` (the action's own word) is left
/// out.
std::string RulingText(const v1::Verdict& v, std::string_view said = "");

/// "called 9 in top_left", "safety", "push-out", "nominated blue" (joined with ", "); "" when
/// nothing was declared.
std::string CallText(const v1::ShotCall& c);

/// The strike as asked: "cue struck, ball speed 2 m/s, phi 10 deg, theta 0 deg, a 0, b 0".
std::string StrikeText(const v1::CueStrike& s);

/// The game in plain words, two or three lines: the match and frame score; whose turn it is
/// with the ball in hand, the ball on, a pending decision or the result, and the last shot's
/// verdict (when `last` carries one); fouls in a row when a seat has any.
std::vector<std::string> GameLines(const v1::GameState& g, const v1::ShotSummary* last);

/// A game event (foul, score, respot, decision, warning, frame_end, match_end) in words; ""
/// for any other kind.
std::string GameEventNote(const v1::TableEvent& e);

/// `info`'s text block for Capabilities.games.
void PrintGames(const v1::Capabilities& c);

}  // namespace sportsim::cli

#endif  // SPORTSIM_CLIENT_GAME_TEXT_H_
