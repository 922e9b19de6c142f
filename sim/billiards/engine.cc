#include "sim/billiards/engine.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <tuple>

#include "absl/strings/str_format.h"
#include "sim/billiards/cloth.h"
#include "sim/billiards/collision.h"
#include "sim/billiards/event_engine.h"
#include "sim/core/check.h"
#include "sim/core/ode/runge_kutta.h"
#include "sim/core/root_find.h"

namespace sportsim::billiards {
namespace {

constexpr std::array<std::string_view, 2> kEngines = {"event", "stepped"};
constexpr std::array<std::string_view, 3> kIntegrators = {"euler", "semi_implicit_euler", "rk4"};

// A pair closer than this counts as touching (m): frozen balls collide at once when approaching.
constexpr double kTouch = 1e-9;
// Contact times are found to this precision (s): at 20 m/s, 2e-12 m of overlap at most.
constexpr double kTimeTol = 1e-13;
// A step that splits into more sub-steps than this is a runaway (a Zeno cascade).
constexpr int kMaxSubsteps = 1000000;

bool Translating(const Ball& b) { return IsTranslating(b.state); }
bool Moving(const Ball& b) { return IsMoving(b.state); }

// A ball's (r; v, w) stacked for sim/core/ode (the rates do not depend on r).
using RateVec = Eigen::Matrix<double, 6, 1>;  // (v, w)

// One integrator step of length h in the ball's current motion state.
void IntegrateBall(const TableModel& model, uint32_t effects, Integrator integrator, double h,
                   Ball* b) {
  if (!Moving(*b) || h <= 0.0) return;
  const MotionState s = b->state;
  const Eigen::Vector3d w0 = b->w;
  // d(v, w)/dt = cloth rates, autonomous; the position follows the stage velocities (r' = v),
  // so (v, w) is the ODE's state and r is integrated with the same weights.
  const auto f = [&](double /*t*/, const RateVec& y) {
    const Rates k = ClothRates(model, effects, s, y.head<3>(), y.tail<3>());
    RateVec dy;
    dy.head<3>() = k.dv;
    dy.tail<3>() = k.dw;
    return dy;
  };
  switch (integrator) {
    case Integrator::kEuler: {
      RateVec y;
      y.head<3>() = b->v;
      y.tail<3>() = b->w;
      const RateVec k1 = f(0.0, y);
      const RateVec y1 = ode::EulerStep(h, y, k1);
      b->r += h * b->v;
      b->v = y1.head<3>();
      b->w = y1.tail<3>();
      break;
    }
    case Integrator::kRk4: {
      RateVec y;
      y.head<3>() = b->v;
      y.tail<3>() = b->w;
      const ode::Rk4Stages<RateVec> k = ode::Rk4StagesOf(f, 0.0, h, y, f(0.0, y));
      // The stage velocities, as the stages saw them.
      const Eigen::Vector3d v0 = b->v;
      const Eigen::Vector3d v2 = v0 + 0.5 * h * k.k1.head<3>();
      const Eigen::Vector3d v3 = v0 + 0.5 * h * k.k2.head<3>();
      const Eigen::Vector3d v4 = v0 + h * k.k3.head<3>();
      const RateVec y1 = k.Combine(h, y);
      b->r += (h / 6.0) * (v0 + 2.0 * v2 + 2.0 * v3 + v4);
      b->v = y1.head<3>();
      b->w = y1.tail<3>();
      break;
    }
    case Integrator::kSemiImplicitEuler: {
      // Partitioned: the rates first, then the position from the new velocity.
      const Rates k = ClothRates(model, effects, s, b->v, b->w);
      b->v += h * k.dv;
      b->w += h * k.dw;
      b->r += h * b->v;
      break;
    }
    default:
      break;  // ValidateSolverOptions admits only the three above
  }
  b->r.z() = model.radius();
  b->v.z() = 0.0;
  if (s == MotionState::kSpinning) b->v.setZero();
  if ((effects & kEffectDisableOrientation) == 0) {
    // Rotate by the mean angular velocity over the step (exact about a fixed axis).
    const Eigen::Vector3d rot = 0.5 * h * (w0 + b->w);
    const double angle = rot.norm();
    if (angle > 0.0) {
      b->q = (Eigen::Quaterniond(Eigen::AngleAxisd(angle, rot / angle)) * b->q).normalized();
    }
  }
}

enum class ContactKind : uint8_t { kBall = 0, kCushion = 1, kPocket = 2 };

struct Contact {
  double tau = std::numeric_limits<double>::infinity();
  ContactKind kind = ContactKind::kBall;
  int a = -1, b = -1, other = -1;
  bool found() const { return a >= 0; }
  // Deterministic total order: time, kind, then ids.
  bool Before(const Contact& o) const {
    return std::tie(tau, kind, a, b, other) < std::tie(o.tau, o.kind, o.a, o.b, o.other);
  }
};

// Closest point parameter of the chord p0 -> p1 to point c, and the distance.
std::pair<double, double> ChordToPoint(const Eigen::Vector2d& p0, const Eigen::Vector2d& p1,
                                       const Eigen::Vector2d& c) {
  const Eigen::Vector2d d = p1 - p0;
  const double len2 = d.squaredNorm();
  const double s = len2 > 0 ? std::clamp((c - p0).dot(d) / len2, 0.0, 1.0) : 0.0;
  return {s, (p0 + s * d - c).norm()};
}

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Closest approach of the chord p0 -> p1 to the segment [a, b]: (chord parameter, distance).
std::pair<double, double> ChordToSegment(const Eigen::Vector2d& p0, const Eigen::Vector2d& p1,
                                         const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = p1 - p0;
  const Eigen::Vector2d e = b - a;
  const double den = Cross(d, e);
  if (den != 0.0) {
    const double s = Cross(a - p0, e) / den;
    const double t = Cross(a - p0, d) / den;
    if (s >= 0 && s <= 1 && t >= 0 && t <= 1) return {s, 0.0};
  }
  std::pair<double, double> best{0.0, (p0 - ClosestOnSegment(a, b, p0)).norm()};
  const double d1 = (p1 - ClosestOnSegment(a, b, p1)).norm();
  if (d1 < best.second) best = {1.0, d1};
  for (const Eigen::Vector2d& q : {a, b}) {
    const auto [s, dist] = ChordToPoint(p0, p1, q);
    if (dist < best.second) best = {s, dist};
  }
  return best;
}

class SteppedEngine {
 public:
  // `counted` events were handled before this run (the cap covers the whole simulation).
  SteppedEngine(const TableModel& model, const SolverOptions& options, TableState* state,
                std::vector<Event>* events, int64_t counted)
      : model_(model), o_(options), s_(state), events_(events), n_(state->balls.size()),
        events_base_(static_cast<int64_t>(events->size()) - counted) {
    trial_.resize(n_);
    next_.resize(n_);
    margin_.resize(n_);
    accel_.resize(n_);
  }

