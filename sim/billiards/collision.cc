#include "sim/billiards/collision.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "sim/billiards/cloth.h"
#include "sim/core/ode/runge_kutta.h"
#include "sim/core/root_find.h"
#include "sim/core/units.h"

namespace sportsim::billiards {

namespace {

// The unit normal from a to b in the table plane and the speed at which they close along it;
// false when they do not close (touching or parting balls, or coincident centres).
bool Closing(const Ball& a, const Ball& b, Eigen::Vector3d* n, Eigen::Vector3d* v_rel,
             double* approach) {
  *n = b.r - a.r;
  n->z() = 0.0;
  const double dist = n->norm();
  if (dist == 0.0) return false;
  *n /= dist;
  *v_rel = a.v - b.v;
  *approach = v_rel->dot(*n);
  return *approach > kMinApproachSpeed;
}

}  // namespace

double BallFriction(const PhysicsParams& p, double slip) {
  return p.mu_ball_a + p.mu_ball_b * std::exp(-p.mu_ball_c_spm * slip);
}

bool CollideBalls(const TableModel& model, uint32_t effects, Ball* a, Ball* b) {
  Eigen::Vector3d n, v_rel;
  double approach = 0.0;
  if (!Closing(*a, *b, &n, &v_rel, &approach)) return false;
  const PhysicsParams& p = model.params();
  const double m = model.mass();
  const double radius = model.radius();
  const double e = approach < kRestingContactSpeed ? 0.0 : p.e_ball;
  const double jn = (1.0 + e) * 0.5 * m * approach;
  Eigen::Vector3d impulse_a = -jn * n;  // on ball a; ball b gets the opposite
  Eigen::Vector3d dw = Eigen::Vector3d::Zero();
  if ((effects & kEffectDisableBallFriction) == 0) {
    const Eigen::Vector3d u = v_rel + radius * (a->w + b->w).cross(n);
    const Eigen::Vector3d ut = u - u.dot(n) * n;
    const double slip = ut.norm();
    if (p.ball_ball_model == BallBallModel::kMathavan2014) {
      // TP A-14's friction at the slip the impact starts with, held through it.
      CollideBallsMathavan(model, n, e, BallFriction(p, slip), p.mu_slide, a, b);
      a->state = Classify(model, *a);
      b->state = Classify(model, *b);
      return true;
    }
    if (slip > 0.0) {
      const double mu = BallFriction(p, slip);
      const double pt = std::min(mu * jn, m * slip / 7.0);
      const Eigen::Vector3d friction = -(pt / slip) * ut;
      impulse_a += friction;
      // The same torque (R n x P) turns both balls: b gets -P at -R n.
      dw = (radius / model.inertia()) * n.cross(friction);
    }
  }
  Eigen::Vector3d dv = impulse_a / m;
  dv.z() = 0.0;  // the slate takes the vertical part
  a->v += dv;
  b->v -= dv;
  a->w += dw;
  b->w += dw;
  a->state = Classify(model, *a);
  b->state = Classify(model, *b);
  return true;
}

// Mathavan, Jackson and Parkin (2014), integrated over the normal impulse P at the balls'
// contact. The contact frame: n from a to b, t = z x n, z up. The state is both balls' (v_n,
// v_t, w_n, w_t, w_z) and W, the integral of the approach (v_a - v_b).n over P. Per dP the
// balls take -n and +n; the contact's friction f = (f_t, f_z) on a (-f on b) opposes its slip
//   u = (v_at - v_bt + R (w_az + w_bz), -R (w_at + w_bt)),
// f = -mu u^ while it slides. Its vertical part presses one ball into the cloth (a where f_z <
// 0, b where f_z > 0) with the load |f_z|, gravity being nothing beside the impulse, and lifts
// the other, which the slate then does not touch; the pressed ball's cloth contact, its bottom
// point, slips at s = (v_n - R w_t, v_t + R w_n) and takes the cloth's sliding friction,
// mu_table times the load against s. With f and the cloth's friction g_k on ball k (k = a, b),
// the rates are (kv = 1/m, kw = R/I, the normal impulse's sign -1 for a and +1 for b, f's +1
// and -1):
//   dv_n = kv (sign + g_n),  dv_t = kv (+-f_t + g_t),  dw_n = kw g_t,
//   dw_t = kw (-f_z - g_n),  dw_z = kw f_t,  dW = (v_a - v_b).n.
// Alone, the contact's friction closes its slip along itself in t (its rate is 7 f_t / m) and
// more slowly in z (5 f_z / m: both balls' centres held on the slate), so the slip turns as
// it closes; once it is closed it stays so with no friction at all (the normal impulse moves
// no tangential slip, and without f there is no load). A cloth contact never sticks during the
// impact: its slip is driven by the normal impulse at 1/m, more than its friction (at most
// 3.5 mu_table mu / m, 0.08 / m for pool) can hold. Compression ends where the approach falls
// to zero; restitution where W has come down to (1 - e^2) of its value then.
namespace {

using PairState = Eigen::Matrix<double, 11, 1>;

class PairImpact {
 public:
  PairImpact(double m, double radius, double mu, double mu_table, double floor)
      : radius_(radius), mu_(mu), mu_table_(mu_table), kv_(1.0 / m),
        kw_(2.5 / (m * radius)), floor_(floor) {}

  Eigen::Vector2d BallSlip(const PairState& z) const {
    return {z[1] - z[6] + radius_ * (z[4] + z[9]), -radius_ * (z[3] + z[8])};
  }
  Eigen::Vector2d ClothSlip(int k, const PairState& z) const {
    const int o = 5 * k;
    return {z[o] - radius_ * z[o + 3], z[o + 1] + radius_ * z[o + 2]};
  }
  static double Approach(const PairState& z) { return z[0] - z[5]; }

  // The contact's friction per dP: against the slip while it slides; none once it is stuck.
  Eigen::Vector2d Friction(const PairState& z, bool stuck) const {
    if (stuck) return Eigen::Vector2d::Zero();
    const Eigen::Vector2d u = BallSlip(z);
    const double n = u.norm();
    return n > floor_ ? Eigen::Vector2d(-mu_ * u / n) : Eigen::Vector2d::Zero();
  }

  // The rates per dP under the contact's friction f, with the normal impulse (`normal` 1) or
  // for the friction impulse f alone (`normal` 0, no cloth friction: a landing's jump).
  PairState Rates(const PairState& z, const Eigen::Vector2d& f, double normal = 1.0) const {
    PairState d;
    for (int k : {0, 1}) {
      const int o = 5 * k;
      const double sign = k == 0 ? -1.0 : 1.0;
      const double ft = k == 0 ? f[0] : -f[0];
      const double load = normal > 0.0 ? std::max(0.0, sign * f[1]) : 0.0;  // f_z < 0 presses a
      Eigen::Vector2d g = Eigen::Vector2d::Zero();
      if (load > 0.0 && mu_table_ > 0.0) {
        Eigen::Vector2d s = ClothSlip(k, z);
        if (!(s.norm() > floor_)) {
          // A slip at zero: its rate without the cloth's friction is r0, and the bottom point
          // answers a force there at 3.5/m in every direction. The friction holds it if it can
          // (never with pool's constants: see above); else the slip leaves along r0, which
          // the friction, opposing it, only slows.
          const Eigen::Vector2d r0(kv_ * sign * normal + radius_ * kw_ * f[1], kv_ * ft);
          if (r0.norm() <= 3.5 * kv_ * mu_table_ * load) {
            g = -r0 / (3.5 * kv_);
            s.setZero();
          } else {
            s = r0;
          }
        }
        const double n = s.norm();
        if (n > 0.0) g = -(mu_table_ * load / n) * s;
      }
      d[o] = kv_ * (sign * normal + g[0]);
      d[o + 1] = kv_ * (ft + g[1]);
      d[o + 2] = kw_ * g[1];
      d[o + 3] = kw_ * (-f[1] - g[0]);
      d[o + 4] = kw_ * f[0];
    }
    d[10] = normal > 0.0 ? Approach(z) : 0.0;
    return d;
  }

