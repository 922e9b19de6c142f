#include "server/swing/golf_shot.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
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

// "sportsim_links, practice, range".
std::string CourseNames() {
  std::string out;
  for (std::string_view n : golf::BuiltinCourseNames()) {
    out += out.empty() ? "" : ", ";
    out += n;
  }
  return out;
}

// A course's part of the request: the course, its hole, the start (a tee or a point in play).
absl::Status CourseFromProto(const v1::SimulateGolfShotRequest& r, GolfShotJob* job) {
  absl::StatusOr<std::shared_ptr<const golf::Course>> found = golf::BuiltinCourse(r.course());
  if (!found.ok()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "course must be one of %s; got %s",
        CourseNames(), Quote(r.course())));
  }
  const golf::Course& c = **found;
  job->course = *found;
  if (r.has_stimp_ft() || r.slope_pct() != 0 || r.slope_toward_deg() != 0 || !r.fairway().empty()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "stimp_ft, slope_pct, slope_toward_deg, fairway: %s sets its greens' speeds, its slopes "
        "and its fairways' firmness (they set the practice green and the range)", c.name));
  }
  job->hole_number = r.hole() == 0 ? 1 : static_cast<int>(std::min<uint32_t>(r.hole(), 1000));
  const golf::CourseHole* hole = c.Hole(job->hole_number);
  if (hole == nullptr) {
    return absl::InvalidArgumentError(
        absl::StrFormat("hole: %u is not a hole of %s (1 to %d)", r.hole(), c.name, c.holes.size()));
  }
  if (!r.tee().empty() && (r.has_from_x_m() || r.has_from_y_m())) {
    return absl::InvalidArgumentError("tee: give a tee or from_x_m, from_y_m, not both");
  }
  const golf::CourseTee* tee = &hole->tees.front();
  if (!r.tee().empty()) {
    tee = nullptr;
    std::vector<std::string> names;
    for (const golf::CourseTee& t : hole->tees) {
      if (t.name == r.tee()) tee = &t;
      names.push_back(t.name);
    }
    if (tee == nullptr) {
      return absl::InvalidArgumentError(absl::StrFormat("tee: %s is not a tee of hole %d (%s)",
                                                        Quote(r.tee()), job->hole_number,
                                                        absl::StrJoin(names, ", ")));
    }
  }
  job->from_x_m = r.has_from_x_m() ? r.from_x_m() : tee->position_m.x();
  job->from_y_m = r.has_from_y_m() ? r.from_y_m() : tee->position_m.y();
  if (absl::Status s = Field("from_x_m", job->from_x_m, -kMaxFrom * 100, kMaxFrom * 100); !s.ok()) {
    return s;
  }
  if (absl::Status s = Field("from_y_m", job->from_y_m, -kMaxFrom * 100, kMaxFrom * 100); !s.ok()) {
    return s;
  }
  const golf::Terrain lie = c.LieAt(job->from_x_m, job->from_y_m, golf::BallSpec{}.radius_m());
  if (lie == golf::Terrain::kOutOfBounds) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "from_x_m, from_y_m: (%g, %g) is out of bounds on %s", job->from_x_m, job->from_y_m, c.name));
  }
  const Eigen::Vector2d pin = *hole->pin_m;
  if (std::hypot(job->from_x_m - pin.x(), job->from_y_m - pin.y()) <= 0.5 * job->hole.diameter_m) {
    return absl::InvalidArgumentError("from_x_m, from_y_m: the ball would start in the hole");
  }
  job->ground = golf::CourseGroundOptions();  // effects and samples are set below
  job->has_hole = true;
  job->hole.x_m = pin.x();
  job->hole.y_m = pin.y();
  if (r.flagstick()) job->hole.flagstick_diameter_m = golf::kFlagstickDiameter;
  job->air_given = r.has_atmosphere();
  job->wind_given = r.has_wind();
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<GolfShotJob> GolfShotJobFromProto(const v1::SimulateGolfShotRequest& r) {
  GolfShotJob job;
  const std::string& course = r.course();
  const bool practice = course.empty() || course == "practice";
  if (!practice && course != "range") {
    if (absl::Status s = CourseFromProto(r, &job); !s.ok()) return s;
  } else if (r.hole() != 0 || !r.tee().empty()) {
    return absl::InvalidArgumentError(
        "hole, tee: practice and range have no holes or tees (a course of ListCourses has)");
  }
  if (job.course) {
    // Set above.
  } else if (practice) {
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
  if (!job.course) {
    job.from_x_m = r.has_from_x_m() ? r.from_x_m() : (practice ? kPracticeFromX : 0.0);
    job.from_y_m = r.has_from_y_m() ? r.from_y_m() : 0.0;
    if (absl::Status s = Field("from_x_m", job.from_x_m, -kMaxFrom, kMaxFrom); !s.ok()) return s;
    if (absl::Status s = Field("from_y_m", job.from_y_m, -kMaxFrom, kMaxFrom); !s.ok()) return s;
    if (job.has_hole && std::hypot(job.from_x_m, job.from_y_m) <= 0.5 * job.hole.diameter_m) {
      return absl::InvalidArgumentError("from_x_m, from_y_m: the ball would start in the hole");
    }
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

namespace {

// The ground's own field names are the sim's; say which request fields they come from.
absl::Status FromTheGround(const absl::Status& s) {
  if (s.code() != absl::StatusCode::kInvalidArgument) return s;
  return absl::InvalidArgumentError(
      absl::StrFormat("%s (the shot as it reaches the ground)", s.message()));
}

// The ground phase into the response: its path samples and events, the totals from `from`
// along the aim (lateral + right: the aim turned a quarter clockwise), the rest.
v1::GolfRest* GroundToProto(const golf::GroundResult& g, const Vector3d& from, double aim_deg,
                            const std::string& surface, v1::SimulateGolfShotResponse* out) {
  for (const golf::GroundSample& s : g.samples) AddPoint(s.t_s, s.position_m, out);
  for (const golf::GroundEvent& e : g.events) GroundEventToProto(e, out->add_events());
  const Vector3d d = g.rest_m - from;
  const double aim = aim_deg * kDeg;
  out->set_total_m(std::hypot(d.x(), d.y()));
  out->set_lateral_m(d.x() * std::sin(aim) - d.y() * std::cos(aim));
  out->set_t_rest_s(g.t_rest_s);
  out->set_bounces(static_cast<uint32_t>(g.bounces));
  v1::GolfRest* rest = out->mutable_rest();
  GroundRestToProto(g, surface, rest);
  return rest;
}

// A shot on a course (PlayCourseShot) into the response.
absl::Status RunCourseShot(const GolfShotJob& job, const std::function<bool()>& cancelled,
                           v1::SimulateGolfShotResponse* out) {
  golf::CourseShot shot;
  shot.hole = job.hole_number;
  shot.from_m = Eigen::Vector2d(job.from_x_m, job.from_y_m);
  shot.aim_deg = job.aim_deg;
  shot.hole_spec = job.hole;
  shot.ground = job.ground;
  shot.ground.cancelled = cancelled;
  switch (job.kind) {
    case GolfShotJob::Kind::kLaunch:
      shot.kind = golf::CourseShot::Kind::kLaunch;
      shot.launch = job.flight->launch;
      shot.ball = job.flight->ball;
      shot.flight = job.flight->options;
      shot.flight.cancelled = cancelled;
      if (job.air_given) shot.air = job.flight->atmosphere;
      if (job.wind_given) shot.wind = job.flight->wind;
      break;
    case GolfShotJob::Kind::kPutt:
    case GolfShotJob::Kind::kRoll:
      shot.kind = job.kind == GolfShotJob::Kind::kPutt ? golf::CourseShot::Kind::kPutt
                                                       : golf::CourseShot::Kind::kRoll;
      shot.speed_mps = job.stroke_speed_mps;
      break;
  }
  absl::StatusOr<golf::CourseShotResult> played = golf::PlayCourseShot(*job.course, shot);
  if (!played.ok()) return FromTheGround(played.status());
  golf::CourseShotResult& p = *played;
  if (p.flight) {
    FlightResultToProto(*p.flight, 0.0, out->mutable_flight());
    out->mutable_flight()->clear_samples();
    out->set_carry_m(p.flight->carry_m);
  }
  p.ground.samples = std::move(p.path);  // the whole path, air then ground
  v1::GolfRest* rest = GroundToProto(p.ground, p.start_m, job.aim_deg, p.ground.rest_surface, out);
  rest->set_distance_to_pin_m(p.distance_to_pin_m);
  rest->set_lie(std::string(golf::TerrainTag(p.lie)));
  rest->set_out_of_bounds(p.ground.out_of_bounds);
  rest->set_penalty_area(p.ground.penalty_area);
  return absl::OkStatus();
}

}  // namespace

absl::Status RunGolfShot(const GolfShotJob& job, const std::function<bool()>& cancelled,
                         v1::SimulateGolfShotResponse* out) {
  if (job.course) return RunCourseShot(job, cancelled, out);
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
      AddPoint(s.t_s, from + golf::AimToCourse(Vector3d(s.x_m, s.y_m, s.z_m), job.aim_deg), out);
    }
    golf::FlightResult in_course = *f;
    in_course.landing_position_m = from + golf::AimToCourse(f->landing_position_m, job.aim_deg);
    in_course.landing_velocity_mps = golf::AimToCourse(f->landing_velocity_mps, job.aim_deg);
    in_course.spin_axis = golf::AimToCourse(f->spin_axis, job.aim_deg);
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
  if (!g.ok()) return FromTheGround(g.status());
  out->set_carry_m(carry);
  v1::GolfRest* rest = GroundToProto(*g, from, job.aim_deg, job.surface.name, out);
  if (job.has_hole) {
    rest->set_distance_to_pin_m(
        g->holed ? 0.0 : std::hypot(g->rest_m.x() - job.hole.x_m, g->rest_m.y() - job.hole.y_m));
  }
  return absl::OkStatus();
}

}  // namespace sportsim::server

namespace sportsim::server {

void CourseToProto(const golf::Course& c, int hole, bool geometry, v1::CourseInfo* out) {
  out->set_name(c.name);
  out->set_description(c.description);
  const auto [lo, hi] = std::minmax_element(c.terrain.z_m.begin(), c.terrain.z_m.end());
  out->set_min_z_m(*lo);
  out->set_max_z_m(*hi);
  out->set_wind_speed_mps(c.wind.speed_mps);
  out->set_wind_toward_deg(c.wind.toward_deg);
  for (const golf::CourseHole& h : c.holes) {
    if (hole != 0 && h.number != hole) continue;
    v1::CourseHoleInfo* o = out->add_holes();
    o->set_number(static_cast<uint32_t>(h.number));
    o->set_par(static_cast<uint32_t>(h.par));
    o->set_stroke_index(static_cast<uint32_t>(h.stroke_index));
    for (const golf::CourseTee& t : h.tees) {
      v1::CourseTee* ot = o->add_tees();
      ot->set_name(t.name);
      ot->set_x_m(t.position_m.x());
      ot->set_y_m(t.position_m.y());
      ot->set_z_m(c.terrain.HeightAt(t.position_m.x(), t.position_m.y()));
    }
    o->mutable_pin()->set_x_m(h.pin_m->x());
    o->mutable_pin()->set_y_m(h.pin_m->y());
    o->mutable_pin()->set_z_m(c.terrain.HeightAt(h.pin_m->x(), h.pin_m->y()));
    o->set_length_m(h.length_m());
    o->set_green_stimp_ft(h.green_stimp_ft);
    o->set_fairway(h.fairway);
  }
  for (golf::Terrain t : {golf::Terrain::kTee, golf::Terrain::kFairway, golf::Terrain::kFirstCut,
                          golf::Terrain::kRough, golf::Terrain::kBunker, golf::Terrain::kGreen,
                          golf::Terrain::kFringe, golf::Terrain::kCartpath}) {
    const golf::Surface s = c.Constants({t, 1});
    v1::SurfaceInfo* o = out->add_surfaces();
    o->set_name(std::string(golf::TerrainTag(t)));
    o->set_restitution_scale(s.restitution_scale);
    o->set_critical_angle_scale(s.critical_angle_scale);
    o->set_bounce_friction(s.bounce_friction);
    o->set_sliding_friction(s.sliding_friction);
    o->set_rolling_resistance(s.rolling_resistance);
    o->set_stimp_ft(s.stimp_ft());
  }
  if (!geometry) return;
  out->set_base(std::string(golf::TerrainTag(c.base)));
  for (const golf::CourseArea& a : c.areas) {
    v1::CourseArea* o = out->add_areas();
    o->set_golf(std::string(golf::TerrainTag(a.terrain)));
    o->set_hole(static_cast<uint32_t>(a.hole));
    for (const Eigen::Vector2d& p : a.polygon) {
      o->add_xy_m(p.x());
      o->add_xy_m(p.y());
    }
  }
  for (const Eigen::Vector2d& p : c.boundary) {
    out->add_boundary_xy_m(p.x());
    out->add_boundary_xy_m(p.y());
  }
  v1::CourseHeightfield* h = out->mutable_heightfield();
  h->set_x0_m(c.terrain.x0_m);
  h->set_y0_m(c.terrain.y0_m);
  h->set_spacing_m(c.terrain.spacing_m);
  h->set_columns(static_cast<uint32_t>(c.terrain.columns));
  h->set_rows(static_cast<uint32_t>(c.terrain.rows));
  h->mutable_z_m()->Reserve(static_cast<int>(c.terrain.z_m.size()));
  for (double z : c.terrain.z_m) h->add_z_m(static_cast<float>(z));
}

v1::ListCoursesResponse ListCourses() {
  v1::ListCoursesResponse out;
  for (std::string_view name : golf::BuiltinCourseNames()) {
    CourseToProto(**golf::BuiltinCourse(name), 0, false, out.add_courses());
  }
  return out;
}

absl::StatusOr<v1::CourseInfo> GetCourse(const v1::GetCourseRequest& r) {
  absl::StatusOr<std::shared_ptr<const golf::Course>> c = golf::BuiltinCourse(r.name());
  if (!c.ok()) {
    return absl::NotFoundError(absl::StrFormat("name: %s is not a course of this server (%s)",
                                               Quote(r.name()), CourseNames()));
  }
  if (r.hole() > (*c)->holes.size()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "hole: %u is not a hole of %s (1 to %d, or 0: all)", r.hole(), (*c)->name,
        (*c)->holes.size()));
  }
  v1::CourseInfo out;
  CourseToProto(**c, static_cast<int>(r.hole()), r.geometry(), &out);
  return out;
}

}  // namespace sportsim::server