  // Balls given a velocity were started by TableSimulation::Create (StartMoving).
  absl::Status Run(double t_end) {
    const double dt = o_.dt_s;
    while (s_->t_s < t_end) {
      if (s_->AtRest()) {
        s_->t_s = t_end;
        break;
      }
      // Next grid point after t (a t already on the grid, to rounding, counts as on it).
      const double k = std::floor(s_->t_s / dt * (1.0 + 1e-12) + 1e-9);
      const double t_next = std::min((k + 1.0) * dt, t_end);
      if (absl::Status st = Step(t_next); !st.ok()) return st;
      s_->t_s = t_next;
    }
    return absl::OkStatus();
  }

 private:
  Ball At(int i, double tau) const {
    Ball b = s_->balls[i];
    IntegrateBall(model_, o_.effects, o_.integrator, tau, &b);
    return b;
  }
  Eigen::Vector2d PosAt(int i, double tau) const { return At(i, tau).r.head<2>(); }

  void Record(Event e) { events_->push_back(std::move(e)); }

  void RecordTransition(int i, MotionState from) {
    billiards::RecordTransition(s_->t_s, i, from, s_->balls[i], events_);
  }

  absl::Status Step(double t_end) {
    const double t0 = s_->t_s;
    const double h = t_end - t0;
    double done = 0.0;
    for (int sub = 0; done < h; ++sub) {
      if (sub >= kMaxSubsteps) {
        return absl::ResourceExhaustedError(absl::StrFormat(
            "more than %d collisions and transitions within one step at t = %.9f s", kMaxSubsteps,
            s_->t_s));
      }
      if (static_cast<int64_t>(events_->size()) - events_base_ > o_.max_events) {
        return absl::ResourceExhaustedError(absl::StrFormat(
            "event cap of %d reached at t = %.9f s", o_.max_events, s_->t_s));
      }
      // 1. The sub-step ends at the earliest transition.
      double tau = h - done;
      for (size_t i = 0; i < n_; ++i) {
        next_[i] = NextTransition{};
        accel_[i] = 0.0;
        if (!Moving(s_->balls[i])) continue;
        Rates rates;
        next_[i] = TimeToTransition(model_, o_.effects, s_->balls[i], &rates);
        accel_[i] = rates.dv.norm();
        tau = std::min(tau, next_[i].dt_s);
      }
      // 2. Trial positions at the end of the sub-step.
      for (size_t i = 0; i < n_; ++i) {
        if (!Moving(s_->balls[i])) continue;
        trial_[i] = At(static_cast<int>(i), tau);
        // The path bends away from its chord by at most |a| tau^2 / 4 for any of our schemes.
        margin_[i] = 0.25 * accel_[i] * tau * tau + 1e-12;
      }
      // 3. Continuous collision detection: the earliest contact within the sub-step.
      if (o_.ccd) {
        const Contact c = EarliestContact(tau);
        if (c.found()) {
          for (size_t i = 0; i < n_; ++i) {
            if (Moving(s_->balls[i])) {
              IntegrateBall(model_, o_.effects, o_.integrator, c.tau, &s_->balls[i]);
            }
          }
          done += c.tau;
          s_->t_s = t0 + done;
          Resolve(c);
          if (absl::Status st = CheckFinite(); !st.ok()) return st;
          continue;
        }
      }
      for (size_t i = 0; i < n_; ++i) {
        if (Moving(s_->balls[i])) s_->balls[i] = trial_[i];
      }
      done += tau;
      s_->t_s = t0 + done;
      // 4. Transitions due now.
      for (size_t i = 0; i < n_; ++i) {
        if (next_[i].kind == TransitionKind::kNone || next_[i].dt_s > tau) continue;
        Ball& b = s_->balls[i];
        if ((o_.effects & kEffectEnableDrag) != 0) {
          // With drag the predicted time is an estimate: snap only when the quantity has
          // (nearly) reached zero, else predict again.
          if (TimeToZero(model_, o_.effects, b, next_[i].kind) > 1e-9) continue;
        }
        const MotionState from = b.state;
        ApplyTransition(model_, next_[i].kind, &b);
        RecordTransition(static_cast<int>(i), from);
      }
      // 5. Resting contacts with CCD; without it, every contact is found by overlap here.
      if (o_.ccd) {
        RestingContacts();
      } else {
        DiscreteContacts();
      }
      LeaveTable();
      if (absl::Status st = CheckFinite(); !st.ok()) return st;
    }
    return absl::OkStatus();
  }

