// SimulateGolfShot: a request -> a validated job (the course, the ball's start, the shot), and
// the job run to rest (flight, then the ground phase) into the response. Pure translation and
// orchestration over sim/golf, tested without a network.
#ifndef SPORTSIM_SERVER_SWING_GOLF_SHOT_H_
#define SPORTSIM_SERVER_SWING_GOLF_SHOT_H_

#include <functional>
#include <memory>
#include <optional>

#include "absl/status/statusor.h"
#include "server/swing/convert.h"
#include "sim/golf/course.h"
#include "sim/golf/course_shot.h"
#include "sim/golf/ground.h"
#include "sim/golf/surface.h"
#include "sportsim/v1/swing.pb.h"

namespace sportsim::server {

struct GolfShotJob {
  enum class Kind { kLaunch, kPutt, kRoll };
  Kind kind = Kind::kPutt;
  golf::Surface surface;
  golf::GroundPlane plane;
  golf::Hole hole;
  bool has_hole = false;       // practice: the hole at the origin
  double from_x_m = 0.0, from_y_m = 0.0;
  double aim_deg = 0.0;        // a launch's target line; a stroke's own heading otherwise
  std::optional<FlightJob> flight;  // kLaunch
  double stroke_speed_mps = 0.0;    // kPutt, kRoll
  golf::GroundOptions ground;
  // A course (not practice or range): the shot played there (PlayCourseShot) on `hole`.
  std::shared_ptr<const golf::Course> course;
  int hole_number = 1;
  bool air_given = false, wind_given = false;  // else the course's
};

/// Validates the request; INVALID_ARGUMENT names the request's field ("course", "stimp_ft",
/// "slope_pct", "putt.speed_mps", "launch.spin_rpm", ...).
absl::StatusOr<GolfShotJob> GolfShotJobFromProto(const v1::SimulateGolfShotRequest& request);

/// Flies (a launch) and runs the ground phase to rest, polling `cancelled`; fills everything of
/// the response but cpu_s. The simulations' own errors pass through (OutOfRange, Cancelled).
absl::Status RunGolfShot(const GolfShotJob& job, const std::function<bool()>& cancelled,
                         v1::SimulateGolfShotResponse* out);

/// A course for the wire: its holes (or only hole `hole`, 1-based; 0 all), its surfaces'
/// constants, and with `geometry` its areas, boundary and heightfield.
void CourseToProto(const golf::Course& course, int hole, bool geometry, v1::CourseInfo* out);

/// ListCourses and GetCourse over the built-in courses. GetCourse: NOT_FOUND naming the known
/// courses; INVALID_ARGUMENT for a hole the course does not have.
v1::ListCoursesResponse ListCourses();
absl::StatusOr<v1::CourseInfo> GetCourse(const v1::GetCourseRequest& request);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_SWING_GOLF_SHOT_H_
