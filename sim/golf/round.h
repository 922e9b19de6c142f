// The referee of a round of golf under the Rules of Golf 2023 (R&A and USGA; docs/golf-rules.md
// has the rules this implements, their numbers and what it leaves out): who plays next, what a
// stroke's result means (holed, at rest, out of bounds, in a penalty area), the relief options
// and their drops, the score. Like the billiards referees it is a set of pure functions of
// (course, settings, state before, input) -> (state after, events): no clock, no unordered
// container, and the only randomness a counter-based draw from the round's seed that the state
// records, so a round replays bit for bit from its commands.
//
// A stroke is played by the course's physics (course_shot.h): StrokeShot turns a player's
// stroke into the CourseShot the ball takes from where it lies (with the round's noise, if
// any), PlayCourseShot flies and rolls it, JudgeStroke rules on the result. PlayStroke does
// the three. A drop (Rule 14.3) is physics too: the ball is let fall from knee height on a
// drawn point of the relief area and rolls out on the course; the referee runs it.
//
// Frame: the course's (x east, y north, z up, metres; headings ccw from +x). Seats are 0..n-1
// in the order the players were given.
#ifndef SPORTSIM_SIM_GOLF_ROUND_H_
#define SPORTSIM_SIM_GOLF_ROUND_H_

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Dense>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "sim/golf/course.h"
#include "sim/golf/course_shot.h"
#include "sim/golf/swing_stroke.h"

