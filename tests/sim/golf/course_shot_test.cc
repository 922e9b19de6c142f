// Shots on a course, launch to rest (course_shot.h).
#include "sim/golf/course_shot.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

namespace sportsim::golf {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

const Course& Links() { return **BuiltinCourse("sportsim_links"); }

// A tour 7-iron-like launch (Trackman's tour averages: 120 mph, 16.3 deg, 7097 rpm).
LaunchConditions Iron(double speed_mps = 53.6) {
  return LaunchConditions{.ball_speed_mps = speed_mps, .launch_angle_deg = 16.3,
                          .launch_direction_deg = 0, .spin_rpm = 7097, .spin_axis_deg = 0};
}

CourseShot Launch(int hole, Eigen::Vector2d from, double aim_deg, LaunchConditions l) {
  CourseShot s;
  s.kind = CourseShot::Kind::kLaunch;
  s.hole = hole;
  s.from_m = from;
  s.aim_deg = aim_deg;
  s.launch = l;
  s.ground.sample_interval_s = 0.05;
  return s;
}

double Heading(Eigen::Vector2d from, Eigen::Vector2d to) {
  return std::atan2(to.y() - from.y(), to.x() - from.x()) / kDeg;
}

// On flat ground the terrain landing is the flight's own landing on its plane: the same carry,
// lateral and landing velocity (the 5 ms samples' interpolant against the solver's landing).
TEST(CourseShotTest, OnFlatGroundTheLandingIsTheFlightsOwn) {
  const Course& range = **BuiltinCourse("range");
  for (double direction : {-4.0, 0.0, 3.0}) {
    LaunchConditions l = Iron();
    l.launch_direction_deg = direction;
    l.spin_axis_deg = 2 * direction;
    CourseShot shot = Launch(1, {0, 0}, 10.0, l);
    shot.air = Atmosphere{};
    shot.wind = Wind{};
    auto played = PlayCourseShot(range, shot);
    ASSERT_TRUE(played.ok()) << played.status();
    auto flat = SimulateFlight(BallSpec{}, l, Atmosphere{}, Wind{}, FlightOptions{});
    ASSERT_TRUE(flat.ok());
    EXPECT_NEAR(played->flight->carry_m, flat->carry_m, 1e-3);
    EXPECT_NEAR(played->flight->lateral_m, flat->lateral_m, 1e-3);
    EXPECT_NEAR(played->flight->flight_time_s, flat->flight_time_s, 1e-4);
    EXPECT_NEAR(played->flight->landing_angle_deg, flat->landing_angle_deg, 0.01);
    EXPECT_NEAR(played->flight->apex_m, flat->apex_m, 0.01);
    // In the course frame, along the aim.
    const Eigen::Vector3d d = played->landing_m - played->start_m;
    EXPECT_NEAR(std::hypot(d.x(), d.y()), flat->carry_m, 1e-3);
    EXPECT_NEAR(played->landing_m.z(), 0.0, 1e-9);
  }
}

// Down from the first hole's raised tee the same shot carries farther than on the flat, and up
// to the third hole's raised green shorter; it lands on the terrain's height.
TEST(CourseShotTest, ElevationChangesTheCarry) {
  const Course& c = Links();
  auto flat = SimulateFlight(BallSpec{}, Iron(), c.air, Wind{}, FlightOptions{});
  ASSERT_TRUE(flat.ok());
  const Eigen::Vector2d tee1 = c.holes[0].tees[0].position_m;
  auto down = PlayCourseShot(c, Launch(1, tee1, 0.0, Iron()));
  ASSERT_TRUE(down.ok()) << down.status();
  const double drop = down->start_m.z() - down->landing_m.z();
  EXPECT_GT(drop, 2.0);
  EXPECT_GT(down->flight->carry_m, flat->carry_m + 0.5 * drop);
  EXPECT_NEAR(down->landing_m.z(),
              c.terrain.HeightAt(down->landing_m.x(), down->landing_m.y()), 1e-6);
  // Toward the third green from 150 m short of it.
  const Eigen::Vector2d pin3 = *c.holes[2].pin_m, from3(pin3.x() + 150, pin3.y());
  auto up = PlayCourseShot(c, Launch(3, from3, 180.0, Iron()));
  ASSERT_TRUE(up.ok()) << up.status();
  EXPECT_GT(up->landing_m.z() - up->start_m.z(), 0.5);
  EXPECT_LT(up->flight->carry_m, flat->carry_m);
}

// Short off the second tee: into the pond, a penalty area, the run ended at its margin.
TEST(CourseShotTest, AShortTeeShotOnTheParThreeFindsThePond) {
  const Course& c = Links();
  const CourseHole& h2 = c.holes[1];
  const Eigen::Vector2d tee = h2.tees[0].position_m;
  auto wet = PlayCourseShot(c, Launch(2, tee, Heading(tee, *h2.pin_m), Iron(33)));
  ASSERT_TRUE(wet.ok()) << wet.status();
  EXPECT_TRUE(wet->ground.penalty_area);
  EXPECT_EQ(wet->lie, Terrain::kWaterHazard);
  // Struck well it carries the pond.
  auto dry = PlayCourseShot(c, Launch(2, tee, Heading(tee, *h2.pin_m), Iron(53)));
  ASSERT_TRUE(dry.ok()) << dry.status();
  EXPECT_FALSE(dry->ground.penalty_area);
  EXPECT_GT(dry->landing_m.y(), 165.0);
}

TEST(CourseShotTest, APuttFindsTheHoleOnTheGreen) {
  const Course& c = Links();
  const Eigen::Vector2d pin = *c.holes[0].pin_m;
  CourseShot putt;
  putt.kind = CourseShot::Kind::kPutt;
  putt.hole = 1;
  putt.from_m = pin + Eigen::Vector2d(-1.5, 0.0);
  putt.aim_deg = 0.0;
  putt.speed_mps = 2.0;  // uphill (the green falls 2 % west); it skids to 5/7 of that
  auto r = PlayCourseShot(c, putt);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_TRUE(r->ground.holed);
  EXPECT_EQ(r->distance_to_pin_m, 0.0);
  putt.speed_mps = 0.5;  // short
  auto s = PlayCourseShot(c, putt);
  ASSERT_TRUE(s.ok());
  EXPECT_FALSE(s->ground.holed);
  EXPECT_EQ(s->lie, Terrain::kGreen);
  EXPECT_GT(s->distance_to_pin_m, 0.1);
}

// A drive hit off the map (north, out of bounds past the boundary) is out where it leaves.
TEST(CourseShotTest, ABallFlyingOffTheMapIsOutOfBounds) {
  const Course& c = Links();
  LaunchConditions driver{.ball_speed_mps = 74, .launch_angle_deg = 11, .spin_axis_deg = 0};
  driver.spin_rpm = 2700;
  auto r = PlayCourseShot(c, Launch(3, {200, 280}, 90.0, driver));
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_TRUE(r->ground.out_of_bounds);
  EXPECT_EQ(r->lie, Terrain::kOutOfBounds);
  EXPECT_EQ(r->ground.events.back().kind, GroundEventKind::kRest);
}

TEST(CourseShotTest, RefusesBadShotsNamingTheField) {
  const Course& c = Links();
  CourseShot s = Launch(9, {0, 0}, 0, Iron());
  EXPECT_NE(PlayCourseShot(c, s).status().message().find("hole: 9"), std::string::npos);
  s = Launch(1, {5000, 0}, 0, Iron());
  EXPECT_NE(PlayCourseShot(c, s).status().message().find("from_m"), std::string::npos);
  s = Launch(1, {0, 0}, 0, Iron(500));
  EXPECT_NE(PlayCourseShot(c, s).status().message().find("launch.ball_speed_mps"),
            std::string::npos);
  s.kind = CourseShot::Kind::kPutt;
  s.speed_mps = 40;
  EXPECT_NE(PlayCourseShot(c, s).status().message().find("speed_mps"), std::string::npos);
}

}  // namespace
}  // namespace sportsim::golf

