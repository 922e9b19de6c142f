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
#include "sim/core/ode/hermite.h"
#include "sim/core/ode/integrator.h"
#include "sim/core/ode/runge_kutta.h"

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
  HermitePoint out;
  ode::CubicHermiteRate(p0, v0, p1, v1, h, f, &out.p, &out.v);
  return out;
}

Vector3d PlanePoint(const GroundPlane& plane, double x, double y) {
  return Vector3d(x, y, plane.HeightAt(x, y));
}

// A zone of the ground: its constants, what it means for play, its name (empty on a plane).
struct Zone {
  enum Kind { kPlay, kWater, kOutOfBounds };
  Surface surface;
  Kind kind = kPlay;
  std::string name;
};

// The ground under the ball: the height, unit normal and zone at (x, y).
class Ground {
 public:
  static constexpr int kOffMap = -1;
  struct Local {
    double z = 0.0;
    Vector3d n = Vector3d::UnitZ();
    // The height's Hessian times n_z: u^T curv u is the normal acceleration of a point moving
    // over the ground at horizontal velocity u (zero on a plane).
    Eigen::Matrix2d curv = Eigen::Matrix2d::Zero();
  };
  virtual ~Ground() = default;
  virtual Local At(double x, double y) const = 0;
  // The zone under (x, y); kOffMap where the ground ends.
  virtual int ZoneAt(double x, double y) const = 0;
  virtual const Zone& ZoneOf(int zone) const = 0;
  // One plane and one zone: hops and the flat pieces in closed form, no zones to cross.
  virtual bool IsPlane() const = 0;
  // One normal everywhere (hops in closed form), zones possibly many.
  virtual bool IsUniform() const = 0;
};

class PlaneGround final : public Ground {
 public:
  PlaneGround(const GroundPlane& plane, const Surface& surface)
      : plane_(plane), n_(plane.Normal()), zone_{surface, Zone::kPlay, ""} {}
  Local At(double x, double y) const override { return {plane_.HeightAt(x, y), n_}; }
  int ZoneAt(double, double) const override { return 0; }
  const Zone& ZoneOf(int) const override { return zone_; }
  bool IsPlane() const override { return true; }
  bool IsUniform() const override { return true; }

 private:
  GroundPlane plane_;
  Vector3d n_;
  Zone zone_;
};

class CourseGround final : public Ground {
 public:
  CourseGround(const Course& course, double ball_radius)
      : course_(course), index_(course), radius_(ball_radius) {
    const int holes = static_cast<int>(course.holes.size());
    zones_.reserve(static_cast<size_t>(kTerrainCount * (holes + 1)));
    for (int t = 0; t < kTerrainCount; ++t) {
      const Terrain terrain = static_cast<Terrain>(t);
      for (int h = 0; h <= holes; ++h) {
        zones_.push_back(Zone{course.Constants(Course::Spot{terrain, h}),
                              IsPenaltyArea(terrain)              ? Zone::kWater
                              : terrain == Terrain::kOutOfBounds ? Zone::kOutOfBounds
                                                                  : Zone::kPlay,
                              std::string(TerrainTag(terrain))});
      }
    }
    off_map_ = zones_[static_cast<size_t>(Index({Terrain::kOutOfBounds, 0}))];
    const std::vector<double>& z = course.terrain.z_m;
    uniform_ = std::all_of(z.begin(), z.end(), [&](double v) { return v == z.front(); });
  }
  Local At(double x, double y) const override {
    Local l;
    Eigen::Vector2d grad;
    Eigen::Matrix2d hess;
    course_.terrain.Sample(x, y, &l.z, &grad, &hess);
    l.n = Vector3d(-grad.x(), -grad.y(), 1.0).normalized();
    l.curv = hess * l.n.z();
    return l;
  }
  int ZoneAt(double x, double y) const override {
    if (!course_.terrain.Covers(x, y)) return kOffMap;
    Course::Spot spot = index_.SurfaceAt(x, y);
    if (spot.terrain == Terrain::kOutOfBounds) {
      // Out of bounds where all of the ball is (Rule 18.2a); until then, what is inside.
      const Terrain lie = index_.LieAt(x, y, radius_);
      if (lie != Terrain::kOutOfBounds) spot = Course::Spot{lie, 0};
    }
    return Index(spot);
  }
  const Zone& ZoneOf(int zone) const override {
    return zone == kOffMap ? off_map_ : zones_[static_cast<size_t>(zone)];
  }
  bool IsPlane() const override { return false; }
  bool IsUniform() const override { return uniform_; }

 private:
  int Index(Course::Spot s) const {
    return static_cast<int>(s.terrain) * (static_cast<int>(course_.holes.size()) + 1) + s.hole;
  }
  const Course& course_;
  CourseIndex index_;
  double radius_;
  std::vector<Zone> zones_;
  Zone off_map_;
  bool uniform_ = false;
};

// The ground's local frame at a point.
struct Frame {
  Vector3d n;    // unit normal
  Vector3d g_t;  // gravity along the ground (zero when the slope is switched off)
  Vector3d fall; // unit fall line (any tangent on the flat)
  double g_n = 0.0;  // gravity's normal part, g n_z
  Eigen::Matrix2d curv = Eigen::Matrix2d::Zero();  // Ground::Local::curv

  // The ground's normal acceleration of a ball moving at v over it (its curvature along the
  // path times v^2), and the normal force per unit mass that holds the ball to it: N = g_n +
  // that. The ball leaves the ground where N < 0.
  double Bend(const Vector3d& v) const { return v.head<2>().dot(curv * v.head<2>()); }
  double Normal(const Vector3d& v) const { return g_n + Bend(v); }
};

