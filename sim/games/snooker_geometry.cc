#include "sim/games/snooker_geometry.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "absl/strings/str_format.h"
#include "sim/core/units.h"

namespace sportsim::games {
namespace {

using billiards::Ball;
using billiards::MotionState;
using billiards::TableState;
using Eigen::Vector2d;

// A ball whose centre is closer than 2R - this to the cue ball's path obstructs it (m): balls
// exactly touching the path's edge do not.
constexpr double kObstructionTolM = 1e-9;

// The cue ball's centre moving from `c` along unit `dir` for `s` metres sweeps a capsule of
// radius R; a ball at x touches it when x is within 2R of the segment.
bool PathClear(double radius, const Vector2d& c, const Vector2d& dir, double s,
               std::span<const Vector2d> obstacles) {
  const double lim = 2.0 * radius - kObstructionTolM;
  for (const Vector2d& x : obstacles) {
    const double t = std::clamp((x - c).dot(dir), 0.0, std::max(s, 0.0));
    if ((x - (c + t * dir)).norm() < lim) return false;
  }
  return true;
}

// The stroke at angle theta from the line of centres: the distance the cue ball's centre runs
// before it touches `on` (d cos(theta) - sqrt(4R^2 - d^2 sin^2(theta))) and the direction.
bool RayClear(double radius, const Vector2d& cue, const Vector2d& on, double theta,
              std::span<const Vector2d> obstacles) {
  const Vector2d delta = on - cue;
  const double d = delta.norm();
  const Vector2d u = delta / d;
  const double ct = std::cos(theta), st = std::sin(theta);
  const Vector2d dir(ct * u.x() - st * u.y(), st * u.x() + ct * u.y());
  const double disc = std::max(0.0, 4.0 * radius * radius - d * d * st * st);
  const double s = d * ct - std::sqrt(disc);
  return PathClear(radius, cue, dir, s, obstacles);
}

// Half-angle of the fan of strokes that reach `on`: asin(2R / d).
double EdgeAngle(double radius, double d) { return std::asin(std::min(1.0, 2.0 * radius / d)); }

bool OnCloth(const Ball& b) { return b.state != MotionState::kPocketed; }

// No ball on the cloth (other than the ones pocketed) within 2R + kTouchGapM of p.
bool SpotFree(const TableState& state, const Vector2d& p, double radius) {
  const double lim = 2.0 * radius + kTouchGapM;
  for (const Ball& b : state.balls) {
    if (!OnCloth(b)) continue;
    if ((b.r.head<2>() - p).norm() < lim) return false;
  }
  return true;
}

// The free position nearest `from` on the segment from + s dir, s in [0, s_max]; false if the
// whole segment is taken. Each ball blocks an open interval of s; the candidates are s = 0
// and the far end of every interval.
bool NearestFreeOnLine(const TableState& state, double radius, const Vector2d& from,
                       const Vector2d& dir, double s_max, Vector2d* out) {
  if (s_max < 0) return false;
  const double lim = 2.0 * radius + kTouchGapM;
  std::vector<double> candidates = {0.0};
  for (const Ball& b : state.balls) {
    if (!OnCloth(b)) continue;
    const Vector2d w = b.r.head<2>() - from;
    const double proj = w.dot(dir);
    const double perp2 = w.squaredNorm() - proj * proj;
    if (perp2 >= lim * lim) continue;
    const double half = std::sqrt(lim * lim - perp2);
    candidates.push_back(proj + half + 1e-9);
  }
  std::sort(candidates.begin(), candidates.end());
  for (double s : candidates) {
    if (s < 0 || s > s_max) continue;
    const Vector2d p = from + s * dir;
    if (SpotFree(state, p, radius)) {
      *out = p;
      return true;
    }
  }
  return false;
}

void PlaceAt(Ball* b, const Vector2d& p, double radius) {
  b->r = Eigen::Vector3d(p.x(), p.y(), radius);
  b->v.setZero();
  b->w.setZero();
  b->state = MotionState::kStationary;
  b->pocket = -1;
}

}  // namespace

bool IsSnookerRed(std::string_view id) {
  return id.size() > 3 && id.substr(0, 3) == "red" && id[3] >= '0' && id[3] <= '9';
}

int SnookerValue(std::string_view id) {
  if (IsSnookerRed(id)) return 1;
  const int c = SnookerGeometry::ColourIndex(id);
  return c < 0 ? 0 : c + 2;
}

int SnookerGeometry::ColourIndex(std::string_view id) {
  for (int i = 0; i < 6; ++i) {
    if (kSnookerColours[i] == id) return i;
  }
  return -1;
}

bool SnookerGeometry::InD(const Vector2d& p) const {
  constexpr double kTol = 1e-9;
  return p.x() <= baulk_x_m + kTol &&
         (p - Vector2d(baulk_x_m, 0.0)).norm() <= d_radius_m + kTol;
}

absl::StatusOr<SnookerGeometry> MakeSnookerGeometry(const billiards::TableModel& model) {
  const billiards::TableSpec& spec = model.spec();
  if (!spec.bounded || spec.length_m <= 0 || spec.width_m <= 0) {
    return absl::InvalidArgumentError("snooker needs a table with cushions");
  }
  SnookerGeometry g;
  g.radius_m = model.radius();
  g.half_length_m = 0.5 * spec.length_m;
  g.half_width_m = 0.5 * spec.width_m;
  g.x_limit_m = g.half_length_m - model.cushion_contact_distance();
  g.y_limit_m = g.half_width_m - model.cushion_contact_distance();
  // WPBSA section 1 figures, scaled to this playing area (exact on the full-size table).
  g.baulk_x_m = -g.half_length_m + kWpbsaBaulkLineM * spec.length_m / kWpbsaLengthM;
  g.d_radius_m = kWpbsaDRadiusM * spec.width_m / kWpbsaWidthM;
  const double black_x = g.half_length_m - kWpbsaBlackFromTopM * spec.length_m / kWpbsaLengthM;
  g.spots = {Vector2d(g.baulk_x_m, -g.d_radius_m),  // yellow: right end of the baulk line
             Vector2d(g.baulk_x_m, g.d_radius_m),   // green: left end
             Vector2d(g.baulk_x_m, 0.0),            // brown: middle of the baulk line
             Vector2d(0.0, 0.0),                    // blue: centre of the table
             Vector2d(0.5 * g.half_length_m, 0.0),  // pink: midway centre - top cushion
             Vector2d(black_x, 0.0)};               // black
  if (g.d_radius_m + g.radius_m > g.y_limit_m || g.baulk_x_m - g.d_radius_m < -g.x_limit_m ||
      black_x > g.x_limit_m || 4.0 * g.radius_m > g.d_radius_m) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "table %s (%.3f x %.3f m) is too small for the snooker markings", spec.name,
        spec.length_m, spec.width_m));
  }
  return g;
}

