#include "sim/swing/swing_stepper.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_format.h"

namespace sportsim::swing {
namespace {

// A breakpoint within this fraction of a step of a grid point is taken as on the grid point.
constexpr double kSnap = 1e-9;

bool AllFinite(const SwingVec& y) { return y.allFinite(); }

absl::Status NonFinite(double t) {
  return absl::InvalidArgumentError(absl::StrFormat(
      "the swing state became non-finite at t = %.9g s: reduce dt_s (or the tolerance) or the "
      "torques",
      t));
}

// Dormand-Prince 5(4) tableau (Dormand & Prince 1980; Hairer, Norsett & Wanner table II.5.2).
constexpr double kC2 = 1.0 / 5, kC3 = 3.0 / 10, kC4 = 4.0 / 5, kC5 = 8.0 / 9;
constexpr double kA21 = 1.0 / 5;
constexpr double kA31 = 3.0 / 40, kA32 = 9.0 / 40;
constexpr double kA41 = 44.0 / 45, kA42 = -56.0 / 15, kA43 = 32.0 / 9;
constexpr double kA51 = 19372.0 / 6561, kA52 = -25360.0 / 2187, kA53 = 64448.0 / 6561,
                 kA54 = -212.0 / 729;
constexpr double kA61 = 9017.0 / 3168, kA62 = -355.0 / 33, kA63 = 46732.0 / 5247,
                 kA64 = 49.0 / 176, kA65 = -5103.0 / 18656;
constexpr double kA71 = 35.0 / 384, kA73 = 500.0 / 1113, kA74 = 125.0 / 192,
                 kA75 = -2187.0 / 6784, kA76 = 11.0 / 84;
// Fifth-order weights minus fourth-order weights (the error estimate).
constexpr double kE1 = 71.0 / 57600, kE3 = -71.0 / 16695, kE4 = 71.0 / 1920,
                 kE5 = -17253.0 / 339200, kE6 = 22.0 / 525, kE7 = -1.0 / 40;
// Continuous extension (Hairer, Norsett & Wanner, dense output of DOPRI5).
constexpr double kD1 = -12715105075.0 / 11282082432, kD3 = 87487479700.0 / 32700410799,
                 kD4 = -10690763975.0 / 1880347072, kD5 = 701980252875.0 / 199316789632,
                 kD6 = -1453857185.0 / 822651844, kD7 = 69997945.0 / 29380423;

}  // namespace

std::string_view SwingIntegratorName(SwingIntegrator integrator) {
  switch (integrator) {
    case SwingIntegrator::kBook: return "book";
    case SwingIntegrator::kEuler: return "euler";
    case SwingIntegrator::kSemiImplicitEuler: return "semi_implicit_euler";
    case SwingIntegrator::kRk4: return "rk4";
    case SwingIntegrator::kDp45: return "dp45";
  }
  return "unknown";
}

std::optional<SwingIntegrator> SwingIntegratorFromName(std::string_view name) {
  for (SwingIntegrator i : kAllSwingIntegrators) {
    if (SwingIntegratorName(i) == name) return i;
  }
  return std::nullopt;
}

absl::Status ValidateSolverOptions(const SwingSolverOptions& o) {
  const bool adaptive = o.integrator == SwingIntegrator::kDp45;
  const std::string_view name = SwingIntegratorName(o.integrator);
  if (adaptive && o.dt_s.has_value()) {
    return absl::InvalidArgumentError(
        "dt_s applies to fixed-step integrators; dp45 takes tolerance and max_step_s");
  }
  if (!adaptive && o.tolerance.has_value()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "tolerance applies to dp45 only; %s is a fixed-step integrator: set dt_s", name));
  }
  if (!adaptive && o.max_step_s.has_value()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "max_step_s applies to dp45 only; %s is a fixed-step integrator: set dt_s", name));
  }
  if (o.dt_s && !(std::isfinite(*o.dt_s) && *o.dt_s >= 1e-6 && *o.dt_s <= 0.1)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("dt_s must be finite and in [1e-06, 0.1] s, got %g", *o.dt_s));
  }
  if (o.tolerance && !(std::isfinite(*o.tolerance) && *o.tolerance >= 1e-14 &&
                       *o.tolerance <= 0.1)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("tolerance must be finite and in [1e-14, 0.1], got %g", *o.tolerance));
  }
  if (o.max_step_s && !(std::isfinite(*o.max_step_s) && *o.max_step_s >= 1e-6 &&
                        *o.max_step_s <= 0.1)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("max_step_s must be finite and in [1e-06, 0.1] s, got %g", *o.max_step_s));
  }
  if (!(std::isfinite(o.max_turn_per_step_rad) && o.max_turn_per_step_rad > 0 &&
        o.max_turn_per_step_rad <= kPi)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "max_turn_per_step_rad must be in (0, pi], got %g", o.max_turn_per_step_rad));
  }
  return absl::OkStatus();
}

