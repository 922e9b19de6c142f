// Calibration from recorded shots: the balls' tracked positions over time, scored against the
// engine's, and a fit of each shot's cue inputs and the table's parameters to them.
//
// A recording is a table at rest (the balls where they stood before the strike), the struck
// ball, and tracked positions (t, ball, x, y) on the tracker's clock, as a camera tracker
// gives them (50 Hz is common). The cue inputs are usually unknown: a shot's strike (the cue
// ball's speed, heading and tip offsets; the cue level) is fitted with it, and so is the
// strike's time on that clock where the recording does not give it.
//
// The score of a shot (ShotError) is the mean distance between each tracked position and the
// simulated ball's centre at the same time, over every tracked point of every ball; the fit
// minimises the sum over shots of each shot's mean squared distance (each shot weighs the
// same whatever its length or frame rate), by Levenberg-Marquardt (Eigen's) in an unbounded
// coordinate per parameter (a logistic map onto its bounds), with forward differences for the
// Jacobian. With a Huber scale (CalibrationOptions::huber_m) each point's squared distance d^2
// is replaced by Huber's loss, d^2 up to the scale and 2 huber_m d - huber_m^2 beyond it, so
// that a tracker's false detections (a reflection, a hand, two balls' labels swapped) pull the
// fit no harder than a point the scale away; the reported scores stay the plain distances.
// A shot's strike starts from the cue ball's first tracked motion and several tip
// offsets, each refined, the best kept. The joint fit then moves the table's parameters and
// every training shot's strike together. Held-out shots never inform the table's parameters:
// their strikes are fitted before and after, with the table's parameters fixed, to report the
// error a new shot would see.
#ifndef SPORTSIM_SIM_BILLIARDS_CALIBRATE_H_
#define SPORTSIM_SIM_BILLIARDS_CALIBRATE_H_

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "Eigen/Core"
#include "absl/status/statusor.h"
#include "sim/billiards/cue.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"

