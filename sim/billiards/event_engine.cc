#include "sim/billiards/event_engine.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>

#include "absl/strings/str_format.h"
#include "sim/billiards/cloth.h"
#include "sim/billiards/collision.h"
#include "sim/core/poly_roots.h"

namespace sportsim::billiards {
namespace {

constexpr double kNever = std::numeric_limits<double>::infinity();
// A gap below this (m) counts as touching: frozen balls, a ball frozen to a cushion, and the
// rounding-level gaps a collision leaves. Half the smallest resting gap, so separated pairs
// are not.
constexpr double kTouchGap = 0.5 * kMinRestingGap;
// Sweeps over a touching group in one sustained contact (each sweep resolves every touching
// pair that approaches); a pair still approaching after them is handled as a next event.
constexpr int kSustainedSweeps = 32;
// The sweeps stop resolving a pair approaching slower than this (m/s): the resting gap opened
// after them (1 nm to 3 um) then takes 1 ms to 3 s to close at that speed, and the queue
// handles it if it does. (10 um/s, before the jam rule, let a snooker shot of the
// 10,000-shot test run to 18,890 events; with it, 10 um/s would save 6 % of the storm batch's
// work, but a slow push into a frozen line would end more than 1 % off its closed form,
// v / 5 each: its test fails.)
constexpr double kSweepApproach = 1e-6;
// Nor one approaching slower than this fraction of the approach of the pair that started the
// group (the velocities settle to 0.1 % of it; 1 % leaves a slow push into a frozen line more
// than 1 % off v / 5 each). Since the sweeps are over-relaxed, looser settling saves nothing
// (3e-3 or 1e-2 of the starting approach, or 3 um/s: within 1 % of the batch's work).
constexpr double kSweepSettle = 1e-3;
// The sweeps' over-relaxation: each pair they resolve gets this times the plastic impulse,
// parting at 0.3 times its approach (the pair that starts the group gets the plastic one).
// Sequential plastic impulses on a group's contacts converge like Gauss-Seidel on a chain's:
// the approaches left fall by cos^2(pi / n) a sweep for n balls in a line (0.5 for four: 10
// sweeps to settle), and successive over-relaxation with w near 2 / (1 + sin(pi / n)) (Young,
// "Iterative methods for solving partial difference equations of elliptic type", Trans. AMS
// 76, 1954) cuts the sweeps by about three. Unlike projected SOR (Cryer, SIAM J. Control 9,
// 1971) no impulse is ever taken back: the sweeps add impulse to approaching pairs only, so
// they end with pairs parting at up to w - 1 of their last approach, a restitution of w - 1 in
// place of the exact plastic solution (which plain Gauss-Seidel reaches no better within its
// settling threshold). The optimum w is 1.26 for five balls and 1.45 for eight; 1.3 takes 14 %
// off the storm batch's work, and a slow push into a frozen line of five ends closer to its
// closed form than without (0.9 % against 1.5 %). 1.5 overshoots there (the pairs part by
// more than the sweeps then close). Every resolution still only removes energy.
constexpr double kSweepRelaxation = 1.3;
// Gauss-Seidel passes that open the resting gaps inside a group.
constexpr int kGapPasses = 8;
// A resting gap short of its size by less than a quarter of it is left as it is: a shorter gap only re-forms sooner and slower (still plastic), and the
// passes converge geometrically (a ball between two halves what is left of both gaps each
// pass), so chasing the rest ran most groups to the pass limit.
constexpr double kGapShortfall = 0.25;
// The gap passes check a move against the balls within this (m) of contact: moves are mostly
// resting gaps (at most kSustainedRestingGap each), so a list stays good for several (its
// validity is judged by the lengths of the moves made, whatever they are).
constexpr double kNearSlack = 4 * kSustainedRestingGap;

// The resting gap for a contact the cloth closes at `closing` m/s^2: re-forming from it, the
// approach speed sqrt(2 closing gap) stays at 0.9 `plastic` or below (`plastic`: the speed
// below which the contact is plastic again, kRestingContactSpeed or, inside a train of a
// sustained contact, kTrainContactSpeed).
double RestingGap(double closing, double largest, double plastic = kRestingContactSpeed) {
  if (!(closing > 0.0)) return largest;
  const double v = 0.9 * plastic;
  return std::clamp(v * v / (2.0 * closing), kMinRestingGap, largest);
}

// Kinds in tie-break order: at equal times collisions come first, then captures, then
// transitions (the order of EventKind).
enum class Kind : uint8_t { kBall = 0, kCushion = 1, kPocket = 2, kTransition = 3 };

// A predicted event. For kBall a < b; `other` is the cushion segment, the pocket (-1: leaving
// the table) or the TransitionKind. Versions make it stale once either ball's trajectory changes.
struct Pending {
  double t = kNever;
  Kind kind = Kind::kTransition;
  int a = -1, b = -1, other = -1;
  uint32_t va = 0, vb = 0;

  bool found() const { return t < kNever; }
  bool Before(const Pending& o) const {  // (t, kind, a, b, other) lexicographically
    if (t != o.t) return t < o.t;
    if (kind != o.kind) return kind < o.kind;
    if (a != o.a) return a < o.a;
    if (b != o.b) return b < o.b;
    return other < o.other;
  }
};
// A ball's motion since its last event: constant accelerations from (t0, r0, v0, w0).
struct Trajectory {
  double t0 = 0.0;
  Eigen::Vector2d r0 = Eigen::Vector2d::Zero();
  Eigen::Vector2d v0 = Eigen::Vector2d::Zero();
  Eigen::Vector2d a = Eigen::Vector2d::Zero();  // zero unless translating
  Eigen::Vector3d w0 = Eigen::Vector3d::Zero();
  Eigen::Vector3d alpha = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q0 = Eigen::Quaterniond::Identity();
  MotionState state = MotionState::kStationary;
  double t_next = kNever;  // the next transition (absolute time)
  TransitionKind next_kind = TransitionKind::kNone;
  // Where the path goes from its origin to its next transition (the whole plane when that is
  // beyond the prediction horizon): the pairs' broad phase (a ball at rest: its position).
  Eigen::Vector2d lo = Eigen::Vector2d::Zero(), hi = Eigen::Vector2d::Zero();
  // lo, hi are the path's box from t0 to its next transition exactly as Predict would make it
  // at t0 (not moved since, and the transition within the prediction horizon).
  bool box_at_t0 = false;
  uint32_t version = 0;
  bool fixed_axis = true;  // the spin axis does not turn: orientation in closed form
  // Orientation at t0 + q_k * q_piece (a cache of a pure function of the segment).
  double q_piece = 0.0;
  int64_t q_k = 0;
  Eigen::Quaterniond q_cached = Eigen::Quaterniond::Identity();
};

Eigen::Quaterniond RotationFromVector(const Eigen::Vector3d& rot) {
  const double angle = rot.norm();
  if (angle == 0.0) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, rot / angle));
}

// The same for the small rotations of orientation pieces (|rot| <= ~0.25 rad): exp of the
// quaternion by its series, no trigonometry. For half-angle x <= 0.125 the first omitted terms
// (x^10 / 10!, x^10 / 11!) are below 1e-15, so the result is unit to rounding.
Eigen::Quaterniond SmallRotation(const Eigen::Vector3d& rot) {
  const double x2 = 0.25 * rot.squaredNorm();  // (angle / 2)^2
  if (x2 > 0.015625) return RotationFromVector(rot);
  const double c = 1.0 - x2 / 2 * (1.0 - x2 / 12 * (1.0 - x2 / 30 * (1.0 - x2 / 56)));
  const double s = 0.5 * (1.0 - x2 / 6 * (1.0 - x2 / 20 * (1.0 - x2 / 42 * (1.0 - x2 / 72))));
  return Eigen::Quaterniond(c, s * rot.x(), s * rot.y(), s * rot.z());
}

