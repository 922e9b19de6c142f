#include "server/swing/golf_shot.h"

#include <cmath>
#include <numbers>
#include <string>

#include "absl/strings/str_format.h"
#include "server/world/world.h"
#include "sim/core/check.h"

namespace sportsim::server {

namespace {

using Eigen::Vector3d;

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kMaxStrokeSpeed = 15.0;  // m/s: a putt or a roll, not a drive along the turf
constexpr double kMaxFrom = 1000.0;       // m
// Practice's default start: a 10 m putt toward the hole at the origin.
constexpr double kPracticeFromX = -10.0;

// The course's rotation of a flight-frame vector (x along the aim, y left) by the aim heading.
Vector3d ToCourse(const Vector3d& v, double aim_deg) {
  const double c = std::cos(aim_deg * kDeg), s = std::sin(aim_deg * kDeg);
  return Vector3d(c * v.x() - s * v.y(), s * v.x() + c * v.y(), v.z());
}

absl::Status Field(std::string_view name, double value, double lo, double hi) {
  return CheckFiniteInRange(name, value, lo, false, hi, false);
}

void AddPoint(double t, const Vector3d& p, v1::SimulateGolfShotResponse* out) {
  v1::GolfPathPoint* q = out->add_path();
  q->set_t_s(t);
  q->set_x_m(p.x());
  q->set_y_m(p.y());
  q->set_z_m(p.z());
}

}  // namespace

absl::StatusOr<GolfShotJob> GolfShotJobFromProto(const v1::SimulateGolfShotRequest& r) {
  GolfShotJob job;
  const std::string& course = r.course();
  const bool practice = course.empty() || course == "practice";
  if (!practice && course != "range") {
    return absl::InvalidArgumentError(absl::StrFormat(
        "course must be practice or range; got %s", Quote(course)));
  }
  if (practice) {
    absl::StatusOr<golf::Surface> green = golf::GreenOfStimp(r.has_stimp_ft() ? r.stimp_ft() : 10);
    if (!green.ok()) return green.status();  // names stimp_ft
    job.surface = *green;
    if (absl::Status s = Field("slope_pct", r.slope_pct(), 0, 20); !s.ok()) return s;
    if (absl::Status s = Field("slope_toward_deg", r.slope_toward_deg(), -360, 360); !s.ok()) {
      return s;
    }
    job.plane = {.slope_pct = r.slope_pct(), .slope_toward_deg = r.slope_toward_deg()};
    if (!r.no_slope()) {
      if (absl::Status s = golf::CheckSlopeHolds(job.plane, job.surface); !s.ok()) return s;
    }
    job.has_hole = true;
    if (r.flagstick()) job.hole.flagstick_diameter_m = golf::kFlagstickDiameter;
    if (!r.fairway().empty()) {
      return absl::InvalidArgumentError("fairway: the practice course is a green (course range "
                                        "has a fairway)");
    }
  } else {
    if (r.has_stimp_ft() || r.slope_pct() != 0 || r.slope_toward_deg() != 0 || r.flagstick()) {
      return absl::InvalidArgumentError(
          "stimp_ft, slope_pct, slope_toward_deg, flagstick: the range is a flat fairway "
          "without a hole (they set the practice green)");
    }
    absl::StatusOr<std::optional<golf::Surface>> fairway =
        FairwayFromProto("fairway", r.fairway().empty() ? "normal" : r.fairway());
    if (!fairway.ok()) return fairway.status();
    job.surface = **fairway;
  }
  job.from_x_m = r.has_from_x_m() ? r.from_x_m() : (practice ? kPracticeFromX : 0.0);
  job.from_y_m = r.has_from_y_m() ? r.from_y_m() : 0.0;
  if (absl::Status s = Field("from_x_m", job.from_x_m, -kMaxFrom, kMaxFrom); !s.ok()) return s;
  if (absl::Status s = Field("from_y_m", job.from_y_m, -kMaxFrom, kMaxFrom); !s.ok()) return s;
  if (job.has_hole && std::hypot(job.from_x_m, job.from_y_m) <= 0.5 * job.hole.diameter_m) {
    return absl::InvalidArgumentError("from_x_m, from_y_m: the ball would start in the hole");
  }
  if (r.has_aim_deg()) {
    if (absl::Status s = Field("aim_deg", r.aim_deg(), -360, 360); !s.ok()) return s;
    job.aim_deg = r.aim_deg();
  } else if (job.has_hole) {
    job.aim_deg = std::atan2(job.hole.y_m - job.from_y_m, job.hole.x_m - job.from_x_m) / kDeg;
  }
  job.ground.hole = job.has_hole;
  if (r.no_spin()) job.ground.effects |= golf::kGroundDisableSpin;
  if (r.no_slope()) job.ground.effects |= golf::kGroundDisableSlope;
  if (r.has_sample_interval_s()) {
    if (absl::Status s = Field("sample_interval_s", r.sample_interval_s(), 1e-3, 10); !s.ok()) {
      return s;
    }
    job.ground.sample_interval_s = r.sample_interval_s();
  }
  switch (r.shot_case()) {
    case v1::SimulateGolfShotRequest::kLaunch: {
      job.kind = GolfShotJob::Kind::kLaunch;
      v1::SimulateFlightRequest flight;
      *flight.mutable_launch() = r.launch();
      *flight.mutable_atmosphere() = r.atmosphere();
      *flight.mutable_wind() = r.wind();
      flight.set_sample_interval_s(job.ground.sample_interval_s);
      absl::StatusOr<FlightJob> fj = FlightJobFromProto(flight);
      if (!fj.ok()) return fj.status();  // names launch.*, atmosphere.*, wind
      job.flight = *std::move(fj);
      break;
    }
    case v1::SimulateGolfShotRequest::kPutt:
    case v1::SimulateGolfShotRequest::kRoll: {
      const bool putt = r.shot_case() == v1::SimulateGolfShotRequest::kPutt;
      const v1::GroundStroke& st = putt ? r.putt() : r.roll();
      const std::string prefix = putt ? "putt." : "roll.";
      if (absl::Status s = Field(prefix + "speed_mps", st.speed_mps(), 0, kMaxStrokeSpeed);
          !s.ok()) {
        return s;
      }
      if (absl::Status s = Field(prefix + "direction_deg", st.direction_deg(), -360, 360);
          !s.ok()) {
        return s;
      }
      if (r.has_aim_deg()) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "aim_deg: a %s goes where %sdirection_deg points (aim_deg is a launch's)",
            putt ? "putt" : "roll", prefix));
      }
      if (r.has_atmosphere() || r.has_wind()) {
        return absl::InvalidArgumentError(
            "atmosphere, wind: a ball on the ground is not flown (they apply to a launch)");
      }
      job.kind = putt ? GolfShotJob::Kind::kPutt : GolfShotJob::Kind::kRoll;
      job.stroke_speed_mps = st.speed_mps();
      job.aim_deg = st.direction_deg();
      break;
    }
    default:
      return absl::InvalidArgumentError("shot: give one of launch, putt or roll");
  }
  return job;
}

