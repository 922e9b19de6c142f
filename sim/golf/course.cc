#include "sim/golf/course.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <type_traits>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "sim/core/check.h"
#include "sim/core/quote.h"

namespace sportsim::golf {

namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr std::array<std::string_view, kTerrainCount> kTags = {
    "tee",    "fairway", "first_cut", "rough",        "bunker",
    "green",  "fringe",  "cartpath",  "water_hazard", "lateral_water_hazard",
    "out_of_bounds"};

// Limits (a course is a few square kilometres; these bound a hostile file's cost).
constexpr int kMaxGridSide = 4096;
constexpr int64_t kMaxGridPoints = int64_t{1} << 22;
constexpr size_t kMaxAreas = 100000;
constexpr size_t kMaxVertices = 100000;      // per polygon
constexpr size_t kMaxTotalVertices = 1000000;
constexpr int kMaxHoles = 36;
constexpr size_t kMaxTees = 16;
constexpr size_t kMaxLinePoints = 16;
constexpr size_t kMaxTextBytes = size_t{64} << 20;
// The steepest the terrain may be between neighbouring grid points: 100 % (45 deg). Turf
// steeper than that is a wall, which the ground model (a ball on a tangent plane) is not for.
constexpr double kMaxGridSlope = 1.0;

// absl::StrCat takes absl::string_view, a distinct type from std::string_view here: S passes a
// std::string_view on as one and anything else as it is.
template <typename T>
decltype(auto) S(const T& v) {
  if constexpr (std::is_same_v<T, std::string_view>) {
    return absl::string_view(v.data(), v.size());
  } else {
    return (v);
  }
}
std::string_view Std(absl::string_view v) { return std::string_view(v.data(), v.size()); }

std::string JoinTags() {
  std::string out;
  for (std::string_view t : kTags) absl::StrAppend(&out, out.empty() ? "" : ", ", S(t));
  return out;
}

// A user's token in an error: printable, at most 24 bytes, in single quotes.
std::string Q(std::string_view s) { return QuoteInput(s, 24, '\''); }

// Even-odd crossing test.
bool InPolygon(const std::vector<Vector2d>& poly, double x, double y) {
  bool in = false;
  const size_t n = poly.size();
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    const Vector2d& a = poly[i];
    const Vector2d& b = poly[j];
    if ((a.y() > y) != (b.y() > y)) {
      const double xc = a.x() + (y - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      if (x < xc) in = !in;
    }
  }
  return in;
}

double SegmentDistance(const Vector2d& p, const Vector2d& a, const Vector2d& b) {
  const Vector2d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

double EdgeDistance(const std::vector<Vector2d>& poly, const Vector2d& p) {
  double d = std::numeric_limits<double>::infinity();
  const size_t n = poly.size();
  for (size_t i = 0, j = n - 1; i < n; j = i++) d = std::min(d, SegmentDistance(p, poly[j], poly[i]));
  return d;
}

double SignedArea(const std::vector<Vector2d>& poly) {
  double a = 0.0;
  const size_t n = poly.size();
  for (size_t i = 0, j = n - 1; i < n; j = i++) {
    a += poly[j].x() * poly[i].y() - poly[i].x() * poly[j].y();
  }
  return 0.5 * a;
}

// Shortest round-trip text of a double.
std::string Num(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string Point(const Vector2d& p) { return absl::StrCat(Num(p.x()), ",", Num(p.y())); }

}  // namespace

std::string_view TerrainTag(Terrain t) { return kTags[static_cast<size_t>(t)]; }

std::optional<Terrain> TerrainFromTag(std::string_view tag) {
  for (size_t i = 0; i < kTags.size(); ++i) {
    if (kTags[i] == tag) return static_cast<Terrain>(i);
  }
  return std::nullopt;
}

// ---- Heightfield ----

bool Heightfield::Covers(double x, double y) const {
  return x >= x0_m && x <= x1_m() && y >= y0_m && y <= y1_m();
}

namespace {

// Catmull-Rom's cubic weights at t in [0, 1] for the samples at -1, 0, 1, 2, and their first
// and second derivatives in t.
struct CubicWeights {
  double w[4], d[4], dd[4];
  explicit CubicWeights(double t) {
    const double t2 = t * t, t3 = t2 * t;
    w[0] = 0.5 * (-t + 2 * t2 - t3);
    w[1] = 0.5 * (2 - 5 * t2 + 3 * t3);
    w[2] = 0.5 * (t + 4 * t2 - 3 * t3);
    w[3] = 0.5 * (-t2 + t3);
    d[0] = 0.5 * (-1 + 4 * t - 3 * t2);
    d[1] = 0.5 * (-10 * t + 9 * t2);
    d[2] = 0.5 * (1 + 8 * t - 9 * t2);
    d[3] = 0.5 * (-2 * t + 3 * t2);
    dd[0] = 0.5 * (4 - 6 * t);
    dd[1] = 0.5 * (-10 + 18 * t);
    dd[2] = 0.5 * (8 - 18 * t);
    dd[3] = 0.5 * (-2 + 6 * t);
  }
};

}  // namespace

double Heightfield::Z(int i, int j) const {
  // Beyond the grid, linear extrapolation from the edge (a plane stays a plane).
  if (i < 0) return 2 * Z(0, j) - Z(1, j);
  if (i >= columns) return 2 * Z(columns - 1, j) - Z(columns - 2, j);
  if (j < 0) return 2 * Z(i, 0) - Z(i, 1);
  if (j >= rows) return 2 * Z(i, rows - 1) - Z(i, rows - 2);
  return z_m[static_cast<size_t>(j) * columns + i];
}

void Heightfield::Sample(double x, double y, double* z, Eigen::Vector2d* gradient,
                         Eigen::Matrix2d* hessian) const {
  const double u = (x - x0_m) / spacing_m;
  const double v = (y - y0_m) / spacing_m;
  const int i = static_cast<int>(std::clamp(std::floor(u), 0.0, static_cast<double>(columns - 2)));
  const int j = static_cast<int>(std::clamp(std::floor(v), 0.0, static_cast<double>(rows - 2)));
  const CubicWeights wx(std::clamp(u - i, 0.0, 1.0)), wy(std::clamp(v - j, 0.0, 1.0));
  // The 4 x 4 samples around the cell: straight from the grid inside it, extended at its edges.
  double p16[4][4];
  if (i >= 1 && i + 2 < columns && j >= 1 && j + 2 < rows) {
    for (int b = 0; b < 4; ++b) {
      const double* row = &z_m[static_cast<size_t>(j - 1 + b) * columns + (i - 1)];
      for (int a = 0; a < 4; ++a) p16[b][a] = row[a];
    }
  } else {
    for (int b = 0; b < 4; ++b) {
      for (int a = 0; a < 4; ++a) p16[b][a] = Z(i - 1 + a, j - 1 + b);
    }
  }
  double h = 0, hx = 0, hy = 0, hxx = 0, hyy = 0, hxy = 0;
  for (int b = 0; b < 4; ++b) {
    double r = 0, rx = 0, rxx = 0;  // along x, in row j - 1 + b
    for (int a = 0; a < 4; ++a) {
      const double p = p16[b][a];
      r += wx.w[a] * p;
      rx += wx.d[a] * p;
      rxx += wx.dd[a] * p;
    }
    h += wy.w[b] * r;
    hx += wy.w[b] * rx;
    hxx += wy.w[b] * rxx;
    hy += wy.d[b] * r;
    hyy += wy.dd[b] * r;
    hxy += wy.d[b] * rx;
  }
  const double s = spacing_m;
  if (z != nullptr) *z = h;
  if (gradient != nullptr) *gradient = Eigen::Vector2d(hx / s, hy / s);
  if (hessian != nullptr) {
    *hessian << hxx / (s * s), hxy / (s * s), hxy / (s * s), hyy / (s * s);
  }
}

void Heightfield::At(double x, double y, double* z, Vector3d* normal) const {
  Eigen::Vector2d grad;
  Sample(x, y, z, normal != nullptr ? &grad : nullptr, nullptr);
  if (normal != nullptr) *normal = Vector3d(-grad.x(), -grad.y(), 1.0).normalized();
}

double Heightfield::HeightAt(double x, double y) const {
  double z = 0.0;
  At(x, y, &z, nullptr);
  return z;
}

Vector3d Heightfield::NormalAt(double x, double y) const {
  Vector3d n;
  At(x, y, nullptr, &n);
  return n;
}

// ---- Holes and queries ----

double CourseHole::length_m() const {
  if (tees.empty() || !pin_m) return 0.0;
  double length = 0.0;
  Vector2d at = tees.front().position_m;
  for (const Vector2d& p : line_m) {
    length += (p - at).norm();
    at = p;
  }
  return length + (*pin_m - at).norm();
}

const CourseHole* Course::Hole(int number) const {
  if (number < 1 || number > static_cast<int>(holes.size())) return nullptr;
  return &holes[static_cast<size_t>(number - 1)];
}

CourseRating Course::RatingOf(std::string_view tee) const {
  std::string_view want = tee;
  if (want.empty() && !holes.empty() && !holes.front().tees.empty()) want = holes.front().tees.front().name;
  for (const CourseRating& r : ratings) {
    if (r.tee == want) return r;
  }
  return CourseRating{std::string(want), 113.0, static_cast<double>(Par())};
}

int Course::Par() const {
  int par = 0;
  for (const CourseHole& h : holes) par += h.par;
  return par;
}

bool Course::InBounds(double x, double y) const {
  if (!terrain.Covers(x, y)) return false;
  return boundary.empty() || InPolygon(boundary, x, y);
}

namespace {

// The surface queries, over every area or only those whose bounding box (grown by `margin`)
// holds the point. One implementation for Course (no boxes) and CourseIndex (boxes).
struct Scan {
  const Course& c;
  const std::vector<Eigen::AlignedBox2d>* boxes;

  bool Near(size_t i, const Vector2d& p, double margin) const {
    if (boxes == nullptr) return true;
    const Eigen::AlignedBox2d& b = (*boxes)[i];
    return p.x() >= b.min().x() - margin && p.x() <= b.max().x() + margin &&
           p.y() >= b.min().y() - margin && p.y() <= b.max().y() + margin;
  }

  Course::Spot SurfaceAt(double x, double y) const {
    if (!c.InBounds(x, y)) return Course::Spot{Terrain::kOutOfBounds, 0};
    const Vector2d p(x, y);
    for (size_t i = c.areas.size(); i-- > 0;) {
      if (Near(i, p, 0.0) && InPolygon(c.areas[i].polygon, x, y)) {
        return Course::Spot{c.areas[i].terrain, c.areas[i].hole};
      }
    }
    return Course::Spot{c.base, 0};
  }

  // Within `limit` of an edge of the class's areas (the distance, or infinity beyond it).
  double DistanceToEdge(double x, double y, Terrain t, double limit) const {
    double d = std::numeric_limits<double>::infinity();
    const Vector2d p(x, y);
    for (size_t i = 0; i < c.areas.size(); ++i) {
      if (c.areas[i].terrain == t && Near(i, p, limit)) {
        d = std::min(d, EdgeDistance(c.areas[i].polygon, p));
      }
    }
    return d;
  }

  Terrain LieAt(double x, double y, double r) const {
    const Course::Spot spot = SurfaceAt(x, y);
    const Vector2d p(x, y);
    // Out of bounds only when all of the ball is (Rule 18.2a): its centre out and at least r
    // from every edge of the out-of-bounds region.
    if (spot.terrain == Terrain::kOutOfBounds) {
      if (!c.terrain.Covers(x, y)) return Terrain::kOutOfBounds;  // off the map
      double d = DistanceToEdge(x, y, Terrain::kOutOfBounds, r);
      if (!c.boundary.empty()) d = std::min(d, EdgeDistance(c.boundary, p));
      if (d >= r) return Terrain::kOutOfBounds;
    }
    // Any part in one of the specified areas (Rule 2.2c's order when in two: penalty area,
    // bunker, putting green).
    for (Terrain t : {Terrain::kLateralWaterHazard, Terrain::kWaterHazard, Terrain::kBunker,
                      Terrain::kGreen}) {
      if (spot.terrain == t || DistanceToEdge(x, y, t, r) < r) return t;
    }
    if (spot.terrain != Terrain::kOutOfBounds) return spot.terrain;
    // Partly out of bounds: in bounds, on what lies under it inside.
    for (size_t i = c.areas.size(); i-- > 0;) {
      if (c.areas[i].terrain != Terrain::kOutOfBounds && Near(i, p, 0.0) &&
          InPolygon(c.areas[i].polygon, x, y)) {
        return c.areas[i].terrain;
      }
    }
    return c.base;
  }
};

}  // namespace

Course::Spot Course::SurfaceAt(double x, double y) const { return Scan{*this, nullptr}.SurfaceAt(x, y); }

double Course::DistanceToEdge(double x, double y, Terrain t) const {
  return Scan{*this, nullptr}.DistanceToEdge(x, y, t, std::numeric_limits<double>::infinity());
}

Terrain Course::LieAt(double x, double y, double r) const { return Scan{*this, nullptr}.LieAt(x, y, r); }

CourseIndex::CourseIndex(const Course& course) : course_(course) {
  boxes_.reserve(course.areas.size());
  for (const CourseArea& a : course.areas) {
    Eigen::AlignedBox2d box;
    for (const Vector2d& p : a.polygon) box.extend(p);
    boxes_.push_back(box);
  }
}

Course::Spot CourseIndex::SurfaceAt(double x, double y) const {
  return Scan{course_, &boxes_}.SurfaceAt(x, y);
}

Terrain CourseIndex::LieAt(double x, double y, double r) const {
  return Scan{course_, &boxes_}.LieAt(x, y, r);
}

Surface Course::Constants(Spot spot) const {
  if (const auto& o = surfaces[static_cast<size_t>(spot.terrain)]; o.has_value()) return *o;
  const CourseHole* hole = Hole(spot.hole);
  auto named = [](std::string_view surface) { return *SurfaceByName(surface); };
  switch (spot.terrain) {
    case Terrain::kGreen:
      return *GreenOfStimp(hole != nullptr ? hole->green_stimp_ft : 10.0);
    case Terrain::kFairway:
      return named(hole != nullptr ? hole->fairway : "fairway");
    case Terrain::kTee: return named("fairway");
    case Terrain::kFirstCut: return named("first_cut");
    case Terrain::kBunker: return named("bunker");
    case Terrain::kFringe: return named("fringe");
    case Terrain::kCartpath: return named("cartpath");
    case Terrain::kRough:
    case Terrain::kWaterHazard:
    case Terrain::kLateralWaterHazard:
    case Terrain::kOutOfBounds: return named("rough");
  }
  return named("rough");
}

// ---- Validation ----

absl::Status ValidateCourse(const Course& c) {
  auto bad = [](const auto&... parts) { return absl::InvalidArgumentError(absl::StrCat(S(parts)...)); };
  if (c.name.empty() || c.name.size() > 40 ||
      !std::all_of(c.name.begin(), c.name.end(), [](char ch) {
        return (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_';
      })) {
    return bad("name: ", Q(c.name), " must be 1-40 characters of a-z, 0-9 and _");
  }
  if (c.description.size() > 200 ||
      !std::all_of(c.description.begin(), c.description.end(),
                   [](char ch) { return static_cast<unsigned char>(ch) >= 0x20; })) {
    return bad("description: at most 200 characters on one line");
  }
  const Heightfield& h = c.terrain;
  if (absl::Status s = CheckFieldsInRange({{"heightfield.x0_m", h.x0_m, -1e6, false, 1e6},
                                           {"heightfield.y0_m", h.y0_m, -1e6, false, 1e6},
                                           {"heightfield.spacing_m", h.spacing_m, 0.1, false, 100}});
      !s.ok()) {
    return s;
  }
  if (h.columns < 2 || h.columns > kMaxGridSide || h.rows < 2 || h.rows > kMaxGridSide ||
      int64_t{h.columns} * h.rows > kMaxGridPoints) {
    return bad(absl::StrFormat(
        "heightfield: %d columns by %d rows; each must be in [2, %d], at most %d points in all",
        h.columns, h.rows, kMaxGridSide, kMaxGridPoints));
  }
  if (h.z_m.size() != static_cast<size_t>(h.columns) * static_cast<size_t>(h.rows)) {
    return bad(absl::StrFormat("heightfield: %d heights for %d columns by %d rows", h.z_m.size(),
                               h.columns, h.rows));
  }
  for (int j = 0; j < h.rows; ++j) {
    for (int i = 0; i < h.columns; ++i) {
      const double z = h.z_m[static_cast<size_t>(j) * h.columns + i];
      if (!std::isfinite(z) || z < -1000 || z > 10000) {
        return bad(absl::StrFormat(
            "heightfield: the height at row %d, column %d must be finite and in [-1000, 10000] m, "
            "got %g (a heightfield may have no holes)",
            j, i, z));
      }
      for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{0, 1}}) {
        if (i + di >= h.columns || j + dj >= h.rows) continue;
        const double dz = h.z_m[static_cast<size_t>(j + dj) * h.columns + i + di] - z;
        if (std::abs(dz) > kMaxGridSlope * h.spacing_m) {
          return bad(absl::StrFormat(
              "heightfield: from row %d, column %d to its %s neighbour the ground rises %g m "
              "in %g m, steeper than %g %%",
              j, i, di == 1 ? "east" : "north", dz, h.spacing_m, 100 * kMaxGridSlope));
        }
      }
    }
  }
  auto inside = [&](const Vector2d& p) { return std::isfinite(p.x()) && std::isfinite(p.y()) && h.Covers(p.x(), p.y()); };
  auto where = [](const Vector2d& p) { return absl::StrFormat("(%g, %g)", p.x(), p.y()); };
  const std::string extent = absl::StrFormat("the heightfield's [%g, %g] x [%g, %g] m", h.x0_m,
                                             h.x1_m(), h.y0_m, h.y1_m());
  auto check_polygon = [&](const std::string& what, const std::vector<Vector2d>& poly) {
    if (poly.size() < 3 || poly.size() > kMaxVertices) {
      return bad(what, ": ", poly.size(), " vertices; a polygon has 3 to ", kMaxVertices);
    }
    for (size_t i = 0; i < poly.size(); ++i) {
      if (!inside(poly[i])) {
        return bad(what, ": vertex ", i + 1, " ", where(poly[i]), " is outside ", extent);
      }
    }
    if (!(std::abs(SignedArea(poly)) > 0.0)) return bad(what, ": the polygon has no area");
    return absl::OkStatus();
  };
  if (!c.boundary.empty()) {
    if (absl::Status s = check_polygon("boundary", c.boundary); !s.ok()) return s;
  }
  if (c.areas.size() > kMaxAreas) return bad("areas: more than ", kMaxAreas);
  size_t total = c.boundary.size();
  for (size_t a = 0; a < c.areas.size(); ++a) {
    const CourseArea& area = c.areas[a];
    const std::string what = absl::StrCat("area ", a + 1, " (golf=", S(TerrainTag(area.terrain)), ")");
    if (static_cast<size_t>(area.terrain) >= kTags.size()) return bad("area ", a + 1, ": bad class");
    if (absl::Status s = check_polygon(what, area.polygon); !s.ok()) return s;
    total += area.polygon.size();
    if (total > kMaxTotalVertices) return bad("areas: more than ", kMaxTotalVertices, " vertices in all");
    if (area.hole < 0 || area.hole > static_cast<int>(c.holes.size())) {
      return bad(what, ": ref=", area.hole, " names no hole (the course has ", c.holes.size(), ")");
    }
  }
  if (c.base != Terrain::kRough && c.base != Terrain::kFirstCut && c.base != Terrain::kFairway) {
    return bad("base: golf=", TerrainTag(c.base), " cannot be the base; rough, first_cut or fairway");
  }
  if (c.holes.empty() || c.holes.size() > kMaxHoles) {
    return bad("holes: ", c.holes.size(), "; a course has 1 to ", kMaxHoles);
  }
  std::set<std::string> rated;
  for (const CourseRating& r : c.ratings) {
    const std::string what = absl::StrCat("rating of tee ", Q(r.tee));
    bool known = false;
    for (const CourseHole& hole : c.holes) {
      for (const CourseTee& tee : hole.tees) known = known || tee.name == r.tee;
    }
    if (!known) return bad(what, ": no hole has a tee of that name");
    if (!rated.insert(r.tee).second) return bad(what, ": given twice");
    if (!(r.slope >= 55.0 && r.slope <= 155.0)) {
      return bad(what, ": slope must be in [55, 155] (World Handicap System), got ", r.slope);
    }
    const double par = c.Par();
    if (!(r.course_rating > 0.5 * par && r.course_rating < 1.5 * par)) {
      return bad(what, ": course_rating must be between half and one and a half times the par (",
                 par, "), got ", r.course_rating);
    }
  }
  std::set<int> indexes;
  for (size_t k = 0; k < c.holes.size(); ++k) {
    const CourseHole& hole = c.holes[k];
    const std::string what = absl::StrCat("hole ", k + 1);
    if (hole.number != static_cast<int>(k) + 1) {
      return bad(what, ": numbered ", hole.number, "; holes are numbered 1, 2, ... in order");
    }
    if (hole.par < 3 || hole.par > 6) return bad(what, ": par must be in [3, 6], got ", hole.par);
    if (hole.stroke_index < 1 || hole.stroke_index > static_cast<int>(c.holes.size()) ||
        !indexes.insert(hole.stroke_index).second) {
      return bad(what, ": handicap (stroke index) ", hole.stroke_index,
                 " must be in [1, ", c.holes.size(), "] and used once");
    }
    if (absl::Status s = CheckFiniteInRange(what + ": green_stimp_ft", hole.green_stimp_ft, 1,
                                            false, 20, false);
        !s.ok()) {
      return s;
    }
    if (hole.fairway != "fairway_firm" && hole.fairway != "fairway" &&
        hole.fairway != "fairway_soft") {
      return bad(what, ": fairway ", Q(hole.fairway), " must be fairway_firm, fairway or fairway_soft");
    }
    if (hole.wind) {
      if (absl::Status s = ValidateWind(*hole.wind); !s.ok()) return bad(what, ": wind ", s.message());
    }
    if (!hole.pin_m) return bad(what, ": no pin (golf=pin)");
    if (!inside(*hole.pin_m)) return bad(what, ": pin ", where(*hole.pin_m), " is outside ", extent);
    if (const Course::Spot at = c.SurfaceAt(hole.pin_m->x(), hole.pin_m->y());
        at.terrain != Terrain::kGreen) {
      return bad(what, ": pin ", where(*hole.pin_m), " is not on a green (it is on ",
                 TerrainTag(at.terrain), ")");
    }
    if (hole.tees.empty() || hole.tees.size() > kMaxTees) {
      return bad(what, ": ", hole.tees.size(), " tees; a hole has 1 to ", kMaxTees);
    }
    std::set<std::string> names;
    for (const CourseTee& tee : hole.tees) {
      const std::string tw = absl::StrCat(what, ": tee ", Q(tee.name));
      if (tee.name.empty() || tee.name.size() > 24 ||
          !std::all_of(tee.name.begin(), tee.name.end(), [](char ch) {
            return (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_';
          })) {
        return bad(tw, ": a tee's name is 1-24 characters of a-z, 0-9 and _");
      }
      if (!names.insert(tee.name).second) return bad(tw, ": named twice");
      if (!inside(tee.position_m)) return bad(tw, ": ", where(tee.position_m), " is outside ", extent);
      const Terrain lie = c.SurfaceAt(tee.position_m.x(), tee.position_m.y()).terrain;
      if (lie == Terrain::kOutOfBounds || IsPenaltyArea(lie)) {
        return bad(tw, ": ", where(tee.position_m), " is in golf=", TerrainTag(lie));
      }
    }
    if (hole.line_m.size() > kMaxLinePoints) {
      return bad(what, ": line has ", hole.line_m.size(), " points; at most ", kMaxLinePoints);
    }
    for (const Vector2d& p : hole.line_m) {
      if (!inside(p)) return bad(what, ": line point ", where(p), " is outside ", extent);
    }
  }
  if (absl::Status s = ComputeAirProperties(c.air).status(); !s.ok()) return bad("air: ", s.message());
  if (absl::Status s = ValidateWind(c.wind); !s.ok()) return bad("wind: ", s.message());
  for (size_t t = 0; t < c.surfaces.size(); ++t) {
    if (!c.surfaces[t]) continue;
    if (absl::Status s = ValidateSurface(*c.surfaces[t]); !s.ok()) {
      return bad("surface golf=", kTags[t], ": ", s.message());
    }
  }
  return absl::OkStatus();
}

// ---- The text format ----

namespace {

// One line: its element, key=value tags, x,y points and plain words, in order.
struct Line {
  int number = 0;
  std::string_view element;
  std::vector<std::pair<std::string_view, std::string_view>> tags;
  std::vector<std::string_view> points;
  std::vector<std::string_view> words;
  std::string_view rest;  // the text after the element (description)
};

class Parser {
 public:
  explicit Parser(std::string_view text) : text_(text) {}
  absl::StatusOr<Course> Parse();

 private:
  template <typename... A>
  absl::Status Bad(const Line& line, const A&... parts) const {
    // The element as written when it is printable and short (all known ones are), else quoted.
    const bool plain = line.element.size() <= 24 &&
                       std::all_of(line.element.begin(), line.element.end(), [](char ch) {
                         return ch >= 0x21 && ch < 0x7f && ch != '\'';
                       });
    return absl::InvalidArgumentError(absl::StrCat("line ", line.number, ": ",
                                                   plain ? std::string(line.element) : Q(line.element),
                                                   ": ", S(parts)...));
  }
  absl::StatusOr<double> Number(const Line& line, std::string_view key, std::string_view v) const {
    double d = 0.0;
    const auto r = std::from_chars(v.data(), v.data() + v.size(), d);
    if (r.ec != std::errc() || r.ptr != v.data() + v.size() || !std::isfinite(d)) {
      return Bad(line, key, ": ", Q(v), " is not a finite number");
    }
    return d;
  }
  absl::StatusOr<int> Integer(const Line& line, std::string_view key, std::string_view v) const {
    int i = 0;
    const auto r = std::from_chars(v.data(), v.data() + v.size(), i);
    if (r.ec != std::errc() || r.ptr != v.data() + v.size()) {
      return Bad(line, key, ": ", Q(v), " is not an integer");
    }
    return i;
  }
  absl::StatusOr<std::vector<Vector2d>> Points(const Line& line) const;
  // The tags of a line as a map, refusing unknown and repeated keys.
  absl::StatusOr<std::map<std::string_view, std::string_view>> Tags(
      const Line& line, std::initializer_list<std::string_view> known) const;
  absl::StatusOr<CourseHole*> HoleOf(const Line& line, std::string_view ref);

  std::string_view text_;
  Course course_;
};

absl::StatusOr<std::vector<Vector2d>> Parser::Points(const Line& line) const {
  std::vector<Vector2d> out;
  out.reserve(line.points.size());
  for (std::string_view p : line.points) {
    const size_t comma = p.find(',');
    auto x = Number(line, "x", p.substr(0, comma));
    if (!x.ok()) return x.status();
    auto y = Number(line, "y", p.substr(comma + 1));
    if (!y.ok()) return y.status();
    out.emplace_back(*x, *y);
  }
  return out;
}

absl::StatusOr<std::map<std::string_view, std::string_view>> Parser::Tags(
    const Line& line, std::initializer_list<std::string_view> known) const {
  std::map<std::string_view, std::string_view> out;
  for (const auto& [k, v] : line.tags) {
    if (std::find(known.begin(), known.end(), k) == known.end()) {
      std::string names;
      for (std::string_view n : known) absl::StrAppend(&names, names.empty() ? "" : ", ", S(n));
      return Bad(line, "unknown key ", Q(k), " (known: ", names, ")");
    }
    if (!out.emplace(k, v).second) return Bad(line, "key ", Q(k), " given twice");
  }
  if (!line.words.empty()) return Bad(line, "unexpected ", Q(line.words.front()));
  return out;
}

absl::StatusOr<CourseHole*> Parser::HoleOf(const Line& line, std::string_view ref) {
  if (ref.empty()) return Bad(line, "ref (the hole's number) is required");
  auto n = Integer(line, "ref", ref);
  if (!n.ok()) return n.status();
  if (*n < 1 || *n > static_cast<int>(course_.holes.size())) {
    return Bad(line, "ref=", *n, " names no hole declared above (", course_.holes.size(),
               " so far)");
  }
  return &course_.holes[static_cast<size_t>(*n - 1)];
}

absl::StatusOr<Course> Parser::Parse() {
  if (text_.size() > kMaxTextBytes) {
    return absl::InvalidArgumentError(
        absl::StrCat("course: ", text_.size(), " bytes; at most ", kMaxTextBytes));
  }
  bool header = false, have_course = false, have_grid = false;
  int z_rows = 0;
  int number = 0;
  for (absl::string_view raw : absl::StrSplit(S(text_), '\n')) {
    ++number;
    std::string_view s = Std(absl::StripAsciiWhitespace(raw));
    if (s.empty() || s.front() == '#') continue;
    Line line;
    line.number = number;
    const size_t sp = s.find_first_of(" \t");
    line.element = s.substr(0, sp);
    line.rest = sp == std::string_view::npos ? std::string_view()
                                             : Std(absl::StripAsciiWhitespace(S(s.substr(sp))));
    if (!header) {
      if (line.element != "sportsim-course" || line.rest != "1") {
        return absl::InvalidArgumentError(absl::StrCat(
            "line ", number, ": a course file begins with the line 'sportsim-course 1'"));
      }
      header = true;
      continue;
    }
    if (line.element == "description") {
      course_.description = std::string(line.rest);
      continue;
    }
    for (absl::string_view piece : absl::StrSplit(S(line.rest), absl::ByAnyChar(" \t"), absl::SkipEmpty())) {
      const std::string_view tok = Std(piece);
      if (const size_t eq = tok.find('='); eq != std::string_view::npos) {
        line.tags.emplace_back(tok.substr(0, eq), tok.substr(eq + 1));
      } else if (tok.find(',') != std::string_view::npos) {
        line.points.push_back(tok);
      } else {
        line.words.push_back(tok);
      }
    }
    const std::string_view e = line.element;
    if (e == "z") {
      if (!have_grid) return Bad(line, "a row of heights before the heightfield line");
      if (z_rows >= course_.terrain.rows) return Bad(line, "more rows than the heightfield's ", course_.terrain.rows);
      if (!line.tags.empty() || !line.points.empty() ||
          line.words.size() != static_cast<size_t>(course_.terrain.columns)) {
        return Bad(line, "row ", z_rows, " has ", line.tags.size() + line.points.size() + line.words.size(),
                   " values for ", course_.terrain.columns, " columns");
      }
      for (size_t i = 0; i < line.words.size(); ++i) {
        auto z = Number(line, absl::StrCat("row ", z_rows, " column ", i), line.words[i]);
        if (!z.ok()) return z.status();
        course_.terrain.z_m.push_back(*z);
      }
      ++z_rows;
      continue;
    }
    if (e == "course") {
      auto tags = Tags(line, {"name", "base"});
      if (!tags.ok()) return tags.status();
      if (have_course) return Bad(line, "given twice");
      have_course = true;
      course_.name = std::string((*tags)["name"]);
      if (auto it = tags->find("base"); it != tags->end()) {
        auto t = TerrainFromTag(it->second);
        if (!t) return Bad(line, "base: ", Q(it->second), " is not a surface class");
        course_.base = *t;
      }
      continue;
    }
    if (!have_course) return Bad(line, "before the course line");
    if (e == "heightfield") {
      auto tags = Tags(line, {"x0", "y0", "spacing", "columns", "rows"});
      if (!tags.ok()) return tags.status();
      if (have_grid) return Bad(line, "given twice");
      for (std::string_view k : {"x0", "y0", "spacing", "columns", "rows"}) {
        if (!tags->contains(k)) return Bad(line, k, " is required");
      }
      Heightfield& h = course_.terrain;
      for (auto [k, out] : {std::pair{"x0", &h.x0_m}, {"y0", &h.y0_m}, {"spacing", &h.spacing_m}}) {
        auto v = Number(line, k, (*tags)[k]);
        if (!v.ok()) return v.status();
        *out = *v;
      }
      for (auto [k, out] : {std::pair{"columns", &h.columns}, {"rows", &h.rows}}) {
        auto v = Integer(line, k, (*tags)[k]);
        if (!v.ok()) return v.status();
        if (*v < 2 || *v > kMaxGridSide) return Bad(line, k, " must be in [2, ", kMaxGridSide, "], got ", *v);
        *out = *v;
      }
      if (int64_t{h.columns} * h.rows > kMaxGridPoints) {
        return Bad(line, h.columns, " x ", h.rows, " is more than ", kMaxGridPoints, " points");
      }
      h.z_m.reserve(static_cast<size_t>(h.columns) * h.rows);
      have_grid = true;
      continue;
    }
    if (e == "air") {
      auto tags = Tags(line, {"temperature_c", "pressure_pa", "relative_humidity", "altitude_m"});
      if (!tags.ok()) return tags.status();
      Atmosphere& a = course_.air;
      for (auto [k, out] : {std::pair{"temperature_c", &a.temperature_c}, {"pressure_pa", &a.pressure_pa},
                            {"relative_humidity", &a.relative_humidity}, {"altitude_m", &a.altitude_m}}) {
        if (auto it = tags->find(k); it != tags->end()) {
          auto v = Number(line, k, it->second);
          if (!v.ok()) return v.status();
          *out = *v;
        }
      }
      continue;
    }
    if (e == "wind") {
      auto tags = Tags(line, {"ref", "speed_mps", "toward_deg"});
      if (!tags.ok()) return tags.status();
      Wind* wind = &course_.wind;
      if (auto it = tags->find("ref"); it != tags->end()) {
        auto hole = HoleOf(line, it->second);
        if (!hole.ok()) return hole.status();
        (*hole)->wind = Wind{};
        wind = &*(*hole)->wind;
      }
      for (auto [k, out] : {std::pair{"speed_mps", &wind->speed_mps}, {"toward_deg", &wind->toward_deg}}) {
        if (auto it = tags->find(k); it != tags->end()) {
          auto v = Number(line, k, it->second);
          if (!v.ok()) return v.status();
          *out = *v;
        }
      }
      continue;
    }
    if (e == "surface") {
      auto tags = Tags(line, {"golf", "restitution_scale", "critical_angle_scale", "bounce_friction",
                              "sliding_friction", "rolling_resistance", "stimp_ft"});
      if (!tags.ok()) return tags.status();
      auto t = TerrainFromTag((*tags)["golf"]);
      if (!t) return Bad(line, "golf: ", Q((*tags)["golf"]), " is not a surface class");
      Surface surface = course_.Constants(Course::Spot{*t, 0});
      surface.name = std::string(TerrainTag(*t));
      for (auto [k, out] : {std::pair{"restitution_scale", &surface.restitution_scale},
                            {"critical_angle_scale", &surface.critical_angle_scale},
                            {"bounce_friction", &surface.bounce_friction},
                            {"sliding_friction", &surface.sliding_friction},
                            {"rolling_resistance", &surface.rolling_resistance}}) {
        if (auto it = tags->find(k); it != tags->end()) {
          auto v = Number(line, k, it->second);
          if (!v.ok()) return v.status();
          *out = *v;
        }
      }
      if (auto it = tags->find("stimp_ft"); it != tags->end()) {
        auto v = Number(line, "stimp_ft", it->second);
        if (!v.ok()) return v.status();
        auto rho = RollingResistanceFromStimp(*v);
        if (!rho.ok()) return Bad(line, rho.status().message());
        surface.rolling_resistance = *rho;
      }
      course_.surfaces[static_cast<size_t>(*t)] = surface;
      continue;
    }
    if (e == "boundary" || e == "area") {
      auto tags = e == "area" ? Tags(line, {"golf", "ref"}) : Tags(line, {});
      if (!tags.ok()) return tags.status();
      auto points = Points(line);
      if (!points.ok()) return points.status();
      if (points->size() < 3 || points->size() > kMaxVertices) {
        return Bad(line, points->size(), " points; a polygon has 3 to ", kMaxVertices);
      }
      if (e == "boundary") {
        if (!course_.boundary.empty()) return Bad(line, "given twice");
        course_.boundary = std::move(*points);
        continue;
      }
      if (course_.areas.size() >= kMaxAreas) return Bad(line, "more than ", kMaxAreas, " areas");
      CourseArea area;
      auto t = TerrainFromTag((*tags)["golf"]);
      if (!t) {
        return Bad(line, "golf: ", Q((*tags)["golf"]), " is not a surface class (",
                   JoinTags(), ")");
      }
      area.terrain = *t;
      if (auto it = tags->find("ref"); it != tags->end()) {
        auto hole = HoleOf(line, it->second);
        if (!hole.ok()) return hole.status();
        area.hole = (*hole)->number;
      }
      area.polygon = std::move(*points);
      course_.areas.push_back(std::move(area));
      continue;
    }
    if (e == "hole") {
      auto tags = Tags(line, {"ref", "par", "handicap", "stimp_ft", "fairway"});
      if (!tags.ok()) return tags.status();
      CourseHole hole;
      auto ref = Integer(line, "ref", (*tags)["ref"]);
      if (!ref.ok()) return ref.status();
      if (*ref != static_cast<int>(course_.holes.size()) + 1 || *ref > kMaxHoles) {
        return Bad(line, "ref=", *ref, ": holes are declared in order 1, 2, ... (at most ",
                   kMaxHoles, "); expected ", course_.holes.size() + 1);
      }
      hole.number = *ref;
      for (auto [k, out] : {std::pair{"par", &hole.par}, {"handicap", &hole.stroke_index}}) {
        if (!tags->contains(k)) return Bad(line, k, " is required");
        auto v = Integer(line, k, (*tags)[k]);
        if (!v.ok()) return v.status();
        *out = *v;
      }
      if (auto it = tags->find("stimp_ft"); it != tags->end()) {
        auto v = Number(line, "stimp_ft", it->second);
        if (!v.ok()) return v.status();
        hole.green_stimp_ft = *v;
      }
      if (auto it = tags->find("fairway"); it != tags->end()) hole.fairway = std::string(it->second);
      course_.holes.push_back(std::move(hole));
      continue;
    }
    if (e == "tee" || e == "pin" || e == "line") {
      auto tags = e == "tee" ? Tags(line, {"ref", "tee"}) : Tags(line, {"ref"});
      if (!tags.ok()) return tags.status();
      auto hole = HoleOf(line, (*tags)["ref"]);
      if (!hole.ok()) return hole.status();
      auto points = Points(line);
      if (!points.ok()) return points.status();
      if (e == "line") {
        if (points->empty() || points->size() > kMaxLinePoints) {
          return Bad(line, points->size(), " points; a line has 1 to ", kMaxLinePoints);
        }
        (*hole)->line_m = std::move(*points);
        continue;
      }
      if (points->size() != 1) return Bad(line, "one point x,y, got ", points->size());
      if (e == "pin") {
        if ((*hole)->pin_m) return Bad(line, "hole ", (*hole)->number, " has a pin already");
        (*hole)->pin_m = points->front();
        continue;
      }
      if ((*hole)->tees.size() >= kMaxTees) return Bad(line, "more than ", kMaxTees, " tees");
      std::string_view name = (*tags)["tee"];
      (*hole)->tees.push_back(CourseTee{std::string(name.empty() ? "default" : name), points->front()});
      continue;
    }
    if (e == "rating") {
      auto tags = Tags(line, {"tee", "slope", "course_rating"});
      if (!tags.ok()) return tags.status();
      CourseRating rating;
      rating.tee = std::string((*tags)["tee"]);
      for (auto [k, out] : {std::pair{"slope", &rating.slope}, {"course_rating", &rating.course_rating}}) {
        if (!tags->contains(k)) return Bad(line, k, " is required");
        auto v = Number(line, k, (*tags)[k]);
        if (!v.ok()) return v.status();
        *out = *v;
      }
      if (course_.ratings.size() >= kMaxTees) return Bad(line, "more than ", kMaxTees, " ratings");
      course_.ratings.push_back(std::move(rating));
      continue;
    }
    return Bad(line, "unknown element (course, description, air, wind, heightfield, z, surface, "
                     "boundary, area, hole, tee, pin, line, rating)");
  }
  if (!header) return absl::InvalidArgumentError("course: empty; it begins with 'sportsim-course 1'");
  if (!have_course) return absl::InvalidArgumentError("course: no course line");
  if (!have_grid) return absl::InvalidArgumentError("heightfield: missing");
  if (z_rows != course_.terrain.rows) {
    return absl::InvalidArgumentError(absl::StrCat("heightfield: ", z_rows, " rows of heights for ",
                                                   course_.terrain.rows, " rows"));
  }
  if (absl::Status s = ValidateCourse(course_); !s.ok()) return s;
  return std::move(course_);
}

}  // namespace

absl::StatusOr<Course> ParseCourse(std::string_view text) { return Parser(text).Parse(); }

std::string FormatCourse(const Course& c) {
  std::string out = "sportsim-course 1\n";
  absl::StrAppend(&out, "course name=", c.name, " base=", S(TerrainTag(c.base)), "\n");
  if (!c.description.empty()) absl::StrAppend(&out, "description ", c.description, "\n");
  absl::StrAppend(&out, "air temperature_c=", Num(c.air.temperature_c), " pressure_pa=",
                  Num(c.air.pressure_pa), " relative_humidity=", Num(c.air.relative_humidity),
                  " altitude_m=", Num(c.air.altitude_m), "\n");
  absl::StrAppend(&out, "wind speed_mps=", Num(c.wind.speed_mps), " toward_deg=",
                  Num(c.wind.toward_deg), "\n");
  for (size_t t = 0; t < c.surfaces.size(); ++t) {
    if (!c.surfaces[t]) continue;
    const Surface& s = *c.surfaces[t];
    absl::StrAppend(&out, "surface golf=", S(kTags[t]), " restitution_scale=", Num(s.restitution_scale),
                    " critical_angle_scale=", Num(s.critical_angle_scale), " bounce_friction=",
                    Num(s.bounce_friction), " sliding_friction=", Num(s.sliding_friction),
                    " rolling_resistance=", Num(s.rolling_resistance), "\n");
  }
  const Heightfield& h = c.terrain;
  absl::StrAppend(&out, "heightfield x0=", Num(h.x0_m), " y0=", Num(h.y0_m), " spacing=",
                  Num(h.spacing_m), " columns=", h.columns, " rows=", h.rows, "\n");
  for (int j = 0; j < h.rows; ++j) {
    out += "z";
    for (int i = 0; i < h.columns; ++i) {
      absl::StrAppend(&out, " ", Num(h.z_m[static_cast<size_t>(j) * h.columns + i]));
    }
    out += "\n";
  }
  for (const CourseHole& hole : c.holes) {
    absl::StrAppend(&out, "hole ref=", hole.number, " par=", hole.par, " handicap=",
                    hole.stroke_index, " stimp_ft=", Num(hole.green_stimp_ft), " fairway=",
                    hole.fairway, "\n");
    for (const CourseTee& tee : hole.tees) {
      absl::StrAppend(&out, "tee ref=", hole.number, " tee=", tee.name, " ", Point(tee.position_m), "\n");
    }
    if (hole.pin_m) absl::StrAppend(&out, "pin ref=", hole.number, " ", Point(*hole.pin_m), "\n");
    if (!hole.line_m.empty()) {
      absl::StrAppend(&out, "line ref=", hole.number);
      for (const Vector2d& p : hole.line_m) absl::StrAppend(&out, " ", Point(p));
      out += "\n";
    }
    if (hole.wind) {
      absl::StrAppend(&out, "wind ref=", hole.number, " speed_mps=", Num(hole.wind->speed_mps),
                      " toward_deg=", Num(hole.wind->toward_deg), "\n");
    }
  }
  for (const CourseRating& r : c.ratings) {
    absl::StrAppend(&out, "rating tee=", r.tee, " slope=", Num(r.slope), " course_rating=",
                    Num(r.course_rating), "\n");
  }
  if (!c.boundary.empty()) {
    out += "boundary";
    for (const Vector2d& p : c.boundary) absl::StrAppend(&out, " ", Point(p));
    out += "\n";
  }
  for (const CourseArea& a : c.areas) {
    absl::StrAppend(&out, "area golf=", S(TerrainTag(a.terrain)));
    if (a.hole != 0) absl::StrAppend(&out, " ref=", a.hole);
    for (const Vector2d& p : a.polygon) absl::StrAppend(&out, " ", Point(p));
    out += "\n";
  }
  return out;
}

}  // namespace sportsim::golf
