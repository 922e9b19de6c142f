#include "sim/golf/ground.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "sim/core/check.h"
#include "sim/core/effects.h"
#include "sim/core/ode/integrator.h"

namespace sportsim::golf {

namespace {

using Eigen::Vector3d;

constexpr double kPi = std::numbers::pi;
// The steepest plane (%): a putting surface or a fairway, not a wall.
constexpr double kMaxSlopePct = 20.0;
// The last piece before a slip or a roll ends, taken at constant acceleration (s): the steps
// before it shrink toward the end (OnPlane).
constexpr double kLastPiece = 1e-4;
// The most path samples a run may ask for (max_time_s / sample_interval_s).
constexpr double kMaxSamples = 1e6;
// Impacts before the bouncing is ended by force (each impact at most keeps 0.765 of the normal
// speed, so ordinary runs end in tens).
constexpr int kMaxImpacts = 1000;

Vector3d Unit(const Vector3d& v, const Vector3d& fallback) {
  const double n = v.norm();
  return n > 0.0 ? Vector3d(v / n) : fallback;
}

// The cubic Hermite interpolant of a step of length h from (p0, v0) to (p1, v1), at the
// fraction f of the step: the position and the velocity. Exact for constant acceleration.
struct HermitePoint {
  Vector3d p, v;
};
HermitePoint Hermite(const Vector3d& p0, const Vector3d& v0, const Vector3d& p1,
                     const Vector3d& v1, double h, double f) {
  const double f2 = f * f, f3 = f2 * f;
  const Vector3d m0 = h * v0, m1 = h * v1;
  return {(2 * f3 - 3 * f2 + 1) * p0 + (f3 - 2 * f2 + f) * m0 + (-2 * f3 + 3 * f2) * p1 +
              (f3 - f2) * m1,
          ((6 * f2 - 6 * f) * p0 + (3 * f2 - 4 * f + 1) * m0 + (-6 * f2 + 6 * f) * p1 +
           (3 * f2 - 2 * f) * m1) /
              h};
}

// What the run needs of the inputs, resolved once.
struct Env {
  Vector3d n;         // the plane's unit normal
  Vector3d g;         // gravity (0, 0, -g)
  Vector3d g_t;       // gravity along the plane (zero when the slope is switched off)
  Vector3d fall;      // unit fall line (any tangent on the flat)
  double g_n = 0.0;   // gravity's normal part, g n_z
  double radius = 0.0;
  double k = 0.4;     // I / (m R^2)
  double mu = 0.4;    // skid friction
  double rho = 0.0;   // rolling resistance
  Vector3d hole_c;    // the hole's centre, on the plane
  double hole_r = 0.0;
  double stick_r = 0.0;  // the flagstick's radius; 0: out
  double stick_e = 0.0;  // its restitution
  bool hole = false;
};

// The ball: its centre, velocity and angular velocity.
struct Ball {
  Vector3d c, v, w;
};

Vector3d PlanePoint(const GroundPlane& plane, double x, double y) {
  return Vector3d(x, y, plane.HeightAt(x, y));
}

class Run {
 public:
  Run(const Env& env, const Surface& surface, const GroundOptions& options)
      : e_(env), surface_(surface), options_(options) {}

  absl::StatusOr<GroundResult> Go(const GroundStart& start, const GroundPlane& plane);

