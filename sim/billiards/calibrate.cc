#include "sim/billiards/calibrate.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <utility>

#include "Eigen/Cholesky"
#include "Eigen/Eigenvalues"
#include "Eigen/LU"
#include "Eigen/QR"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "sim/billiards/shot.h"
#include "unsupported/Eigen/LevenbergMarquardt"

namespace sportsim::billiards {
namespace {

using Eigen::VectorXd;

// A parameter's unbounded coordinate u and its value lo + (hi - lo) / (1 + exp(-u)).
double FromU(double u, double lo, double hi) { return lo + (hi - lo) / (1.0 + std::exp(-u)); }
double ToU(double p, double lo, double hi) {
  const double f = std::clamp((p - lo) / (hi - lo), 1e-6, 1.0 - 1e-6);
  return std::log(f / (1.0 - f));
}

// Forward-difference step in the unbounded coordinates. The engine's positions are smooth in
// its inputs between changes of its event sequence, and rounding leaves them good to ~1e-15
// m, so a small step costs little accuracy.
constexpr double kDiffStep = 1e-6;
// The table's parameters change every ball's path at once, and small kinks (a graze that
// turns into a contact, a ball stopping just before or after it is hit) make the score rough
// in them at the scale of 1e-4 of their coordinate: their differences take a step larger than
// that roughness, so that the Jacobian follows the trend a fit's steps see.
constexpr double kParamDiffStep = 1e-3;
// LM iterations of a strike's refit to new table parameters (from its fit to the last ones).
constexpr int kRefitIterations = 10;
// Passes of the calibration's fit (LM on the parameters, then fresh strike fits).
constexpr int kPasses = 4;
// The parameters' first window (s after each strike; then doubled until the whole shot) and
// the LM iterations of each window before the whole shot's (at most max_iterations).
constexpr double kFirstParamWindow = 1.0;
constexpr int kWindowIterations = 10;
// An early window's pull of the parameters' coordinates toward their start (as kTipPrior's
// on a strike's tip offsets): a unit of a coordinate weighs as a millimetre of every point's
// error in one shot. What a short window barely sees (the spin-down in a shot's first second)
// stays where it was; what it sees moves.
constexpr double kParamPrior = 1e-3;
// The residual of every point of a shot whose simulation failed (m): large, so that the fit
// steps back from where the engine refuses or runs away.
constexpr double kFailedResidual = 10.0;

// Median of a list (0 when empty).
double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The tracker's noise: second differences of a ball's tracked positions are mostly noise (its
// acceleration moves them by a millimetre at most, and only while it slides), so their median
// absolute value, over sqrt(6) and the normal distribution's 0.6745, estimates the noise of a
// coordinate. SecondDifferences appends a track's |second differences| (both coordinates);
// NoiseOf estimates the noise from them (at least 10 um).
void SecondDifferences(std::span<const Eigen::Vector2d> p, std::vector<double>* out) {
  for (size_t j = 1; j + 1 < p.size(); ++j) {
    const Eigen::Vector2d dd = p[j + 1] - 2 * p[j] + p[j - 1];
    out->push_back(std::abs(dd.x()));
    out->push_back(std::abs(dd.y()));
  }
}
double NoiseOf(std::vector<double> d2) {
  return std::max(1e-5, Median(std::move(d2)) / (0.6745 * std::sqrt(6.0)));
}
// A recording's noise, from every ball's track.
double RecordingNoise(const Recording& rec) {
  std::vector<std::vector<Eigen::Vector2d>> tracks(rec.initial.balls.size());
  for (const TrackPoint& q : rec.track) tracks[static_cast<size_t>(q.ball)].push_back(q.xy);
  std::vector<double> d2;
  for (const auto& t : tracks) SecondDifferences(t, &d2);
  return NoiseOf(std::move(d2));
}

// The number of a recording's tracked points with t_s <= until_s (the track is in order).
int PointsUntil(const Recording& rec, double until_s) {
  return static_cast<int>(std::upper_bound(rec.track.begin(), rec.track.end(), until_s,
                                           [](double t, const TrackPoint& p) { return t < p.t_s; }) -
                          rec.track.begin());
}

// A strike and when it happened on the track's clock.
struct TimedStrike {
  CueStrike strike;
  double time_s = 0.0;
};

// Plays `strike` on the recording's table and writes the first `n` points' residuals (the
// simulated centre minus the tracked position, times `weight`) into out[0 .. 2n). Before the
// strike's time every ball is where it stood.
absl::Status ShotResiduals(const TableModel& model, const SolverOptions& solver,
                           const Recording& rec, const TimedStrike& timed, int n, double weight,
                           double* out) {
  const CueStrike& strike = timed.strike;
  int i = 0;
  for (; i < n && rec.track[static_cast<size_t>(i)].t_s < timed.time_s; ++i) {
    const TrackPoint& p = rec.track[static_cast<size_t>(i)];
    const Eigen::Vector3d& r = rec.initial.balls[static_cast<size_t>(p.ball)].r;
    out[2 * i] = weight * (r.x() - p.xy.x());
    out[2 * i + 1] = weight * (r.y() - p.xy.y());
  }
  TableState state = rec.initial;
  absl::StatusOr<StrikeOutcome> struck = ApplyStrike(model, solver.effects, strike, rec.cue, &state);
  if (!struck.ok()) return struck.status();
  std::vector<Event> events;
  absl::StatusOr<std::unique_ptr<TableSimulation>> sim =
      TableSimulation::Create(model, solver, std::move(state), &events);
  if (!sim.ok()) return sim.status();
  for (; i < n; ++i) {
    const TrackPoint& p = rec.track[static_cast<size_t>(i)];
    const double t = p.t_s - timed.time_s;
    if (t > (*sim)->time()) {
      events.clear();
      if (absl::Status s = (*sim)->AdvanceTo(t, &events); !s.ok()) return s;
    }
    const Eigen::Vector3d& r = (*sim)->state().balls[static_cast<size_t>(p.ball)].r;
    out[2 * i] = weight * (r.x() - p.xy.x());
    out[2 * i + 1] = weight * (r.y() - p.xy.y());
  }
  return absl::OkStatus();
}

ShotError ErrorOf(const double* residuals, int n) {
  ShotError e;
  e.points = n;
  double sum = 0.0, sum2 = 0.0;
  for (int i = 0; i < n; ++i) {
    const double d2 = residuals[2 * i] * residuals[2 * i] + residuals[2 * i + 1] * residuals[2 * i + 1];
    const double d = std::sqrt(d2);
    sum += d;
    sum2 += d2;
    e.max_m = std::max(e.max_m, d);
  }
  if (n > 0) {
    e.mean_m = sum / n;
    e.rms_m = std::sqrt(sum2 / n);
  }
  return e;
}

// The budget and the cancellation, shared by every simulation of a calibration.
class Budget {
 public:
  Budget(int64_t max_simulations, const std::function<bool()>* cancelled)
      : max_(max_simulations), cancelled_(cancelled) {}
  // One more simulation, or why not.
  absl::Status Take() {
    if (cancelled_ != nullptr && *cancelled_ && (*cancelled_)()) {
      return absl::CancelledError("the calibration was cancelled");
    }
    if (++used_ > max_) {
      return absl::ResourceExhaustedError(
          absl::StrFormat("max_simulations: the calibration needs more than %d simulations", max_));
    }
    if (used_ > share_) {
      over_share_ = true;
      return absl::ResourceExhaustedError("max_simulations: past the share of it given");
    }
    return absl::OkStatus();
  }
  int64_t used() const { return used_; }
  // A part of the work that may stop short (the second start) runs with a share of the budget:
  // Take fails past `until` simulations in all, and over_share says so.
  void Share(int64_t until) {
    share_ = until;
    over_share_ = false;
  }
  void Unshare() { share_ = std::numeric_limits<int64_t>::max(); }
  bool over_share() const { return over_share_; }

 private:
  int64_t max_;
  int64_t used_ = 0;
  int64_t share_ = std::numeric_limits<int64_t>::max();
  bool over_share_ = false;
  const std::function<bool()>* cancelled_;
};

// When a recording's strike happened on its track's clock: known, or fitted within
// [lo, hi] from t0. The bounds and the start are read from the cue ball's track alone (no
// model): the strike comes before the cue ball's departure from its spot (Departure: a point a
// centimetre away and the next farther along the same line; a single point away is a
// tracker's false detection, not the strike), and after the point before the last one still
// on the spot (not the last itself: a ball struck just before it is still within the
// tracker's noise of its spot there); the departure's two points, extrapolated back to the
// spot at their speed, say when.
struct StrikeClock {
  bool fitted = false;
  double lo = 0.0, hi = 0.0, t0 = 0.0;
  double frame_s = 0.0;  // the tracker's interval between the cue ball's first points away
  // This clock narrowed to a tenth of a frame on either side of t (where the first motion put
  // the strike), within its bounds: where a fit over the whole shot may move the time. Over
  // the whole shot the time is barely seen (a few points of the first motion among
  // thousands) and trades against the speed and the spin: left free it drifts by many
  // milliseconds for a hair's better score, with the strike wrong.
  StrikeClock Around(double t) const {
    if (!fitted) return *this;
    StrikeClock c = *this;
    const double w = 0.1 * frame_s;
    c.lo = std::max(lo, t - w);
    c.hi = std::min(hi, t + w);
    c.t0 = std::clamp(t, c.lo, c.hi);
    c.fitted = c.hi - c.lo > 1e-9;
    return c;
  }
};
// A cue ball point this close to its spot is taken as still there (a tracker's noise).
constexpr double kOnSpot = 0.003;

// The struck ball's tracked points, in order.
std::vector<const TrackPoint*> CuePoints(const Recording& rec) {
  std::vector<const TrackPoint*> out;
  for (const TrackPoint& p : rec.track) {
    if (p.ball == rec.cue) out.push_back(&p);
  }
  return out;
}

// The struck ball's departure from `spot` among its points `cue` after time `after`: the
// departure's first point and the next (Departs). With no departure (a track that ends one
// point into the motion, or one whose points never line up) its first point a centimetre away
// and no next; neither when it never leaves.
std::pair<const TrackPoint*, const TrackPoint*> Departure(const std::vector<const TrackPoint*>& cue,
                                                          const Eigen::Vector2d& spot, double after) {
  const TrackPoint* away = nullptr;
  for (size_t k = 0; k < cue.size(); ++k) {
    if (cue[k]->t_s <= after) continue;
    if (k + 1 < cue.size() && Departs(spot, *cue[k], *cue[k + 1])) return {cue[k], cue[k + 1]};
    if (away == nullptr && (cue[k]->xy - spot).norm() >= kStruckDistance) away = cue[k];
  }
  return {away, nullptr};
}

StrikeClock ClockOf(const TableModel& model, const Recording& rec) {
  StrikeClock c;
  if (rec.strike_time_s) {
    c.t0 = c.lo = c.hi = *rec.strike_time_s;
    return c;
  }
  const Eigen::Vector2d spot = rec.initial.balls[static_cast<size_t>(rec.cue)].r.head<2>();
  const std::vector<const TrackPoint*> cue = CuePoints(rec);
  const auto [first, second] = Departure(cue, spot, -1.0);
  if (first == nullptr) return c;  // never struck: FitStrike says so
  double previous = 0.0;  // the cue ball's last point's time
  for (const TrackPoint* p : cue) {
    if (p == first) break;
    if ((p->xy - spot).norm() <= kOnSpot) c.lo = previous;
    previous = p->t_s;
  }
  c.hi = first->t_s;
  c.fitted = c.hi - c.lo > 1e-9;  // else it is known to be there
  c.t0 = 0.5 * (c.lo + c.hi);
  if (second != nullptr && second->t_s > first->t_s) {
    // The speed at the first point: the mean speed to the second, with the sliding friction's
    // loss over half the interval added back.
    const double dt = second->t_s - first->t_s;
    c.frame_s = dt;
    const double v = (second->xy - first->xy).norm() / dt +
                     0.5 * model.params().mu_slide * model.params().gravity_mps2 * dt;
    if (v > 0.0) c.t0 = first->t_s - (first->xy - spot).norm() / v;
  }
  // Inside the interval, off its ends (where the fit's map is flat).
  const double margin = 0.02 * (c.hi - c.lo);
  c.t0 = std::clamp(c.t0, c.lo + margin, c.hi - margin);
  return c;
}

// A strike's unbounded coordinates: the cue ball's speed (logistic onto its bounds), its
// heading, the two tip offsets, (when fitted) the elevation and (when fitted) the strike's
// time. An offset is the limit times the sine of its coordinate, and the time the clock's
// interval's middle plus its half-width times a sine (periodic: a fit never stalls against a
// bound, as it can on a logistic map's flat tails); a pair of offsets outside the miscue
// circle is scaled back onto it.
struct StrikeMap {
  StrikeBounds bounds;
  double offset_limit = 0.5;  // just inside the miscue limit
  StrikeClock clock;

  int size() const { return (bounds.fit_elevation ? 5 : 4) + (clock.fitted ? 1 : 0); }
  double max_theta() const { return bounds.max_elevation_deg * std::numbers::pi / 180.0; }
  TimedStrike ToTimed(const double* u) const {
    TimedStrike t{ToStrike(u), clock.t0};
    if (clock.fitted) t.time_s = mid() + half() * std::sin(u[size() - 1]);
    return t;
  }
  // This map with the strike's time held at t.
  StrikeMap HeldAt(double t) const {
    StrikeMap m = *this;
    m.clock = StrikeClock{.fitted = false, .lo = t, .hi = t, .t0 = t};
    return m;
  }
  void FromTimed(const TimedStrike& t, double* u) const {
    FromStrike(t.strike, u);
    if (clock.fitted) u[size() - 1] = std::asin(std::clamp((t.time_s - mid()) / half(), -1.0, 1.0));
  }

 private:
  double mid() const { return 0.5 * (clock.lo + clock.hi); }
  double half() const { return 0.5 * (clock.hi - clock.lo); }
  CueStrike ToStrike(const double* u) const {
    CueStrike s;
    s.ball_speed = true;
    s.speed_mps = FromU(u[0], bounds.min_speed_mps, bounds.max_speed_mps);
    s.phi_rad = u[1];
    s.a = offset_limit * std::sin(u[2]);
    s.b = offset_limit * std::sin(u[3]);
    const double r = std::hypot(s.a, s.b);
    if (r > offset_limit) {
      s.a *= offset_limit / r;
      s.b *= offset_limit / r;
    }
    if (bounds.fit_elevation) s.theta_rad = max_theta() * 0.5 * (1.0 - std::cos(u[4]));
    return s;
  }
  void FromStrike(const CueStrike& s, double* u) const {
    u[0] = ToU(s.speed_mps, bounds.min_speed_mps, bounds.max_speed_mps);
    u[1] = s.phi_rad;
    u[2] = std::asin(std::clamp(s.a / offset_limit, -1.0, 1.0));
    u[3] = std::asin(std::clamp(s.b / offset_limit, -1.0, 1.0));
    if (bounds.fit_elevation) {
      u[4] = std::acos(std::clamp(1.0 - 2.0 * std::max(s.theta_rad, 1e-3) / max_theta(), -1.0, 1.0));
    }
  }
};

// The cue ball's first tracked motion: its heading from where it stood to the first point a
// centimetre away, and its mean speed since the strike (at the clock's start) with the
// sliding friction's loss added back. nullopt when the cue ball's track never leaves its spot.
std::optional<std::pair<double, double>> FirstMotion(const TableModel& model, const Recording& rec,
                                                     const StrikeClock& clock) {
  const Eigen::Vector2d start = rec.initial.balls[static_cast<size_t>(rec.cue)].r.head<2>();
  const TrackPoint* first = Departure(CuePoints(rec), start, clock.t0).first;
  if (first == nullptr) return std::nullopt;
  const double dt = first->t_s - clock.t0;
  const Eigen::Vector2d d = first->xy - start;
  const double speed = d.norm() / dt + 0.5 * model.params().mu_slide * model.params().gravity_mps2 * dt;
  return std::make_pair(std::atan2(d.y(), d.x()), speed);
}

// Levenberg-Marquardt over a residual function of the unbounded coordinates, with its Jacobian
// by forward differences (or a block-structured one given by the caller).
struct LmFunctor : Eigen::DenseFunctor<double> {
  LmFunctor(int inputs, int values) : Eigen::DenseFunctor<double>(inputs, values) {}
  std::function<absl::Status(const VectorXd&, VectorXd*)> residuals;
  std::function<absl::Status(const VectorXd&, const VectorXd&, Eigen::MatrixXd*)> jacobian;
  absl::Status status;
  VectorXd last_x, last_f;

  int operator()(const VectorXd& x, VectorXd& f) {
    status = residuals(x, &f);
    if (!status.ok()) return -1;
    last_x = x;
    last_f = f;
    return 0;
  }
  int df(const VectorXd& x, Eigen::MatrixXd& j) {
    VectorXd f0;
    if (last_x.size() == x.size() && last_x == x) {
      f0 = last_f;
    } else {
      f0.resize(values());
      if (status = residuals(x, &f0); !status.ok()) return -1;
    }
    status = jacobian(x, f0, &j);
    return status.ok() ? 0 : -1;
  }
};

// Runs LM from x; returns the iterations done. Stops on the functor's error (returned).
absl::StatusOr<int> Minimize(LmFunctor& functor, VectorXd* x, int max_iterations) {
  Eigen::LevenbergMarquardt<LmFunctor> lm(functor);
  lm.setMaxfev(std::max(1, max_iterations) * 4);
  lm.setXtol(1e-10);
  lm.setFtol(1e-10);
  Eigen::LevenbergMarquardtSpace::Status s = lm.minimizeInit(*x);
  if (s == Eigen::LevenbergMarquardtSpace::ImproperInputParameters) {
    return absl::InvalidArgumentError("too few tracked points for the parameters fitted");
  }
  int iterations = 0;
  while (s == Eigen::LevenbergMarquardtSpace::NotStarted || s == Eigen::LevenbergMarquardtSpace::Running) {
    if (iterations >= max_iterations) break;
    s = lm.minimizeOneStep(*x);
    ++iterations;
  }
  if (s == Eigen::LevenbergMarquardtSpace::UserAsked && !functor.status.ok()) return functor.status;
  // minimizeOneStep leaves x at the best point it accepted.
  return iterations;
}

// A shot's fit context: the residual count and weight of the points it is fitted on, and the
// fit's Huber scale (0: squared distances).
struct ShotPoints {
  int n = 0;
  double weight = 0.0;
  double huber_m = 0.0;
};
ShotPoints PointsOf(const Recording& rec, double until_s, double huber_m) {
  ShotPoints p;
  p.n = PointsUntil(rec, until_s);
  p.weight = p.n > 0 ? 1.0 / std::sqrt(static_cast<double>(p.n)) : 0.0;
  p.huber_m = huber_m;
  return p;
}

// Residuals scaled so that their squares sum to Huber's loss: a point's pair (its distance d,
// unweighted) keeps its direction and takes the length sqrt(2 h d - h^2) beyond the scale h.
// A least-squares fit of these minimises the loss (Levenberg-Marquardt's Gauss-Newton model of
// it is the square-root one, which holds up for Huber's loss: it is convex and its root is
// smooth but at h, where it is continuous with its slope).
void Robust(const ShotPoints& pts, double* r) {
  if (pts.huber_m <= 0.0) return;
  const double h = pts.huber_m;
  for (int i = 0; i < pts.n; ++i) {
    const double d = std::hypot(r[2 * i], r[2 * i + 1]) / pts.weight;
    if (d <= h) continue;
    const double scale = std::sqrt(2.0 * h * d - h * h) / d;
    r[2 * i] *= scale;
    r[2 * i + 1] *= scale;
  }
}

// Residuals of one shot under the fit's loss, with a failed simulation's large ones in place of
// an error (budget and cancellation errors pass through).
absl::Status Simulate(const TableModel& model, const SolverOptions& solver, const Recording& rec,
                      const TimedStrike& strike, const ShotPoints& pts, Budget* budget, double* out) {
  if (absl::Status s = budget->Take(); !s.ok()) return s;
  if (!ShotResiduals(model, solver, rec, strike, pts.n, pts.weight, out).ok()) {
    std::fill(out, out + 2 * pts.n, kFailedResidual * pts.weight);
  }
  Robust(pts, out);
  return absl::OkStatus();
}

// A shot's loss under the fit (the sum of its squared residuals) and its plain score, from one
// simulation.
struct Scored {
  double loss = 0.0;
  ShotError error;
};
absl::StatusOr<Scored> ScoreOn(const TableModel& model, const SolverOptions& solver,
                               const Recording& rec, const TimedStrike& strike,
                               const ShotPoints& pts, Budget* budget) {
  // The distances unweighted, so that the score is ScoreShot's to the bit; the loss weighted
  // as the fit's residuals are (weight times distance, the same product).
  ShotPoints plain = pts;
  plain.huber_m = 0.0;
  plain.weight = 1.0;
  VectorXd r(2 * pts.n);
  if (absl::Status s = Simulate(model, solver, rec, strike, plain, budget, r.data()); !s.ok()) {
    return s;
  }
  Scored out;
  out.error = ErrorOf(r.data(), pts.n);
  VectorXd robust = pts.weight * r;
  Robust(pts, robust.data());
  out.loss = robust.squaredNorm();
  return out;
}

// The windows a strike is fitted over in turn, as times on the track's clock: the first
// 0.25 s after the strike, doubled until the whole window (until_s after the strike). A
// shot's collisions make the score rugged in the strike (a slightly other heading misses a
// ball): fitted on its first motion only, before the first collisions, the strike is close
// enough that each longer window's fit starts in the right basin.
std::vector<double> Windows(const Recording& rec, const StrikeClock& clock, double until_s) {
  const double end = std::min(until_s, rec.track.back().t_s - clock.t0);
  std::vector<double> w;
  for (double t = 0.25; t < end; t *= 2.0) w.push_back(clock.t0 + t);
  w.push_back(clock.t0 + until_s);
  return w;
}

// LM over a strike's coordinates u on a recording's points up to `window`. With a prior (the
// early windows of FitStrike) a weak pull toward its tip offsets (kTipPrior: a unit of the
// offsets' coordinates weighs as a millimetre of error) keeps them from wandering along the
// directions the data leaves flat: the spin barely shows before the cushions.
constexpr double kTipPrior = 1e-3;
constexpr int kStrikeIterations = 30;  // LM iterations of a strike's fit on one window
// A strike's residuals on a recording's points up to a window: the points' (under the fit's
// loss), then, with a prior, the tip offsets' pull toward it.
struct StrikeResiduals {
  const TableModel& model;
  const SolverOptions& solver;
  const Recording& rec;
  const StrikeMap& map;
  ShotPoints pts;
  const VectorXd* prior;
  Budget* budget;
  // The prior's weight on the side offset's coordinate and on the height's.
  std::array<double, 2> prior_weight = {kTipPrior, kTipPrior};

  int size() const { return 2 * pts.n + (prior != nullptr ? 2 : 0); }
  absl::Status operator()(const VectorXd& x, double* r) const {
    if (absl::Status s = Simulate(model, solver, rec, map.ToTimed(x.data()), pts, budget, r); !s.ok()) {
      return s;
    }
    if (prior != nullptr) {
      r[2 * pts.n] = prior_weight[0] * (x[2] - (*prior)[2]);
      r[2 * pts.n + 1] = prior_weight[1] * (x[3] - (*prior)[3]);
    }
    return absl::OkStatus();
  }
  // Forward differences at x, whose residuals are r0.
  absl::Status Jacobian(const VectorXd& x, const VectorXd& r0, Eigen::MatrixXd* j) const {
    VectorXd xp = x, r(r0.size());
    j->resize(r0.size(), x.size());
    for (int c = 0; c < x.size(); ++c) {
      xp[c] = x[c] + kDiffStep;
      if (absl::Status s = (*this)(xp, r.data()); !s.ok()) return s;
      j->col(c) = (r - r0) / kDiffStep;
      xp[c] = x[c];
    }
    return absl::OkStatus();
  }
};

absl::Status RefineStrike(const TableModel& model, const SolverOptions& solver, const Recording& rec,
                          const StrikeMap& map, double window, double huber_m, const VectorXd* prior,
                          int iterations, Budget* budget, VectorXd* u,
                          std::array<double, 2> prior_weight = {kTipPrior, kTipPrior}) {
  const int k = map.size();
  const StrikeResiduals residuals{model, solver, rec, map, PointsOf(rec, window, huber_m),
                                  prior, budget, prior_weight};
  if (2 * residuals.pts.n < k) return absl::OkStatus();  // too early to say anything: keep the start
  LmFunctor f(k, residuals.size());
  f.residuals = [&](const VectorXd& x, VectorXd* r) { return residuals(x, r->data()); };
  f.jacobian = [&](const VectorXd& x, const VectorXd& r0, Eigen::MatrixXd* j) {
    return residuals.Jacobian(x, r0, j);
  };
  return Minimize(f, u, iterations).status();
}

// One of FitStrike's strikes as it is carried from window to window: its coordinates, its
// map (the strike's time held after the first window), the start whose tip offsets its prior
// pulls toward, and Resample's sort key: its loss on the window Resample last scored it on
// (the window fitted, then the next one).
struct Candidate {
  VectorXd u;
  StrikeMap map;
  VectorXd start;
  double loss = std::numeric_limits<double>::infinity();
};

// Between two of FitStrike's windows, `window` fitted and `next` to come: which strikes the
// next window's fit starts from. The window so far determines a strike only to a spread (the
// side spin and the heading trade against each other until the first collision or cushion,
// the spin's height until the cloth has turned it), and the next window's basin may be a
// narrow part of it, away from where the noise put the fit (a heading a hair off misses a
// ball a metre on). So:
//  - the strikes whose fit to this window is worse than the best by more than kPruneChi2
//    times the residuals' variance (a chi-square difference, the variance read off the best
//    fit) are dropped: the data so far already rules them out. The best kMinParents stay
//    whatever they score: the best on a window may still be the wrong one on the next, and
//    with a single line left the fit has nowhere else to go;
//  - strikes are drawn around the kept ones in turn, twice the population's size (kDraws),
//    each from the Gaussian its fit leaves (the residuals' variance times the inverse normal
//    matrix, with the tip prior; along a direction the window leaves flat, within a unit of
//    the coordinates);
//  - of the kept and the drawn, as many as the population holds go on, those with the least
//    loss on the next window: the ones whose fit there starts nearest.
// Draws are seeded: the same recording gives the same fit. StrikeBounds::resample; off by
// default. Measured with billiards_calibration_study --strike-recovery (docs/billiards.md,
// "Resampled starts"): fitting random three-cushion shots under their own table, it misses
// (more than 5 % above the true strike's error) none of 120 against 2 with each start alone,
// for 9-15 % fewer simulations (11 against 14, and 15 against 30, under the earlier, rougher
// integrations of the Mathavan cushion, which the starts carried alone suffered from most).
// Under a wrong model, which every real table's is somewhere, it is no better on the whole
// shot, and its draws along what the early windows leave flat (the spin) make predictions
// from a shot's first 0.4 s worse.
constexpr double kPruneChi2 = 25.0;
constexpr size_t kDraws = 2;
constexpr size_t kMinParents = 5;
absl::Status Resample(const TableModel& model, const SolverOptions& solver, const Recording& rec,
                      double window, double next, double huber_m, int index, Budget* budget,
                      std::vector<Candidate>* pop) {
  const ShotPoints pts = PointsOf(rec, window, huber_m);
  const ShotPoints ahead = PointsOf(rec, next, huber_m);
  const int k = pop->front().map.size();
  if (2 * pts.n <= k + 2) return absl::OkStatus();  // nothing fitted yet
  const size_t size = pop->size();
  for (Candidate& c : *pop) {
    absl::StatusOr<Scored> scored = ScoreOn(model, solver, rec, c.map.ToTimed(c.u.data()), pts, budget);
    if (!scored.ok()) return scored.status();
    c.loss = scored->loss;
  }
  // Best first; ties in their start's order (stable), so the outcome does not hang on the sort.
  auto by_loss = [](const Candidate& x, const Candidate& y) { return x.loss < y.loss; };
  std::stable_sort(pop->begin(), pop->end(), by_loss);
  const double variance = pop->front().loss / (2 * pts.n - k);
  size_t kept = 0;
  while (kept < size && (*pop)[kept].loss <= pop->front().loss + kPruneChi2 * variance) ++kept;
  kept = std::max(kept, std::min(size, kMinParents));
  pop->resize(kept);
  std::mt19937_64 rng(0x5eedf17u + static_cast<uint64_t>(index));
  std::normal_distribution<double> normal;
  std::vector<Eigen::MatrixXd> spread(kept);  // each kept strike's draw: u + spread z
  for (size_t p = 0; p < kept; ++p) {
    const Candidate& parent = (*pop)[p];
    const StrikeResiduals residuals{model, solver, rec, parent.map, pts, &parent.start, budget};
    VectorXd r0(residuals.size());
    if (absl::Status s = residuals(parent.u, r0.data()); !s.ok()) return s;
    Eigen::MatrixXd j;
    if (absl::Status s = residuals.Jacobian(parent.u, r0, &j); !s.ok()) return s;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(j.transpose() * j);
    VectorXd sd(k);
    for (int i = 0; i < k; ++i) {
      const double lambda = eig.eigenvalues()[i];
      sd[i] = lambda > 0.0 ? std::min(1.0, std::sqrt(variance / lambda)) : 1.0;
    }
    spread[p] = eig.eigenvectors() * sd.asDiagonal();
  }
  for (size_t d = 0; d < kDraws * size; ++d) {
    const size_t p = d % kept;
    VectorXd z(k);
    for (int c = 0; c < k; ++c) z[c] = normal(rng);
    Candidate child = (*pop)[p];
    child.u += spread[p] * z;
    pop->push_back(std::move(child));
  }
  for (Candidate& c : *pop) {
    absl::StatusOr<Scored> scored = ScoreOn(model, solver, rec, c.map.ToTimed(c.u.data()), ahead, budget);
    if (!scored.ok()) return scored.status();
    c.loss = scored->loss;
  }
  std::stable_sort(pop->begin(), pop->end(), by_loss);
  if (pop->size() > size) pop->resize(size);
  return absl::OkStatus();
}

// A strike's whole shot, simulated to rest: whether it meets an intent (StrikeBounds::intent)
// and where the struck ball rests. A strike the engine refuses meets none and rests nowhere.
struct PlayedOut {
  bool met = false;
  bool rested = false;
  Eigen::Vector2d rest = Eigen::Vector2d::Zero();
};
absl::StatusOr<PlayedOut> PlayOut(const TableModel& model, const SolverOptions& solver,
                                  const Recording& rec, const CueStrike& strike,
                                  const ShotIntent& intent, Budget* budget) {
  if (absl::Status s = budget->Take(); !s.ok()) return s;
  PlayedOut out;
  TableState state = rec.initial;
  if (!ApplyStrike(model, solver.effects, strike, rec.cue, &state).ok()) return out;
  absl::StatusOr<ShotResult> shot = SimulateShot(model, solver, state, ShotOptions{});
  if (!shot.ok()) return out;
  out.met = intent && intent(rec.initial, rec.cue, shot->events);
  out.rested = true;
  out.rest = shot->final_state.balls[static_cast<size_t>(rec.cue)].r.head<2>();
  return out;
}

// The strikes a prediction tries (StrikeBounds::central_rest, intent): tip offsets on a grid,
// as fractions of the miscue limit. Side offsets every kPlausibleSideStep within
// kPlausibleReach of the centre, each pinned there (kPlausiblePin, StrikeResiduals' prior
// weight: a thousandth of a unit of the offset's coordinate weighs as a centimetre of root
// mean square distance, ten thousand times kTipPrior's pull);
// heights every kPlausibleHeightStep as starts, pulled toward as the fit's early windows are
// (kTipPrior: where the window sees the height, they all come to it; where the slide outlasts
// it, they stay spread). The rest of each strike (speed, heading, elevation) is fitted to the
// window for up to kPlausibleIterations. Each row of the grid is walked out from its middle
// both ways, each strike starting from its neighbour's fit: the heading that trades against
// the side offset moves smoothly along it. Then each row is refined kPlausibleRefinements
// times where it is plausible: every gap of the row with a plausible strike at either end is
// halved, the new strike starting from the fit at that end with the lesser loss, so that the
// plausible strikes of a row end kPlausibleSideStep / 2^kPlausibleRefinements apart, and as
// far from the first implausible ones beside them; each weighs the same (the grid's prior is
// uniform) and the rows' implausible parts cost no more than before. A three-cushion point's
// band of side offsets is often narrower than the coarse step: under the synthetic shots' own
// table (billiards_calibration_study --predict-recovery --shots 40 --aimed --scoring), the
// median prediction with the point intended went from 383 mm at 0.05 to 266 at 0.025 and 251
// at 0.0125, the predictions that score from 34 to 37 of 40, while halving the heights' step as
// well moved it by a tenth of that (255 mm, at 0.025 and 0.075). Refined only where plausible
// it gives 325 mm (37 of 40; mean 400 mm) for 20,300 simulations a shot; the uniform 0.0125
// grid 251 mm (mean 384) for 34,400 (10,300 at 0.05). Refining also the gaps within a
// chi-square of 25 of the best changed nothing (325 mm, 22,400): the rest of the gap is in
// where the fits start (a walk along the row, or a neighbour's fit) and forty shots' chance.
constexpr double kPlausibleSideStep = 0.05;
constexpr double kPlausibleHeightStep = 0.15;
constexpr double kPlausibleReach = 0.7;
constexpr double kPlausiblePin = 10.0;
constexpr int kPlausibleIterations = 10;
constexpr int kPlausibleRefinements = 2;

// One of the strikes a prediction weighs.
struct Plausible {
  TimedStrike timed;
  double loss = 0.0;
  ShotError error;
  PlayedOut out;
  bool refined = false;  // off the coarse grid (WeighPlausible's refinement)
};

// A prediction from a shot's start (StrikeBounds::central_rest, intent), after the best fit
// `best` over the window (its loss `best_cost`, its strike's time held). The plausible strikes
// are the grid's whose loss over the window is within kPlausibleChi2 of the best's, and the
// best itself; each is played to rest. Under an intent, the grid is refined where plausible,
// and those that meet it are weighed (the coarse grid's, as with none, where none does). Each
// weighs as its likelihood against the best's, exp(-chi2 / 2).
// With central_rest the strike taken is their weighted medoid in where the struck ball rests:
// the one whose rest is nearest the others' on the weighted average, the choice among them
// that minimises the expected distance from the true rest, were the weights the posterior;
// else the one with the least loss.
absl::Status WeighPlausible(const TableModel& model, const SolverOptions& solver,
                           const Recording& rec, const StrikeBounds& bounds, const StrikeMap& map,
                           double window, const ShotPoints& all, double huber_m, Budget* budget,
                           double best_cost, StrikeFit* best) {
  const StrikeMap held = map.HeldAt(best->strike_time_s);
  const int k = held.size();
  const double variance = best_cost / std::max(1, 2 * all.n - k);
  const double limit = best_cost + kPlausibleChi2 * variance;
  std::vector<Plausible> plausible;
  {
    Plausible p{{best->strike, best->strike_time_s}, best_cost, best->error, {}};
    absl::StatusOr<PlayedOut> out = PlayOut(model, solver, rec, p.timed.strike, bounds.intent, budget);
    if (!out.ok()) return out.status();
    p.out = *out;
    plausible.push_back(std::move(p));
  }
  // The intent alone, met by the best fit: the prior agrees with the data, and the best fit
  // stands with nothing more to weigh.
  if (!bounds.central_rest && plausible.front().out.met) {
    best->plausible = 1;
    best->intent_met = true;
    return absl::OkStatus();
  }
  VectorXd base(k);
  held.FromTimed({best->strike, best->strike_time_s}, base.data());
  const double l = model.params().miscue_limit;
  // One strike of the grid, its tip at (a, b) fractions of the miscue limit, its fit starting
  // from `u` (left at the fit): plausible (and played out into `plausible`) or not.
  struct Node {
    VectorXd u;
    double loss = 0.0;
    bool plausible = false;
  };
  const auto fit_at = [&](double a, double b, VectorXd u, bool refined) -> absl::StatusOr<Node> {
    CueStrike tip = held.ToTimed(u.data()).strike;
    tip.a = a * l;
    tip.b = b * l;
    held.FromTimed({tip, best->strike_time_s}, u.data());
    const VectorXd pin = u;
    if (absl::Status s = RefineStrike(model, solver, rec, held, window, huber_m, &pin,
                                      kPlausibleIterations, budget, &u, {kPlausiblePin, kTipPrior});
        !s.ok()) {
      return s;
    }
    TimedStrike timed = held.ToTimed(u.data());
    timed.strike.phi_rad = std::remainder(timed.strike.phi_rad, 2.0 * std::numbers::pi);
    absl::StatusOr<Scored> scored = ScoreOn(model, solver, rec, timed, all, budget);
    if (!scored.ok()) return scored.status();
    Node node{std::move(u), scored->loss, false};
    if (!(scored->loss <= limit)) return node;
    absl::StatusOr<PlayedOut> out =
        PlayOut(model, solver, rec, timed.strike, bounds.intent, budget);
    if (!out.ok()) return out.status();
    node.plausible = true;
    if (out->rested) plausible.push_back({timed, scored->loss, scored->error, *out, refined});
    return node;
  };
  // Refined under an intent only: the central rest of all the plausible strikes is no better
  // on the whole from the refined rows (the same runs: 482 mm coarse against 528 refined, 284
  // against 284 on 40 random aimed shots, 549 against 489 with raised cues; the rests of
  // neighbouring strikes scatter as much as the grid's), at twice the simulations.
  const int fine = bounds.intent ? 1 << kPlausibleRefinements : 1;  // finest steps in a coarse one
  const double step = kPlausibleSideStep / fine;
  const int sides = static_cast<int>(std::lround(kPlausibleReach / kPlausibleSideStep));
  const int heights = static_cast<int>(std::floor(kPlausibleReach / kPlausibleHeightStep));
  for (int j = -heights; j <= heights; ++j) {
    const double b = j * kPlausibleHeightStep;
    std::map<int, Node> row;  // by side offset, in units of `step`
    for (const int dir : {1, -1}) {
      VectorXd u = base;
      for (int i = dir > 0 ? 0 : -1; std::abs(i) <= sides; i += dir) {
        const double a = i * kPlausibleSideStep;
        if (std::hypot(a, b) > kPlausibleReach + 1e-9) continue;
        absl::StatusOr<Node> node = fit_at(a, b, u, false);
        if (!node.ok()) return node.status();
        u = node->u;
        row.emplace(i * fine, *std::move(node));
      }
    }
    for (int gap = fine; gap > 1; gap /= 2) {
      std::vector<std::pair<int, const Node*>> halve;  // a midpoint and the fit it starts from
      for (auto it = row.begin(); it != row.end(); ++it) {
        const auto next = std::next(it);
        if (next == row.end() || next->first - it->first != gap) continue;
        if (!it->second.plausible && !next->second.plausible) continue;
        const Node& from = it->second.loss <= next->second.loss ? it->second : next->second;
        halve.emplace_back(it->first + gap / 2, &from);
      }
      for (const auto& [i, from] : halve) {  // in the row's order
        absl::StatusOr<Node> node = fit_at(i * step, b, from->u, true);
        if (!node.ok()) return node.status();
        row.emplace(i, *std::move(node));
      }
    }
  }
  const bool any_met = std::any_of(plausible.begin(), plausible.end(),
                                   [](const Plausible& p) { return p.out.met; });
  // Where no strike meets the intent, the refinement found nothing it was for: the coarse
  // grid's strikes are weighed, as with no intent (the same strike to the bit).
  std::vector<const Plausible*> pool;
  for (const Plausible& p : plausible) {
    if (p.out.rested && (any_met ? p.out.met : !p.refined)) pool.push_back(&p);
  }
  if (pool.empty()) return absl::OkStatus();  // no plausible strike rests: the best fit stands
  const auto chi2 = [&](const Plausible& p) {
    return variance > 0.0 ? std::max(0.0, (p.loss - best_cost) / variance) : 0.0;
  };
  const Plausible* chosen = nullptr;
  double least = std::numeric_limits<double>::infinity();
  for (const Plausible* p : pool) {  // in the grid's order: ties go to the earlier
    double sum = p->loss;
    if (bounds.central_rest) {
      sum = 0.0;
      for (const Plausible* q : pool) {
        sum += std::exp(-0.5 * chi2(*q)) * (p->out.rest - q->out.rest).norm();
      }
    }
    if (sum < least) {
      least = sum;
      chosen = p;
    }
  }
  best->strike = chosen->timed.strike;
  best->error = chosen->error;
  best->plausible = static_cast<int>(plausible.size());
  best->intent_met = chosen->out.met;
  best->window_chi2 = chi2(*chosen);
  return absl::OkStatus();
}

// FitStrike's work, on a budget. A final fit (FitStrike's; a calibration's reports) refines
// an unknown strike time, at the end, with the rest of the best start's strike over the whole
// window (the best fit under this table), and over a window that ends before the track weighs
// the plausible strikes where the bounds ask (a prediction: WeighPlausible). A calibration's
// passes are not final: the time stays where the first motion put it (it must not take up the
// table's errors), and their growing windows are no predictions. `loss`, when given, is set to
// the best fit's loss over the window (Simulate's residuals' sum of squares).
absl::StatusOr<StrikeFit> FitStrikeOn(const TableModel& model, const SolverOptions& solver,
                                      const Recording& rec, const StrikeBounds& bounds,
                                      double until_s, double huber_m, Budget* budget,
                                      bool final_fit, double* loss = nullptr) {
  StrikeFit best;
  const int64_t used0 = budget->used();
  const StrikeClock clock = ClockOf(model, rec);
  const ShotPoints all = PointsOf(rec, clock.t0 + until_s, huber_m);
  if (all.n == 0) return absl::InvalidArgumentError("track: no points in the fitted window");
  StrikeMap map{bounds, 0.999 * model.params().miscue_limit, clock};
  const int k = map.size();
  if (2 * all.n < k) return absl::InvalidArgumentError("track: too few points to fit the strike");
  const std::optional<std::pair<double, double>> motion = FirstMotion(model, rec, clock);
  if (!motion) {
    return absl::InvalidArgumentError("track: the cue ball's track never leaves its spot (1 cm)");
  }
  // Starts: the first motion's heading and speed with the tip on a grid of side offsets (the
  // side is hard to tell from the first motion: squirt and heading trade against each other
  // until the cushions show the spin) and of heights; each fitted over the growing windows.
  const double l = model.params().miscue_limit;
  std::vector<std::pair<double, double>> tips;
  for (double a : {0.0, 0.3 * l, -0.3 * l, 0.6 * l, -0.6 * l}) {
    for (double b : {0.0, 0.5 * l, -0.5 * l}) tips.emplace_back(a, b);
  }
  const std::vector<double> windows = Windows(rec, clock, until_s);
  double best_cost = std::numeric_limits<double>::infinity();
  // Scores a strike over the whole window and keeps it where it beats the best so far; its
  // heading in (-pi, pi] first, so that the error kept is the reported strike's to the bit.
  auto keep = [&](TimedStrike timed) -> absl::Status {
    timed.strike.phi_rad = std::remainder(timed.strike.phi_rad, 2.0 * std::numbers::pi);
    absl::StatusOr<Scored> scored = ScoreOn(model, solver, rec, timed, all, budget);
    if (!scored.ok()) return scored.status();
    if (scored->loss < best_cost) {
      best_cost = scored->loss;
      best.strike = timed.strike;
      best.strike_time_s = timed.time_s;
      best.error = scored->error;
    }
    return absl::OkStatus();
  };
  // An unknown strike time is fitted on the first window only, the cue ball's first motion,
  // and then held: over the whole shot it would also take up what the table's parameters get
  // wrong (a late strike for a slow cloth), which the calibration's fit must see.
  std::vector<Candidate> pop;
  for (const auto& [a, b] : tips) {
    CueStrike s0;
    s0.ball_speed = true;
    s0.speed_mps = std::clamp(motion->second, bounds.min_speed_mps * 1.01, bounds.max_speed_mps * 0.99);
    s0.phi_rad = motion->first;
    s0.a = a;
    s0.b = b;
    Candidate c{VectorXd(k), map, VectorXd()};
    map.FromTimed({s0, clock.t0}, c.u.data());
    c.start = c.u;
    pop.push_back(std::move(c));
  }
  for (size_t w = 0; w < windows.size(); ++w) {
    const bool last = w + 1 == windows.size();
    for (Candidate& c : pop) {
      if (absl::Status s = RefineStrike(model, solver, rec, c.map, windows[w], huber_m,
                                        last ? nullptr : &c.start, kStrikeIterations, budget, &c.u);
          !s.ok()) {
        return s;
      }
      if (c.map.clock.fitted) {
        c.map = map.HeldAt(c.map.ToTimed(c.u.data()).time_s);
        c.u.conservativeResize(c.map.size());  // the time was the last coordinate
      }
    }
    if (!last && bounds.resample) {
      if (absl::Status s = Resample(model, solver, rec, windows[w], windows[w + 1], huber_m,
                                    static_cast<int>(w), budget, &pop);
          !s.ok()) {
        return s;
      }
    }
  }
  for (const Candidate& c : pop) {
    if (absl::Status s = keep(c.map.ToTimed(c.u.data())); !s.ok()) return s;
  }
  StrikeMap polish = map;
  polish.clock = clock.Around(best.strike_time_s);
  if (final_fit && polish.clock.fitted) {
    VectorXd u(polish.size());
    polish.FromTimed({best.strike, best.strike_time_s}, u.data());
    if (absl::Status s = RefineStrike(model, solver, rec, polish, windows.back(), huber_m, nullptr,
                                      kStrikeIterations, budget, &u);
        !s.ok()) {
      return s;
    }
    // LM keeps the best point it saw: never worse but for rounding.
    if (absl::Status s = keep(polish.ToTimed(u.data())); !s.ok()) return s;
  }
  // A prediction from the shot's start: the plausible strikes weighed.
  if (final_fit && (bounds.intent || bounds.central_rest) &&
      clock.t0 + until_s < rec.track.back().t_s) {
    if (absl::Status s = WeighPlausible(model, solver, rec, bounds, map, clock.t0 + until_s, all,
                                       huber_m, budget, best_cost, &best);
        !s.ok()) {
      return s;
    }
  }
  if (loss != nullptr) *loss = best_cost;
  best.simulations = budget->used() - used0;
  return best;
}

absl::Status CheckOptions(const StrikeBounds& b) {
  if (!(b.min_speed_mps > 0.0) || !(b.max_speed_mps > b.min_speed_mps) ||
      !(b.max_speed_mps <= kMaxStrikeSpeed)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "strike_bounds: speeds must satisfy 0 < min < max <= %g m/s", kMaxStrikeSpeed));
  }
  if (b.fit_elevation && !(b.max_elevation_deg > 0.0 && b.max_elevation_deg <= kMaxElevationDeg)) {
    return absl::InvalidArgumentError("strike_bounds.max_elevation_deg must be in (0, 89]");
  }
  return absl::OkStatus();
}

absl::Status CheckHuber(double huber_m) {
  if (!(huber_m >= 0.0 && huber_m <= kMaxHuberScale)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "huber_m must be in [0, %g] m (0: squared distances), got %g", kMaxHuberScale, huber_m));
  }
  return absl::OkStatus();
}

}  // namespace

