// Referees of the games played on a billiards table: the common types every game shares, and
// the dispatch by game. A referee is a pure function of (rules, game state before, the shot's
// call, the engine's events, the balls at rest) -> (verdict, game state after, game events); it
// reads no clock and iterates no unordered container, so a replay gives the same result.
//
// Games: 8-ball, 9-ball, 10-ball (pool.{h,cc}), snooker (snooker.{h,cc}), three-cushion
// (three_cushion.{h,cc}). The rules and their sources (WPA, WPBSA, UMB) are in
// docs/games.md; the JSON contract (names, reasons, keys) in docs/cli.md.
//
// Seats are 0 and 1. Balls are named by their ids ("cue", "1".."15", "red1", "black", ...) in
// every type a client sees, and by index into TableState::balls inside a shot's facts.
#ifndef SPORTSIM_SIM_GAMES_GAME_H_
#define SPORTSIM_SIM_GAMES_GAME_H_

#include <array>
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "Eigen/Core"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"

namespace sportsim::games {

using billiards::TableModel;
using billiards::TableState;

// ---------------------------------------------------------------------------------------------
// Names

enum class GameKind : uint8_t { kFree, kEightBall, kNineBall, kTenBall, kSnooker, kThreeCushion };
/// "free", "8ball", "9ball", "10ball", "snooker", "three-cushion" (in enum order).
std::span<const std::string_view> GameNames();
std::string_view GameName(GameKind g);
/// InvalidArgument naming the allowed names for an unknown name.
absl::StatusOr<GameKind> GameFromName(std::string_view name);

/// Where the cue ball may be placed before the next shot.
enum class BallInHand : uint8_t {
  kNone,      ///< the cue ball is played from where it lies
  kAnywhere,  ///< anywhere on the cloth (pool fouls, WPA 6)
  kKitchen,   ///< behind the head string (the break; the 8-ball break-scratch variant)
  kD,         ///< inside snooker's D (WPBSA)
};
/// "none", "anywhere", "kitchen", "d".
std::string_view BallInHandName(BallInHand b);
absl::StatusOr<BallInHand> BallInHandFromName(std::string_view name);

/// Who breaks the next frame of a match.
enum class BreakRotation : uint8_t { kAlternate, kWinner };
std::string_view BreakRotationName(BreakRotation r);  ///< "alternate", "winner"

/// How a match starts: the game's own rack with seat 0 to break, or the balls given (a position
/// after a legal break: drills, puzzles, tests).
enum class Start : uint8_t { kBreak, kInPlay };
std::string_view StartName(Start s);  ///< "break", "in-play"
absl::StatusOr<Start> StartFromName(std::string_view name);

/// 8-ball groups.
enum class Group : uint8_t { kNone, kSolids, kStripes };
std::string_view GroupName(Group g);  ///< "", "solids", "stripes"

/// How a match ended (GameState.result in the API).
enum class MatchResult : uint8_t { kNone, kWon, kConceded, kThreeFouls, kDraw, kAbandoned };
std::string_view MatchResultName(MatchResult r);  ///< "", "won", "conceded", "three_fouls", ...

// ---------------------------------------------------------------------------------------------
// Rules: the table's settings, fixed at creation.

/// One game variant settable with `--rule NAME=VALUE`.
struct VariantInfo {
  std::string_view name;                ///< e.g. "break_scratch_in_hand"
  std::vector<std::string_view> games;  ///< game names it applies to
  std::vector<std::string_view> values; ///< allowed values; empty: an integer in [lo, hi]
  int lo = 0, hi = 0;                   ///< integer range (values empty)
  std::string_view default_value;       ///< the rulebook's (named in the description)
  std::string_view description;
};
/// Every variant of every game, in a fixed order.
std::span<const VariantInfo> AllVariants();
/// The variants of one game (empty for free).
std::vector<const VariantInfo*> VariantsFor(GameKind g);

struct Rules {
  GameKind game = GameKind::kFree;
  int race_to = 1;                      ///< frames to win the match, >= 1
  BreakRotation break_rotation = BreakRotation::kAlternate;  ///< also `--rule break=...`
  double shot_clock_s = 0.0;            ///< table time per shot (s); 0 = off
  /// Every variant of the game, name -> value, filled with the defaults by MakeRules.
  std::map<std::string, std::string, std::less<>> variants;