// What the run needs of the inputs, resolved once.
struct Env {
  Vector3d g;         // gravity (0, 0, -g)
  double radius = 0.0;
  double k = 0.4;     // I / (m R^2)
  bool slope = true;  // the slope's pull on
  Vector3d hole_c;    // the hole's centre, on the ground
  Vector3d hole_n;    // the ground's normal there
  Vector3d hole_fall; // and its fall line
  double hole_r = 0.0;
  double stick_r = 0.0;  // the flagstick's radius; 0: out
  double stick_e = 0.0;  // its restitution
  bool hole = false;
};

// The ball: its centre, velocity and angular velocity.
struct Ball {
  Vector3d c, v, w;
};

// One step on the ground: the ball after it (its spin not set), the slip, the step's length
// and whether it ends at the slip's or the roll's end.
struct StepOut {
  Ball b;
  Vector3d s;
  double step = 0.0;
  bool transition = false;
  double error = 0.0;  // dp45: the step's scaled error estimate (<= 1 meets the tolerance)
};

// dp45's error scale: positions against tolerance_m, velocities and slips as the position
// error they make over kErrorHorizon.
constexpr double kErrorHorizon = 0.1;  // s
constexpr double kMinAdaptiveStep = 1e-7;  // s
// The zone is probed along each step at least this often (m).
constexpr double kZoneProbe = 0.02;

class Run {
 public:
  Run(const Env& env, const Ground& ground, const GroundOptions& options)
      : e_(env), ground_(ground), options_(options), plane_(ground.IsPlane()),
        dp45_(options.integrator == ode::Integrator::kDp45), h_adapt_(options.dt_s) {
    if (plane_) plane_frame_ = MakeFrame(ground.At(0.0, 0.0));
  }

  absl::StatusOr<GroundResult> Go(const GroundStart& start);

 private:
  enum class Next { kDone, kGround, kHop, kImpact };

