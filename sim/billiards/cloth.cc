#include "sim/billiards/cloth.h"

#include <cmath>
#include <limits>

namespace sportsim::billiards {
namespace {

double Sign(double x) { return x > 0 ? 1.0 : (x < 0 ? -1.0 : 0.0); }

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
      if (un > 0) {
        const Eigen::Vector3d uh = u / un;
        const double f = p.mu_slide * p.gravity_mps2;
        r.dv = -f * uh;
        r.dw = (2.5 * f / radius) * Eigen::Vector3d(-uh.y(), uh.x(), 0.0);  // z^ x u^
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
    case TransitionKind::kSlideEnd: {
      if (ball.state != MotionState::kSliding) return kNever;
      const Eigen::Vector3d u = Slip(ball.v, ball.w, model.radius());
      const double closing = -u.dot(Slip(rates.dv, rates.dw, model.radius()));
      return closing > 0 ? u.squaredNorm() / closing : kNever;
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
       {TransitionKind::kSlideEnd, TransitionKind::kRollStop, TransitionKind::kSpinStop}) {
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
    case TransitionKind::kSlideEnd: {
      // Friction acts at the contact point, so the angular momentum about it is conserved:
      // v_roll = v - 2/7 u (exact at u = 0; a projection for the last bit of slip).
      const Eigen::Vector3d u = Slip(ball->v, ball->w, radius);
      ball->v -= (2.0 / 7.0) * u;
      ball->v.z() = 0.0;
      ball->w.x() = -ball->v.y() / radius;
      ball->w.y() = ball->v.x() / radius;
      if (ball->v.head<2>().norm() <= kRestSpeed) {
        ball->v.setZero();
        ball->w.x() = ball->w.y() = 0.0;
      }
      break;
    }
    case TransitionKind::kRollStop:
      ball->v.setZero();
      ball->w.x() = ball->w.y() = 0.0;
      break;
    case TransitionKind::kSpinStop:
      ball->w.z() = 0.0;
      break;
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