  // Earliest contact in [0, tau] among ball pairs, cushions and pockets.
  Contact EarliestContact(double tau) const {
    Contact best;
    const double radius = model_.radius();
    const auto consider = [&best](const Contact& c) {
      if (c.Before(best)) best = c;
    };
    // Finds the first zero of g on [0, tau] given g(0) > 0 and the chord's closest approach at
    // s_c, or returns +inf.
    const auto first_root = [&](auto&& g, double g0, double s_c) -> double {
      const double tc = s_c * tau;
      if (tc > 0.0) {
        const double gc = g(tc);
        if (gc <= 0.0) return FindBracketedRoot(g, 0.0, tc, g0, gc, kTimeTol);
      }
      if (s_c < 1.0) {
        const double g1 = g(tau);
        if (g1 <= 0.0) return FindBracketedRoot(g, 0.0, tau, g0, g1, kTimeTol);
      }
      return std::numeric_limits<double>::infinity();
    };
    const auto& balls = s_->balls;
    for (size_t i = 0; i < n_; ++i) {
      const Ball& bi = balls[i];
      if (bi.state == MotionState::kPocketed) continue;
      const bool ti = Translating(bi);
      const Eigen::Vector2d p0i = bi.r.head<2>();
      const Eigen::Vector2d p1i = ti ? trial_[i].r.head<2>() : p0i;
      // Ball pairs.
      for (size_t j = i + 1; j < n_; ++j) {
        const Ball& bj = balls[j];
        if (bj.state == MotionState::kPocketed) continue;
        const bool tj = Translating(bj);
        if (!ti && !tj) continue;
        const Eigen::Vector2d p1j = tj ? trial_[j].r.head<2>() : bj.r.head<2>();
        const Eigen::Vector2d rel0 = bj.r.head<2>() - p0i;
        const Eigen::Vector2d rel1 = p1j - p1i;
        const auto [s_c, dmin] = ChordToPoint(rel0, rel1, Eigen::Vector2d::Zero());
        const double slack = (ti ? margin_[i] : 0.0) + (tj ? margin_[j] : 0.0);
        if (dmin > 2.0 * radius + slack) continue;
        const double g0 = rel0.norm() - 2.0 * radius;
        Contact c{.kind = ContactKind::kBall, .a = static_cast<int>(i), .b = static_cast<int>(j)};
        if (g0 <= kTouch) {
          // Touching: a real collision now, or a resting contact (slower than
          // kRestingContactSpeed, or not approaching) that RestingContacts() keeps at the end of
          // the sub-step.
          if ((bi.v - bj.v).head<2>().dot(rel0) >= kRestingContactSpeed * rel0.norm()) {
            c.tau = 0.0;
            consider(c);
          }
          continue;
        }
        const auto g = [&](double t) {
          return (PosAt(static_cast<int>(j), t) - PosAt(static_cast<int>(i), t)).norm() -
                 2.0 * radius;
        };
        c.tau = first_root(g, g0, s_c);
        if (c.tau <= tau) consider(c);
      }
      if (!ti) continue;
      // Cushions.
      if (model_.spec().bounded && (o_.effects & kEffectDisableCushions) == 0) {
        const double dc = model_.cushion_contact_distance();
        const auto& cushions = model_.spec().cushions;
        for (size_t k = 0; k < cushions.size(); ++k) {
          const CushionSegment& seg = cushions[k];
          const auto [s_c, dmin] = ChordToSegment(p0i, p1i, seg.a, seg.b);
          if (dmin > dc + margin_[i]) continue;
          const Eigen::Vector2d near0 = ClosestOnSegment(seg.a, seg.b, p0i);
          const double g0 = (p0i - near0).norm() - dc;
          Contact c{.kind = ContactKind::kCushion, .a = static_cast<int>(i),
                    .other = static_cast<int>(k)};
          if (g0 <= kTouch) {
            if (bi.v.head<2>().dot(p0i - near0) <= -kRestingContactSpeed * (p0i - near0).norm()) {
              c.tau = 0.0;
              consider(c);
            }
            continue;  // frozen to the cushion: a resting contact
          }
          const auto g = [&](double t) {
            const Eigen::Vector2d p = PosAt(static_cast<int>(i), t);
            return (p - ClosestOnSegment(seg.a, seg.b, p)).norm() - dc;
          };
          c.tau = first_root(g, g0, s_c);
          if (c.tau <= tau) consider(c);
        }
      }
      // Pockets.
      if (model_.spec().bounded && (o_.effects & kEffectDisablePockets) == 0) {
        const auto& pockets = model_.spec().pockets;
        for (size_t k = 0; k < pockets.size(); ++k) {
          const Pocket& pk = pockets[k];
          const auto [s_c, dmin] = ChordToPoint(p0i, p1i, pk.centre);
          if (dmin > pk.radius_m + margin_[i]) continue;
          const double g0 = (p0i - pk.centre).norm() - pk.radius_m;
          Contact c{.kind = ContactKind::kPocket, .a = static_cast<int>(i),
                    .other = static_cast<int>(k)};
          if (g0 <= 0.0) {
            c.tau = 0.0;
            consider(c);
            continue;
          }
          const auto g = [&](double t) {
            return (PosAt(static_cast<int>(i), t) - pk.centre).norm() - pk.radius_m;
          };
          c.tau = first_root(g, g0, s_c);
          if (c.tau <= tau) consider(c);
        }
      }
    }
    return best;
  }

