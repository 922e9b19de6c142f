// The ground phase on a course's terrain and surfaces (ground.h SimulateGroundOnCourse).
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "sim/golf/course.h"
#include "sim/golf/ground.h"

namespace sportsim::golf {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

const Course& Links() { return **BuiltinCourse("sportsim_links"); }

GroundOptions NoSamples() {
  GroundOptions o;
  o.sample_interval_s = 0;
  return o;
}

int Count(const GroundResult& r, GroundEventKind kind) {
  return static_cast<int>(std::count_if(r.events.begin(), r.events.end(),
                                        [&](const GroundEvent& e) { return e.kind == kind; }));
}

const GroundEvent* First(const GroundResult& r, GroundEventKind kind) {
  for (const GroundEvent& e : r.events) {
    if (e.kind == kind) return &e;
  }
  return nullptr;
}

// A uniform tilted heightfield is the plane: putts, rolling balls and landings rest where they
// rest on part 1's plane (the same RK4, so to rounding), holed or not alike.
TEST(CourseGroundTest, AUniformTiltedHeightfieldBehavesAsThePlane) {
  const GroundPlane plane{.slope_pct = 3.0, .slope_toward_deg = 30.0};
  auto course = PracticeCourse(10.0, plane.slope_pct, plane.slope_toward_deg);
  ASSERT_TRUE(course.ok()) << course.status();
  const Surface green = *GreenOfStimp(10.0);
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int holed = 0;
  for (int i = 0; i < 200; ++i) {
    const double x = -4 + 8 * u(rng), y = -4 + 8 * u(rng);
    if (std::hypot(x, y) < 0.1) continue;
    const double aim = std::atan2(-y, -x) / kDeg + (u(rng) - 0.5) * 4;
    GroundStart start;
    switch (i % 3) {
      case 0: start = PuttStart(x, y, 0.5 + 2 * u(rng), aim); break;
      case 1: start = RollingStart(x, y, 0.5 + 2 * u(rng), aim); break;
      default: {
        const double v = 5 + 10 * u(rng), d = (30 + 30 * u(rng)) * kDeg;
        start.kind = GroundStartKind::kLanding;
        start.position_m = Eigen::Vector3d(x, y, 0);
        start.velocity_mps = v * Eigen::Vector3d(std::cos(d) * std::cos(aim * kDeg),
                                                 std::cos(d) * std::sin(aim * kDeg), -std::sin(d));
        start.spin_radps = Eigen::Vector3d(-std::sin(aim * kDeg), std::cos(aim * kDeg), 0) *
                           (200 * u(rng));
      }
    }
    const GroundOptions o = NoSamples();
    auto on_plane = SimulateGround(BallSpec{}, green, plane, Hole{}, start, o);
    auto on_course = SimulateGroundOnCourse(BallSpec{}, *course, 1, Hole{}, start, o);
    ASSERT_TRUE(on_plane.ok()) << on_plane.status();
    ASSERT_TRUE(on_course.ok()) << on_course.status();
    if (on_course->rest_surface != "green") continue;  // ran off the green: no plane there
    EXPECT_EQ(on_course->holed, on_plane->holed) << i;
    EXPECT_LT((on_course->rest_m - on_plane->rest_m).norm(), 1e-6) << i;
    EXPECT_NEAR(on_course->t_rest_s, on_plane->t_rest_s, 1e-6) << i;
    holed += on_course->holed;
  }
  EXPECT_GT(holed, 0);  // the hole is met, not only the open green
}

// 10,000 random landings, putts and rolling balls all over the built-in course: no NaN, never
// below the terrain, always an end (rest, hole, water or out of bounds), events in time order,
// the rest on the terrain and its surface the one under it.
TEST(CourseGroundTest, RandomShotsOnTheBuiltInCourseEndOnTheTerrain) {
  const Course& c = Links();
  const double r = BallSpec{}.radius_m();
  std::mt19937_64 rng(20261205);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int ends[4] = {0, 0, 0, 0};  // rest, holed, water, out of bounds
  for (int i = 0; i < 10000; ++i) {
    const int hole = 1 + i % 3;
    const Eigen::Vector2d pin = *c.holes[static_cast<size_t>(hole - 1)].pin_m;
    // Half near the pin, half anywhere.
    const double x = i % 2 == 0 ? pin.x() - 40 + 80 * u(rng) : c.terrain.x0_m + 5 + 600 * u(rng);
    const double y = i % 2 == 0 ? pin.y() - 40 + 80 * u(rng) : c.terrain.y0_m + 5 + 370 * u(rng);
    const Terrain lie = c.LieAt(x, y, r);
    if (lie == Terrain::kOutOfBounds || IsPenaltyArea(c.SurfaceAt(x, y).terrain)) continue;
    const double heading = 360 * u(rng);
    GroundStart start;
    if (i % 3 == 0) {
      start = PuttStart(x, y, 0.5 + 6 * u(rng), heading);
    } else if (i % 3 == 1) {
      start = RollingStart(x, y, 0.5 + 6 * u(rng), heading);
    } else {
      const double v = 10 + 30 * u(rng), d = (20 + 40 * u(rng)) * kDeg;
      start.kind = GroundStartKind::kLanding;
      start.position_m = Eigen::Vector3d(x, y, 0);
      start.velocity_mps = v * Eigen::Vector3d(std::cos(d) * std::cos(heading * kDeg),
                                               std::cos(d) * std::sin(heading * kDeg), -std::sin(d));
      start.spin_radps = Eigen::Vector3d(-std::sin(heading * kDeg), std::cos(heading * kDeg), 0) *
                         (50 + 700 * u(rng));
    }
    // Half with RK4 at 5 ms, half with the courses' default (dp45).
    GroundOptions o = i % 4 < 2 ? GroundOptions{} : CourseGroundOptions();
    o.sample_interval_s = 0.01;
    auto res = SimulateGroundOnCourse(BallSpec{}, c, hole, Hole{}, start, o);
    ASSERT_TRUE(res.ok()) << i << ": " << res.status();
    const GroundResult& g = *res;
    ASSERT_FALSE(g.events.empty());
    const GroundEventKind last = g.events.back().kind;
    ASSERT_TRUE(last == GroundEventKind::kRest || last == GroundEventKind::kHoled) << i;
    ends[g.holed ? 1 : g.penalty_area ? 2 : g.out_of_bounds ? 3 : 0]++;
    for (size_t k = 1; k < g.events.size(); ++k) {
      ASSERT_GE(g.events[k].t_s, g.events[k - 1].t_s) << i;
    }
    for (const GroundSample& s : g.samples) {
      ASSERT_TRUE(s.position_m.allFinite()) << i;
      if (!c.terrain.Covers(s.position_m.x(), s.position_m.y())) continue;
      // The contact point never below the ground (a millimetre for the tangent-plane contact
      // on curved ground).
      EXPECT_GE(s.position_m.z(), c.terrain.HeightAt(s.position_m.x(), s.position_m.y()) - 1e-3)
          << i << " at t " << s.t_s;
    }
    if (!g.holed && !g.out_of_bounds) {
      EXPECT_NEAR(g.rest_m.z(), c.terrain.HeightAt(g.rest_m.x(), g.rest_m.y()), 1e-3) << i;
    }
    if (!g.holed && !g.penalty_area && !g.out_of_bounds) {
      // At rest where the surface holds it, on the surface the result names.
      const Eigen::Vector3d n = c.terrain.NormalAt(g.rest_m.x(), g.rest_m.y());
      const double tan = std::sqrt(1 - n.z() * n.z()) / n.z();
      EXPECT_EQ(g.rest_surface, g.events.back().surface) << i;
      EXPECT_FALSE(g.rest_surface.empty()) << i;
      EXPECT_LT(tan, 2.0) << i;
    }
  }
  // Every ending happens somewhere on the course.
  EXPECT_GT(ends[0], 100);
  EXPECT_GT(ends[2], 0);
  EXPECT_GT(ends[3], 0);
}

// A ball rolled off the first green toward the bunker short right of it stops in the bunker.
TEST(CourseGroundTest, ABallRolledOffTheGreenIntoABunkerStopsInIt) {
  const Course& c = Links();
  const Eigen::Vector2d from(360, -2), bunker(352, -15);
  ASSERT_EQ(c.SurfaceAt(from.x(), from.y()).terrain, Terrain::kGreen);
  const double heading = std::atan2(bunker.y() - from.y(), bunker.x() - from.x()) / kDeg;
  int in_bunker = 0;
  for (double speed = 3; speed <= 9; speed += 1) {
    auto res = SimulateGroundOnCourse(BallSpec{}, c, 1, Hole{},
                                      RollingStart(from.x(), from.y(), speed, heading), NoSamples());
    ASSERT_TRUE(res.ok()) << res.status();
    if (res->rest_surface != "bunker") continue;
    ++in_bunker;
    // It crossed the green's edge and the bunker's, and rests inside the bunker.
    bool crossed = false;
    for (const GroundEvent& e : res->events) crossed |= e.kind == GroundEventKind::kSurface && e.surface == "bunker";
    EXPECT_TRUE(crossed || First(*res, GroundEventKind::kBounce) != nullptr) << speed;
    EXPECT_EQ(c.SurfaceAt(res->rest_m.x(), res->rest_m.y()).terrain, Terrain::kBunker);
  }
  EXPECT_GE(in_bunker, 3);
}

// Into the pond: a penalty_area event where the centre enters the water, and the run ends
// there.
TEST(CourseGroundTest, ABallRollingIntoWaterEndsAtTheMargin) {
  const Course& c = Links();
  // North from the second tee toward the pond (its south edge at y = 120 on x = 395).
  auto res = SimulateGroundOnCourse(BallSpec{}, c, 2, Hole{}, RollingStart(395, 100, 12, 90),
                                    NoSamples());
  ASSERT_TRUE(res.ok()) << res.status();
  EXPECT_TRUE(res->penalty_area);
  EXPECT_EQ(res->rest_surface, "water_hazard");
  const GroundEvent* e = First(*res, GroundEventKind::kPenaltyArea);
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(res->events.back().kind, GroundEventKind::kRest);
  EXPECT_EQ(res->events.back().t_s, e->t_s);
  // At the margin: 1 mm inside it, the water; 1 mm before it (back along the path), not.
  const Eigen::Vector3d back = -e->velocity_mps.normalized();
  EXPECT_EQ(c.SurfaceAt(e->position_m.x() - 1e-3 * back.x(), e->position_m.y() - 1e-3 * back.y()).terrain,
            Terrain::kWaterHazard);
  EXPECT_NE(c.SurfaceAt(e->position_m.x() + 1e-3 * back.x(), e->position_m.y() + 1e-3 * back.y()).terrain,
            Terrain::kWaterHazard);
}

// Across the boundary (north of the third hole, y = 316): out of bounds where all of the ball
// is out, its centre a radius past the line.
TEST(CourseGroundTest, OutOfBoundsWhereTheWholeBallIsOut) {
  const Course& c = Links();
  const double r = BallSpec{}.radius_m();
  auto res = SimulateGroundOnCourse(BallSpec{}, c, 3, Hole{}, RollingStart(200, 300, 14, 90),
                                    NoSamples());
  ASSERT_TRUE(res.ok()) << res.status();
  EXPECT_TRUE(res->out_of_bounds);
  const GroundEvent* e = First(*res, GroundEventKind::kOutOfBounds);
  ASSERT_NE(e, nullptr);
  // The event's point is the contact point; its centre is over (x, y) on the flat-ish rough.
  EXPECT_NEAR(e->position_m.y(), 316 + r, 2e-4);
}

// The distance (m) the point (x, y) lies outside the map (0 on or inside it), and the ground's
// height where it left (the nearest point of the map).
double PastTheEdge(const Heightfield& h, double x, double y) {
  return std::hypot(x - std::clamp(x, h.x0_m, h.x1_m()), y - std::clamp(y, h.y0_m, h.y1_m()));
}
double HeightAtTheEdge(const Heightfield& h, double x, double y) {
  return h.HeightAt(std::clamp(x, h.x0_m, h.x1_m()), std::clamp(y, h.y0_m, h.y1_m()));
}

// Fast, flat, heavily spun landings anywhere in play, heading for the nearest edge of the map,
// bounce and skip along, and many leave the map. A run that leaves it ends where the ball's
// centre crosses the edge (to a micrometre), never under the ground there: a hop that meets
// the ground before its centre leaves the map lands on the map. No sample over the map lies
// under the ground (the tangent-plane contact's half millimetre on curved ground).
TEST(CourseGroundTest, BallsLeaveTheMapAtItsEdgeAndNeverUnderTheGround) {
  const Course& c = Links();
  const Heightfield& h = c.terrain;
  const double r = BallSpec{}.radius_m();
  const double x0 = h.x0_m, x1 = h.x1_m(), y0 = h.y0_m, y1 = h.y1_m();
  std::vector<GroundStart> starts;
  {
    // A skipping ball, found by the fuzzer: its last hop met the ground 5 mm before the edge
    // and the run ended under the ground past it.
    GroundStart s;
    s.kind = GroundStartKind::kLanding;
    s.position_m = Eigen::Vector3d(-133.68626039016306, 46.481019968450894, 0);
    s.velocity_mps = Eigen::Vector3d(-68.637330067196046, -59.999999999897867, -60);
    s.spin_radps = Eigen::Vector3d(-1500, -1500, -500);
    starts.push_back(s);
  }
  std::mt19937_64 rng(41);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  while (starts.size() < 300) {
    const double x = x0 + (x1 - x0) * u(rng), y = y0 + (y1 - y0) * u(rng);
    if (c.LieAt(x, y, r) == Terrain::kOutOfBounds || IsPenaltyArea(c.SurfaceAt(x, y).terrain)) continue;
    const double to_edge[4] = {x - x0, x1 - x, y - y0, y1 - y};
    const int edge = static_cast<int>(std::min_element(to_edge, to_edge + 4) - to_edge);
    const double heading = (edge == 0 ? 180 : edge == 1 ? 0 : edge == 2 ? 270 : 90) + 60 * (u(rng) - 0.5);
    const double v = 40 + 60 * u(rng), d = (3 + 30 * u(rng)) * kDeg;
    GroundStart s;
    s.kind = GroundStartKind::kLanding;
    s.position_m = Eigen::Vector3d(x, y, 0);
    s.velocity_mps = v * Eigen::Vector3d(std::cos(d) * std::cos(heading * kDeg),
                                         std::cos(d) * std::sin(heading * kDeg), -std::sin(d));
    s.spin_radps = Eigen::Vector3d(3000 * (u(rng) - 0.5), 3000 * (u(rng) - 0.5), 1000 * (u(rng) - 0.5));
    starts.push_back(s);
  }
  int left_the_map = 0;
  for (size_t i = 0; i < starts.size(); ++i) {
    GroundOptions o;
    o.sample_interval_s = 1e-3;
    auto res = SimulateGroundOnCourse(BallSpec{}, c, 1, Hole{}, starts[i], o);
    if (!res.ok()) {  // a flat landing on ground that falls away faster: it would not land
      ASSERT_THAT(std::string(res.status().message()), ::testing::HasSubstr("into the ground"));
      continue;
    }
    ASSERT_FALSE(res->events.empty());
    EXPECT_EQ(res->events.back().kind, GroundEventKind::kRest) << i;
    // The ball's centre at the end: R along the normal above the contact point.
    const Eigen::Vector3d& end = res->rest_m;
    const Eigen::Vector3d centre =
        end + r * h.NormalAt(std::clamp(end.x(), x0, x1), std::clamp(end.y(), y0, y1));
    const double inside =
        std::min({centre.x() - x0, x1 - centre.x(), centre.y() - y0, y1 - centre.y()});
    if (inside < 1e-6) {  // it left the map
      ++left_the_map;
      EXPECT_TRUE(res->out_of_bounds) << i;
      EXPECT_LT(PastTheEdge(h, centre.x(), centre.y()), 1e-6) << i;
      EXPECT_GE(end.z() - HeightAtTheEdge(h, end.x(), end.y()), -5e-4) << i;
    }
    for (const GroundSample& s : res->samples) {
      if (!h.Covers(s.position_m.x(), s.position_m.y())) continue;
      ASSERT_GE(s.position_m.z() - h.HeightAt(s.position_m.x(), s.position_m.y()), -5e-4)
          << i << " at t " << s.t_s;
    }
  }
  EXPECT_GT(left_the_map, 100);
}

TEST(CourseGroundTest, TheSameShotGivesBitIdenticalResults) {
  const Course& c = Links();
  GroundStart start;
  start.kind = GroundStartKind::kLanding;
  start.position_m = Eigen::Vector3d(240, 0, 0);
  start.velocity_mps = Eigen::Vector3d(25, 1, -12);
  start.spin_radps = Eigen::Vector3d(0, 250, 0);
  auto a = SimulateGroundOnCourse(BallSpec{}, c, 1, Hole{}, start, GroundOptions{});
  auto b = SimulateGroundOnCourse(BallSpec{}, c, 1, Hole{}, start, GroundOptions{});
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->samples.size(), b->samples.size());
  EXPECT_EQ(a->rest_m, b->rest_m);
  for (size_t i = 0; i < a->samples.size(); ++i) EXPECT_EQ(a->samples[i].position_m, b->samples[i].position_m);
  EXPECT_GT(Count(*a, GroundEventKind::kBounce), 0);
}