namespace sportsim::billiards {

/// Latest time a track may hold (s).
inline constexpr double kMaxTrackTime = 3600.0;
/// A ball tracked this far from where it stood (m) has been struck: how a track file names
/// its struck ball, and where a strike fit reads the cue ball's first motion.
inline constexpr double kStruckDistance = 0.01;

/// One tracked position: ball `ball` (its index in Recording::initial) centred at `xy` (m, the
/// table frame) at `t_s` (s on the track's clock; the strike is at Recording::strike_time_s).
struct TrackPoint {
  double t_s = 0.0;
  int ball = 0;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
};

/// Largest angle (degrees) between a ball's first two points away from its spot, seen from
/// the spot, for them to be its departure (Departs).
inline constexpr double kDepartureDeg = 15.0;

/// Whether a ball's tracked point p, followed by its next point q, is its departure from its
/// spot: both kStruckDistance away or more, q farther, and in the same direction from the spot
/// within kDepartureDeg (a struck ball's first motion is straight, or nearly, whatever its
/// spin). A tracker's false detection (a reflection, a hand, another ball's label) lands
/// anywhere, and two in a row hardly ever line up so: a shot starts at a departure, not at a
/// point away.
bool Departs(const Eigen::Vector2d& spot, const TrackPoint& p, const TrackPoint& q);

/// A recorded shot.
struct Recording {
  std::string name;
  TableState initial;              ///< every ball at rest before the strike
  int cue = 0;                     ///< the struck ball (index in initial.balls)
  std::vector<TrackPoint> track;   ///< in time order (ties in any order)
  /// The cue inputs when they are known (a robot, a sensor cue): then they are not fitted.
  std::optional<CueStrike> strike;
  /// When the cue struck, on the track's clock (s). A tracker's clock rarely starts at the
  /// strike: it may run for a while before it, and at 50 Hz the strike falls anywhere within
  /// a 20 ms frame, which a 3 m/s ball crosses 6 cm of. nullopt: unknown, fitted with the
  /// strike, between the cue ball's last tracked point on its spot (within 3 mm; else 0) and
  /// its departure (Departs: a point away alone may be a tracker's false detection). A known
  /// strike needs a known time.
  std::optional<double> strike_time_s = 0.0;
};

/// Checks a recording against a model: balls on the table and at rest, a valid cue index,
/// at least one tracked point, times finite, in [0, kMaxTrackTime] and in order, ball indices
/// valid, positions finite, a known strike valid and timed, a strike time in [0,
/// kMaxTrackTime]. InvalidArgument naming the field.
absl::Status ValidateRecording(const TableModel& model, const Recording& recording);

/// How far the engine's shot is from the recording.
struct ShotError {
  double mean_m = 0.0;   ///< mean distance over the tracked points (the score)
  double rms_m = 0.0;    ///< root mean square distance
  double max_m = 0.0;    ///< largest distance
  int points = 0;        ///< tracked points scored
};

/// Simulates `strike` on the recording's table under `model`, struck at `strike_time_s` on
/// the track's clock (by default the recording's, or where it is unknown the estimate read
/// from the cue ball's track), and scores it against the tracked points up to until_s after
/// the strike (all of them by default); before the strike every ball is where it stood.
/// Errors: the strike's or the engine's (InvalidArgument, ResourceExhausted).
absl::StatusOr<ShotError> ScoreShot(const TableModel& model, const SolverOptions& solver,
                                    const Recording& recording, const CueStrike& strike,
                                    double until_s = 1e300,
                                    std::optional<double> strike_time_s = std::nullopt);

/// What the player meant a shot to do, as a prior for a fit that sees only the shot's start
/// (StrikeBounds::intent): whether a simulated shot did it, given the table before the strike,
/// the struck ball and the engine's events in time order. A three-cushion point, say
/// (games::ThreeCushionIntent).
using ShotIntent =
    std::function<bool(const TableState& before, int cue, std::span<const Event> events)>;

/// A prediction (StrikeBounds::central_rest, intent) weighs the strikes whose loss over the
/// window is within this many times the residuals' variance of the best fit's (a chi-square
/// difference; each weighs as its likelihood against the best's, exp(-chi2 / 2), so that
/// those near the bound count for a hundredth of the best).
inline constexpr double kPlausibleChi2 = 9.0;

/// What a shot's fitted strike may be: the cue ball's speed just after the strike (ball_speed),
/// its heading, the tip offsets (each within +-0.7 of the miscue limit, so that both together
/// stay inside it) and, when fit_elevation, the cue's elevation (else level); and how it is
/// searched for.
struct StrikeBounds {
  double min_speed_mps = 0.05;
  double max_speed_mps = kMaxStrikeSpeed;
  bool fit_elevation = false;
  double max_elevation_deg = 30.0;
  /// Resample the fit's starts between its windows (docs/billiards.md, "Resampled starts"):
  /// with the table's model right, fewer misses on chaotic shots; under a wrong model
  /// (every real table) no better on the whole shot and worse at predicting it from its
  /// start, so off by default.
  bool resample = false;
  /// Predicting a shot from its start: how a fit over a window that ends before the track
  /// does picks its strike. The window leaves the strike undetermined (before its first
  /// cushion or ball a level cue's side spin hardly shows, the height only once the slide
  /// ends), and a hair's difference there is a metre at the end of a three-cushion path. So
  /// the fit weighs the plausible strikes (a grid of tip offsets, the rest of each strike
  /// fitted to the window; those within kPlausibleChi2 of the best fit, each as its
  /// likelihood), played to rest (docs/billiards.md, "Predicting a shot from its start"):
  ///  - central_rest: the strike taken is the one whose rest is the plausible strikes'
  ///    weighted medoid (the least expected distance from where the ball will rest), not the
  ///    best fit's;
  ///  - intent: what the shot was meant to do (empty: nothing assumed), a prior: the grid is
  ///    refined where it is plausible (a band of strikes that meet an intent can be narrower
  ///    than its step), and only the plausible strikes that meet it are weighed, where any
  ///    does (else the coarse grid's, as with no intent); with central_rest off, the best of
  ///    them is taken (the best fit itself, and nothing more is tried, where it meets the
  ///    intent).
  /// Neither is consulted over a whole track (the data decide) or in a calibration's
  /// training fits; a calibration's held-out shots take them.
  bool central_rest = false;
  ShotIntent intent;
};

/// Fits a shot's strike (and its time, where the recording's is unknown) to its tracked
/// points up to until_s after the strike (with the table fixed). An unknown strike time is
/// fitted on the first motion, then refined with the strike over the whole window within a
/// tenth of a tracker's frame of it (docs/billiards.md); its window is counted from its
/// estimate read from the track, so that the points fitted stay the same while it moves.
struct StrikeFit {
  CueStrike strike;       ///< ball_speed = true: speed_mps is the cue ball's speed
  double strike_time_s = 0.0;  ///< on the track's clock (the recording's when known)
  ShotError error;        ///< over the points fitted
  int64_t simulations = 0;
  /// A prediction's (StrikeBounds::central_rest, intent): the plausible strikes found (0:
  /// none weighed, the best fit taken), whether the strike taken meets the intent, and its
  /// loss over the window above the best fit's, in the residuals' variances.
  int plausible = 0;
  bool intent_met = false;
  double window_chi2 = 0.0;
};
/// huber_m > 0 fits under Huber's loss with that scale (m; see the top of this file), 0 under
/// squared distances.
absl::StatusOr<StrikeFit> FitStrike(const TableModel& model, const SolverOptions& solver,
                                    const Recording& recording, const StrikeBounds& bounds = {},
                                    double until_s = 1e300, double huber_m = 0.0);

/// Largest Huber scale a fit takes (m).
inline constexpr double kMaxHuberScale = 1.0;

/// A table parameter to fit (a ParamInfos() name) and its bounds; lo = hi = 0 takes the
/// published range of CalibrationRange (or, for parameters without one, the parameter's
/// allowed range).
struct FitParam {
  std::string name;
  double lo = 0.0, hi = 0.0;
};

/// The published range a parameter is searched in by default (lo, hi), where there is one:
/// the cloth, ball and cushion constants of Alciatore's typical-values FAQ and Mathavan et
/// al. (2010). nullopt: none (the parameter's allowed range is used).
std::optional<std::pair<double, double>> CalibrationRange(std::string_view name);

struct CalibrationOptions {
  std::vector<FitParam> params;    ///< the table's parameters to fit (may be empty: strikes only)
  /// Indices of the recordings held out of the fit (scored only).
  std::vector<int> heldout;
  StrikeBounds strike_bounds;
  /// Fit each held-out shot's strike on its points up to this long after the strike only;
  /// the held-out report then also says how well the rest of the shot is predicted. Default:
  /// every point.
  double strike_window_s = 1e300;
  /// Levenberg-Marquardt iterations of the joint fit on whole shots, each start's (with
  /// unknown strike times, a quarter of them, at least one of two or more, go to the last
  /// solve, which frees the times); the fits on the shots' first seconds before the first
  /// start's (docs/billiards.md, "Growing windows", "Two starts") take up to 10 more a window
  /// (up to max_iterations if that is fewer).
  int max_iterations = 60;
  int64_t max_simulations = 5000000;  ///< budget over the whole calibration
  /// Huber's scale (m) for every fit (0: squared distances). A scale a few times the
  /// tracker's noise and below the model's error (2 cm, say) makes the fit robust to false
  /// detections; the reports' distances are the plain ones either way.
  double huber_m = 0.0;
  /// Read the cloth from the training shots' tracks first (ReadCloth, no model of the table)
  /// and start from it: the rolling resistance and the sliding friction each replace the
  /// table's where at least kClothMinStretches stretches read it, as a given parameter would
  /// (everything "before" is scored on it; a fitted one starts there, within its bounds).
  /// InvalidArgument when neither is read. Held-out shots are not read.
  bool read_cloth = false;
  std::function<bool()> cancelled;  ///< polled between simulations: Cancelled
  /// Called as the calibration goes: the fraction done (0..1) and the stage's name.
  std::function<void(double, std::string_view)> progress;
};

/// One recording's fit: its strike and error before (the model's parameters as given) and
/// after (the fitted parameters), each scored on all its tracked points.
struct ShotReport {
  std::string name;
  bool heldout = false;
  CueStrike strike_before, strike_after;
  double strike_time_before_s = 0.0, strike_time_after_s = 0.0;  ///< on the track's clock
  ShotError before, after;
  /// A held-out shot predicted from its window under the fitted parameters
  /// (StrikeBounds::central_rest, intent): StrikeFit's plausible and intent_met.
  int plausible = 0;
  bool intent_met = false;
};

struct ParamReport {
  std::string name;
  double before = 0.0, after = 0.0, lo = 0.0, hi = 0.0;
  /// The fitted value's standard error, linearised at the fit with every strike profiled out
  /// (variable projection) and the tracker's noise taken as independent between points, at
  /// the scale of the fit's residuals: what the shots determine the parameter to. Correlated
  /// errors (a model that is wrong the same way along a shot) make the true spread larger.
  /// Infinity where the shots cannot tell the parameter from the others (a part of it in the
  /// normal matrix's null space: no shot moves it, or it trades exactly against others, or
  /// it sits at a bound, where its coordinate no longer moves); 0 where nothing was fitted.
  double standard_error = 0.0;
  /// The fit ended within a thousandth of its range of a bound: the best value may lie
  /// beyond it, and the standard error (of the bounded coordinate) says little.
  bool at_bound = false;
};

/// What a set of recordings says of their cloth, read from every ball's stretches (ReadCloth,
/// below): the rolling resistance (a roll's deceleration over g) and the sliding friction (a
/// slide's acceleration over g), each as the median and quartiles over the stretches (each
/// stretch one measurement: the spread between them is the cloth's and the balls', far above a
/// single fit's standard error). Zero where no stretch was found.
struct ClothReading {
  int rolling = 0, sliding = 0;  ///< stretches read
  double mu_roll = 0.0, mu_roll_q1 = 0.0, mu_roll_q3 = 0.0;
  double mu_slide = 0.0, mu_slide_q1 = 0.0, mu_slide_q3 = 0.0;
};

/// The fewest stretches a calibration takes a cloth constant from (CalibrationOptions::
/// read_cloth): fewer, and one odd stretch (a ball grazing another unseen) is the median.
inline constexpr int kClothMinStretches = 3;

/// What CalibrationOptions::read_cloth read and took: the table's values before it beside the
/// reading, and which of the two constants replaced them.
struct ClothTaken {
  ClothReading reading;
  double mu_roll_before = 0.0, mu_slide_before = 0.0;
  bool mu_roll_taken = false, mu_slide_taken = false;
  /// The values taken (the reading's medians, within a fitted constant's bounds).
  double mu_roll = 0.0, mu_slide = 0.0;
};

struct CalibrationReport {
  PhysicsParams params;              ///< the fitted parameters (the model's, the fitted ones moved)
  std::vector<ParamReport> fitted;   ///< in CalibrationOptions::params order
  std::vector<ShotReport> shots;     ///< in recording order
  /// Median over the shots of each shot's mean distance (m).
  double train_before_m = 0.0, train_after_m = 0.0;
  double heldout_before_m = 0.0, heldout_after_m = 0.0;  ///< 0 when nothing is held out
  int iterations = 0;                ///< joint fit iterations
  int64_t simulations = 0;
  /// The joint fit's starts, each one's loss at its end as a distance (m): the root of the
  /// training shots' mean squared distances (under Huber's loss, its squares) averaged over
  /// the shots. The first, growing windows (docs/billiards.md); the second, the fit over
  /// whole shots from the starting parameters, when the first ended above the trackers'
  /// noise ("Two starts"): infinity where it ran out of its share of the budget (the
  /// budget less a reserve for what follows), and the first stood. Empty when nothing was
  /// fitted jointly (strikes alone).
  std::vector<double> start_rms_m;
  int start_kept = 0;  ///< the start whose fit was kept (1 or 2; 0 with no joint fit)
  /// With read_cloth: the reading of the training shots' tracks and what it replaced.
  std::optional<ClothTaken> cloth;
};

/// Checks a calibration's inputs as Calibrate does before any work (the model, the solver,
/// every recording, the parameters and their bounds, the held-out indices, the options).
absl::Status ValidateCalibration(const TableSpec& spec, const SolverOptions& solver,
                                 std::span<const Recording> recordings,
                                 const CalibrationOptions& options);

/// Calibrates `spec`'s parameters (the model's starting point) and every shot's strike to the
/// recordings. InvalidArgument for a bad recording (its index named), parameter name, bound or
/// option; ResourceExhausted past max_simulations; Cancelled when `cancelled` says so.
absl::StatusOr<CalibrationReport> Calibrate(const TableSpec& spec, const SolverOptions& solver,
                                            std::span<const Recording> recordings,
                                            const CalibrationOptions& options);

/// The rails of a rectangular playing area: the side x = +length/2, x = -length/2, y = +width/2,
/// y = -width/2.
enum class Rail { kPlusX = 0, kMinusX = 1, kPlusY = 2, kMinusY = 3 };

/// The rail nearest a point of the table (the side whose line is closest).
Rail NearestRail(const TableSpec& spec, const Eigen::Vector2d& xy);

/// The rails ball `ball` meets in a recording, in order, read from its track alone (a
/// model-free reference for a recorded shot's cushion sequence): a bounce is a sample whose
/// distance from a rail is the least within `window_s` on each side and within `near_m` (or
/// 0.6 of the step to its neighbours, for a fast ball) of the contact distance, where the
/// distance falls before it and rises after it, each trend a least-squares line over the
/// window, significant at `z` standard errors of the tracker's noise (estimated from the
/// track's second differences), so a resting or sliding-along ball seen through noise is not
/// a bounce. Where the tracker lost the ball at the cushion (frames dropped beside the
/// sample), the lines through the three samples on either side of the gap meeting within
/// `near_m` of the contact distance, inside the gap, stand for the sample's nearness.
std::vector<Rail> TrackedRails(const TableModel& model, const Recording& recording, int ball,
                               double near_m = 0.03, double window_s = 0.3, double z = 4.0);

/// The rails ball `ball` meets in a simulated shot's events, in order: each of its cushion
/// events as the rail nearest where it happened.
std::vector<Rail> SimulatedRails(const TableSpec& spec, std::span<const Event> events, int ball);

/// A stretch of a tracked ball's path between two contacts (a strike, a ball, a cushion),
/// read from the track alone, with no model of the table: on cloth a ball slides at a constant
/// acceleration (mu_slide g against its slip, whose direction holds while it slides) until
/// its slip vanishes, then rolls, slowing at mu_roll g along its path. Both coordinates are
/// fitted as that motion (position and velocity continuous where the roll begins, the time it
/// begins chosen for the least residual), over a window grown point by point while the
/// residuals stay within the tracker's noise (the whole window's within a chi-square bound at
/// 5 standard deviations, its newest five points' within their own): a contact's jump in
/// velocity ends it.
struct TrackedStretch {
  int ball = 0;
  double t0_s = 0.0, t1_s = 0.0;  ///< its first and last tracked points
  int points = 0;
  /// When the roll begins: t0_s when it rolls throughout, past t1_s when it slides throughout.
  double roll_from_s = 0.0;
  int slide_points = 0;        ///< points before the roll
  double v0_mps = 0.0;         ///< the fitted speed at t0_s
  double v_roll_mps = 0.0;     ///< ... where the roll begins (or at t1_s)
  double v1_mps = 0.0;         ///< ... at t1_s
  double slide_mps2 = 0.0;     ///< the slide's acceleration (its magnitude)
  double roll_decel_mps2 = 0.0;    ///< the roll's acceleration against the motion
  double roll_lateral_mps2 = 0.0;  ///< ... and across it (signed, left of it positive)
  /// The standard errors of the slide's acceleration and the roll's deceleration at the
  /// tracker's noise (all nine coefficients fitted, when the roll begins among them).
  double slide_se_mps2 = 0.0, roll_se_mps2 = 0.0;
  /// The slide is read when it lasts 0.1 s and 6 points or more, its acceleration between
  /// kSlidingMinAccel and kSlidingMaxAccel (sliding friction 0.08-0.6); the roll when it
  /// lasts 0.4 s and 10 points or more, its acceleration at most kRollingMaxAccel (no cloth's
  /// rolling resistance comes near; a slide's friction is ten times as much), slowing, and
  /// moving (0.05 m/s or faster) where it begins.
  bool slide_read = false, roll_read = false;
};
inline constexpr double kRollingMaxAccel = 0.5;
inline constexpr double kSlidingMinAccel = 0.8;
inline constexpr double kSlidingMaxAccel = 6.0;

/// The stretches of ball `ball`'s track in a recording, in time order (empty for a ball
/// index out of range or too few tracked points). The tracker's noise is estimated from the
/// track: each point's distance from the line through its two neighbours, in time, which
/// holds for the uneven steps trackers give (many log a ball only when it has moved).
std::vector<TrackedStretch> TrackedStretches(const Recording& recording, int ball);

/// What a set of recordings says of their cloth (ClothReading, above).
ClothReading ReadCloth(std::span<const Recording> recordings, double gravity_mps2 = 9.81);

/// A synthetic recording: `strike` played on `initial` under `model` at strike_time_s on the
/// tracker's clock, every ball on the table tracked at `rate_hz` (at t = k / rate_hz, k >= 1)
/// until all rest after the strike (at most max_s), each coordinate with Gaussian noise of
/// sigma noise_m (seeded; 0: exact). The strike is kept in the recording only when
/// keep_strike, its time when keep_strike or keep_strike_time. A fraction
/// false_detections of the points (drawn with their own generator from the seed, so that the
/// noise stays the same) are a tracker's false detections: somewhere on the playing area,
/// uniformly, instead of where the ball is.
struct SyntheticOptions {
  double rate_hz = 50.0;
  double noise_m = 0.0;
  uint64_t seed = 1;
  double max_s = 60.0;
  bool keep_strike = false;
  double strike_time_s = 0.0;
  bool keep_strike_time = true;
  double false_detections = 0.0;
};
absl::StatusOr<Recording> SyntheticRecording(const TableModel& model, const SolverOptions& solver,
                                             const TableState& initial, int cue,
                                             const CueStrike& strike,
                                             const SyntheticOptions& options = {});

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_CALIBRATE_H_
