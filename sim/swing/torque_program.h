// Torque programs for the swing: piecewise-constant or piecewise-linear schedules for the
// shoulder torque Q_alpha and the wrist torque Q_beta.
//
// Every knot time is a breakpoint that the integrators step onto exactly, and the torque inside
// a step comes from the piece of the segment the step lies in: no floating-point comparison of
// an accumulated time with a switch time ever decides which piece applies.
#ifndef SPORTSIM_SIM_SWING_TORQUE_PROGRAM_H_
#define SPORTSIM_SIM_SWING_TORQUE_PROGRAM_H_

#include <vector>

#include "absl/status/statusor.h"

namespace sportsim::swing {

enum class Interpolation {
  kPiecewiseConstant,  ///< knot i's value holds on [t_i, t_{i+1}); the first also before t_0
  kPiecewiseLinear,    ///< linear between knots, constant before the first and after the last
};

struct TorqueKnot {
  double t_s = 0.0;        ///< time from the start of the swing (s)
  double torque_nm = 0.0;  ///< (N m)
};

struct TorqueSchedule {
  Interpolation interpolation = Interpolation::kPiecewiseConstant;
  std::vector<TorqueKnot> knots;  ///< 1 to kMaxKnots knots, times >= 0 and strictly increasing
};

/// Q_alpha and Q_beta at one instant (N m).
struct Torques {
  double q_alpha = 0.0;
  double q_beta = 0.0;
};

/// A validated pair of schedules, split into segments between consecutive breakpoints. On each
/// segment both torques are affine in t.
class TorqueProgram {
 public:
  static constexpr int kMaxKnots = 64;
  static constexpr double kMaxTorqueNm = 1e5;  ///< a sanity bound; realism limits live elsewhere
  /// Knot times closer than this (s) to each other (across the two schedules) or to t = 0 make
  /// one breakpoint: no integrator should take a 1e-16 s step to honour a rounding difference.
  static constexpr double kMergeS = 1e-12;

  /// Validates the schedules: 1..kMaxKnots knots each, finite times in [0, 1e3] s, strictly
  /// increasing, finite torques with |Q| <= kMaxTorqueNm.
  static absl::StatusOr<TorqueProgram> Create(const TorqueSchedule& q_alpha,
                                              const TorqueSchedule& q_beta);

  /// The chapter's program: Q_alpha = 100 N m throughout; Q_beta = -10 N m until 0.1 s, then 0.
  static TorqueProgram Chapter();
  /// Constant torques, no breakpoints.
  static TorqueProgram Constant(double q_alpha_nm, double q_beta_nm);

  /// Breakpoints in increasing order (every knot time > 0 of either schedule, deduplicated).
  const std::vector<double>& breakpoints() const { return breakpoints_; }
  int num_segments() const { return static_cast<int>(segments_.size()); }

  /// Torques at time t on segment `segment` (0 = before the first breakpoint). The segment, not
  /// t, decides the piece: at a breakpoint the left segment gives the left limit.
  Torques At(int segment, double t) const {
    const Segment& s = segments_[static_cast<size_t>(segment)];
    const double dt = t - s.t0;
    return {s.qa0 + s.qa_slope * dt, s.qb0 + s.qb_slope * dt};
  }

  /// The segment containing time t (right-continuous: a breakpoint belongs to the segment after
  /// it). For callers that start at an arbitrary time; steppers track the segment themselves.
  int SegmentAt(double t) const;

  const TorqueSchedule& q_alpha() const { return q_alpha_; }
  const TorqueSchedule& q_beta() const { return q_beta_; }

 private:
  struct Segment {
    double t0;        // segment start (s)
    double qa0, qa_slope;
    double qb0, qb_slope;
  };
  TorqueProgram() = default;
  void Build();

  TorqueSchedule q_alpha_, q_beta_;
  std::vector<double> breakpoints_;
  std::vector<Segment> segments_;
};

}  // namespace sportsim::swing

#endif  // SPORTSIM_SIM_SWING_TORQUE_PROGRAM_H_
