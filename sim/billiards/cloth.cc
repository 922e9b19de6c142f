#include "sim/billiards/cloth.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sportsim::billiards {
namespace {

double Sign(double x) { return x > 0 ? 1.0 : (x < 0 ? -1.0 : 0.0); }

// Slip-speed friction's bands. Band k (1..K) holds the slips from E(k-1) to E(k), E(j) = u_c j /
// K; slips from E(K) = u_c up slide at mu_s ("band K + 1"). A band's slips start a guard below
// its edges: a slip brought to an edge by its transition time (E(k-1), give or take rounding,
// about 1e-15 m/s at the speeds of a table) is still in band k, so every rate the band's piece
// evaluates, to its very end, is band k's; the transition then sets the slip a guard further
// down, inside band k - 1 (which shortens a band by 1e-12 s at most, for 16). The guard is 1e-13 m/s,
// or a thousandth of the band where that is narrower (a fade far below kRestSlip, which ends
// the slide first: the calibration's probes of u_c near 0 come here).
double Guard(const PhysicsParams& p) {
  return std::min(1e-13, 1e-3 * p.slide_fade_speed_mps / p.slide_fade_bands);
}

bool Fades(const PhysicsParams& p) { return p.slide_fade_speed_mps > 0.0; }
int Bands(const PhysicsParams& p) { return static_cast<int>(p.slide_fade_bands); }

// The band of a slip: 1..K in the fade, K + 1 above it; 0 with the fade off.
int BandOf(const PhysicsParams& p, double slip) {
  if (!Fades(p)) return 0;
  const int bands = Bands(p);
  const double k = std::floor((slip + Guard(p)) * bands / p.slide_fade_speed_mps) + 1.0;
  return k > bands ? bands + 1 : static_cast<int>(std::max(k, 1.0));
}

// E(j): the slip at band j's upper edge.
double BandEdge(const PhysicsParams& p, int j) {
  return p.slide_fade_speed_mps * j / Bands(p);
}

// The rolling part of a sliding ball's motion, v - 2/7 u (horizontal).
Eigen::Vector3d RollingPart(const Eigen::Vector3d& v, const Eigen::Vector3d& u) {
  return {v.x() - (2.0 / 7.0) * u.x(), v.y() - (2.0 / 7.0) * u.y(), 0.0};
}

// Changes v by dv and w_xy by z^ x dv / R: the contact point's slip does not change.
void AddKeepingSlip(const Eigen::Vector3d& dv, double radius, Eigen::Vector3d* v,
                    Eigen::Vector3d* w) {
  v->x() += dv.x();
  v->y() += dv.y();
  w->x() -= dv.y() / radius;
  w->y() += dv.x() / radius;
}

// A sliding ball at (or within rounding of) no slip starts rolling. Friction acts at the contact
// point, so the angular momentum about it is conserved: v_roll = v - 2/7 u (exact at u = 0; a
// projection for the last bit of slip).
void EndSlide(double radius, Ball* ball) {
  const Eigen::Vector3d u = Slip(ball->v, ball->w, radius);
  ball->v -= (2.0 / 7.0) * u;
  ball->v.z() = 0.0;
  ball->w.x() = -ball->v.y() / radius;
  ball->w.y() = ball->v.x() / radius;
  if (ball->v.head<2>().norm() <= kRestSpeed) {
    ball->v.setZero();
    ball->w.x() = ball->w.y() = 0.0;
  }
}

bool InFade(const PhysicsParams& p, int band) { return band >= 1 && band <= Bands(p); }

// The sliding friction coefficient in a band (BandOf): mu_slide outside the fade, the fade's
// value at the band's middle slip in it.
double SlideFriction(const PhysicsParams& p, int band) {
  return InFade(p, band) ? p.mu_slide * (band - 0.5) / Bands(p) : p.mu_slide;
}

}  // namespace

MotionState Classify(const TableModel& model, const Ball& ball) {
  if (ball.state == MotionState::kPocketed) return MotionState::kPocketed;
  const double speed = ball.v.head<2>().norm();
  const double slip = Slip(ball.v, ball.w, model.radius()).norm();
  if (slip > kRestSlip) return MotionState::kSliding;
  if (speed > kRestSpeed) return MotionState::kRolling;
  if (std::abs(ball.w.z()) > kRestSpin) return MotionState::kSpinning;
  return MotionState::kStationary;
}

