// The built-in courses: sportsim_links (the default), practice and range. Made up for sportsim:
// no mapped course's data. Each is generated here as a Course (a heightfield sampled from smooth
// functions, polygons from ellipses) and validated like a loaded one.
#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "sim/core/check.h"
#include "sim/golf/course.h"

namespace sportsim::golf {

namespace {

using Eigen::Vector2d;

constexpr double kPi = std::numbers::pi;

// An ellipse centred at c with semi-axes a (along heading rot_deg) and b, as n vertices.
std::vector<Vector2d> Ellipse(Vector2d c, double a, double b, double rot_deg = 0.0, int n = 48) {
  std::vector<Vector2d> out;
  out.reserve(static_cast<size_t>(n));
  const double r = rot_deg * kPi / 180.0;
  for (int i = 0; i < n; ++i) {
    const double t = 2.0 * kPi * i / n;
    const Vector2d p(a * std::cos(t), b * std::sin(t));
    out.emplace_back(c.x() + p.x() * std::cos(r) - p.y() * std::sin(r),
                     c.y() + p.x() * std::sin(r) + p.y() * std::cos(r));
  }
  return out;
}

std::vector<Vector2d> Rect(double x0, double y0, double x1, double y1) {
  return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
}

// A grid of zero heights.
Heightfield Grid(double x0, double y0, double spacing, int columns, int rows) {
  Heightfield h{.x0_m = x0, .y0_m = y0, .spacing_m = spacing, .columns = columns, .rows = rows};
  h.z_m.assign(static_cast<size_t>(columns) * rows, 0.0);
  return h;
}

double Smoothstep(double t) {
  t = std::clamp(t, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// How far inside an ellipse (rotated by rot_deg) a point is: < 1 inside, 1 on the edge.
double EllipseRadius(Vector2d p, Vector2d c, double a, double b, double rot_deg = 0.0) {
  const double r = rot_deg * kPi / 180.0;
  const Vector2d d = p - c;
  const double u = d.x() * std::cos(r) + d.y() * std::sin(r);
  const double v = -d.x() * std::sin(r) + d.y() * std::cos(r);
  return std::sqrt((u / a) * (u / a) + (v / b) * (v / b));
}

// A green: an ellipse, the plane its surface lies on, an optional tier.
struct GreenShape {
  Vector2d c;
  double a, b, rot_deg;
  double z;                // height at the centre
  double fall_pct;         // the plane's grade
  double fall_toward_deg;  // heading of its fall line
  double tier_m = 0.0;     // the upper tier's rise (0: one tier)
  double tier_offset_m = 0.0;   // the tier's line, along tier_toward_deg from the centre
  double tier_toward_deg = 0.0;  // the upper tier lies this way
  double tier_width_m = 2.5;     // the face's half-width (tanh scale)

  double Height(Vector2d p) const {
    const double f = fall_toward_deg * kPi / 180.0;
    const Vector2d d = p - c;
    double h = z - fall_pct / 100.0 * (d.x() * std::cos(f) + d.y() * std::sin(f));
    if (tier_m != 0.0) {
      const double t = tier_toward_deg * kPi / 180.0;
      const double s = d.x() * std::cos(t) + d.y() * std::sin(t) - tier_offset_m;
      h += 0.5 * tier_m * (1.0 + std::tanh(s / tier_width_m));
    }
    return h;
  }
};

struct BunkerShape {
  Vector2d c;
  double a, b, rot_deg;
  double depth_m = 0.5;
};

// sportsim_links: three holes by the sea.
// 1. Par 4, 370 m, east from an elevated tee (6 m above the landing area) down a fairway with a
//    bunker on the right, to a green sloping back to front with a bunker short right.
// 2. Par 3, 160 m, north over a pond (a yellow penalty area) to a two-tier green whose upper
//    tier, at the back, is 0.7 m above the lower one, bunkered left and right.
// 3. Par 5, 480 m, west and uphill (about 9 m), a creek (a red penalty area) along the left,
//    out of bounds close on the right, cross bunkers at about 300 m, a green raised at the end.
// Cart paths join the greens to the next tees. The boundary (leisure=golf_course) runs round it
// all; a practice ground in the south-west corner is out of bounds (golf=out_of_bounds).
Course MakeLinks() {
  Course c;
  c.name = "sportsim_links";
  c.description = "Three holes by the sea (par 4, 3, 5), made up for sportsim";
  c.air = Atmosphere{.temperature_c = 16.0, .pressure_pa = 101325.0, .relative_humidity = 0.7,
                     .altitude_m = 10.0};
  c.wind = Wind{.speed_mps = 0.0, .toward_deg = 0.0};

  const GreenShape greens[] = {
      {.c = {365, 5}, .a = 17, .b = 13, .rot_deg = 0, .z = 4.0, .fall_pct = 2.0,
       .fall_toward_deg = 180},
      {.c = {395, 228}, .a = 20, .b = 14, .rot_deg = 90, .z = 5.0, .fall_pct = 1.5,
       .fall_toward_deg = 270, .tier_m = 0.7, .tier_offset_m = 2.0, .tier_toward_deg = 90},
      {.c = {-95, 268}, .a = 16, .b = 14, .rot_deg = 20, .z = 15.0, .fall_pct = 2.5,
       .fall_toward_deg = 0},
  };
  const BunkerShape bunkers[] = {
      {.c = {245, -24}, .a = 12, .b = 6, .rot_deg = 10},        // 1: fairway, right
      {.c = {352, -15}, .a = 8, .b = 5, .rot_deg = -30},        // 1: greenside, short right
      {.c = {370, 230}, .a = 7, .b = 4, .rot_deg = 80},         // 2: left
      {.c = {419, 222}, .a = 7, .b = 4, .rot_deg = 100},        // 2: right
      {.c = {60, 285}, .a = 10, .b = 5, .rot_deg = 80},         // 3: cross bunkers
      {.c = {42, 262}, .a = 9, .b = 5, .rot_deg = 95},
      {.c = {-80, 250}, .a = 8, .b = 4.5, .rot_deg = 30},       // 3: greenside, short left
  };
  const Vector2d pond_c(395, 140);
  const double pond_a = 38, pond_b = 20;

  // The land: a gentle swell, the first tee's hill, the third hole's rise to the west, the
  // pond's hollow, a creek's ditch; then the greens and bunkers shaped into it.
  auto land = [&](Vector2d p) {
    const double x = p.x(), y = p.y();
    double z = 4.0 + 1.2 * std::sin(x / 70.0) * std::cos(y / 55.0);
    z += 6.0 * std::exp(-((x + 5) * (x + 5) + y * y) / (2.0 * 45.0 * 45.0));
    z += 9.0 * Smoothstep((300.0 - x) / 380.0) * Smoothstep((y - 170.0) / 60.0);
    z -= 2.0 * std::exp(-std::pow(EllipseRadius(p, pond_c, pond_a + 10, pond_b + 10), 2));
    // The creek: a ditch along y = 225 from x = 280 west to x = -40.
    const double along = Smoothstep((280.0 - x) / 20.0) * Smoothstep((x + 40.0) / 20.0);
    z -= 1.2 * along * std::exp(-(y - 225.0) * (y - 225.0) / (2.0 * 5.0 * 5.0));
    for (const GreenShape& g : greens) {
      // Within 1.25 of the green's ellipse the ground is the green's; out to 2.2 it blends.
      const double r = EllipseRadius(p, g.c, g.a, g.b, g.rot_deg);
      const double w = 1.0 - Smoothstep((r - 1.25) / 0.95);
      z = (1.0 - w) * z + w * g.Height(p);
    }
    for (const BunkerShape& b : bunkers) {
      const double r = EllipseRadius(p, b.c, b.a, b.b, b.rot_deg);
      // The floor inside 0.75 of the ellipse, a face out to its edge and a little beyond.
      z -= b.depth_m * (1.0 - Smoothstep((r - 0.75) / 0.35));
    }
    return z;
  };
  c.terrain = Grid(-160, -60, 2.0, 306, 191);  // to x = 450, y = 320
  Heightfield& h = c.terrain;
  for (int j = 0; j < h.rows; ++j) {
    for (int i = 0; i < h.columns; ++i) {
      const double z = land(Vector2d(h.x0_m + i * h.spacing_m, h.y0_m + j * h.spacing_m));
      h.z_m[static_cast<size_t>(j) * h.columns + i] = std::round(z * 1000.0) / 1000.0;  // mm
    }
  }
  c.boundary = {{-156, -56}, {446, -56}, {446, 316}, {-156, 316}};

  CourseHole h1{.number = 1, .par = 4, .stroke_index = 2};
  h1.tees = {{"white", {0, 0}}, {"red", {40, -3}}};
  h1.pin_m = Vector2d(369, 2);
  h1.green_stimp_ft = 10.0;
  h1.fairway = "fairway_firm";
  CourseHole h2{.number = 2, .par = 3, .stroke_index = 3};
  h2.tees = {{"white", {392, 62}}, {"red", {394, 85}}};
  h2.pin_m = Vector2d(397, 239);  // on the upper tier
  h2.green_stimp_ft = 11.0;
  CourseHole h3{.number = 3, .par = 5, .stroke_index = 1};
  h3.tees = {{"white", {380, 272}}, {"red", {330, 272}}};
  h3.line_m = {{120, 276}};
  h3.pin_m = Vector2d(-99, 271);
  h3.green_stimp_ft = 10.0;
  h3.fairway = "fairway_soft";
  c.holes = {h1, h2, h3};
  // Ratings of the two tee sets over the three holes (par 12), set for this course as a rating
  // committee would judge it (the creek, the pond and the raised greens make it harder than
  // standard), not measured: they give handicaps something to act on.
  c.ratings = {{"white", 128.0, 12.6}, {"red", 119.0, 12.1}};

  auto add = [&](Terrain t, int hole, std::vector<Vector2d> poly) {
    c.areas.push_back(CourseArea{.terrain = t, .hole = hole, .polygon = std::move(poly)});
  };
  // Fairways: chains of ellipses, each inside a first cut 3 m wider.
  struct Piece {
    int hole;
    Vector2d c;
    double a, b, rot;
  };
  const Piece fairway[] = {
      {1, {120, 0}, 75, 20, 0},    {1, {230, 2}, 60, 22, 0},     {1, {315, 4}, 40, 16, 0},
      {3, {300, 272}, 70, 20, 0},  {3, {180, 276}, 70, 22, 0},   {3, {70, 274}, 60, 20, 0},
      {3, {-20, 270}, 55, 16, -5},
  };
  for (const Piece& f : fairway) add(Terrain::kFirstCut, f.hole, Ellipse(f.c, f.a + 3, f.b + 3, f.rot));
  for (const Piece& f : fairway) add(Terrain::kFairway, f.hole, Ellipse(f.c, f.a, f.b, f.rot));
  // Greens inside their fringes (a collar 1.5 m wide).
  for (int k = 0; k < 3; ++k) {
    const GreenShape& g = greens[k];
    add(Terrain::kFringe, k + 1, Ellipse(g.c, g.a + 1.5, g.b + 1.5, g.rot_deg, 64));
  }
  for (int k = 0; k < 3; ++k) {
    const GreenShape& g = greens[k];
    add(Terrain::kGreen, k + 1, Ellipse(g.c, g.a, g.b, g.rot_deg, 64));
  }
  for (const BunkerShape& b : bunkers) add(Terrain::kBunker, 0, Ellipse(b.c, b.a, b.b, b.rot_deg, 32));
  add(Terrain::kWaterHazard, 2, Ellipse(pond_c, pond_a, pond_b, 0, 48));
  // The creek, 8 m wide along y = 225 from x = 270 to x = -30.
  add(Terrain::kLateralWaterHazard, 3, {{270, 221}, {120, 220}, {-30, 222}, {-30, 229},
                                        {120, 228}, {270, 229}});
  // Cart paths, 3 m wide: green 1 to tee 2, green 2 to tee 3.
  add(Terrain::kCartpath, 0, {{384, 10}, {387, 10}, {387, 55}, {384, 55}});
  add(Terrain::kCartpath, 0, {{424, 236}, {427, 236}, {427, 268}, {424, 268}});
  add(Terrain::kOutOfBounds, 0, Rect(-156, -56, -110, -20));
  // Teeing grounds.
  for (const CourseHole* hole : {&c.holes[0], &c.holes[1], &c.holes[2]}) {
    for (const CourseTee& t : hole->tees) {
      const Vector2d& p = t.position_m;
      add(Terrain::kTee, hole->number, Rect(p.x() - 4, p.y() - 4, p.x() + 4, p.y() + 4));
    }
  }
  return c;
}

// The driving range: flat, firm fairway 340 m long and 100 m wide, rough beyond, a target
// green at 150 m (the range's one "hole", par 3), teeing ground at the origin.
Course MakeRange() {
  Course c;
  c.name = "range";
  c.description = "A flat driving range: firm fairway, a target green at 150 m";
  c.terrain = Grid(-20, -100, 10.0, 43, 21);  // to x = 400, y = 100
  CourseHole hole{.number = 1, .par = 3, .stroke_index = 1};
  hole.tees = {{"range", {0, 0}}};
  hole.pin_m = Vector2d(150, 0);
  hole.fairway = "fairway_firm";
  c.holes = {hole};
  c.areas.push_back({Terrain::kFairway, 1, Rect(-10, -50, 330, 50)});
  c.areas.push_back({Terrain::kFringe, 1, Ellipse({150, 0}, 13.5, 13.5)});
  c.areas.push_back({Terrain::kGreen, 1, Ellipse({150, 0}, 12, 12)});
  c.areas.push_back({Terrain::kTee, 1, Rect(-5, -25, 5, 25)});
  return c;
}

}  // namespace

absl::StatusOr<Course> PracticeCourse(double stimp_ft, double slope_pct, double slope_toward_deg) {
  if (absl::Status s = CheckFieldsInRange({{"stimp_ft", stimp_ft, 1, false, 20},
                                           {"slope_pct", slope_pct, 0, false, 20},
                                           {"slope_toward_deg", slope_toward_deg, -1e6, false, 1e6}});
      !s.ok()) {
    return s;
  }
  Course c;
  c.name = "practice";
  c.description = "A plane practice green, 50 m square, its hole at the origin";
  c.terrain = Grid(-30, -30, 10.0, 7, 7);
  Heightfield& h = c.terrain;
  const double d = slope_toward_deg * kPi / 180.0;
  for (int j = 0; j < h.rows; ++j) {
    for (int i = 0; i < h.columns; ++i) {
      const double x = h.x0_m + i * h.spacing_m, y = h.y0_m + j * h.spacing_m;
      const double z = -(slope_pct / 100.0) * (x * std::cos(d) + y * std::sin(d));
      h.z_m[static_cast<size_t>(j) * h.columns + i] = z == 0.0 ? 0.0 : z;
    }
  }
  CourseHole hole{.number = 1, .par = 3, .stroke_index = 1};
  hole.tees = {{"practice", {-10, 0}}};
  hole.pin_m = Vector2d(0, 0);
  hole.green_stimp_ft = stimp_ft;
  c.holes = {hole};
  c.areas.push_back({Terrain::kFringe, 1, Rect(-27, -27, 27, 27)});
  c.areas.push_back({Terrain::kGreen, 1, Rect(-25, -25, 25, 25)});
  if (absl::Status s = ValidateCourse(c); !s.ok()) return s;
  return c;
}

std::span<const std::string_view> BuiltinCourseNames() {
  static constexpr std::string_view kNames[] = {"sportsim_links", "practice", "range"};
  return kNames;
}

absl::StatusOr<std::shared_ptr<const Course>> BuiltinCourse(std::string_view name) {
  static std::once_flag once;
  static std::shared_ptr<const Course> links, practice, range;
  std::call_once(once, [] {
    links = std::make_shared<const Course>(MakeLinks());
    practice = std::make_shared<const Course>(*PracticeCourse(10.0, 0.0, 0.0));
    range = std::make_shared<const Course>(MakeRange());
  });
  if (name == "sportsim_links") return links;
  if (name == "practice") return practice;
  if (name == "range") return range;
  return absl::NotFoundError(
      "course: not a built-in course (known: sportsim_links, practice, range)");
}

}  // namespace sportsim::golf