  PairState operator()(const PairState& z, bool stuck) const {
    return Rates(z, Friction(z, stuck));
  }

  // The state change of the friction impulse that closes the contact's slip u: (m u_t / 7,
  // m u_z / 5) against it.
  PairState Closing(const PairState& z) const {
    const Eigen::Vector2d u = BallSlip(z);
    return Rates(z, Eigen::Vector2d(-u[0] / (7.0 * kv_), -u[1] / (5.0 * kv_)), 0.0);
  }

 private:
  double radius_, mu_, mu_table_, kv_, kw_, floor_;
};

}  // namespace

// The rates are smooth between a few switches: the contact's slip landing on zero (after which
// nothing but the normal impulse acts, and the rest is exact), the end of compression, the end
// of restitution, and a pressed ball's cloth slip passing zero (where its friction turns at
// once: a kink the error control steps through). The impact is integrated by Dormand and
// Prince's 5(4) pair under error control (each step's error within kMathavanPairTolerance of
// the balls' speed, in v and R w). No step goes past where the present rates would close the
// contact's slip or end the phase; the slip lands once within `landing` of zero and the rest
// of it is closed at once (its friction impulse, (m u_t / 7, m u_z / 5), exact but for the
// cloth friction that impulse would bring, second order in the slip left).
void CollideBallsMathavan(const TableModel& model, const Eigen::Vector3d& n, double e,
                          double mu, double mu_table, Ball* a, Ball* b) {
  constexpr double kMathavanPairTolerance = 1e-10;
  const Eigen::Vector3d ez = Eigen::Vector3d::UnitZ(), et = ez.cross(n);
  const double m = model.mass(), radius = model.radius();
  PairState z;
  z << a->v.dot(n), a->v.dot(et), a->w.dot(n), a->w.dot(et), a->w.dot(ez), b->v.dot(n),
      b->v.dot(et), b->w.dot(n), b->w.dot(et), b->w.dot(ez), 0.0;
  const double speed =
      a->v.norm() + b->v.norm() + radius * (a->w.norm() + b->w.norm());
  const double tol = kMathavanPairTolerance * speed;
  const double landing = 1e-9 * speed;
  const PairImpact rates(m, radius, mu, mu_table, 1e-12 * speed);
  const double total = (1.0 + e) * 0.5 * m * PairImpact::Approach(z);
  auto error_of = [radius](const PairState& err) {
    double worst = 0.0;
    for (int k : {0, 5}) {
      worst = std::max({worst, std::abs(err[k]), std::abs(err[k + 1]),
                        radius * std::abs(err[k + 2]), radius * std::abs(err[k + 3]),
                        radius * std::abs(err[k + 4])});
    }
    return worst;
  };
  bool stuck = false;
  auto land = [&] {
    z += rates.Closing(z);
    stuck = true;
  };
  if (rates.BallSlip(z).norm() <= landing) land();
  bool compressing = true, rejected = false;
  double target = 0.0, h = 0.125 * total;
  // The pair's steps go down to h_min (a kink's error needs steps of about tol / (mu_table mu),
  // 1e-8 of the impact). Should it take more than kSmallSteps of them (a cloth slip that could
  // stick chatters about zero: outside pool's constants), the rest is taken in steps of
  // 1/kFallbackSteps of the impact, error control off, a slip that then crosses zero landing.
  constexpr int kSmallSteps = 500, kFallbackSteps = 1000;
  const double h_min = 1e-9 * total;
  int small_steps = 0;
  PairState k1 = rates(z, stuck), next, k_next;
  ode::Dp45Stages<PairState> stages;
  auto f = [&](double /*p*/, const PairState& s) { return rates(s, stuck); };
  // Guards only: the fallback alone ends it.
  for (int k = 0; k < 4 * (kSmallSteps + kFallbackSteps); ++k) {
    const bool fallback = small_steps > kSmallSteps;
    // How far the present rates would carry the phase to its end, and a sliding slip to zero.
    double ahead;
    if (compressing) {
      ahead = -PairImpact::Approach(z) / PairImpact::Approach(k1);
    } else {
      // W + q h + r h^2 / 2 = target, q = the approach (< 0) and r its rate (< 0).
      const double q = k1[10], r = PairImpact::Approach(k1), left = z[10] - target;
      ahead = 2.0 * left / (-q + std::sqrt(std::max(0.0, q * q - 2.0 * r * left)));
    }
    // The cloth's friction can outdo the normal impulse where mu_slide mu nears 2 (far outside
    // any cloth and ball's), and the approach then stops falling: no prediction there.
    if (!(ahead > 0.0)) ahead = std::numeric_limits<double>::infinity();
    const bool phase_limited = !(h < ahead);
    double taken = std::min(h, ahead);
    if (!stuck) {
      const Eigen::Vector2d u = rates.BallSlip(z), du = rates.BallSlip(k1);
      const double closing = -du.dot(u) / u.norm();
      if (closing > 0.0 && u.norm() / closing < taken) taken = u.norm() / closing;
    }
    taken = std::max(taken, std::min(fallback ? total / kFallbackSteps : h_min, ahead));
    if (taken <= h_min) ++small_steps;
    next = ode::Dp45Solution(f, 0.0, taken, z, k1, &stages, taken);
    k_next = rates(next, stuck);
    const double err = error_of(ode::Dp45Error(taken, k1, stages, k_next));
    const bool overshot = !stuck && rates.BallSlip(next).dot(rates.BallSlip(z)) < 0.0;
    if (!fallback && (!(err <= tol) || overshot) && taken > h_min) {
      h = std::max(h_min, taken * (overshot ? 0.5 : ode::Dp45StepFactor(err / tol, rejected)));
      rejected = true;
      continue;
    }
    // A step past the phase's end (the rates changed on the way, so the prediction fell
    // short) is taken again to where the phase's quantity, linear over the step, crosses it.
    const double end_tol = 1e-13 * speed * (compressing ? 1.0 : total);
    const double end_from = compressing ? PairImpact::Approach(z) : z[10] - target;
    const double end_to = compressing ? PairImpact::Approach(next) : next[10] - target;
    if (!fallback && end_to < -end_tol && taken > h_min) {
      h = std::max(h_min, taken * end_from / (end_from - end_to));
      continue;
    }
    z = next;
    k1 = k_next;
    if (!stuck && (overshot || rates.BallSlip(z).norm() <= landing)) {
      land();
      k1 = rates(z, stuck);
    }
    if (compressing && PairImpact::Approach(z) <= end_tol) {
      compressing = false;
      target = (1.0 - e * e) * z[10];
      if (e == 0.0) break;
    } else if (!compressing && z[10] - target <= end_tol) {
      break;
    }
    if (!phase_limited) h = std::min(total, taken * ode::Dp45StepFactor(err / tol, rejected));
    rejected = false;
  }
  // The slate takes any vertical velocity: both balls stay on it.
  a->v = z[0] * n + z[1] * et;
  a->w = z[2] * n + z[3] * et + z[4] * ez;
  b->v = z[5] * n + z[6] * et;
  b->w = z[7] * n + z[8] * et + z[9] * ez;
}

namespace {

// Ball on the rolling manifold (or at rest, or spinning in place): it answers a finite contact
// force through the rolling constraint.
bool OnRollingManifold(const Ball& b) {
  return b.state == MotionState::kRolling || b.state == MotionState::kStationary ||
         b.state == MotionState::kSpinning;
}

// Horizontal velocity change of a ball from impulse p at r_c (from its centre).
Eigen::Vector3d Response(const TableModel& model, bool rolling, const Eigen::Vector3d& p,
                         const Eigen::Vector3d& rc) {
  Eigen::Vector3d ph(p.x(), p.y(), 0.0);
  if (!rolling) return ph / model.mass();
  const Eigen::Vector3d torque = rc.cross(p);
  const Eigen::Vector3d turn = Eigen::Vector3d::UnitZ().cross(torque) / model.radius();
  return (5.0 / (7.0 * model.mass())) * (ph - Eigen::Vector3d(turn.x(), turn.y(), 0.0));
}

// Applies impulse p at r_c to ball b as a sustained contact: through the rolling constraint
// when the ball is on the rolling manifold, else as to a free ball. Then the cloth's answers
// that would end within the resting time scale (about 0.1 ms) are applied at once: a slide
// with slip below kRestingContactSpeed ends (v - 2/7 u, the slide-to-roll), the spin about z
// the contact's friction gives a ball without side spin is taken by the cloth's spin friction
// (side spin is never reversed by it: it stops first).
void Apply(const TableModel& model, uint32_t effects, bool rolling, const Eigen::Vector3d& p,
           const Eigen::Vector3d& rc, Ball* b) {
  const double radius = model.radius();
  const Eigen::Vector3d torque = rc.cross(p);
  const double wz0 = b->w.z();
  b->v += Response(model, rolling, p, rc);
  b->v.z() = 0.0;
  if (!rolling) {
    b->w += torque / model.inertia();
    const Eigen::Vector3d u = Slip(b->v, b->w, radius);
    rolling = u.norm() < kRestingContactSpeed;
    if (rolling) b->v -= (2.0 / 7.0) * u;
  }
  if (rolling) {
    b->w.x() = -b->v.y() / radius;
    b->w.y() = b->v.x() / radius;
  }
  const double wz = wz0 + torque.z() / model.inertia();
  const bool absorb = (effects & kEffectDisableSpinDecay) == 0 &&
                      (wz0 == 0.0 || (wz > 0.0) != (wz0 > 0.0));
  b->w.z() = absorb ? 0.0 : wz;
  b->state = Classify(model, *b);
}

}  // namespace

double RestingStopSpeed(const TableModel& model) {
  return std::sqrt(2.0 * kRestingStopDistance * model.params().mu_roll *
                   model.params().gravity_mps2);
}

void StopCreep(const TableModel& model, uint32_t effects, Ball* b) {
  if ((effects & kEffectDisableRollingResistance) != 0 || b->state != MotionState::kRolling ||
      !(b->v.head<2>().norm() < RestingStopSpeed(model))) {
    return;
  }
  b->v.setZero();
  b->w.x() = b->w.y() = 0.0;
  b->state = Classify(model, *b);
}

bool CollideBallsResting(const TableModel& model, uint32_t effects, Ball* a, Ball* b,
                         double relax) {
  Eigen::Vector3d n, v_rel;
  double approach = 0.0;
  if (!Closing(*a, *b, &n, &v_rel, &approach)) return false;
  const double target = relax * approach;
  const PhysicsParams& p = model.params();
  const double m = model.mass();
  const double radius = model.radius();
  const bool ra = OnRollingManifold(*a), rb = OnRollingManifold(*b);
  const Eigen::Vector3d rca = radius * n, rcb = -radius * n;
  // Normal relative velocity after, per unit normal impulse and per unit friction impulse.
  const double kn = (Response(model, ra, -n, rca) - Response(model, rb, n, rcb)).dot(n);
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  double cap = 0.0, mu = 0.0, kt = 0.0;
  if ((effects & kEffectDisableBallFriction) == 0) {
    const Eigen::Vector3d u = v_rel + radius * (a->w + b->w).cross(n);
    const Eigen::Vector3d ut = u - u.dot(n) * n;
    const double slip = ut.norm();
    if (slip > 0.0) {
      t = ut / slip;  // friction on a is -pt t
      mu = BallFriction(p, slip);
      cap = m * slip / 7.0;
      kt = (Response(model, ra, -t, rca) - Response(model, rb, t, rcb)).dot(n);
    }
  }
  // target + jn kn + pt kt = 0 with pt = min(mu jn, cap): linear on each branch.
  double jn = -target / (kn + mu * kt);
  double pt = mu * jn;
  if (!(jn > 0.0) || pt > cap) {
    pt = cap;
    jn = -(target + cap * kt) / kn;
    if (!(jn > 0.0)) {
      jn = -target / kn;  // friction alone would part them: no friction
      pt = 0.0;
    }
    pt = std::min(pt, mu * jn);
  }
  const Eigen::Vector3d impulse_a = -jn * n - pt * t;
  Apply(model, effects, ra, impulse_a, rca, a);
  Apply(model, effects, rb, -impulse_a, rcb, b);
  return true;
}

// Mathavan, Jackson and Parkin (2010), integrated over the normal impulse P at the nose I. The
// cushion frame: y toward the cushion (-normal), z up, x = y x z along the rail. The nose
// touches the ball at angle theta above its equator (sin theta = (h - R) / R); the slate at C
// below. The impulse dP moves the ball by the nose's normal impulse and the two contacts'
// friction: at I, fx along the rail and ft along the nose's tangent (0, -sin theta, cos theta);
// at C, gx and gy, under the slate's normal load N = sin theta - ft cos theta (what keeps the
// ball on the slate). A sliding contact's friction is mu times its load against its slip (the
// directions phi at I and phi' at C of the paper); a stuck contact's is whatever holds its slip,
// for as long as that lies within mu times its load. Compression lasts while the ball still
// moves into the cushion; restitution stops when the normal work at I, W = integral of the
// nose's normal velocity dP, has come back down to (1 - e^2) of its value at the end of
// compression.
namespace {

// The state (vx, vy, wx, wy, wz, W) and its rates per unit of normal impulse at the nose.
using MathavanState = Eigen::Matrix<double, 6, 1>;
// The friction per unit dP: (fx, ft) at the nose, (gx, gy) at the slate.
using MathavanFriction = Eigen::Vector4d;

// How a contact grips. Sliding: its friction opposes its slip. Stuck: its friction holds its
// slip. At the edge: its slip has just left zero (it came unstuck, or reached zero where its
// friction could not hold it) and is still tiny: the friction lies on the cone's edge along the
// one direction in which the slip grows along itself. The slip's own direction turns toward
// that one at a rate of order mu / |slip|, far faster than anything else in the impact, so
// taking it there at once is exact as the slip goes to zero (and taking the slip's own
// direction makes the equations too stiff to step there).
enum class Grip { kSliding, kStuck, kEdge };

struct SlipContact {
  Grip grip = Grip::kSliding;
  Eigen::Vector2d offset = Eigen::Vector2d::Zero();  // the slip it last stuck or left zero at
};

class MathavanRates {
 public:
  static constexpr int kNose = 0, kSlate = 1;