// A touching contact (gap below kTouchGap) with normal approach speed `approach` and
// `closing`, minus the gap's second derivative: handled now when approaching, or when not
// moving apart while the cloth closes it (a resting push). Otherwise it is predicted later.
bool TouchingContactNow(double approach, double closing) {
  return approach > kMinApproachSpeed || (approach > -kMinApproachSpeed && closing > 0.0);
}

// Axis-aligned box of a path p + v s + a s^2 / 2 over s in [0, S].
struct Box {
  Eigen::Vector2d lo, hi;
};
Box PathBox(const Eigen::Vector2d& p, const Eigen::Vector2d& v, const Eigen::Vector2d& a,
            double S) {
  Box box{p, p};
  const Eigen::Vector2d end = p + S * (v + 0.5 * S * a);
  box.lo = box.lo.cwiseMin(end);
  box.hi = box.hi.cwiseMax(end);
  for (int k = 0; k < 2; ++k) {
    // The turning point s = -v / a, where it lies inside (0, S): v and a of opposite signs and
    // |v| < |a| S (tested without the division).
    if (v[k] * a[k] < 0.0 && std::abs(v[k]) < std::abs(a[k]) * S) {
      const double s = -v[k] / a[k];
      const double x = p[k] + s * (v[k] + 0.5 * s * a[k]);
      box.lo[k] = std::min(box.lo[k], x);
      box.hi[k] = std::max(box.hi[k], x);
    }
  }
  return box;
}
// Do the boxes overlap (edges included)?
// The box tests compare without a branch each (& on the comparisons, one branch at the use):
// their outcomes are data-dependent, and a chain of && mispredicts often.
bool Overlaps(const Box& a, const Box& b) {
  return (a.lo.x() <= b.hi.x()) & (a.hi.x() >= b.lo.x()) & (a.lo.y() <= b.hi.y()) &
         (a.hi.y() >= b.lo.y());
}
// Is the box inside `region` (edges included)?
bool Within(const Box& box, const Box& region) {
  return box.lo.x() >= region.lo.x() && box.hi.x() <= region.hi.x() &&
         box.lo.y() >= region.lo.y() && box.hi.y() <= region.hi.y();
}
// Does the box come within `reach` of the point p (per axis)?
bool Near(const Box& box, const Eigen::Vector2d& p, double reach) {
  return (box.lo.x() <= p.x() + reach) & (box.hi.x() >= p.x() - reach) &
         (box.lo.y() <= p.y() + reach) & (box.hi.y() >= p.y() - reach);
}

class EventSimulation final : public TableSimulation {
 public:
  EventSimulation(const TableModel& model, const SolverOptions& options, TableState initial)
      : model_(model),
        o_(options),
        state_(std::move(initial)),
        n_(static_cast<int>(state_.balls.size())),
        traj_(state_.balls.size()),
        best_(state_.balls.size()),
        t_(state_.t_s),
        gap_(options.resting_contacts == RestingContacts::kSustained ? kSustainedRestingGap
                                                                      : kRestingGap),
        d_(2.0 * model.radius()),
        dc_(model.cushion_contact_distance()),
        cushions_(model.spec().bounded && (options.effects & kEffectDisableCushions) == 0),
        pockets_(model.spec().bounded && (options.effects & kEffectDisablePockets) == 0),
        orientation_((options.effects & kEffectDisableOrientation) == 0),
        half_(0.5 * model.spec().length_m + model.radius(),
              0.5 * model.spec().width_m + model.radius()) {
    resting_.resize(state_.balls.size());
    reach_.resize(state_.balls.size());
    candidates_.resize(state_.balls.size());
    memo_.resize(state_.balls.size() * state_.balls.size());
    last_plastic_.assign(memo_.size(), -kNever);
    jammed_at_.assign(memo_.size(), -kNever);
    slot_of_.assign(state_.balls.size(), -1);
    for (const CushionSegment& seg : model.spec().cushions) {
      const Eigen::Vector2d lo = seg.a.cwiseMin(seg.b), hi = seg.a.cwiseMax(seg.b);
      cushion_reach_.push_back(Box{lo.array() - dc_, hi.array() + dc_});
    }
    if (model.spec().bounded) clear_ = ClearOfTheRails();  // from cushion_reach_
    for (int i = 0; i < n_; ++i) SetOrigin(i, state_.balls[i], t_);
    // A ball at rest has no event of its own, and every contact it can have is with a moving
    // ball, whose prediction finds it: only the moving balls are predicted at the start.
    for (int i = 0; i < n_; ++i) {
      if (traj_[i].state != MotionState::kStationary) Predict(i);
    }
  }