  void Resolve(const Contact& c) {
    auto& balls = s_->balls;
    switch (c.kind) {
      case ContactKind::kBall: {
        Ball& a = balls[c.a];
        Ball& b = balls[c.b];
        const MotionState fa = a.state, fb = b.state;
        if (!CollideBalls(model_, o_.effects, &a, &b)) return;
        Record({.t_s = s_->t_s, .kind = EventKind::kBallBall, .a = c.a, .b = c.b,
                .va = a.v.head<2>(), .vb = b.v.head<2>(), .ra = a.r.head<2>()});
        RecordTransition(c.a, fa);
        RecordTransition(c.b, fb);
        break;
      }
      case ContactKind::kCushion: {
        Ball& a = balls[c.a];
        const CushionSegment& seg = model_.spec().cushions[c.other];
        const Eigen::Vector2d p = a.r.head<2>();
        const Eigen::Vector2d n = (p - ClosestOnSegment(seg.a, seg.b, p)).normalized();
        const MotionState fa = a.state;
        if (!CollideCushion(model_, n, &a)) return;
        Record({.t_s = s_->t_s, .kind = EventKind::kBallCushion, .a = c.a, .other = c.other,
                .va = a.v.head<2>(), .ra = a.r.head<2>()});
        RecordTransition(c.a, fa);
        break;
      }
      case ContactKind::kPocket:
        Capture(c.a, c.other);
        break;
    }
  }