bool Departs(const Eigen::Vector2d& spot, const TrackPoint& p, const TrackPoint& q) {
  const Eigen::Vector2d a = p.xy - spot, b = q.xy - spot;
  const double na = a.norm(), nb = b.norm();
  return na >= kStruckDistance && nb > na &&
         a.dot(b) >= std::cos(kDepartureDeg * std::numbers::pi / 180.0) * na * nb;
}

absl::Status ValidateRecording(const TableModel& model, const Recording& rec) {
  if (absl::Status s = ValidateLayout(model, rec.initial); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("initial: ", s.message()));
  }
  const int balls = static_cast<int>(rec.initial.balls.size());
  for (const Ball& b : rec.initial.balls) {
    if (b.pocket < 0 && (b.v.squaredNorm() != 0.0 || b.w.squaredNorm() != 0.0)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("initial: ball \"%s\" must be at rest before the strike", b.id.substr(0, 16)));
    }
  }
  if (rec.cue < 0 || rec.cue >= balls || rec.initial.balls[static_cast<size_t>(rec.cue)].pocket >= 0) {
    return absl::InvalidArgumentError(absl::StrFormat("cue: %d is not a ball on the table", rec.cue));
  }
  if (rec.track.empty()) return absl::InvalidArgumentError("track: no tracked points");
  double t_prev = 0.0;
  for (size_t i = 0; i < rec.track.size(); ++i) {
    const TrackPoint& p = rec.track[i];
    if (!(p.t_s >= 0.0 && p.t_s <= kMaxTrackTime)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "track[%d].t_s must be finite and in [0, %g] s, got %g", i, kMaxTrackTime, p.t_s));
    }
    if (p.t_s < t_prev) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "track[%d].t_s: points must be in time order (%g after %g)", i, p.t_s, t_prev));
    }
    t_prev = p.t_s;
    if (p.ball < 0 || p.ball >= balls) {
      return absl::InvalidArgumentError(
          absl::StrFormat("track[%d].ball: %d is not a ball of the table (0..%d)", i, p.ball, balls - 1));
    }
    if (!p.xy.allFinite() || std::abs(p.xy.x()) > 100.0 || std::abs(p.xy.y()) > 100.0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("track[%d].xy must be finite and within 100 m", i));
    }
  }
  if (rec.strike_time_s && !(*rec.strike_time_s >= 0.0 && *rec.strike_time_s <= kMaxTrackTime)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "strike_time_s must be finite and in [0, %g] s, got %g", kMaxTrackTime, *rec.strike_time_s));
  }
  if (rec.strike) {
    if (absl::StatusOr<StrikeOutcome> s = ComputeStrike(model, 0, *rec.strike); !s.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("strike: ", s.status().message()));
    }
    if (!rec.strike_time_s) {
      return absl::InvalidArgumentError("strike_time_s: a known strike needs its time");
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<ShotError> ScoreShot(const TableModel& model, const SolverOptions& solver,
                                    const Recording& rec, const CueStrike& strike, double until_s,
                                    std::optional<double> strike_time_s) {
  if (absl::Status s = ValidateRecording(model, rec); !s.ok()) return s;
  if (strike_time_s && !(*strike_time_s >= 0.0 && *strike_time_s <= kMaxTrackTime)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("strike_time_s must be in [0, %g] s, got %g", kMaxTrackTime, *strike_time_s));
  }
  const TimedStrike timed{strike, strike_time_s ? *strike_time_s : ClockOf(model, rec).t0};
  const int n = PointsUntil(rec, timed.time_s + until_s);
  std::vector<double> r(static_cast<size_t>(2 * n));
  if (absl::Status s = ShotResiduals(model, solver, rec, timed, n, 1.0, r.data()); !s.ok()) return s;
  return ErrorOf(r.data(), n);
}