  using Contacts = std::array<SlipContact, 2>;

  // The rates under the grips in `contact`, which the caller changes between steps.
  MathavanRates(double m, double radius, double sin_theta, double mu_cushion, double mu_slate,
                double slip_floor, const Contacts* contact)
      : contact_(contact), radius_(radius), st_(sin_theta),
        ct_(std::sqrt(1.0 - sin_theta * sin_theta)), mw_(mu_cushion), ms_(mu_slate),
        kv_(1.0 / m), kw_(2.5 / (m * radius)), floor_(slip_floor) {}
  // The same rates under other grips.
  MathavanRates(const MathavanRates& rates, const Contacts* contact)
      : MathavanRates(rates) {
    contact_ = contact;
  }

  // Contact j's slip in the state z (before its offset), or the slip's rate in the rates z: at
  // the nose across it (x) and along its tangent; at the slate in x and y.
  Eigen::Vector2d Slip(int j, const MathavanState& z) const {
    if (j == kNose) {
      return {z[0] + z[3] * radius_ * st_ - z[4] * radius_ * ct_, -z[1] * st_ + z[2] * radius_};
    }
    return {z[0] - z[3] * radius_, z[1] + z[2] * radius_};
  }

  MathavanState operator()(double p, const MathavanState& z) const {
    return BothSliding() ? Sliding(p, z) : RatesOf(z, Friction(z));
  }