  void Capture(int i, int pocket) {
    Ball& b = s_->balls[i];
    const MotionState from = b.state;
    b.v.setZero();
    b.w.setZero();
    b.state = MotionState::kPocketed;
    b.pocket = pocket;
    Record({.t_s = s_->t_s, .kind = EventKind::kBallPocket, .a = i, .other = pocket,
            .ra = b.r.head<2>()});
    RecordTransition(i, from);
  }

  // Resting contacts (touching, approaching slower than kRestingContactSpeed: a ball pushed
  // into a frozen group or a cushion by its spin) are kept at sub-step resolution instead of as
  // an endless cascade of micro-collisions: overlap is projected away (only moving balls move)
  // and an approaching pair gets a plastic impulse. Not events; the transitions they cause are.
  void RestingContacts() {
    auto& balls = s_->balls;
    const double radius = model_.radius();
    const bool cushions = model_.spec().bounded && (o_.effects & kEffectDisableCushions) == 0;
    for (int pass = 0; pass < 16; ++pass) {  // Gauss-Seidel: a cluster settles in a few passes
      bool any = false;
      for (size_t i = 0; i < n_; ++i) {
        if (balls[i].state == MotionState::kPocketed) continue;
        for (size_t j = i + 1; j < n_; ++j) {
          if (balls[j].state == MotionState::kPocketed) continue;
          const bool ti = Translating(balls[i]), tj = Translating(balls[j]);
          if (!ti && !tj) continue;
          Eigen::Vector3d d = balls[j].r - balls[i].r;
          d.z() = 0.0;
          const double dist = d.norm();
          const double overlap = 2.0 * radius - dist;
          if (overlap <= 1e-12 || dist == 0.0) continue;
          const Eigen::Vector3d n = d / dist;
          if (ti && tj) {
            balls[i].r -= 0.5 * overlap * n;
            balls[j].r += 0.5 * overlap * n;
          } else if (ti) {
            balls[i].r -= overlap * n;
          } else {
            balls[j].r += overlap * n;
          }
          any = true;
          const MotionState fi = balls[i].state, fj = balls[j].state;
          if (CollideBalls(model_, o_.effects, &balls[i], &balls[j])) {
            RecordTransition(static_cast<int>(i), fi);
            RecordTransition(static_cast<int>(j), fj);
          }
        }
        if (!cushions || !Translating(balls[i])) continue;
        const double dc = model_.cushion_contact_distance();
        for (const CushionSegment& seg : model_.spec().cushions) {
          const Eigen::Vector2d p = balls[i].r.head<2>();
          const Eigen::Vector2d off = p - ClosestOnSegment(seg.a, seg.b, p);
          const double dist = off.norm();
          if (dist >= dc - 1e-12 || dist == 0.0) continue;
          const Eigen::Vector2d n = off / dist;
          balls[i].r.head<2>() += (dc - dist) * n;
          any = true;
          const MotionState from = balls[i].state;
          if (CollideCushion(model_, n, &balls[i])) RecordTransition(static_cast<int>(i), from);
        }
      }
      if (!any) break;
    }
  }

