#include "sim/billiards/cue.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "sim/billiards/cloth.h"
#include "sim/billiards/collision.h"
#include "sim/core/check.h"
#include "sim/core/units.h"

namespace sportsim::billiards {
namespace {

// Standard normal deviates by Box-Muller from a 64-bit Mersenne twister: the same numbers on
// every platform (std::normal_distribution is implementation-defined).
class Gaussian {
 public:
  explicit Gaussian(uint64_t seed) : rng_(seed) {}
  double Next() {
    const double u1 = (static_cast<double>(rng_() >> 11) + 1.0) * 0x1.0p-53;  // (0, 1]
    const double u2 = static_cast<double>(rng_() >> 11) * 0x1.0p-53;          // [0, 1)
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(kTwoPi * u2);
  }

 private:
  std::mt19937_64 rng_;
};

absl::Status CheckStrike(const TableModel& model, const CueStrike& s) {
  if (absl::Status st = CheckFiniteInRange(s.ball_speed ? "ball_speed_mps" : "speed_mps",
                                           s.speed_mps, 0, true, kMaxStrikeSpeed, false);
      !st.ok()) {
    return st;
  }
  if (absl::Status st = CheckFiniteInRange("phi_deg", RadToDeg(s.phi_rad), -360, false, 360, false);
      !st.ok()) {
    return st;
  }
  if (absl::Status st = CheckFiniteInRange("theta_deg", RadToDeg(s.theta_rad), 0, false,
                                           kMaxElevationDeg, false);
      !st.ok()) {
    return st;
  }
  if (absl::Status st = CheckFiniteInRange("a", s.a, -1, false, 1, false); !st.ok()) return st;
  if (absl::Status st = CheckFiniteInRange("b", s.b, -1, false, 1, false); !st.ok()) return st;
  if (absl::Status st = CheckFiniteInRange("noise", s.noise, 0, false, 100, false); !st.ok()) {
    return st;
  }
  const double offset = std::hypot(s.a, s.b);
  const double limit = model.params().miscue_limit;
  if (offset > limit) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "miscue: tip offset sqrt(a^2 + b^2) = %.3f R exceeds the miscue limit %.3f R", offset,
        limit));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<StrikeOutcome> ComputeStrike(const TableModel& model, uint32_t effects,
                                            const CueStrike& strike) {
  if (absl::Status s = CheckStrike(model, strike); !s.ok()) return s;
  const PhysicsParams& p = model.params();
  const double m = model.mass();
  const double radius = model.radius();
  const double inertia = model.inertia();

  StrikeOutcome out;
  CueStrike s = strike;
  if (s.noise > 0) {
    Gaussian g(s.seed);
    s.a += s.noise * kNoiseOffsetM / radius * g.Next();
    s.b += s.noise * kNoiseOffsetM / radius * g.Next();
    s.theta_rad = std::max(0.0, s.theta_rad + s.noise * DegToRad(kNoiseThetaDeg) * g.Next());
    s.phi_rad += s.noise * DegToRad(kNoisePhiDeg) * g.Next();
    s.speed_mps = std::max(1e-3, s.speed_mps + s.noise * kNoiseSpeedMps * g.Next());
    // Noise can push the tip past the miscue limit: that is a miscue, as it would be for a player.
    if (absl::Status st = CheckStrike(model, s); !st.ok()) {
      return absl::InvalidArgumentError(absl::StrFormat("with noise: %s", st.message()));
    }
  }
  out.applied = s;

  // Shooter's frame: forward f, right e_r, cue axis d (down at theta), e_up perpendicular to d.
  const Eigen::Vector3d f(std::cos(s.phi_rad), std::sin(s.phi_rad), 0.0);
  const Eigen::Vector3d right(f.y(), -f.x(), 0.0);
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  const double ct = std::cos(s.theta_rad);
  const double st = std::sin(s.theta_rad);
  const Eigen::Vector3d d = ct * f - st * z;
  const Eigen::Vector3d up = st * f + ct * z;
  const double off2 = s.a * s.a + s.b * s.b;
  const Eigen::Vector3d rc =
      radius * (s.a * right + s.b * up - std::sqrt(std::max(0.0, 1.0 - off2)) * d);
  // Impulse per unit cue speed.
  const double j_per_v0 = 2.0 / (1.0 / p.cue_mass_kg + 1.0 / m + radius * radius * off2 / inertia);
  double v0 = s.speed_mps;
  if (s.ball_speed) v0 = s.speed_mps * m / (j_per_v0 * ct);  // horizontal ball speed requested
  if (!(v0 <= 10 * kMaxStrikeSpeed)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "ball_speed_mps %g at theta %g deg needs a cue speed of %g m/s", s.speed_mps,
        RadToDeg(s.theta_rad), v0));
  }
  const double j = j_per_v0 * v0;
  out.cue_speed_mps = v0;
  out.v = (j / m) * d;
  out.v.z() = 0.0;
  out.w = (j / inertia) * rc.cross(d);
  if ((effects & kEffectDisableSquirt) == 0 && s.a != 0.0) {
    const double a = s.a;
    const double alpha = std::atan(2.5 * a * std::sqrt(1.0 - a * a) /
                                   (1.0 + m / p.cue_end_mass_kg + 2.5 * (1.0 - a * a)));
    const double c = std::cos(alpha), sn = std::sin(alpha);
    out.v = Eigen::Vector3d(c * out.v.x() - sn * out.v.y(), sn * out.v.x() + c * out.v.y(), 0.0);
    out.squirt_rad = alpha;
  }
  return out;
}

