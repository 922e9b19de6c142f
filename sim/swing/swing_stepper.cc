#include "sim/swing/swing_stepper.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_format.h"
#include "sim/core/ode/hermite.h"

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

}  // namespace

const ode::AccuracyLimits SwingSolverOptions::kLimits = {
    .default_dt_s = kDefaultDt,
    .dt_s = {.lo = 1e-6, .hi = 0.1},
    .default_tolerance = kDefaultTolerance,
    .tolerance = {.lo = 1e-14, .hi = 0.1},
    .default_max_step_s = kDefaultMaxStep,
    .max_step_s = {.lo = 1e-6, .hi = 0.1}};

std::string_view SwingIntegratorName(SwingIntegrator integrator) {
  return ode::IntegratorName(integrator);
}

std::optional<SwingIntegrator> SwingIntegratorFromName(std::string_view name) {
  for (SwingIntegrator i : kAllSwingIntegrators) {
    if (SwingIntegratorName(i) == name) return i;
  }
  return std::nullopt;
}

absl::Status ValidateSolverOptions(const SwingSolverOptions& o) {
  if (std::find(kAllSwingIntegrators.begin(), kAllSwingIntegrators.end(), o.integrator) ==
      kAllSwingIntegrators.end()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "integrator must be book, euler, semi_implicit_euler, rk4 or dp45, got %d",
        static_cast<int>(o.integrator)));
  }
  if (absl::Status s = ode::ValidateAccuracy(o.integrator, o.accuracy, SwingSolverOptions::kLimits);
      !s.ok()) {
    return s;
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
      dt_(o.accuracy.dt_s.value_or(SwingSolverOptions::kDefaultDt)),
      tol_(o.accuracy.tolerance.value_or(SwingSolverOptions::kDefaultTolerance)),
      max_step_(o.accuracy.max_step_s.value_or(SwingSolverOptions::kDefaultMaxStep)),
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
      y1 = ode::EulerStep(h, y, F(seg, t_, y));
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
      const auto f = [&](double t, const SwingVec& x) { return F(seg, t, x); };
      y1 = ode::Rk4Step(f, t_, h, y, F(seg, t_, y));
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
  // Hairer, Norsett & Wanner's starting-step heuristic (sim/core/ode/runge_kutta.h).
  const int seg = segment_;
  const auto f = [&](double t, const SwingVec& x) { return F(seg, t, x); };
  const SwingVec f0 = F(segment_, t_, y_);
  const double h = ode::Dp45InitialStep(f, t_, y_, f0, tol_, max_step_, t_end);
  k1_ = f0;
  fsal_valid_ = true;
  return h;
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
  const auto f = [&](double t, const SwingVec& x) { return F(seg, t, x); };
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
    const double t1 = to_stop ? t_stop : t_ + h;
    ode::Dp45Stages<SwingVec> st;
    const SwingVec y1 = ode::Dp45Solution(f, t_, h, y, k1, &st, t1);
    const SwingVec k7 = F(seg, t1, y1);
    const double e = ode::Dp45ErrorNorm(ode::Dp45Error(h, k1, st, k7), y, y1, tol_,
                                        ode::ErrorNorm::kRms);
    if (!std::isfinite(e) || !AllFinite(y1)) {
      // Treat as a failed step: shrink hard, and give up only on underflow.
      ++rejected_;
      h_ = 0.2 * h;
      rejected_last = true;
      if (attempt > 60) return NonFinite(t1);
      continue;
    }
    const double fac = ode::Dp45StepFactor(e, rejected_last);
    if (e <= 1.0) {
      *rec = StepRecord{.t0 = t_, .t1 = t1, .y0 = y, .y1 = y1, .segment = seg, .dense = true};
      rec->continuous = ode::MakeDp45Dense(h, y, y1, k1, st, k7);
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
    h_ = h * fac;
  }
}

SwingVec SwingStepper::Interpolate(const StepRecord& r, double t) {
  const double h = r.t1 - r.t0;
  if (h <= 0) return r.y1;
  const double s = (t - r.t0) / h;
  if (r.dense) return r.continuous(s);
  const SwingVec f0 = F(r.segment, r.t0, r.y0);
  const SwingVec f1 = F(r.segment, r.t1, r.y1);
  if (integrator_ != SwingIntegrator::kRk4) {
    // First-order schemes: their angles and rates agree only to O(h), so each component gets its
    // own cubic Hermite (angles from rates, rates from accelerations), consistent to that order.
    return ode::CubicHermite(r.y0, f0, r.y1, f1, h, s);
  }
  // RK4: quintic Hermite for the angles from their values, rates and accelerations at both ends
  // (interpolation error O(h^6), below the scheme's O(h^4)); the rates are its derivative. A
  // cubic's O(h^4) error is as large as RK4's own and blurs its observed order.
  Eigen::Vector2d p, v;
  ode::QuinticHermite<Eigen::Vector2d>(r.y0.head<2>(), r.y0.tail<2>(), f0.tail<2>(),
                                       r.y1.head<2>(), r.y1.tail<2>(), f1.tail<2>(), h, s, &p,
                                       &v);
  SwingVec out;
  out.head<2>() = p;
  out.tail<2>() = v;
  return out;
}

}  // namespace sportsim::swing
