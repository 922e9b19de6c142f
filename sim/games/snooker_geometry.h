// Snooker table markings and the two pieces of plain geometry the WPBSA rules ask a referee
// for: respotting colours (the occupied-spot order) and whether the cue ball is "snookered".
//
// Sources:
// - WPBSA, Official Rules of the Game of Snooker, section 1 (the table): on the full-size table
//   (playing area 3569 x 1778 mm, 11 ft 8.5 in x 5 ft 10 in) the baulk line is drawn 737 mm
//   (29 in) from the face of the baulk cushion; the D is a semicircle behind it, centred on its
//   middle, of radius 292 mm (11.5 in); the spots: brown at the middle of the baulk line,
//   yellow at its right-hand end (seen from baulk) and green at its left, blue at the centre of
//   the table, pink midway between the centre and the face of the top cushion, black 324 mm
//   (12.75 in) from the face of the top cushion.
// - WPBSA section 2 (definitions), "snookered": a straight stroke to every ball on is wholly or
//   partly obstructed by a ball or balls not on; if one or more balls on can be struck at both
//   extreme edges free of obstruction by any ball not on, the cue ball is not snookered; in hand,
//   it is snookered only if obstructed from every position on or within the lines of the D.
// - WPBSA section 3 rule 4 (spotting colours): own spot; if occupied, the highest-valued free
//   spot; the higher value first when several wait; if no spot is free, as near its own spot as
//   possible between the spot and the nearest part of the top cushion; if that is occupied too
//   (pink and black), as near as possible on the centre line below its spot. A spot is occupied
//   when a ball cannot be placed there without touching another ball.
//
// Other table sizes scale the WPBSA figures: the baulk distance, the black's distance and the D
// radius are taken as fractions of the playing area (737/3569 and 324/3569 of the length,
// 292/1778 of the width), so the full-size table gets exactly the published figures.
//
// Frame (model.h): the baulk cushion at x = -length/2, the top cushion at x = +length/2;
// looking up the table (+x) from baulk, yellow is on the right (y < 0), green on the left.
#ifndef SPORTSIM_SIM_GAMES_SNOOKER_GEOMETRY_H_
#define SPORTSIM_SIM_GAMES_SNOOKER_GEOMETRY_H_

#include <array>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "Eigen/Core"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"

namespace sportsim::games {

/// The six colours in value order (yellow 2 .. black 7).
inline constexpr std::array<std::string_view, 6> kSnookerColours = {"yellow", "green", "brown",
                                                                   "blue",   "pink",  "black"};

/// True for "red1", "red2", ... (any id starting with "red" followed by a digit).
bool IsSnookerRed(std::string_view id);
/// Value of a snooker ball: reds 1, yellow 2 .. black 7; 0 for the cue ball and anything else.
int SnookerValue(std::string_view id);

/// WPBSA full-size figures (m) that the markings scale from.
inline constexpr double kWpbsaLengthM = 3.569;       ///< playing area length
inline constexpr double kWpbsaWidthM = 1.778;        ///< playing area width
inline constexpr double kWpbsaBaulkLineM = 0.737;    ///< baulk line from the baulk cushion face
inline constexpr double kWpbsaDRadiusM = 0.292;      ///< radius of the D
inline constexpr double kWpbsaBlackFromTopM = 0.324; ///< black spot from the top cushion face

/// Markings of a snooker table, computed from its playing area (see the header comment).
struct SnookerGeometry {
  double radius_m = 0.0;           ///< ball radius R (m)
  double half_length_m = 0.0;      ///< length / 2 (m): the top cushion face at +this
  double half_width_m = 0.0;       ///< width / 2 (m)
  double x_limit_m = 0.0;          ///< largest |x| of a ball centre on the cloth (m)
  double y_limit_m = 0.0;          ///< largest |y| of a ball centre on the cloth (m)
  double baulk_x_m = 0.0;          ///< x of the baulk line (m)
  double d_radius_m = 0.0;         ///< radius of the D (m), centred at (baulk_x_m, 0)
  /// Spots in kSnookerColours order (m).
  std::array<Eigen::Vector2d, 6> spots;