  /// The value of a variant (its default if unset; "" for a name the game lacks).
  std::string_view Variant(std::string_view name) const;
  /// An integer variant's value (0 if unset or not an integer).
  int VariantInt(std::string_view name) const;
};

/// Validates and builds the rules: race_to in [1, 99], shot_clock_s in [0, 3600], every
/// `--rule NAME=VALUE` known for the game and allowed. Messages name the rule and the allowed
/// values, e.g. "rule break_scratch_in_hand must be one of anywhere, kitchen; got \"x\"".
absl::StatusOr<Rules> MakeRules(GameKind game, int race_to = 1, double shot_clock_s = 0.0,
                                const std::vector<std::pair<std::string, std::string>>& settings = {});
/// Sets one variant (validated as in MakeRules). "break" sets break_rotation too.
absl::Status SetVariant(std::string_view name, std::string_view value, Rules* rules);

// ---------------------------------------------------------------------------------------------
// A shot as the referee sees it.

/// What the shooter declares with the strike.
struct ShotCall {
  std::string ball;       ///< called object ball id ("" = none)
  std::string pocket;     ///< called pocket name, as TableSpec::pockets ("" = none)
  bool safety = false;    ///< declared safety (8-ball, 10-ball): the turn passes after the shot
  bool push_out = false;  ///< declared push-out (9-ball, 10-ball, the shot after the break)
  std::string nominate;   ///< nominated ball (snooker colour, free ball)
};

/// Everything a referee reads about one shot.
struct ShotRecord {
  int struck = 0;              ///< index of the struck ball in `before`
  bool placed = false;         ///< the struck ball was placed from hand before this shot
  TableState before;           ///< the table at rest just before the strike (after placement)
  std::vector<billiards::Event> events;  ///< every engine event of the shot, in time order
  TableState after;            ///< the table at rest after the shot
};

/// A ball falling into a pocket (or leaving the table: pocket -1).
struct Pocketing {
  int ball = -1;
  int pocket = -1;   ///< index into TableSpec::pockets; -1 = off the table
  double t_s = 0.0;  ///< when (s, table time)
};

/// A ball the struck ball touched, at the first time it touched it.
struct Contact {
  int ball = -1;
  double t_s = 0.0;  ///< (s, table time)
  int struck_cushions_before = 0;  ///< cushion hits of the struck ball before this contact
};

/// Two events this close in time count as simultaneous (a split hit) (s).
inline constexpr double kSimultaneousS = 1e-9;

/// The facts of a shot, gathered from its events (docs/games.md).
struct ShotFacts {
  int struck = -1;
  /// Balls the struck ball touched first, all at first_contact_t_s (several: a split hit),
  /// ascending index; empty when it touched no ball.
  std::vector<int> first_contacts;
  double first_contact_t_s = -1.0;  ///< (s); -1 when no contact
  /// Every distinct ball the struck ball touched, in order of first touch.
  std::vector<Contact> struck_contacts;
  /// Per ball index: the times of its cushion hits, ascending (s).
  std::vector<std::vector<double>> cushion_t_s;
  /// Pocketings and balls leaving the table, in time order.
  std::vector<Pocketing> pocketed;
  /// Where the struck ball was before its first ball contact: its place before the shot, then
  /// its centre at each of its own events (cushion hits, changes of motion) before that
  /// contact, in time order (every one of them when it touches no ball).
  std::vector<Eigen::Vector2d> struck_path;