SwingVec SwingStepper::InitialState(const SwingModel& model) {
  return {0.0, model.params().beta0_rad, 0.0, 0.0};
}

SwingStepper::SwingStepper(const SwingModel* model, const TorqueProgram* program,
                           const SwingSolverOptions& o)
    : model_(model),
      program_(program),
      integrator_(o.integrator),
      dt_(o.dt_s.value_or(SwingSolverOptions::kDefaultDt)),
      tol_(o.tolerance.value_or(SwingSolverOptions::kDefaultTolerance)),
      max_step_(o.max_step_s.value_or(SwingSolverOptions::kDefaultMaxStep)),
      max_turn_(o.max_turn_per_step_rad),
      y_(InitialState(*model)) {}

absl::StatusOr<SwingStepper> SwingStepper::Create(const SwingModel* model,
                                                  const TorqueProgram* program,
                                                  const SwingSolverOptions& options) {
  if (absl::Status s = ValidateSolverOptions(options); !s.ok()) return s;
  return SwingStepper(model, program, options);
}

double SwingStepper::SegmentEnd() const {
  const auto& b = program_->breakpoints();
  return segment_ < static_cast<int>(b.size()) ? b[static_cast<size_t>(segment_)]
                                               : std::numeric_limits<double>::infinity();
}

void SwingStepper::ProgramChanged(const TorqueProgram* program) {
  program_ = program;
  segment_ = program_->SegmentAt(t_);
  fsal_valid_ = false;
}

absl::Status SwingStepper::Step(double t_limit, StepRecord* record) {
  if (!(t_limit > t_)) {
    return absl::FailedPreconditionError(
        absl::StrFormat("Step: t_limit %.9g s is not after the current time %.9g s", t_limit, t_));
  }
  return integrator_ == SwingIntegrator::kDp45 ? Dp45Step(t_limit, record)
                                               : FixedStep(t_limit, record);
}

absl::Status SwingStepper::FixedStep(double t_limit, StepRecord* rec) {
  // The step ends at the next grid point, or earlier at a breakpoint or the limit.
  const double t_grid = static_cast<double>(grid_ + 1) * dt_;
  const double snap = kSnap * dt_;
  double t_end = t_grid;
  bool on_grid = true;
  const double b = SegmentEnd();
  if (b < t_grid - snap) {
    t_end = b;
    on_grid = false;
  }
  if (t_limit < t_end - snap) {
    t_end = t_limit;
    on_grid = false;
  }
  const double h = t_end - t_;
  const int seg = segment_;
  const SwingVec& y = y_;
  SwingVec y1;
  switch (integrator_) {
    case SwingIntegrator::kEuler: {
      y1 = y + h * F(seg, t_, y);
      break;
    }
    case SwingIntegrator::kSemiImplicitEuler: {
      const SwingVec f = F(seg, t_, y);
      y1.tail<2>() = y.tail<2>() + h * f.tail<2>();
      y1.head<2>() = y.head<2>() + h * y1.tail<2>();
      break;
    }
    case SwingIntegrator::kBook: {
      // Rates only between stages; positions stay at the start of the step.
      const Eigen::Vector2d w = y.tail<2>();
      SwingVec s = y;
      const Eigen::Vector2d k1 = h * F(seg, t_, s).tail<2>();
      s.tail<2>() = w + 0.5 * k1;
      const Eigen::Vector2d k2 = h * F(seg, t_ + 0.5 * h, s).tail<2>();
      s.tail<2>() = w + 0.5 * k2;
      const Eigen::Vector2d k3 = h * F(seg, t_ + 0.5 * h, s).tail<2>();
      s.tail<2>() = w + k3;
      const Eigen::Vector2d k4 = h * F(seg, t_ + h, s).tail<2>();
      y1.tail<2>() = w + (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0;
      y1.head<2>() = y.head<2>() + h * y1.tail<2>();
      break;
    }
    case SwingIntegrator::kRk4: {
      const SwingVec k1 = F(seg, t_, y);
      const SwingVec k2 = F(seg, t_ + 0.5 * h, y + (0.5 * h) * k1);
      const SwingVec k3 = F(seg, t_ + 0.5 * h, y + (0.5 * h) * k2);
      const SwingVec k4 = F(seg, t_ + h, y + h * k3);
      y1 = y + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
      break;
    }
    case SwingIntegrator::kDp45:
      return absl::InternalError("dp45 is not a fixed-step scheme");
  }
  if (!AllFinite(y1)) return NonFinite(t_end);
  // Under-resolution: the fastest angle (alpha, beta or phi) turning too far in one step.
  const double w = std::max({std::abs(y1[2]), std::abs(y1[3]), std::abs(y1[3] - y1[2]),
                             std::abs(y[2]), std::abs(y[3]), std::abs(y[3] - y[2])});
  if (w * h > max_turn_) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "dt_s = %g s is too large for this swing: at t = %.6g s an angle turned %.3g rad in one "
        "step (limit %g rad, |omega| = %.4g rad/s); use a smaller dt_s (below %.2g s here, and "
        "less as the swing speeds up) or dp45",
        dt_, t_end, w * h, max_turn_, w, max_turn_ / w));
  }
  *rec = StepRecord{.t0 = t_, .t1 = t_end, .y0 = y, .y1 = y1, .segment = seg};
  y_ = y1;
  t_ = t_end;
  if (on_grid) {
    ++grid_;
    t_ = t_grid;
    rec->t1 = t_grid;
  }
  // Past (or within a snap of) the breakpoint: the next segment's torques apply.
  while (SegmentEnd() <= t_ + snap) ++segment_;
  ++steps_;
  return absl::OkStatus();
}

