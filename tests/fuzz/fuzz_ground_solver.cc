// Golf: the ground phase (sim/golf/ground.h) with the surface, plane, hole (and flagstick),
// start (a landing, a putt or a rolling ball) and options decoded from the bytes within and
// slightly beyond their valid ranges (plus NaN, infinities, zeros). The validator must refuse
// invalid inputs cleanly (InvalidArgument, short messages); a run is cut off through its
// cancellation poll (a few hundred thousand steps) or its time limit (OutOfRange). An accepted run must end holed or at
// rest on the plane, with finite events in time order and samples never below the plane, and
// give bit-identical results twice. A third of the inputs play on the built-in course (the start
// moved onto its map, one of its holes): the same, on the terrain (samples at most 0.5 mm below
// it: the interpolation across the grid's kinks).
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "sim/golf/course.h"
#include "sim/golf/ground.h"
#include "sim/golf/surface.h"
#include "tests/fuzz/fuzz_util.h"
#include "tests/fuzz/fuzz_values.h"

namespace g = sportsim::golf;
using sportsim::fuzz::Bits;
using sportsim::fuzz::RangeValue;

namespace {

absl::StatusOr<g::GroundResult> RunOnce(const g::Surface& surface, const g::GroundPlane& plane,
                                        const g::Hole& hole, const g::GroundStart& start,
                                        g::GroundOptions o) {
  int polls = 0;
  o.cancelled = [&polls] { return ++polls > 300; };
  return g::SimulateGround(g::BallSpec{}, surface, plane, hole, start, o);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  const auto builtins = g::BuiltinSurfaces();
  g::Surface surface = builtins[in.ConsumeIntegralInRange<size_t>(0, builtins.size() - 1)];
  if (in.ConsumeIntegralInRange(0, 3) == 0) {
    surface.restitution_scale = RangeValue(in, 0, 1.5);
    surface.critical_angle_scale = RangeValue(in, 0, 5);
    surface.bounce_friction = RangeValue(in, 0, 2);
    surface.sliding_friction = RangeValue(in, 0, 2);
    surface.rolling_resistance = RangeValue(in, 0, 2);
  }
  g::GroundPlane plane;
  plane.slope_pct = RangeValue(in, 0, 20);
  plane.slope_toward_deg = RangeValue(in, -360, 360);
  g::Hole hole;
  hole.x_m = RangeValue(in, -30, 30);
  hole.y_m = RangeValue(in, -30, 30);
  if (in.ConsumeIntegralInRange(0, 7) == 0) {
    hole.diameter_m = RangeValue(in, 0.04, 0.3);
    hole.depth_m = RangeValue(in, 0, 0.2);
  }
  if (in.ConsumeBool()) {
    hole.flagstick_diameter_m = RangeValue(in, 0.005, 0.06);
    hole.flagstick_restitution = RangeValue(in, 0, 1);
  }
  g::GroundOptions o;
  o.hole = in.ConsumeBool();
  o.effects = in.ConsumeIntegralInRange<uint32_t>(0, 4);
  if (in.ConsumeIntegralInRange(0, 3) == 0) {
    o.dt_s = RangeValue(in, 1e-4, 0.01);
    o.settle_speed_mps = RangeValue(in, 0.001, 1);
    o.sample_interval_s = RangeValue(in, 0, 1);
    o.max_time_s = RangeValue(in, 0, 600);
  }
  if (in.ConsumeIntegralInRange(0, 3) == 0) {  // dp45, its tolerance and largest step
    o.integrator = sportsim::ode::Integrator::kDp45;
    o.tolerance_m = RangeValue(in, 1e-10, 0.1);
    o.dt_s = RangeValue(in, 1e-4, 0.1);
  }
  g::GroundStart start;
  const double x = RangeValue(in, -30, 30), y = RangeValue(in, -30, 30);
  switch (in.ConsumeIntegralInRange(0, 2)) {
    case 0:
      start.kind = g::GroundStartKind::kLanding;
      start.position_m = Eigen::Vector3d(x, y, 0);
      start.velocity_mps = Eigen::Vector3d(RangeValue(in, -60, 60), RangeValue(in, -60, 60),
                                           RangeValue(in, -60, 0));
      start.spin_radps = Eigen::Vector3d(RangeValue(in, -1500, 1500), RangeValue(in, -1500, 1500),
                                         RangeValue(in, -500, 500));
      break;
    case 1: start = g::PuttStart(x, y, RangeValue(in, 0, 10), RangeValue(in, -360, 360)); break;
    default: start = g::RollingStart(x, y, RangeValue(in, 0, 10), RangeValue(in, -360, 360)); break;
  }
  // A third of the inputs play on the built-in course instead, the start moved onto it.
  const bool on_course = in.ConsumeIntegralInRange(0, 2) == 0;
  const g::Course& links = **g::BuiltinCourse("sportsim_links");
  const int hole_number = in.ConsumeIntegralInRange(1, 3);
  if (on_course) {
    start.position_m.x() = links.terrain.x0_m + (x + 30) / 60 * (links.terrain.x1_m() - links.terrain.x0_m);
    start.position_m.y() = links.terrain.y0_m + (y + 30) / 60 * (links.terrain.y1_m() - links.terrain.y0_m);
  }
  auto run = [&] {
    if (!on_course) return RunOnce(surface, plane, hole, start, o);
    g::GroundOptions oc = o;
    int polls = 0;
    oc.cancelled = [&polls] { return ++polls > 300; };
    return g::SimulateGroundOnCourse(g::BallSpec{}, links, hole_number, hole, start, oc);
  };
  auto ground_z = [&](double px, double py) {
    return on_course ? links.terrain.HeightAt(px, py) : plane.HeightAt(px, py);
  };
  const absl::StatusOr<g::GroundResult> r = run();
  if (!r.ok()) {
    sportsim::fuzz::CheckMessage("ground", r.status());
    FUZZ_CHECK(r.status().code() == absl::StatusCode::kInvalidArgument ||
                   r.status().code() == absl::StatusCode::kOutOfRange ||
                   r.status().code() == absl::StatusCode::kCancelled,
               "ground: %s", r.status().ToString().c_str());
    return 0;
  }
  FUZZ_CHECK(!r->events.empty(), "no events");
  const g::GroundEventKind last = r->events.back().kind;
  FUZZ_CHECK(last == g::GroundEventKind::kRest || last == g::GroundEventKind::kHoled,
             "the run ended with %s", std::string(g::GroundEventName(last)).c_str());
  FUZZ_CHECK(r->holed == (last == g::GroundEventKind::kHoled), "holed flag");
  FUZZ_FINITE(r->rest_m.x());
  FUZZ_FINITE(r->rest_m.y());
  FUZZ_FINITE(r->rest_m.z());
  FUZZ_FINITE(r->t_rest_s);
  const double below = r->rest_m.z() - ground_z(r->rest_m.x(), r->rest_m.y());
  FUZZ_CHECK(std::abs(below) < (on_course ? 1e-3 : 1e-6) || r->out_of_bounds,
             "rest %g m off the ground", below);
  for (size_t i = 0; i < r->events.size(); ++i) {
    const g::GroundEvent& e = r->events[i];
    FUZZ_CHECK(e.position_m.allFinite() && e.velocity_mps.allFinite() && std::isfinite(e.t_s),
               "event %zu not finite", i);
    if (i > 0) FUZZ_CHECK(r->events[i - 1].t_s <= e.t_s, "events out of time order at %zu", i);
  }
  for (const g::GroundSample& s : r->samples) {
    FUZZ_CHECK(s.position_m.allFinite() && std::isfinite(s.speed_mps), "sample not finite");
    const double h = s.position_m.z() - ground_z(s.position_m.x(), s.position_m.y());
    FUZZ_CHECK(h > (on_course ? -5e-4 : -1e-6), "a sample %g m below the ground at t = %g", h,
               s.t_s);
  }
  const absl::StatusOr<g::GroundResult> again = run();
  FUZZ_CHECK(again.ok(), "second run failed: %s", again.status().ToString().c_str());
  for (int k = 0; k < 3; ++k) {
    FUZZ_CHECK(Bits(again->rest_m[k]) == Bits(r->rest_m[k]), "not bit-identical");
  }
  FUZZ_CHECK(again->events.size() == r->events.size(), "not bit-identical: events");
  return 0;
}
