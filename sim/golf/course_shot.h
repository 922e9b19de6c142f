// A shot on a course, launch to rest: a launch flown over the terrain (it lands where it first
// meets the ground, on an elevated green or down a hill, not on the plane of its start), or a
// putt or a rolled ball; then the ground phase on the course (ground.h) to rest, into the
// hole, into water or out of bounds. The same code serves a single shot and a round's stroke.
//
// Frames: the course's (x east, y north, z up; headings ccw from +x). A launch's conditions
// are relative to its aim (launch_direction_deg and spin axis + to the right, as launch
// monitors report them); the flight's own result is in its frame (x along the aim, y left, z
// up from the start's ground height).
//
// The flight over terrain: the ball is flown (ball_flight.h, the given options) above a plane
// under the whole course, sampled every 5 ms, and its landing is the first point where the
// ball reaches the terrain: the first sample at or below the ground, then bisection on the
// cubic Hermite interpolant of the two samples around it (positions and velocities: exact for
// the step's polynomial to well under a millimetre). The landing's velocity is the
// interpolant's, its spin the samples' interpolated rate about the flight's spin axis. A ball
// that leaves the map in the air is out of bounds where it left.
#ifndef SPORTSIM_SIM_GOLF_COURSE_SHOT_H_
#define SPORTSIM_SIM_GOLF_COURSE_SHOT_H_

#include <functional>
#include <optional>
#include <vector>

#include <Eigen/Dense>

#include "absl/status/statusor.h"
#include "sim/golf/ball_flight.h"
#include "sim/golf/course.h"
#include "sim/golf/ground.h"

namespace sportsim::golf {

struct CourseShot {
  enum class Kind { kLaunch, kPutt, kRoll };
  Kind kind = Kind::kLaunch;
  int hole = 1;  ///< the hole being played (its pin)
  Eigen::Vector2d from_m = Eigen::Vector2d::Zero();
  /// A launch's target line, or a putt's or a roll's heading (deg, ccw from +x).
  double aim_deg = 0.0;
  LaunchConditions launch;    ///< kLaunch
  double speed_mps = 0.0;     ///< kPutt, kRoll: [0, 15]
  BallSpec ball;
  /// The air and the wind: the course's (the hole's wind if it has one) unless given here.
  std::optional<Atmosphere> air;
  /// Relative to the aim as in a single flight (toward_deg: 0 tailwind, 90 left to right).
  std::optional<Wind> wind;
  FlightOptions flight;  ///< its launch_height_m and sample_interval_s are set here
  Hole hole_spec;        ///< the hole's size and flagstick (its x_m, y_m: the pin's)
  /// Its sample_interval_s also spaces the flight's path points. Default: dp45 at 1e-8 m.
  GroundOptions ground = CourseGroundOptions();
};

struct CourseShotResult {
  /// A launch's flight in its own frame, ended at the terrain landing: carry, lateral, apex
  /// (above the start's ground), flight time and the landing's speed, angle and spin are the
  /// terrain landing's. Its samples are dropped.
  std::optional<FlightResult> flight;
  Eigen::Vector3d start_m = Eigen::Vector3d::Zero();    ///< on the ground (course frame)
  Eigen::Vector3d landing_m = Eigen::Vector3d::Zero();  ///< a launch's first contact
  /// The flight's path points (course frame, the ball's lowest point) every
  /// ground.sample_interval_s, then the ground's own samples.
  std::vector<GroundSample> path;
  GroundResult ground;
  Terrain lie = Terrain::kRough;  ///< the Rules' lie at rest (Course::LieAt)
  double distance_to_pin_m = 0.0;  ///< 0 when holed
};

/// A vector of a flight's frame (x along the aim, y left, z up) in the course frame, the aim a
/// heading (deg, ccw from +x).
Eigen::Vector3d AimToCourse(const Eigen::Vector3d& v, double aim_deg);

/// Plays the shot. InvalidArgument names the bad field (hole, from_m, speed_mps, launch.*,
/// and the flight's and the ground's own); OutOfRange and Cancelled from the simulations.
absl::StatusOr<CourseShotResult> PlayCourseShot(const Course& course, const CourseShot& shot);

}  // namespace sportsim::golf

#endif  // SPORTSIM_SIM_GOLF_COURSE_SHOT_H_