double SwingStepper::Dp45InitialStep(double t_end) {
  // Hairer, Norsett & Wanner's starting-step heuristic (Solving ODEs I, sec. II.4).
  const SwingVec f0 = F(segment_, t_, y_);
  const SwingVec sk = tol_ * (SwingVec::Ones() + y_.cwiseAbs());
  const double d0 = std::sqrt((y_.cwiseQuotient(sk)).squaredNorm() / 4.0);
  const double d1 = std::sqrt((f0.cwiseQuotient(sk)).squaredNorm() / 4.0);
  double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
  h0 = std::min({h0, max_step_, t_end - t_});
  const SwingVec f1 = F(segment_, t_ + h0, y_ + h0 * f0);
  const double d2 = std::sqrt(((f1 - f0).cwiseQuotient(sk)).squaredNorm() / 4.0) / h0;
  const double dm = std::max(d1, d2);
  const double h1 = dm <= 1e-15 ? std::max(1e-6, h0 * 1e-3) : std::pow(0.01 / dm, 1.0 / 5.0);
  k1_ = f0;
  fsal_valid_ = true;
  return std::min({100.0 * h0, h1, max_step_});
}

absl::Status SwingStepper::Dp45Step(double t_limit, StepRecord* rec) {
  const double b = SegmentEnd();
  const double t_stop = std::min(b, t_limit);
  if (h_ <= 0) h_ = Dp45InitialStep(t_stop);
  if (!fsal_valid_) {
    k1_ = F(segment_, t_, y_);
    fsal_valid_ = true;
  }
  const int seg = segment_;
  const SwingVec& y = y_;
  const SwingVec& k1 = k1_;
  bool rejected_last = false;
  for (int attempt = 0;; ++attempt) {
    double h = std::min(h_, max_step_);
    // Land exactly on a breakpoint or the limit when it is within reach.
    bool to_stop = false;
    if (t_ + h >= t_stop - 1e-12 * std::max(1.0, std::abs(t_stop))) {
      h = t_stop - t_;
      to_stop = true;
    }
    if (!(h > 1e-14 * std::max(1.0, std::abs(t_)))) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "dp45 step size underflow at t = %.9g s: the swing is too stiff or singular for "
          "tolerance %g",
          t_, tol_));
    }
    const SwingVec k2 = F(seg, t_ + kC2 * h, y + h * (kA21 * k1));
    const SwingVec k3 = F(seg, t_ + kC3 * h, y + h * (kA31 * k1 + kA32 * k2));
    const SwingVec k4 = F(seg, t_ + kC4 * h, y + h * (kA41 * k1 + kA42 * k2 + kA43 * k3));
    const SwingVec k5 =
        F(seg, t_ + kC5 * h, y + h * (kA51 * k1 + kA52 * k2 + kA53 * k3 + kA54 * k4));
    const double t1 = to_stop ? t_stop : t_ + h;
    const SwingVec k6 =
        F(seg, t1, y + h * (kA61 * k1 + kA62 * k2 + kA63 * k3 + kA64 * k4 + kA65 * k5));
    const SwingVec y1 =
        y + h * (kA71 * k1 + kA73 * k3 + kA74 * k4 + kA75 * k5 + kA76 * k6);
    const SwingVec k7 = F(seg, t1, y1);
    const SwingVec err =
        h * (kE1 * k1 + kE3 * k3 + kE4 * k4 + kE5 * k5 + kE6 * k6 + kE7 * k7);
    const SwingVec sk = tol_ * (SwingVec::Ones() + y.cwiseAbs().cwiseMax(y1.cwiseAbs()));
    const double e = std::sqrt(err.cwiseQuotient(sk).squaredNorm() / 4.0);
    if (!std::isfinite(e) || !AllFinite(y1)) {
      // Treat as a failed step: shrink hard, and give up only on underflow.
      ++rejected_;
      h_ = 0.2 * h;
      rejected_last = true;
      if (attempt > 60) return NonFinite(t1);
      continue;
    }
    double fac = 0.9 * std::pow(std::max(e, 1e-10), -0.2);
    if (e <= 1.0) {
      fac = std::clamp(fac, 0.2, rejected_last ? 1.0 : 5.0);
      *rec = StepRecord{.t0 = t_, .t1 = t1, .y0 = y, .y1 = y1, .segment = seg, .dense = true};
      rec->rcont[0] = y;
      rec->rcont[1] = y1 - y;
      rec->rcont[2] = h * k1 - rec->rcont[1];
      rec->rcont[3] = rec->rcont[1] - h * k7 - rec->rcont[2];
      rec->rcont[4] = h * (kD1 * k1 + kD3 * k3 + kD4 * k4 + kD5 * k5 + kD6 * k6 + kD7 * k7);
      y_ = y1;
      t_ = t1;
      k1_ = k7;
      // A step shortened to land on a stop keeps the earlier, larger proposal.
      h_ = std::min(to_stop ? std::max(h_, h * fac) : h * fac, max_step_);
      while (SegmentEnd() <= t_ + TorqueProgram::kMergeS) {
        ++segment_;
        fsal_valid_ = false;  // the torques jump: k7 belongs to the old segment
      }
      ++steps_;
      return absl::OkStatus();
    }
    ++rejected_;
    rejected_last = true;
    h_ = h * std::clamp(fac, 0.2, 1.0);
  }
}

