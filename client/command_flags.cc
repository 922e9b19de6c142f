// The command line's grammar (command_flags.h).
#include "client/command_flags.h"

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "absl/flags/commandlineflag.h"
#include "absl/flags/reflection.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/time.h"
#include "client/cli.h"

namespace sportsim::cli {
namespace {

// This abseil's string_view is its own type, not std::string_view: text is joined here.
template <typename... T>
std::string Cat(const T&... parts) {
  std::string out;
  (out.append(std::string_view(parts)), ...);
  return out;
}
template <typename... T>
void Append(std::string* out, const T&... parts) {
  (out->append(std::string_view(parts)), ...);
}
absl::CommandLineFlag* FindFlag(std::string_view name) {
  return absl::FindCommandLineFlag(absl::string_view(name.data(), name.size()));
}

// ---------------------------------------------------------------------------------------------
// The flags of each command

constexpr std::string_view kGlobal[] = {"server", "format", "timeout"};

// Repeatable flags are not absl flags (absl keeps only a flag's last value): their values are
// kept in order here.
struct Repeatable {
  std::string_view name;
  std::string_view meta;
};
constexpr Repeatable kRepeatable[] = {
    {"ball", "ID@X,Y"}, {"param", "NAME=VALUE"}, {"rule", "NAME=VALUE"}};

using Flags = std::vector<FlagUse>;

Flags Join(std::initializer_list<Flags> parts) {
  Flags out;
  for (const Flags& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

const Flags& SetupFlags() {
  static const Flags f = {
      {"table", "table preset: pool-7ft, pool-8ft, pool-9ft, snooker, carom, unbounded "
                "(default pool-9ft; a ruled game: the game's)"},
      {"rack", "rack: empty, 8ball, 9ball, 10ball, snooker, three-cushion, chapter19 (default: the "
               "preset's game)"},
      {"ball", "put a ball at rest at (X, Y) m; an id already racked moves there, a new one is "
               "added (repeatable, each id once)"},
      {"param", "a model parameter (repeatable; `sportsim info` lists names, units, ranges)"},
      {"param_file", "model parameters from a JSON file: an object of NAME: VALUE, or a `table "
                     "calibrate --format json` report (its params); --param overrides it"},
      {"cushion_model", "han (default), mathavan2010, stronge or mirror"},
      {"ball_ball_model", "alciatore (default: one impulse) or mathavan2014 (integrated, with "
                          "the cloth's friction at the pressed ball)"},
      {"jitter", "seeded random gaps between racked balls, [0, 0.01] m (default 0)"},
      {"rack_seed", "seed of --jitter (default 0)"},
  };
  return f;
}

const Flags& SolverFlags() {
  static const Flags f = {
      {"engine", "billiards engine: event or stepped (default event; stepped with --enable drag)"},
      {"integrator", "stepped engine only: euler, semi_implicit_euler or rk4 (default rk4)"},
      {"dt", "stepped engine only: the step, [1e-6, 0.1] s (default 1/960 s)"},
      {"no_ccd", "stepped engine only: no continuous collision detection"},
      {"disable", "effects to switch off: drag, spin_decay, rolling_resistance, ball_friction, "
                  "cushions, pockets, orientation, squirt"},
      {"enable", "effects off by default to switch on: drag (stepped engine)"},
  };
  return f;
}

const Flags& StrikeFlags() {
  static const Flags f = {
      {"speed", "cue speed V0, (0, 20] m/s (give --speed or --ball-speed)"},
      {"ball_speed", "the struck ball's speed just after the strike, (0, 20] m/s (or --speed)"},
      {"phi", "heading (deg), counter-clockwise from +x, [-360, 360] (default 0)"},
      {"theta", "cue elevation (deg), [0, 89] (default 0)"},
      {"a", "side offset of the tip, fraction of the radius, > 0 right of centre (default 0)"},
      {"b", "vertical offset of the tip, fraction of the radius, > 0 above centre (default 0)"},
      {"noise", "Gaussian strike noise, [0, 100]; 1 = FastFiz's sigmas (default 0)"},
      {"seed", "seed of --noise (default 0)"},
      {"strike_ball", "the ball the cue strikes (default cue; on a table: the server's choice)"},
  };
  return f;
}

const Flags& GolferFlags() {
  static const Flags f = {
      {"gamma", "arm angle at the top of the backswing (deg), [-360, 360] (default 135)"},
      {"beta0", "wrist cock at the top (deg), [-360, 360] (default 120)"},
      {"shoulder_accel"}, {"arm_length"}, {"club_length"}, {"arm_inertia"},
      {"arm_first_moment"}, {"club_inertia"}, {"club_mass"}, {"club_first_moment"}, {"gravity"},
  };
  return f;
}

const Flags& SwingSolverFlags() {
  static const Flags f = {
      {"integrator", "swing integrator: book, euler, semi_implicit_euler, rk4 or dp45 (default "
                     "rk4)"},
      {"dt", "fixed-step schemes only: the step, [1e-6, 0.1] s (default 0.0025 s)"},
      {"tolerance", "dp45 only: the error bound per step, [1e-14, 0.1] (default 1e-8)"},
      {"max_step", "dp45 only: the largest step, [1e-6, 0.1] s (default 0.01 s)"},
  };
  return f;
}

const Flags& SwingDisableFlag() {
  static const Flags f = {{"disable", "swing effects to switch off: gravity, shoulder_accel, "
                                      "wrist_torque"}};
  return f;
}

const Flags& TorqueFlags() {
  static const Flags f = {{"qalpha"}, {"qbeta"}, {"qbeta_until"}};
  return f;
}

const Flags& AirFlags() {
  static const Flags f = {{"wind"},          {"temperature_c"}, {"pressure_pa"},
                          {"humidity"},      {"altitude_m"},    {"aero"},
                          {"sample_interval"}};
  return f;
}

const Flags& BallStrikeFlags() {
  static const Flags f = Join({
      {{"club", "launch a ball at each impact with this club: driver, 3-wood, 3-iron, 5-iron, "
                "7-iron, 9-iron, pitching-wedge, sand-wedge (default: no ball)"},
       {"dynamic_loft_deg"}, {"face_angle_deg"}, {"club_path_deg"}, {"cor"},
       {"fairway", "roll the ball out to rest on a flat fairway: firm, normal or soft (default: "
                   "the flight ends at its landing)"}},
      AirFlags(),
  });
  return f;
}

const Flags& NoFlags() {
  static const Flags f;
  return f;
}

std::vector<CommandSpec> MakeSpecs() {
  const FlagUse token_seat{"token", "a seat's token (create printed it)"};
  const FlagUse token_any{"token", "a seat's token, or the admin token (ruled games: only it)"};
  const FlagUse page_size{"page_size", "entries per page, [0, 1000]; 0: the default, 100"};
  const FlagUse page_token{"page_token", "the previous page's next_page_token"};
  const FlagUse swing_until{"until", "impact (default) or duration"};
  const FlagUse swing_rate{
      "rate", "snapshots per second at most while swinging, [0, 1000]; 0: every tick (default)"};
  const FlagUse swing_svg{"svg", "at the end, a stroboscopic side view of the swing"};
  const FlagUse arm_drawn{"arm_length", "with --svg: the arm length drawn (m; default: from "
                                        "the states)"};
  const FlagUse club_drawn{"club_length", "with --svg: the club length drawn (m; default: from "
                                          "the states)"};
  const FlagUse from_sequence{"from_sequence",
                              "replay the events after this sequence that are still held, "
                              "then go on live"};
  const std::vector<std::pair<std::string_view, std::string_view>> flight_refusals = {
      {"integrator", "the flight is integrated with RK4 at --dt: SimulateFlightRequest has no "
                     "integrator choice"},
      {"tolerance", "the flight is integrated with RK4 at --dt: SimulateFlightRequest has no "
                    "tolerance"},
      {"max_step", "the flight is integrated with RK4 at --dt: SimulateFlightRequest has no "
                   "largest step"},
  };
  return {
      {"info", "", "", "server version, build and capabilities", NoFlags()},
      {"health", "", "[SERVICE]", "gRPC health check; exit 0 when SERVING", NoFlags()},
      {"shot", "simulate", "(--speed V0 | --ball-speed V)",
       "fast-forward one cue shot until every ball is at rest",
       Join({SetupFlags(), SolverFlags(), StrikeFlags(),
             {{"sample_rate", "trajectory samples per second, [1, 10000] (default none; 240 "
                              "with --format csv or --svg)"},
              {"max_time", "stop after this much simulated time, (0, 3600] s (default 600)"},
              {"svg", "write a top view of the table with the paths and events"}}}),
       /*series=*/true},
      {"shot", "batch", "",
       "fast-forward a batch of candidate strikes, read from stdin (one CueStrike as JSON a "
       "line: ball_speed_mps or speed_mps, phi_deg, theta_deg, a, b, ball); prints one JSON "
       "outcome a line, in input order",
       Join({SetupFlags(), SolverFlags(),
             {{"samples", "noise samples of each strike, [1, 1000] (default 1); strikes x "
                          "samples at most 100000"},
              {"noise", "Gaussian noise on every sample, [0, 100]; 1 = FastFiz's sigmas "
                        "(default 0: every sample is the strike itself)"},
              {"seed", "seed of --noise: the same seed, the same outcomes (default 0)"},
              {"outcome", "summary (default: first contact, pocketed, t_rest_s), final (and "
                          "every ball's final state) or events (and every event)"},
              {"max_time", "stop each shot after this much simulated time, (0, 3600] s "
                           "(default 600)"}}}),
       /*series=*/false, /*stream=*/true},
      {"table", "create", "",
       "an authoritative table; prints the seat tokens (and a ruled game's admin token)",
       Join({SetupFlags(), SolverFlags(),
             {{"seats", "seats, [1, 16] (default 2, or the number of --seat-names)"},
              {"seat_names", "seat names, 1 to 32 characters each, each name once"},
              {"tick_hz", "ticks per second, [1, 1000] (default 120)"},
              {"game", "free (default), 8ball, 9ball, 10ball, snooker, three-cushion"},
              {"race_to", "ruled games: frames to win the match, [1, 99] (default 1)"},
              {"shot_clock", "ruled games: seconds of table time per shot, [0, 3600] (default 0: "
                             "off)"},
              {"start", "ruled games: break (default) or in-play"},
              {"aim_lines", "on (default) or off: may the seat to play ask for aim lines "
                            "(PreviewShot)"},
              {"rule", "ruled games: a variant (repeatable; `sportsim info` lists them)"},
              {"noise", "ruled games: noise on every strike, [0, 100] (default 0)"},
              {"seed", "ruled games: the noise's seed (default random, secret until the match "
                       "ends)"}}})},
      {"table", "list", "", "the tables, a page at a time", {page_size, page_token}},
      {"table", "get", "ID", "a table's state", {{"geometry", "include cushions and pockets"}}},
      {"table", "delete", "ID --token T", "delete a table", {token_any}},
      {"table", "reset", "ID --token T", "re-rack a table as it was created", {token_any}},
      {"table", "place", "ID --token T --ball ID@X,Y",
       "ball in hand: put one ball at rest (the seat to play, every ball at rest)",
       {{"token", "the seat to play's token"},
        {"ball", "the ball and where to put it, in m (exactly one)"}}},
      {"table", "shoot", "ID --token T (--speed V0 | --ball-speed V)",
       "strike a shot (the seat to play, every ball at rest)",
       Join({{{"token", "the seat to play's token"}},
             StrikeFlags(),
             {{"next_seat", "free play: pass the turn to this seat with the shot"},
              {"call", "ruled games: the called ball and pocket, BALL:POCKET"},
              {"safety", "ruled games: declare a safety"},
              {"push_out", "9-ball, 10-ball: declare a push-out"},
              {"nominate", "snooker: the nominated ball"}}})},
      {"table", "turn", "ID --token T --seat N", "pass the turn (free play)",
       {{"token", "the seat to play's token"}, {"seat", "the seat to play next"}}},
      {"table", "decide", "ID --token T --choice CHOICE", "answer a ruled game's pending decision",
       {{"token", "the deciding seat's token"}, {"choice"}}},
      {"table", "concede", "ID --token T [--seat N] [--frame N]", "concede the frame",
       {{"token", "a seat's token (it concedes), or the admin token with --seat"},
        {"seat", "with the admin token: the seat that concedes"},
        {"frame", "the frame conceded (default: the table's frame, read first)"}}},
      {"table", "record", "ID", "a ruled game's match record", NoFlags()},
      {"table", "calibrate", "FILE...",
       "fit a table's parameters and each shot's cue inputs to recorded shots (track files of "
       "t, ball, x, y as CSV or JSON lines, `shot simulate --format csv` writes one; or shot "
       "sets, a JSON array of many shots); progress on stderr",
       Join({{{"table", "table preset to start from (default pool-9ft)"},
              {"param", "a starting parameter (repeatable)"},
              {"param_file", "starting parameters from a JSON file (as table create's)"},
              {"cushion_model", "han (default), mathavan2010, stronge or mirror"},
              {"ball_ball_model", "alciatore (default) or mathavan2014"}},
             SolverFlags(),
             {{"fit", "parameters to fit, NAME or NAME=LO:HI, comma separated (default bounds: "
                      "the published ranges; none: the strikes only)"},
              {"heldout", "shots (0-based, in the files' order) scored but not fitted on, comma "
                          "separated"},
              {"window", "held-out shots' strikes from their first seconds only, (0, 3600] s"},
              {"max_iterations", "Levenberg-Marquardt iterations, [1, 1000] (default 60)"},
              {"max_simulations", "simulations in all, [1, 1e9] (default 5000000)"},
              {"cue_ball", "the struck ball in every file (default: the first to depart from "
                           "its spot)"},
              {"fit_elevation", "fit the cue's elevation too (default level)"},
              {"predict", "held-out shots fitted on a --window: best-fit (default) or central "
                          "(the plausible strikes' central rest)"},
              {"intent", "what the held-out shots were meant to do, a prior for --window "
                         "predictions: none (default), three-cushion (the UMB point) or pot "
                         "(a ball pocketed, the struck ball kept up)"},
              {"read_cloth", "read the cloth (mu_roll, mu_slide) from the training shots' "
                             "tracks and start from it"},
              {"huber", "Huber's scale in metres, [0, 1]: false detections pull the fit as "
                        "hard as a point this far (default: squared distances)"},
              {"track_origin", "where the files' (0, 0) is: centre (default, the table frame) "
                               "or corner (of the playing area, x along its length)"},
              {"track_scale", "metres per unit of the files' coordinates (default 1)"}}})},
      {"table", "watch", "ID", "the table's snapshots as they come",
       {{"rate", "snapshots per second at most while balls move, [0, 1000] (default 30); 0, "
                 "or above the tick rate: every tick"},
        {"until_rest", "exit when the table comes to rest after a shot: at the end of the shot "
                       "in progress, or, when the table is at rest, at the end of the next shot"},
        {"fields"}, {"changed_only"}, from_sequence,
        {"svg", "at the end, draw the paths seen"}},
       /*series=*/true, /*stream=*/true},
      {"swing", "simulate", "", "fast-forward one golf swing (and the ball, with --club)",
       Join({SwingSolverFlags(),
             {swing_until,
              {"duration", "run length for --until duration (default 0.5 s), the cap for "
                           "impact (default 2 s); [1e-6, 10] s"},
              {"stride"}},
             TorqueFlags(), GolferFlags(), SwingDisableFlag(),
             {{"club", "launch a ball at the impact with this club: driver, 3-wood, 3-iron, "
                       "5-iron, 7-iron, 9-iron, pitching-wedge, sand-wedge (default: no ball)"},
              {"dynamic_loft_deg"}, {"face_angle_deg"}, {"club_path_deg"}, {"cor"},
              {"fairway", "roll the ball out to rest on a flat fairway: firm, normal or soft "
                          "(default: the flight ends at its landing)"}},
             AirFlags()}),
       /*series=*/true},
      {"swing", "create", "", "a live swing session; prints its id and the seat tokens",
       Join({GolferFlags(), SwingSolverFlags(), SwingDisableFlag(),
             {{"tick_hz", "ticks per second, [1, 1000] (default 400)"},
              {"seats", "seats, [1, 16] (default 1, or the number of --seat-names)"},
              {"seat_names", "seat names, 1 to 32 characters each, each name once"},
              {"profile"}},
             BallStrikeFlags()})},
      {"swing", "list", "", "the sessions, a page at a time", {page_size, page_token}},
      {"swing", "get", "ID", "a session's state", NoFlags()},
      {"swing", "delete", "ID --token T", "delete a session", {token_seat}},
      {"swing", "reset", "ID --token T", "back to the address position",
       {token_seat,
        {"gamma", "a new address position: arm angle at the top (deg), [-360, 360]"},
        {"beta0", "a new address position: wrist cock at the top (deg), [-360, 360]"}}},
      {"swing", "start", "ID --token T", "a swing with a torque program from the next tick",
       Join({{token_seat}, TorqueFlags(),
             {swing_until,
              {"duration", "run length for --until duration, the cap for impact; [1e-6, 10] s "
                           "(default 2 s)"}}})},
      {"swing", "watch", "ID", "the session's states as they come",
       {swing_rate, {"until_impact"}, from_sequence, swing_svg, arm_drawn, club_drawn},
       /*series=*/true, /*stream=*/true},
      {"swing", "drive", "ID --token T",
       "drive a swing with torques from stdin, one t_s,qalpha_nm,qbeta_nm a line",
       {token_seat, swing_rate, {"apply_late"}, swing_until,
        {"duration", "run length for --until duration, the cap for impact; [1e-6, 10] s "
                     "(default 2 s)"},
        swing_svg, arm_drawn, club_drawn},
       /*series=*/true, /*stream=*/true},
      {"flight", "simulate", "--ball-speed MPS --launch-deg DEG --spin-rpm RPM",
       "fly a golf ball from launch conditions to landing",
       Join({{{"ball_speed", "launch speed, (0, 120] m/s (required)"},
              {"launch_deg", "launch angle above the horizontal, [-90, 90] deg (required)"},
              {"spin_rpm", "total spin, [0, 30000] rpm (required)"},
              {"spin_axis_deg"}, {"launch_direction_deg"}},
             AirFlags(),
             {{"dt", "RK4 step, [1e-5, 0.1] s (default 0.001 s)"},
              {"disable", "flight effects to switch off: drag, lift, spin_decay, wind"},
              {"fairway", "roll the ball out to rest on a flat fairway: firm, normal or soft "
                          "(default: the flight ends at its landing)"},
              {"svg", "side view (equal scales) and top view of the trajectory"}}}),
       /*series=*/true, /*stream=*/false, flight_refusals},
      {"golf", "simulate", "(a launch | --putt-speed MPS | --roll-speed MPS)",
       "a golf shot to rest on the ground: bounces, spin-back, skid, roll, slope and hole",
       Join({{{"course", "practice (a plane green, hole at the origin; the default), range (a "
                         "flat fairway) or a course of `course list`"},
              {"hole", "a course's hole, 1-based (default 1)"},
              {"tee", "a course's tee by name (default the hole's first; not with --from)"},
              {"stimp", "practice: the green's Stimpmeter speed, [1, 20] ft (default 10)"},
              {"slope_pct", "practice: the green's grade, [0, 20] %, no steeper than the green "
                            "holds a ball (default 0)"},
              {"slope_toward_deg", "practice: heading the fall line points toward (deg)"},
              {"fairway", "range: firm, normal or soft (default normal)"},
              {"flagstick", "practice or a course: the flagstick (19.05 mm) is in the hole"},
              {"from", "the ball's position X,Y in metres (default -10,0 on practice, 0,0 on "
                       "the range)"},
              {"aim_deg", "a launch's target line, heading in deg (default toward the pin, or "
                          "+x on the range)"},
              {"ball_speed", "a launch: ball speed, (0, 120] m/s"},
              {"launch_deg", "a launch: launch angle above the horizontal, [-90, 90] deg"},
              {"spin_rpm", "a launch: total spin, [0, 30000] rpm"},
              {"spin_axis_deg"}, {"launch_direction_deg"},
              {"putt_speed", "a putt (struck: it skids first), [0, 15] m/s"},
              {"putt_direction_deg", "the putt's heading (deg, ccw from +x; default 0)"},
              {"roll_speed", "a ball already rolling (as off a Stimpmeter), [0, 15] m/s"},
              {"roll_direction_deg", "the rolling ball's heading (deg, ccw from +x; default 0)"}},
             AirFlags(),
             {{"disable", "ground effects to switch off: ground_spin, ground_slope"},
              {"svg", "the path from above, with the hole, bounces and rest (on a course: "
                      "over its surfaces and elevation)"}}}),
       /*series=*/true, /*stream=*/false, flight_refusals},
      {"course", "list", "", "the server's golf courses: holes, pars, lengths", NoFlags()},
      {"course", "show", "NAME", "a golf course's holes, tees, pins and surfaces",
       {{"hole", "only this hole (1-based); --svg frames it"},
        {"svg", "the course from above: surfaces, elevation, tees and pins"}}},
      {"round", "create", "--players NAME,NAME",
       "a round of golf on a course (stroke play, match play or Stableford, gross or net); "
       "prints the seat tokens and the admin token",
       {{"course", "a course of `course list` (default sportsim_links)"},
        {"holes", "the holes played, A-B (default all of the course's)"},
        {"players", "the players' names in seat order, 1 to 8 (required)"},
        {"tees", "each player's tee by name, in seat order (default each hole's first)"},
        {"play", "the form of play: stroke (default), match (two players) or stableford"},
        {"handicaps", "each player's Handicap Index in seat order (World Handicap System; "
                      "+2.1 or -2.1 is a plus handicap, - none): net scores by stroke index"},
        {"profile", "realistic (default: launches within a human's reach) or arcade"},
        {"noise", "the spread of launches and putts, [0, 5] (default 0)"},
        {"seed", "the seed of the noise and of drops (default 0)"},
        {"rule", "a round variant (repeatable): order=honour|ready; max_score=N|par+N|"
                 "net_double_bogey (stroke play); allowance=PCT (handicap allowance)"},
        {"tick_hz", "ticks per second, [1, 240] (default 30)"},
        {"fast_forward", "each stroke comes to rest at the next tick (tests, bots)"},
        {"shot_clock", "round time the seat to play has, [0, 3600] s (default 0: none); when it "
                       "runs out, a penalty stroke, and it starts again"}}},
      {"round", "list", "", "the rounds, a page at a time", {page_size, page_token}},
      {"round", "get", "ID", "a round: whose turn, every ball's lie and distance, the scores",
       NoFlags()},
      {"round", "scorecard", "ID", "a round's scorecard: each hole's score, totals, against par",
       NoFlags()},
      {"round", "record", "ID", "a round's creation and every command with its tick", NoFlags()},
      {"round", "delete", "ID --token T", "delete a round", {{"token", "the admin token"}}},
      {"round", "stroke", "ID --token T (a launch | --putt-speed MPS)",
       "play the seat's ball where it lies (the seat to play)",
       {{"token", "the seat's token"},
        {"ball_speed", "a launch: ball speed, (0, 120] m/s (realistic: at most 107)"},
        {"launch_deg", "a launch: launch angle above the horizontal, deg"},
        {"spin_rpm", "a launch: total spin, rpm"},
        {"spin_axis_deg"}, {"launch_direction_deg"},
        {"aim_deg", "a launch's target line, heading in deg (default toward the pin)"},
        {"putt_speed", "a putt (struck: it skids first), (0, 15] m/s"},
        {"putt_direction_deg", "the putt's heading (deg, ccw from +x; default toward the pin)"},
        {"club", "a swing with this club (driver, 3-wood, 3-iron, 5-iron, 7-iron, 9-iron, "
                 "pitching-wedge, sand-wedge): the golfer's torques run to impact"},
        {"qalpha"}, {"qbeta"}, {"qbeta_until"},
        {"dynamic_loft_deg"}, {"face_angle_deg"}, {"club_path_deg"},
        {"gamma"}, {"beta0"}, {"arm_length"}, {"club_length"}, {"arm_inertia"},
        {"arm_first_moment"}, {"club_inertia"}, {"club_mass"}, {"club_first_moment"},
        {"gravity"}, {"shoulder_accel"},
        {"flagstick", "--flagstick=false takes the flagstick out for this stroke (default in)"}}},
      {"round", "decide", "ID --token T --choice CHOICE",
       "a relief decision: a pending decision's choice, or unplayable on the seat's turn",
       {{"token", "the deciding seat's token"},
        {"choice", "stroke_and_distance, back_on_the_line, lateral, "
                   "back_on_the_line_outside_bunker (as offered), unplayable, pick_up, or "
                   "match play's concede_stroke, concede_hole, concede_match"},
        {"back_m", "back_on_the_line: metres behind the reference point on the line from the "
                   "hole (default: the nearest point that leaves room to drop)"}}},
      {"round", "concede", "ID --token T [--stroke | --hole | --match]",
       "match play: concede the opponent's next stroke (the default; their ball is holed with "
       "it), the hole or the match (Rule 3.2b: final once made)",
       {{"token", "the conceding seat's token"}}},
      {"round", "monitor", "ID --token T --device DEVICE_ID",
       "bind a launch monitor (its GSPro Open Connect DeviceID) to the seat: its shots sent to "
       "the server's Open Connect listener play the seat's strokes",
       {{"token", "the seat's token"}, {"device", "the DeviceID the monitor's connector sends"}}},
      {"round", "pickup", "ID --token T",
       "pick up the seat's ball (Stableford: no score on the hole; stroke play with a maximum "
       "score: the maximum)",
       {{"token", "the seat's token"}}},
      {"round", "watch", "ID", "a round's events as they come",
       {{"rate", "snapshots per second at most while a ball moves (default: every tick)"},
        {"until_rest", "exit when the moving ball (or the next one) comes to rest"},
        from_sequence},
       /*series=*/false, /*stream=*/true},
  };
}

const std::vector<CommandSpec>& Specs() {
  static const auto* specs = new std::vector<CommandSpec>(MakeSpecs());
  return *specs;
}

bool IsGlobal(std::string_view name) {
  return std::find(std::begin(kGlobal), std::end(kGlobal), name) != std::end(kGlobal);
}

const Repeatable* FindRepeatable(std::string_view name) {
  for (const Repeatable& r : kRepeatable) {
    if (r.name == name) return &r;
  }
  return nullptr;
}

// Every flag some command takes, and the global ones.
const std::set<std::string_view>& KnownFlags() {
  static const auto* known = [] {
    auto* s = new std::set<std::string_view>(std::begin(kGlobal), std::end(kGlobal));
    for (const CommandSpec& c : Specs()) {
      for (const FlagUse& f : c.flags) s->insert(f.name);
    }
    return s;
  }();
  return *known;
}

// The names given on the command line, in order (each once).
std::vector<std::string>& GivenOrder() {
  static auto* names = new std::vector<std::string>();
  return *names;
}

std::set<std::string, std::less<>>& GivenSet() {
  static auto* names = new std::set<std::string, std::less<>>();
  return *names;
}

std::map<std::string, std::vector<std::string>, std::less<>>& Repeated() {
  static auto* values = new std::map<std::string, std::vector<std::string>, std::less<>>();
  return *values;
}

std::string Meta(std::string_view name) {
  if (const Repeatable* r = FindRepeatable(name)) return std::string(r->meta);
  const absl::CommandLineFlag* f = FindFlag(name);
  if (f == nullptr || f->IsOfType<bool>()) return "";
  if (f->IsOfType<double>() || f->IsOfType<std::optional<double>>()) return "X";
  if (f->IsOfType<int>() || f->IsOfType<std::optional<int>>() || f->IsOfType<uint64_t>() ||
      f->IsOfType<std::optional<uint64_t>>()) {
    return "N";
  }
  if (f->IsOfType<std::vector<std::string>>()) return "A,B,...";
  if (f->IsOfType<absl::Duration>()) return "D";
  return "S";
}

// Why a value does not parse as the flag's type.
std::string WhyNot(const absl::CommandLineFlag& f, std::string_view value) {
  if (f.IsOfType<double>() || f.IsOfType<std::optional<double>>()) {
    return Cat("'", value, "' is not a number");
  }
  if (f.IsOfType<int>() || f.IsOfType<std::optional<int>>()) {
    return Cat("'", value, "' is not an integer");
  }
  if (f.IsOfType<uint64_t>() || f.IsOfType<std::optional<uint64_t>>()) {
    return Cat("'", value, "' is not an integer, 0 or more");
  }
  if (f.IsOfType<absl::Duration>()) {
    return Cat("'", value, "' is not a duration (e.g. 500ms, 30s, 1m)");
  }
  if (f.IsOfType<bool>()) return Cat("'", value, "' is not true or false");
  return Cat("'", value, "' is not a valid value");
}

std::string FlagLine(std::string_view name, std::string_view help_override) {
  std::string help(help_override);
  std::string default_text;
  if (const absl::CommandLineFlag* f = FindFlag(name)) {
    if (help.empty()) help = f->Help();
    const std::string d = f->DefaultValue();
    // Defaults worth showing: not empty, not "false", not an unset optional.
    if (help_override.empty() && !d.empty() && d != "false" && !f->IsOfType<bool>() &&
        help.find("default") == std::string::npos) {
      default_text = " (default " + d + ")";
    }
  }
  std::string left = Dashed(name);
  if (const std::string meta = Meta(name); !meta.empty()) left += " " + meta;
  return absl::StrFormat("  %-26s %s%s\n", left, help, default_text);
}

}  // namespace

std::string Dashed(std::string_view name) {
  std::string out = "--";
  for (char c : name) out += c == '_' ? '-' : c;
  return out;
}

bool FlagGiven(std::string_view name) { return GivenSet().contains(name); }

const std::vector<std::string>& RepeatedFlagValues(std::string_view name) {
  static const std::vector<std::string> kNone;
  auto it = Repeated().find(name);
  return it == Repeated().end() ? kNone : it->second;
}

std::vector<std::string>& WordFlagsGiven() {
  static auto* words = new std::vector<std::string>();
  return *words;
}

const std::vector<std::string>& WordFlags() { return WordFlagsGiven(); }

std::optional<std::string> ParseArgs(int argc, char** argv, std::vector<std::string>* positional,
                                     HelpRequest* help) {
  bool flags_done = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (flags_done) {
      positional->push_back(a);
      continue;
    }
    if (a == "--") {
      flags_done = true;
      continue;
    }
    // --name, --name=value; a single dash too (-name), as the flag library allows, but not a
    // negative number.
    const bool flag = (a.size() > 2 && a[0] == '-' && a[1] == '-') ||
                      (a.size() > 1 && a[0] == '-' && std::isalpha(static_cast<unsigned char>(a[1])));
    if (!flag) {
      positional->push_back(a);
      continue;
    }
    const size_t start = a[1] == '-' ? 2 : 1;
    const size_t eq = a.find('=');
    std::string name = a.substr(start, eq == std::string::npos ? std::string::npos : eq - start);
    std::replace(name.begin(), name.end(), '-', '_');
    const bool has_value = eq != std::string::npos;
    std::string value = has_value ? a.substr(eq + 1) : "";
    if (name == "help" || name == "helpshort" || name == "h") {
      if (*help == HelpRequest::kNone) *help = HelpRequest::kHelp;
      continue;
    }
    if (name == "helpfull") {
      *help = HelpRequest::kHelpFull;
      continue;
    }
    const std::string shown = Dashed(name);
    // `round concede ID --stroke | --hole | --match`: words choosing what is conceded, not the
    // golf commands' --hole N.
    if (!has_value && positional->size() >= 2 && (*positional)[0] == "round" &&
        (*positional)[1] == "concede" && (name == "stroke" || name == "hole" || name == "match")) {
      WordFlagsGiven().push_back(name);
      continue;
    }
    if (const Repeatable* r = FindRepeatable(name)) {
      if (!has_value) {
        if (i + 1 >= argc) return shown + ": needs a value, " + std::string(r->meta);
        value = argv[++i];
      }
      Repeated()[name].push_back(value);
      if (GivenSet().insert(name).second) GivenOrder().push_back(name);
      continue;
    }
    absl::CommandLineFlag* f =
        KnownFlags().contains(name) ? FindFlag(name) : nullptr;
    if (f == nullptr) {
      return shown + ": unknown flag (sportsim --helpfull lists every flag)";
    }
    if (GivenSet().contains(name)) return shown + ": given twice";
    if (f->IsOfType<bool>()) {
      if (!has_value) value = "true";
    } else if (!has_value) {
      if (i + 1 >= argc) return shown + ": needs a value";
      value = argv[++i];
    }
    if (value.empty() && !f->IsOfType<std::string>() &&
        !f->IsOfType<std::vector<std::string>>()) {
      return shown + ": needs a value";
    }
    std::string error;
    if (!f->ParseFrom(value, &error)) return shown + ": " + WhyNot(*f, value);
    GivenSet().insert(name);
    GivenOrder().push_back(name);
  }
  return std::nullopt;
}

const CommandSpec* FindCommand(std::string_view command, std::string_view sub) {
  for (const CommandSpec& c : Specs()) {
    if (c.command == command && c.sub == sub) return &c;
  }
  return nullptr;
}

std::optional<std::string> CheckFlagsApply(const CommandSpec& spec) {
  const std::string name =
      spec.sub.empty() ? std::string(spec.command) : Cat(spec.command, " ", spec.sub);
  for (const std::string& given : GivenOrder()) {
    if (IsGlobal(given)) continue;
    const bool takes = std::any_of(spec.flags.begin(), spec.flags.end(),
                                   [&](const FlagUse& f) { return f.name == given; });
    if (takes) continue;
    for (const auto& [flag, why] : spec.refusals) {
      if (flag == given) return Cat(Dashed(given), ": not a flag of ", name, ": ", why);
    }
    return Cat(Dashed(given), ": not a flag of ", name, " (sportsim ", name,
                        " --help lists its flags)");
  }
  return std::nullopt;
}

std::optional<std::string> CommandHelp(std::string_view command, std::string_view sub) {
  std::vector<const CommandSpec*> specs;
  for (const CommandSpec& c : Specs()) {
    if (c.command == command && (sub.empty() || c.sub == sub)) specs.push_back(&c);
  }
  if (specs.empty()) return std::nullopt;
  std::string out;
  if (specs.size() > 1) {
    Append(&out, "sportsim ", command, " SUBCOMMAND ... (sportsim ", command,
                    " SUBCOMMAND --help for its flags)\n\n");
    for (const CommandSpec* c : specs) {
      Append(&out, absl::StrFormat("  %-10s %s\n", c->sub, c->what));
    }
    return out;
  }
  const CommandSpec& c = *specs.front();
  Append(&out, "sportsim ", c.command, c.sub.empty() ? "" : " ", c.sub,
                  c.args.empty() ? "" : " ", c.args, c.flags.empty() ? "" : " [flags]", "\n  ",
                  c.what, "\n\n");
  if (c.flags.empty()) {
    Append(&out, "Takes no flags of its own.\n");
  } else {
    Append(&out, "Flags:\n");
    for (const FlagUse& f : c.flags) Append(&out, FlagLine(f.name, f.help));
  }
  Append(&out, "\nGlobal flags (any command):\n");
  for (std::string_view g : kGlobal) Append(&out, FlagLine(g, ""));
  Append(&out, "Output: --format ", c.series ? "text, json or csv" : "text or json",
                  c.stream ? " (jsonl too: one line per snapshot)" : "",
                  ". Any other flag is a usage error (exit 64).\n");
  return out;
}

std::string FullHelp(std::string_view usage) {
  std::string out(usage);
  Append(&out, "\n\nEvery flag (sportsim COMMAND SUBCOMMAND --help: a command's own, with "
                        "their meaning there):\n");
  std::set<std::string_view> names = KnownFlags();
  for (const Repeatable& r : kRepeatable) names.insert(r.name);
  for (std::string_view n : names) {
    std::string help;
    if (n == "ball") help = "a ball ID@X,Y (repeatable): shot simulate, table create, table place";
    if (n == "param") help = "a model parameter NAME=VALUE (repeatable): shot simulate, table create";
    if (n == "rule") help = "a game variant NAME=VALUE (repeatable): table create";
    std::vector<std::string> users;
    for (const CommandSpec& c : Specs()) {
      for (const FlagUse& f : c.flags) {
        if (f.name == n) users.push_back(Cat(c.command, " ", c.sub));
      }
    }
    std::string line = FlagLine(n, help);
    if (!users.empty() && help.empty()) {
      line.pop_back();  // the newline
      std::string joined;
      for (const std::string& u : users) Append(&joined, joined.empty() ? "" : ", ", u);
      line += "\n      " + std::string(26, ' ') + "(" + joined + ")\n";
    }
    out += line;
  }
  return out;
}

}  // namespace sportsim::cli