absl::StatusOr<StrikeFit> FitStrike(const TableModel& model, const SolverOptions& solver,
                                    const Recording& rec, const StrikeBounds& bounds,
                                    double until_s, double huber_m) {
  if (absl::Status s = ValidateRecording(model, rec); !s.ok()) return s;
  if (absl::Status s = CheckOptions(bounds); !s.ok()) return s;
  if (absl::Status s = CheckHuber(huber_m); !s.ok()) return s;
  Budget budget(std::numeric_limits<int64_t>::max(), nullptr);
  return FitStrikeOn(model, solver, rec, bounds, until_s, huber_m, &budget, /*final_fit=*/true);
}

std::optional<std::pair<double, double>> CalibrationRange(std::string_view name) {
  // Alciatore, "typical physical properties" FAQ (billiards.colostate.edu): sliding friction
  // 0.15-0.4, rolling resistance 0.005-0.015 (pool cloth; the range is widened down to 0.002
  // here because heated carom cloth is faster), spin-down 5-15 rad/s^2 (widened down to 2: a
  // tracked carom table's calibrates to 3.1, docs/billiards.md), ball-ball restitution
  // 0.92-0.98, ball-cushion restitution 0.6-0.9 (up to 0.98: Mathavan et al. 2010 measured
  // 0.98 at the nose). Cushion friction: around Mathavan's measured 0.14 and Han's 0.2. The
  // cushion rubber's Poisson ratio (Stronge's stiffness ratio): 0.3 (a compressible filled
  // rubber; pooltool's fixed frequency ratio 1.7 is about 0.3) to 0.5 (incompressible).
  // Slip-speed friction's u_c has no published value (Cross's curve was not at hand): from
  // none to 1 m/s, a third of a hard stun shot's first slip, past which the fade would be the
  // slide's whole law rather than its end. The cushion restitution's exponent: from none (a
  // constant restitution) to 1, a loss 1 - e growing in proportion to the approach speed,
  // five times a viscoelastic sphere's 1/5.
  struct Range {
    std::string_view name;
    double lo, hi;
  };
  static constexpr Range kRanges[] = {
      {"mu_slide", 0.15, 0.4},          {"mu_roll", 0.002, 0.015},
      {"spin_decel_rps2", 2.0, 15.0},   {"e_ball", 0.92, 0.98},
      {"e_cushion", 0.6, 0.98},         {"f_cushion", 0.05, 0.35},
      {"e_cushion_mathavan", 0.6, 0.99}, {"f_cushion_mathavan", 0.05, 0.35},
      {"cushion_poisson_ratio", 0.3, 0.5},
      {"slide_fade_speed_mps", 0.0, 1.0}, {"cushion_restitution_exponent", 0.0, 1.0},
  };
  for (const Range& r : kRanges) {
    if (r.name == name) return std::make_pair(r.lo, r.hi);
  }
  return std::nullopt;
}