  bool BothSliding() const {
    return (*contact_)[kNose].grip == Grip::kSliding && (*contact_)[kSlate].grip == Grip::kSliding;
  }

  // The rates while both contacts slide (the common case, written out).
  MathavanState Sliding(double /*p*/, const MathavanState& z) const {
    const SlipContact &nose = (*contact_)[kNose], &slate = (*contact_)[kSlate];
    const double sx = z[0] + z[3] * radius_ * st_ - z[4] * radius_ * ct_ - nose.offset[0];
    const double sy = -z[1] * st_ + z[2] * radius_ - nose.offset[1];
    const double cx = z[0] - z[3] * radius_ - slate.offset[0];
    const double cy = z[1] + z[2] * radius_ - slate.offset[1];
    const double s = std::sqrt(sx * sx + sy * sy), c = std::sqrt(cx * cx + cy * cy);
    // A slip within rounding of zero has no direction of its own: none at the nose (no
    // friction), and at the slate the one the nose's impulse alone gives it. A ball rolling
    // into the cushion starts so (its slip at C is zero but for rounding), and its slip there
    // grows along that direction from the first instant.
    const double cphi = s > floor_ ? sx / s : 0.0, sphi = s > floor_ ? sy / s : 0.0;
    double cphi2 = 0.0, sphi2 = 0.0;
    if (c > floor_) {
      cphi2 = cx / c;
      sphi2 = cy / c;
    } else {
      const double ax = -kv_ * mw_ * cphi + radius_ * kw_ * mw_ * cphi * st_;
      const double ay = -kv_ * (ct_ - mw_ * st_ * sphi) - radius_ * kw_ * mw_ * sphi;
      const double a = std::sqrt(ax * ax + ay * ay);
      if (a > 0.0) {
        cphi2 = ax / a;
        sphi2 = ay / a;
      }
    }
    const double load = st_ + mw_ * sphi * ct_;  // the slate's normal impulse per dP
    MathavanState d;
    d[0] = -kv_ * (mw_ * cphi + ms_ * cphi2 * load);
    d[1] = -kv_ * (ct_ - mw_ * st_ * sphi + ms_ * sphi2 * load);
    d[2] = -kw_ * (mw_ * sphi + ms_ * sphi2 * load);
    d[3] = -kw_ * (mw_ * cphi * st_ - ms_ * cphi2 * load);
    d[4] = kw_ * (mw_ * cphi * ct_);
    d[5] = z[1] * ct_;  // the nose's normal velocity
    return d;
  }

  // The friction at z under the contacts' present grips.
  MathavanFriction Friction(const MathavanState& z) const {
    std::array<Eigen::Vector2d, 2> d;
    for (int j : {kNose, kSlate}) d[j] = Direction(j, z);
    for (int j : {kNose, kSlate}) {
      if ((*contact_)[j].grip == Grip::kEdge) d[j] = EdgeDirection(j, z, d);
    }
    return Solve(d);
  }

  // The friction at z were contact j stuck, the other as it is.
  MathavanFriction Held(int j, const MathavanState& z) const {
    Contacts held = *contact_;
    held[j].grip = Grip::kStuck;
    return MathavanRates(*this, &held).Friction(z);
  }

  // How far contact j's friction f lies outside its cone (its square less the square of mu
  // times the load): positive where a stuck contact cannot hold.
  double Excess(int j, const MathavanFriction& f) const {
    if (j == kNose) return f[0] * f[0] + f[1] * f[1] - mw_ * mw_;
    const double limit = ms_ * (st_ - ct_ * f[1]);
    return f[2] * f[2] + f[3] * f[3] - limit * limit;
  }

  static Eigen::Vector2d Of(int j, const MathavanFriction& f) {
    return j == kNose ? f.head<2>() : f.tail<2>();
  }

  MathavanState RatesOf(const MathavanState& z, const MathavanFriction& f) const {
    MathavanState d;
    d[0] = kv_ * (f[0] + f[2]);
    d[1] = kv_ * (-ct_ - st_ * f[1] + f[3]);
    d[2] = kw_ * (f[1] + f[3]);
    d[3] = kw_ * (st_ * f[0] - f[2]);
    d[4] = -kw_ * ct_ * f[0];
    d[5] = z[1] * ct_;
    return d;
  }

  // The jump in the state that changes contact j's slip by `change` at once: the friction
  // impulse at j that makes the change, with the other contact's friction following its grip
  // as it does per dP. Exact in the limit of a small change, whatever path the slip would take:
  // the rates are affine in j's friction, so a slip s0 closing on zero and held there collects
  // the friction impulse M^-1 s0 more than a slip held at s0 does (M the slip rate's response
  // to j's friction), however its direction turns on the way. Both affine maps are read off at
  // zero and at unit impulses. False (no jump) where j's friction cannot be set (no friction,
  // or no load) or the other contact is at the edge (its friction would follow j's nonlinearly).
  bool Jump(int j, const MathavanState& z, const Eigen::Vector2d& change,
            MathavanState* jump) const {
    const int o = 1 - j;
    if ((*contact_)[o].grip == Grip::kEdge) return false;
    Contacts free = *contact_;
    free[j].grip = Grip::kSliding;  // its friction set, as a sliding contact's is by its direction
    const MathavanRates r(*this, &free);
    std::array<Eigen::Vector2d, 2> d;
    d[o] = r.Direction(o, z);
    const bool nose_stuck = (*contact_)[kNose].grip == Grip::kStuck;
    const double load = st_ - ct_ * (nose_stuck ? 0.0 : -mw_ * d[kNose][1]);
    if (j == kNose ? !(mw_ > 0.0) : !(ms_ > 0.0 && load > 0.0)) return false;
    auto friction = [&](const Eigen::Vector2d& fj) {
      std::array<Eigen::Vector2d, 2> dj = d;
      if (j == kNose) {
        dj[kNose] = -fj / mw_;
      } else if (nose_stuck) {  // the stuck nose holds against the slate's friction fj
        const double k = kw_ * radius_;
        MathavanFriction f;
        f << -(kv_ - st_ * k) * fj[0] / (kv_ + k),
            (-kv_ * st_ * ct_ - (k - kv_ * st_) * fj[1]) / (kv_ * st_ * st_ + k), fj[0], fj[1];
        return f;
      } else {
        dj[kSlate] = -fj / (ms_ * load);
      }
      return r.Solve(dj);
    };
    const MathavanState base = r.RatesOf(z, friction(Eigen::Vector2d::Zero()));
    MathavanState per[2];
    Eigen::Matrix2d response;
    for (int k : {0, 1}) {
      per[k] = r.RatesOf(z, friction(Eigen::Vector2d::Unit(k))) - base;
      response.col(k) = Slip(j, per[k]);
    }
    if (!(std::abs(response.determinant()) > 0.0)) return false;
    const Eigen::Vector2d impulse = response.inverse() * change;
    *jump = impulse[0] * per[0] + impulse[1] * per[1];
    (*jump)[5] = 0.0;  // the nose's normal work takes no impulse
    return true;
  }

