#include "sim/golf/course.h"

#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "sim/golf/ground.h"

namespace sportsim::golf {
namespace {

using ::testing::HasSubstr;

// A small hand-written course: a 40 m x 20 m field rising 1 m to the east, one hole.
constexpr char kSmall[] = R"(sportsim-course 1
# a comment
course name=small base=rough
description A test field
air temperature_c=20 pressure_pa=101000 relative_humidity=0.5 altitude_m=100
wind speed_mps=2 toward_deg=90
heightfield x0=0 y0=0 spacing=10 columns=5 rows=3
z 0 0.25 0.5 0.75 1
z 0 0.25 0.5 0.75 1
z 0 0.25 0.5 0.75 1
hole ref=1 par=3 handicap=1 stimp_ft=11 fairway=fairway_soft
tee ref=1 tee=white 2,10
pin ref=1 35,10
boundary 1,1 39,1 39,19 1,19
area golf=fairway ref=1 5,5 30,5 30,15 5,15
area golf=green ref=1 30,5 38,5 38,15 30,15
area golf=bunker 20,12 25,12 25,18 20,18
area golf=water_hazard 10,1 15,1 15,4 10,4
)";

std::string Replace(std::string_view from, std::string_view to) {
  std::string text = kSmall;
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

TEST(CourseTest, ParsesAHandWrittenCourse) {
  auto c = ParseCourse(kSmall);
  ASSERT_TRUE(c.ok()) << c.status();
  EXPECT_EQ(c->name, "small");
  EXPECT_EQ(c->description, "A test field");
  EXPECT_EQ(c->air.temperature_c, 20);
  EXPECT_EQ(c->wind.speed_mps, 2);
  ASSERT_EQ(c->holes.size(), 1u);
  EXPECT_EQ(c->holes[0].par, 3);
  EXPECT_EQ(c->holes[0].tees[0].name, "white");
  EXPECT_DOUBLE_EQ(c->holes[0].length_m(), 33.0);
  EXPECT_EQ(c->SurfaceAt(10, 10).terrain, Terrain::kFairway);
  EXPECT_EQ(c->SurfaceAt(10, 10).hole, 1);
  EXPECT_EQ(c->SurfaceAt(35, 10).terrain, Terrain::kGreen);
  EXPECT_EQ(c->SurfaceAt(22, 13).terrain, Terrain::kBunker);  // painted over the fairway
  EXPECT_EQ(c->SurfaceAt(3, 17).terrain, Terrain::kRough);    // the base
  EXPECT_EQ(c->SurfaceAt(0.5, 10).terrain, Terrain::kOutOfBounds);
  // The hole's green speed and fairway firmness reach the constants.
  EXPECT_NEAR(c->Constants(c->SurfaceAt(35, 10)).stimp_ft(), 11.0, 1e-9);
  EXPECT_EQ(c->Constants(c->SurfaceAt(10, 10)).name, "fairway_soft");
  EXPECT_DOUBLE_EQ(c->terrain.HeightAt(20, 7), 0.5);
}

// The loader refuses each malformed course, naming the line or the field.
TEST(CourseTest, RefusesMalformedCoursesNamingTheField) {
  const std::pair<std::string, std::string> cases[] = {
      {Replace("pin ref=1 35,10\n", ""), "hole 1: no pin"},
      {Replace("pin ref=1 35,10", "pin ref=1 22,10"), "pin (22, 10) is not on a green"},
      {Replace("z 0 0.25 0.5 0.75 1\nhole", "z 0 0.25 0.5 1\nhole"), "row 2 has 4 values"},
      {Replace("z 0 0.25 0.5 0.75 1\nhole", "z 0 0.25 nan 0.75 1\nhole"),
       "row 2 column 2: 'nan' is not a finite number"},
      {Replace("z 0 0.25 0.5 0.75 1\nhole", "hole"), "heightfield: 2 rows of heights for 3"},
      {Replace("z 0 0.25 0.5 0.75 1\nhole", "z 0 0.25 0.5 0.75 30\nhole"), "steeper than 100 %"},
      {Replace("course name=small", "course name=Small!"), "name: 'Small!'"},
      {Replace("par=3", "par=9"), "hole 1: par must be in [3, 6], got 9"},
      {Replace("handicap=1", "handicap=2"), "handicap (stroke index) 2"},
      {Replace("stimp_ft=11", "stimp_ft=40"), "green_stimp_ft must be finite"},
      {Replace("fairway=fairway_soft", "fairway=moss"), "fairway 'moss'"},
      {Replace("golf=bunker", "golf=lava"), "golf: 'lava' is not a surface class"},
      {Replace("area golf=bunker", "area golf=bunker ref=4"), "ref=4 names no hole"},
      {Replace("area golf=bunker 20,12", "area golf=bunker 20,12 60,12"),
       "vertex 2 (60, 12) is outside"},
      {Replace("tee ref=1 tee=white 2,10", "tee ref=1 tee=white 12,2"), "is in golf=water_hazard"},
      {Replace("sportsim-course 1", "sportsim-course 2"), "begins with the line"},
      {Replace("air temperature_c=20", "air temperature_c=200"), "air: "},
      {Replace("wind speed_mps=2", "wind speed_mps=-2"), "wind: "},
      {Replace("heightfield x0=0", "heightfield x0=0 colour=red"), "unknown key 'colour'"},
      {Replace("columns=5", "columns=5000000"), "columns must be in [2, 4096]"},
      {std::string(kSmall) + "area golf=green 1,1 2,2\n", "2 points; a polygon has 3"},
      {std::string(kSmall) + "area golf=green 1,1 2,2 3,3\n", "the polygon has no area"},
      {std::string(kSmall) + "surface golf=rough rolling_resistance=-1\n",
       "surface golf=rough: surface rough: rolling_resistance must be finite"},
      {std::string(kSmall) + "surface golf=green stimp_ft=0.5\n", "stimp_ft must be finite"},
      {std::string(kSmall) + "teapot ref=1\n", "unknown element"},
      {std::string(kSmall) + "rating tee=blue slope=120 course_rating=3.2\n", "no hole has a tee"},
      {std::string(kSmall) + "rating tee=white slope=200 course_rating=3.2\n", "slope must be in [55, 155]"},
      {std::string(kSmall) + "rating tee=white slope=120 course_rating=9\n", "course_rating must be"},
      {std::string(kSmall) + "rating tee=white slope=120\n", "course_rating is required"},
      {std::string(kSmall) + "rating tee=white slope=120 course_rating=3.2\n"
                             "rating tee=white slope=121 course_rating=3.1\n", "given twice"},
      {"", "course: empty"},
  };
  for (const auto& [text, message] : cases) {
    auto c = ParseCourse(text);
    ASSERT_FALSE(c.ok()) << message;
    EXPECT_EQ(c.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(std::string(c.status().message()), HasSubstr(message));
  }
}

TEST(CourseTest, SurfaceOverridesReplaceTheBuiltInConstants) {
  auto c = ParseCourse(std::string(kSmall) +
                       "surface golf=rough rolling_resistance=0.9 sliding_friction=0.7\n"
                       "surface golf=green stimp_ft=13\n");
  ASSERT_TRUE(c.ok()) << c.status();
  const Surface rough = c->Constants(c->SurfaceAt(3, 17));
  EXPECT_EQ(rough.rolling_resistance, 0.9);
  EXPECT_EQ(rough.sliding_friction, 0.7);
  EXPECT_EQ(rough.restitution_scale, SurfaceByName("rough")->restitution_scale);
  EXPECT_NEAR(c->Constants(c->SurfaceAt(35, 10)).stimp_ft(), 13.0, 1e-9);
}

// A plane sampled on the grid is reproduced between the samples, height and normal, as the
// ground phase's plane gives them, and its curvature is zero (Catmull-Rom patches with the
// samples extended linearly beyond the edge reproduce linear functions).
TEST(CourseTest, TheTerrainReproducesAPlane) {
  auto c = PracticeCourse(10.0, 3.0, 30.0);
  ASSERT_TRUE(c.ok()) << c.status();
  const GroundPlane plane{.slope_pct = 3.0, .slope_toward_deg = 30.0};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-29.0, 29.0);
  for (int i = 0; i < 1000; ++i) {
    const double x = u(rng), y = u(rng);
    EXPECT_NEAR(c->terrain.HeightAt(x, y), plane.HeightAt(x, y), 1e-12);
    EXPECT_LT((c->terrain.NormalAt(x, y) - plane.Normal()).norm(), 1e-12);
    Eigen::Matrix2d hessian;
    c->terrain.Sample(x, y, nullptr, nullptr, &hessian);
    EXPECT_LT(hessian.norm(), 1e-12);
  }
  // Beyond the edge: the edge's height and normal.
  EXPECT_NEAR(c->terrain.HeightAt(-40, 0), plane.HeightAt(-30, 0), 1e-12);
}

// On a curved grid the height interpolates the samples, the normal is the gradient's, the
// Hessian the gradient's derivative, and height and slope are continuous across cell edges.
TEST(CourseTest, TerrainNormalIsTheHeightsGradient) {
  const auto links = BuiltinCourse("sportsim_links");
  ASSERT_TRUE(links.ok());
  const Heightfield& h = (*links)->terrain;
  EXPECT_EQ(h.HeightAt(h.x0_m + 7 * h.spacing_m, h.y0_m + 11 * h.spacing_m),
            h.z_m[11 * static_cast<size_t>(h.columns) + 7]);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> ux(h.x0_m + 1, h.x1_m() - 1), uy(h.y0_m + 1, h.y1_m() - 1);
  for (int i = 0; i < 1000; ++i) {
    const double x = ux(rng), y = uy(rng), e = 1e-6;
    // Inside a cell (not on its lines, where the gradient jumps).
    if (std::abs(std::remainder(x - h.x0_m, h.spacing_m)) < 2 * e ||
        std::abs(std::remainder(y - h.y0_m, h.spacing_m)) < 2 * e) {
      continue;
    }
    const double gx = (h.HeightAt(x + e, y) - h.HeightAt(x - e, y)) / (2 * e);
    const double gy = (h.HeightAt(x, y + e) - h.HeightAt(x, y - e)) / (2 * e);
    const Eigen::Vector3d n = Eigen::Vector3d(-gx, -gy, 1).normalized();
    EXPECT_LT((h.NormalAt(x, y) - n).norm(), 1e-7) << x << "," << y;
    Eigen::Vector2d g0, g_east, g_north;
    Eigen::Matrix2d hess;
    h.Sample(x, y, nullptr, &g0, &hess);
    h.Sample(x + e, y, nullptr, &g_east, nullptr);
    h.Sample(x, y + e, nullptr, &g_north, nullptr);
    EXPECT_LT(((g_east - g0) / e - hess.col(0)).norm(), 1e-4 * (1 + hess.norm())) << x;
    EXPECT_LT(((g_north - g0) / e - hess.col(1)).norm(), 1e-4 * (1 + hess.norm())) << y;
  }
  // Across a cell edge (x = x0 + 7 s) height and slope meet from both sides.
  const double xe = h.x0_m + 7 * h.spacing_m, ye = h.y0_m + 11.3 * h.spacing_m;
  Eigen::Vector2d left, right;
  double zl = 0, zr = 0;
  h.Sample(xe - 1e-9, ye, &zl, &left, nullptr);
  h.Sample(xe + 1e-9, ye, &zr, &right, nullptr);
  EXPECT_NEAR(zl, zr, 1e-8);
  EXPECT_LT((left - right).norm(), 1e-7);
}

// Rules 18.2a, 17.1a, 12.1, 13.1a: out of bounds only wholly, the specified areas on a touch.
TEST(CourseTest, TheLieFollowsTheRulesAtEdges) {
  auto c = ParseCourse(kSmall);
  ASSERT_TRUE(c.ok()) << c.status();
  const double r = 0.02135;
  // The boundary at x = 1: the centre 1 cm outside is still in bounds (part of the ball is in);
  // 2.2 cm outside it is out.
  EXPECT_EQ(c->SurfaceAt(0.99, 10).terrain, Terrain::kOutOfBounds);
  EXPECT_EQ(c->LieAt(0.99, 10, r), Terrain::kRough);
  EXPECT_EQ(c->LieAt(1 - 0.022, 10, r), Terrain::kOutOfBounds);
  EXPECT_EQ(c->LieAt(-5, 10, r), Terrain::kOutOfBounds);  // off the map
  // The water's edge at y = 4: a ball whose centre is 2 cm beyond it touches it.
  EXPECT_EQ(c->SurfaceAt(12, 4.02).terrain, Terrain::kRough);
  EXPECT_EQ(c->LieAt(12, 4.02, r), Terrain::kWaterHazard);
  EXPECT_NEAR(c->DistanceToEdge(12, 4.02, Terrain::kWaterHazard), 0.02, 1e-12);
  EXPECT_EQ(c->DistanceToEdge(12, 4.02, Terrain::kCartpath), std::numeric_limits<double>::infinity());
  EXPECT_EQ(c->LieAt(12, 4.03, r), Terrain::kRough);
  // A bunker's edge (x = 20), from the fairway; the green's (x = 30).
  EXPECT_EQ(c->LieAt(19.99, 13, r), Terrain::kBunker);
  EXPECT_EQ(c->LieAt(19.97, 13, r), Terrain::kFairway);
  EXPECT_EQ(c->LieAt(29.99, 10, r), Terrain::kGreen);
}

TEST(CourseTest, BuiltInCoursesAreCompleteAndValid) {
  ASSERT_EQ(BuiltinCourseNames().front(), "sportsim_links");
  for (std::string_view name : BuiltinCourseNames()) {
    auto c = BuiltinCourse(name);
    ASSERT_TRUE(c.ok()) << name;
    EXPECT_TRUE(ValidateCourse(**c).ok()) << name << ": " << ValidateCourse(**c);
    EXPECT_EQ((*c)->name, name);
  }
  EXPECT_EQ(BuiltinCourse("augusta").status().code(), absl::StatusCode::kNotFound);
  const Course& links = **BuiltinCourse("sportsim_links");
  // A par 3, a par 4 and a par 5.
  std::vector<int> pars;
  for (const CourseHole& h : links.holes) pars.push_back(h.par);
  EXPECT_THAT(pars, ::testing::UnorderedElementsAre(3, 4, 5));
  // Water of both colours, bunkers, out of bounds, cart paths.
  auto count = [&](Terrain t) {
    return std::count_if(links.areas.begin(), links.areas.end(),
                         [&](const CourseArea& a) { return a.terrain == t; });
  };
  EXPECT_GE(count(Terrain::kWaterHazard), 1);
  EXPECT_GE(count(Terrain::kLateralWaterHazard), 1);
  EXPECT_GE(count(Terrain::kBunker), 4);
  EXPECT_GE(count(Terrain::kCartpath), 1);
  EXPECT_FALSE(links.boundary.empty());
  // Elevation: the first tee above its green, the third hole's green above its tee.
  auto z = [&](const Eigen::Vector2d& p) { return links.terrain.HeightAt(p.x(), p.y()); };
  EXPECT_GT(z(links.holes[0].tees[0].position_m) - z(*links.holes[0].pin_m), 4.0);
  EXPECT_GT(z(*links.holes[2].pin_m) - z(links.holes[2].tees[0].position_m), 5.0);
  // The second green has two tiers: along its long axis the ground rises by more than its
  // plane's fall, in a face steeper than the rest of it.
  const Eigen::Vector2d g2(395, 228);
  double steepest = 0.0;
  for (double y = g2.y() - 14; y < g2.y() + 14; y += 0.25) {
    steepest = std::max(steepest, (z({g2.x(), y + 0.25}) - z({g2.x(), y})) / 0.25);
  }
  EXPECT_GT(z({g2.x(), g2.y() + 10}) - z({g2.x(), g2.y() - 10}), 0.5);
  EXPECT_GT(steepest, 0.08);
  // Every hole's length is sensible for its par (metres, as the WHS guidelines' bands roughly).
  for (const CourseHole& h : links.holes) {
    const double l = h.length_m();
    if (h.par == 3) {
      EXPECT_THAT(l, ::testing::AllOf(::testing::Gt(90), ::testing::Lt(230)));
    }
    if (h.par == 4) {
      EXPECT_THAT(l, ::testing::AllOf(::testing::Gt(230), ::testing::Lt(430)));
    }
    if (h.par == 5) {
      EXPECT_THAT(l, ::testing::AllOf(::testing::Gt(400), ::testing::Lt(600)));
    }
  }
  // The greens hold a ball at rest at their speed near every pin (the slope within 2 m of it
  // below the rolling resistance).
  for (const CourseHole& h : links.holes) {
    const Surface green = links.Constants(links.SurfaceAt(h.pin_m->x(), h.pin_m->y()));
    for (double dx = -2; dx <= 2; dx += 0.5) {
      for (double dy = -2; dy <= 2; dy += 0.5) {
        const Eigen::Vector3d n = links.terrain.NormalAt(h.pin_m->x() + dx, h.pin_m->y() + dy);
        EXPECT_LT(std::sqrt(1 - n.z() * n.z()) / n.z(), green.rolling_resistance) << h.number;
      }
    }
  }
}

// FormatCourse writes what ParseCourse reads back, bit for bit.
TEST(CourseTest, TheTextFormatRoundTrips) {
  for (std::string_view name : BuiltinCourseNames()) {
    const Course& c = **BuiltinCourse(name);
    const std::string text = FormatCourse(c);
    auto back = ParseCourse(text);
    ASSERT_TRUE(back.ok()) << name << ": " << back.status();
    EXPECT_EQ(FormatCourse(*back), text) << name;
    EXPECT_EQ(back->terrain.z_m, c.terrain.z_m);
    ASSERT_EQ(back->areas.size(), c.areas.size());
    for (size_t i = 0; i < c.areas.size(); ++i) {
      ASSERT_EQ(back->areas[i].polygon.size(), c.areas[i].polygon.size());
      for (size_t k = 0; k < c.areas[i].polygon.size(); ++k) {
        EXPECT_EQ(back->areas[i].polygon[k], c.areas[i].polygon[k]);
      }
    }
  }
  const auto links = ParseCourse(FormatCourse(**BuiltinCourse("sportsim_links")));
  ASSERT_EQ(links->ratings.size(), 2u);  // the white and red tees' ratings
  EXPECT_EQ(links->RatingOf("red").slope, 119.0);
  EXPECT_EQ(links->RatingOf("red").course_rating, 12.1);
  auto small = ParseCourse(std::string(kSmall) + "rating tee=white slope=121 course_rating=3.4\n");
  ASSERT_TRUE(small.ok()) << small.status();
  EXPECT_EQ(small->RatingOf("white").slope, 121.0);
  auto again = ParseCourse(FormatCourse(*small));
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ(FormatCourse(*again), FormatCourse(*small));
}

}  // namespace
}  // namespace sportsim::golf