  absl::Status AdvanceTo(double t_end, std::vector<Event>* events) override {
    if (!(std::isfinite(t_end) && t_end >= t_)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "t_end_s must be finite and not before the table's time %g s, got %g", t_, t_end));
    }
    for (int next = Next(); next >= 0 && best_[next].t <= t_end; next = Next()) {
      const Pending e = best_[next];
      if (!Current(e)) {  // never expected (a ball's change re-predicts its partners)
        Predict(next);
        continue;
      }
      if (++processed_ > o_.max_events) {
        return absl::ResourceExhaustedError(absl::StrFormat(
            "event cap of %d reached at t = %.9f s (next: %s of ball %s%s): a runaway, or raise "
            "max_events",
            o_.max_events, e.t, EventKindName(static_cast<EventKind>(e.kind)),
            state_.balls[e.a].id,
            e.b >= 0 ? " and ball " + state_.balls[e.b].id : std::string()));
      }
      t_ = e.t;
      dirty_ = true;
      if (absl::Status s = Handle(e, events); !s.ok()) return s;
    }
    t_ = t_end;
    dirty_ = true;
    return absl::OkStatus();
  }

  const TableState& state() override {
    if (dirty_) {
      for (int i = 0; i < n_; ++i) Eval(i, t_, &state_.balls[i]);
      state_.t_s = t_;
      dirty_ = false;
    }
    return state_;
  }

  double time() const override { return t_; }

  bool AtRest() const override {
    for (const Trajectory& tr : traj_) {
      if (tr.state != MotionState::kStationary && tr.state != MotionState::kPocketed) {
        return false;
      }
    }
    return true;
  }

  int64_t events_processed() const override { return processed_; }
  const EventEngineCounts& counts() const { return counts_; }

 private:
  // --- Trajectories ------------------------------------------------------------------------

  // Starts ball i's new trajectory at time t from its state `b`.
  void SetOrigin(int i, const Ball& b, double t) {
    Trajectory& tr = traj_[i];
    tr.t0 = t;
    tr.r0 = b.r.head<2>();
    tr.v0 = b.v.head<2>();
    tr.w0 = b.w;
    tr.q0 = b.q;
    tr.state = b.state;
    tr.a.setZero();
    tr.alpha.setZero();
    tr.t_next = kNever;
    tr.next_kind = TransitionKind::kNone;
    if (IsMoving(b.state)) {
      Rates rates;
      const NextTransition next = TimeToTransition(model_, o_.effects, b, &rates);
      if (IsTranslating(b.state)) tr.a = rates.dv.head<2>();
      if (b.state == MotionState::kSpinning) tr.v0.setZero();
      tr.alpha = rates.dw;
      if (next.kind != TransitionKind::kNone) {
        tr.t_next = t + next.dt_s;
        tr.next_kind = next.kind;
      }
    } else {
      tr.v0.setZero();
      if (b.state == MotionState::kStationary) tr.w0.setZero();
    }
    // How OrientationAt integrates (nothing to set up when the orientation is off).
    tr.fixed_axis = !orientation_ ||
                    tr.w0.cross(tr.alpha).norm() <= 1e-12 * tr.w0.norm() * tr.alpha.norm();
    if (!tr.fixed_axis) {
      // |w| is largest at an end of the segment (it is linear in time).
      const double span = std::min(tr.t_next, t + kPredictionHorizon) - t;
      const double w_max = std::max(tr.w0.norm(), (tr.w0 + span * tr.alpha).norm());
      tr.q_piece = std::clamp(kOrientationTurn / w_max, 1.0 / 8192.0, 1.0 / 16.0);
    }
    tr.q_k = 0;
    tr.q_cached = tr.q0;
    tr.lo = tr.hi = tr.r0;
    tr.box_at_t0 = false;
    if (IsTranslating(tr.state)) {
      if (tr.t_next <= t + kPredictionHorizon) {
        const Box box = PathBox(tr.r0, tr.v0, tr.a, tr.t_next - t);
        tr.lo = box.lo;
        tr.hi = box.hi;
        tr.box_at_t0 = true;
      } else {
        // The path outlasts the prediction horizon (no rolling resistance): predictions look
        // from later times, further along it, than one box from here could cover.
        tr.lo.setConstant(-kNever);
        tr.hi.setConstant(kNever);
      }
    }
    ++tr.version;
    SetReach(i);
  }

  // Ball i's entry in reach_ from its trajectory.
  void SetReach(int i) {
    const Trajectory& tr = traj_[i];
    const double r = d_ + kTouchGap + 1e-10;
    reach_[i] = Reach{.lo_x = tr.lo.x() - r, .hi_x = tr.hi.x() + r, .lo_y = tr.lo.y() - r,
                      .hi_y = tr.hi.y() + r, .translating = IsTranslating(tr.state)};
  }

  // Moves ball i's path (just started by SetOrigin) by `by`: a resting gap opened.
  void MoveOrigin(int i, const Eigen::Vector2d& by) {
    Trajectory& tr = traj_[i];
    tr.r0 += by;
    tr.lo += by;
    tr.hi += by;
    tr.box_at_t0 = false;  // moved: Predict's box from the new r0 rounds differently
    SetReach(i);
  }

  // (A ball that does not translate has v0 = a = 0 (SetOrigin): the same formulas give r0 (a
  // zero coordinate possibly +0 for -0) and zero, without a branch on its state.)
  Eigen::Vector2d PosAt(int i, double t) const {
    const Trajectory& tr = traj_[i];
    const double tau = t - tr.t0;
    return tr.r0 + tau * (tr.v0 + (0.5 * tau) * tr.a);
  }
  Eigen::Vector2d VelAt(int i, double t) const {
    const Trajectory& tr = traj_[i];
    return tr.v0 + (t - tr.t0) * tr.a;
  }

  // Orientation at tau after the segment start.
  Eigen::Quaterniond OrientationAt(Trajectory& tr, double tau) {
    if (!orientation_ || tau <= 0.0 || !IsMoving(tr.state)) return tr.q0;
    if (tr.fixed_axis) {
      // About a fixed axis the rotation is the integral of w: exact.
      return (RotationFromVector(tau * (tr.w0 + (0.5 * tau) * tr.alpha)) * tr.q0).normalized();
    }
    // w = w0 + alpha t turns: fourth-order Magnus per piece, Omega = h w(mid) +
    // (h^3 / 12) alpha x w0 (the commutator term of a linearly varying generator).
    const double h = tr.q_piece;
    const Eigen::Vector3d twist = tr.alpha.cross(tr.w0) / 12.0;
    const auto piece = [&](double t1, double t2) {
      const double len = t2 - t1;
      return SmallRotation(len * (tr.w0 + (0.5 * (t1 + t2)) * tr.alpha) +
                           (len * len * len) * twist);
    };
    const auto k = static_cast<int64_t>(std::floor(tau / h));
    if (k < tr.q_k) {
      tr.q_k = 0;
      tr.q_cached = tr.q0;
    }
    while (tr.q_k < k) {
      const double t1 = static_cast<double>(tr.q_k) * h;
      tr.q_cached = piece(t1, t1 + h) * tr.q_cached;  // unit to rounding: normalized below
      ++tr.q_k;
    }
    return (piece(static_cast<double>(k) * h, tau) * tr.q_cached).normalized();
  }

  // Ball i's state at time t (id and pocket untouched).
  void Eval(int i, double t, Ball* b) {
    Trajectory& tr = traj_[i];
    const double tau = t - tr.t0;
    const double radius = model_.radius();
    b->state = tr.state;
    b->r = Eigen::Vector3d(tr.r0.x(), tr.r0.y(), radius);
    b->v.setZero();
    b->w = tr.w0;
    if (IsTranslating(tr.state)) {
      const Eigen::Vector2d r = tr.r0 + tau * (tr.v0 + (0.5 * tau) * tr.a);
      const Eigen::Vector2d v = tr.v0 + tau * tr.a;
      b->r.head<2>() = r;
      b->v.head<2>() = v;
    }
    if (IsMoving(tr.state)) b->w = tr.w0 + tau * tr.alpha;
    b->q = OrientationAt(tr, tau);
  }

  // --- Prediction --------------------------------------------------------------------------

  // The index of the pair of balls i and j (either order) in the n x n per-pair arrays.
  size_t PairIndex(int i, int j) const {
    return static_cast<size_t>(std::min(i, j)) * n_ + std::max(i, j);
  }

  // The end of what can be predicted for ball i now.
  double Window(int i) const { return std::min(traj_[i].t_next, t_ + kPredictionHorizon); }

  // Whether balls i (its path within `box` from now) and j can meet at all: one of them
  // translates, and their path boxes come within contact (the margin covers touching pairs and
  // the rounding of boxes made from different origins). Taken before the pair's memo: most
  // balls rest most of the time, and most pairs are far apart.
  bool MayMeet(bool i_translating, const Box& box, int j) const {
    const Reach& r = reach_[j];
    return (i_translating | r.translating) & (box.lo.x() <= r.hi_x) & (box.hi.x() >= r.lo_x) &
           (box.lo.y() <= r.hi_y) & (box.hi.y() >= r.lo_y);
  }

  // Ball i (at P, V now) against ball j, a pair that MayMeet, looking at most `horizon` ahead.
  // `now_only`, when given, is set when the answer holds only at this instant: the pair was
  // touching, so what was found depends on how close it is now (the contact now, or a threshold
  // below 2R for a pair that overlaps by rounding).
  Pending PredictPair(int i, const Eigen::Vector2d& P, const Eigen::Vector2d& V, int j,
                      double horizon, bool* now_only = nullptr) const {
    const Trajectory& ti = traj_[i];
    const Trajectory& tj = traj_[j];
    Pending p{.kind = Kind::kBall, .a = std::min(i, j), .b = std::max(i, j)};
    p.va = traj_[p.a].version;
    p.vb = traj_[p.b].version;
    if (ti.state == MotionState::kPocketed || tj.state == MotionState::kPocketed) return p;
    const double S = std::min(horizon, Window(j) - t_);
    const Eigen::Vector2d dp = PosAt(j, t_) - P;
    const Eigen::Vector2d dv = VelAt(j, t_) - V;
    const Eigen::Vector2d da = tj.a - ti.a;
    const double dist = dp.norm();
    if (dist == 0.0) return p;
    const double gap = dist - d_;
    // No further cull by the relative path's box: a pair here passed MayMeet (the balls' own
    // boxes meet), the box culled only one in eight of these, and the Bernstein test of the
    // quartic below rejects those for less than the box cost the other seven. (Nor could it
    // apply to a touching pair: over a short horizon its box can stay clear of the contact
    // square, a pair lined up with an axis, while it touches and closes now.)
    if (gap < kTouchGap) {
      if (now_only != nullptr) *now_only = true;
      const Eigen::Vector2d n = dp / dist;
      const double approach = -dv.dot(n);
      const double closing = -da.dot(n) - (dv.squaredNorm() - approach * approach) / dist;
      if (TouchingContactNow(approach, closing)) {
        p.t = t_;
        return p;
      }
    }
    // A touching or overlapping pair that is not handled now (moving apart) makes contact
    // again when its distance falls below what it is now: a pair that starts overlapped and
    // turns back before the overlap opens must not pass through.
    const double d = gap < kTouchGap ? std::min(d_, dist) * (1.0 - 1e-12) : d_;
    const double c[5] = {(dist - d) * (dist + d), 2.0 * dv.dot(dp),
                         dv.squaredNorm() + da.dot(dp), da.dot(dv), 0.25 * da.squaredNorm()};
    double s = FirstDownCrossing(c, 4, 0.0, S);
    if (s == kNever) return p;
    // Polish on the distance itself: the squared form loses digits when the contact is
    // glancing (its slope 2 dr.dv is small against |dr|^2); |dr| - d does not.
    for (int it = 0; it < 2; ++it) {
      const Eigen::Vector2d r = dp + s * (dv + (0.5 * s) * da);
      const double rn = r.norm();
      const double slope = r.dot(dv + s * da) / rn;
      if (!(slope < 0.0)) break;
      const double next = s - (rn - d) / slope;
      if (!(std::abs(next - s) <= 1e-9 * (s + 1e-6)) || next < 0.0 || next > S) break;
      s = next;
    }
    p.t = t_ + s;
    return p;
  }

  // PredictPair through the pair's memo: a pair whose trajectories have not changed since it
  // was last predicted keeps its contact, or its absence up to where it was looked for (the
  // search is the same from either ball; only where it stops differs). A touching pair's
  // answer depends on the instant it was made, so it is not kept. A ball predicted after
  // its partner (the two balls of a collision, a group after a sustained contact, a ball whose
  // earliest event went stale) then solves only the pairs that changed.
  Pending PairEvent(int i, const Eigen::Vector2d& P, const Eigen::Vector2d& V, int j,
                    double horizon) {
    const int a = std::min(i, j), b = std::max(i, j);
    PairMemo& m = memo_[PairIndex(a, b)];
    const uint32_t va = traj_[a].version, vb = traj_[b].version;
    const double end = t_ + std::min(horizon, Window(j) - t_);
    if ((m.va == va) & (m.vb == vb) & (m.t >= t_) & ((m.t < kNever) | (m.until >= end))) {
      return Pending{.t = m.t, .kind = Kind::kBall, .a = a, .b = b, .va = va, .vb = vb};
    }
    bool now_only = false;
    const Pending p = PredictPair(i, P, V, j, horizon, &now_only);
    m = now_only ? PairMemo{} : PairMemo{.t = p.t, .until = end, .va = va, .vb = vb};
    return p;
  }

  // Ball i against cushion segment k, whose grown box (cushion_reach_) the path box `box`
  // meets: the caller culls.
  Pending PredictCushion(int i, int k, const Box& box, double S, const Eigen::Vector2d& P,
                         const Eigen::Vector2d& V, const Eigen::Vector2d& A) const {
    Pending p{.kind = Kind::kCushion, .a = i, .other = k, .va = traj_[i].version};
    const CushionSegment& seg = model_.spec().cushions[k];
    const Eigen::Vector2d e = seg.b - seg.a;
    const double len2 = e.squaredNorm();
    const double lambda0 = len2 > 0.0 ? (P - seg.a).dot(e) / len2 : 0.0;
    const bool at_end = lambda0 <= 0.0 || lambda0 >= 1.0;
    const Eigen::Vector2d near = ClosestOnSegment(seg.a, seg.b, P);
    const Eigen::Vector2d off = P - near;
    const double dist = off.norm();
    if (dist == 0.0) return p;
    const double gap = dist - dc_;
    if (gap < kTouchGap) {
      const Eigen::Vector2d n = off / dist;
      const double approach = -V.dot(n);
      const double closing =
          -A.dot(n) - (at_end ? (V.squaredNorm() - approach * approach) / dist : 0.0);
      if (TouchingContactNow(approach, closing)) {
        p.t = t_;
        return p;
      }
    }
    // As for ball pairs: a ball touching or inside the contact distance and moving away makes
    // contact again when its distance falls below what it is now.
    const double dc = gap < kTouchGap ? std::min(dc_, dist) * (1.0 - 1e-12) : dc_;
    double best = kNever;
    if (len2 > 0.0) {
      // The line part from either side: |h(s)| = dc with |h| falling, h the signed distance,
      // accepted where the contact point lies on the segment.
      const Eigen::Vector2d nn = Eigen::Vector2d(-e.y(), e.x()) / std::sqrt(len2);
      const double h0 = nn.dot(P - seg.a), h1 = nn.dot(V), h2 = 0.5 * nn.dot(A);
      for (const double side : {1.0, -1.0}) {
        const double c[3] = {side * h0 - dc, side * h1, side * h2};
        const double s = FirstDownCrossing(c, 2, 0.0, S);
        if (s >= best) continue;
        const Eigen::Vector2d at = P + s * (V + 0.5 * s * A);
        const double lambda = (at - seg.a).dot(e) / len2;
        if (lambda >= 0.0 && lambda <= 1.0) best = s;
      }
    }
    // The rounded ends. The earliest of all these is the first contact: the distance to the
    // segment is the distance to its line where the foot is on it, else to the nearer end.
    for (const Eigen::Vector2d& q : {seg.a, seg.b}) {
      if (!Near(box, q, dc)) continue;
      const Eigen::Vector2d D = P - q;
      const double dq = D.norm();
      if (dq <= dc) continue;  // touching this end: handled above, or moving away from it
      const double c[5] = {(dq - dc) * (dq + dc), 2.0 * V.dot(D), V.squaredNorm() + A.dot(D),
                           A.dot(V), 0.25 * A.squaredNorm()};
      best = std::min(best, FirstDownCrossing(c, 4, 0.0, std::min(S, best)));
    }
    if (best < kNever) p.t = t_ + best;
    return p;
  }

  Pending PredictPocket(int i, int k, const Box& box, double S, const Eigen::Vector2d& P,
                        const Eigen::Vector2d& V, const Eigen::Vector2d& A) const {
    Pending p{.kind = Kind::kPocket, .a = i, .other = k, .va = traj_[i].version};
    const Pocket& pk = model_.spec().pockets[k];
    if (!Near(box, pk.centre, pk.radius_m)) return p;
    const Eigen::Vector2d D = P - pk.centre;
    const double dq = D.norm();
    if (dq <= pk.radius_m) {
      p.t = t_;
      return p;
    }
    const double c[5] = {(dq - pk.radius_m) * (dq + pk.radius_m), 2.0 * V.dot(D),
                         V.squaredNorm() + A.dot(D), A.dot(V), 0.25 * A.squaredNorm()};
    const double s = FirstDownCrossing(c, 4, 0.0, S);
    if (s < kNever) p.t = t_ + s;
    return p;
  }

  // Whether a path box stays strictly inside a bounded table's edges (half_).
  bool OnTable(const Box& box) const {
    return box.lo.x() > -half_.x() && box.hi.x() < half_.x() && box.lo.y() > -half_.y() &&
           box.hi.y() < half_.y();
  }

  // A bounded table's centre line plus a radius on each side: past it the ball has left the
  // table (cushions off, or pockets off and through a pocket mouth).
  Pending PredictLeave(int i, const Box& box, double S, const Eigen::Vector2d& P,
                       const Eigen::Vector2d& V, const Eigen::Vector2d& A) const {
    Pending p{.kind = Kind::kPocket, .a = i, .other = -1, .va = traj_[i].version};
    if (OnTable(box)) return p;
    double best = kNever;
    for (int k = 0; k < 2; ++k) {
      for (const double side : {1.0, -1.0}) {
        // half - side * x(s) falls through zero.
        const double c[3] = {half_[k] - side * P[k], -side * V[k], -0.5 * side * A[k]};
        if (c[0] <= 0.0) {
          best = 0.0;
        } else {
          best = std::min(best, FirstDownCrossing(c, 2, 0.0, S));
        }
      }
    }
    if (best < kNever) p.t = t_ + best;
    return p;
  }

  // A rectangle about the table's centre that no cushion, pocket or edge is near: every cull of
  // PredictCushion, PredictPocket and PredictLeave fails for a path box inside it (empty when
  // the layout leaves none).
  Box ClearOfTheRails() const {
    const TableSpec& spec = model_.spec();
    Eigen::Vector2d half(0.5 * spec.length_m - dc_, 0.5 * spec.width_m - dc_);
    // (A segment's ends lie in its box: the box test covers them.)
    const auto clear = [&](const Box& r) {
      for (const Box& c : cushion_reach_) {
        if (Overlaps(r, c)) return false;
      }
      for (const Pocket& pk : spec.pockets) {
        if (Near(r, pk.centre, pk.radius_m)) return false;
      }
      return OnTable(r);
    };
    for (int k = 0; k < 64 && half.minCoeff() > 0.0; ++k) {
      const Box r{-half, half};
      if (clear(r)) return r;
      half *= 0.95;
    }
    return Box{Eigen::Vector2d::Constant(kNever), Eigen::Vector2d::Constant(-kNever)};
  }

  // Ball i's earliest event from now, in best_ (the event queue: Next).
  void Predict(int i) {
    ++counts_.predictions;
    const Trajectory& tr = traj_[i];
    Pending best{.kind = Kind::kTransition, .a = i, .va = tr.version};
    if (tr.state == MotionState::kPocketed) {
      best_[i] = best;
      return;
    }
    if (IsMoving(tr.state)) {
      if (tr.t_next <= t_ + kPredictionHorizon) {
        best.t = tr.t_next;
        best.other = static_cast<int>(tr.next_kind);
      } else {
        best.t = t_ + kPredictionHorizon;  // look again then
        best.other = static_cast<int>(TransitionKind::kNone);
      }
    }
    const auto consider = [&best](const Pending& c) {
      if (c.found() && c.Before(best)) best = c;
    };
    const Eigen::Vector2d P = PosAt(i, t_), V = VelAt(i, t_);
    // Where i goes from now to the end of its window (at the path's start, the box SetOrigin
    // made: the same numbers).
    const Box box = !IsTranslating(tr.state)           ? Box{P, P}
                    : tr.box_at_t0 && t_ == tr.t0 ? Box{tr.lo, tr.hi}
                                                  : PathBox(P, V, tr.a, Window(i) - t_);
    if (IsTranslating(tr.state) && model_.spec().bounded && !Within(box, clear_)) {
      const double S = Window(i) - t_;
      const Eigen::Vector2d& A = tr.a;
      if (cushions_) {
        // The segments' boxes grown by the contact distance (cushion_reach_) cull first.
        const int nc = static_cast<int>(model_.spec().cushions.size());
        for (int k = 0; k < nc; ++k) {
          if (Overlaps(box, cushion_reach_[k])) consider(PredictCushion(i, k, box, S, P, V, A));
        }
      }
      if (pockets_) {
        const int np = static_cast<int>(model_.spec().pockets.size());
        for (int k = 0; k < np; ++k) consider(PredictPocket(i, k, box, S, P, V, A));
      }
      consider(PredictLeave(i, box, S, P, V, A));
    }
    // Pairs only up to the best found so far: ball i is predicted again by then anyway (its
    // best event is handled, or made stale by a change of i or its partner, and either way
    // Predict(i) runs), so a later contact would be thrown away.
    // The balls that MayMeet i are gathered first without a branch (each is stored, the count
    // grows by the test): whether a pair passes the cull is data-dependent, and a branch on it
    // mispredicts about one time in five.
    const bool translating = IsTranslating(tr.state);
    int* const candidates = candidates_.data();
    int nc = 0;
    for (int j = 0; j < n_; ++j) {
      candidates[nc] = j;
      nc += MayMeet(translating, box, j) & (j != i);
    }
    for (int c = 0; c < nc; ++c) {
      const double horizon = std::min(Window(i), best.t) - t_;
      consider(PairEvent(i, P, V, candidates[c], horizon));
    }
    best_[i] = best;
  }

  // The event queue is best_ itself: each ball's earliest event, never stale (every change of
  // a ball re-predicts it and the balls whose best involved it), a pair's contact in both
  // balls' entries until it is handled. The next event is the earliest by Pending's total
  // order. With a table's few balls a scan beats a heap: the scan for the earliest time keeps
  // its running minimum without a branch, and only the entries at that very time (the two of
  // a pair, or simultaneous events) are ordered by Before. Returns -1 when no ball has one.
  int Next() const {
    double earliest = kNever;
    int next = -1;
    for (int j = 0; j < n_; ++j) {
      const double t = best_[j].t;
      const bool earlier = t < earliest;
      earliest = earlier ? t : earliest;
      next = earlier ? j : next;
    }
    for (int j = next + 1; next >= 0 && j < n_; ++j) {
      if (best_[j].t == earliest && best_[j].Before(best_[next])) next = j;
    }
    return next;
  }

  bool Current(const Pending& p) const {
    return traj_[p.a].version == p.va && (p.b < 0 || traj_[p.b].version == p.vb);
  }

  // After balls a (and b) got new trajectories: predict them again, and every ball whose
  // earliest event involved one of them.
  void Repredict(int a, int b = -1) {
    Predict(a);
    if (b >= 0) Predict(b);
    PredictPartners([a, b](int x) { return x >= 0 && (x == a || x == b); });
  }

  // Predicts again every ball not `changed` whose earliest event involves a ball that is (its
  // event was made from trajectories since replaced). changed(-1), no ball, must be false.
  template <typename Changed>
  void PredictPartners(const Changed& changed) {
    for (int j = 0; j < n_; ++j) {
      const Pending& p = best_[j];
      if (changed(j) || !p.found()) continue;
      if (changed(p.a) || changed(p.b)) Predict(j);
    }
  }

  // --- Handling ----------------------------------------------------------------------------


  absl::Status Handle(const Pending& e, std::vector<Event>* events) {
    switch (e.kind) {
      case Kind::kBall:
        HandleBalls(e.a, e.b, events);
        break;
      case Kind::kCushion:
        HandleCushion(e.a, e.other, events);
        break;
      case Kind::kPocket:
        HandlePocket(e.a, e.other, events);
        break;
      case Kind::kTransition: {
        ++counts_.transition;
        Ball& b = scratch_a_;
        Eval(e.a, t_, &b);
        const MotionState from = b.state;
        const auto kind = static_cast<TransitionKind>(e.other);
        if (kind != TransitionKind::kNone) ApplyTransition(model_, kind, &b);
        RecordTransition(t_, e.a, from, b, events);
        SetOrigin(e.a, b, t_);
        Repredict(e.a);
        break;
      }
    }
    for (const int i : {e.a, e.b}) {
      if (i < 0) continue;
      const Trajectory& tr = traj_[i];
      if (!tr.r0.allFinite() || !tr.v0.allFinite() || !tr.w0.allFinite() || !tr.a.allFinite() ||
          std::isnan(tr.t_next)) {
        return absl::InternalError(absl::StrFormat(
            "ball %s: state became non-finite at t = %.9f s", state_.balls[i].id, t_));
      }
    }
    return absl::OkStatus();
  }

  // A contact of ball i with `partner`: true when it should be reported (not a hop of a push
  // already reported).
  bool Report(int i, int partner, bool plastic) {
    std::array<Resting, 4>& ring = resting_[i];
    if (!plastic) {
      ring.fill(Resting{});  // a real collision ends every push on the ball
      return true;
    }
    Resting* oldest = &ring[0];
    for (Resting& r : ring) {
      if (r.partner == partner) {
        const bool continues = t_ - r.t <= kRestingTrain;
        r.t = t_;
        return !continues;
      }
      if (r.t < oldest->t) oldest = &r;
    }
    *oldest = {partner, t_};
    return true;
  }

  // The approach speed (m/s) below which a contact of balls i and j is plastic: within
  // kRestingTrain of the pair's last plastic contact it continues that sustained contact (the
  // TC model's rule: a contact that follows another within the contact time is not a new
  // collision), re-forming because the resting gap it opened closed.
  double PlasticBelow(int i, int j) const {
    if (o_.resting_contacts != RestingContacts::kSustained) return kRestingContactSpeed;
    const double last = last_plastic_[PairIndex(i, j)];
    return t_ - last <= kRestingTrain ? kTrainContactSpeed : kRestingContactSpeed;
  }

  // Opens a resting gap between balls ia and ib (new trajectories set) after a plastic contact
  // or a push with nothing to resolve, so that the contact, if the cloth keeps closing it,
  // re-forms later instead of at once.
  void OpenRestingGap(int ia, int ib) {
    Trajectory& ta = traj_[ia];
    Trajectory& tb = traj_[ib];
    const Eigen::Vector2d dp = tb.r0 - ta.r0;
    const double dist = dp.norm();
    if (dist > 0.0 && dist < d_ + kRestingGap) {
      const Eigen::Vector2d n = dp / dist;
      if ((tb.v0 - ta.v0).dot(n) < kRestingContactSpeed) {
        const double want = d_ + RestingGap(-(tb.a - ta.a).dot(n), kRestingGap);
        const double open = std::max(0.0, want - dist);
        const bool ma = IsTranslating(ta.state), mb = IsTranslating(tb.state);
        if (ma && mb) {
          MoveOrigin(ia, -0.5 * open * n);
          MoveOrigin(ib, 0.5 * open * n);
        } else if (ma) {
          MoveOrigin(ia, -open * n);
        } else if (mb) {
          MoveOrigin(ib, open * n);
        }
      }
    }
  }

  // The resting gap balls i and j (new trajectories set) should have along n, from i to j:
  // what the cloth's closing acceleration allows for the pair's plastic speed.
  double GapSize(int i, int j, const Eigen::Vector2d& n) const {
    return RestingGap(-(traj_[j].a - traj_[i].a).dot(n), gap_, PlasticBelow(i, j));
  }

  // The slot of ball i in the cluster being resolved (its state at t_ on first use).
  int Slot(int i) {
    if (slot_of_[i] >= 0) return slot_of_[i];
    slot_of_[i] = static_cast<int>(cluster_.size());
    cluster_.push_back(i);
    cluster_balls_.emplace_back();
    Eval(i, t_, &cluster_balls_.back());
    cluster_from_.push_back(cluster_balls_.back().state);
    in_pair_.push_back(0);
    expanded_.push_back(0);
    changed_.push_back(0);
    changed_now_.push_back(0);
    cluster_moved_.push_back(0);
    near_made_.push_back(-1.0);
    if (near_.size() < cluster_.size()) near_.resize(cluster_.size());
    return static_cast<int>(cluster_.size()) - 1;
  }

  // Resolves a resting ball-ball contact (approach below PlasticBelow, or a push with none) as
  // a sustained contact of its group (RestingContacts::kSustained; docs/billiards.md, "Resting
  // contacts"): the group grows from the pair through the balls linked (gaps below the
  // sustained resting gap) to a ball whose velocity changed; the pair and then every pair of
  // the group that approaches (faster than the sweeps' settling speed) are resolved by
  // CollideBallsResting in over-relaxed sweeps (kSweepRelaxation) until none does, all at this
  // instant and as one event; creeping balls stop (StopCreep); then the resting gaps of the
  // balls moved open, and only the balls that changed are predicted again. A pair of the group
  // that was approaching faster than PlasticBelow before the event is a real collision: left
  // to the queue, which has it when the pair touches.
  // `start`: the pair's normal approach speed now (HandleBalls').
  void HandleSustained(int ia, int ib, double start, std::vector<Event>* events) {
    for (const int i : cluster_) slot_of_[i] = -1;
    cluster_.clear();
    cluster_balls_.clear();
    cluster_from_.clear();
    in_pair_.clear();
    expanded_.clear();
    changed_.clear();
    changed_now_.clear();
    cluster_moved_.clear();
    near_made_.clear();
    links_.clear();
    // Every ball's position now (impulses leave positions; the gap passes move them).
    pos_.resize(n_);
    for (int j = 0; j < n_; ++j) pos_[j] = PosAt(j, t_);
    // Within the largest resting gap (a cheap squared test first).
    const double link = d_ + gap_;
    const double link2 = link * link * (1.0 + 1e-9);
    const auto linked = [&](const Eigen::Vector2d& dp) {
      const double q = dp.squaredNorm();
      return q < link2 && std::sqrt(q) - d_ < gap_;
    };
    const auto resolve = [&](int i, int j, double relax) {
      const int si = Slot(i), sj = Slot(j);
      if (CollideBallsResting(model_, o_.effects, &cluster_balls_[si], &cluster_balls_[sj],
                              relax)) {
        ++counts_.sustained_contacts;
        // Reported as the first contact of the pair's train only (Report, kRestingTrain).
        const bool ri = Report(i, j, /*plastic=*/true), rj = Report(j, i, /*plastic=*/true);
        if (ri || rj) {
          events->push_back({.t_s = t_, .kind = EventKind::kBallBall, .a = i, .b = j,
                             .va = cluster_balls_[si].v.head<2>(),
                             .vb = cluster_balls_[sj].v.head<2>(),
                             .ra = cluster_balls_[si].r.head<2>()});
        }
      } else {
        ++counts_.ball_ball_push;
      }
      in_pair_[si] = in_pair_[sj] = 1;
      last_plastic_[PairIndex(i, j)] = t_;
    };
    // The group grows from the pair: a ball joins when it is linked to one whose velocity
    // changed (only such a pair can start to approach), with its links to the group's balls.
    // The rest of a cluster (a frozen rack the pair belongs to) is not looked at.
    const auto expand = [&](size_t k, bool with_links) {
      if (expanded_[k]) return;
      expanded_[k] = 1;
      const Eigen::Vector2d rk = pos_[cluster_[k]];
      for (int j = 0; j < n_; ++j) {
        if (traj_[j].state == MotionState::kPocketed || slot_of_[j] >= 0) continue;
        if (!linked(pos_[j] - rk)) continue;
        const size_t s = static_cast<size_t>(Slot(j));
        for (size_t q = 0; with_links && q < s; ++q) {
          if (linked(pos_[j] - pos_[cluster_[q]])) links_.push_back({q, s});
        }
      }
    };
    // The sweeps resolve pairs approaching faster than this.
    const double settle = std::max(kSweepApproach, kSweepSettle * start);
    resolve(ia, ib, 1.0);
    if (linked(pos_[ib] - pos_[ia])) links_.push_back({0, 1});
    expand(0, true);
    expand(1, true);
    // Sweeps over the group's touching pairs: each approaching one is resolved. Only pairs
    // with a ball whose velocity changed since the last sweep need a look; the sweeps change
    // velocities only.
    changed_[0] = changed_[1] = 1;
    for (int sweep = 0; sweep < kSustainedSweeps; ++sweep) {
      ++counts_.sustained_sweeps;
      bool any = false;
      std::fill(changed_now_.begin(), changed_now_.end(), 0);
      const size_t nl = links_.size();
      for (size_t l = 0; l < nl; ++l) {
        const auto [k, q] = links_[l];
        if (!changed_[k] && !changed_[q] && !changed_now_[k] && !changed_now_[q]) continue;
        const Ball& bk = cluster_balls_[k];
        const Ball& bq = cluster_balls_[q];
        const Eigen::Vector2d dp = (bq.r - bk.r).head<2>();
        const double dist = dp.norm();
        if (!(dist > 0.0)) continue;
        const double approach = (bk.v - bq.v).head<2>().dot(dp / dist);
        if (approach <= settle) continue;
        const int i = cluster_[k], j = cluster_[q];
        const double limit = PlasticBelow(i, j);
        // A pair that was approaching that fast before this event is a real collision, left to
        // the queue; one that only the sweeps sped up (the over-relaxed impulses overshoot
        // downstream for a sweep or two) stays part of this sustained contact.
        if (approach >= limit && (VelAt(i, t_) - VelAt(j, t_)).dot(dp / dist) >= limit) continue;
        resolve(std::min(i, j), std::max(i, j), kSweepRelaxation);
        changed_now_[k] = changed_now_[q] = 1;
        any = true;
      }
      if (!any) break;
      changed_.swap(changed_now_);
      for (size_t k = 0; k < cluster_.size(); ++k) {
        if (changed_[k]) expand(k, true);
      }
    }
    // A ball the group leaves creeping slower than RestingStopSpeed stops (its roll would end
    // within 1.4 ms, after 0.1 um).
    for (size_t k = 0; k < cluster_.size(); ++k) {
      if (in_pair_[k]) StopCreep(model_, o_.effects, &cluster_balls_[k]);
    }
    for (size_t k = 0; k < cluster_.size(); ++k) {
      counts_.state_changes += cluster_balls_[k].state != cluster_from_[k];
      RecordTransition(t_, cluster_[k], cluster_from_[k], cluster_balls_[k], events);
    }
    // New trajectories for the balls an impulse changed; the others keep theirs unless the
    // resting gaps below move them.
    const auto restart = [&](size_t k) {
      if (!cluster_moved_[k]) {
        SetOrigin(cluster_[k], cluster_balls_[k], t_);
        cluster_moved_[k] = 1;
      }
    };
    for (size_t k = 0; k < cluster_.size(); ++k) {
      if (in_pair_[k]) restart(k);
    }
    // Resting gaps between the group's balls (each at least the gap that the pair's closing
    // acceleration allows, as after a plastic contact), in a few Gauss-Seidel passes. Moving
    // balls move; balls at rest too when the pair is jammed: it comes back within its train
    // after its gap could not open (a pair back at the same instant is one: it reopened by
    // less than kTouchGap; a ball wedged between two at rest, which stop after each contact:
    // the gaps cannot open otherwise, and the pair would be hit again within microseconds,
    // thousands of times).
    const bool jammed = t_ - jammed_at_[PairIndex(ia, ib)] <= kRestingTrain;
    const auto movable = [&](int i) {
      return IsTranslating(traj_[i].state) ||
             (jammed && traj_[i].state != MotionState::kPocketed);
    };
    // Whether the ball in slot k can move to p without coming closer than 2R to a ball other
    // than `partner` to which it is not already closer. Only the balls that were within
    // kNearSlack of contact when its list was made can be (the list holds while the shifts
    // made since, all balls together, and this move add up to less than kNearSlack).
    double shifted = 0.0;  // the length of every shift so far, summed
    const auto free = [&](size_t k, int partner, const Eigen::Vector2d& p) {
      const int i = cluster_[k];
      const double move = (p - pos_[i]).norm();
      const bool scan = near_made_[k] < 0.0 || shifted - near_made_[k] + move >= kNearSlack;
      if (scan) {
        near_[k].clear();
        near_made_[k] = shifted;
        const double reach = (d_ + kNearSlack) * (d_ + kNearSlack);
        for (int j = 0; j < n_; ++j) {
          if (j == i || traj_[j].state == MotionState::kPocketed) continue;
          if ((pos_[j] - pos_[i]).squaredNorm() < reach) near_[k].push_back(j);
        }
      }
      for (const int j : near_[k]) {
        if (j == partner) continue;
        const double after = (pos_[j] - p).squaredNorm();
        if (after < d_ * d_ && after < (pos_[j] - pos_[i]).squaredNorm()) return false;
      }
      // Nor deeper into a cushion or a pocket's capture circle than it is (a ball at rest
      // against a rail may be moved by a jammed pair: it would stay inside, never predicted).
      const bool clear = Within(Box{p, p}, clear_);
      if (!clear && cushions_) {
        const std::vector<CushionSegment>& segs = model_.spec().cushions;
        for (size_t c = 0; c < segs.size(); ++c) {
          if (!Overlaps(Box{p, p}, cushion_reach_[c])) continue;
          const CushionSegment& seg = segs[c];
          const double after = (p - ClosestOnSegment(seg.a, seg.b, p)).squaredNorm();
          if (after < dc_ * dc_ &&
              after < (pos_[i] - ClosestOnSegment(seg.a, seg.b, pos_[i])).squaredNorm()) {
            return false;
          }
        }
      }
      if (!clear && pockets_) {
        for (const Pocket& pk : model_.spec().pockets) {
          const double after = (p - pk.centre).squaredNorm();
          if (after < pk.radius_m * pk.radius_m && after < (pos_[i] - pk.centre).squaredNorm()) {
            return false;
          }
        }
      }
      return true;
    };
    const auto shift = [&](size_t k, const Eigen::Vector2d& by) {
      restart(k);
      const int i = cluster_[k];
      MoveOrigin(i, by);
      pos_[i] += by;
      shifted += by.norm();
    };
    // The gaps to open are those of the balls an impulse or a gap moved (cluster_moved_): the
    // passes look at the pairs with such a ball, and a ball that a gap moves brings its
    // neighbours in for the next pass.
    const double reach = (link + kNearSlack) * (link + kNearSlack);
    for (int pass = 0; pass < kGapPasses; ++pass) {
      bool moved = false;
      for (size_t k = 0; k < cluster_.size(); ++k) {
        if (cluster_moved_[k]) expand(k, false);
      }
      const size_t g = cluster_.size();
      links_.clear();
      for (size_t k = 0; k < g; ++k) {
        for (size_t q = k + 1; q < g; ++q) {
          if ((cluster_moved_[k] || cluster_moved_[q]) &&
              (pos_[cluster_[q]] - pos_[cluster_[k]]).squaredNorm() < reach) {
            links_.push_back({k, q});
          }
        }
      }
      for (const auto& [k, q] : links_) {
        const int i = cluster_[k], j = cluster_[q];
        const Eigen::Vector2d dp = pos_[j] - pos_[i];
        if (!linked(dp)) continue;
        const double dist = dp.norm();
        if (!(dist > 0.0)) continue;
        const Eigen::Vector2d n = dp / dist;
        if ((cluster_balls_[q].v - cluster_balls_[k].v).head<2>().dot(n) >= kRestingContactSpeed) {
          continue;
        }
        const double size = GapSize(i, j, n);
        const double open = d_ + size - dist;
        if (!(open > kGapShortfall * size)) continue;
        // Both move half the way, or one all of it; never into a deeper overlap with a third
        // ball (the pair then keeps its gap, and the queue resolves it if it closes).
        const bool mi = movable(i), mj = movable(j);
        const Eigen::Vector2d step = open * n;
        if (mi && mj && free(k, j, pos_[i] - 0.5 * step) && free(q, i, pos_[j] + 0.5 * step)) {
          shift(k, -0.5 * step);
          shift(q, 0.5 * step);
        } else if (mi && free(k, j, pos_[i] - step)) {
          shift(k, -step);
        } else if (mj && free(q, i, pos_[j] + step)) {
          shift(q, step);
        } else {
          continue;
        }
        moved = true;
      }
      if (!moved) break;
    }
    // The pair that started it must not be touching any more (else it is handled again at
    // once): as after a single plastic contact, it opens by the smallest resting gap even
    // where that presses a third ball (by 1 nm at most; the queue resolves that).
    {
      const Eigen::Vector2d dp = pos_[ib] - pos_[ia];
      const double dist = dp.norm();
      const double open = d_ + kMinRestingGap - dist;
      const bool ma = movable(ia), mb = movable(ib);
      if (dist > 0.0 && open > 0.0 && (ma || mb)) {
        const Eigen::Vector2d step = ((ma && mb ? 0.5 : 1.0) * open / dist) * dp;
        if (ma) shift(0, -step);  // the pair's slots: resolve(ia, ib) made them first
        if (mb) shift(1, step);
      }
    }
    // Whether the pair's gap stayed short of its size (by more than the passes leave).
    {
      const Eigen::Vector2d dp = pos_[ib] - pos_[ia];
      const double dist = dp.norm();
      const Eigen::Vector2d n = dist > 0.0 ? Eigen::Vector2d(dp / dist) : Eigen::Vector2d::Zero();
      if (dist - d_ < (1.0 - kGapShortfall) * GapSize(ia, ib, n)) {
        jammed_at_[PairIndex(ia, ib)] = t_;
      }
    }
    const size_t g = cluster_.size();
    counts_.group_balls += static_cast<int64_t>(g);
    for (size_t k = 0; k < g; ++k) {
      if (cluster_moved_[k]) Predict(cluster_[k]);
    }
    PredictPartners([this](int i) {
      return i >= 0 && slot_of_[i] >= 0 && cluster_moved_[slot_of_[i]];
    });
  }

  void HandleBalls(int ia, int ib, std::vector<Event>* events) {
    if (o_.resting_contacts == RestingContacts::kSustained) {
      const Eigen::Vector2d dp = PosAt(ib, t_) - PosAt(ia, t_);
      const double approach = (VelAt(ia, t_) - VelAt(ib, t_)).dot(dp.normalized());
      if (approach < PlasticBelow(ia, ib)) {
        ++counts_.ball_ball;
        ++counts_.ball_ball_plastic;
        HandleSustained(ia, ib, approach, events);
        return;
      }
    }
    Ball& a = scratch_a_;
    Ball& b = scratch_b_;
    Eval(ia, t_, &a);
    Eval(ib, t_, &b);
    const MotionState fa = a.state, fb = b.state;
    const Eigen::Vector2d n0 = (b.r - a.r).head<2>().normalized();
    const bool plastic = (a.v - b.v).head<2>().dot(n0) < kRestingContactSpeed;
    ++counts_.ball_ball;
    counts_.ball_ball_plastic += plastic;
    const bool hit = CollideBalls(model_, o_.effects, &a, &b);
    counts_.ball_ball_push += !hit;
    counts_.state_changes += (a.state != fa) + (b.state != fb);
    if (hit) {
      const bool ra = Report(ia, ib, plastic), rb = Report(ib, ia, plastic);
      if (ra || rb) {
        events->push_back({.t_s = t_, .kind = EventKind::kBallBall, .a = ia, .b = ib,
                           .va = a.v.head<2>(), .vb = b.v.head<2>(), .ra = a.r.head<2>()});
      }
    }
    RecordTransition(t_, ia, fa, a, events);
    RecordTransition(t_, ib, fb, b, events);
    SetOrigin(ia, a, t_);
    SetOrigin(ib, b, t_);
    OpenRestingGap(ia, ib);
    Repredict(ia, ib);
  }

  void HandleCushion(int ia, int k, std::vector<Event>* events) {
    Ball& a = scratch_a_;
    Eval(ia, t_, &a);
    const CushionSegment& seg = model_.spec().cushions[k];
    const Eigen::Vector2d p = a.r.head<2>();
    const Eigen::Vector2d off = p - ClosestOnSegment(seg.a, seg.b, p);
    const double dist = off.norm();
    const MotionState from = a.state;
    if (dist > 0.0) {
      const Eigen::Vector2d n = off / dist;
      const bool plastic = -a.v.head<2>().dot(n) < kRestingContactSpeed;
      ++counts_.cushion;
      const bool hit = CollideCushion(model_, n, &a);
      counts_.cushion_plastic += plastic || !hit;
      counts_.state_changes += a.state != from;
      if (hit && Report(ia, -2 - k, plastic)) {
        events->push_back({.t_s = t_, .kind = EventKind::kBallCushion, .a = ia, .other = k,
                           .va = a.v.head<2>(), .ra = a.r.head<2>()});
      }
      RecordTransition(t_, ia, from, a, events);
      SetOrigin(ia, a, t_);
      Trajectory& ta = traj_[ia];
      if (dist < dc_ + kRestingGap && ta.v0.dot(n) < kRestingContactSpeed &&
          IsTranslating(ta.state)) {
        MoveOrigin(ia, std::max(0.0, dc_ + RestingGap(-ta.a.dot(n), kRestingGap) - dist) * n);
      }
    } else {
      RecordTransition(t_, ia, from, a, events);
      SetOrigin(ia, a, t_);
    }
    Repredict(ia);
  }

  void HandlePocket(int ia, int k, std::vector<Event>* events) {
    ++counts_.pocket;
    Ball& a = scratch_a_;
    Eval(ia, t_, &a);
    const MotionState from = a.state;
    a.v.setZero();
    a.w.setZero();
    a.state = MotionState::kPocketed;
    state_.balls[ia].pocket = k;
    events->push_back({.t_s = t_, .kind = EventKind::kBallPocket, .a = ia, .other = k,
                       .ra = a.r.head<2>()});
    RecordTransition(t_, ia, from, a, events);
    SetOrigin(ia, a, t_);
    Repredict(ia);
  }

  const TableModel& model_;
  const SolverOptions o_;
  TableState state_;  // ids and pockets; the balls' states at t_ when !dirty_
  const int n_;
  std::vector<Trajectory> traj_;
  // Each ball's path box (Trajectory lo, hi) grown by the reach of a contact, and whether it
  // translates: MayMeet's data, packed apart from the trajectories it is made from.
  struct Reach {
    double lo_x, hi_x, lo_y, hi_y;
    bool translating;
  };
  std::vector<Reach> reach_;
  std::vector<int> candidates_;  // Predict's balls that MayMeet the one predicted
  std::vector<Box> cushion_reach_;  // each cushion segment's box grown by dc_
  std::vector<Pending> best_;  // each ball's earliest predicted event
  // The last prediction of each pair (a < b, at a * n + b): its contact time (kNever: none up
  // to `until`) for the trajectory versions it was made from.
  struct PairMemo {
    double t = kNever;
    double until = -kNever;
    uint32_t va = 0, vb = 0;  // versions start at 1: an unused memo matches nothing
  };
  std::vector<PairMemo> memo_;
  std::vector<double> last_plastic_;  // per pair (a * n + b, a < b): its last plastic contact
  double t_;
  bool dirty_ = true;
  int64_t processed_ = 0;
  EventEngineCounts counts_;
  Ball scratch_a_, scratch_b_;
  // Per ball, the latest plastic contacts: partner (a ball index, or -2 - segment for a
  // cushion) and time, to report a push once rather than every hop.
  struct Resting {
    int partner = -1;
    double t = -kNever;
  };
  std::vector<std::array<Resting, 4>> resting_;
  // The group a sustained contact reaches (HandleSustained): ball indices, their states at t_
  // and motion states before, and per-slot flags.
  std::vector<int> cluster_;
  std::vector<int> slot_of_;  // per ball: its slot in cluster_, or -1
  std::vector<Ball> cluster_balls_;
  std::vector<MotionState> cluster_from_;
  std::vector<char> cluster_moved_;  // per slot: new trajectory set (an impulse or a gap move)
  std::vector<char> in_pair_;        // per slot: in a pair resolved (an impulse or a push)
  std::vector<char> expanded_;       // per slot: its linked balls have joined the group
  std::vector<Eigen::Vector2d> pos_;  // every ball's position at t_ (HandleSustained)
  std::vector<char> changed_, changed_now_;  // per slot: velocity changed in a sweep
  std::vector<std::pair<size_t, size_t>> links_;  // slot pairs near contact (HandleSustained)
  std::vector<std::vector<int>> near_;  // per slot: balls near contact (HandleSustained's free)
  std::vector<double> near_made_;       // per slot: the shifts summed when near_ was made
  std::vector<double> jammed_at_;  // per pair (a * n + b, a < b): when its gap last could not open
  const double gap_;  // the largest resting gap (m)
  const double d_;   // contact distance of two balls (m)
  const double dc_;  // contact distance from a cushion nose line (m)
  const bool cushions_, pockets_, orientation_;
  // No cushion, pocket or edge is near a path inside this box (ClearOfTheRails).
  Box clear_{Eigen::Vector2d::Constant(kNever), Eigen::Vector2d::Constant(-kNever)};
  const Eigen::Vector2d half_;  // |x|, |y| beyond which a ball has left a bounded table
};

}  // namespace

const EventEngineCounts* EventCountsOf(const TableSimulation& sim) {
  const auto* e = dynamic_cast<const EventSimulation*>(&sim);
  return e != nullptr ? &e->counts() : nullptr;
}

std::unique_ptr<TableSimulation> MakeEventSimulation(const TableModel& model,
                                                     const SolverOptions& options,
                                                     TableState initial) {
  return std::make_unique<EventSimulation>(model, options, std::move(initial));
}

}  // namespace sportsim::billiards