  bool Touched(int ball) const;                    ///< the struck ball touched it
  bool Pocketed(int ball) const;                   ///< pocketed or off the table
  bool OffTable(int ball) const;                   ///< left the table (pocket -1)
  int PocketOf(int ball) const;                    ///< pocket index; -1 off table or not pocketed
  int CushionHits(int ball) const;                 ///< all cushion hits of a ball
  int CushionHitsBefore(int ball, double t_s) const;  ///< hits strictly before t_s
  bool AnyCushionAtOrAfter(double t_s) const;      ///< any ball hit a cushion at or after t_s
  /// Number of distinct balls, other than `except`, that hit a cushion.
  int BallsReachingCushion(int except) const;
};

/// Gathers the facts of a shot (pure; any order of equal-time events gives the same facts).
ShotFacts ExtractFacts(const ShotRecord& record);
/// The same from the table before the shot, the struck ball and the shot's events, as a
/// billiards::ShotIntent sees a shot.
ShotFacts ExtractFacts(const TableState& before, int struck,
                       std::span<const billiards::Event> events);

// ---------------------------------------------------------------------------------------------
// Verdicts, game events and the game state.

/// The referee's word on one shot (last_shot.verdict in the API).
struct Verdict {
  bool foul = false;
  /// snake_case: "" (a plain shot), scratch, no_contact, wrong_ball_first, no_rail,
  /// ball_off_table, illegal_break, eight_early, eight_wrong_pocket, wrong_pocket,
  /// three_fouls, shot_clock, push_out, behind_head_string, miss, ...
  std::string reason;
  int points = 0;             ///< points scored (snooker, three-cushion; penalties go to the opponent)
  bool turn_passes = false;   ///< the other seat plays (or decides) next
  std::vector<std::string> respotted;  ///< ball ids put back on the table, in order
  bool frame_over = false;    ///< this shot ended the frame
};

enum class GameEventKind : uint8_t {
  kFoul,      ///< seat fouled; reason; points = penalty awarded (snooker)
  kScore,     ///< seat scored points (or pocketed reason=ball legally, pool)
  kRespot,    ///< ball was put back on the table
  kDecision,  ///< seat must choose one of choices
  kWarning,   ///< seat is on two fouls in a row (9-ball, 10-ball three-foul rule)
  kFrameEnd,  ///< seat won the frame; reason
  kMatchEnd,  ///< winner won the match (-1: a draw); reason = the result
};
/// "foul", "score", "respot", "decision", "warning", "frame_end", "match_end".
std::string_view GameEventKindName(GameEventKind k);

/// Something the server streams to watchers (WatchTable kinds).
struct GameEvent {
  GameEventKind kind = GameEventKind::kFoul;
  int seat = -1;                     ///< the seat it concerns
  std::string reason;                ///< snake_case
  int points = 0;                    ///< points (score, foul penalty)
  int winner = -1;                   ///< frame_end, match_end
  std::string ball;                  ///< respot: the ball id
  std::vector<std::string> choices;  ///< decision: the choices
};

/// A choice the rules give a seat before play goes on.
struct Decision {
  int seat = -1;                      ///< -1: none pending
  std::vector<std::string> choices;   ///< snake_case words
  bool pending() const { return seat >= 0; }
};

/// Everything of the API's game state (docs/cli.md "game"), and the bookkeeping the referees need.
struct GameState {
  GameKind game = GameKind::kFree;
  int frame = 1;                      ///< frame (rack) number, from 1
  int race_to = 1;                    ///< frames to win the match
  std::array<int, 2> frames_won{};    ///< per seat
  int to_play = 0;                    ///< the seat to shoot (or to decide, while one is pending)
  BallInHand ball_in_hand = BallInHand::kNone;
  std::vector<std::string> on;        ///< ball ids the shooter may hit first
  std::array<Group, 2> groups{};      ///< 8-ball: per seat; kNone = open table
  std::array<int, 2> scores{};        ///< points in the frame (snooker, three-cushion)
  std::array<int, 2> fouls_in_row{};  ///< consecutive fouls per seat in this frame
  std::array<bool, 2> warned{};       ///< the seat was warned on two fouls (three-foul rule)
  bool call_required = false;         ///< the next shot must be called or a safety
  bool push_out_available = false;    ///< the next shot may be declared a push-out
  Decision decision;                  ///< pending decision
  int winner = -1;                    ///< the match's winner once it ended (-1: none or a draw)
  MatchResult result = MatchResult::kNone;  ///< set once, when the match ends
  int breaker = 0;                    ///< who broke (or breaks) this frame
  bool is_break = true;               ///< the next shot is the frame's break
  int shot = 0;                       ///< shots judged in the match
  std::array<int, 2> innings{};       ///< innings played per seat in the frame (three-cushion)
  int last_shooter = -1;              ///< who played the last judged shot (-1: none)
  bool pushed_out = false;            ///< the last shot was a push-out (its decision pending)
  // Snooker and three-cushion bookkeeping (owned by those referees).
  std::string phase;                  ///< snooker: "reds", "colour", "colours", "respotted_black"
  std::string nominated;              ///< snooker: the colour nominated for this shot
  bool free_ball = false;             ///< snooker: a free ball is in force
  int misses_in_row = 0;              ///< snooker: misses from the same position (miss rule)
  TableState replay_position;         ///< snooker: the balls before the last stroke (miss rule)
  bool opening = false;               ///< three-cushion: the next shot is the opening shot
  std::string replay_phase;           ///< snooker: `phase` before the last stroke (miss rule)
  /// Seeds the game's draws (snooker: who plays the re-spotted black); an input the server
  /// sets at creation and records, never the wall clock.
  uint64_t seed = 0;