namespace {

// A parameter to fit: its field and bounds.
struct Fitted {
  const ParamInfo* info;
  double lo, hi;
};

// A calibration's inputs, checked, resolved.
struct Prepared {
  TableModel model0;
  std::vector<bool> heldout;
  std::vector<Fitted> fitted;
};

absl::StatusOr<Prepared> Prepare(const TableSpec& spec, const SolverOptions& solver,
                                 std::span<const Recording> recordings,
                                 const CalibrationOptions& options) {
  absl::StatusOr<TableModel> model0 = TableModel::Create(spec);
  if (!model0.ok()) return model0.status();
  if (absl::Status s = ValidateSolverOptions(solver); !s.ok()) return s;
  if (absl::Status s = CheckOptions(options.strike_bounds); !s.ok()) return s;
  if (recordings.empty()) return absl::InvalidArgumentError("recordings: none given");
  if (options.max_iterations < 1 || options.max_iterations > 1000) {
    return absl::InvalidArgumentError("max_iterations must be in [1, 1000]");
  }
  if (options.max_simulations < 1) return absl::InvalidArgumentError("max_simulations must be >= 1");
  if (!(options.strike_window_s > 0.0)) {
    return absl::InvalidArgumentError("strike_window_s must be > 0");
  }
  if (absl::Status s = CheckHuber(options.huber_m); !s.ok()) return s;
  const int shots = static_cast<int>(recordings.size());
  for (int i = 0; i < shots; ++i) {
    if (absl::Status s = ValidateRecording(*model0, recordings[static_cast<size_t>(i)]); !s.ok()) {
      return absl::InvalidArgumentError(absl::StrFormat("recordings[%d].%s", i, s.message()));
    }
  }
  std::vector<bool> heldout(static_cast<size_t>(shots), false);
  for (int h : options.heldout) {
    if (h < 0 || h >= shots) {
      return absl::InvalidArgumentError(absl::StrFormat("heldout: %d is not a recording (0..%d)", h, shots - 1));
    }
    heldout[static_cast<size_t>(h)] = true;
  }
  // The parameters: their fields and bounds.
  std::vector<Fitted> fitted;
  for (const FitParam& p : options.params) {
    const ParamInfo* info = nullptr;
    for (const ParamInfo& i : ParamInfos()) {
      if (i.name == p.name) info = &i;
    }
    if (info == nullptr) {
      return absl::InvalidArgumentError(
          absl::StrFormat("params: unknown parameter \"%s\"", p.name.substr(0, 32)));
    }
    for (const Fitted& f : fitted) {
      if (f.info == info) return absl::InvalidArgumentError(absl::StrCat("params: ", p.name, " twice"));
    }
    if (info->field == &PhysicsParams::slide_fade_bands) {
      return absl::InvalidArgumentError(
          "params: slide_fade_bands is the fade's accuracy (a whole number), not fitted");
    }
    double lo = p.lo, hi = p.hi;
    if (lo == 0.0 && hi == 0.0) {
      const std::optional<std::pair<double, double>> r = CalibrationRange(p.name);
      lo = r ? r->first : info->lo;
      hi = r ? r->second : info->hi;
    }
    if (!(lo < hi) || !std::isfinite(lo) || !std::isfinite(hi) || lo < info->lo || hi > info->hi) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "params: %s's bounds must satisfy %g <= lo < hi <= %g", p.name, info->lo, info->hi));
    }
    const double v = spec.params.*(info->field);
    if (v < lo || v > hi) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "params: %s starts at %g, outside its bounds [%g, %g]", p.name, v, lo, hi));
    }
    fitted.push_back({info, lo, hi});
  }

  return Prepared{*std::move(model0), std::move(heldout), std::move(fitted)};
}

}  // namespace

absl::Status ValidateCalibration(const TableSpec& spec, const SolverOptions& solver,
                                 std::span<const Recording> recordings,
                                 const CalibrationOptions& options) {
  return Prepare(spec, solver, recordings, options).status();
}

// The fitted parameters' standard errors in their unbounded coordinates, linearised at the
// fit: the sandwich (J'J)^+ J'DJ (J'J)^+ of the reduced Jacobian J (each training shot's rows
// with what its own strike can take up projected out). D is the residuals' variance: a shot's
// rows carry its weight w (every shot weighs the same, whatever its points), and each
// coordinate of a point the noise variance s^2, estimated from the unweighted residuals over
// the degrees of freedom left (`dof`: the parameters and the strikes' coordinates). A
// parameter with a part in J'J's null space (no shot moves it, or it trades exactly against
// others) gets infinity; the others' errors stand, since the pseudo-inverse leaves them as the
// determined subspace has them.
std::vector<double> StandardErrorsU(const Eigen::MatrixXd& j, const VectorXd& r,
                                    std::span<const int> train, std::span<const int> row0,
                                    std::span<const ShotPoints> pts, int dof) {
  const int kp = static_cast<int>(j.cols());
  std::vector<double> out(static_cast<size_t>(kp), std::numeric_limits<double>::infinity());
  double squares = 0.0;
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(kp, kp);
  for (int i : train) {
    const ShotPoints& sp = pts[static_cast<size_t>(i)];
    const int first = row0[static_cast<size_t>(i)], n = 2 * sp.n;
    if (n == 0) continue;
    const double w2 = sp.weight * sp.weight;
    squares += r.segment(first, n).squaredNorm() / w2;
    const auto block = j.middleRows(first, n);
    b += w2 * (block.transpose() * block);
  }
  const int left = static_cast<int>(r.size()) - dof;
  if (left <= 0) return out;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(j.transpose() * j);
  if (eig.info() != Eigen::Success) return out;
  const VectorXd& lambda = eig.eigenvalues();  // ascending
  const Eigen::MatrixXd& v = eig.eigenvectors();
  // Directions whose curvature is below 1e-12 of the largest (singular values below 1e-6 of
  // the largest: far under what forward differences resolve) are not determined.
  const double floor = 1e-12 * lambda[kp - 1];
  Eigen::MatrixXd pinv = Eigen::MatrixXd::Zero(kp, kp);
  VectorXd undetermined = VectorXd::Zero(kp);
  for (int k = 0; k < kp; ++k) {
    if (lambda[k] > floor && lambda[k] > 0.0) {
      pinv += v.col(k) * v.col(k).transpose() / lambda[k];
    } else {
      undetermined += v.col(k).cwiseAbs2();
    }
  }
  const Eigen::MatrixXd cov = pinv * (squares / left * b) * pinv;
  for (int c = 0; c < kp; ++c) {
    if (undetermined[c] > 1e-9) continue;
    out[static_cast<size_t>(c)] = std::sqrt(std::max(0.0, cov(c, c)));
  }
  return out;
}

