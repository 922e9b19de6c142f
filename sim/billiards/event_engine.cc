#include "sim/billiards/event_engine.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <tuple>

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

// The resting gap for a contact the cloth closes at `closing` m/s^2: re-forming from it, the
// approach speed sqrt(2 closing gap) stays at 0.9 kRestingContactSpeed or below.
double RestingGap(double closing) {
  if (!(closing > 0.0)) return kRestingGap;
  const double v = 0.9 * kRestingContactSpeed;
  return std::clamp(v * v / (2.0 * closing), kMinRestingGap, kRestingGap);
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
  bool Involves(int i) const { return a == i || b == i; }
  bool Before(const Pending& o) const {
    return std::tie(t, kind, a, b, other) < std::tie(o.t, o.kind, o.a, o.b, o.other);
  }
};
// Heap order: the earliest event (by the total order above) at the front.
struct Later {
  bool operator()(const Pending& x, const Pending& y) const { return y.Before(x); }
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
    if (a[k] != 0.0) {
      const double s = -v[k] / a[k];
      if (s > 0.0 && s < S) {
        const double x = p[k] + s * (v[k] + 0.5 * s * a[k]);
        box.lo[k] = std::min(box.lo[k], x);
        box.hi[k] = std::max(box.hi[k], x);
      }
    }
  }
  return box;
}
// Does the box come within `reach` of the box [lo, hi]?
bool Near(const Box& box, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, double reach) {
  return box.lo.x() <= hi.x() + reach && box.hi.x() >= lo.x() - reach &&
         box.lo.y() <= hi.y() + reach && box.hi.y() >= lo.y() - reach;
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
        d_(2.0 * model.radius()),
        dc_(model.cushion_contact_distance()),
        cushions_(model.spec().bounded && (options.effects & kEffectDisableCushions) == 0),
        pockets_(model.spec().bounded && (options.effects & kEffectDisablePockets) == 0),
        orientation_((options.effects & kEffectDisableOrientation) == 0),
        half_(0.5 * model.spec().length_m + model.radius(),
              0.5 * model.spec().width_m + model.radius()) {
    resting_.resize(state_.balls.size());
    for (int i = 0; i < n_; ++i) SetOrigin(i, state_.balls[i], t_);
    for (int i = 0; i < n_; ++i) Predict(i);
  }

  absl::Status AdvanceTo(double t_end, std::vector<Event>* events) override {
    if (!(std::isfinite(t_end) && t_end >= t_)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "t_end_s must be finite and not before the table's time %g s, got %g", t_, t_end));
    }
    while (!heap_.empty() && heap_.front().t <= t_end) {
      const Pending e = heap_.front();
      std::pop_heap(heap_.begin(), heap_.end(), Later());
      heap_.pop_back();
      if (!Current(e)) continue;
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
      if (heap_.size() > 8 * static_cast<size_t>(n_) + 64) Compact();
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
    const double cross = tr.w0.cross(tr.alpha).norm();
    tr.fixed_axis = cross <= 1e-12 * tr.w0.norm() * tr.alpha.norm();
    if (!tr.fixed_axis) {
      // |w| is largest at an end of the segment (it is linear in time).
      const double span = std::min(tr.t_next, t + kPredictionHorizon) - t;
      const double w_max = std::max(tr.w0.norm(), (tr.w0 + span * tr.alpha).norm());
      tr.q_piece = std::clamp(kOrientationTurn / w_max, 1.0 / 8192.0, 1.0 / 16.0);
    }
    tr.q_k = 0;
    tr.q_cached = tr.q0;
    ++tr.version;
  }

  Eigen::Vector2d PosAt(int i, double t) const {
    const Trajectory& tr = traj_[i];
    if (!IsTranslating(tr.state)) return tr.r0;
    const double tau = t - tr.t0;
    return tr.r0 + tau * (tr.v0 + (0.5 * tau) * tr.a);
  }
  Eigen::Vector2d VelAt(int i, double t) const {
    const Trajectory& tr = traj_[i];
    if (!IsTranslating(tr.state)) return Eigen::Vector2d::Zero();
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

  // The end of what can be predicted for ball i now.
  double Window(int i) const { return std::min(traj_[i].t_next, t_ + kPredictionHorizon); }

  // Ball i (at P, V now) against ball j, looking at most `horizon` ahead.
  Pending PredictPair(int i, const Eigen::Vector2d& P, const Eigen::Vector2d& V, int j,
                      double horizon) const {
    const Trajectory& ti = traj_[i];
    const Trajectory& tj = traj_[j];
    Pending p{.kind = Kind::kBall, .a = std::min(i, j), .b = std::max(i, j)};
    p.va = traj_[p.a].version;
    p.vb = traj_[p.b].version;
    if (!IsTranslating(ti.state) && !IsTranslating(tj.state)) return p;
    if (ti.state == MotionState::kPocketed || tj.state == MotionState::kPocketed) return p;
    const double S = std::min(horizon, Window(j) - t_);
    const Eigen::Vector2d dp = PosAt(j, t_) - P;
    const Eigen::Vector2d dv = VelAt(j, t_) - V;
    const Eigen::Vector2d da = tj.a - ti.a;
    // Cull: the relative path's box must reach the disc of radius d around the origin.
    const Box box = PathBox(dp, dv, da, S);
    if (!Near(box, Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero(), d_)) return p;
    const double dist = dp.norm();
    if (dist == 0.0) return p;
    const double gap = dist - d_;
    if (gap < kTouchGap) {
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

  // Ball i against cushion segment k.
  Pending PredictCushion(int i, int k, const Box& box, double S, const Eigen::Vector2d& P,
                         const Eigen::Vector2d& V, const Eigen::Vector2d& A) const {
    Pending p{.kind = Kind::kCushion, .a = i, .other = k, .va = traj_[i].version};
    const CushionSegment& seg = model_.spec().cushions[k];
    if (!Near(box, seg.a.cwiseMin(seg.b), seg.a.cwiseMax(seg.b), dc_)) return p;
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
      if (!Near(box, q, q, dc)) continue;
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
    if (!Near(box, pk.centre, pk.centre, pk.radius_m)) return p;
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

  // A bounded table's centre line plus a radius on each side: past it the ball has left the
  // table (cushions off, or pockets off and through a pocket mouth).
  Pending PredictLeave(int i, const Box& box, double S, const Eigen::Vector2d& P,
                       const Eigen::Vector2d& V, const Eigen::Vector2d& A) const {
    Pending p{.kind = Kind::kPocket, .a = i, .other = -1, .va = traj_[i].version};
    if (box.lo.x() > -half_.x() && box.hi.x() < half_.x() && box.lo.y() > -half_.y() &&
        box.hi.y() < half_.y()) {
      return p;
    }
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

  // Ball i's earliest event from now, pushed on the heap.
  void Predict(int i) {
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
    if (IsTranslating(tr.state) && model_.spec().bounded) {
      const double S = Window(i) - t_;
      const Eigen::Vector2d& A = tr.a;
      const Box box = PathBox(P, V, A, S);
      if (cushions_) {
        const int nc = static_cast<int>(model_.spec().cushions.size());
        for (int k = 0; k < nc; ++k) consider(PredictCushion(i, k, box, S, P, V, A));
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
    for (int j = 0; j < n_; ++j) {
      if (j == i) continue;
      const double horizon = std::min(Window(i), best.t) - t_;
      consider(PredictPair(i, P, V, j, horizon));
    }
    best_[i] = best;
    if (best.found()) Push(best);
  }

  void Push(const Pending& p) {
    heap_.push_back(p);
    std::push_heap(heap_.begin(), heap_.end(), Later());
  }

  // Drops stale predictions: the heap is rebuilt from each ball's current best.
  void Compact() {
    heap_.clear();
    for (const Pending& p : best_) {
      if (p.found() && Current(p)) heap_.push_back(p);
    }
    std::make_heap(heap_.begin(), heap_.end(), Later());
  }

  bool Current(const Pending& p) const {
    return traj_[p.a].version == p.va && (p.b < 0 || traj_[p.b].version == p.vb);
  }

  // After balls a (and b) got new trajectories: predict them again, and every ball whose
  // earliest event involved one of them.
  void Repredict(int a, int b = -1) {
    Predict(a);
    if (b >= 0) Predict(b);
    for (int j = 0; j < n_; ++j) {
      if (j == a || j == b) continue;
      const Pending& p = best_[j];
      if (p.found() && (p.Involves(a) || (b >= 0 && p.Involves(b)))) Predict(j);
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

  void HandleBalls(int ia, int ib, std::vector<Event>* events) {
    Ball& a = scratch_a_;
    Ball& b = scratch_b_;
    Eval(ia, t_, &a);
    Eval(ib, t_, &b);
    const MotionState fa = a.state, fb = b.state;
    const Eigen::Vector2d n0 = (b.r - a.r).head<2>().normalized();
    const bool plastic = (a.v - b.v).head<2>().dot(n0) < kRestingContactSpeed;
    if (CollideBalls(model_, o_.effects, &a, &b)) {
      const bool ra = Report(ia, ib, plastic), rb = Report(ib, ia, plastic);
      if (ra || rb) {
        events->push_back({.t_s = t_, .kind = EventKind::kBallBall, .a = ia, .b = ib,
                           .va = a.v.head<2>(), .vb = b.v.head<2>()});
      }
    }
    RecordTransition(t_, ia, fa, a, events);
    RecordTransition(t_, ib, fb, b, events);
    SetOrigin(ia, a, t_);
    SetOrigin(ib, b, t_);
    // A plastic (resting) contact, or a push with nothing to resolve: open a resting gap so
    // that the contact, if the cloth keeps closing it, re-forms later instead of at once.
    Trajectory& ta = traj_[ia];
    Trajectory& tb = traj_[ib];
    const Eigen::Vector2d dp = tb.r0 - ta.r0;
    const double dist = dp.norm();
    if (dist > 0.0 && dist < d_ + kRestingGap) {
      const Eigen::Vector2d n = dp / dist;
      if ((tb.v0 - ta.v0).dot(n) < kRestingContactSpeed) {
        const double want = d_ + RestingGap(-(tb.a - ta.a).dot(n));
        const double open = std::max(0.0, want - dist);
        const bool ma = IsTranslating(ta.state), mb = IsTranslating(tb.state);
        if (ma && mb) {
          ta.r0 -= 0.5 * open * n;
          tb.r0 += 0.5 * open * n;
        } else if (ma) {
          ta.r0 -= open * n;
        } else if (mb) {
          tb.r0 += open * n;
        }
      }
    }
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
      if (CollideCushion(model_, n, &a) && Report(ia, -2 - k, plastic)) {
        events->push_back({.t_s = t_, .kind = EventKind::kBallCushion, .a = ia, .other = k,
                           .va = a.v.head<2>()});
      }
      RecordTransition(t_, ia, from, a, events);
      SetOrigin(ia, a, t_);
      Trajectory& ta = traj_[ia];
      if (dist < dc_ + kRestingGap && ta.v0.dot(n) < kRestingContactSpeed &&
          IsTranslating(ta.state)) {
        ta.r0 += std::max(0.0, dc_ + RestingGap(-ta.a.dot(n)) - dist) * n;
      }
    } else {
      RecordTransition(t_, ia, from, a, events);
      SetOrigin(ia, a, t_);
    }
    Repredict(ia);
  }

  void HandlePocket(int ia, int k, std::vector<Event>* events) {
    Ball& a = scratch_a_;
    Eval(ia, t_, &a);
    const MotionState from = a.state;
    a.v.setZero();
    a.w.setZero();
    a.state = MotionState::kPocketed;
    state_.balls[ia].pocket = k;
    events->push_back({.t_s = t_, .kind = EventKind::kBallPocket, .a = ia, .other = k});
    RecordTransition(t_, ia, from, a, events);
    SetOrigin(ia, a, t_);
    Repredict(ia);
  }

  const TableModel& model_;
  const SolverOptions o_;
  TableState state_;  // ids and pockets; the balls' states at t_ when !dirty_
  const int n_;
  std::vector<Trajectory> traj_;
  std::vector<Pending> best_;  // each ball's earliest predicted event
  std::vector<Pending> heap_;
  double t_;
  bool dirty_ = true;
  int64_t processed_ = 0;
  Ball scratch_a_, scratch_b_;
  // Per ball, the latest plastic contacts: partner (a ball index, or -2 - segment for a
  // cushion) and time, to report a push once rather than every hop.
  struct Resting {
    int partner = -1;
    double t = -kNever;
  };
  std::vector<std::array<Resting, 4>> resting_;
  const double d_;   // contact distance of two balls (m)
  const double dc_;  // contact distance from a cushion nose line (m)
  const bool cushions_, pockets_, orientation_;
  const Eigen::Vector2d half_;  // |x|, |y| beyond which a ball has left a bounded table
};

}  // namespace

std::unique_ptr<TableSimulation> MakeEventSimulation(const TableModel& model,
                                                     const SolverOptions& options,
                                                     TableState initial) {
  return std::make_unique<EventSimulation>(model, options, std::move(initial));
}

}  // namespace sportsim::billiards