  Frame MakeFrame(const Ground::Local& l) const {
    const Vector3d& n = l.n;
    Frame f;
    f.n = n;
    f.curv = l.curv;
    f.g_n = -e_.g.z() * n.z();
    const Vector3d gt = e_.g - e_.g.dot(n) * n;
    f.fall = Unit(gt, Vector3d::UnitX());
    f.g_t = e_.slope ? gt : Vector3d::Zero();
    return f;
  }
  // The normal where a ball centred at c touches the ground (Under) is NormalAt's.
  // The dynamics take the ground under the centre (one lookup; the touch point lies R sin(slope)
  // from it, and the difference is smooth, so it costs no order of accuracy).
  Frame FrameAt(const Vector3d& c) const {
    return plane_ ? plane_frame_ : MakeFrame(ground_.At(c.x(), c.y()));
  }
  Vector3d NormalAt(const Vector3d& c) const { return plane_ ? plane_frame_.n : Under(c).n; }
  // The ground point the ball touches, Q, and the normal there: Q + R n(Q) is the centre's
  // nearest ground point condition, solved by fixed-point iteration from below the centre
  // (exact in one on a plane; on terrain a few millimetres' correction near grid kinks).
  struct Touch {
    Vector3d q, n;
    Ground::Local l;
  };
  Touch Under(const Vector3d& c) const {
    if (plane_) {
      return {c - e_.radius * plane_frame_.n, plane_frame_.n, Ground::Local{0.0, plane_frame_.n}};
    }
    Ground::Local l = ground_.At(c.x(), c.y());
    double x = c.x(), y = c.y();
    for (int i = 0; i < 2; ++i) {
      x = c.x() - e_.radius * l.n.x();
      y = c.y() - e_.radius * l.n.y();
      l = ground_.At(x, y);
    }
    return {Vector3d(x, y, l.z), l.n, l};
  }
  // How far the ball's surface is above the ground (m; < 0: into it).
  double Clearance(const Vector3d& c) const {
    const Touch t = Under(c);
    return (c - t.q).dot(t.n) - e_.radius;
  }
  // The centre put R above the ground along the normal where it touches.
  void Settle(Vector3d* c) const {
    const Touch t = Under(*c);
    *c += (e_.radius - (*c - t.q).dot(t.n)) * t.n;
  }
  Vector3d Contact(const Vector3d& centre) const { return centre - e_.radius * NormalAt(centre); }
  const Surface& surface() const { return zone_->surface; }
  void Emit(GroundEventKind kind) { EmitAt(kind, b_, t_); }
  void EmitAt(GroundEventKind kind, const Ball& ball, double t) {
    result_.events.push_back(GroundEvent{.t_s = t,
                                         .kind = kind,
                                         .position_m = Contact(ball.c),
                                         .velocity_mps = ball.v,
                                         .spin_radps = ball.w.norm(),
                                         .surface = zone_->name});
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
  // Samples due in (t_, t_ + tf] along a hop from the ball as it is now.
  void SampleHop(double tf) {
    if (options_.sample_interval_s <= 0.0) return;
    while (next_sample_ <= t_ + tf) {
      const double s = next_sample_ - t_;
      Sample(next_sample_, b_.c + b_.v * s + 0.5 * s * s * e_.g, (b_.v + s * e_.g).norm());
      next_sample_ = start_t_ + options_.sample_interval_s * static_cast<double>(++samples_);
    }
  }
  void Finish(bool holed) {
    finished_ = true;
    result_.holed = holed;
    result_.t_rest_s = t_;
    b_.v.setZero();
    if (holed) {
      result_.rest_m = e_.hole_c;
      b_.w.setZero();
    } else {
      result_.rest_m = Contact(b_.c);
    }
    Emit(holed ? GroundEventKind::kHoled : GroundEventKind::kRest);
    if (holed) result_.events.back().position_m = e_.hole_c;
    if (!plane_) {
      result_.rest_surface = zone_->name;
      result_.out_of_bounds = zone_->kind == Zone::kOutOfBounds;
      result_.penalty_area = zone_->kind == Zone::kWater;
    }
    if (options_.sample_interval_s > 0.0) {
      Sample(t_, holed ? Vector3d(e_.hole_c + e_.radius * e_.hole_n) : b_.c, 0.0);
    }
  }
  // The ball's centre is now over zone `z` (another than zone_): the event, and the end of the
  // run in water or off the map. True when the run is over.
  bool EnterZone(int z) {
    const Zone& next = ground_.ZoneOf(z);
    const bool was_out = zone_->kind == Zone::kOutOfBounds;
    zone_id_ = z;
    zone_ = &next;
    if (next.kind == Zone::kWater) {
      Emit(GroundEventKind::kPenaltyArea);
    } else if (next.kind == Zone::kOutOfBounds) {
      if (!was_out) Emit(GroundEventKind::kOutOfBounds);
    } else {
      Emit(GroundEventKind::kSurface);
    }
    if (next.kind == Zone::kWater || z == Ground::kOffMap) {
      Finish(false);
      return true;
    }
    return false;
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
  // A hop from the ground back onto it (or off the map, or into water: true, the run is over).
  bool Hop();
  // Impacts and hops until the ball stays on the ground (kGround) or the run ends (kDone).
  absl::StatusOr<Next> Bounces(bool impact_first);
  // The hole as the contact point moves from -> to over [t0, t0 + h].
  enum class Rim { kNone, kHoled, kDeflected };
  Rim CrossHole(double t0, double h, const Ball& from, const Ball& to);
  // The ball meets the flagstick after entering the rim at `entry` (time te): holed, or b_ and
  // t_ set to the ball leaving the stick.
  Rim HitFlagstick(const Ball& entry, const Vector3d& de, const Vector3d& dir, double offset,
                   double te);
  // One step of at most h from (from, s0): pure.
  StepOut Advance(const Ball& from, const Vector3d& s0, bool rolling, double h) const;
  // One Dormand-Prince 5(4) step of y' = g(y) (autonomous; positions first, then rates) and its
  // scaled error (kErrorHorizon).
  template <typename Vec, typename G>
  Vec Dp45(G&& g, const Vec& y0, double h, double* error) const {
    const Vec k1 = g(0.0, y0);
    ode::Dp45Stages<Vec> st;
    const Vec y1 = ode::Dp45Solution(g, 0.0, h, y0, k1, &st, h);
    const Vec err = ode::Dp45Error(h, k1, st, g(h, y1));
    double e = err.template head<3>().template lpNorm<Eigen::Infinity>();
    for (int i = 3; i < err.size(); ++i) e = std::max(e, kErrorHorizon * std::abs(err[i]));
    *error = std::isfinite(e) ? e / options_.tolerance_m : std::numeric_limits<double>::infinity();
    return y1;
  }
  // The skid and the roll to rest, into the hole, off the ground (kHop, kImpact) or out.
  absl::StatusOr<Next> OnGround();

  const Env& e_;
  const Ground& ground_;
  const GroundOptions& options_;
  const bool plane_;
  const bool dp45_;    // error-controlled steps on the ground (else RK4 at dt_s)
  double h_adapt_;     // dp45: the next step to try
  Frame plane_frame_;
  int zone_id_ = 0;
  const Zone* zone_ = nullptr;
  GroundResult result_;
  Ball b_;
  double t_ = 0.0;
  double start_t_ = 0.0;
  double next_sample_ = 0.0;
  int64_t samples_ = 0;
  int64_t polls_ = 0;
  bool in_rim_ = false;  // the contact point is inside the rim's circle (after a lip-out)
  bool holed_ = false;
  bool first_impact_ = true;
  bool finished_ = false;
};

// Penner's bounce against the ground tilted toward the ball by theta_c, with the tangential
// impulse that stops the contact point's slip, capped by Coulomb (see ground.h).
void Run::Impact() {
  const Vector3d n = NormalAt(b_.c);
  const Surface& sf = surface();
  const double vn = -b_.v.dot(n);
  const Vector3d vt = b_.v + vn * n;
  const double vt_norm = vt.norm();
  Vector3d np = n;
  if (vt_norm > 0.0 && sf.critical_angle_scale > 0.0) {
    const double descent = std::atan2(vn, vt_norm);
    const double tc = std::min(
        sf.critical_angle_scale * PennerCriticalAngle(b_.v.norm(), descent),
        0.5 * kPi - descent);  // at most head-on against the tilted plane
    np = std::cos(tc) * n - std::sin(tc) * (vt / vt_norm);
  }
  const double un = std::max(-b_.v.dot(np), 0.0);
  const double e = std::min(1.0, sf.restitution_scale * PennerRestitution(un));
  const double jn = (1.0 + e) * un;  // normal impulse per unit mass
  Vector3d slip = b_.v + b_.w.cross(-e_.radius * np);
  slip -= slip.dot(np) * np;
  b_.v += jn * np;
  const double sn = slip.norm();
  if (sn > 0.0) {
    const Vector3d sh = slip / sn;
    const double j = std::min(sn * e_.k / (1.0 + e_.k), sf.bounce_friction * jn);
    b_.v -= j * sh;
    b_.w += (j / (e_.k * e_.radius)) * np.cross(sh);
  }
  ++result_.bounces;
}

bool Run::Hop() {
  const Vector3d c0 = b_.c;
  const Vector3d v0 = b_.v;
  auto at = [&](double s) { return Vector3d(c0 + v0 * s + 0.5 * s * s * e_.g); };
  double tf = 0.0;
  bool off_map = false;
  if (ground_.IsUniform()) {
    const Frame f = FrameAt(c0);
    tf = 2.0 * v0.dot(f.n) / f.g_n;  // back on the plane (gravity's normal part g_n)
    const Vector3d c = at(tf);
    off_map = ground_.ZoneAt(c.x(), c.y()) == Ground::kOffMap;
  } else {
    // Probes every 0.1 m of travel (at most 5 ms apart) until the ball is on or under the
    // tangent plane below its centre, then bisection between the last two.
    auto clearance = [&](double s) { return Clearance(at(s)); };
    double lo = 0.0, hi = -1.0;
    for (int i = 1; hi < 0.0; ++i) {
      const double v = (v0 + lo * e_.g).norm();
      const double s = lo + std::min(5e-3, 0.1 / std::max(v, 1e-3));
      const Vector3d c = at(s);
      if (ground_.ZoneAt(c.x(), c.y()) == Ground::kOffMap) {
        // Past the map's edge by this probe: where the centre crossed it (bisection), and
        // whether the ball met the ground before that (then it lands on the map as usual,
        // rather than leaving it from under the ground).
        double in = lo, out = s;
        for (int k = 0; k < 60 && out - in > 1e-12; ++k) {
          const double mid = 0.5 * (in + out);
          const Vector3d p = at(mid);
          (ground_.ZoneAt(p.x(), p.y()) == Ground::kOffMap ? out : in) = mid;
        }
        if (clearance(in) <= 0.0) {
          hi = in;
        } else {
          off_map = true;
          hi = out;
        }
        break;
      }
      if (clearance(s) <= 0.0) {
        hi = s;
        break;
      }
      lo = s;
      if (i > 1000000) break;  // unreachable: gravity brings it down within seconds
    }
    if (hi < 0.0) hi = lo;
    if (!off_map) {
      for (int i = 0; i < 60 && hi - lo > 1e-12; ++i) {
        const double mid = 0.5 * (lo + hi);
        (clearance(mid) <= 0.0 ? hi : lo) = mid;
      }
    }
    tf = hi;
  }
  SampleHop(tf);
  b_.c = at(tf);
  b_.v = v0 + tf * e_.g;
  t_ += tf;
  if (off_map) return EnterZone(Ground::kOffMap);
  Settle(&b_.c);  // back on the ground exactly (rounding, or the bisection's last bit)
  if (const int z = ground_.ZoneAt(b_.c.x(), b_.c.y()); z != zone_id_) return EnterZone(z);
  return false;
}

absl::StatusOr<Run::Next> Run::Bounces(bool impact_first) {
  double last_rebound = std::numeric_limits<double>::infinity();
  bool impact = impact_first;
  for (;;) {
    if (absl::Status st = Poll(); !st.ok()) return st;
    if (!impact && Hop()) return Next::kDone;
    impact = false;
    const GroundEventKind kind = first_impact_ ? GroundEventKind::kLanding : GroundEventKind::kBounce;
    if (e_.hole && (Contact(b_.c) - e_.hole_c).norm() <= e_.hole_r - e_.radius) {
      Emit(kind);
      Finish(true);
      return Next::kDone;
    }
    Impact();
    Emit(kind);
    first_impact_ = false;
    // The bouncing ends when a rebound is lower than settle_speed_mps, or no lower than the
    // one before: a ball skimming down a slope at a grazing angle, where the slope's pull
    // during each hop feeds what the impacts take (Penner's impact law is fitted to
    // landings, not to a ball skipping along the turf); on the ground it goes on skidding or
    // rolling.
    const Vector3d n = NormalAt(b_.c);
    const double vn = b_.v.dot(n);
    if (vn < options_.settle_speed_mps || vn >= last_rebound || result_.bounces >= kMaxImpacts) {
      b_.v -= vn * n;  // stays on the ground
      return Next::kGround;
    }
    last_rebound = vn;
  }
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
  const Vector3d dir = Unit(ve, Unit(d1 - d0, e_.hole_fall));
  const double offset = std::abs(de.cross(dir).dot(e_.hole_n));
  const double te = t0 + lambda * h;
  const Ball entry{e_.hole_c + de + e_.radius * e_.hole_n, ve, from.w + lambda * (to.w - from.w)};
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
  b_ = Ball{e_.hole_c + c + e_.radius * e_.hole_n, v1, entry.w};
  t_ = te + t1;
  if (holed) return Rim::kHoled;
  Emit(GroundEventKind::kLipOut);
  b_.c = e_.hole_c + exit + e_.radius * e_.hole_n;
  t_ = te + t_exit;
  return Rim::kDeflected;
}

StepOut Run::Advance(const Ball& from, const Vector3d& s0, bool rolling, double h) const {
  // Without a pull along a plane (flat, or the slope switched off) neither the slip's nor the
  // velocity's direction turns: the skid and the roll are each at constant acceleration, and
  // one step reaches each transition exactly (the step is cut there). Otherwise RK4.
  const Frame f0 = FrameAt(from.c);
  const bool straight = ground_.IsUniform() && f0.g_t.squaredNorm() == 0.0;
  const double mu = surface().sliding_friction;
  const double n0 = std::max(f0.Normal(from.v), 0.0);  // the ground's push at the start
  const double hold = surface().rolling_resistance * n0;  // the most the resistance holds
  StepOut o{from, s0, h, false};
  Ball& b = o.b;
  if (!rolling) {
    const double rate_slip = mu * n0 * (1.0 + 1.0 / e_.k);
    const Vector3d sh = s0 / s0.norm();
    const double r = rate_slip - f0.g_t.dot(sh);
    // Near its end the slip's direction turns ever faster (the slope's pull against a
    // vanishing slip): the steps shrink with the time left, half of it each, so each turns
    // the direction by a bounded angle, until the last piece is short.
    const double left = r > 0.0 ? s0.norm() / r : h;
    const double hs = straight || r <= 0.0 || left <= kLastPiece ? h : std::min(h, 0.5 * left);
    // The last piece is taken whole however short the step offered (dp45's error control
    // shrinks its steps as the direction turns: it would never reach the end).
    if (r > 0.0 && (s0.norm() <= r * hs || left <= kLastPiece)) {
      // The slip ends inside this step. v - k/(1+k) s moves at the constant rate g_t/(1+k)
      // (the friction terms cancel), so the velocity at the end of the slip is exact whatever
      // path the slip's direction takes on the way to zero; the position takes the slip as
      // shrinking linearly over the piece.
      o.step = s0.norm() / r;
      const double kk = e_.k / (1.0 + e_.k);
      const Vector3d base = from.v - kk * s0;
      b.c += (base + 0.5 * kk * s0) * o.step + (0.5 * o.step * o.step / (1.0 + e_.k)) * f0.g_t;
      b.v = base + (o.step / (1.0 + e_.k)) * f0.g_t;
      o.s.setZero();
      o.transition = true;
      return o;
    }
    // RK4 on (c, v, s), the ground's frame taken where each stage puts the centre.
    struct D {
      Vector3d c, v, s;
    };
    auto f = [&](const Vector3d& c, const Vector3d& v, const Vector3d& sl) {
      if (plane_) {
        const Vector3d u = Unit(sl, Vector3d::Zero());
        return D{v, f0.g_t - mu * f0.g_n * u, f0.g_t - mu * f0.g_n * (1.0 + 1.0 / e_.k) * u};
      }
      // On terrain the ground bends the path (its normal acceleration) and pushes with N.
      const Frame fr = FrameAt(c);
      const double bend = fr.Bend(v);
      const double push = std::max(fr.g_n + bend, 0.0);
      const Vector3d u = Unit(sl - sl.dot(fr.n) * fr.n, Vector3d::Zero());
      return D{v, fr.g_t + bend * fr.n - mu * push * u,
               fr.g_t - mu * push * (1.0 + 1.0 / e_.k) * u};
    };
    o.step = hs;
    if (dp45_) {
      using V9 = Eigen::Matrix<double, 9, 1>;
      auto g = [&](double, const V9& y) {
        const D d = f(y.segment<3>(0), y.segment<3>(3), y.segment<3>(6));
        V9 out;
        out << d.c, d.v, d.s;
        return out;
      };
      V9 y0;
      y0 << b.c, b.v, s0;
      const V9 y1 = Dp45(g, y0, hs, &o.error);
      b.c = y1.segment<3>(0);
      b.v = y1.segment<3>(3);
      o.s = y1.segment<3>(6);
      return o;
    }
    const D k1 = f(b.c, b.v, s0);
    const D k2 = f(b.c + 0.5 * hs * k1.c, b.v + 0.5 * hs * k1.v, s0 + 0.5 * hs * k1.s);
    const D k3 = f(b.c + 0.5 * hs * k2.c, b.v + 0.5 * hs * k2.v, s0 + 0.5 * hs * k2.s);
    const D k4 = f(b.c + hs * k3.c, b.v + hs * k3.v, s0 + hs * k3.s);
    b.c += (hs / 6.0) * (k1.c + 2.0 * k2.c + 2.0 * k3.c + k4.c);
    b.v += (hs / 6.0) * (k1.v + 2.0 * k2.v + 2.0 * k3.v + k4.v);
    o.s += (hs / 6.0) * (k1.s + 2.0 * k2.s + 2.0 * k3.s + k4.s);
    return o;
  }
  const double speed = from.v.norm();
  const Vector3d vh = Unit(from.v, Unit(f0.g_t, f0.fall));
  const double r = (hold - f0.g_t.dot(vh)) / (1.0 + e_.k);
  // As for the slip: the path hooks down the slope ever tighter as the ball stops.
  const double left = r > 0.0 ? speed / r : h;
  const double hs = straight || r <= 0.0 || left <= kLastPiece ? h : std::min(h, 0.5 * left);
  if (r > 0.0 && (speed <= r * hs || left <= kLastPiece)) {  // as the slip's last piece
    o.step = speed / r;
    const Vector3d a = (f0.g_t - hold * vh) / (1.0 + e_.k);
    b.c += from.v * o.step + 0.5 * o.step * o.step * a;
    b.v.setZero();
    o.transition = true;
    return o;
  }
  const double rho = surface().rolling_resistance;
  auto acc = [&](const Vector3d& c, const Vector3d& v) {
    if (plane_) return Vector3d((f0.g_t - rho * f0.g_n * Unit(v, vh)) / (1.0 + e_.k));
    const Frame fr = FrameAt(c);
    const double bend = fr.Bend(v);
    const double push = std::max(fr.g_n + bend, 0.0);
    const Vector3d vt = v - v.dot(fr.n) * fr.n;
    return Vector3d((fr.g_t - rho * push * Unit(vt, vh)) / (1.0 + e_.k) + bend * fr.n);
  };
  o.step = hs;
  if (dp45_) {
    using V6 = Eigen::Matrix<double, 6, 1>;
    auto g = [&](double, const V6& y) {
      V6 out;
      out << y.segment<3>(3), acc(y.segment<3>(0), y.segment<3>(3));
      return out;
    };
    V6 y0;
    y0 << b.c, b.v;
    const V6 y1 = Dp45(g, y0, hs, &o.error);
    b.c = y1.segment<3>(0);
    b.v = y1.segment<3>(3);
    return o;
  }
  // RK4 on (c, v); on the plane with the plane's own (small, inlined) acceleration.
  auto rk4 = [&](auto&& a) {
    const Vector3d c0 = b.c, v0 = b.v;
    const Vector3d k1 = a(c0, v0);
    const Vector3d v2 = v0 + 0.5 * hs * k1;
    const Vector3d k2 = a(c0 + 0.5 * hs * v0, v2);
    const Vector3d v3 = v0 + 0.5 * hs * k2;
    const Vector3d k3 = a(c0 + 0.5 * hs * v2, v3);
    const Vector3d v4 = v0 + hs * k3;
    const Vector3d k4 = a(c0 + hs * v3, v4);
    b.c += (hs / 6.0) * (v0 + 2.0 * v2 + 2.0 * v3 + v4);
    b.v += (hs / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
  };
  if (plane_) {
    const Vector3d gt = f0.g_t / (1.0 + e_.k);
    const double decel = rho * f0.g_n / (1.0 + e_.k);
    rk4([&](const Vector3d&, const Vector3d& v) { return Vector3d(gt - decel * Unit(v, vh)); });
  } else {
    rk4(acc);
  }
  return o;
}

// The skid and the roll, to rest, into the hole, off the ground or out of play.
absl::StatusOr<Run::Next> Run::OnGround() {
  // On one plane without a pull along it, one step reaches each transition (the exact pieces);
  // zones to cross, or a pull, take steps of dt_s.
  const bool one_piece = plane_ && plane_frame_.g_t.squaredNorm() == 0.0;
  const double h = one_piece ? options_.max_time_s : options_.dt_s;
  // The slip of the contact point (tangential: the ball is on the ground) and the spin about
  // the normal (friction does not change it), from the ball as it is now: here, and after the
  // flagstick.
  Vector3d s;
  double w_normal = 0.0;
  bool rolling = false;
  auto take_ball = [&] {
    const Vector3d n = NormalAt(b_.c);
    s = b_.v + b_.w.cross(-e_.radius * n);
    s -= s.dot(n) * n;
    w_normal = b_.w.dot(n);
    rolling = s.norm() <= 1e-12;
    if (rolling) s.setZero();
  };
  take_ball();
  for (;;) {
    if (absl::Status st = Poll(); !st.ok()) return st;
    const Ball from = b_;
    const double t0 = t_;
    StepOut o = Advance(from, s, rolling, dp45_ ? std::min(h, h_adapt_) : h);
    if (dp45_) {
      // Rejected while the error is over the tolerance; the next step from the last error.
      bool rejected = false;
      while (o.error > 1.0 && o.step > kMinAdaptiveStep) {
        rejected = true;
        ++result_.rejected_steps;
        o = Advance(from, s, rolling, o.step * ode::Dp45StepFactor(o.error, true));
      }
      if (o.error > 0.0 && !o.transition) {
        h_adapt_ = std::clamp(o.step * ode::Dp45StepFactor(o.error, rejected), kMinAdaptiveStep,
                              options_.dt_s);
      }
    }
    // Onto another zone (or off the map): the step is cut where the centre crosses. The zone
    // is probed along the step's interpolant every kZoneProbe of travel, so that a graze over
    // another surface's edge inside a long step is not passed over.
    int zone = zone_id_;
    if (!plane_) {
      zone = ground_.ZoneAt(o.b.c.x(), o.b.c.y());
      double reach = o.step;  // the zone changes by here
      const int probes = static_cast<int>(
          std::min(1e4, std::ceil((o.b.c - from.c).norm() / kZoneProbe)));
      for (int k = 1; k < probes; ++k) {
        const double f = static_cast<double>(k) / probes;
        const Vector3d p = Hermite(from.c, from.v, o.b.c, o.b.v, o.step, f).p;
        if (ground_.ZoneAt(p.x(), p.y()) != zone_id_) {
          const StepOut m = Advance(from, s, rolling, f * o.step);
          if (ground_.ZoneAt(m.b.c.x(), m.b.c.y()) != zone_id_) {
            reach = f * o.step;
            zone = -2;  // (any other than zone_id_: recomputed after the cut)
          }
          break;
        }
      }
      if (zone != zone_id_) {
        double lo = 0.0, hi = reach;
        for (int i = 0; i < 64 && hi - lo > 1e-9; ++i) {
          const double mid = 0.5 * (lo + hi);
          const StepOut m = Advance(from, s, rolling, mid);
          (ground_.ZoneAt(m.b.c.x(), m.b.c.y()) == zone_id_ ? lo : hi) = mid;
        }
        if (hi < o.step) o = Advance(from, s, rolling, hi);
        zone = ground_.ZoneAt(o.b.c.x(), o.b.c.y());
      }
    }
    b_.c = o.b.c;
    b_.v = o.b.v;
    s = o.s;
    t_ = t0 + o.step;
    ++result_.steps;
    // Keep the ball on the ground: it takes off where the ground falls away faster than
    // gravity pulls it back over the step, and meets rising ground in an impact.
    Frame f1 = FrameAt(b_.c);
    Next leave = Next::kGround;
    if (!plane_ && zone != Ground::kOffMap) {
      if (f1.Normal(b_.v) < 0.0) {
        // The ground falls away faster than gravity can hold the ball to it: it takes off
        // where N crosses zero (bisection on the step's length, to 1 ns).
        double lo = 0.0, hi = o.step;
        for (int i = 0; i < 64 && hi - lo > 1e-9; ++i) {
          const double mid = 0.5 * (lo + hi);
          const StepOut m = Advance(from, s, rolling, mid);
          (FrameAt(m.b.c).Normal(m.b.v) >= 0.0 ? lo : hi) = mid;
        }
        if (hi < o.step) {
          o = Advance(from, s, rolling, hi);
          b_.c = o.b.c;
          b_.v = o.b.v;
          s = o.s;
          t_ = t0 + o.step;
          f1 = FrameAt(b_.c);
          zone = ground_.ZoneAt(b_.c.x(), b_.c.y());
        }
        leave = Next::kHop;
      } else if (b_.v.dot(f1.n) < -options_.settle_speed_mps) {
        leave = Next::kImpact;  // rising into the ball faster than the step followed
      }
    }
    if (plane_) {
      b_.c += (e_.radius - b_.c.dot(f1.n)) * f1.n;  // against rounding
    } else if (leave != Next::kHop) {
      Settle(&b_.c);  // on the ground (an impact too: it meets the ground where it touches)
    }
    if (leave == Next::kGround) {
      b_.v -= b_.v.dot(f1.n) * f1.n;
      s -= s.dot(f1.n) * f1.n;
    }
    b_.w = w_normal * f1.n + f1.n.cross(b_.v - s) / e_.radius;
    SampleSegment(t0, t_, from, b_);
    switch (CrossHole(t0, t_ - t0, from, b_)) {
      case Rim::kNone: break;
      case Rim::kHoled: holed_ = true; return Next::kDone;
      case Rim::kDeflected:
        take_ball();  // off the flagstick: the new velocity with the old spin slips
        continue;
    }
    if (zone != zone_id_) {
      if (EnterZone(zone)) return Next::kDone;
    }
    if (leave != Next::kGround) return leave;
    if (!o.transition) continue;
    if (!rolling) {
      rolling = true;
      Emit(GroundEventKind::kRoll);
      continue;
    }
    // Speed zero: at rest where the resistance holds the slope's pull.
    if (f1.g_t.norm() <= surface().rolling_resistance * f1.g_n) {
      if (e_.hole && (Contact(b_.c) - e_.hole_c).norm() <= e_.hole_r) {
        holed_ = true;  // at rest over the hole: it drops
      }
      return Next::kDone;
    }
  }
}

absl::StatusOr<GroundResult> Run::Go(const GroundStart& start) {
  start_t_ = t_ = start.time_s;
  next_sample_ = start_t_;
  zone_id_ = ground_.ZoneAt(start.position_m.x(), start.position_m.y());
  zone_ = &ground_.ZoneOf(zone_id_);
  const Ground::Local l = ground_.At(start.position_m.x(), start.position_m.y());
  b_.c = Vector3d(start.position_m.x(), start.position_m.y(), l.z) + e_.radius * l.n;
  b_.v = start.velocity_mps;
  b_.w = Vector3d::Zero();
  switch (start.kind) {
    case GroundStartKind::kLanding:
      if ((options_.effects & kGroundDisableSpin) == 0) b_.w = start.spin_radps;
      break;
    case GroundStartKind::kPutt:
    case GroundStartKind::kRolling: {
      // Along the ground, at the given speed, heading where the given velocity points.
      const double speed = b_.v.norm();
      b_.v = speed * Unit(b_.v - b_.v.dot(l.n) * l.n, Vector3d::Zero());
      if (start.kind == GroundStartKind::kRolling) {
        b_.w = l.n.cross(b_.v) / e_.radius;  // the contact point at rest
      }
      break;
    }
  }
  if (options_.sample_interval_s > 0.0) {
    Sample(t_, b_.c, b_.v.norm());
    next_sample_ = start_t_ + options_.sample_interval_s;
    samples_ = 1;
  }
  Next next = start.kind == GroundStartKind::kLanding ? Next::kImpact : Next::kGround;
  first_impact_ = start.kind == GroundStartKind::kLanding;  // else impacts are bounces
  if (zone_->kind == Zone::kWater) {  // landed in water
    Emit(GroundEventKind::kLanding);
    Emit(GroundEventKind::kPenaltyArea);
    Finish(false);
    return std::move(result_);
  }
  while (next != Next::kDone) {
    absl::StatusOr<Next> n =
        next == Next::kGround ? OnGround() : Bounces(/*impact_first=*/next == Next::kImpact);
    if (!n.ok()) return n.status();
    next = *n;
  }
  if (!finished_) Finish(holed_);
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

GroundOptions CourseGroundOptions() {
  GroundOptions o;
  o.integrator = ode::Integrator::kDp45;
  o.tolerance_m = 1e-8;
  o.dt_s = 0.05;
  return o;
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
    case GroundEventKind::kSurface: return "surface";
    case GroundEventKind::kOutOfBounds: return "out_of_bounds";
    case GroundEventKind::kPenaltyArea: return "penalty_area";
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

namespace {

// The checks a plane and a course share: the ball, the options, the hole's size and flagstick
// (its position when `hole_position`), the start's numbers.
absl::Status ValidateCommon(const BallSpec& ball, const Hole& hole, bool hole_position,
                            const GroundStart& start, const GroundOptions& options) {
  if (absl::Status s = ValidateBallSpec(ball); !s.ok()) return s;
  if (absl::Status s = CheckFieldsInRange({
          {"gravity_mps2", options.gravity_mps2, 0, true, 100},
          {"dt_s", options.dt_s, 1e-6, false, options.integrator == ode::Integrator::kDp45 ? 0.1 : 0.01},
          {"max_time_s", options.max_time_s, 0, true, 3600},
          {"settle_speed_mps", options.settle_speed_mps, 0.001, false, 1},
          {"start.time_s", start.time_s, -1e6, false, 1e6},
      });
      !s.ok()) {
    return s;
  }
  if (options.integrator == ode::Integrator::kDp45) {
    if (absl::Status s = CheckFiniteInRange("tolerance_m", options.tolerance_m, 0, true, 0.1, false);
        !s.ok()) {
      return absl::InvalidArgumentError(absl::StrCat(s.message(), " (dp45 needs a tolerance)"));
    }
  } else if (options.integrator != ode::Integrator::kRk4) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "integrator: %s; the ground phase takes rk4 or dp45", ode::IntegratorName(options.integrator)));
  } else if (options.tolerance_m != 0.0) {
    return absl::InvalidArgumentError("tolerance_m: rk4 takes a step (dt_s), not a tolerance");
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
    if (hole_position) {
      for (const auto& [name, v] : {std::pair{"hole.x_m", hole.x_m}, {"hole.y_m", hole.y_m}}) {
        if (absl::Status s = CheckFiniteInRange(name, v, -1e5, false, 1e5, false); !s.ok()) {
          return s;
        }
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
  return absl::OkStatus();
}

Env MakeEnv(const BallSpec& ball, const Hole& hole, const GroundOptions& options) {
  Env env;
  env.g = Vector3d(0.0, 0.0, -options.gravity_mps2);
  env.radius = ball.radius_m();
  env.k = ball.inertia_factor;
  env.slope = (options.effects & kGroundDisableSlope) == 0;
  env.hole = options.hole;
  env.hole_r = 0.5 * hole.diameter_m;
  env.stick_r = 0.5 * hole.flagstick_diameter_m;
  env.stick_e = hole.flagstick_restitution;
  return env;
}

void PlaceHole(const Ground& ground, double x, double y, const Vector3d& g, Env* env) {
  const Ground::Local l = ground.At(x, y);
  env->hole_c = Vector3d(x, y, l.z);
  env->hole_n = l.n;
  env->hole_fall = Unit(g - g.dot(l.n) * l.n, Vector3d::UnitX());
}

}  // namespace

absl::Status ValidateGround(const BallSpec& ball, const Surface& surface,
                            const GroundPlane& plane, const Hole& hole,
                            const GroundStart& start, const GroundOptions& options) {
  if (absl::Status s = ValidateSurface(surface); !s.ok()) return s;
  if (absl::Status s = CheckFieldsInRange({
          {"slope_pct", plane.slope_pct, 0, false, kMaxSlopePct},
          {"slope_toward_deg", plane.slope_toward_deg, -1e6, false, 1e6},
      });
      !s.ok()) {
    return s;
  }
  if (absl::Status s = ValidateCommon(ball, hole, true, start, options); !s.ok()) return s;
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
  const PlaneGround ground(plane, surface);
  Env env = MakeEnv(ball, hole, options);
  PlaceHole(ground, hole.x_m, hole.y_m, env.g, &env);
  Run run(env, ground, options);
  return run.Go(start);
}

absl::StatusOr<GroundResult> SimulateGroundOnCourse(const BallSpec& ball, const Course& course,
                                                    int hole_number, const Hole& hole,
                                                    const GroundStart& start,
                                                    const GroundOptions& options) {
  if (absl::Status s = ValidateCommon(ball, hole, false, start, options); !s.ok()) return s;
  const CourseHole* h = course.Hole(hole_number);
  if (h == nullptr) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "hole: %d is not a hole of %s (1 to %d)", hole_number, course.name, course.holes.size()));
  }
  const double x = start.position_m.x(), y = start.position_m.y();
  const CourseGround ground(course, ball.radius_m());
  const int zone = ground.ZoneAt(x, y);
  const Zone& z = ground.ZoneOf(zone);
  if (z.kind == Zone::kOutOfBounds) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "start.position_m: (%g, %g) is out of bounds on %s", x, y, course.name));
  }
  if (z.kind == Zone::kWater && start.kind != GroundStartKind::kLanding) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "start.position_m: (%g, %g) is in water (golf=%s)", x, y, z.name));
  }
  const Ground::Local l = ground.At(x, y);
  if (start.kind == GroundStartKind::kLanding && !(start.velocity_mps.dot(l.n) < 0.0)) {
    return absl::InvalidArgumentError(
        "start.velocity_mps: a landing ball must move into the ground");
  }
  Env env = MakeEnv(ball, hole, options);
  PlaceHole(ground, h->pin_m->x(), h->pin_m->y(), env.g, &env);
  if (options.hole && start.kind != GroundStartKind::kLanding &&
      (Vector3d(x, y, l.z) - env.hole_c).norm() <= 0.5 * hole.diameter_m) {
    return absl::InvalidArgumentError("start.position_m: the ball starts in the hole");
  }
  Run run(env, ground, options);
  return run.Go(start);
}

}  // namespace sportsim::golf