namespace sportsim::golf {
namespace {

// Chips up the two-tier green that stop on the tier's face, where the slope's pull is only just
// held: dp45's error control shrinks its steps as the path hooks at the end of the roll, and
// the roll's last piece must still be taken whole (once it was not: a ball crept at a
// micrometre per second until max_time_s, after minutes of CPU).
TEST(CourseShotTest, ChipsThatStopOnATierFaceComeToRest) {
  const Course& links = Links();
  const Eigen::Vector2d pin = *links.Hole(2)->pin_m;
  const Eigen::Vector2d from = pin + 25.0 * (links.Hole(2)->tees[0].position_m - pin).normalized();
  for (double speed : {9.6, 9.7, 9.8}) {
    for (double da : {-1.5, -1.25, -1.0}) {
      CourseShot shot = Launch(2, from, Heading(from, pin) + da,
                               LaunchConditions{.ball_speed_mps = speed, .launch_angle_deg = 35,
                                                .launch_direction_deg = 0, .spin_rpm = 4000,
                                                .spin_axis_deg = 0});
      shot.hole_spec.flagstick_diameter_m = kFlagstickDiameter;
      absl::StatusOr<CourseShotResult> r = PlayCourseShot(links, shot);
      ASSERT_TRUE(r.ok()) << speed << " " << da << ": " << r.status();
      EXPECT_LT(r->ground.t_rest_s, 30.0);
      EXPECT_LT(r->ground.steps + r->ground.rejected_steps, 200000);
      EXPECT_EQ(r->lie, Terrain::kGreen);
    }
  }
}

}  // namespace
}  // namespace sportsim::golf
