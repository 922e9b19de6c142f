#include "sim/swing/torque_program.h"

#include <algorithm>
#include <cmath>
#include <string_view>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"

namespace sportsim::swing {
namespace {

absl::Status ValidateSchedule(std::string_view name, const TorqueSchedule& s) {
  if (s.knots.empty() || s.knots.size() > TorqueProgram::kMaxKnots) {
    return absl::InvalidArgumentError(absl::StrFormat("%s.knots must have 1 to %d knots, got %d",
                                                      name, TorqueProgram::kMaxKnots,
                                                      s.knots.size()));
  }
  for (size_t i = 0; i < s.knots.size(); ++i) {
    const TorqueKnot& k = s.knots[i];
    if (!std::isfinite(k.t_s) || k.t_s < 0 || k.t_s > 1e3) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s.knots[%d].t_s must be finite and in [0, 1000] s, got %g", name, i, k.t_s));
    }
    if (i > 0 && !(k.t_s > s.knots[i - 1].t_s)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s.knots[%d].t_s must be greater than the previous knot's %g s, got %g", name, i,
          s.knots[i - 1].t_s, k.t_s));
    }
    if (!std::isfinite(k.torque_nm) || std::abs(k.torque_nm) > TorqueProgram::kMaxTorqueNm) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s.knots[%d].torque_nm must be finite and in [-%g, %g] N m, got %g",
                          name, i, TorqueProgram::kMaxTorqueNm, TorqueProgram::kMaxTorqueNm,
                          k.torque_nm));
    }
  }
  return absl::OkStatus();
}

// Value at t_lo and slope of one schedule on a segment starting at t_lo that contains no knot.
void PieceOn(const TorqueSchedule& s, double t_lo, double* v0, double* slope) {
  const auto& k = s.knots;
  // Index of the last knot at or before t_lo (knots are strictly increasing); a knot within
  // kMergeS after t_lo was merged into this breakpoint and counts as reached.
  const double reach = t_lo + TorqueProgram::kMergeS;
  size_t i = 0;
  while (i + 1 < k.size() && k[i + 1].t_s <= reach) ++i;
  if (s.interpolation == Interpolation::kPiecewiseConstant || reach < k.front().t_s ||
      i + 1 >= k.size()) {
    // Before the first knot, after the last, or a constant piece.
    *v0 = (reach < k.front().t_s) ? k.front().torque_nm : k[i].torque_nm;
    *slope = 0.0;
    return;
  }
  const double m = (k[i + 1].torque_nm - k[i].torque_nm) / (k[i + 1].t_s - k[i].t_s);
  *slope = m;
  *v0 = k[i].torque_nm + m * (t_lo - k[i].t_s);
}

}  // namespace

absl::StatusOr<TorqueProgram> TorqueProgram::Create(const TorqueSchedule& q_alpha,
                                                    const TorqueSchedule& q_beta) {
  if (absl::Status s = ValidateSchedule("qalpha", q_alpha); !s.ok()) return s;
  if (absl::Status s = ValidateSchedule("qbeta", q_beta); !s.ok()) return s;
  TorqueProgram p;
  p.q_alpha_ = q_alpha;
  p.q_beta_ = q_beta;
  p.Build();
  return p;
}

TorqueProgram TorqueProgram::Chapter() {
  TorqueProgram p;
  p.q_alpha_ = {Interpolation::kPiecewiseConstant, {{0.0, 100.0}}};
  p.q_beta_ = {Interpolation::kPiecewiseConstant, {{0.0, -10.0}, {0.1, 0.0}}};
  p.Build();
  return p;
}

TorqueProgram TorqueProgram::Constant(double q_alpha_nm, double q_beta_nm) {
  TorqueProgram p;
  p.q_alpha_ = {Interpolation::kPiecewiseConstant, {{0.0, q_alpha_nm}}};
  p.q_beta_ = {Interpolation::kPiecewiseConstant, {{0.0, q_beta_nm}}};
  p.Build();
  return p;
}

void TorqueProgram::Build() {
  breakpoints_.clear();
  for (const TorqueSchedule* s : {&q_alpha_, &q_beta_}) {
    for (const TorqueKnot& k : s->knots) {
      if (k.t_s > kMergeS) breakpoints_.push_back(k.t_s);
    }
  }
  std::sort(breakpoints_.begin(), breakpoints_.end());
  breakpoints_.erase(std::unique(breakpoints_.begin(), breakpoints_.end(),
                                 [](double a, double b) { return b - a <= kMergeS; }),
                     breakpoints_.end());
  // Segment j spans [b_{j-1}, b_j] with b_{-1} = 0 (or -inf) and b_n = +inf.
  segments_.clear();
  for (size_t j = 0; j <= breakpoints_.size(); ++j) {
    const double lo = j == 0 ? 0.0 : breakpoints_[j - 1];
    Segment seg{.t0 = lo, .qa0 = 0, .qa_slope = 0, .qb0 = 0, .qb_slope = 0};
    PieceOn(q_alpha_, lo, &seg.qa0, &seg.qa_slope);
    PieceOn(q_beta_, lo, &seg.qb0, &seg.qb_slope);
    segments_.push_back(seg);
  }
}

int TorqueProgram::SegmentAt(double t) const {
  return static_cast<int>(std::upper_bound(breakpoints_.begin(), breakpoints_.end(), t) -
                          breakpoints_.begin());
}

}  // namespace sportsim::swing