Rates ClothRates(const TableModel& model, uint32_t effects, MotionState state,
                 const Eigen::Vector3d& v, const Eigen::Vector3d& w) {
  Rates r;
  const PhysicsParams& p = model.params();
  const double radius = model.radius();
  switch (state) {
    case MotionState::kSliding: {
      const Eigen::Vector3d u = Slip(v, w, radius);
      const double un = u.norm();
      const int band = BandOf(p, un);
      if (un > 0) {
        const Eigen::Vector3d uh = u / un;
        const double f = SlideFriction(p, band) * p.gravity_mps2;
        r.dv = -f * uh;
        r.dw = (2.5 * f / radius) * Eigen::Vector3d(-uh.y(), uh.x(), 0.0);  // z^ x u^
      }
      if (InFade(p, band) && (effects & kEffectDisableRollingResistance) == 0) {
        const Eigen::Vector3d vr = RollingPart(v, u);
        const double n = vr.norm();
        if (n > kRestSpeed) {
          AddKeepingSlip(-(p.mu_roll * p.gravity_mps2 / n) * vr, radius, &r.dv, &r.dw);
        }
      }
      break;
    }
    case MotionState::kRolling: {
      const double speed = v.head<2>().norm();
      if ((effects & kEffectDisableRollingResistance) == 0 && speed > 0) {
        r.dv = -(p.mu_roll * p.gravity_mps2 / speed) * Eigen::Vector3d(v.x(), v.y(), 0.0);
      }
      break;
    }
    case MotionState::kSpinning:
    case MotionState::kStationary:
    case MotionState::kAirborne:
    case MotionState::kPocketed:
      break;
  }
  const bool moving = state == MotionState::kSliding || state == MotionState::kRolling ||
                      state == MotionState::kSpinning;
  if (moving && (effects & kEffectDisableSpinDecay) == 0) {
    r.dw.z() -= p.spin_decel_rps2 * Sign(w.z());
  }
  if (moving && (effects & kEffectEnableDrag) != 0) {
    const double m = model.mass();
    const double speed = v.norm();
    const double k = 0.5 * p.air_density_kgpm3 * p.drag_coefficient * 3.141592653589793 *
                     radius * radius / m;
    Eigen::Vector3d a_drag = -k * speed * v;
    a_drag.z() = 0.0;
    if (state == MotionState::kRolling) a_drag *= 5.0 / 7.0;
    r.dv += a_drag;
    const double kt = 0.5 * p.air_density_kgpm3 * p.spin_drag_coefficient *
                      std::pow(radius, 5) / model.inertia();
    const Eigen::Vector3d alpha_drag = -kt * w.norm() * w;
    if (state == MotionState::kSliding) {
      r.dw += alpha_drag;
    } else {
      r.dw.z() += alpha_drag.z();
    }
  }
  if (state == MotionState::kRolling) {
    // The rolling constraint w_xy = z^ x v / R holds for the rates too.
    r.dw.x() = -r.dv.y() / radius;
    r.dw.y() = r.dv.x() / radius;
  }
  return r;
}

namespace {

// Time until one quantity reaches zero at the given (current) rates.
double ZeroTime(const TableModel& model, const Ball& ball, const Rates& rates,
                TransitionKind kind) {
  constexpr double kNever = std::numeric_limits<double>::infinity();
  // Each quantity falls linearly at its current rate; time to reach zero.
  switch (kind) {
    case TransitionKind::kSlideEnd:
    case TransitionKind::kSlideBand: {
      // The slip falls along its own direction, |u| at the rate -u . du / |u|, to its band's
      // lower edge: zero in the last band (or with the fade off), where the slide ends
      // (kSlideEnd); E(k - 1) in band k >= 2 (kSlideBand).
      if (ball.state != MotionState::kSliding) return kNever;
      const PhysicsParams& p = model.params();
      const Eigen::Vector3d u = Slip(ball.v, ball.w, model.radius());
      const int band = BandOf(p, u.norm());
      const bool last = band <= 1;
      if (last != (kind == TransitionKind::kSlideEnd)) return kNever;
      const double closing = -u.dot(Slip(rates.dv, rates.dw, model.radius()));
      if (!(closing > 0)) return kNever;
      if (last) return u.squaredNorm() / closing;
      const double un = u.norm();
      return std::max(un - BandEdge(p, band - 1), 0.0) * un / closing;
    }
    case TransitionKind::kGlideStop: {
      if (ball.state != MotionState::kSliding || !Fades(model.params())) return kNever;
      const Eigen::Vector3d u = Slip(ball.v, ball.w, model.radius());
      const Eigen::Vector3d vr = RollingPart(ball.v, u);
      if (vr.norm() <= kRestSpeed) return kNever;
      const Eigen::Vector3d dvr =
          RollingPart(rates.dv, Slip(rates.dv, rates.dw, model.radius()));
      const double closing = -vr.dot(dvr);
      return closing > 0 ? vr.squaredNorm() / closing : kNever;
    }
    case TransitionKind::kRollStop: {
      if (ball.state != MotionState::kRolling) return kNever;
      const Eigen::Vector2d vh = ball.v.head<2>();
      const double closing = -vh.dot(rates.dv.head<2>());
      return closing > 0 ? vh.squaredNorm() / closing : kNever;
    }
    case TransitionKind::kSpinStop: {
      if (ball.state != MotionState::kSliding && ball.state != MotionState::kRolling &&
          ball.state != MotionState::kSpinning) {
        return kNever;
      }
      const double closing = -ball.w.z() * rates.dw.z();
      return closing > 0 && ball.w.z() != 0 ? ball.w.z() * ball.w.z() / closing : kNever;
    }
    case TransitionKind::kNone:
      break;
  }
  return kNever;
}

}  // namespace