  // Contacts by overlap at the end of a sub-step (CCD off): what a naive stepper does.
  void DiscreteContacts() {
    auto& balls = s_->balls;
    const double radius = model_.radius();
    for (size_t i = 0; i < n_; ++i) {
      if (balls[i].state == MotionState::kPocketed) continue;
      for (size_t j = i + 1; j < n_; ++j) {
        if (balls[j].state == MotionState::kPocketed) continue;
        if ((balls[j].r - balls[i].r).head<2>().norm() < 2.0 * radius) {
          Resolve({.tau = 0, .kind = ContactKind::kBall, .a = static_cast<int>(i),
                   .b = static_cast<int>(j)});
        }
      }
      if (!Translating(balls[i]) || !model_.spec().bounded) continue;
      const Eigen::Vector2d p = balls[i].r.head<2>();
      if ((o_.effects & kEffectDisableCushions) == 0) {
        const auto& cushions = model_.spec().cushions;
        for (size_t k = 0; k < cushions.size(); ++k) {
          if ((p - ClosestOnSegment(cushions[k].a, cushions[k].b, p)).norm() <
              model_.cushion_contact_distance()) {
            Resolve({.tau = 0, .kind = ContactKind::kCushion, .a = static_cast<int>(i),
                     .other = static_cast<int>(k)});
          }
        }
      }
      if ((o_.effects & kEffectDisablePockets) == 0) {
        const auto& pockets = model_.spec().pockets;
        for (size_t k = 0; k < pockets.size(); ++k) {
          if ((p - pockets[k].centre).norm() <= pockets[k].radius_m) {
            Capture(static_cast<int>(i), static_cast<int>(k));
            break;
          }
        }
      }
    }
  }

  // A ball whose centre is past a cushion line by more than a radius has left the table (only
  // possible with cushions off, or through a cushion with CCD off).
  void LeaveTable() {
    if (!model_.spec().bounded) return;
    const double hx = 0.5 * model_.spec().length_m + model_.radius();
    const double hy = 0.5 * model_.spec().width_m + model_.radius();
    for (size_t i = 0; i < n_; ++i) {
      const Ball& b = s_->balls[i];
      if (b.state == MotionState::kPocketed) continue;
      if (std::abs(b.r.x()) > hx || std::abs(b.r.y()) > hy) Capture(static_cast<int>(i), -1);
    }
  }

  absl::Status CheckFinite() const {
    for (const Ball& b : s_->balls) {
      if (!b.r.allFinite() || !b.v.allFinite() || !b.w.allFinite()) {
        return absl::InternalError(
            absl::StrFormat("ball %s: state became non-finite at t = %.9f s", b.id, s_->t_s));
      }
    }
    return absl::OkStatus();
  }

  const TableModel& model_;
  const SolverOptions& o_;
  TableState* s_;
  std::vector<Event>* events_;
  size_t n_;
  int64_t events_base_;
  std::vector<Ball> trial_;
  std::vector<NextTransition> next_;
  std::vector<double> margin_;
  std::vector<double> accel_;  // |dv/dt| at the start of the sub-step (m/s^2)
};

// The stepped engine behind the TableSimulation interface: the table state is the state.
class SteppedSimulation final : public TableSimulation {
 public:
  SteppedSimulation(const TableModel& model, const SolverOptions& options, TableState state)
      : model_(model), o_(options), state_(std::move(state)) {}

  absl::Status AdvanceTo(double t_s, std::vector<Event>* events) override {
    if (!(std::isfinite(t_s) && t_s >= state_.t_s)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "t_end_s must be finite and not before the table's time %g s, got %g", state_.t_s,
          t_s));
    }
    const size_t before = events->size();
    SteppedEngine engine(model_, o_, &state_, events, processed_);
    const absl::Status s = engine.Run(t_s);
    processed_ += static_cast<int64_t>(events->size() - before);
    return s;
  }
  const TableState& state() override { return state_; }
  double time() const override { return state_.t_s; }
  bool AtRest() const override { return state_.AtRest(); }
  int64_t events_processed() const override { return processed_; }