SwingVec SwingStepper::Interpolate(const StepRecord& r, double t) {
  const double h = r.t1 - r.t0;
  if (h <= 0) return r.y1;
  const double s = (t - r.t0) / h;
  if (r.dense) {
    const double s1 = 1.0 - s;
    return r.rcont[0] +
           s * (r.rcont[1] + s1 * (r.rcont[2] + s * (r.rcont[3] + s1 * r.rcont[4])));
  }
  const SwingVec f0 = F(r.segment, r.t0, r.y0);
  const SwingVec f1 = F(r.segment, r.t1, r.y1);
  const double s2 = s * s, s3 = s2 * s;
  if (integrator_ != SwingIntegrator::kRk4) {
    // First-order schemes: their angles and rates agree only to O(h), so each component gets its
    // own cubic Hermite (angles from rates, rates from accelerations), consistent to that order.
    return (2 * s3 - 3 * s2 + 1) * r.y0 + (s3 - 2 * s2 + s) * h * f0 + (3 * s2 - 2 * s3) * r.y1 +
           (s3 - s2) * h * f1;
  }
  // RK4: quintic Hermite for the angles from their values, rates and accelerations at both ends
  // (interpolation error O(h^6), below the scheme's O(h^4)); the rates are its derivative. A
  // cubic's O(h^4) error is as large as RK4's own and blurs its observed order.
  const double s4 = s3 * s, s5 = s4 * s;
  const double h0 = 1 - 10 * s3 + 15 * s4 - 6 * s5, h5 = 1 - h0;
  const double h1 = s - 6 * s3 + 8 * s4 - 3 * s5;
  const double h2 = 0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5;
  const double h3 = 0.5 * s3 - s4 + 0.5 * s5;
  const double h4 = -4 * s3 + 7 * s4 - 3 * s5;
  const double d0 = -30 * s2 + 60 * s3 - 30 * s4, d5 = -d0;
  const double d1 = 1 - 18 * s2 + 32 * s3 - 15 * s4;
  const double d2 = s - 4.5 * s2 + 6 * s3 - 2.5 * s4;
  const double d3 = 1.5 * s2 - 4 * s3 + 2.5 * s4;
  const double d4 = -12 * s2 + 28 * s3 - 15 * s4;
  const Eigen::Vector2d p0 = r.y0.head<2>(), p1 = r.y1.head<2>();
  const Eigen::Vector2d v0 = r.y0.tail<2>(), v1 = r.y1.tail<2>();
  const Eigen::Vector2d a0 = f0.tail<2>(), a1 = f1.tail<2>();
  SwingVec out;
  out.head<2>() = h0 * p0 + h1 * h * v0 + h2 * h * h * a0 + h3 * h * h * a1 + h4 * h * v1 + h5 * p1;
  out.tail<2>() = (d0 * p0 + d5 * p1) / h + d1 * v0 + d2 * h * a0 + d3 * h * a1 + d4 * v1;
  return out;
}

}  // namespace sportsim::swing
