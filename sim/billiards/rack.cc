#include "sim/billiards/rack.h"

#include <array>
#include <cmath>
#include <random>
#include <string>

#include "absl/strings/str_format.h"
#include "sim/billiards/cue.h"
#include "sim/core/check.h"
#include "sim/core/units.h"

namespace sportsim::billiards {
namespace {

constexpr std::array<std::string_view, 7> kRacks = {"empty",   "8ball",         "9ball",
                                                    "10ball",  "snooker",       "three-cushion",
                                                    "chapter19"};

Ball At(std::string id, double x, double y, double radius) {
  Ball b;
  b.id = std::move(id);
  b.r = Eigen::Vector3d(x, y, radius);
  return b;
}

// Triangle rows pointing to -x from the apex at `apex`: row k has k+1 balls. `spacing` is the
// distance between neighbouring centres.
Eigen::Vector2d TriangleSpot(Eigen::Vector2d apex, int row, int col, double spacing) {
  const double dx = spacing * std::sqrt(3.0) / 2.0;
  return apex + Eigen::Vector2d(row * dx, (col - 0.5 * row) * spacing);
}

}  // namespace

std::span<const std::string_view> RackNames() { return kRacks; }

absl::StatusOr<std::vector<Ball>> MakeRack(std::string_view name, const TableModel& model,
                                           double jitter_m, uint64_t seed) {
  if (absl::Status s = CheckFiniteInRange("jitter_m", jitter_m, 0, false, kMaxRackJitterM, false); !s.ok()) {
    return s;
  }
  const double radius = model.radius();
  const double d = 2.0 * radius;
  const double spacing = d + jitter_m;
  const double length = model.spec().length_m;
  const bool bounded = model.spec().bounded;
  // Head spot and foot spot a quarter of the length from each end; the break comes from the
  // head end (-x).
  const Eigen::Vector2d head(-0.25 * length, 0.0);
  const Eigen::Vector2d foot(0.25 * length, 0.0);
  std::vector<Ball> balls;
  if (name == "empty") {
    // No balls; place them with explicit positions.
  } else if (name == "8ball" || name == "9ball" || name == "10ball") {
    if (!bounded) return absl::InvalidArgumentError("rack " + std::string(name) + " needs a table with cushions");
    balls.push_back(At("cue", head.x(), head.y(), radius));
    if (name == "8ball") {
      // Apex ball on the foot spot, the 8 in the middle of the third row, a stripe and a solid
      // in the two back corners (WPA 8-ball rack: one of each group in the corners); the rest
      // in a fixed mixed order.
      const std::array<int, 15> order = {1, 9, 2, 10, 8, 3, 11, 4, 12, 5, 13, 6, 14, 15, 7};
      int k = 0;
      for (int row = 0; row < 5; ++row) {
        for (int col = 0; col <= row; ++col) {
          const Eigen::Vector2d p = TriangleSpot(foot, row, col, spacing);
          balls.push_back(At(std::to_string(order[k++]), p.x(), p.y(), radius));
        }
      }
    } else if (name == "10ball") {
      // WPA 10-ball: a triangle of four rows, the 1 on the foot spot (the apex), the 10 in the
      // centre of the third row, the rest in a fixed order.
      const std::array<int, 10> order = {1, 2, 3, 4, 10, 5, 6, 7, 8, 9};
      int k = 0;
      for (int row = 0; row < 4; ++row) {
        for (int col = 0; col <= row; ++col) {
          const Eigen::Vector2d p = TriangleSpot(foot, row, col, spacing);
          balls.push_back(At(std::to_string(order[k++]), p.x(), p.y(), radius));
        }
      }
    } else {
      // Diamond: rows of 1, 2, 3, 2, 1; the 1 on the foot spot, the 9 in the centre.
      const std::array<int, 5> row_size = {1, 2, 3, 2, 1};
      const std::array<int, 9> order = {1, 2, 3, 4, 9, 5, 6, 7, 8};
      const double dx = spacing * std::sqrt(3.0) / 2.0;
      int k = 0;
      for (int row = 0; row < 5; ++row) {
        for (int col = 0; col < row_size[row]; ++col) {
          const double y = (col - 0.5 * (row_size[row] - 1)) * spacing;
          balls.push_back(At(std::to_string(order[k++]), foot.x() + row * dx, y, radius));
        }
      }
    }
  } else if (name == "snooker") {
    if (!bounded || length < 3.0) return absl::InvalidArgumentError("rack snooker needs the snooker table");
    // WPBSA spots: baulk line 737 mm from the baulk cushion, the D of radius 292 mm; blue at the
    // centre, pink midway to the top cushion, black 324 mm from it. Looking up the table (+x)
    // from baulk, yellow is on the right (-y) of the D and green on the left.
    const double baulk = -0.5 * length + 0.737;
    const double pink = 0.25 * length;
    const double black = 0.5 * length - 0.324;
    balls.push_back(At("cue", baulk - 0.1, -0.15, radius));
    int k = 1;
    const Eigen::Vector2d apex(pink + spacing + 1e-3, 0.0);  // 1 mm behind the pink
    for (int row = 0; row < 5; ++row) {
      for (int col = 0; col <= row; ++col) {
        const Eigen::Vector2d p = TriangleSpot(apex, row, col, spacing);
        balls.push_back(At(absl::StrFormat("red%d", k++), p.x(), p.y(), radius));
      }
    }
    balls.push_back(At("yellow", baulk, -0.292, radius));
    balls.push_back(At("green", baulk, 0.292, radius));
    balls.push_back(At("brown", baulk, 0.0, radius));
    balls.push_back(At("blue", 0.0, 0.0, radius));
    balls.push_back(At("pink", pink, 0.0, radius));
    balls.push_back(At("black", black, 0.0, radius));
  } else if (name == "three-cushion") {
    if (!bounded) return absl::InvalidArgumentError("rack three-cushion needs a table with cushions");
    // Opening position: red on the foot spot, yellow on the head spot, the cue ball on the head
    // string 18.25 cm to the side of the yellow.
    balls.push_back(At("cue", head.x(), -0.1825, radius));
    balls.push_back(At("yellow", head.x(), 0.0, radius));
    balls.push_back(At("red", foot.x(), 0.0, radius));
  } else if (name == "chapter19") {
    // Bourg & Bywalec ch. 19: cue ball 50 diameters back, the 8-ball one diameter in front of
    // the pair of object balls at +/- 0.75 D.
    if (bounded && length < 52 * d) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "rack chapter19 needs a table at least %.2f m long (use the unbounded table)", 52 * d));
    }
    balls.push_back(At("cue", -50 * d, 0.0, radius));
    balls.push_back(At("8", -d, 0.0, radius));
    balls.push_back(At("1", 0.0, -0.75 * d, radius));
    balls.push_back(At("2", 0.0, 0.75 * d, radius));
  } else {
    return absl::InvalidArgumentError(absl::StrFormat(
        "rack must be one of empty, 8ball, 9ball, 10ball, snooker, three-cushion, chapter19; got \"%s\"",
        name));
  }
  // Seeded jitter of racked object balls (the cue ball and spotted balls stay put).
  if (jitter_m > 0 && (name == "8ball" || name == "9ball" || name == "10ball" || name == "snooker")) {
    std::mt19937_64 rng(seed);
    const auto uniform = [&rng]() { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
    const size_t last = name == "snooker" ? 16 : balls.size();
    for (size_t i = 1; i < last; ++i) {
      const double rad = 0.5 * jitter_m * std::sqrt(uniform());
      const double ang = kTwoPi * uniform();
      balls[i].r.x() += rad * std::cos(ang);
      balls[i].r.y() += rad * std::sin(ang);
    }
  }
  TableState check{.balls = balls};
  if (absl::Status s = ValidateLayout(model, check); !s.ok()) {
    return absl::InvalidArgumentError(
        absl::StrFormat("rack %s does not fit this table: %s", name, s.message()));
  }
  return balls;
}

}  // namespace sportsim::billiards