 private:
  Vector3d Contact(const Vector3d& centre) const { return centre - e_.radius * e_.n; }
  void Emit(GroundEventKind kind) { EmitAt(kind, b_, t_); }
  void EmitAt(GroundEventKind kind, const Ball& ball, double t) {
    result_.events.push_back(GroundEvent{.t_s = t,
                                         .kind = kind,
                                         .position_m = Contact(ball.c),
                                         .velocity_mps = ball.v,
                                         .spin_radps = ball.w.norm()});
  }
  void Sample(double t, const Vector3d& centre, double speed) {
    result_.samples.push_back(GroundSample{.t_s = t, .position_m = Contact(centre),
                                           .speed_mps = speed});
  }
  // Samples due in (t0, t1] along the step from -> to (on its Hermite interpolant).
  void SampleSegment(double t0, double t1, const Ball& from, const Ball& to) {
    if (options_.sample_interval_s <= 0.0) return;
    while (next_sample_ <= t1 && t1 > t0) {
      const double f = std::clamp((next_sample_ - t0) / (t1 - t0), 0.0, 1.0);
      const HermitePoint q = Hermite(from.c, from.v, to.c, to.v, t1 - t0, f);
      Sample(next_sample_, q.p, q.v.norm());
      next_sample_ = start_t_ + options_.sample_interval_s * static_cast<double>(++samples_);
    }
  }
  void Finish(bool holed) {
    result_.holed = holed;
    result_.t_rest_s = t_;
    if (holed) {
      result_.rest_m = e_.hole_c;
      b_.v.setZero();
      b_.w.setZero();
    } else {
      result_.rest_m = Contact(b_.c);
    }
    Emit(holed ? GroundEventKind::kHoled : GroundEventKind::kRest);
    if (holed) result_.events.back().position_m = e_.hole_c;
    if (options_.sample_interval_s > 0.0) {
      Sample(t_, holed ? Vector3d(e_.hole_c + e_.radius * e_.n) : b_.c, 0.0);
    }
  }

  absl::Status Poll() {
    if (options_.cancelled && ++polls_ % ode::kPollSteps == 0 && options_.cancelled()) {
      return absl::CancelledError("the ground phase was cancelled");
    }
    if (t_ - start_t_ > options_.max_time_s) {
      return absl::OutOfRangeError(absl::StrFormat(
          "the ball did not come to rest within max_time_s (%g s)", options_.max_time_s));
    }
    return absl::OkStatus();
  }

  void Impact();
  // A hop from the plane, back onto it.
  void Hop();
  // The hole as the contact point moves q0 -> q1 (speeds v0 -> v1) over [t0, t0 + h]:
  // true when the ball drops in (t_ and the ball set to the entry).
  enum class Rim { kNone, kHoled, kDeflected };
  Rim CrossHole(double t0, double h, const Ball& from, const Ball& to);
  // The ball meets the flagstick after entering the rim at `entry` (time te): holed, or b_ and
  // t_ set to the ball leaving the stick.
  Rim HitFlagstick(const Ball& entry, const Vector3d& de, const Vector3d& dir, double offset,
                   double te);
  absl::Status OnPlane();