TEST(CourseGroundTest, RefusesStartsOutOfPlay) {
  const Course& c = Links();
  auto oob = SimulateGroundOnCourse(BallSpec{}, c, 1, Hole{}, PuttStart(-158, 318, 1, 0), NoSamples());
  EXPECT_THAT(std::string(oob.status().message()), ::testing::HasSubstr("out of bounds"));
  auto water = SimulateGroundOnCourse(BallSpec{}, c, 2, Hole{}, PuttStart(395, 140, 1, 0), NoSamples());
  EXPECT_THAT(std::string(water.status().message()), ::testing::HasSubstr("water"));
  auto hole = SimulateGroundOnCourse(BallSpec{}, c, 4, Hole{}, PuttStart(0, 0, 1, 0), NoSamples());
  EXPECT_THAT(std::string(hole.status().message()), ::testing::HasSubstr("hole: 4"));
  auto up = SimulateGroundOnCourse(
      BallSpec{}, c, 1, Hole{},
      GroundStart{.kind = GroundStartKind::kLanding, .velocity_mps = Eigen::Vector3d(1, 0, 1)},
      NoSamples());
  EXPECT_THAT(std::string(up.status().message()), ::testing::HasSubstr("into the ground"));
}

// Both integrators converge on the terrain to a reference (RK4 at 50 us): putts across the
// two-tier green and landings on the first hole's slopes. The courses' default (dp45 at
// 1e-8 m) rests within 1 mm, RK4's error falls with its step and dp45's with its tolerance.
TEST(CourseGroundTest, BothIntegratorsConvergeOnTheTerrain) {
  const Course& c = Links();
  std::vector<GroundStart> starts;
  const Eigen::Vector2d pin2 = *c.holes[1].pin_m;
  for (int i = 0; i < 6; ++i) {  // up and across the tier toward the pin
    starts.push_back(PuttStart(pin2.x() - 4 + 1.5 * i, pin2.y() - 14, 3.2 + 0.1 * i,
                               80 + 4 * i));
  }
  for (int i = 0; i < 6; ++i) {  // onto the first hole's fairway and green
    GroundStart l;
    l.kind = GroundStartKind::kLanding;
    l.position_m = Eigen::Vector3d(220 + 25 * i, -10 + 4 * i, 0);
    l.velocity_mps = Eigen::Vector3d(18, 0.5 * i, -14);
    l.spin_radps = Eigen::Vector3d(0, 300 + 40 * i, 0);
    starts.push_back(l);
  }
  auto rest = [&](const GroundStart& start, ode::Integrator integrator, double value) {
    GroundOptions o = NoSamples();
    o.integrator = integrator;
    if (integrator == ode::Integrator::kDp45) {
      o.tolerance_m = value;
      o.dt_s = 0.05;
    } else {
      o.dt_s = value;
    }
    auto r = SimulateGroundOnCourse(BallSpec{}, c, start.kind == GroundStartKind::kPutt ? 2 : 1,
                                    Hole{}, start, o);
    EXPECT_TRUE(r.ok()) << r.status();
    return r.ok() ? r->rest_m : Eigen::Vector3d::Zero();
  };
  double rk4_coarse = 0, rk4_fine = 0, dp_loose = 0, dp_tight = 0;
  for (const GroundStart& start : starts) {
    const Eigen::Vector3d ref = rest(start, ode::Integrator::kRk4, 5e-5);
    // The courses' default (dp45 at 1e-8 m) within 1 mm; RK4 at 5 ms within a centimetre.
    EXPECT_LT((rest(start, ode::Integrator::kDp45, 1e-8) - ref).norm(), 1e-3);
    EXPECT_LT((rest(start, ode::Integrator::kRk4, 5e-3) - ref).norm(), 1e-2);
    rk4_coarse = std::max(rk4_coarse, (rest(start, ode::Integrator::kRk4, 1e-2) - ref).norm());
    rk4_fine = std::max(rk4_fine, (rest(start, ode::Integrator::kRk4, 1e-3) - ref).norm());
    dp_loose = std::max(dp_loose, (rest(start, ode::Integrator::kDp45, 1e-4) - ref).norm());
    dp_tight = std::max(dp_tight, (rest(start, ode::Integrator::kDp45, 1e-9) - ref).norm());
  }
  EXPECT_LT(rk4_fine, rk4_coarse);
  EXPECT_LT(dp_tight, dp_loose);
  EXPECT_LT(dp_tight, 1e-4);
}

// The bounding-box index answers as the plain scan does.
TEST(CourseGroundTest, TheIndexAnswersAsTheCourse) {
  const Course& c = Links();
  const CourseIndex index(c);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ux(c.terrain.x0_m - 2, c.terrain.x1_m() + 2),
      uy(c.terrain.y0_m - 2, c.terrain.y1_m() + 2);
  for (int i = 0; i < 20000; ++i) {
    const double x = ux(rng), y = uy(rng);
    const Course::Spot a = c.SurfaceAt(x, y), b = index.SurfaceAt(x, y);
    ASSERT_EQ(a.terrain, b.terrain);
    ASSERT_EQ(a.hole, b.hole);
    ASSERT_EQ(c.LieAt(x, y, 0.5), index.LieAt(x, y, 0.5));
  }
}

}  // namespace
}  // namespace sportsim::golf
