// Golf courses as data: terrain (a heightfield), surfaces (polygons named by OpenStreetMap's
// golf tags), holes (tees, pin, par, stroke index, the green's speed, the fairway's firmness),
// the air and the wind; a text format for them (docs/golf-courses.md), its loader with errors
// that name the line and the field, and the built-in courses.
//
// Frame: x east, y north, z up, metres; headings in degrees counter-clockwise from +x.
//
// Terrain: heights on a regular grid, interpolated by Catmull-Rom bicubic patches: the height
// and its slope are continuous everywhere (C1: a rolling ball meets no kinks), the curvature is
// continuous inside a cell and jumps at its edges; the patches pass through the samples and
// reproduce a plane exactly (beyond the grid's edge the samples are extended linearly).
//
// Surfaces: each area is a polygon with a class (golf=tee|fairway|rough|bunker|green|
// water_hazard|lateral_water_hazard|cartpath|out_of_bounds as OpenStreetMap tags them, and our
// first_cut and fringe, which OpenStreetMap has no tag for). Areas overlap in painter's order:
// at a point, the last listed area containing it decides; where none does, the course's base
// class (rough unless said). A polygon is closed implicitly; a self-crossing one counts by the
// even-odd rule. Outside the course's boundary (leisure=golf_course) is out of bounds, as are
// golf=out_of_bounds areas inside it.
//
// The lie of a ball for the Rules of Golf 2023 (LieAt) differs from the surface under its
// centre at edges: a ball is out of bounds only when all of it is (Rule 18.2a), and in a
// penalty area (17.1a), in a bunker (12.1) or on the putting green (13.1a) when any part of it
// touches one.
#ifndef SPORTSIM_SIM_GOLF_COURSE_H_
#define SPORTSIM_SIM_GOLF_COURSE_H_

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Dense>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "sim/golf/atmosphere.h"
#include "sim/golf/surface.h"

namespace sportsim::golf {

/// Surface classes of a course.
enum class Terrain : uint8_t {
  kTee,
  kFairway,
  kFirstCut,
  kRough,
  kBunker,
  kGreen,
  kFringe,
  kCartpath,
  kWaterHazard,         ///< a yellow penalty area
  kLateralWaterHazard,  ///< a red penalty area
  kOutOfBounds,
};
inline constexpr int kTerrainCount = 11;
/// The tag: "tee", "fairway", "first_cut", "rough", "bunker", "green", "fringe", "cartpath",
/// "water_hazard", "lateral_water_hazard", "out_of_bounds".
std::string_view TerrainTag(Terrain terrain);
std::optional<Terrain> TerrainFromTag(std::string_view tag);
inline bool IsPenaltyArea(Terrain t) {
  return t == Terrain::kWaterHazard || t == Terrain::kLateralWaterHazard;
}

/// Heights on a regular grid: z_m[row * columns + column] at (x0 + column s, y0 + row s).
struct Heightfield {
  double x0_m = 0.0, y0_m = 0.0;
  double spacing_m = 1.0;  ///< [0.1, 100]
  int columns = 2, rows = 2;  ///< each [2, 4096]; at most 4,194,304 points
  std::vector<double> z_m;    ///< finite, [-1000, 10000]

  double x1_m() const { return x0_m + spacing_m * (columns - 1); }
  double y1_m() const { return y0_m + spacing_m * (rows - 1); }
  bool Covers(double x, double y) const;
  /// The height; outside the grid, the nearest edge's.
  double HeightAt(double x, double y) const;
  /// The unit upward normal at (x, y) (the nearest edge's outside).
  Eigen::Vector3d NormalAt(double x, double y) const;
  /// HeightAt and NormalAt in one lookup.
  void At(double x, double y, double* z, Eigen::Vector3d* normal) const;
  /// The height, its gradient (dz/dx, dz/dy) and its Hessian at (x, y), each optional.
  void Sample(double x, double y, double* z, Eigen::Vector2d* gradient,
              Eigen::Matrix2d* hessian) const;

 private:
  double Z(int column, int row) const;  // a sample, extended linearly beyond the grid
};

/// An area of one surface class.
struct CourseArea {
  Terrain terrain = Terrain::kRough;
  /// The hole it belongs to (1-based; 0: none). A green takes its hole's Stimpmeter speed and a
  /// fairway its hole's firmness.
  int hole = 0;
  std::vector<Eigen::Vector2d> polygon;  ///< at least 3 vertices, at most 100,000
};

struct CourseTee {
  std::string name;  ///< as OpenStreetMap's tee=* (e.g. "white", "red"); unique in its hole
  Eigen::Vector2d position_m = Eigen::Vector2d::Zero();
};

/// A tee set's rating under the World Handicap System (the USGA/R&A course rating and slope,
/// OpenStreetMap has no tag for them): over the course's holes played from tees of that name.
struct CourseRating {
  std::string tee;             ///< the tees' name (tee=*)
  double slope = 113.0;        ///< [55, 155]; 113 is a course of standard difficulty
  double course_rating = 0.0;  ///< a scratch golfer's expected score over the course's holes
};

struct CourseHole {
  int number = 1;        ///< 1..holes, in order
  int par = 4;           ///< [3, 6]
  int stroke_index = 1;  ///< OpenStreetMap's handicap=*: 1..holes, each once
  std::vector<CourseTee> tees;  ///< at least one; the first is the default
  std::optional<Eigen::Vector2d> pin_m;  ///< the hole's position (golf=pin); required
  /// The line of play's turning points between the tee and the pin (golf=hole's way); may be
  /// empty (a straight hole).
  std::vector<Eigen::Vector2d> line_m;
  double green_stimp_ft = 10.0;  ///< [1, 20]
  std::string fairway = "fairway";  ///< fairway_firm | fairway | fairway_soft
  std::optional<Wind> wind;  ///< the hole's wind if it has its own (toward_deg: a heading)