 private:
  const TableModel& model_;
  const SolverOptions o_;
  TableState state_;
  int64_t processed_ = 0;
};

}  // namespace

absl::StatusOr<std::unique_ptr<TableSimulation>> TableSimulation::Create(
    const TableModel& model, const SolverOptions& options, TableState initial,
    std::vector<Event>* events) {
  if (absl::Status s = ValidateSolverOptions(options); !s.ok()) return s;
  if (!std::isfinite(initial.t_s)) {
    return absl::InvalidArgumentError("the table's time must be finite");
  }
  StartMoving(model, &initial, events);
  std::unique_ptr<TableSimulation> sim;
  if (options.engine == Engine::kEvent) {
    sim = MakeEventSimulation(model, options, std::move(initial));
  } else {
    sim = std::make_unique<SteppedSimulation>(model, options, std::move(initial));
  }
  return sim;
}

std::span<const std::string_view> EngineNames() { return kEngines; }
std::span<const std::string_view> IntegratorNames() { return kIntegrators; }

std::string_view EngineName(Engine e) { return e == Engine::kEvent ? "event" : "stepped"; }

absl::Status ValidateSolverOptions(const SolverOptions& o) {
  if (o.engine != Engine::kStepped && o.engine != Engine::kEvent) {
    return absl::InvalidArgumentError("engine must be event or stepped");
  }
  if (o.integrator != Integrator::kEuler && o.integrator != Integrator::kSemiImplicitEuler &&
      o.integrator != Integrator::kRk4) {
    return absl::InvalidArgumentError("integrator must be euler, semi_implicit_euler or rk4");
  }
  if (absl::Status s = CheckFiniteInRange("dt_s", o.dt_s, 1e-6, false, 0.1, false); !s.ok()) {
    return s;
  }
  if (absl::Status s = ValidateEffectBits("effects", o.effects, kEffectKnownBits); !s.ok()) {
    return s;
  }
  if (o.max_events < 1 || o.max_events > 10'000'000) {
    return absl::InvalidArgumentError(
        absl::StrFormat("max_events must be in [1, 10000000], got %d", o.max_events));
  }
  if (o.engine == Engine::kEvent) {
    if (EffectOn(o.effects, kEffectEnableDrag)) {
      return absl::InvalidArgumentError(
          "engine: the event engine cannot model air drag (it has no closed form): use engine "
          "stepped or leave drag off");
    }
  }
  return absl::OkStatus();
}

absl::Status Advance(const TableModel& model, const SolverOptions& options, double t_end_s,
                     TableState* state, std::vector<Event>* events) {
  // Checked before Create touches anything: a bad time changes nothing (Create checks the
  // options).
  if (!(std::isfinite(t_end_s) && t_end_s >= state->t_s)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "t_end_s must be finite and not before the table's time %g s, got %g", state->t_s,
        t_end_s));
  }
  absl::StatusOr<std::unique_ptr<TableSimulation>> sim =
      TableSimulation::Create(model, options, *state, events);
  if (!sim.ok()) return sim.status();
  const absl::Status s = (*sim)->AdvanceTo(t_end_s, events);
  *state = (*sim)->state();
  return s;
}

void StartMoving(const TableModel& model, TableState* state, std::vector<Event>* events) {
  for (size_t i = 0; i < state->balls.size(); ++i) {
    Ball& b = state->balls[i];
    if (b.state != MotionState::kStationary && b.state != MotionState::kSpinning) continue;
    b.r.z() = model.radius();
    b.v.z() = 0.0;
    const MotionState from = b.state;
    b.state = Classify(model, b);
    RecordTransition(state->t_s, static_cast<int>(i), from, b, events);
  }
}

double TotalKineticEnergy(const TableModel& model, const TableState& state) {
  double e = 0.0;
  for (const Ball& b : state.balls) {
    if (b.state != MotionState::kPocketed) e += KineticEnergy(model, b);
  }
  return e;
}

}  // namespace sportsim::billiards