double TimeToZero(const TableModel& model, uint32_t effects, const Ball& ball,
                  TransitionKind kind) {
  return ZeroTime(model, ball, ClothRates(model, effects, ball.state, ball.v, ball.w), kind);
}

NextTransition TimeToTransition(const TableModel& model, uint32_t effects, const Ball& ball,
                                Rates* rates_out) {
  NextTransition next;
  const Rates rates = ClothRates(model, effects, ball.state, ball.v, ball.w);
  if (rates_out != nullptr) *rates_out = rates;
  for (TransitionKind kind :
       {TransitionKind::kSlideEnd, TransitionKind::kRollStop, TransitionKind::kSpinStop,
        TransitionKind::kSlideBand, TransitionKind::kGlideStop}) {
    const double dt = ZeroTime(model, ball, rates, kind);
    if (dt < next.dt_s) {
      next.dt_s = dt;
      next.kind = kind;
    }
  }
  return next;
}

void ApplyTransition(const TableModel& model, TransitionKind kind, Ball* ball) {
  const double radius = model.radius();
  switch (kind) {
    case TransitionKind::kSlideEnd:
      EndSlide(radius, ball);
      break;
    case TransitionKind::kRollStop:
      ball->v.setZero();
      ball->w.x() = ball->w.y() = 0.0;
      break;
    case TransitionKind::kSpinStop:
      ball->w.z() = 0.0;
      break;
    case TransitionKind::kSlideBand: {
      // The slip is at the edge E(j) nearest it (its band's lower one): set it a guard inside
      // the band below, keeping v - 2/7 u (the angular momentum about the contact point).
      const PhysicsParams& p = model.params();
      const Eigen::Vector3d u = Slip(ball->v, ball->w, radius);
      const double un = u.norm();
      const double edges = un / BandEdge(p, 1);  // past K only for a fade below rounding
      const int j = edges >= Bands(p) ? Bands(p) : static_cast<int>(std::lround(edges));
      const double target = BandEdge(p, j) - 2.0 * Guard(p);
      if (j < 1 || target <= kRestSlip) {  // the slide ends at a band edge too slow to slide
        EndSlide(radius, ball);
        break;
      }
      const Eigen::Vector3d du = (target / un - 1.0) * u;
      // v - 2/7 u kept: v moves by 2/7 du and w by what makes the slip move by du.
      ball->v.x() += (2.0 / 7.0) * du.x();
      ball->v.y() += (2.0 / 7.0) * du.y();
      ball->w.x() += (5.0 / 7.0) * du.y() / radius;
      ball->w.y() -= (5.0 / 7.0) * du.x() / radius;
      break;
    }
    case TransitionKind::kGlideStop: {
      const Eigen::Vector3d u = Slip(ball->v, ball->w, radius);
      AddKeepingSlip(-RollingPart(ball->v, u), radius, &ball->v, &ball->w);
      break;
    }
    case TransitionKind::kNone:
      break;
  }
  if (ball->state == MotionState::kRolling && kind == TransitionKind::kSpinStop) {
    return;  // still rolling: do not let a rounding-level slip reclassify it as sliding
  }
  ball->state = Classify(model, *ball);
}

double KineticEnergy(const TableModel& model, const Ball& ball) {
  return 0.5 * model.mass() * ball.v.squaredNorm() + 0.5 * model.inertia() * ball.w.squaredNorm();
}

}  // namespace sportsim::billiards