bool InPocketMouth(const TableModel& model, const Eigen::Vector2d& xy) {
  // Clear of every cushion and jaw by the contact distance the engine keeps (a ball at rest
  // against a jaw is that far from its nose line, less than a radius), to the engine's
  // penetration tolerance.
  const auto near_pocket = [&](const Pocket& pocket) {
    return (xy - pocket.centre).norm() <= pocket.radius_m + 2.0 * model.radius();
  };
  const std::vector<Pocket>& pockets = model.spec().pockets;
  if (std::none_of(pockets.begin(), pockets.end(), near_pocket)) return false;
  const double clear = model.cushion_contact_distance() - 1e-6;
  const std::vector<CushionSegment>& cushions = model.spec().cushions;
  for (const CushionSegment& c : cushions) {
    if ((xy - ClosestOnSegment(c.a, c.b, xy)).norm() < clear) return false;
  }
  const auto cross = [](const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
    return u.x() * v.y() - u.y() * v.x();
  };
  for (const Pocket& pocket : pockets) {
    if (!near_pocket(pocket)) continue;
    // Between the jaws: on the pocket's side of both jaw lines (not behind a jaw, inside the
    // rail).
    int inside = 0;
    for (const char* end : {"_a", "_b"}) {
      const std::string name = "jaw_" + pocket.name + end;
      for (const CushionSegment& c : cushions) {
        if (c.name != name) continue;
        const Eigen::Vector2d e = c.b - c.a;
        inside += cross(e, xy - c.a) * cross(e, pocket.centre - c.a) > 0.0;
      }
    }
    if (inside == 2) return true;
  }
  return false;
}

absl::Status ValidateLayout(const TableModel& model, const TableState& state) {
  const double radius = model.radius();
  const size_t n = state.balls.size();
  for (size_t i = 0; i < n; ++i) {
    const Ball& b = state.balls[i];
    if (b.id.empty() || b.id.size() > 32) {
      return absl::InvalidArgumentError(
          absl::StrFormat("ball %d: id must be 1 to 32 characters", static_cast<int>(i)));
    }
    // A scan of the ids before it: tables hold a few dozen balls, and this runs for every
    // shot of a batch (a set of strings cost more than the rest of the check).
    for (size_t k = 0; k < i; ++k) {
      if (state.balls[k].id == b.id) {
        return absl::InvalidArgumentError(absl::StrFormat("ball id \"%s\" appears twice", b.id));
      }
    }
    if (!b.r.allFinite() || !b.v.allFinite() || !b.w.allFinite() || !b.q.coeffs().allFinite()) {
      return absl::InvalidArgumentError(
          absl::StrFormat("ball %s: position, velocity and spin must be finite", b.id));
    }
    if (b.state == MotionState::kPocketed) continue;
    if (model.spec().bounded) {
      const double lim_x = 0.5 * model.spec().length_m - model.cushion_contact_distance();
      const double lim_y = 0.5 * model.spec().width_m - model.cushion_contact_distance();
      // A ball may also rest in a pocket's mouth, between the jaws, beyond the rail lines.
      if ((std::abs(b.r.x()) > lim_x + 1e-9 || std::abs(b.r.y()) > lim_y + 1e-9) &&
          !InPocketMouth(model, b.r.head<2>())) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "ball %s at (%g, %g) m is not on the cloth: |x| <= %g, |y| <= %g m", b.id, b.r.x(),
            b.r.y(), lim_x, lim_y));
      }
    } else if (b.r.head<2>().norm() > 1e4) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "ball %s at (%g, %g) m: positions must be within 10 km of the origin", b.id, b.r.x(),
          b.r.y()));
    }
  }
  for (size_t i = 0; i < n; ++i) {
    if (state.balls[i].state == MotionState::kPocketed) continue;
    for (size_t j = i + 1; j < n; ++j) {
      if (state.balls[j].state == MotionState::kPocketed) continue;
      const double d = (state.balls[i].r - state.balls[j].r).head<2>().norm();
      if (d < 2.0 * radius - 1e-6) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "balls %s and %s overlap: centres %.6f m apart, less than a diameter %.6f m",
            state.balls[i].id, state.balls[j].id, d, 2.0 * radius));
      }
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<StrikeOutcome> ApplyStrike(const TableModel& model, uint32_t effects,
                                          const CueStrike& strike, int cue, TableState* state) {
  if (cue < 0 || cue >= static_cast<int>(state->balls.size())) {
    return absl::InvalidArgumentError("no cue ball (id \"cue\") on the table");
  }
  const Ball& ball = state->balls[cue];
  if (ball.state == MotionState::kPocketed) {
    return absl::InvalidArgumentError(
        absl::StrFormat("the cue ball %s is pocketed: place it on the cloth first", ball.id));
  }
  if (absl::Status s = ValidateLayout(model, *state); !s.ok()) return s;
  if (!state->AtRest()) {
    return absl::FailedPreconditionError("balls are still moving");
  }
  absl::StatusOr<StrikeOutcome> out = ComputeStrike(model, effects, strike);
  if (!out.ok()) return out.status();
  Ball& b = state->balls[cue];
  b.v = out->v;
  b.w = out->w;
  b.state = Classify(model, b);
  return out;
}

}  // namespace sportsim::billiards