namespace sportsim::golf {

/// A club-length for relief areas (Rule 14.3b: the longest club but the putter): 45 inches, a
/// typical driver (the Equipment Rules cap a club at 48 inches).
inline constexpr double kClubLengthM = 1.143;
/// Knee height, from which a ball is dropped (Rule 14.3b(2)) (m).
inline constexpr double kKneeHeightM = 0.5;

/// Order of play (Rule 6.4): the honour on the tee, then the ball farthest from the hole; or
/// "ready golf" (6.4b note: allowed in stroke play), where any player whose ball is not holed
/// may play.
enum class OrderOfPlay : uint8_t { kHonour, kReady };
std::string_view OrderOfPlayName(OrderOfPlay o);  ///< "honour", "ready"

/// What a player may input: "realistic" refuses launches beyond human reach (RoundLimits),
/// "arcade" only the physics' own bounds.
enum class Realism : uint8_t { kRealistic, kArcade };
std::string_view RealismName(Realism r);  ///< "realistic", "arcade"
absl::StatusOr<Realism> RealismFromName(std::string_view name);

/// The realistic profile's bounds on a stroke (docs/golf-rules.md "Strokes" has their sources).
struct RoundLimits {
  /// Ball speed: the clubhead's human limit (70 m/s, sim/swing/realism.h) times the largest
  /// smash factor the conformance limit on the driver's face allows (about 1.52).
  double max_ball_speed_mps = 107.0;
  double min_launch_angle_deg = -20.0;
  double max_launch_angle_deg = 75.0;
  double max_launch_direction_deg = 45.0;  ///< either side of the aim
  double max_spin_rpm = 12000.0;           ///< wedges off a tight lie reach about 11,000
  double max_putt_speed_mps = 12.0;
};
inline constexpr RoundLimits kRoundLimits{};

/// The form of play (Rules 3 and 21): stroke play (3.3, the fewest strokes; with a maximum
/// score per hole, 21.2), match play (3.2, two players, hole by hole) or Stableford (21.1,
/// points against par per hole).
enum class PlayFormat : uint8_t { kStroke, kMatch, kStableford };
std::string_view PlayFormatName(PlayFormat p);  ///< "stroke", "match", "stableford"
absl::StatusOr<PlayFormat> PlayFormatFromName(std::string_view name);

/// Stroke play's maximum score per hole (Rule 21.2b: set by the Committee): none, a number, par
/// plus a number, or net double bogey (par + 2 + the strokes the player receives there, the
/// World Handicap System's cap).
struct MaxScore {
  enum class Kind : uint8_t { kNone, kFixed, kParPlus, kNetDoubleBogey };
  Kind kind = Kind::kNone;
  int n = 0;
};

struct RoundPlayerSpec {
  std::string name;  ///< 1-40 printable characters
  std::string tee;   ///< a tee name of the holes ("" = each hole's first tee)
  /// The World Handicap System's Handicap Index, [-10, 54] (a "plus" handicap is negative);
  /// unset: the player plays off scratch (no strokes received).
  std::optional<double> handicap_index;
};

/// The round's settings, fixed at creation.
struct RoundSettings {
  int first_hole = 1, last_hole = 1;   ///< the holes played, in order (of the course's)
  std::vector<RoundPlayerSpec> players;  ///< 1-8 (match play: 2)
  PlayFormat play = PlayFormat::kStroke;
  MaxScore max_score;  ///< stroke play only
  /// The handicap allowance (%, World Handicap System Appendix C) that turns a course handicap
  /// into a playing handicap; unset: the recommended one for the format (individual stroke
  /// play and Stableford 95 %, singles match play 100 %).
  std::optional<double> allowance_pct;
  OrderOfPlay order = OrderOfPlay::kHonour;
  Realism realism = Realism::kRealistic;
  /// The spread of launches and putts, 0 (none) to 5: at 1 a launch's speed has a standard
  /// deviation of 1.5 %, its vertical angle 1 deg, its direction 1.5 deg, its spin 5 %, its
  /// spin axis 2 deg; a putt's speed 3 % and its direction 0.5 deg.
  double noise = 0.0;
  uint64_t seed = 0;  ///< the draws of noise and drops
  BallSpec ball;
};

/// Net scoring: some player has a Handicap Index.
bool HasHandicaps(const RoundSettings& settings);

/// Validates the settings against the course: holes in range and in order, 1-8 players with
/// names, each player's tee a tee of some hole played, noise in [0, 5]. InvalidArgument names
/// the field.
absl::Status ValidateRoundSettings(const Course& course, const RoundSettings& settings);
/// Sets a `--rule NAME=VALUE` of a round: order=honour|ready; max_score=N|par+N|
/// net_double_bogey|none (stroke play); allowance=PCT (0-100, the handicap allowance).
absl::Status SetRoundVariant(std::string_view name, std::string_view value, RoundSettings* settings);

/// The areas of the course (Rule 2.2).
enum class CourseAreaKind : uint8_t { kGeneral, kTeeing, kPenaltyArea, kBunker, kGreen };
std::string_view CourseAreaName(CourseAreaKind a);  ///< "general", "teeing", ...

struct RoundBall {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< on the ground
  Terrain lie = Terrain::kTee;
  bool holed = false;
  /// On the putting green and lifted (its spot marked) while another player plays (13.1b).
  bool marked = false;
  /// Picked up: out of play for the rest of the hole without being holed (Stableford when no
  /// point is left to score, a maximum score reached, a hole decided in match play).
  bool picked_up = false;
  /// Where the last stroke was made from and the lie there (stroke and distance, 14.6); before
  /// the first stroke of a hole, the tee.
  Eigen::Vector3d last_spot_m = Eigen::Vector3d::Zero();
  Terrain last_lie = Terrain::kTee;
};

struct RoundPlayer {
  std::string name;
  std::string tee;
  int strokes = 0;    ///< on the current hole, penalty strokes included
  int penalties = 0;  ///< the penalty strokes among them
  RoundBall ball;
  /// Per hole of the round (index 0 = first_hole): the gross score, 0 while not yet completed
  /// or with no score (a ball picked up in Stableford or match play: `no_score`); in stroke
  /// play with a maximum score, at most the maximum.
  std::vector<int> scores;
  std::vector<bool> no_score;  ///< per hole: completed without a score
  /// The playing handicap (World Handicap System: the course handicap times the allowance,
  /// rounded; in match play the difference from the lower player's), and the strokes it
  /// gives on each hole of the round by stroke index (negative: a plus handicap gives back).
  int playing_handicap = 0;
  std::vector<int> received;
  std::vector<int> points;  ///< Stableford: per hole (Rule 21.1b), 0 until completed
  int Total() const;        ///< the completed holes' gross sum
  int NetTotal() const;     ///< Total less the strokes received on the holes with a score
  int Points() const;       ///< the Stableford points' sum
};

/// World Handicap System (Rules of Handicapping 6.1): the course handicap of a Handicap Index
/// from the tee set's rating, index x slope / 113 + (course rating - par), scaled from 18 holes
/// to the course's holes (a 9-hole course takes half the index, as Rule 6.1b does); unrounded.
double CourseHandicap(const Course& course, std::string_view tee, double handicap_index);
/// The strokes a playing handicap gives on a hole of stroke index `stroke_index` of `holes`
/// (Rule of Handicapping 6.2 / Appendix E): one on each hole in stroke index order, round and
/// round again; a plus handicap gives strokes back from the highest index down.
int StrokesReceived(int playing_handicap, int stroke_index, int holes);
/// Stableford points (Rule 21.1b): 2 at the fixed score (par, less the strokes received), one
/// more for each stroke under, one less for each over, never below 0.
int StablefordPoints(int gross, int par, int received);
/// The maximum score of a hole for a player (0: none).
int MaxScoreOf(const MaxScore& max, int par, int received);

/// A relief decision the seat must make before anyone plays on.
struct RoundDecision {
  int seat = 0;
  std::string reason;  ///< "penalty_area" (Rule 17.1d) or "unplayable" (19)
  Terrain area = Terrain::kRough;  ///< the penalty area's class, or the ball's lie
  /// The reference for the options: where the ball last crossed the penalty area's edge, or
  /// the unplayable ball's spot.
  Eigen::Vector3d reference_m = Eigen::Vector3d::Zero();
  /// "stroke_and_distance", "back_on_the_line", "lateral" and, for a ball in a bunker,
  /// "back_on_the_line_outside_bunker" (two strokes), in this order; only those with a relief
  /// area to drop in.
  std::vector<std::string> choices;
};

struct RoundState {
  int hole = 1;  ///< the hole being played (the course's number)
  std::vector<RoundPlayer> players;
  /// The order on this hole's tee (Rule 6.4a/b: seat order on the first, then the lowest score
  /// on the hole before, ties keeping the order before).
  std::vector<int> tee_order;
  std::optional<RoundDecision> decision;
  bool over = false;
  /// When over: "finished" (stroke play and Stableford: all holes played out); in match play
  /// "3 and 2", "1 up", "halved" or "conceded"; "" before.
  std::string result;
  /// When over: the seats with the lowest total (net with handicaps), the most Stableford
  /// points, or the match's winner, ascending (several: a tie or a halved match).
  std::vector<int> winners;
  /// Match play, per hole of the round: the seat that won it, -1 halved, -2 not yet completed.
  std::vector<int> hole_winners;
  uint64_t draws = 0;   ///< seeded draws made so far
  int64_t strokes = 0;  ///< strokes the round has played (all players)
};

enum class RoundEventKind : uint8_t {
  kStroke,     ///< a stroke was made (from: position_m)
  kHoled,      ///< the ball is in the hole (13.2c)
  kRest,       ///< the ball came to rest (position_m, lie)
  kPenalty,    ///< penalty strokes (penalty_strokes; reason; rule)
  kDecision,   ///< a relief decision is pending (choices)
  kChoice,     ///< the decision was made (choice)
  kDrop,       ///< a drop (position_m: where it first touched; rest_m; in_area; attempt)
  kPlaced,     ///< the ball was placed (position_m): after two failed drops, or on its spot
  kMarked,     ///< the ball on the green was marked and lifted
  kReplaced,   ///< and replaced for its owner's turn
  kConceded,   ///< match play: a concession (choice: concede_stroke, concede_hole, concede_match)
  kPickedUp,   ///< the ball was picked up (reason: stableford, max_score, decided, pick_up)
  kHoleEnd,    ///< the hole is complete (scores in the state)
  kRoundEnd,   ///< the round is over (result, winners in the state)
};
/// "stroke", "holed", "rest", "penalty", "decision", "choice", "drop", "placed", "marked",
/// "replaced", "conceded", "picked_up", "hole_end", "round_end".
std::string_view RoundEventName(RoundEventKind kind);

struct RoundEvent {
  RoundEventKind kind = RoundEventKind::kStroke;
  int seat = -1;
  int hole = 0;
  int strokes = 0;  ///< the seat's strokes on the hole after the event
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d rest_m = Eigen::Vector3d::Zero();  ///< kDrop
  std::string lie;          ///< the lie's tag (kRest, kDrop, kPlaced)
  int penalty_strokes = 0;  ///< kPenalty
  std::string reason;       ///< kPenalty, kDecision: out_of_bounds, penalty_area, unplayable, ...
  std::string rule;         ///< the Rule's number, e.g. "18.2b"
  std::vector<std::string> choices;  ///< kDecision
  std::string choice;       ///< kChoice
  int attempt = 0;          ///< kDrop: 1 or 2
  bool in_area = false;     ///< kDrop: it came to rest in the relief area
};

struct RoundStep {
  RoundState state;
  std::vector<RoundEvent> events;
};

/// A player's stroke: a launch (ball speed, angles, spin), a putt, or a swing (a golfer's torque
/// program and a club: swing_stroke.h), toward `aim_deg` (the pin when unset). The ball is
/// played where it lies: a stroke has no position.
struct RoundStroke {
  enum class Kind : uint8_t { kLaunch, kPutt, kSwing };
  Kind kind = Kind::kLaunch;
  LaunchConditions launch;  ///< kLaunch (its direction and spin axis relative to the aim)
  double speed_mps = 0.0;   ///< kPutt
  std::optional<SwingStroke> swing;  ///< kSwing
  std::optional<double> aim_deg;
  bool flagstick_in = true;  ///< Rule 13.2: the player's choice, in or out
};

/// A relief choice: one of the decision's choices; `back_m` is how far behind the reference
/// point on the line from the hole the back-on-the-line reference point is (m; unset: the
/// nearest point behind that the relief area mostly allows).
struct RoundChoice {
  std::string choice;
  std::optional<double> back_m;
};

/// The round at its first tee: every ball on its player's tee, the honour in seat order.
absl::StatusOr<RoundState> StartRound(const Course& course, const RoundSettings& settings);

/// The seat to play next under the honour order (-1 when the round is over): the seat with a
/// pending decision; else, among balls not holed, those not yet struck from the tee in the
/// tee order; then the ball farthest from the hole (ties: the lower seat).
int ToPlay(const Course& course, const RoundSettings& settings, const RoundState& state);
/// The seats that may play now: ToPlay's, or under ready golf every seat not holed (none while
/// a decision is pending).
std::vector<int> MayPlay(const Course& course, const RoundSettings& settings,
                         const RoundState& state);

/// FailedPrecondition naming the Rule when `seat` may not play now (the round is over, a
/// decision is pending, another seat's turn, the ball is holed); InvalidArgument naming the
/// field for a stroke outside the realistic profile (RoundLimits) or the physics' ranges.
absl::Status CheckStroke(const Course& course, const RoundSettings& settings,
                         const RoundState& state, int seat, const RoundStroke& stroke);
/// The shot the stroke gives: from the seat's ball, at its hole, the round's noise drawn from
/// the seed (the round's stroke count picks the draws). A swing is run to impact first (under
/// the realistic profile, a clubhead beyond a human's 70 m/s is refused naming "torques").
absl::StatusOr<CourseShot> StrokeShot(const Course& course, const RoundSettings& settings,
                                      const RoundState& state, int seat,
                                      const RoundStroke& stroke,
                                      const std::function<bool()>& cancelled = {});
/// Rules on the stroke's result: the stroke counts; holed, at rest, out of bounds (stroke and
/// distance, 18.2b: the ball back where the stroke was made, per 14.6), or in a penalty area
/// (a decision with its choices, 17.1d); the marks on the green; the hole's and the round's
/// end. `cancelled` is polled by the drops' physics.
absl::StatusOr<RoundStep> JudgeStroke(const Course& course, const RoundSettings& settings,
                                      const RoundState& state, int seat,
                                      const CourseShotResult& shot,
                                      const std::function<bool()>& cancelled = {});

/// The stroke played and judged: CheckStroke, StrokeShot, PlayCourseShot, JudgeStroke. The
/// shot's result (for its path and events) is written to `shot` when given.
absl::StatusOr<RoundStep> PlayStroke(const Course& course, const RoundSettings& settings,
                                     const RoundState& state, int seat, const RoundStroke& stroke,
                                     CourseShotResult* shot = nullptr,
                                     const std::function<bool()>& cancelled = {});

/// A seat's relief decision: one of the pending decision's choices (the penalty counted, the
/// ball dropped or placed where the Rule says), or "unplayable" when it is the seat's turn and
/// no decision is pending (Rule 19.1: anywhere but in a penalty area; it opens a decision).
/// Also, not relief: "pick_up" while the seat's ball is in play (Stableford, 21.1c: no score;
/// stroke play with a maximum score, 21.2c: the maximum); and in match play, at any time the ball is not
/// moving, "concede_stroke" (the opponent's next stroke: their ball is holed with it),
/// "concede_hole" or "concede_match" (Rule 3.2b: final once made).
/// FailedPrecondition names the Rule when the seat may not decide now; InvalidArgument names
/// the choice when it is not one of the offered.
absl::StatusOr<RoundStep> Decide(const Course& course, const RoundSettings& settings,
                                 const RoundState& state, int seat, const RoundChoice& choice,
                                 const std::function<bool()>& cancelled = {});

/// The shot clock ran out on the seat to play (the seat with a pending decision, else ToPlay's):
/// one penalty stroke under the round's pace-of-play policy (Rule 5.6b(3) lets the Committee
/// set one; "shot_clock", rule "5.6b"). FailedPrecondition when the round is over.
absl::StatusOr<RoundStep> ShotClockExpired(const Course& course, const RoundSettings& settings,
                                           const RoundState& state);

/// Match play's state: the seat ahead (-1: all square), by how many holes, with how many to
/// play, and "dormie" (as many up as are left).
struct MatchStatus {
  int leader = -1;
  int up = 0;
  int to_play = 0;
  bool dormie = false;
};
MatchStatus MatchStatusOf(const RoundSettings& settings, const RoundState& state);
/// "all square with 3 to play", "Ann 2 up with 1 to play (dormie)", "Ann won 3 and 2".
std::string MatchStatusText(const RoundSettings& settings, const RoundState& state);

/// A plain reference player (benches, load tools, tests), aimed at the pin: on the green or
/// within 20 m a putt at the speed that rolls about to the hole on a stimp-10 green; under 60 m
/// a 40-degree pitch; beyond, a 20-degree full shot sized by the distance (at most 70 m/s). A
/// tenth shorter for each stroke over par, so that an over-hit raised green is not tried for
/// ever.
RoundStroke ReferenceStroke(double distance_m, bool on_green, int strokes_over_par);

/// The area of the course (Rule 2.2) of a lie at a spot, for the hole being played: tees and
/// greens of other holes are general area.
CourseAreaKind AreaOfCourse(const Course& course, int hole, const Eigen::Vector2d& spot,
                            double ball_radius_m);

}  // namespace sportsim::golf

#endif  // SPORTSIM_SIM_GOLF_ROUND_H_