 private:
  // A sliding contact's direction: its slip's; none within rounding of zero.
  Eigen::Vector2d Direction(int j, const MathavanState& z) const {
    const Eigen::Vector2d s = Slip(j, z) - (*contact_)[j].offset;
    const double n = s.norm();
    return n > floor_ ? Eigen::Vector2d(s / n) : Eigen::Vector2d::Zero();
  }

  // The friction given each unstuck contact's direction d[j]; each stuck contact's from its slip
  // rate held at zero. The slip rates are linear in the friction (K = R kw):
  //   nose  x: fx (kv + K) + gx (kv - K sin)
  //   nose  t: kv sin cos + ft (kv sin^2 + K) + gy (K - kv sin)
  //   slate x: fx (kv - K sin) + gx (kv + K)
  //   slate y: -kv cos + ft (K - kv sin) + gy (kv + K)
  // An unstuck nose's friction is -mu_w d; an unstuck slate's, g = -mu_s (sin - cos ft) d, is
  // linear in the nose's ft. So the x rows (fx, gx) and the tangential rows (ft, gy) decouple,
  // and each case is a scalar or a 2x2 solve, written out (a quarter of a sticking impact's
  // time went to a general 4x4 LU).
  MathavanFriction Solve(const std::array<Eigen::Vector2d, 2>& d) const {
    const double k = kw_ * radius_;
    const bool nose_stuck = (*contact_)[kNose].grip == Grip::kStuck;
    const bool slate_stuck = (*contact_)[kSlate].grip == Grip::kStuck;
    // The slate's unstuck friction along its direction, per unit of (sin - cos ft).
    const double gx_d = -ms_ * d[kSlate][0], gy_d = -ms_ * d[kSlate][1];
    double fx, ft, gx, gy;
    if (!nose_stuck) {
      fx = -mw_ * d[kNose][0];
      ft = -mw_ * d[kNose][1];
      if (slate_stuck) {
        gx = -(kv_ - st_ * k) * fx / (kv_ + k);
        gy = (kv_ * ct_ - (k - kv_ * st_) * ft) / (kv_ + k);
      } else {
        gx = gx_d * (st_ - ct_ * ft);
        gy = gy_d * (st_ - ct_ * ft);
      }
    } else if (slate_stuck) {
      // fx (kv + K) + gx (kv - K sin) = 0 and fx (kv - K sin) + gx (kv + K) = 0: both zero.
      fx = gx = 0.0;
      const double a = kv_ * st_ * st_ + k, b = k - kv_ * st_, c = kv_ + k;
      const double r1 = -kv_ * st_ * ct_, r3 = kv_ * ct_;
      const double det = a * c - b * b;
      ft = (r1 * c - b * r3) / det;
      gy = (a * r3 - b * r1) / det;
    } else {
      // gy = gy_d (sin - cos ft) in the nose's tangential row, which then gives ft alone.
      const double b = k - kv_ * st_;
      ft = (-kv_ * st_ * ct_ - b * gy_d * st_) / (kv_ * st_ * st_ + k - b * gy_d * ct_);
      gx = gx_d * (st_ - ct_ * ft);
      gy = gy_d * (st_ - ct_ * ft);
      fx = -(kv_ - st_ * k) * gx / (kv_ + k);
    }
    MathavanFriction f;
    f << fx, ft, gx, gy;
    return f;
  }

  // The direction u on the cone's edge (friction -mu N u) in which contact j's slip grows along
  // itself: its rate parallel to u, pointing along it. Secant iterations on the angle from the
  // direction the held friction's excess points to (the solution as the excess goes to zero),
  // then from the three quarter-turns off it.
  Eigen::Vector2d EdgeDirection(int j, const MathavanState& z,
                                std::array<Eigen::Vector2d, 2> d) const {
    const Eigen::Vector2d f = Of(j, Held(j, z));
    const double start = f.norm() > 0.0 ? std::atan2(-f[1], -f[0]) : 0.0;
    Eigen::Vector2d rate;
    auto across = [&](double angle) {
      d[j] = {std::cos(angle), std::sin(angle)};
      rate = Slip(j, RatesOf(z, Solve(d)));
      return rate[0] * d[j][1] - rate[1] * d[j][0];
    };
    for (double turn : {0.0, 0.5 * kPi, -0.5 * kPi, kPi}) {
      double a0 = start + turn, a1 = a0 + 1e-6, g0 = across(a0), g1 = across(a1);
      for (int it = 0; it < 40 && g1 != 0.0 && std::abs(a1 - a0) > 1e-15; ++it) {
        const double a2 = a1 - g1 * (a1 - a0) / (g1 - g0);
        if (!std::isfinite(a2)) break;
        a0 = a1;
        g0 = g1;
        a1 = a2;
        g1 = across(a1);
      }
      if (rate.dot(d[j]) >= 0.0) return d[j];
    }
    return {std::cos(start), std::sin(start)};
  }