absl::Status RespotColours(const SnookerGeometry& geo, std::span<const std::string> colours,
                           TableState* state, std::vector<std::string>* placed) {
  const double radius = geo.radius_m;
  // The colours waiting, by decreasing value (a total order: values are distinct).
  std::vector<std::pair<int, int>> waiting;  // (colour index, ball index)
  for (const std::string& id : colours) {
    const int c = SnookerGeometry::ColourIndex(id);
    const int i = state->Find(id);
    if (c < 0 || i < 0) return absl::InvalidArgumentError("respot: no colour \"" + id + "\"");
    if (OnCloth(state->balls[i])) continue;  // already on the table: nothing to do
    if (std::any_of(waiting.begin(), waiting.end(), [c](auto w) { return w.first == c; })) continue;
    waiting.push_back({c, i});
  }
  std::sort(waiting.begin(), waiting.end(), [](auto l, auto r) { return l.first > r.first; });
  const auto place = [&](int c, int i, const Vector2d& p) {
    PlaceAt(&state->balls[i], p, radius);
    if (placed != nullptr) placed->push_back(std::string(kSnookerColours[c]));
  };
  // Own spots first: a free own spot is never given to another colour.
  std::vector<std::pair<int, int>> rest;
  for (auto [c, i] : waiting) {
    if (SpotFree(*state, geo.spots[c], radius)) {
      place(c, i, geo.spots[c]);
    } else {
      rest.push_back({c, i});
    }
  }
  for (auto [c, i] : rest) {
    // The highest-valued free spot.
    bool done = false;
    for (int s = 5; s >= 0 && !done; --s) {
      if (SpotFree(*state, geo.spots[s], radius)) {
        place(c, i, geo.spots[s]);
        done = true;
      }
    }
    if (done) continue;
    const Vector2d spot = geo.spots[c];
    Vector2d p;
    // As near its spot as possible towards the top cushion, else on the line below the spot.
    if (NearestFreeOnLine(*state, radius, spot, Vector2d(1, 0), geo.x_limit_m - spot.x(), &p) ||
        NearestFreeOnLine(*state, radius, spot, Vector2d(-1, 0), spot.x() + geo.x_limit_m, &p)) {
      place(c, i, p);
      continue;
    }
    // Not in the rules (both lines full cannot happen with 22 balls): the free grid point
    // nearest the spot, spacing R/2, ties broken by x then y.
    const double h = 0.5 * radius;
    std::vector<std::tuple<double, double, double>> grid;
    for (double x = -geo.x_limit_m; x <= geo.x_limit_m; x += h) {
      for (double y = -geo.y_limit_m; y <= geo.y_limit_m; y += h) {
        grid.push_back({(Vector2d(x, y) - spot).squaredNorm(), x, y});
      }
    }
    std::sort(grid.begin(), grid.end());
    for (const auto& [d2, x, y] : grid) {
      if (SpotFree(*state, Vector2d(x, y), radius)) {
        place(c, i, Vector2d(x, y));
        done = true;
        break;
      }
    }
    if (!done) return absl::InternalError("respot: no free place on the table");
  }
  return absl::OkStatus();
}