namespace {

ClothTaken TakeCloth(const TableSpec& spec, const std::vector<Fitted>& fitted,
                     const ClothReading& reading);
absl::StatusOr<ClothReading> ReadClothOf(std::span<const Recording> recordings,
                                         const std::vector<bool>& skip, double gravity_mps2,
                                         const std::function<bool()>& cancelled);

// The calibration from `spec` as given (Calibrate reads the cloth first when asked).
absl::StatusOr<CalibrationReport> CalibrateFrom(const TableSpec& spec, const SolverOptions& solver,
                                                std::span<const Recording> recordings,
                                                const CalibrationOptions& options) {
  absl::StatusOr<Prepared> prepared = Prepare(spec, solver, recordings, options);
  if (!prepared.ok()) return prepared.status();
  const TableModel* model0 = &prepared->model0;
  const std::vector<bool>& heldout = prepared->heldout;
  const std::vector<Fitted>& fitted = prepared->fitted;
  const int shots = static_cast<int>(recordings.size());
  Budget budget(options.max_simulations, &options.cancelled);
  auto progress = [&](double f, std::string_view stage) {
    if (options.progress) options.progress(std::clamp(f, 0.0, 1.0), stage);
  };
  CalibrationReport report;
  report.shots.resize(static_cast<size_t>(shots));
  // The shots fitted with the parameters, and their residual rows.
  std::vector<int> train;
  for (int i = 0; i < shots; ++i) {
    if (!heldout[static_cast<size_t>(i)]) train.push_back(i);
  }
  const int kp = static_cast<int>(fitted.size());
  std::vector<int> row0(static_cast<size_t>(shots), 0);  // first residual of a shot
  std::vector<ShotPoints> pts(static_cast<size_t>(shots));
  int rows = 0;
  for (int i : train) {
    pts[static_cast<size_t>(i)] = PointsOf(recordings[static_cast<size_t>(i)], 1e300, options.huber_m);
    row0[static_cast<size_t>(i)] = rows;
    rows += 2 * pts[static_cast<size_t>(i)].n;
  }
  const bool joint = !train.empty() && kp > 0 && rows >= kp;

  // The strikes' coordinates in the joint fit. An unknown strike time is held where the
  // shot's first motion put it (free, it would take up what the parameters get wrong: a late
  // strike for a slow cloth) until the parameters have settled; then a last solve frees it
  // within a tenth of a frame of it (StrikeClock::Around), since a time off by a fraction of
  // a millisecond biases the parameters in turn (a strike that lags is fitted faster, which a
  // livelier cloth makes up).
  const StrikeMap map{options.strike_bounds, 0.999 * spec.params.miscue_limit};
  std::vector<StrikeClock> clocks;
  for (const Recording& rec : recordings) clocks.push_back(ClockOf(*model0, rec));
  // Whether a training shot's time is to be freed (held-out shots are not in the joint fit).
  bool any_clock = false;
  for (int i : train) {
    any_clock = any_clock || (clocks[static_cast<size_t>(i)].fitted &&
                              !recordings[static_cast<size_t>(i)].strike);
  }
  bool free_time = false;
  std::vector<TimedStrike> strikes(static_cast<size_t>(shots));
  auto map_of = [&](int i) {
    if (!free_time || !clocks[static_cast<size_t>(i)].fitted) {
      return map.HeldAt(strikes[static_cast<size_t>(i)].time_s);
    }
    StrikeMap m = map;
    m.clock = clocks[static_cast<size_t>(i)];
    return m;
  };

  // 1. Every shot's strike under the starting parameters: the "before" report and the fit's
  // starting point. Known strikes are kept.
  for (int i = 0; i < shots; ++i) {
    const Recording& rec = recordings[static_cast<size_t>(i)];
    ShotReport& sr = report.shots[static_cast<size_t>(i)];
    sr.name = rec.name;
    sr.heldout = heldout[static_cast<size_t>(i)];
    const double window = sr.heldout ? options.strike_window_s : 1e300;
    if (rec.strike) {
      strikes[static_cast<size_t>(i)] = {*rec.strike, *rec.strike_time_s};
    } else {
      absl::StatusOr<StrikeFit> fit =
          FitStrikeOn(*model0, solver, rec, options.strike_bounds, window, options.huber_m, &budget,
                      /*final_fit=*/!joint || sr.heldout);
      if (!fit.ok()) {
        return absl::Status(fit.status().code(),
                            absl::StrFormat("recordings[%d]: %s", i, fit.status().message()));
      }
      strikes[static_cast<size_t>(i)] = {fit->strike, fit->strike_time_s};
    }
    sr.strike_before = strikes[static_cast<size_t>(i)].strike;
    sr.strike_time_before_s = strikes[static_cast<size_t>(i)].time_s;
    absl::StatusOr<ShotError> e =
        ScoreShot(*model0, solver, rec, sr.strike_before, 1e300, sr.strike_time_before_s);
    if (!e.ok()) return e.status();
    sr.before = *e;
    progress(0.3 * (i + 1) / shots, "strikes before");
  }
  // What fitting every strike once cost: the reserve the second start leaves for what follows.
  const int64_t first_strikes = budget.used();

  // 2. The fit over the training shots by variable projection: LM over the table's parameters
  // alone, each evaluation refitting every unknown strike to them first (from where it was),
  // so the score is a function of the parameters with the strikes at their best. A joint LM
  // over both at once stalls (one shot's strike on a kink of its own score, a graze, rejects
  // every step of all the others), and alternating the two crawls along their coupling (a
  // livelier cushion and a slower strike trade against each other).
  PhysicsParams fitted_params = spec.params;
  std::vector<double> standard_errors(static_cast<size_t>(kp), 0.0);
  auto model_at = [&](const VectorXd& u) -> absl::StatusOr<TableModel> {
    TableSpec ts = spec;
    for (int c = 0; c < kp; ++c) {
      const Fitted& fp = fitted[static_cast<size_t>(c)];
      ts.params.*(fp.info->field) = FromU(u[c], fp.lo, fp.hi);
    }
    return TableModel::Create(std::move(ts));
  };
  // Every training shot's residuals under the parameters u, the strikes as they are.
  auto all_residuals = [&](const VectorXd& u, double* out) -> absl::Status {
    absl::StatusOr<TableModel> m = model_at(u);
    if (!m.ok()) return m.status();
    for (int i : train) {
      if (absl::Status st = Simulate(*m, solver, recordings[static_cast<size_t>(i)],
                                     strikes[static_cast<size_t>(i)], pts[static_cast<size_t>(i)],
                                     &budget, out + row0[static_cast<size_t>(i)]);
          !st.ok()) {
        return st;
      }
    }
    return absl::OkStatus();
  };
  // The points the parameters are fitted on: each training shot's up to window_s after its
  // strike's first estimate (origin, held while the strike's time moves, so that the points
  // stay the same); set_window recounts them and their rows.
  std::vector<double> origin(static_cast<size_t>(shots), 0.0);
  for (int i = 0; i < shots; ++i) origin[static_cast<size_t>(i)] = clocks[static_cast<size_t>(i)].t0;
  double window_s = 1e300;
  auto set_window = [&](double w) {
    window_s = w;
    rows = 0;
    for (int i : train) {
      pts[static_cast<size_t>(i)] =
          PointsOf(recordings[static_cast<size_t>(i)], origin[static_cast<size_t>(i)] + w, options.huber_m);
      row0[static_cast<size_t>(i)] = rows;
      rows += 2 * pts[static_cast<size_t>(i)].n;
    }
  };
  if (joint) {
    VectorXd x(kp);
    for (int c = 0; c < kp; ++c) {
      // A start on a bound (a switch's off value, as a fade or a restitution's fall fitted from
      // 0) starts a hundredth of the range inside it: on the bound the logistic coordinate sits
      // on its flat tail, where the parameter answers a millionth of what it does in the
      // middle, and the first accepted step could leap to the other tail and stay there.
      const Fitted& fp = fitted[static_cast<size_t>(c)];
      const double inside = 0.01 * (fp.hi - fp.lo);
      x[c] = ToU(std::clamp(spec.params.*(fp.info->field), fp.lo + inside, fp.hi - inside), fp.lo,
                 fp.hi);
    }
    // The strikes refitted to the parameters u (from where they were), then every shot's
    // residuals: the reduced problem's residual function.
    // Each refit starts from the strikes of the last accepted point (`anchor`), never from a
    // rejected trial's, so that the score at a point does not depend on the trials before it.
    std::vector<TimedStrike> anchor = strikes;
    auto refit = [&](const VectorXd& u, double* out) -> absl::Status {
      absl::StatusOr<TableModel> m = model_at(u);
      if (!m.ok()) return m.status();
      for (int i : train) {
        const Recording& rec = recordings[static_cast<size_t>(i)];
        if (rec.strike) continue;
        const StrikeMap sm = map_of(i);
        VectorXd su(sm.size());
        sm.FromTimed(anchor[static_cast<size_t>(i)], su.data());
        if (absl::Status st = RefineStrike(*m, solver, rec, sm, origin[static_cast<size_t>(i)] + window_s,
                                           options.huber_m, nullptr, kRefitIterations, &budget, &su);
            !st.ok()) {
          return st;
        }
        strikes[static_cast<size_t>(i)] = sm.ToTimed(su.data());
      }
      return all_residuals(u, out);
    };
    // The reduced Jacobian: each shot's block of d(residuals)/d(parameters) with the part its
    // own strike can take up projected out (Kaufman's variable projection), the strikes being
    // at their optimum for u (df follows an evaluation at u).
    auto reduced_jacobian = [&](const VectorXd& u, const VectorXd& r0, Eigen::MatrixXd* j) -> absl::Status {
      anchor = strikes;  // u is accepted; its strikes are the last evaluation's
      VectorXd up = u, r(rows);
      for (int c = 0; c < kp; ++c) {
        up[c] = u[c] + kParamDiffStep;
        if (absl::Status st = all_residuals(up, r.data()); !st.ok()) return st;
        j->col(c) = (r - r0) / kParamDiffStep;
        up[c] = u[c];
      }
      absl::StatusOr<TableModel> m = model_at(u);
      if (!m.ok()) return m.status();
      for (int i : train) {
        const Recording& rec = recordings[static_cast<size_t>(i)];
        if (rec.strike) continue;
        const StrikeMap sm = map_of(i);
        const int ks = sm.size();
        const int r_0 = row0[static_cast<size_t>(i)], n = 2 * pts[static_cast<size_t>(i)].n;
        Eigen::MatrixXd js(n, ks);
        VectorXd su(ks), rs(n);
        sm.FromTimed(strikes[static_cast<size_t>(i)], su.data());
        for (int c = 0; c < ks; ++c) {
          VectorXd sp = su;
          sp[c] += kDiffStep;
          if (absl::Status st = Simulate(*m, solver, rec, sm.ToTimed(sp.data()), pts[static_cast<size_t>(i)],
                                         &budget, rs.data());
              !st.ok()) {
            return st;
          }
          js.col(c) = (rs - r0.segment(r_0, n)) / kDiffStep;
        }
        // An orthonormal basis of the strike's columns (rank-revealing: flat directions drop).
        Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(js);
        const int rank = static_cast<int>(qr.rank());
        if (rank == 0) continue;
        const Eigen::MatrixXd q = qr.householderQ() * Eigen::MatrixXd::Identity(n, rank);
        auto block = j->block(r_0, 0, n, kp);
        block -= q * (q.transpose() * block);
      }
      return absl::OkStatus();
    };
    // The whole shots' reduced problem (the windows below build their own).
    LmFunctor f(kp, rows);
    f.residuals = [&](const VectorXd& u, VectorXd* r) { return refit(u, r->data()); };
    f.jacobian = reduced_jacobian;
    // Passes: LM on the parameters; then every strike fitted afresh (FitStrike's starts and
    // windows) under the parameters reached, kept where it beats the one carried along (a
    // strike fitted under the starting parameters can sit in another basin, a ball hit on the
    // other side, and pull the parameters its way); again while a strike changed. Returns the
    // iterations used, up to `most`; r is left the residuals at x.
    VectorXd r(rows);
    // Shot i's strike fitted afresh under m (FitStrike's starts and windows) on the window,
    // its time held; `loss`, if given, gets the fit's loss.
    auto fresh_strike = [&](const TableModel& m, int i,
                            double* loss) -> absl::StatusOr<TimedStrike> {
      absl::StatusOr<StrikeFit> fit =
          FitStrikeOn(m, solver, recordings[static_cast<size_t>(i)], options.strike_bounds, window_s,
                      options.huber_m, &budget, /*final_fit=*/false, loss);
      if (!fit.ok()) return fit.status();
      return TimedStrike{fit->strike, fit->strike_time_s};
    };
    // Every strike fitted afresh under the parameters x, kept where it beats the one carried
    // along (r: the residuals at x with the strikes as they are). Whether one changed.
    auto renew = [&]() -> absl::StatusOr<bool> {
      absl::StatusOr<TableModel> m = model_at(x);
      if (!m.ok()) return m.status();
      bool changed = false;
      for (int i : train) {
        const Recording& rec = recordings[static_cast<size_t>(i)];
        if (rec.strike) continue;
        const ShotPoints& sp = pts[static_cast<size_t>(i)];
        const double now = r.segment(row0[static_cast<size_t>(i)], 2 * sp.n).squaredNorm();
        double loss = 0.0;
        absl::StatusOr<TimedStrike> fresh = fresh_strike(*m, i, &loss);
        if (!fresh.ok()) return fresh.status();
        if (loss < (1.0 - 1e-3) * now) {
          strikes[static_cast<size_t>(i)] = anchor[static_cast<size_t>(i)] = *fresh;
          changed = true;
        }
      }
      return changed;
    };
    // The strikes as fitted to the parameters x reached (the last evaluation may have been a
    // rejected trial's), carried from there on; r their residuals.
    auto settle = [&]() -> absl::Status {
      anchor = strikes;
      if (absl::Status st = refit(x, r.data()); !st.ok()) return st;
      anchor = strikes;
      return absl::OkStatus();
    };
    auto run_passes = [&](int most, double progress_from, double progress_to) -> absl::StatusOr<int> {
      int used = 0;
      for (int pass = 0; pass < kPasses && used < most; ++pass) {
        absl::StatusOr<int> it = Minimize(f, &x, most - used);
        if (!it.ok()) return it.status();
        used += std::max(*it, 1);
        if (absl::Status st = settle(); !st.ok()) return st;
        absl::StatusOr<bool> changed = renew();
        if (!changed.ok()) return changed.status();
        progress(progress_from + (progress_to - progress_from) * (pass + 1) / kPasses, "fit");
        if (!*changed) break;
        if (absl::Status st = all_residuals(x, r.data()); !st.ok()) return st;
        f.last_x.resize(0);  // the strikes moved: no cached evaluation holds
      }
      return used;
    };
    // Growing windows first. The score over whole shots is rugged in the parameters far from
    // the truth (a livelier cushion or a slower cloth sends a ball to another rail some seconds
    // in), and a first Gauss-Newton step from a start that is off in one constant can trade it
    // for others into another valley: five constants fitted to twelve synthetic shots from a
    // start whose rolling resistance alone was off (0.01 for 0.006) took the cushion's
    // restitution from 0.98 to 0.86 in one step and ended at 0.915, the loss 350 times the
    // one at the truth. Fitted on each shot's first second, then two, four, ..., then the
    // whole shot (as a strike is fitted, Windows), each window's fit starts in the basin the
    // longer one needs.
    double longest = 0.0;
    for (int i : train) {
      const Recording& rec = recordings[static_cast<size_t>(i)];
      longest = std::max(longest, rec.track.back().t_s - origin[static_cast<size_t>(i)]);
    }
    const VectorXd x_start = x;
    const std::vector<TimedStrike> strikes_start = strikes;
    bool first = true;
    for (double w = kFirstParamWindow; w < longest; w *= 2.0) {
      set_window(w);
      if (rows < kp) continue;
      LmFunctor g(kp, rows + kp);
      g.residuals = [&](const VectorXd& u, VectorXd* out) -> absl::Status {
        if (absl::Status st = refit(u, out->data()); !st.ok()) return st;
        out->tail(kp) = kParamPrior * (u - x_start);
        return absl::OkStatus();
      };
      g.jacobian = [&](const VectorXd& u, const VectorXd& r0, Eigen::MatrixXd* j) -> absl::Status {
        Eigen::MatrixXd jr(rows, kp);
        if (absl::Status st = reduced_jacobian(u, r0.head(rows), &jr); !st.ok()) return st;
        j->topRows(rows) = jr;
        j->bottomRows(kp) = kParamPrior * Eigen::MatrixXd::Identity(kp, kp);
        return absl::OkStatus();
      };
      // On the first window fitted, the strikes afresh first: fitted to whole shots under the
      // starting parameters, a strike takes up some of what they get wrong, and can be off
      // from its start. Then one solve a window, each strike refined from where it was (no
      // fresh fits: at every window they cost more than all the rest).
      r.resize(rows);
      if (first) {
        first = false;
        if (absl::Status st = all_residuals(x, r.data()); !st.ok()) return st;
        if (absl::StatusOr<bool> changed = renew(); !changed.ok()) return changed.status();
      }
      absl::StatusOr<int> it = Minimize(g, &x, std::min(kWindowIterations, options.max_iterations));
      if (!it.ok()) return it.status();
      report.iterations += std::max(*it, 1);
      if (absl::Status st = settle(); !st.ok()) return st;
      progress(0.3 + 0.1 * std::min(1.0, w / longest), "fit, first seconds");
    }
    set_window(1e300);
    r.resize(rows);
    // The held passes' share of the iterations; the rest (at least one of two or more) frees
    // the times.
    const int held_iterations =
        any_clock ? std::max(1, options.max_iterations * 3 / 4) : options.max_iterations;
    // The passes over whole shots from where x and the strikes are, then a restart: every
    // strike fitted afresh under the parameters reached and taken whatever it scores there,
    // then the passes again; kept if they end lower. A strike carried along the fit's path can
    // settle in a basin of its own that scores better than a fresh fit at the parameters
    // reached but holds them in a false valley: five constants fitted to eight synthetic shots
    // from the carom preset stopped with the spin-down at 6.17 for 7.5, the loss 66 % above
    // the one at the truth, where a fit started at the truth stays; fresh strikes see a smooth
    // valley to the truth. One restart: more, while each lowered the loss, cost the
    // calibration study 55 % more time and moved its fits little. One parameter's fits end at
    // the noise without it (the study's and the tests'), so they are spared it. Returns the
    // first passes' iterations (the restart's go to the report); r is left the residuals at x.
    auto descend = [&](double progress_from, double progress_to) -> absl::StatusOr<int> {
      const double mid = (progress_from + progress_to) / 2.0;
      absl::StatusOr<int> used = run_passes(held_iterations, progress_from, kp >= 2 ? mid : progress_to);
      if (!used.ok() || kp < 2) return used;
      const VectorXd x_kept = x;
      const std::vector<TimedStrike> strikes_kept = strikes;
      if (absl::Status st = all_residuals(x, r.data()); !st.ok()) return st;
      const double loss_kept = r.squaredNorm();
      absl::StatusOr<TableModel> m = model_at(x);
      if (!m.ok()) return m.status();
      for (int i : train) {
        const Recording& rec = recordings[static_cast<size_t>(i)];
        if (rec.strike) continue;
        absl::StatusOr<TimedStrike> fresh = fresh_strike(*m, i, nullptr);
        if (!fresh.ok()) return fresh.status();
        strikes[static_cast<size_t>(i)] = *fresh;
      }
      anchor = strikes;
      f.last_x.resize(0);
      absl::StatusOr<int> restart_used = run_passes(held_iterations, mid, progress_to);
      if (!restart_used.ok()) return restart_used.status();
      report.iterations += *restart_used;
      if (absl::Status st = all_residuals(x, r.data()); !st.ok()) return st;
      if (!(r.squaredNorm() < loss_kept)) {
        x = x_kept;
        strikes = anchor = strikes_kept;
        if (absl::Status st = all_residuals(x, r.data()); !st.ok()) return st;
      }
      f.last_x.resize(0);
      return used;
    };
    absl::StatusOr<int> held_used = descend(0.4, kp >= 2 ? 0.65 : 0.9);
    if (!held_used.ok()) return held_used.status();
    const double train_shots = static_cast<double>(train.size());
    report.start_rms_m = {std::sqrt(r.squaredNorm() / train_shots)};
    report.start_kept = 1;
    // The second start: the passes over whole shots from the starting parameters and the
    // strikes fitted under them, kept if they end lower. Each start finds a valley the other
    // can miss: in the calibration study, the windows took Mathavan's five constants to the
    // truth on aimed shots where the whole shots' first step had gone astray (restitution
    // 0.915, 16.4 mm), and missed it on raised shots with the elevation fitted (0.959, 12.6 mm)
    // where the whole shots found it (1.3 mm). A fit at the trackers' noise (its mean squared
    // distance within 1.5 times the noise's, 2 s^2 for a noise s in each coordinate,
    // estimated from the tracks alone: the truth's is within a few percent of it) cannot be
    // bettered, and is spared it. One parameter's fits are spared it too (one valley, as the
    // restart). The second start may stop short: it runs on the budget less a reserve for
    // what follows it (the first strikes' cost, at least a tenth of the budget), and where it
    // runs out the first start stands (the second's loss reported as infinity), so a budget
    // the first start and the rest fit in is not exhausted by the second.
    if (kp >= 2) {
      const double loss_first = r.squaredNorm();  // descend left r at x
      double at_noise = 0.0;
      for (int i : train) {
        const double s = RecordingNoise(recordings[static_cast<size_t>(i)]);
        at_noise += 1.5 * 2.0 * s * s;
      }
      if (!(loss_first <= at_noise)) {
        const VectorXd x_first = x;
        const std::vector<TimedStrike> strikes_first = strikes;
        const int used_first = *held_used;
        x = x_start;
        strikes = anchor = strikes_start;
        budget.Share(options.max_simulations - std::max(first_strikes, options.max_simulations / 10));
        absl::Status second = all_residuals(x, r.data());
        f.last_x.resize(0);
        if (second.ok()) {
          held_used = descend(0.65, 0.9);
          second = held_used.status();
        }
        budget.Unshare();
        if (!second.ok() && !budget.over_share()) return second;
        report.start_rms_m.push_back(second.ok() ? std::sqrt(r.squaredNorm() / train_shots)
                                                 : std::numeric_limits<double>::infinity());
        // The start not kept has its passes counted here, the kept one's below.
        if (!second.ok() || !(r.squaredNorm() < loss_first)) {
          if (second.ok()) report.iterations += *held_used;
          x = x_first;
          strikes = anchor = strikes_first;
          held_used = used_first;
          if (absl::Status st = all_residuals(x, r.data()); !st.ok()) return st;
        } else {
          report.iterations += used_first;
          report.start_kept = 2;
        }
        f.last_x.resize(0);
      }
    }
    report.iterations += *held_used;
    if (any_clock && *held_used < options.max_iterations) {
      // The times freed, each around where it was held.
      free_time = true;
      for (int i : train) {
        clocks[static_cast<size_t>(i)] =
            clocks[static_cast<size_t>(i)].Around(strikes[static_cast<size_t>(i)].time_s);
      }
      f.last_x.resize(0);
      absl::StatusOr<int> it = Minimize(f, &x, options.max_iterations - *held_used);
      if (!it.ok()) return it.status();
      report.iterations += std::max(*it, 1);
      if (absl::Status st = settle(); !st.ok()) return st;
    }
    // The parameters' standard errors at the fit: the reduced Jacobian there, the strikes
    // where the fit left them.
    if (absl::Status st = all_residuals(x, r.data()); !st.ok()) return st;
    Eigen::MatrixXd jr(rows, kp);
    if (absl::Status st = f.jacobian(x, r, &jr); !st.ok()) return st;
    int dof = kp;
    for (int i : train) {
      if (!recordings[static_cast<size_t>(i)].strike) dof += map_of(i).size();
    }
    const std::vector<double> errors_u = StandardErrorsU(jr, r, train, row0, pts, dof);
    for (int c = 0; c < kp; ++c) {
      const Fitted& fp = fitted[static_cast<size_t>(c)];
      const double p = FromU(x[c], fp.lo, fp.hi);
      fitted_params.*(fp.info->field) = p;
      // dp/du of the logistic map onto [lo, hi].
      const double slope = (p - fp.lo) * (fp.hi - p) / (fp.hi - fp.lo);
      const double e = errors_u[static_cast<size_t>(c)];
      standard_errors[static_cast<size_t>(c)] = std::isfinite(e) ? slope * e : e;
    }
  }
  TableSpec fitted_spec = spec;
  fitted_spec.params = fitted_params;
  absl::StatusOr<TableModel> model1 = TableModel::Create(fitted_spec);
  if (!model1.ok()) return model1.status();

  // 3. The "after" report: training shots with the strikes fitted along with the parameters,
  // held-out ones with strikes fitted afresh under the fitted parameters.
  std::vector<double> train_before, train_after, held_before, held_after;
  for (int i = 0; i < shots; ++i) {
    const Recording& rec = recordings[static_cast<size_t>(i)];
    ShotReport& sr = report.shots[static_cast<size_t>(i)];
    if (sr.heldout && !rec.strike) {
      absl::StatusOr<StrikeFit> fit =
          FitStrikeOn(*model1, solver, rec, options.strike_bounds, options.strike_window_s,
                      options.huber_m, &budget, /*final_fit=*/true);
      if (!fit.ok()) return fit.status();
      strikes[static_cast<size_t>(i)] = {fit->strike, fit->strike_time_s};
      sr.plausible = fit->plausible;
      sr.intent_met = fit->intent_met;
    }
    sr.strike_after = strikes[static_cast<size_t>(i)].strike;
    sr.strike_after.phi_rad = std::remainder(sr.strike_after.phi_rad, 2.0 * std::numbers::pi);
    sr.strike_time_after_s = strikes[static_cast<size_t>(i)].time_s;
    absl::StatusOr<ShotError> e =
        ScoreShot(*model1, solver, rec, sr.strike_after, 1e300, sr.strike_time_after_s);
    if (!e.ok()) return e.status();
    sr.after = *e;
    (sr.heldout ? held_before : train_before).push_back(sr.before.mean_m);
    (sr.heldout ? held_after : train_after).push_back(sr.after.mean_m);
    progress(0.9 + 0.1 * (i + 1) / shots, "report");
  }
  report.params = fitted_params;
  for (size_t c = 0; c < fitted.size(); ++c) {
    const Fitted& f = fitted[c];
    const double after = fitted_params.*(f.info->field);
    report.fitted.push_back({.name = std::string(f.info->name),
                             .before = spec.params.*(f.info->field),
                             .after = after,
                             .lo = f.lo,
                             .hi = f.hi,
                             .standard_error = standard_errors[c],
                             .at_bound = std::min(after - f.lo, f.hi - after) < 1e-3 * (f.hi - f.lo)});
  }
  report.train_before_m = Median(train_before);
  report.train_after_m = Median(train_after);
  report.heldout_before_m = Median(held_before);
  report.heldout_after_m = Median(held_after);
  report.simulations = budget.used();
  return report;
}

}  // namespace