  const Contacts* contact_;
  double radius_, st_, ct_, mw_, ms_, kv_, kw_, floor_;
};

}  // namespace

// The impact is smooth in P between the contacts' switches (a sliding slip landing on zero, to
// stick there or to leave it at the edge; a stuck or edge contact's held friction crossing its
// cone; an edge slip grown large enough to slide), so it is integrated between them by Dormand
// and Prince's 5(4) pair under error control (each step's error estimate within
// kMathavanTolerance of the ball's speed, in velocity and R w). A sliding slip headed for zero
// is stepped no further than where its present rate would bring it to zero, and lands once
// within `landing` of it: the rest of its way is taken at once (MathavanRates::Jump, the
// friction impulse that closes it, exact to second order in the slip left however its
// direction turns on the way, which near zero it does at a rate of order mu / |slip|, too fast
// to step). A slip that cannot stick there passes through zero or by it: where its present
// rate carries it within kMiss of zero it is first taken to that closest point, and leaves at
// the edge; else it is stepped on. A cone crossing and an edge slip's growth to the hand-off
// are found inside their step by false position, a phase end by Newton's method. Should the
// pair still fail, the steps fall to the finest, (1 + e) m v_n / cushion_impulse_steps, taken
// by the midpoint rule; the pair is tried again after a number of fine steps that doubles
// while it fails.
void CollideCushionMathavan(const TableModel& model, const Eigen::Vector3d& nh, double e,
                            double mu_cushion, double mu_slate, Ball* ball) {
  constexpr double kMathavanTolerance = 1e-8;
  constexpr int kNose = MathavanRates::kNose, kSlate = MathavanRates::kSlate;
  const PhysicsParams& p = model.params();
  const Eigen::Vector3d ey = -nh, ez = Eigen::Vector3d::UnitZ(), ex = ey.cross(ez);
  const double m = model.mass(), radius = model.radius();
  MathavanState z;
  z << ball->v.dot(ex), ball->v.dot(ey), ball->w.dot(ex), ball->w.dot(ey), ball->w.dot(ez), 0.0;
  const double speed = ball->v.norm() + radius * ball->w.norm();
  const double slip_floor = 1e-9 * speed;
  MathavanRates::Contacts contacts;  // both sliding until a slip reaches zero
  const MathavanRates rates(m, radius, model.cushion_sin(), mu_cushion, mu_slate, slip_floor,
                            &contacts);
  const double tol = kMathavanTolerance * speed;
  // An edge contact's slip goes back to its own direction once 1e-4 of the speed: small enough
  // that the edge's direction has not drifted from the slip's (handed back at 1e-3 a test
  // impact's rebound was 2e-6 of the speed off its reference), large enough that the sliding
  // slip is no longer stiff (handed back at 1e-6, a slip creeping away from zero at the edge of
  // sticking stays within a few times that for much of the impact, and there its direction
  // turns faster than the pair can step).
  const double hand_off = 1e-4 * speed;
  // A sliding slip closing on zero lands within this of it (MathavanRates::Jump). Landed from
  // 1e-4, 1e-5 or 1e-6 of the speed, creeping impacts' rebounds agree within 1e-9 of the speed;
  // the pair cannot always bring a turning slip much below 1e-6.
  const double landing = 1e-5 * speed;
  constexpr double kMiss = 1e-6;  // a reversal's miss of zero, over the speed (below)
  const double total = (1.0 + e) * m * z[1];  // the frictionless impact's impulse
  const double steps = p.cushion_impulse_steps;
  // The pair's steps may go down to 1/1000 of the fallback step: a small slip turns fast (at a
  // rate of order mu / |slip|), and a slip that passes close by zero, or creeps near it, needs
  // steps of the order of its size. After kSmallSteps steps shorter than the fallback step the
  // pair's floor goes back up to it, and so to the fallback below it. A slip creeping just
  // above the landing while its holding friction crosses the cone's edge (it neither lands nor
  // leaves) takes a few hundred such steps: with 200, 6 of 60,000 random impacts fell to the
  // fallback, its step count moving their rebounds by up to 1e-4 of the speed; with 2000 none
  // does, each within 1e-7 of the reference, and the mean cost is the same.
  constexpr int kSmallSteps = 2000;
  const double h_min = total / steps, h_max = 0.5 * total;
  double h_floor = 1e-3 * h_min;
  int small_steps = 0;
  auto error_of = [radius](const MathavanState& err) {
    return std::max({std::abs(err[0]), std::abs(err[1]), radius * std::abs(err[2]),
                     radius * std::abs(err[3]), radius * std::abs(err[4])});
  };
  // One step of length h from z (k1 its rates): the new state, its rates, the error estimate
  // (the midpoint rule's is not estimated: it is only the fallback's).
  auto step = [&](bool fine, double h, const MathavanState& k1, MathavanState* out,
                  MathavanState* k_out) {
    if (fine) {
      *out = z + h * rates(0.0, z + (0.5 * h) * k1);
      *k_out = rates(0.0, *out);
      return 0.0;
    }
    ode::Dp45Stages<MathavanState> stages;
    if (rates.BothSliding()) {
      auto sliding = [&rates](double q, const MathavanState& s) { return rates.Sliding(q, s); };
      *out = ode::Dp45Solution(sliding, 0.0, h, z, k1, &stages, h);
    } else {
      *out = ode::Dp45Solution(rates, 0.0, h, z, k1, &stages, h);
    }
    *k_out = rates(0.0, *out);
    return error_of(ode::Dp45Error(h, k1, stages, *k_out));
  };
  // Contact j's slip is at zero: it sticks if its friction can hold it, and else grips at the
  // edge (a slate slip that starts at zero keeps sliding: the rates' rounding rule). A slip
  // that lands, near zero, is first taken the rest of its way (above).
  auto settle = [&](int j, bool start) {
    SlipContact& c = contacts[j];
    MathavanState jump;
    if (!start && rates.Jump(j, z, c.offset - rates.Slip(j, z), &jump)) z += jump;
    const bool holds = rates.Excess(j, rates.Held(j, z)) <= 0.0;
    if (!holds && start && j == kSlate) return;
    c = {holds ? Grip::kStuck : Grip::kEdge, rates.Slip(j, z)};
  };
  for (int j : {kNose, kSlate}) {
    if (rates.Slip(j, z).norm() <= slip_floor) settle(j, true);
  }
  MathavanState k1 = rates(0.0, z), next, k_next;
  // The held friction's excess over the cone: it changes sign where a stuck contact comes
  // unstuck and where an edge contact sticks.
  auto held_excess = [&](int j, const MathavanState& s) {
    return rates.Excess(j, rates.Held(j, s));
  };
  // An edge slip's size over the hand-off: it rises through zero where the slip slides again.
  auto grown = [&](int j, const MathavanState& s) {
    return (rates.Slip(j, s) - contacts[j].offset).norm() - hand_off;
  };
  // The first switch inside the step [0, h] from z: a cone crossing, or an edge slip grown to
  // the hand-off. The step is cut to it (`end`, `k_end` and the error estimate remade there)
  // and the contact returned, with `hands_off` saying which kind; -1 if none.
  auto first_switch = [&](bool fine, double* h, MathavanState* end, MathavanState* k_end,
                          double* err, bool* hands_off) {
    int which = -1;
    for (int j : {kNose, kSlate}) {
      const Grip grip = contacts[j].grip;
      if (grip == Grip::kSliding) continue;
      // Oriented to rise through zero at the crossing: the excess for a stuck contact, its
      // negative for an edge one; or an edge slip's growth.
      const double sign = grip == Grip::kStuck ? 1.0 : -1.0;
      const bool growing = grip == Grip::kEdge && !(sign * held_excess(j, *end) > 0.0) &&
                           grown(j, *end) > 0.0;
      auto crossing = [&](const MathavanState& s) {
        return growing ? grown(j, s) : sign * held_excess(j, s);
      };
      double fb = crossing(*end);
      if (!(fb > 0.0)) continue;
      double a = 0.0, b = *h, fa = crossing(z);
      if (fa > 0.0) b = 0.0;  // already across: the switch is at z
      MathavanState at_b = b > 0.0 ? *end : z, k_at_b = b > 0.0 ? *k_end : k1;
      double err_b = b > 0.0 ? *err : 0.0;
      int side = 0;  // Illinois' false position
      // A hand-off needs no precision: anywhere the slip is within twice the hand-off will do.
      for (int it = 0; it < 60 && b - a > 1e-15 * total && !(growing && fb <= hand_off); ++it) {
        const double x = std::clamp(b - fb * (b - a) / (fb - fa), a, b);
        const double x_err = step(fine, x, k1, end, k_end);
        const double fx = crossing(*end);
        if (fx > 0.0) {
          b = x;
          fb = fx;
          at_b = *end;
          k_at_b = *k_end;
          err_b = x_err;
          if (side == 1) fa *= 0.5;
          side = 1;
        } else {
          a = x;
          fa = fx;
          if (side == -1) fb *= 0.5;
          side = -1;
        }
      }
      *h = b;
      *end = at_b;
      *k_end = k_at_b;
      *err = err_b;
      which = j;
      *hands_off = growing;
    }
    return which;
  };
  bool compressing = true, rejected = false;
  double target = 0.0, h = 0.125 * total;
  int fine_left = 0, fine_run = 1;
  // Compression ends where vy falls to 0; restitution where W falls to its target. Each is
  // monotone in P (the nose's normal impulse slows vy; W falls while vy < 0).
  auto phase_end = [&](const MathavanState& s) { return compressing ? s[1] : s[5] - target; };
  // How far ahead a sliding slip headed for zero would reach it, were its rate steady: no step
  // goes past that, so the slip lands on zero in a few steps instead of crossing it.
  auto zero_ahead = [&] {
    double ahead = std::numeric_limits<double>::infinity();
    for (int j : {kNose, kSlate}) {
      const SlipContact& c = contacts[j];
      if (c.grip != Grip::kSliding) continue;
      const Eigen::Vector2d s = rates.Slip(j, z) - c.offset;
      const double n = s.norm(), closing = -rates.Slip(j, k1).dot(s) / n;
      if (n > slip_floor && closing > 0.0) ahead = std::min(ahead, n / closing);
    }
    return ahead;
  };
  double ahead = zero_ahead();
  const int cap = 8 * static_cast<int>(steps) + 64;  // guards only: the fine steps alone end it
  for (int k = 0; k < cap; ++k) {
    const bool fine = fine_left > 0 || h <= h_floor;
    if (fine) h = h_min;
    // The step's length, cut at a sliding slip's zero ahead or at a switch. Once the small steps
    // are spent the fallback's steps are not cut: a creeping slip would cut them ever shorter.
    const bool spent = small_steps > kSmallSteps;
    double taken = fine && spent ? h : std::min(h, ahead);
    if (taken < h_min && ++small_steps > kSmallSteps) h_floor = h_min;
    const bool cut = taken < h;
    double err = step(fine, taken, k1, &next, &k_next);
    bool hands_off = false;
    const int switching = first_switch(fine, &taken, &next, &k_next, &err, &hands_off);
    if (!fine && !(err <= tol)) {
      h = std::max(h_floor, taken * ode::Dp45StepFactor(err / tol, rejected));
      rejected = true;
      if (h <= h_floor) {  // the pair cannot meet the tolerance above its floor
        fine_left = fine_run;
        fine_run = std::min(2 * fine_run, 64);
      }
      continue;
    }
    if (phase_end(next) <= 0.0) {
      // The phase ends inside this step: Newton's method on the step's length, each iterate a
      // step of the same rule from z (the phase's quantity falls at the rate k_next gives).
      // A switch later in the step is found again in the next.
      double hh = taken;
      for (int it = 0; it < 6; ++it) {
        const double slope = compressing ? k_next[1] : k_next[5];
        if (!(slope < 0.0)) break;
        const double h_new = std::clamp(hh - phase_end(next) / slope, 0.0, taken);
        if (std::abs(h_new - hh) <= 1e-13 * total) break;
        hh = h_new;
        step(fine, hh, k1, &next, &k_next);
      }
      z = next;
      k1 = k_next;
      if (!compressing) break;
      compressing = false;
      target = (1.0 - e * e) * z[5];
      if (e == 0.0) break;
      rejected = false;
      ahead = zero_ahead();
      continue;
    }
    z = next;
    k1 = k_next;
    bool changed = false;
    if (switching >= 0 && hands_off) {  // an edge slip grown to the hand-off slides
      contacts[switching].grip = Grip::kSliding;
      changed = true;
    } else if (switching >= 0) {  // a stuck contact comes to the edge; an edge contact sticks
      SlipContact& c = contacts[switching];
      c = {c.grip == Grip::kStuck ? Grip::kEdge : Grip::kStuck, rates.Slip(switching, z)};
      changed = true;
    }
    for (int j : {kNose, kSlate}) {
      SlipContact& c = contacts[j];
      const Eigen::Vector2d slip = rates.Slip(j, z) - c.offset;
      const double n = slip.norm();
      if (c.grip == Grip::kEdge && n > hand_off) {
        c.grip = Grip::kSliding;
        changed = true;
      } else if (c.grip == Grip::kSliding && n <= landing) {
        // A slip headed for zero, near it, lands. One that can stick there does (its friction
        // draws it in, whatever its direction). One that cannot passes through zero, or by
        // it: where its present rate would carry it within kMiss of zero (a reversal) it is
        // carried to that closest point, an Euler step whose error is second order in the
        // slip, and the miss is closed by a jump; else (it swings by, its direction turning
        // fast) it is stepped on, landing only within the tolerance. So is one for which no
        // jump can be made (the other contact at the edge).
        const Eigen::Vector2d rate = rates.Slip(j, k1);
        const double closing = -rate.dot(slip);
        MathavanState unused;
        if (n > slip_floor && !(closing > 0.0)) continue;
        if (n > tol && !rates.Jump(j, z, -slip, &unused)) continue;
        if (n > tol && held_excess(j, z) > 0.0) {
          const double to_closest = closing / rate.squaredNorm();
          if (!((slip + to_closest * rate).norm() <= kMiss * speed)) continue;
          z += to_closest * k1;
          k1 = rates(0.0, z);
        }
        settle(j, false);
        changed = true;
      }
    }
    if (changed) k1 = rates(0.0, z);
    ahead = zero_ahead();
    if (fine) {
      if (--fine_left <= 0) h = 2.0 * h_min;
    } else if (switching < 0 && !cut) {
      fine_run = 1;
      h = std::min(h_max, h * ode::Dp45StepFactor(err / tol, rejected));
    }
    rejected = false;
  }
  ball->v = z[0] * ex + z[1] * ey;  // the slate holds the ball down: no vertical velocity
  ball->w = z[2] * ex + z[3] * ey + z[4] * ez;
}

// Stronge's compliant contact, in time tau = omega_n t (omega_n the normal spring's frequency)
// and velocities over the approach speed. The normal force per unit (m v0 omega_n) is sin tau
// in compression (tau <= pi/2) and sin(phase) in restitution, phase = tau / e + (pi/2) (1 -
// 1/e), until phase = pi at tau_f = (1 + e) pi/2; its impulse is 1 - cos tau, then 1 - e cos
// phase. The tangential spring's deflection u (units v0 / omega_n) pulls the contact back with
// force u / eta^2 (eta^2 = beta / r^2, the stiffness ratio k / k_t), so dv/dtau = -r^2 u.
// Stick: u' = v, a harmonic motion of frequency r, while |u| <= mu eta^2 Fn. Slip in direction
// s: the force is s mu Fn, so u = s mu eta^2 Fn and v falls by beta s mu times the normal
// impulse, while the interface slip v - u' keeps the sign s.
namespace {

constexpr double kHalfPi = 0.5 * kPi;

class CompliantContact {
 public:
  CompliantContact(double e, double mu, double beta, double r)
      : e_(e), mu_(mu), beta_(beta), r_(r), eta2_(beta / (r * r)),
        end_(e > 0.0 ? (1.0 + e) * kHalfPi : kHalfPi) {}

