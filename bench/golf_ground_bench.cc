// CPU of the golf ball's ground phase per shot beside its flight's: a tour drive and a tour
// 7-iron (flight, then bounces and roll on the normal fairway), and putts of 3 and 10 m on a
// Stimp 10 green, flat and across a 2 % slope (RK4 on the ground at 1, 2 and 5 ms, the
// default; a flat green needs no steps); and on sportsim_links a drive from the first tee and a
// 10 m putt on its green. Flights at their default (RK4, 1 ms), no samples. Results:
// docs/golf-ground.md.
#include <benchmark/benchmark.h>

#include <cmath>

#include "sim/golf/ball_flight.h"
#include "sim/golf/course_shot.h"
#include "sim/golf/ground.h"
#include "sim/golf/surface.h"

namespace sportsim::golf {
namespace {

LaunchConditions Launch(int which) {
  if (which == 0) return {.ball_speed_mps = 167 * kMphToMps, .launch_angle_deg = 10.9, .spin_rpm = 2686};
  return {.ball_speed_mps = 120 * kMphToMps, .launch_angle_deg = 16.3, .spin_rpm = 7097};
}

FlightResult Fly(int which) {
  FlightOptions o;
  o.sample_interval_s = 0;
  return *SimulateFlight(BallSpec{}, Launch(which), Atmosphere{}, Wind{}, o);
}

GroundOptions Quiet() {
  GroundOptions o;
  o.sample_interval_s = 0;
  o.hole = false;
  return o;
}

// Arg: 0 drive, 1 seven-iron.
void BM_Flight(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(Fly(static_cast<int>(state.range(0))));
}
BENCHMARK(BM_Flight)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_GroundAfterFlight(benchmark::State& state) {
  const FlightResult flight = Fly(static_cast<int>(state.range(0)));
  const Surface fairway = *SurfaceByName("fairway");
  const GroundStart start = LandingFromFlight(flight);
  for (auto _ : state) {
    benchmark::DoNotOptimize(SimulateGround(BallSpec{}, fairway, {}, {}, start, Quiet()));
  }
}
BENCHMARK(BM_GroundAfterFlight)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// Args: putt length (m), slope (%), RK4 step (us).
void BM_Putt(benchmark::State& state) {
  const Surface green = *GreenOfStimp(10);
  const double length = static_cast<double>(state.range(0));
  const GroundPlane plane{.slope_pct = static_cast<double>(state.range(1)),
                          .slope_toward_deg = -90};
  // A speed that stops about `length` on the flat (skid, then roll).
  const double speed = std::sqrt(2 * length * 5.0 / 7.0 * green.rolling_resistance * 9.80665);
  GroundOptions o = Quiet();
  o.hole = true;
  o.dt_s = 1e-6 * static_cast<double>(state.range(2));
  const Hole hole{.x_m = length + 1.0, .y_m = 0};  // never reached: every putt runs to rest
  for (auto _ : state) {
    benchmark::DoNotOptimize(SimulateGround(BallSpec{}, green, plane, hole,
                                            PuttStart(0, 0, speed, 0), o));
  }
}
BENCHMARK(BM_Putt)
    ->Args({3, 0, 1000})
    ->Args({10, 0, 1000})
    ->Args({3, 2, 1000})
    ->Args({10, 2, 1000})
    ->Args({10, 2, 2000})
    ->Args({10, 2, 5000})
    ->Unit(benchmark::kMicrosecond);

// On sportsim_links (terrain, surfaces, the pin): Arg 0, the tour drive from the first tee
// (launch to rest, the flight over the terrain included); Arg 1, a 10 m putt on the first
// green; Arg 2, the same putt with dp45 at 1e-6 m. Beside them on the plane: BM_Flight plus
// BM_GroundAfterFlight, and BM_Putt.
void BM_CourseShot(benchmark::State& state) {
  const Course& links = **BuiltinCourse("sportsim_links");
  const Eigen::Vector2d pin = *links.holes[0].pin_m;
  CourseShot shot;
  shot.hole = 1;
  shot.ground.sample_interval_s = 0;
  shot.flight.sample_interval_s = 0;
  if (state.range(0) == 0) {
    shot.kind = CourseShot::Kind::kLaunch;
    shot.from_m = links.holes[0].tees[0].position_m;
    shot.aim_deg = std::atan2(pin.y() - shot.from_m.y(), pin.x() - shot.from_m.x()) * 180 / M_PI;
    shot.launch = Launch(0);
  } else {
    shot.kind = CourseShot::Kind::kPutt;
    shot.from_m = pin + Eigen::Vector2d(-10, 0.5);
    shot.speed_mps = 3.4;
    if (state.range(0) == 2) {
      shot.ground.integrator = ode::Integrator::kDp45;
      shot.ground.tolerance_m = 1e-6;
      shot.ground.dt_s = 0.05;
    }
  }
  for (auto _ : state) benchmark::DoNotOptimize(PlayCourseShot(links, shot));
}
BENCHMARK(BM_CourseShot)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace sportsim::golf

BENCHMARK_MAIN();