absl::StatusOr<CalibrationReport> Calibrate(const TableSpec& spec, const SolverOptions& solver,
                                            std::span<const Recording> recordings,
                                            const CalibrationOptions& options) {
  if (!options.read_cloth) return CalibrateFrom(spec, solver, recordings, options);
  // The inputs are checked on the table as given, before anything is read.
  absl::StatusOr<Prepared> prepared = Prepare(spec, solver, recordings, options);
  if (!prepared.ok()) return prepared.status();
  if (options.progress) options.progress(0.0, "reading the cloth");
  absl::StatusOr<ClothReading> reading = ReadClothOf(
      recordings, prepared->heldout, spec.params.gravity_mps2, options.cancelled);
  if (!reading.ok()) return reading.status();
  const ClothTaken taken = TakeCloth(spec, prepared->fitted, *reading);
  if (!taken.mu_roll_taken && !taken.mu_slide_taken) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "read_cloth: the training shots' tracks show %d rolling and %d sliding stretches; a "
        "cloth constant needs %d",
        reading->rolling, reading->sliding, kClothMinStretches));
  }
  TableSpec read = spec;
  if (taken.mu_roll_taken) read.params.mu_roll = taken.mu_roll;
  if (taken.mu_slide_taken) read.params.mu_slide = taken.mu_slide;
  absl::StatusOr<CalibrationReport> report = CalibrateFrom(read, solver, recordings, options);
  if (!report.ok()) return report.status();
  report->cloth = taken;
  return report;
}

namespace {

// How far a point is from a rail's line, towards the table's inside.
double RailGap(const TableSpec& spec, int rail, const Eigen::Vector2d& xy) {
  switch (static_cast<Rail>(rail)) {
    case Rail::kPlusX: return spec.length_m / 2 - xy.x();
    case Rail::kMinusX: return spec.length_m / 2 + xy.x();
    case Rail::kPlusY: return spec.width_m / 2 - xy.y();
    case Rail::kMinusY: break;
  }
  return spec.width_m / 2 + xy.y();
}

}  // namespace

Rail NearestRail(const TableSpec& spec, const Eigen::Vector2d& xy) {
  int nearest = 0;
  for (int r = 1; r < 4; ++r) {
    if (RailGap(spec, r, xy) < RailGap(spec, nearest, xy)) nearest = r;
  }
  return static_cast<Rail>(nearest);
}