  /// Along the line of play from the default tee through line_m to the pin (m).
  double length_m() const;
};

struct Course {
  std::string name;          ///< [a-z0-9_], 1-40 characters
  std::string description;   ///< at most 200 characters
  Heightfield terrain;
  /// The course's edge (leisure=golf_course); empty: the heightfield's rectangle. Inside the
  /// heightfield.
  std::vector<Eigen::Vector2d> boundary;
  std::vector<CourseArea> areas;   ///< painter's order (at most 100,000)
  Terrain base = Terrain::kRough;  ///< where no area is: rough, first_cut or fairway
  std::vector<CourseHole> holes;   ///< 1..36
  /// Tee sets' ratings (at most one per tee name); a tee set without one rates as standard
  /// (slope 113, course rating = the course's par).
  std::vector<CourseRating> ratings;
  Atmosphere air;
  /// The course's wind; toward_deg is a heading in the course frame (ccw from +x), not
  /// relative to a target line as in a flight.
  Wind wind;
  /// Per class, constants that replace the built-in surface's (surface golf=...).
  std::array<std::optional<Surface>, kTerrainCount> surfaces;

  const CourseHole* Hole(int number) const;
  /// The rating of the tees named `tee` ("" : each hole's first tee, rated as the first hole's
  /// first tee's name); standard (slope 113, rating = par) when it has none.
  CourseRating RatingOf(std::string_view tee) const;
  int Par() const;  ///< the holes' par
  /// The class and hole of the surface under (x, y) (painter's order, boundary, base).
  struct Spot {
    Terrain terrain = Terrain::kRough;
    int hole = 0;
  };
  Spot SurfaceAt(double x, double y) const;
  /// The ground constants of a spot: an override of the course, else the built-in surface of
  /// its class (a green at its hole's speed, a fairway at its hole's firmness; a tee as a
  /// fairway, a penalty area or out of bounds as rough).
  Surface Constants(Spot spot) const;
  /// The lie under the Rules (see above) of a ball of radius r whose centre is over (x, y).
  Terrain LieAt(double x, double y, double ball_radius_m) const;
  /// True when (x, y) is inside the boundary (or the heightfield when there is none).
  bool InBounds(double x, double y) const;
  /// The distance from (x, y) to the nearest edge of the class `terrain`'s areas (m); infinity
  /// when there are none.
  double DistanceToEdge(double x, double y, Terrain terrain) const;
};

/// The surface queries of a course sped up by each area's bounding box: the same answers as
/// Course::SurfaceAt and Course::LieAt. The course must outlive it and not change.
class CourseIndex {
 public:
  explicit CourseIndex(const Course& course);
  const Course& course() const { return course_; }
  Course::Spot SurfaceAt(double x, double y) const;
  Terrain LieAt(double x, double y, double ball_radius_m) const;

 private:
  const Course& course_;
  std::vector<Eigen::AlignedBox2d> boxes_;
};

/// Checks the whole course; InvalidArgument names the field (and the hole or area).
absl::Status ValidateCourse(const Course& course);

/// Parses the course text format (docs/golf-courses.md) and validates the result. Errors name
/// the line and the field. Inputs over 64 MiB are refused.
absl::StatusOr<Course> ParseCourse(std::string_view text);
/// The course in the text format; ParseCourse(FormatCourse(c)) == c, bit for bit.
std::string FormatCourse(const Course& course);

/// The built-in courses' names, the default first: "sportsim_links", "practice", "range".
std::span<const std::string_view> BuiltinCourseNames();
/// A built-in course by name (built once, shared); NotFound naming the known ones.
absl::StatusOr<std::shared_ptr<const Course>> BuiltinCourse(std::string_view name);

/// The practice green: a plane 60 m square falling at slope_pct toward slope_toward_deg, green
/// over its middle 50 m square at stimp_ft, a fringe band, rough beyond, the hole at the
/// origin, one tee ("practice") 10 m west of it.
absl::StatusOr<Course> PracticeCourse(double stimp_ft, double slope_pct, double slope_toward_deg);

}  // namespace sportsim::golf

#endif  // SPORTSIM_SIM_GOLF_COURSE_H_