  bool match_over() const { return result != MatchResult::kNone; }
};

/// The result of judging a shot (or a decision, a concession, a shot clock's expiry).
struct Judgement {
  Verdict verdict;
  GameState state;                    ///< the state after
  std::vector<GameEvent> events;      ///< in order
};

// ---------------------------------------------------------------------------------------------
// Referees

/// One game's rules. Implementations are stateless; every call is a pure function.
class Referee {
 public:
  virtual ~Referee() = default;
  virtual GameKind game() const = 0;

  /// Racks a frame: replaces `balls` with the game's rack and sets the per-frame fields of
  /// `state` (frame, breaker and frames_won are already set by the caller; to_play = breaker).
  virtual absl::Status RackFrame(const Rules& rules, const TableModel& model, GameState* state,
                                 TableState* balls) const = 0;
  /// A match started in play from the given balls (a position after a legal break): checks the
  /// ids and sets the per-frame fields of `state` (seat 0 to play).
  virtual absl::Status SetUpInPlay(const Rules& rules, const TableModel& model,
                                   const TableState& balls, GameState* state) const = 0;

  /// Refuses a shot the rules forbid (FailedPrecondition: not this seat's turn, a decision
  /// pending, the match over, a required call or nomination missing, the cue ball still in
  /// hand; InvalidArgument: a call naming an unknown ball or pocket). The message names the
  /// rule. Changes nothing.
  virtual absl::Status CheckShot(const Rules& rules, const TableModel& model,
                                 const GameState& state, int seat, const ShotCall& call,
                                 const TableState& balls) const;
  /// Refuses a placement of the cue ball at `xy` (m) by `seat` outside the zone, overlapping a
  /// ball, off the cloth or in a pocket, or without ball in hand.
  virtual absl::Status CheckPlacement(const Rules& rules, const TableModel& model,
                                      const GameState& state, int seat, const TableState& balls,
                                      const std::string& ball_id, Eigen::Vector2d xy) const;
  /// True when `xy` (m) lies in the placement zone (anywhere: on the cloth; kitchen: behind
  /// the head string, table_marks.h). Snooker overrides it for the D.
  virtual bool InZone(const TableModel& model, BallInHand zone, Eigen::Vector2d xy) const;
  /// Judges a shot that CheckShot accepted. `balls` holds the table at rest after the shot
  /// (record.after); the referee may change it (respots, a new frame's rack).
  virtual Judgement Judge(const Rules& rules, const TableModel& model, const GameState& state,
                          const ShotCall& call, const ShotRecord& record,
                          TableState* balls) const = 0;
  /// Answers a pending decision. FailedPrecondition when none is pending for `seat`,
  /// InvalidArgument for a choice not offered (the message lists the choices).
  virtual absl::StatusOr<Judgement> Decide(const Rules& rules, const TableModel& model,
                                           const GameState& state, int seat,
                                           std::string_view choice, TableState* balls) const = 0;
  /// The seat concedes the frame: the opponent wins it (the match may go on).
  virtual absl::StatusOr<Judgement> Concede(const Rules& rules, const TableModel& model,
                                            const GameState& state, int seat,
                                            TableState* balls) const;
  /// The shot clock of the seat to play expired: the game's penalty (pool: a foul, ball in
  /// hand anywhere). FailedPrecondition after the match or while a decision is pending.
  virtual absl::StatusOr<Judgement> ShotClockExpired(const Rules& rules, const TableModel& model,
                                                     const GameState& state,
                                                     TableState* balls) const = 0;
};

/// Each game's referee, defined in its own file (pool.cc, snooker.cc, three_cushion.cc).
const Referee& EightBallReferee();
const Referee& NineBallReferee();
const Referee& TenBallReferee();
const Referee& SnookerReferee();
const Referee& ThreeCushionReferee();

/// The referee of a game; nullptr for free (and for a game whose referee is not linked in).
const Referee* RefereeFor(GameKind game);

/// Starts a match: state with frame 1, seat 0 to break, and the rack in `balls` (kBreak), or
/// the given balls as a position after a legal break (kInPlay). InvalidArgument for free.
absl::StatusOr<GameState> StartMatch(const Rules& rules, const TableModel& model, Start start,
                                     TableState* balls);

// ---------------------------------------------------------------------------------------------
// Helpers shared by the referees.

/// The other seat.
inline int Other(int seat) { return 1 - seat; }

/// Ends the frame won by `winner` with `reason` (frame_end event), counts it, and either ends
/// the match (match_end event; `result` is the match's result, e.g. kWon, kConceded,
/// kThreeFouls) or racks the next frame with the breaker chosen by rules.break_rotation.
absl::Status EndFrame(const Referee& referee, const Rules& rules, const TableModel& model,
                      int winner, std::string_view reason, MatchResult result, GameState* state,
                      TableState* balls, std::vector<GameEvent>* events);
/// Ends the match as a draw (three-cushion equal innings): match_end with winner -1.
void EndMatchDraw(GameState* state, std::vector<GameEvent>* events);

/// Puts a pocketed (or off-table) ball back on the cloth at rest at `xy`.
void PlaceBall(const TableModel& model, int index, Eigen::Vector2d xy, TableState* balls);
/// True when ball `index` may stand at `xy` (m): on the cloth (inside the cushion noses by the
/// contact distance), outside every pocket's capture circle, and at least 2R + kSpotGapM from
/// every other ball on the table.
bool IsFreeSpot(const TableModel& model, const TableState& balls, int index, Eigen::Vector2d xy);
/// Gap left between a respotted ball and its neighbours (m): "not touching" with margin for
/// the layout check's 1 um tolerance.
inline constexpr double kSpotGapM = 1e-5;
/// The nearest free place to `spot` on the ray spot + t dir (t >= 0, dir a unit vector) up to
/// the cushion; failing that on the ray spot - t dir. The ball ends frozen (kSpotGapM) to a
/// blocking ball when the spot is taken. NotFound when the whole line is taken.
absl::StatusOr<Eigen::Vector2d> FindSpotOnLine(const TableModel& model, const TableState& balls,
                                               int index, Eigen::Vector2d spot,
                                               Eigen::Vector2d dir);

}  // namespace sportsim::games

#endif  // SPORTSIM_SIM_GAMES_GAME_H_