namespace {

// Least-squares line through (t, y): its slope, and the spread of t (sum of squares about
// its mean: the slope's standard error is the noise over its square root).
struct LineFit {
  double slope = 0.0, sxx = 0.0;
  double mean_t = 0.0, mean_y = 0.0;  // the line passes through (mean_t, mean_y)
  int n = 0;
};
LineFit FitLine(std::span<const double> t, std::span<const double> y) {
  LineFit f;
  f.n = static_cast<int>(t.size());
  if (f.n < 2) return f;
  double mt = 0.0, my = 0.0;
  for (int i = 0; i < f.n; ++i) {
    mt += t[static_cast<size_t>(i)];
    my += y[static_cast<size_t>(i)];
  }
  mt /= f.n;
  my /= f.n;
  f.mean_t = mt;
  f.mean_y = my;
  double sxy = 0.0;
  for (int i = 0; i < f.n; ++i) {
    const double dt = t[static_cast<size_t>(i)] - mt;
    f.sxx += dt * dt;
    sxy += dt * (y[static_cast<size_t>(i)] - my);
  }
  if (f.sxx <= 0.0) return f;
  f.slope = sxy / f.sxx;
  return f;
}

// Whether a bounce off a rail lies in a gap of the track next to sample k (the samples' times
// t and distances from the rail g): where the tracker lost the ball at the cushion (frames
// dropped there, as a camera's often are near a rail), the sample nearest the bounce can lie
// farther from the rail than a step. For a contact between samples c and c + 1 (c = k - 1 or
// k), the ball's distance into it and out of it are each a line through the three samples on
// that side; they meet where the ball turned, which is a bounce when it is within near_m of the
// contact distance `reach` and between the two samples.
bool BounceInAGap(std::span<const double> t, std::span<const double> g, int k, double reach,
                  double near_m) {
  const int n = static_cast<int>(t.size());
  for (const int c : {k - 1, k}) {
    if (c < 2 || c + 3 >= n) continue;
    const size_t uc = static_cast<size_t>(c);
    const LineFit in = FitLine(t.subspan(uc - 2, 3), g.subspan(uc - 2, 3));
    const LineFit out = FitLine(t.subspan(uc + 1, 3), g.subspan(uc + 1, 3));
    if (!(in.slope < 0.0 && out.slope > 0.0)) continue;
    const double turn = (out.mean_y - in.mean_y + in.slope * in.mean_t - out.slope * out.mean_t) /
                        (in.slope - out.slope);
    const double at = in.mean_y + in.slope * (turn - in.mean_t);
    if (turn >= t[uc] && turn <= t[uc + 1] && std::abs(at - reach) <= near_m) return true;
  }
  return false;
}

}  // namespace

std::vector<Rail> TrackedRails(const TableModel& model, const Recording& recording, int ball,
                               double near_m, double window_s, double z) {
  // The ball's positions in time order, from where it stood.
  if (ball < 0 || ball >= static_cast<int>(recording.initial.balls.size())) return {};
  std::vector<double> t = {0.0};
  std::vector<Eigen::Vector2d> p = {recording.initial.balls[static_cast<size_t>(ball)].r.head<2>()};
  for (const TrackPoint& q : recording.track) {
    if (q.ball != ball) continue;
    t.push_back(q.t_s);
    p.push_back(q.xy);
  }
  const TableSpec& spec = model.spec();
  const double reach = model.cushion_contact_distance();
  std::vector<std::pair<int, int>> bounces;  // (sample, rail)
  const int n = static_cast<int>(p.size());
  std::vector<double> d2;
  SecondDifferences(std::span(p).subspan(1), &d2);
  const double sigma = NoiseOf(std::move(d2));
  std::vector<double> gap(static_cast<size_t>(n));
  for (int r = 0; r < 4; ++r) {
    // The ball's distance from rail r's line, sample by sample.
    for (int j = 0; j < n; ++j) {
      gap[static_cast<size_t>(j)] = RailGap(spec, r, p[static_cast<size_t>(j)]);
    }
    for (int k = 1; k + 1 < n; ++k) {
      const size_t uk = static_cast<size_t>(k);
      // The sample nearest a bounce is within half a step of the contact (more, for a fast
      // ball), or the bounce lies in a gap of the track beside it; and it is the least
      // distance within the window (the first of equal ones).
      const double step = std::max((p[uk] - p[uk - 1]).norm(), (p[uk + 1] - p[uk]).norm());
      if (gap[uk] > reach + std::max(near_m, 0.6 * step) &&
          !BounceInAGap(t, gap, k, reach, near_m)) {
        continue;
      }
      int lo = k, hi = k;
      while (lo > 0 && t[uk] - t[static_cast<size_t>(lo - 1)] <= window_s) --lo;
      while (hi + 1 < n && t[static_cast<size_t>(hi + 1)] - t[uk] <= window_s) ++hi;
      bool least = true;
      for (int j = lo; j <= hi && least; ++j) {
        least = j < k ? gap[static_cast<size_t>(j)] > gap[uk] : gap[static_cast<size_t>(j)] >= gap[uk];
      }
      if (!least || k - lo < 2 || hi - k < 2) continue;
      // Coming in, then going out: the distance's trend before and after, each a line fitted
      // by least squares, significant against the tracker's noise, so a resting or
      // sliding-along ball seen through noise is not a bounce.
      const std::span<const double> ts(t), gs(gap);
      const LineFit in = FitLine(ts.subspan(static_cast<size_t>(lo), uk - static_cast<size_t>(lo) + 1),
                                 gs.subspan(static_cast<size_t>(lo), uk - static_cast<size_t>(lo) + 1));
      const LineFit outf = FitLine(ts.subspan(uk, static_cast<size_t>(hi - k) + 1),
                                   gs.subspan(uk, static_cast<size_t>(hi - k) + 1));
      if (-in.slope > z * sigma / std::sqrt(in.sxx) && outf.slope > z * sigma / std::sqrt(outf.sxx)) {
        bounces.emplace_back(k, r);
      }
    }
  }
  std::sort(bounces.begin(), bounces.end());
  std::vector<Rail> out;
  for (const auto& [k, r] : bounces) out.push_back(static_cast<Rail>(r));
  return out;
}

std::vector<Rail> SimulatedRails(const TableSpec& spec, std::span<const Event> events, int ball) {
  std::vector<Rail> out;
  for (const Event& e : events) {
    if (e.kind == EventKind::kBallCushion && e.a == ball) out.push_back(NearestRail(spec, e.ra));
  }
  return out;
}

namespace {

// A ball's tracked points in time order.
struct BallTrack {
  std::vector<double> t;
  std::vector<Eigen::Vector2d> p;
};
BallTrack TrackOf(const Recording& rec, int ball) {
  BallTrack b;
  for (const TrackPoint& q : rec.track) {
    if (q.ball != ball) continue;
    b.t.push_back(q.t_s);
    b.p.push_back(q.xy);
  }
  return b;
}

// The tracker's noise on a coordinate, from uneven steps: an inner point's distance from the
// line through its two neighbours (taken at its time, with weights wa and wb on them) has
// variance sigma^2 (1 + wa^2 + wb^2) where the ball's acceleration is small; the median of
// the distances so normalised, over the normal distribution's 0.6745, estimates sigma (at
// least 10 um). Most of a track rolls, so a slide's curvature barely moves the median.
double UnevenNoise(const BallTrack& b) {
  std::vector<double> e;
  for (size_t j = 1; j + 1 < b.t.size(); ++j) {
    const double span = b.t[j + 1] - b.t[j - 1];
    if (!(span > 0.0)) continue;
    const double wa = (b.t[j + 1] - b.t[j]) / span, wb = (b.t[j] - b.t[j - 1]) / span;
    const Eigen::Vector2d d = b.p[j] - (wa * b.p[j - 1] + wb * b.p[j + 1]);
    const double norm = std::sqrt(1.0 + wa * wa + wb * wb);
    e.push_back(std::abs(d.x()) / norm);
    e.push_back(std::abs(d.y()) / norm);
  }
  return std::max(1e-5, Median(std::move(e)) / 0.6745);
}

// Between two contacts a ball slides at a constant acceleration a until its slip vanishes,
// at time c, then rolls at a constant acceleration r. With u the time from the stretch's first
// point, each coordinate is p0 + v0 u + a A(u) + r B(u), where A = u^2/2 before c and
// c u - c^2/2 after it, B = 0 before c and (u - c)^2/2 after it: position and velocity
// continuous at c, and linear in (p0, v0, a, r) for a given c. c = 0 rolls throughout (A = 0);
// c = infinity slides throughout (B = 0).
Eigen::Vector4d SlideRollBasis(double u, double c) {
  if (u < c) return {1.0, u, 0.5 * u * u, 0.0};
  return {1.0, u, c * u - 0.5 * c * c, 0.5 * (u - c) * (u - c)};
}

// The fit of both coordinates for one c, grown a point at a time by Givens rotations: the
// triangular factor of the basis, the rotated positions, and the residual sum of squares the
// rotations leave (positions from the first point's). Stable where the normal equations are
// not: a 30 s window's squared positions are 10^10 times its residuals. A coefficient no
// point informs yet (r before c) stays zero.
struct SlideRollSums {
  double c = 0.0;
  Eigen::Matrix4d r = Eigen::Matrix4d::Zero();
  Eigen::Matrix<double, 4, 2> z = Eigen::Matrix<double, 4, 2>::Zero();
  double ssr = 0.0;
  void Add(double u, const Eigen::Vector2d& q) {
    Eigen::Vector4d phi = SlideRollBasis(u, c);
    Eigen::Vector2d y = q;
    for (int i = 0; i < 4; ++i) {
      if (phi(i) == 0.0) continue;
      const double h = std::hypot(r(i, i), phi(i));
      const double cs = r(i, i) / h, sn = phi(i) / h;
      for (int j = i; j < 4; ++j) {
        const double top = r(i, j), row = phi(j);
        r(i, j) = cs * top + sn * row;
        phi(j) = cs * row - sn * top;
      }
      for (int k = 0; k < 2; ++k) {
        const double top = z(i, k), row = y(k);
        z(i, k) = cs * top + sn * row;
        y(k) = cs * row - sn * top;
      }
    }
    ssr += y.squaredNorm();
  }
  // The coefficients (p0, v0, a, r; a column each coordinate), by back substitution; zero
  // where the factor's diagonal is (nothing informs that coefficient).
  Eigen::Matrix<double, 4, 2> Coefficients() const {
    Eigen::Matrix<double, 4, 2> coef = Eigen::Matrix<double, 4, 2>::Zero();
    const double tiny = 1e-12 * r.diagonal().cwiseAbs().maxCoeff();
    for (int i = 3; i >= 0; --i) {
      if (!(std::abs(r(i, i)) > tiny)) continue;
      Eigen::RowVector2d rhs = z.row(i);
      for (int j = i + 1; j < 4; ++j) rhs -= r(i, j) * coef.row(j);
      coef.row(i) = rhs / r(i, i);
    }
    return coef;
  }
  // The residual sum of squares; infinity for a split whose slide is no slide (its
  // acceleration outside kSlidingMinAccel-kSlidingMaxAccel): a ball between contacts slides
  // at mu_slide g, and a window that only rolls is the split at 0.
  double Residual() const {
    if (c > 0.0 && std::isfinite(c)) {
      const double slide = Coefficients().row(2).norm();
      if (slide < kSlidingMinAccel || slide > kSlidingMaxAccel) {
        return std::numeric_limits<double>::infinity();
      }
    }
    return ssr;
  }
};

// Fewest points a stretch's fit takes (8 coefficients and c), the longest a window grows (s),
// the longest slide it looks for (s: a slip of 13 m/s on a 0.2 cloth), and the finest step
// between the roll's start times it tries (s).
constexpr int kStretchMinPoints = 8;
constexpr double kStretchMaxS = 30.0;
constexpr double kMaxSlideS = 2.0;
constexpr double kRollStartStepS = 0.005;

// Whether m points' residual sum of squares (both coordinates) is the noise's: within 5
// standard deviations of its chi-square mean, with 2 m - 9 degrees of freedom, and 10 % over
// it for the noise's own estimate (a median of a few thousand distances, good to 3 % or so,
// which a thousand points' sum doubles and no longer hides). The window is tested at every
// point it grows by, a thousand times over a long roll, and at 3 standard deviations the
// noise alone ends one in ten of them.
bool FitsNoise(double ssr, int m, double sigma) {
  const double dof = 2.0 * m - 9.0;
  return ssr <= sigma * sigma * (1.1 * dof + 5.0 * std::sqrt(2.0 * dof));
}

// The points a window's newest residuals are tested over, and their bound (in squared noise,
// both coordinates: a chi-square of 10 passes 40 once in 60,000). A contact shows first
// there: a jump of 5 cm/s moves the next five points by 1 to 5 mm at 50 Hz, which a long
// window's whole sum would take many more points to notice.
constexpr int kTailPoints = 5;
constexpr double kTailBound = 40.0;

// The sums of points lo..hi for the roll from c (from point lo).
SlideRollSums SumsOver(const BallTrack& b, int lo, int hi, double c) {
  const size_t ulo = static_cast<size_t>(lo);
  SlideRollSums sums{.c = c};
  for (size_t j = ulo; j <= static_cast<size_t>(hi); ++j) {
    sums.Add(b.t[j] - b.t[ulo], b.p[j] - b.p[ulo]);
  }
  return sums;
}

// The roll's start c (from point lo) refined between the steps beside the one it falls in, by
// golden section on the residual: a start half a 50 Hz step off moves a 2 m/s^2 slide's
// positions by a tenth of a millimetre, as much as a good tracker's noise.
double RefineRollStart(const BallTrack& b, int lo, int hi, double c) {
  if (!(c > 0.0) || !std::isfinite(c)) return c;
  const double t0 = b.t[static_cast<size_t>(lo)];
  int j = lo;
  while (j + 1 < hi && b.t[static_cast<size_t>(j + 1)] - t0 < c) ++j;
  double x0 = b.t[static_cast<size_t>(std::max(lo, j - 1))] - t0;
  double x1 = b.t[static_cast<size_t>(std::min(hi, j + 2))] - t0;
  const auto f = [&](double x) { return SumsOver(b, lo, hi, x).Residual(); };
  constexpr double kGolden = 0.6180339887498949;
  double a = x1 - kGolden * (x1 - x0), bb = x0 + kGolden * (x1 - x0);
  double fa = f(a), fb = f(bb);
  for (int it = 0; it < 30; ++it) {
    if (fa <= fb) {
      x1 = bb;
      bb = a;
      fb = fa;
      a = x1 - kGolden * (x1 - x0);
      fa = f(a);
    } else {
      x0 = a;
      a = bb;
      fa = fb;
      bb = x0 + kGolden * (x1 - x0);
      fb = f(bb);
    }
  }
  const double best = fa <= fb ? a : bb;
  return std::min(fa, fb) <= f(c) ? best : c;
}

// The far end of the longest window from point `from` whose points fit one slide and roll
// within the noise, and in *roll_from the best start of its roll (from the window's first
// point); -1 when not even its first kStretchMinPoints do. The roll's start is tried at 0, in
// the middle of every step within kMaxSlideS (its best is within half a step, and a slide's
// last 10 ms move a ball by a tenth of a millimetre), and past the end.
int GrowStretch(const BallTrack& b, int from, double sigma, double* roll_from) {
  const int n = static_cast<int>(b.t.size());
  const double t0 = b.t[static_cast<size_t>(from)];
  const Eigen::Vector2d p0 = b.p[static_cast<size_t>(from)];
  SlideRollSums sliding{.c = std::numeric_limits<double>::infinity()};
  std::vector<SlideRollSums> splits = {SlideRollSums{.c = 0.0}};
  double last_grid = 0.0;  // the latest start on the grid
  int last = -1;
  for (int k = from; k < n; ++k) {
    const size_t uk = static_cast<size_t>(k);
    const double u = b.t[uk] - t0;
    if (u > kStretchMaxS) break;
    if (k > from) {
      // A roll starting within the last step: every earlier point slid, as in `sliding`.
      const double c = 0.5 * (b.t[uk - 1] - t0 + u);
      if (c <= kMaxSlideS && c - last_grid >= kRollStartStepS) {
        splits.push_back(sliding);
        splits.back().c = c;
        last_grid = c;
      }
    }
    const Eigen::Vector2d q = b.p[uk] - p0;
    sliding.Add(u, q);
    for (SlideRollSums& s : splits) s.Add(u, q);
    const int m = k - from + 1;
    if (m < kStretchMinPoints) continue;
    const SlideRollSums* best = &sliding;
    double ssr = sliding.Residual();
    for (const SlideRollSums& s : splits) {
      if (const double r = s.Residual(); r < ssr) {
        ssr = r;
        best = &s;
      }
    }
    if (!FitsNoise(ssr, m, sigma) && best->c > 0.0 && std::isfinite(best->c)) {
      // The grid's best start may be off by up to half a step, which over a long roll the
      // noise no longer hides: refined, it joins the starts tried from here on.
      SlideRollSums refined = SumsOver(b, from, k, RefineRollStart(b, from, k, best->c));
      if (const double r = refined.Residual(); r < ssr) {
        ssr = r;
        splits.push_back(std::move(refined));
        best = &splits.back();
      }
    }
    if (!FitsNoise(ssr, m, sigma)) break;
    if (m >= 2 * kTailPoints) {
      const Eigen::Matrix<double, 4, 2> coef = best->Coefficients();
      double tail = 0.0;
      for (int j = k - kTailPoints + 1; j <= k; ++j) {
        const size_t uj = static_cast<size_t>(j);
        const Eigen::Vector2d fit = coef.transpose() * SlideRollBasis(b.t[uj] - t0, best->c);
        tail += (b.p[uj] - p0 - fit).squaredNorm();
      }
      if (tail > kTailBound * sigma * sigma) break;
    }
    last = k;
    *roll_from = best->c;
  }
  return last;
}

// The fit over points lo..hi with the roll from c (from point lo), read as a stretch. The
// standard errors come from the Jacobian of all nine coefficients, c with them (a slide's end
// and its acceleration trade off against each other), at the noise.
TrackedStretch DescribeStretch(const BallTrack& b, int ball, int lo, int hi, double c,
                               double sigma) {
  c = RefineRollStart(b, lo, hi, c);
  const size_t ulo = static_cast<size_t>(lo), uhi = static_cast<size_t>(hi);
  const Eigen::Matrix<double, 4, 2> coef = SumsOver(b, lo, hi, c).Coefficients();
  const Eigen::Vector2d v0 = coef.row(1).transpose();
  const Eigen::Vector2d slide = coef.row(2).transpose();
  const Eigen::Vector2d roll = coef.row(3).transpose();
  // The Jacobian's columns: x's p0, v0, a, r; y's; then c. Its normal matrix is summed a row
  // at a time, and the covariance is sigma^2 (J'J)^+, which is J^+ J^+' where the columns are
  // independent (a stretch long enough to be read). J^+ itself, as Eigen forms it, goes
  // through a square identity of J's rows: a 30 s window at 500 Hz has 30,000 of them, 7 GB;
  // 250 Hz shots took 240 us a point to read, where they take 21 now (`BM_ReadCloth`). The
  // columns are scaled to unit length first: a window's u^2 terms are a thousand times its
  // constant ones.
  Eigen::Matrix<double, 9, 9> normal = Eigen::Matrix<double, 9, 9>::Zero();
  for (size_t j = ulo; j <= uhi; ++j) {
    const double u = b.t[j] - b.t[ulo];
    const Eigen::Vector4d phi = SlideRollBasis(u, c);
    const double after = u >= c ? u - c : 0.0;
    for (int axis = 0; axis < 2; ++axis) {
      Eigen::Matrix<double, 9, 1> row = Eigen::Matrix<double, 9, 1>::Zero();
      row.segment<4>(4 * axis) = phi;
      row(8) = (slide(axis) - roll(axis)) * after;
      normal.noalias() += row * row.transpose();
    }
  }
  Eigen::Matrix<double, 9, 1> scale;
  for (int k = 0; k < 9; ++k) scale(k) = normal(k, k) > 0.0 ? 1.0 / std::sqrt(normal(k, k)) : 1.0;
  const Eigen::Matrix<double, 9, 9> scaled = scale.asDiagonal() * normal * scale.asDiagonal();
  const Eigen::Matrix<double, 9, 9> pinv = scaled.completeOrthogonalDecomposition().pseudoInverse();
  const Eigen::Matrix<double, 9, 9> cov =
      sigma * sigma * (scale.asDiagonal() * pinv * scale.asDiagonal());
  // The variance of a vector coefficient's part along a unit direction.
  const auto along_var = [&](int index, const Eigen::Vector2d& dir) {
    Eigen::Matrix2d block;
    block << cov(index, index), cov(index, index + 4), cov(index + 4, index),
        cov(index + 4, index + 4);
    return std::max(0.0, dir.dot(block * dir));
  };
  TrackedStretch s;
  s.ball = ball;
  s.t0_s = b.t[ulo];
  s.t1_s = b.t[uhi];
  s.points = hi - lo + 1;
  const double span = s.t1_s - s.t0_s;
  const double slide_s = std::min(c, span);
  s.roll_from_s = s.t0_s + c;
  for (size_t j = ulo; j <= uhi && b.t[j] - b.t[ulo] < c; ++j) ++s.slide_points;
  s.v0_mps = v0.norm();
  const Eigen::Vector2d v_roll = v0 + slide * slide_s;
  s.v_roll_mps = v_roll.norm();
  s.v1_mps = (v_roll + roll * (span - slide_s)).norm();
  s.slide_mps2 = slide.norm();
  if (s.slide_mps2 > 0.0) s.slide_se_mps2 = std::sqrt(along_var(2, slide.normalized()));
  if (v_roll.norm() > 0.0) {
    const Eigen::Vector2d along = v_roll.normalized();
    s.roll_decel_mps2 = -roll.dot(along);
    s.roll_lateral_mps2 = along.x() * roll.y() - along.y() * roll.x();
    s.roll_se_mps2 = std::sqrt(along_var(3, along));
  }
  const int roll_points = s.points - s.slide_points;
  s.slide_read = slide_s >= 0.1 && s.slide_points >= 6 && s.slide_mps2 >= kSlidingMinAccel &&
                 s.slide_mps2 <= kSlidingMaxAccel;
  s.roll_read = span - slide_s >= 0.4 && roll_points >= 10 && roll.norm() <= kRollingMaxAccel &&
                s.roll_decel_mps2 > 0.0 && s.v_roll_mps >= 0.05;
  return s;
}

// The q-quantile of a list, linear between order statistics (0 when empty).
double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

// TrackedStretches, polling `cancelled` (may be null) before each window: nullopt when it
// says so.
std::optional<std::vector<TrackedStretch>> StretchesOf(const Recording& recording, int ball,
                                                       const std::function<bool()>* cancelled) {
  if (ball < 0 || ball >= static_cast<int>(recording.initial.balls.size())) {
    return std::vector<TrackedStretch>{};
  }
  const BallTrack b = TrackOf(recording, ball);
  const int n = static_cast<int>(b.t.size());
  if (n < kStretchMinPoints) return std::vector<TrackedStretch>{};
  const double sigma = UnevenNoise(b);
  std::vector<TrackedStretch> out;
  int i = 0;
  while (i + kStretchMinPoints <= n) {
    if (cancelled != nullptr && (*cancelled)()) return std::nullopt;
    double c = 0.0;
    const int k = GrowStretch(b, i, sigma, &c);
    if (k < 0) {
      ++i;
      continue;
    }
    out.push_back(DescribeStretch(b, ball, i, k, c, sigma));
    i = k + 1;
  }
  return out;
}

}  // namespace