  double Solve(double v0) {
    double t = 0.0, v = v0, u = 0.0;
    // At tau = 0 the normal force is zero: the spring sticks if the friction it gains, mu eta^2
    // tau, outgrows the deflection, v0 tau.
    bool stick = v0 <= mu_ * eta2_;
    double s = 1.0;
    // Each phase ends at a switch or at the end; more than a handful means rounding ping-pong
    // at a switch, and the rest is taken as slip.
    for (int phase = 0; phase < 16 && t < end_; ++phase) {
      if (stick) {
        const double t0 = t, u0 = u, v1 = v;
        auto deflection = [&](double x) {
          return u0 * std::cos(r_ * (x - t0)) + v1 / r_ * std::sin(r_ * (x - t0));
        };
        // The spring's swing against what friction holds: not monotone, so sampled.
        t = FirstDrop(t0, 64, [&](double x) {
          return mu_ * eta2_ * Force(x) - std::abs(deflection(x));
        });
        u = deflection(t);
        v = -r_ * u0 * std::sin(r_ * (t - t0)) + v1 * std::cos(r_ * (t - t0));
        s = u >= 0.0 ? 1.0 : -1.0;
        stick = false;
      } else {
        const double t0 = t, v1 = v, p0 = Impulse(t0), sign = s;
        auto speed = [&](double x) { return v1 - beta_ * sign * mu_ * (Impulse(x) - p0); };
        // The interface slip: its rate is -mu Fn (beta - eta^2) in compression and -mu Fn
        // (beta - eta^2 / e^2) in restitution, one sign in each, so it is monotone in each.
        t = FirstDrop(t0, 1, [&](double x) {
          return sign * (speed(x) - eta2_ * sign * mu_ * ForceRate(x));
        });
        v = speed(t);
        u = sign * mu_ * eta2_ * Force(t);
        stick = true;
      }
    }
    if (t < end_) v -= beta_ * s * mu_ * (Impulse(end_) - Impulse(t));
    return v;
  }