bool BothEdgesClear(double radius, const Vector2d& cue, const Vector2d& on,
                    std::span<const Vector2d> obstacles) {
  const double d = (on - cue).norm();
  if (d <= 2.0 * radius + kTouchGapM) return true;  // touching: nothing can come between
  const double alpha = EdgeAngle(radius, d);
  return RayClear(radius, cue, on, alpha, obstacles) && RayClear(radius, cue, on, -alpha, obstacles);
}

bool AnyPartClear(double radius, const Vector2d& cue, const Vector2d& on,
                  std::span<const Vector2d> obstacles, int rays) {
  const double d = (on - cue).norm();
  if (d <= 2.0 * radius + kTouchGapM) return true;
  const double alpha = EdgeAngle(radius, d);
  rays = std::max(rays, 3);
  for (int k = 0; k < rays; ++k) {
    const double theta = -alpha + 2.0 * alpha * k / (rays - 1);
    if (RayClear(radius, cue, on, theta, obstacles)) return true;
  }
  return false;
}

bool FullBallClear(double radius, const Vector2d& cue, const Vector2d& on,
                   std::span<const Vector2d> obstacles) {
  const double d = (on - cue).norm();
  if (d <= 2.0 * radius + kTouchGapM) return true;
  return RayClear(radius, cue, on, 0.0, obstacles);
}

bool IsSnookered(double radius, const Vector2d& cue, std::span<const Vector2d> on,
                 std::span<const Vector2d> not_on) {
  if (on.empty()) return false;
  for (const Vector2d& o : on) {
    if (BothEdgesClear(radius, cue, o, not_on)) return false;
  }
  return true;
}

std::vector<Vector2d> DSamplePositions(const SnookerGeometry& geo, const DSampling& sampling) {
  const double h = sampling.spacing_m > 0 ? sampling.spacing_m : geo.radius_m / 8.0;
  const double rd = geo.d_radius_m;
  const Vector2d centre(geo.baulk_x_m, 0.0);
  std::vector<Vector2d> out;
  const int n = static_cast<int>(std::floor(rd / h));
  // Grid aligned on the baulk line (i = 0) and the long centre line (j = 0).
  for (int i = 0; i <= n; ++i) {
    for (int j = -n; j <= n; ++j) {
      const Vector2d p(geo.baulk_x_m - i * h, j * h);
      if ((p - centre).norm() <= rd) out.push_back(p);
    }
  }
  // The chord's ends and the arc, every h.
  out.push_back(Vector2d(geo.baulk_x_m, -rd));
  out.push_back(Vector2d(geo.baulk_x_m, rd));
  const int m = std::max(2, static_cast<int>(std::ceil(kPi * rd / h)));
  for (int k = 1; k < m; ++k) {
    const double a = 0.5 * kPi + kPi * k / m;  // from +y round through -x to -y
    out.push_back(centre + rd * Vector2d(std::cos(a), std::sin(a)));
  }
  return out;
}

bool IsSnookeredFromD(const SnookerGeometry& geo, std::span<const Vector2d> on,
                      std::span<const Vector2d> not_on, const DSampling& sampling) {
  if (on.empty()) return false;
  const double radius = geo.radius_m;
  const double lim = 2.0 * radius - 1e-9;
  bool any_position = false;
  for (const Vector2d& p : DSamplePositions(geo, sampling)) {
    if (std::abs(p.x()) > geo.x_limit_m || std::abs(p.y()) > geo.y_limit_m) continue;
    const auto touches = [&](std::span<const Vector2d> balls) {
      return std::any_of(balls.begin(), balls.end(),
                         [&](const Vector2d& b) { return (b - p).norm() < lim; });
    };
    if (touches(on) || touches(not_on)) continue;
    any_position = true;
    if (!IsSnookered(radius, p, on, not_on)) return false;
  }
  return any_position;
}

}  // namespace sportsim::games