std::vector<TrackedStretch> TrackedStretches(const Recording& recording, int ball) {
  return *StretchesOf(recording, ball, nullptr);
}

ClothReading ReadCloth(std::span<const Recording> recordings, double gravity_mps2) {
  return *ReadClothOf(recordings, {}, gravity_mps2, {});
}

namespace {

// ReadCloth over the recordings not skipped (skip[i]; none when `skip` is empty), polling
// `cancelled` (may be empty) between windows: Cancelled when it says so.
absl::StatusOr<ClothReading> ReadClothOf(std::span<const Recording> recordings,
                                         const std::vector<bool>& skip, double gravity_mps2,
                                         const std::function<bool()>& cancelled) {
  std::vector<double> roll, slide;
  for (size_t i = 0; i < recordings.size(); ++i) {
    if (i < skip.size() && skip[i]) continue;
    const Recording& rec = recordings[i];
    for (int ball = 0; ball < static_cast<int>(rec.initial.balls.size()); ++ball) {
      std::optional<std::vector<TrackedStretch>> stretches =
          StretchesOf(rec, ball, cancelled ? &cancelled : nullptr);
      if (!stretches) return absl::CancelledError("calibration cancelled");
      for (const TrackedStretch& s : *stretches) {
        if (s.roll_read) roll.push_back(s.roll_decel_mps2 / gravity_mps2);
        if (s.slide_read) slide.push_back(s.slide_mps2 / gravity_mps2);
      }
    }
  }
  ClothReading r;
  r.rolling = static_cast<int>(roll.size());
  r.sliding = static_cast<int>(slide.size());
  r.mu_roll = Quantile(roll, 0.5);
  r.mu_roll_q1 = Quantile(roll, 0.25);
  r.mu_roll_q3 = Quantile(roll, 0.75);
  r.mu_slide = Quantile(slide, 0.5);
  r.mu_slide_q1 = Quantile(slide, 0.25);
  r.mu_slide_q3 = Quantile(slide, 0.75);
  return r;
}

// Each constant read by enough stretches is taken, within its bounds where it is fitted (a
// fit must start inside them) and its allowed range otherwise.
ClothTaken TakeCloth(const TableSpec& spec, const std::vector<Fitted>& fitted,
                     const ClothReading& reading) {
  ClothTaken t{.reading = reading,
               .mu_roll_before = spec.params.mu_roll,
               .mu_slide_before = spec.params.mu_slide,
               .mu_roll = spec.params.mu_roll,
               .mu_slide = spec.params.mu_slide};
  const auto within = [&](double PhysicsParams::*field, double v) {
    for (const Fitted& f : fitted) {
      if (f.info->field == field) return std::clamp(v, f.lo, f.hi);
    }
    for (const ParamInfo& i : ParamInfos()) {
      if (i.field == field) return std::clamp(v, i.lo, i.hi);
    }
    return v;
  };
  if (reading.rolling >= kClothMinStretches) {
    t.mu_roll_taken = true;
    t.mu_roll = within(&PhysicsParams::mu_roll, reading.mu_roll);
  }
  if (reading.sliding >= kClothMinStretches) {
    t.mu_slide_taken = true;
    t.mu_slide = within(&PhysicsParams::mu_slide, reading.mu_slide);
  }
  return t;
}

}  // namespace

absl::StatusOr<Recording> SyntheticRecording(const TableModel& model, const SolverOptions& solver,
                                             const TableState& initial, int cue,
                                             const CueStrike& strike,
                                             const SyntheticOptions& options) {
  if (!(options.rate_hz >= 1.0 && options.rate_hz <= 10000.0)) {
    return absl::InvalidArgumentError("rate_hz must be in [1, 10000]");
  }
  if (!(options.noise_m >= 0.0 && options.noise_m <= 1.0)) {
    return absl::InvalidArgumentError("noise_m must be in [0, 1] m");
  }
  if (!(options.max_s > 0.0 && options.max_s <= kMaxTrackTime)) {
    return absl::InvalidArgumentError(absl::StrFormat("max_s must be in (0, %g] s", kMaxTrackTime));
  }
  if (!(options.strike_time_s >= 0.0 && options.strike_time_s < options.max_s)) {
    return absl::InvalidArgumentError("strike_time_s must be in [0, max_s)");
  }
  if (!(options.false_detections >= 0.0 && options.false_detections <= 1.0)) {
    return absl::InvalidArgumentError("false_detections must be in [0, 1]");
  }
  Recording rec;
  rec.initial = initial;
  rec.initial.t_s = 0.0;
  rec.cue = cue;
  if (options.keep_strike) rec.strike = strike;
  rec.strike_time_s = options.keep_strike || options.keep_strike_time
                          ? std::optional<double>(options.strike_time_s)
                          : std::nullopt;
  TableState state = rec.initial;
  absl::StatusOr<StrikeOutcome> struck = ApplyStrike(model, solver.effects, strike, cue, &state);
  if (!struck.ok()) return struck.status();
  std::vector<Event> events;
  absl::StatusOr<std::unique_ptr<TableSimulation>> sim =
      TableSimulation::Create(model, solver, std::move(state), &events);
  if (!sim.ok()) return sim.status();
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  // False detections from their own generator, so that the noise is the same with or without.
  std::mt19937_64 false_rng(options.seed ^ 0x5eed'fa15'e0de'7ec7ULL);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Eigen::Vector2d area(model.spec().length_m, model.spec().width_m);
  for (int64_t k = 1;; ++k) {
    const double t = static_cast<double>(k) / options.rate_hz;
    if (t > options.max_s) break;
    const bool started = t >= options.strike_time_s;
    if (started) {
      events.clear();
      if (absl::Status s = (*sim)->AdvanceTo(t - options.strike_time_s, &events); !s.ok()) return s;
    }
    const TableState& now = started ? (*sim)->state() : rec.initial;
    for (size_t b = 0; b < now.balls.size(); ++b) {
      if (now.balls[b].pocket >= 0) continue;
      TrackPoint p{.t_s = t, .ball = static_cast<int>(b), .xy = now.balls[b].r.head<2>()};
      if (options.noise_m > 0.0) {
        p.xy.x() += options.noise_m * noise(rng);
        p.xy.y() += options.noise_m * noise(rng);
      }
      if (options.false_detections > 0.0 && unit(false_rng) < options.false_detections) {
        const double fx = unit(false_rng) - 0.5;
        const double fy = unit(false_rng) - 0.5;
        p.xy = Eigen::Vector2d(fx, fy).cwiseProduct(area);
      }
      rec.track.push_back(p);
    }
    if (started && (*sim)->AtRest()) break;
  }
  return rec;
}

}  // namespace sportsim::billiards