  const Env& e_;
  const Surface& surface_;
  const GroundOptions& options_;
  GroundResult result_;
  Ball b_;
  double t_ = 0.0;
  double start_t_ = 0.0;
  double next_sample_ = 0.0;
  int64_t samples_ = 0;
  int64_t polls_ = 0;
  bool in_rim_ = false;  // the contact point is inside the rim's circle (after a lip-out)
  bool holed_ = false;
};

// Penner's bounce against the plane tilted toward the ball by theta_c, with the tangential
// impulse that stops the contact point's slip, capped by Coulomb (see ground.h).
void Run::Impact() {
  const Vector3d& n = e_.n;
  const double vn = -b_.v.dot(n);
  const Vector3d vt = b_.v + vn * n;
  const double vt_norm = vt.norm();
  Vector3d np = n;
  if (vt_norm > 0.0 && surface_.critical_angle_scale > 0.0) {
    const double descent = std::atan2(vn, vt_norm);
    const double tc = std::min(
        surface_.critical_angle_scale * PennerCriticalAngle(b_.v.norm(), descent),
        0.5 * kPi - descent);  // at most head-on against the tilted plane
    np = std::cos(tc) * n - std::sin(tc) * (vt / vt_norm);
  }
  const double un = std::max(-b_.v.dot(np), 0.0);
  const double e = std::min(1.0, surface_.restitution_scale * PennerRestitution(un));
  const double jn = (1.0 + e) * un;  // normal impulse per unit mass
  Vector3d slip = b_.v + b_.w.cross(-e_.radius * np);
  slip -= slip.dot(np) * np;
  b_.v += jn * np;
  const double sn = slip.norm();
  if (sn > 0.0) {
    const Vector3d sh = slip / sn;
    const double j = std::min(sn * e_.k / (1.0 + e_.k), surface_.bounce_friction * jn);
    b_.v -= j * sh;
    b_.w += (j / (e_.k * e_.radius)) * np.cross(sh);
  }
  ++result_.bounces;
}

void Run::Hop() {
  const Vector3d& n = e_.n;
  const double vn = b_.v.dot(n);
  const double tf = 2.0 * vn / e_.g_n;  // back on the plane (gravity's normal part g_n)
  const Vector3d c0 = b_.c;
  const Vector3d v0 = b_.v;
  if (options_.sample_interval_s > 0.0) {
    while (next_sample_ <= t_ + tf) {
      const double s = next_sample_ - t_;
      const Vector3d c = c0 + v0 * s + 0.5 * s * s * e_.g;
      Sample(next_sample_, c, (v0 + s * e_.g).norm());
      next_sample_ = start_t_ + options_.sample_interval_s * static_cast<double>(++samples_);
    }
  }
  b_.c = c0 + v0 * tf + 0.5 * tf * tf * e_.g;
  b_.v = v0 + tf * e_.g;
  // Back on the plane exactly (rounding): the centre R above it.
  b_.c += (e_.radius - b_.c.dot(n)) * n;
  t_ += tf;
}

Run::Rim Run::CrossHole(double t0, double h, const Ball& from, const Ball& to) {
  if (!e_.hole) return Rim::kNone;
  const Vector3d d0 = Contact(from.c) - e_.hole_c;
  const Vector3d d1 = Contact(to.c) - e_.hole_c;
  const double r2 = e_.hole_r * e_.hole_r;
  if (in_rim_) {
    if (d1.squaredNorm() > r2) in_rim_ = false;
    return Rim::kNone;
  }
  if (d0.squaredNorm() <= r2) return Rim::kNone;  // only entries count
  // The step's path as the cubic Hermite interpolant of its ends (positions and velocities):
  // as accurate as the step itself, where a chord is not. It lies in the hull of its Bezier
  // points d0, d0 + m0/3, d1 - m1/3, d1: a step whose hull stays outside the rim is passed by.
  const Vector3d m0 = h * from.v, m1 = h * to.v;
  const double reach = std::max({(m0 / 3.0).norm(), (d1 - m1 / 3.0 - d0).norm(), (d1 - d0).norm()});
  if (d0.norm() - reach > e_.hole_r) return Rim::kNone;
  auto at = [&](double f) { return Hermite(d0, from.v, d1, to.v, h, f); };
  // The first crossing of the rim: probes close enough that the path cannot enter and leave
  // the rim between two unseen (a quarter of the radius apart at most), then bisection.
  const int probes = static_cast<int>(
      std::clamp(std::ceil(3.0 * reach / (0.25 * e_.hole_r)), 16.0, 1e6));
  double lo = 0.0, hi = -1.0;
  for (int i = 1; i <= probes; ++i) {
    const double f = static_cast<double>(i) / probes;
    if (at(f).p.squaredNorm() <= r2) {
      hi = f;
      break;
    }
    lo = f;
  }
  if (hi < 0.0) return Rim::kNone;
  for (int i = 0; i < 60 && hi - lo > 1e-15; ++i) {
    const double mid = 0.5 * (lo + hi);
    (at(mid).p.squaredNorm() <= r2 ? hi : lo) = mid;
  }
  const double lambda = hi;
  const HermitePoint entry_point = at(lambda);
  const Vector3d& de = entry_point.p;
  const Vector3d& ve = entry_point.v;
  const double speed = ve.norm();
  const Vector3d dir = Unit(ve, Unit(d1 - d0, e_.fall));
  const double offset = std::abs(de.cross(dir).dot(e_.n));
  const double te = t0 + lambda * h;
  const Ball entry{e_.hole_c + de + e_.radius * e_.n, ve, from.w + lambda * (to.w - from.w)};
  if (speed <= HoleCaptureSpeed(e_.hole_r, e_.radius, offset, -e_.g.z())) {
    b_ = entry;
    t_ = te;
    return Rim::kHoled;
  }
  if (e_.stick_r > 0.0 && offset < e_.stick_r + e_.radius) {
    in_rim_ = true;
    return HitFlagstick(entry, de, dir, offset, te);
  }
  EmitAt(GroundEventKind::kLipOut, entry, te);
  in_rim_ = true;
  return Rim::kNone;
}

Run::Rim Run::HitFlagstick(const Ball& entry, const Vector3d& de, const Vector3d& dir,
                           double offset, double te) {
  const double speed = entry.v.norm();
  const double reach = e_.stick_r + e_.radius;  // centre to centre at contact
  // Along the line from the rim to the contact, then the contact's normal (in the plane).
  const double s1 = std::max(0.0, -de.dot(dir) - std::sqrt(reach * reach - offset * offset));
  const Vector3d c = de + s1 * dir;
  const Vector3d nc = Unit(c, -dir);
  const Vector3d v1 = entry.v - (1.0 + e_.stick_e) * entry.v.dot(nc) * nc;
  const double t1 = s1 / speed;
  const double g = -e_.g.z();
  const double v1n = v1.norm();
  bool holed = v1n == 0.0;
  Vector3d exit = c;
  double t_exit = t1;
  if (!holed) {
    // It reaches the rim again when its leading side does (its centre R short of the rim),
    // having fallen d since the near rim. It is in if by then it has fallen its radius (the
    // wall is met below its centre), or if it has too little speed left to climb the drop
    // back over the lip (v^2 < 2 g d).
    const Vector3d u = v1 / v1n;
    const double cu = c.dot(u);
    const double to_rim = -cu + std::sqrt(std::max(0.0, cu * cu - c.squaredNorm() +
                                                             e_.hole_r * e_.hole_r));
    const double t = t1 + std::max(0.0, to_rim - e_.radius) / v1n;
    const double drop = 0.5 * g * t * t;
    holed = drop >= e_.radius || v1n * v1n <= 2.0 * g * drop;
    // Out: over the hole it flies (no friction, the spin kept), and goes on from the rim.
    exit = c + to_rim * u;
    t_exit = t1 + to_rim / v1n;
  }
  b_ = Ball{e_.hole_c + c + e_.radius * e_.n, v1, entry.w};
  t_ = te + t1;
  if (holed) return Rim::kHoled;
  Emit(GroundEventKind::kLipOut);
  b_.c = e_.hole_c + exit + e_.radius * e_.n;
  t_ = te + t_exit;
  return Rim::kDeflected;
}

// The skid and the roll on the plane, to rest or into the hole.
absl::Status Run::OnPlane() {
  const Vector3d& n = e_.n;
  // Without a pull along the plane (flat, or the slope switched off) neither the slip's nor the
  // velocity's direction turns: the skid and the roll are each at constant acceleration, and
  // one step reaches each transition exactly (the step is cut there). Otherwise RK4 at dt_s.
  const bool straight = e_.g_t.squaredNorm() == 0.0;
  const double h = straight ? options_.max_time_s : options_.dt_s;
  const double rate_slip = e_.mu * e_.g_n * (1.0 + 1.0 / e_.k);
  // The slip of the contact point (tangential: the ball is on the plane) and the spin about the
  // normal (friction does not change it), from the ball as it is now: here, and after the
  // flagstick.
  Vector3d s;
  double w_normal = 0.0;
  bool rolling = false;
  auto take_ball = [&] {
    s = b_.v + b_.w.cross(-e_.radius * n);
    s -= s.dot(n) * n;
    w_normal = b_.w.dot(n);
    rolling = s.norm() <= 1e-12;
    if (rolling) s.setZero();
  };
  take_ball();
  auto spin_of = [&](const Vector3d& v, const Vector3d& slip) {
    return Vector3d(w_normal * n + n.cross(v - slip) / e_.radius);
  };
  const double hold = e_.rho * e_.g_n;  // the most the resistance holds at rest
  for (;;) {
    if (absl::Status st = Poll(); !st.ok()) return st;
    const Ball from = b_;
    const double t0 = t_;
    double step = h;
    bool transition = false;  // slip or speed reaches zero at the step's end
    if (!rolling) {
      const Vector3d sh = s / s.norm();
      const double r = rate_slip - e_.g_t.dot(sh);
      // Near its end the slip's direction turns ever faster (the slope's pull against a
      // vanishing slip): the steps shrink with the time left, half of it each, so each turns
      // the direction by a bounded angle, until the last piece is short.
      const double left = r > 0.0 ? s.norm() / r : h;
      const double hs = straight || left <= kLastPiece ? h : std::min(h, 0.5 * left);
      if (r > 0.0 && s.norm() <= r * hs) {
        // The slip ends inside this step. v - k/(1+k) s moves at the constant rate g_t/(1+k)
        // (the friction terms cancel), so the velocity at the end of the slip is exact whatever
        // path the slip's direction takes on the way to zero; the position takes the slip as
        // shrinking linearly over the piece.
        step = s.norm() / r;
        const double kk = e_.k / (1.0 + e_.k);
        const Vector3d base = b_.v - kk * s;
        b_.c += (base + 0.5 * kk * s) * step + (0.5 * step * step / (1.0 + e_.k)) * e_.g_t;
        b_.v = base + (step / (1.0 + e_.k)) * e_.g_t;
        s.setZero();
        transition = true;
      } else {
        // RK4 on (c, v, s).
        struct D {
          Vector3d c, v, s;
        };
        auto f = [&](const Vector3d& v, const Vector3d& sl) {
          const Vector3d u = Unit(sl, Vector3d::Zero());
          return D{v, e_.g_t - e_.mu * e_.g_n * u, e_.g_t - rate_slip * u};
        };
        step = hs;
        const D k1 = f(b_.v, s);
        const D k2 = f(b_.v + 0.5 * hs * k1.v, s + 0.5 * hs * k1.s);
        const D k3 = f(b_.v + 0.5 * hs * k2.v, s + 0.5 * hs * k2.s);
        const D k4 = f(b_.v + hs * k3.v, s + hs * k3.s);
        b_.c += (hs / 6.0) * (k1.c + 2.0 * k2.c + 2.0 * k3.c + k4.c);
        b_.v += (hs / 6.0) * (k1.v + 2.0 * k2.v + 2.0 * k3.v + k4.v);
        s += (hs / 6.0) * (k1.s + 2.0 * k2.s + 2.0 * k3.s + k4.s);
      }
    } else {
      const double speed = b_.v.norm();
      const Vector3d vh = Unit(b_.v, Unit(e_.g_t, e_.fall));
      const double r = (hold - e_.g_t.dot(vh)) / (1.0 + e_.k);
      // As for the slip: the path hooks down the slope ever tighter as the ball stops.
      const double left = r > 0.0 ? speed / r : h;
      const double hs = straight || left <= kLastPiece ? h : std::min(h, 0.5 * left);
      if (r > 0.0 && speed <= r * hs) {
        step = speed / r;
        const Vector3d a = (e_.g_t - hold * vh) / (1.0 + e_.k);
        b_.c += b_.v * step + 0.5 * step * step * a;
        b_.v.setZero();
        transition = true;
      } else {
        auto acc = [&](const Vector3d& v) {
          return Vector3d((e_.g_t - hold * Unit(v, vh)) / (1.0 + e_.k));
        };
        step = hs;
        const Vector3d k1 = acc(b_.v);
        const Vector3d k2 = acc(b_.v + 0.5 * hs * k1);
        const Vector3d k3 = acc(b_.v + 0.5 * hs * k2);
        const Vector3d k4 = acc(b_.v + hs * k3);
        const Vector3d v0 = b_.v;
        b_.c += hs * v0 + (hs * hs / 6.0) * (k1 + k2 + k3);
        b_.v += (hs / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
      }
    }
    // Keep the centre on the plane against rounding.
    b_.c += (e_.radius - b_.c.dot(n)) * n;
    b_.v -= b_.v.dot(n) * n;
    b_.w = spin_of(b_.v, s);
    t_ = t0 + step;
    ++result_.steps;
    SampleSegment(t0, t_, from, b_);
    switch (CrossHole(t0, step, from, b_)) {
      case Rim::kNone: break;
      case Rim::kHoled: holed_ = true; return absl::OkStatus();
      case Rim::kDeflected:
        take_ball();  // off the flagstick: the new velocity with the old spin slips
        continue;
    }
    if (!transition) continue;
    if (!rolling) {
      rolling = true;
      Emit(GroundEventKind::kRoll);
      continue;
    }
    // Speed zero: at rest where the resistance holds the slope's pull.
    if (e_.g_t.norm() <= hold) {
      if (e_.hole && (Contact(b_.c) - e_.hole_c).norm() <= e_.hole_r) {
        holed_ = true;  // at rest over the hole: it drops
      }
      return absl::OkStatus();
    }
  }
}

absl::StatusOr<GroundResult> Run::Go(const GroundStart& start, const GroundPlane& plane) {
  start_t_ = t_ = start.time_s;
  next_sample_ = start_t_;
  b_.c = PlanePoint(plane, start.position_m.x(), start.position_m.y()) + e_.radius * e_.n;
  b_.v = start.velocity_mps;
  b_.w = Vector3d::Zero();
  switch (start.kind) {
    case GroundStartKind::kLanding:
      if ((options_.effects & kGroundDisableSpin) == 0) b_.w = start.spin_radps;
      break;
    case GroundStartKind::kPutt:
    case GroundStartKind::kRolling: {
      // Along the plane, at the given speed, heading where the given velocity points.
      const double speed = b_.v.norm();
      b_.v = speed * Unit(b_.v - b_.v.dot(e_.n) * e_.n, Vector3d::Zero());
      if (start.kind == GroundStartKind::kRolling) {
        b_.w = e_.n.cross(b_.v) / e_.radius;  // the contact point at rest
      }
      break;
    }
  }
  if (options_.sample_interval_s > 0.0) {
    Sample(t_, b_.c, b_.v.norm());
    next_sample_ = start_t_ + options_.sample_interval_s;
    samples_ = 1;
  }
  if (start.kind == GroundStartKind::kLanding) {
    bool first = true;
    double last_rebound = std::numeric_limits<double>::infinity();
    for (;;) {
      if (absl::Status st = Poll(); !st.ok()) return st;
      if (e_.hole && (Contact(b_.c) - e_.hole_c).norm() <= e_.hole_r - e_.radius) {
        Emit(first ? GroundEventKind::kLanding : GroundEventKind::kBounce);
        Finish(true);
        return std::move(result_);
      }
      Impact();
      Emit(first ? GroundEventKind::kLanding : GroundEventKind::kBounce);
      first = false;
      // The bouncing ends when a rebound is lower than settle_speed_mps, or no lower than the
      // one before: a ball skimming down a slope at a grazing angle, where the slope's pull
      // during each hop feeds what the impacts take (Penner's impact law is fitted to
      // landings, not to a ball skipping along the turf); on the plane it goes on skidding or
      // rolling.
      const double vn = b_.v.dot(e_.n);
      if (vn < options_.settle_speed_mps || vn >= last_rebound || result_.bounces >= kMaxImpacts) {
        b_.v -= vn * e_.n;  // stays on the plane
        break;
      }
      last_rebound = vn;
      Hop();
    }
  }
  if (absl::Status st = OnPlane(); !st.ok()) return st;
  Finish(holed_);
  return std::move(result_);
}

}  // namespace

Vector3d GroundPlane::Normal() const {
  const double p = slope_pct / 100.0;
  const double d = slope_toward_deg * kPi / 180.0;
  return Vector3d(p * std::cos(d), p * std::sin(d), 1.0).normalized();
}

double GroundPlane::HeightAt(double x, double y) const {
  const double d = slope_toward_deg * kPi / 180.0;
  const double z = -(slope_pct / 100.0) * (x * std::cos(d) + y * std::sin(d));
  return z == 0.0 ? 0.0 : z;  // never -0
}

GroundStart LandingFromFlight(const FlightResult& flight) {
  return GroundStart{.kind = GroundStartKind::kLanding,
                     .position_m = flight.landing_position_m,
                     .velocity_mps = flight.landing_velocity_mps,
                     .spin_radps = flight.landing_spin_rpm * kRpmToRadPerS * flight.spin_axis,
                     .time_s = flight.flight_time_s};
}

GroundStart PuttStart(double x, double y, double speed, double direction_deg) {
  const double d = direction_deg * kPi / 180.0;
  return GroundStart{.kind = GroundStartKind::kPutt,
                     .position_m = Vector3d(x, y, 0.0),
                     .velocity_mps = speed * Vector3d(std::cos(d), std::sin(d), 0.0)};
}

GroundStart RollingStart(double x, double y, double speed, double direction_deg) {
  GroundStart s = PuttStart(x, y, speed, direction_deg);
  s.kind = GroundStartKind::kRolling;
  return s;
}

std::string_view GroundEventName(GroundEventKind kind) {
  switch (kind) {
    case GroundEventKind::kLanding: return "landing";
    case GroundEventKind::kBounce: return "bounce";
    case GroundEventKind::kRoll: return "roll";
    case GroundEventKind::kHoled: return "holed";
    case GroundEventKind::kLipOut: return "lip_out";
    case GroundEventKind::kRest: return "rest";
  }
  return "rest";
}

double HoleCaptureSpeed(double hole_radius, double ball_radius, double offset, double g) {
  if (offset >= hole_radius) return 0.0;
  const double chord = 2.0 * std::sqrt(hole_radius * hole_radius - offset * offset);
  return std::max(0.0, (chord - ball_radius) * std::sqrt(g / (2.0 * ball_radius)));
}

absl::Status CheckSlopeHolds(const GroundPlane& plane, const Surface& surface) {
  if (plane.slope_pct / 100.0 <= surface.rolling_resistance) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrFormat(
      "slope_pct: %g %% is steeper than the %s (Stimp %.3g ft) holds a ball at rest (at most "
      "%.3g %%): the ball would never stop",
      plane.slope_pct, surface.name, surface.stimp_ft(), 100.0 * surface.rolling_resistance));
}

absl::Status ValidateGround(const BallSpec& ball, const Surface& surface,
                            const GroundPlane& plane, const Hole& hole,
                            const GroundStart& start, const GroundOptions& options) {
  if (absl::Status s = ValidateBallSpec(ball); !s.ok()) return s;
  if (absl::Status s = ValidateSurface(surface); !s.ok()) return s;
  if (absl::Status s = CheckFieldsInRange({
          {"slope_pct", plane.slope_pct, 0, false, kMaxSlopePct},
          {"slope_toward_deg", plane.slope_toward_deg, -1e6, false, 1e6},
          {"gravity_mps2", options.gravity_mps2, 0, true, 100},
          {"dt_s", options.dt_s, 1e-6, false, 0.01},

          {"max_time_s", options.max_time_s, 0, true, 3600},
          {"settle_speed_mps", options.settle_speed_mps, 0.001, false, 1},
          {"start.time_s", start.time_s, -1e6, false, 1e6},
      });
      !s.ok()) {
    return s;
  }
  // Samples: none, or at most kMaxSamples over max_time_s.
  if (options.sample_interval_s != 0.0) {
    if (absl::Status s =
            CheckFiniteInRange("sample_interval_s", options.sample_interval_s, 1e-3, false, 10, false);
        !s.ok()) {
      return absl::InvalidArgumentError(absl::StrCat(s.message(), " (or 0: no samples)"));
    }
    if (options.max_time_s / options.sample_interval_s > kMaxSamples) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "sample_interval_s: %g s over max_time_s %g s is more than %g samples",
          options.sample_interval_s, options.max_time_s, kMaxSamples));
    }
  }
  if (absl::Status s = ValidateEffectBits("effects", options.effects, kGroundEffectBits);
      !s.ok()) {
    return s;
  }
  if (options.hole) {
    if (absl::Status s = CheckFiniteInRange("hole.diameter_m", hole.diameter_m, ball.diameter_m,
                                            true, 1, false);
        !s.ok()) {
      return s;
    }
    if (absl::Status s = CheckFiniteInRange("hole.depth_m", hole.depth_m, 0, true, 1, false);
        !s.ok()) {
      return s;
    }
    if (hole.flagstick_diameter_m != 0.0) {
      if (absl::Status s = CheckFieldsInRange(
              {{"hole.flagstick_diameter_m", hole.flagstick_diameter_m, 0.005, false,
                0.5 * hole.diameter_m},
               {"hole.flagstick_restitution", hole.flagstick_restitution, 0, false, 1}});
          !s.ok()) {
        return absl::InvalidArgumentError(absl::StrCat(s.message(), " (or 0: the flagstick out)"));
      }
    }
    for (const auto& [name, v] : {std::pair{"hole.x_m", hole.x_m}, {"hole.y_m", hole.y_m}}) {
      if (absl::Status s = CheckFiniteInRange(name, v, -1e5, false, 1e5, false); !s.ok()) {
        return s;
      }
    }
  }
  const char* const pos[] = {"start.position_m.x", "start.position_m.y"};
  for (int i = 0; i < 2; ++i) {
    if (absl::Status s = CheckFiniteInRange(pos[i], start.position_m[i], -1e5, false, 1e5, false);
        !s.ok()) {
      return s;
    }
  }
  const char* const vel[] = {"start.velocity_mps.x", "start.velocity_mps.y",
                             "start.velocity_mps.z"};
  const char* const spin[] = {"start.spin_radps.x", "start.spin_radps.y", "start.spin_radps.z"};
  for (int i = 0; i < 3; ++i) {
    if (absl::Status s = CheckFiniteInRange(vel[i], start.velocity_mps[i], -200, false, 200, false);
        !s.ok()) {
      return s;
    }
    if (absl::Status s = CheckFiniteInRange(spin[i], start.spin_radps[i], -1e4, false, 1e4, false);
        !s.ok()) {
      return s;
    }
  }
  const Vector3d n = plane.Normal();
  if (start.kind == GroundStartKind::kLanding && !(start.velocity_mps.dot(n) < 0.0)) {
    return absl::InvalidArgumentError(
        "start.velocity_mps: a landing ball must move into the plane");
  }
  if ((options.effects & kGroundDisableSlope) == 0) {
    if (absl::Status s = CheckSlopeHolds(plane, surface); !s.ok()) return s;
  }
  if (options.hole && start.kind != GroundStartKind::kLanding) {
    const Vector3d q = PlanePoint(plane, start.position_m.x(), start.position_m.y());
    const Vector3d hc = PlanePoint(plane, hole.x_m, hole.y_m);
    if ((q - hc).norm() <= 0.5 * hole.diameter_m) {
      return absl::InvalidArgumentError("start.position_m: the ball starts in the hole");
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<GroundResult> SimulateGround(const BallSpec& ball, const Surface& surface,
                                            const GroundPlane& plane, const Hole& hole,
                                            const GroundStart& start,
                                            const GroundOptions& options) {
  if (absl::Status s = ValidateGround(ball, surface, plane, hole, start, options); !s.ok()) {
    return s;
  }
  Env env;
  env.n = plane.Normal();
  env.g = Vector3d(0.0, 0.0, -options.gravity_mps2);
  env.g_n = options.gravity_mps2 * env.n.z();
  const Vector3d gt = env.g - env.g.dot(env.n) * env.n;
  env.fall = Unit(gt, Vector3d::UnitX());
  env.g_t = (options.effects & kGroundDisableSlope) != 0 ? Vector3d::Zero() : gt;
  env.radius = ball.radius_m();
  env.k = ball.inertia_factor;
  env.mu = surface.sliding_friction;
  env.rho = surface.rolling_resistance;
  env.hole = options.hole;
  env.hole_c = PlanePoint(plane, hole.x_m, hole.y_m);
  env.hole_r = 0.5 * hole.diameter_m;
  env.stick_r = 0.5 * hole.flagstick_diameter_m;
  env.stick_e = hole.flagstick_restitution;
  Run run(env, surface, options);
  return run.Go(start, plane);
}

}  // namespace sportsim::golf
