#include "sim/golf/course_shot.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "sim/core/check.h"
#include "sim/core/ode/hermite.h"

namespace sportsim::golf {

namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kFlightSample = 5e-3;     // the flight's samples for the landing search (s)
constexpr double kMaxStrokeSpeed = 15.0;  // a putt or a roll (m/s)

// A flight sample's position and velocity (flight frame).
Vector3d P(const FlightSample& s) { return Vector3d(s.x_m, s.y_m, s.z_m); }
Vector3d V(const FlightSample& s) { return Vector3d(s.vx_mps, s.vy_mps, s.vz_mps); }

// The cubic Hermite interpolant between two samples at the fraction f: position, velocity.
std::pair<Vector3d, Vector3d> Between(const FlightSample& a, const FlightSample& b, double f) {
  Vector3d p, v;
  ode::CubicHermiteRate(P(a), V(a), P(b), V(b), b.t_s - a.t_s, f, &p, &v);
  return {p, v};
}

}  // namespace

Vector3d AimToCourse(const Vector3d& v, double aim_deg) {
  const double c = std::cos(aim_deg * kDeg), s = std::sin(aim_deg * kDeg);
  return Vector3d(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z());
}

absl::StatusOr<CourseShotResult> PlayCourseShot(const Course& course, const CourseShot& shot) {
  const CourseHole* hole = course.Hole(shot.hole);
  if (hole == nullptr) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "hole: %d is not a hole of %s (1 to %d)", shot.hole, course.name, course.holes.size()));
  }
  if (absl::Status s = CheckFieldsInRange({{"from_m.x", shot.from_m.x(), -1e5, false, 1e5},
                                           {"from_m.y", shot.from_m.y(), -1e5, false, 1e5},
                                           {"aim_deg", shot.aim_deg, -1e4, false, 1e4}});
      !s.ok()) {
    return s;
  }
  if (!course.terrain.Covers(shot.from_m.x(), shot.from_m.y())) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "from_m: (%g, %g) is off %s's map", shot.from_m.x(), shot.from_m.y(), course.name));
  }
  const double radius = shot.ball.radius_m();
  CourseShotResult out;
  const double z0 = course.terrain.HeightAt(shot.from_m.x(), shot.from_m.y());
  out.start_m = Vector3d(shot.from_m.x(), shot.from_m.y(), z0);
  GroundStart start;
  if (shot.kind == CourseShot::Kind::kLaunch) {
    if (absl::Status s = ValidateLaunchConditions(shot.launch); !s.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("launch.", s.message()));
    }
    // Flown above a plane 1 m under the lowest ground, sampled finely for the landing search.
    const double low = *std::min_element(course.terrain.z_m.begin(), course.terrain.z_m.end()) - 1.0;
    FlightOptions fo = shot.flight;
    fo.launch_height_m = z0 - low;
    fo.sample_interval_s = kFlightSample;
    Wind wind;
    if (shot.wind) {
      wind = *shot.wind;
    } else {
      wind = hole->wind ? *hole->wind : course.wind;
      wind.toward_deg = std::remainder(shot.aim_deg - wind.toward_deg, 360.0);  // heading -> + right of the aim
    }
    absl::StatusOr<FlightResult> f =
        SimulateFlight(shot.ball, shot.launch, shot.air.value_or(course.air), wind, fo);
    if (!f.ok()) return f.status();
    const Vector3d base(shot.from_m.x(), shot.from_m.y(), low);
    auto course_point = [&](const Vector3d& p) { return Vector3d(base + AimToCourse(p, shot.aim_deg)); };
    // Height above the ground (negative: below), or nullopt off the map.
    auto above = [&](const Vector3d& p) -> std::optional<double> {
      const Vector3d q = course_point(p);
      if (!course.terrain.Covers(q.x(), q.y())) return std::nullopt;
      return q.z() - course.terrain.HeightAt(q.x(), q.y());
    };
    const std::vector<FlightSample>& s = f->samples;
    size_t i = 1;
    bool off_map = false;
    for (; i < s.size(); ++i) {
      const std::optional<double> h = above(P(s[i]));
      if (!h) {
        off_map = true;
        break;
      }
      if (*h <= 0.0) break;
    }
    if (i >= s.size()) i = s.size() - 1;  // the low plane: unreachable on the map
    // Bisection on the interpolant between samples i-1 and i: the first contact (or the edge).
    double lo = 0.0, hi = 1.0;
    for (int k = 0; k < 60; ++k) {
      const double mid = 0.5 * (lo + hi);
      const std::optional<double> h = above(Between(s[i - 1], s[i], mid).first);
      (!h || *h <= 0.0 ? hi : lo) = mid;
    }
    const auto [p, v] = Between(s[i - 1], s[i], hi);
    const double t = s[i - 1].t_s + hi * (s[i].t_s - s[i - 1].t_s);
    const double spin_rpm = s[i - 1].spin_rpm + hi * (s[i].spin_rpm - s[i - 1].spin_rpm);
    // The flight's summary at the terrain landing, heights above the start's ground.
    FlightResult& fr = out.flight.emplace(*f);
    fr.samples.clear();
    fr.flight_time_s = t;
    fr.carry_m = std::hypot(p.x(), p.y());
    fr.carry_downrange_m = p.x();
    fr.lateral_m = -p.y();
    fr.apex_m = 0.0;
    fr.apex_time_s = 0.0;
    for (size_t k = 0; k < i; ++k) {
      if (s[k].z_m - fo.launch_height_m > fr.apex_m) {
        fr.apex_m = s[k].z_m - fo.launch_height_m;
        fr.apex_time_s = s[k].t_s;
      }
    }
    fr.landing_position_m = Vector3d(p.x(), p.y(), p.z() - fo.launch_height_m);
    fr.landing_velocity_mps = v;
    fr.landing_speed_mps = v.norm();
    fr.landing_angle_deg = std::atan2(-v.z(), std::hypot(v.x(), v.y())) / kDeg;
    fr.landing_spin_rpm = spin_rpm;
    // The path in the air at the ground's sample spacing (its lowest point: the centre is
    // flown as the flight's z, which starts on the ground), then the landing.
    const double every = shot.ground.sample_interval_s;
    if (every > 0.0) {
      double next = 0.0;
      for (size_t k = 0; k < i; ++k) {
        if (s[k].t_s + 1e-9 < next) continue;
        out.path.push_back(GroundSample{s[k].t_s, course_point(P(s[k])), s[k].speed_mps});
        next += every;
      }
    }
    out.landing_m = course_point(p);
    start.kind = GroundStartKind::kLanding;
    start.position_m = out.landing_m;
    start.velocity_mps = AimToCourse(v, shot.aim_deg);
    start.spin_radps = spin_rpm * kRpmToRadPerS * AimToCourse(f->spin_axis, shot.aim_deg);
    start.time_s = t;
    if (off_map && !course.terrain.Covers(out.landing_m.x(), out.landing_m.y())) {
      // Left the map in the air: out of bounds where it left.
      GroundResult& g = out.ground;
      g.rest_m = out.landing_m;
      g.t_rest_s = t;
      g.out_of_bounds = true;
      g.rest_surface = std::string(TerrainTag(Terrain::kOutOfBounds));
      for (GroundEventKind kind : {GroundEventKind::kOutOfBounds, GroundEventKind::kRest}) {
        g.events.push_back(GroundEvent{.t_s = t, .kind = kind, .position_m = out.landing_m,
                                       .velocity_mps = Vector3d::Zero(),
                                       .surface = g.rest_surface});
      }
      out.lie = Terrain::kOutOfBounds;
      out.distance_to_pin_m = (out.landing_m.head<2>() - *hole->pin_m).norm();
      return out;
    }
  } else {
    if (absl::Status s = CheckFiniteInRange("speed_mps", shot.speed_mps, 0, false,
                                            kMaxStrokeSpeed, false);
        !s.ok()) {
      return s;
    }
    start = shot.kind == CourseShot::Kind::kPutt
                ? PuttStart(shot.from_m.x(), shot.from_m.y(), shot.speed_mps, shot.aim_deg)
                : RollingStart(shot.from_m.x(), shot.from_m.y(), shot.speed_mps, shot.aim_deg);
  }
  absl::StatusOr<GroundResult> g =
      SimulateGroundOnCourse(shot.ball, course, shot.hole, shot.hole_spec, start, shot.ground);
  if (!g.ok()) return g.status();
  out.ground = *std::move(g);
  out.path.insert(out.path.end(), out.ground.samples.begin(), out.ground.samples.end());
  out.ground.samples.clear();
  const Vector3d& r = out.ground.rest_m;
  out.lie = out.ground.holed ? Terrain::kGreen
            : out.ground.penalty_area
                ? *TerrainFromTag(out.ground.rest_surface)
                : course.LieAt(r.x(), r.y(), radius);
  out.distance_to_pin_m = out.ground.holed ? 0.0 : (r.head<2>() - *hole->pin_m).norm();
  return out;
}

}  // namespace sportsim::golf