absl::Status RunGolfShot(const GolfShotJob& job, const std::function<bool()>& cancelled,
                         v1::SimulateGolfShotResponse* out) {
  const Vector3d from(job.from_x_m, job.from_y_m, job.plane.HeightAt(job.from_x_m, job.from_y_m));
  golf::GroundOptions ground = job.ground;
  ground.cancelled = cancelled;
  golf::GroundStart start;
  double carry = 0.0;
  if (job.kind == GolfShotJob::Kind::kLaunch) {
    FlightJob flight = *job.flight;
    flight.options.cancelled = cancelled;
    absl::StatusOr<golf::FlightResult> f = golf::SimulateFlight(
        flight.ball, flight.launch, flight.atmosphere, flight.wind, flight.options);
    if (!f.ok()) return f.status();
    carry = f->carry_m;
    // The path in the air, in the course frame (the flight lands at the start's height: the
    // ground phase takes its contact point on the plane under the landing point).
    for (const golf::FlightSample& s : f->samples) {
      AddPoint(s.t_s, from + ToCourse(Vector3d(s.x_m, s.y_m, s.z_m), job.aim_deg), out);
    }
    golf::FlightResult in_course = *f;
    in_course.landing_position_m = from + ToCourse(f->landing_position_m, job.aim_deg);
    in_course.landing_velocity_mps = ToCourse(f->landing_velocity_mps, job.aim_deg);
    in_course.spin_axis = ToCourse(f->spin_axis, job.aim_deg);
    start = golf::LandingFromFlight(in_course);
    FlightResultToProto(*f, 0.0, out->mutable_flight());
    out->mutable_flight()->clear_samples();
    if (!out->path().empty()) out->mutable_path()->RemoveLast();  // the landing: the ground's
  } else {
    start = job.kind == GolfShotJob::Kind::kPutt
                ? golf::PuttStart(job.from_x_m, job.from_y_m, job.stroke_speed_mps, job.aim_deg)
                : golf::RollingStart(job.from_x_m, job.from_y_m, job.stroke_speed_mps,
                                     job.aim_deg);
  }
  absl::StatusOr<golf::GroundResult> g =
      golf::SimulateGround(golf::BallSpec{}, job.surface, job.plane, job.hole, start, ground);
  if (!g.ok()) {
    // The ground's own field names are the sim's; say which request fields they come from.
    if (g.status().code() == absl::StatusCode::kInvalidArgument) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s (the shot as it reaches the ground)", g.status().message()));
    }
    return g.status();
  }
  for (const golf::GroundSample& s : g->samples) AddPoint(s.t_s, s.position_m, out);
  for (const golf::GroundEvent& e : g->events) GroundEventToProto(e, out->add_events());
  const Vector3d d = g->rest_m - from;
  const double aim = job.aim_deg * kDeg;
  out->set_carry_m(carry);
  out->set_total_m(std::hypot(d.x(), d.y()));
  // + right of the aim line: the aim turned a quarter clockwise.
  out->set_lateral_m(d.x() * std::sin(aim) - d.y() * std::cos(aim));
  out->set_t_rest_s(g->t_rest_s);
  out->set_bounces(static_cast<uint32_t>(g->bounces));
  v1::GolfRest* rest = out->mutable_rest();
  GroundRestToProto(*g, job.surface.name, rest);
  if (job.has_hole) {
    rest->set_distance_to_pin_m(
        g->holed ? 0.0 : std::hypot(g->rest_m.x() - job.hole.x_m, g->rest_m.y() - job.hole.y_m));
  }
  return absl::OkStatus();
}

}  // namespace sportsim::server