  /// The spot of a colour ("yellow" .. "black"); index into `spots`, -1 for a non-colour.
  static int ColourIndex(std::string_view id);
  /// A ball centre on or within the lines of the D (tolerance 1e-9 m).
  bool InD(const Eigen::Vector2d& p) const;
};

/// Markings of the model's table; InvalidArgument for a table without cushions or too small to
/// hold them.
absl::StatusOr<SnookerGeometry> MakeSnookerGeometry(const billiards::TableModel& model);

/// Balls closer than 2R + this are touching (m); respotted balls keep at least this gap.
inline constexpr double kTouchGapM = 1e-6;

/// Respots the colours named in `colours` (balls of `state`, pocketed or off the table) by the
/// WPBSA order above: first every colour whose own spot is free, then the others by decreasing
/// value on the highest-valued free spot, else on the line from its spot towards the top cushion
/// (nearest its spot), else on the line from its spot towards the baulk cushion; never touching
/// another ball. Respotted balls are at rest. Appends the ids in the order placed to `placed`.
absl::Status RespotColours(const SnookerGeometry& geo, std::span<const std::string> colours,
                           billiards::TableState* state, std::vector<std::string>* placed);

/// How the D is sampled when the cue ball is in hand (IsSnookeredFromD).
struct DSampling {
  double spacing_m = 0.0;  ///< grid and boundary spacing (m); 0: R / 8 (3.3 mm on full size)
};

/// Whether the cue ball at `cue` can strike the ball on at `on` at both extreme edges (the cue
/// ball's whole swept width: its centre moving along each of the two lines tangent to the
/// circle of radius 2R about `on`, up to the tangent point) without its swept capsule (radius
/// R) touching any ball at `obstacles`. A cue ball already touching `on` counts as clear.
bool BothEdgesClear(double radius, const Eigen::Vector2d& cue, const Eigen::Vector2d& on,
                    std::span<const Eigen::Vector2d> obstacles);

/// Whether some straight stroke reaches any part of `on` unobstructed (the miss rule's "clear
/// line to any part"): the fan of directions between the two extreme edges, sampled at
/// `rays` directions (edges and centre included).
bool AnyPartClear(double radius, const Eigen::Vector2d& cue, const Eigen::Vector2d& on,
                  std::span<const Eigen::Vector2d> obstacles, int rays = 33);

/// Whether the full-ball line (the cue ball's centre straight at the centre of `on`) is free.
bool FullBallClear(double radius, const Eigen::Vector2d& cue, const Eigen::Vector2d& on,
                   std::span<const Eigen::Vector2d> obstacles);

/// Snookered (WPBSA section 2) with the cue ball at `cue`: no ball in `on` can be struck at both
/// extreme edges free of the balls in `not_on`. False when `on` is empty.
bool IsSnookered(double radius, const Eigen::Vector2d& cue, std::span<const Eigen::Vector2d> on,
                 std::span<const Eigen::Vector2d> not_on);

/// Snookered with the cue ball in hand: obstructed from every position of the D where the cue
/// ball can be placed (on the cloth, touching no ball of `on` or `not_on`). The positions: a
/// square grid of spacing h over the D's bounding box, plus points every h along the baulk
/// line's chord and the arc (so the edges of the D are sampled too). A clear region of the D
/// narrower than h can be missed (then "snookered" is reported where a player with perfect
/// placement was not); h = R / 8 by default. False when no position is free.
bool IsSnookeredFromD(const SnookerGeometry& geo, std::span<const Eigen::Vector2d> on,
                      std::span<const Eigen::Vector2d> not_on, const DSampling& sampling = {});

/// The positions IsSnookeredFromD tries, in a fixed order (for tests and for clients).
std::vector<Eigen::Vector2d> DSamplePositions(const SnookerGeometry& geo,
                                              const DSampling& sampling = {});

}  // namespace sportsim::games

#endif  // SPORTSIM_SIM_GAMES_SNOOKER_GEOMETRY_H_
