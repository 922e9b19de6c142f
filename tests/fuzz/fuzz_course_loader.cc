// Golf courses: the course text format's loader (sim/golf/course.h) on arbitrary bytes. A
// refusal must be INVALID_ARGUMENT with a short message without raw control characters; an
// accepted course must validate, write back to text that loads to the same text (bit for bit),
// and answer the terrain and surface queries with finite heights and unit normals at every
// pin, tee and polygon vertex and just outside the map.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "sim/golf/course.h"
#include "tests/fuzz/fuzz_util.h"

namespace g = sportsim::golf;

namespace {

void Probe(const g::Course& c, double x, double y) {
  double z = 0.0;
  Eigen::Vector3d n;
  c.terrain.At(x, y, &z, &n);
  FUZZ_CHECK(std::isfinite(z) && std::abs(n.norm() - 1.0) < 1e-9 && n.z() > 0.0,
             "terrain at (%g, %g): z %g, normal (%g, %g, %g)", x, y, z, n.x(), n.y(), n.z());
  const g::Course::Spot spot = c.SurfaceAt(x, y);
  FUZZ_CHECK(spot.hole >= 0 && spot.hole <= static_cast<int>(c.holes.size()), "spot hole %d",
             spot.hole);
  const g::Terrain lie = c.LieAt(x, y, 0.02135);
  FUZZ_CHECK(static_cast<int>(lie) < g::kTerrainCount, "lie %d", static_cast<int>(lie));
  FUZZ_CHECK(g::ValidateSurface(c.Constants(spot)).ok(), "constants of %s",
             std::string(g::TerrainTag(spot.terrain)).c_str());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const absl::StatusOr<g::Course> course = g::ParseCourse(text);
  if (!course.ok()) {
    const absl::Status& s = course.status();
    FUZZ_CHECK(s.code() == absl::StatusCode::kInvalidArgument, "code %d: %s",
               static_cast<int>(s.code()), std::string(s.message()).c_str());
    FUZZ_CHECK(s.message().size() < 400, "message of %zu bytes", s.message().size());
    for (char ch : s.message()) {
      FUZZ_CHECK(static_cast<unsigned char>(ch) >= 0x20 && ch != 0x7f,
                 "a control character in: %s", std::string(s.message()).c_str());
    }
    return 0;
  }
  const g::Course& c = *course;
  FUZZ_CHECK(g::ValidateCourse(c).ok(), "accepted but invalid: %s",
             std::string(g::ValidateCourse(c).message()).c_str());
  const std::string written = g::FormatCourse(c);
  const absl::StatusOr<g::Course> again = g::ParseCourse(written);
  FUZZ_CHECK(again.ok(), "its own text refused: %s",
             std::string(again.status().message()).c_str());
  if (again.ok()) {
    FUZZ_CHECK(g::FormatCourse(*again) == written, "the text does not round-trip");
  }
  for (const g::CourseHole& h : c.holes) {
    Probe(c, h.pin_m->x(), h.pin_m->y());
    for (const g::CourseTee& t : h.tees) Probe(c, t.position_m.x(), t.position_m.y());
    FUZZ_CHECK(std::isfinite(h.length_m()), "hole %d length", h.number);
  }
  for (const g::CourseArea& a : c.areas) {
    for (const Eigen::Vector2d& p : a.polygon) Probe(c, p.x(), p.y());
  }
  Probe(c, c.terrain.x0_m - 1.0, c.terrain.y0_m - 1.0);
  Probe(c, c.terrain.x1_m() + 1.0, c.terrain.y1_m() + 1.0);
  return 0;
}