 private:
  double Phase(double t) const { return t / e_ + kHalfPi * (1.0 - 1.0 / e_); }
  double Force(double t) const { return t <= kHalfPi ? std::sin(t) : std::sin(Phase(t)); }
  double ForceRate(double t) const {
    return t <= kHalfPi ? std::cos(t) : std::cos(Phase(t)) / e_;
  }
  double Impulse(double t) const {
    return t <= kHalfPi ? 1.0 - std::cos(t) : 1.0 - e_ * std::cos(Phase(t));
  }

  // The first tau in (a, end] where f turns negative (f(a) is about zero or positive); end when
  // it does not. Each of compression and restitution (where the force's law changes) is
  // sampled at `samples` points, and a sign change refined to rounding by FindBracketedRoot.
  // One sample a phase suffices where f is monotone in each.
  template <typename F>
  double FirstDrop(double a, int samples, F f) const {
    double lo = a;
    std::optional<double> f_lo;  // f at lo once computed (at a, only when it is needed)
    auto step = [&](double from, double to) -> bool {
      for (int k = 1; k <= samples; ++k) {
        const double x = k == samples ? to : from + (to - from) * k / samples;
        const double fx = f(x);
        if (fx < 0.0) {
          // At a phase's start f is zero in exact arithmetic: rounding below it is zero.
          const double fa = f_lo.has_value() ? *f_lo : std::max(0.0, f(lo));
          lo = FindBracketedRoot(f, lo, x, fa, fx, 1e-15 * (1.0 + x));
          return true;
        }
        lo = x;
        f_lo = fx;
      }
      return false;
    };
    if (a < kHalfPi && end_ > kHalfPi) {
      if (step(a, kHalfPi)) return lo;
      return step(kHalfPi, end_) ? lo : end_;
    }
    return step(a, end_) ? lo : end_;
  }

  double e_, mu_, beta_, r_, eta2_, end_;
};

}  // namespace

double CompliantTangentialRebound(double slip, double e, double mu, double beta,
                                  double frequency_ratio) {
  if (!(slip > 0.0) || !(mu > 0.0)) return slip;
  return CompliantContact(e, mu, beta, frequency_ratio).Solve(slip);
}

double StrongeFrequencyRatio(double poisson) {
  return std::sqrt(3.5 * 2.0 * (1.0 - poisson) / (2.0 - poisson));
}

double CushionRestitution(double e, double exponent, double approach_mps) {
  if (approach_mps < kRestingContactSpeed) return 0.0;
  if (exponent == 0.0) return e;
  return std::clamp(1.0 - (1.0 - e) * std::pow(approach_mps, exponent), 0.0, 1.0);
}

bool CollideCushion(const TableModel& model, const Eigen::Vector2d& normal, Ball* ball) {
  const Eigen::Vector3d nh(normal.x(), normal.y(), 0.0);
  const double vn = ball->v.dot(nh);
  if (vn >= -kMinApproachSpeed) return false;
  const PhysicsParams& p = model.params();
  if (p.cushion_model == CushionModel::kMirror) {
    ball->v -= (-vn < kRestingContactSpeed ? 1.0 : 2.0) * vn * nh;
  } else if (p.cushion_model == CushionModel::kMathavan2010) {
    CollideCushionMathavan(
        model, nh, CushionRestitution(p.e_cushion_mathavan, p.cushion_restitution_exponent, -vn),
        p.f_cushion_mathavan, p.mu_slide, ball);
  } else {
    // kHan and kStrongeCompliant. The nose touches the ball at angle theta_a above its
    // equator: contact point r_c = R (-cos nh + sin z^), contact normal into the ball
    // n = cos nh - sin z^.
    const double m = model.mass();
    const double radius = model.radius();
    const double s = model.cushion_sin();
    const double c = std::sqrt(1.0 - s * s);
    const Eigen::Vector3d rc = radius * (-c * nh + s * Eigen::Vector3d::UnitZ());
    const Eigen::Vector3d n = c * nh - s * Eigen::Vector3d::UnitZ();
    const double e = CushionRestitution(p.e_cushion, p.cushion_restitution_exponent, -vn);
    const double jn = -(1.0 + e) * m * ball->v.dot(n);
    // Slip of the contact point across the nose; Coulomb friction capped at sticking, where
    // 7/(2m) is a free sphere's inverse effective mass for a tangential impulse at its surface.
    const Eigen::Vector3d vc = ball->v + ball->w.cross(rc);
    const Eigen::Vector3d st = vc - vc.dot(n) * n;
    Eigen::Vector3d friction = Eigen::Vector3d::Zero();
    const double slip = st.norm();
    if (slip > 0.0) {
      double pt = std::min(p.f_cushion * jn, 2.0 * m * slip / 7.0);
      if (p.cushion_model == CushionModel::kStrongeCompliant && jn > 0.0) {
        // The same contact as springs: the slip after, over the approach speed along n
        // (jn / ((1 + e) m), positive: the ball moves into the cushion).
        const double approach = jn / ((1.0 + e) * m);
        const double after = CompliantTangentialRebound(
            slip / approach, e, p.f_cushion, 3.5, StrongeFrequencyRatio(p.cushion_poisson_ratio));
        pt = (slip - after * approach) * m / 3.5;
      }
      friction = -(pt / slip) * st;
    }
    ball->v += (jn * n + friction) / m;
    ball->v.z() = 0.0;  // the slate absorbs the downward push; jumps are not modelled
    ball->w += rc.cross(friction) / model.inertia();
  }
  ball->state = Classify(model, *ball);
  return true;
}

Eigen::Vector2d ClosestOnSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                 const Eigen::Vector2d& p) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  if (len2 == 0.0) return a;
  const double s = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
  return a + s * ab;
}

}  // namespace sportsim::billiards
