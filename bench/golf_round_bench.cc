// CPU of a round's strokes on sportsim_links, and of whole rounds (docs/golf-rounds.md has the
// results): a stroke is its flight, its ground phase and the referee's ruling (PlayStroke);
// BM_Judge is the referee's share alone (JudgeStroke on a played shot). BM_Round plays the
// course's three holes with four players by a fixed policy (a launch toward the pin sized by
// the distance, high under 60 m, a tenth shorter for each stroke over par on the hole; putts on
// and near the green; the last relief choice offered), the same policy the durability tests use; its counters give the strokes a round took and the CPU per hole
// (an 18-hole round of four is about six of these).
#include <benchmark/benchmark.h>

#include <cmath>

#include "sim/golf/course.h"
#include "sim/golf/round.h"

namespace sportsim::golf {
namespace {

const Course& Links() { return **BuiltinCourse("sportsim_links"); }

RoundSettings Settings(int players) {
  RoundSettings s;
  s.first_hole = 1;
  s.last_hole = 3;
  const char* names[] = {"Ann", "Bob", "Cat", "Dan"};
  for (int i = 0; i < players; ++i) s.players.push_back({names[i], ""});
  s.seed = 3;
  return s;
}

RoundStroke Launch(double speed, double angle, double spin) {
  RoundStroke k;
  k.launch = LaunchConditions{.ball_speed_mps = speed, .launch_angle_deg = angle,
                              .launch_direction_deg = 0, .spin_rpm = spin, .spin_axis_deg = 0};
  return k;
}

// The state with seat 0's ball `metres` from hole 1's pin, on the line to the tee.
RoundState Lying(double metres) {
  RoundState st = *StartRound(Links(), Settings(1));
  const Eigen::Vector2d pin = *Links().Hole(1)->pin_m;
  const Eigen::Vector2d p = pin + metres * (Links().Hole(1)->tees[0].position_m - pin).normalized();
  st.players[0].strokes = 1;
  st.players[0].ball.position_m = Eigen::Vector3d(p.x(), p.y(), Links().terrain.HeightAt(p.x(), p.y()));
  st.players[0].ball.lie = Links().LieAt(p.x(), p.y(), 0.021335);
  return st;
}

// Arg: 0 a drive from the tee, 1 a 7-iron from 150 m, 2 a 6 m putt.
void BM_Stroke(benchmark::State& state) {
  const RoundSettings s = Settings(1);
  const int which = static_cast<int>(state.range(0));
  const RoundState st = which == 0 ? *StartRound(Links(), s) : Lying(which == 1 ? 150.0 : 6.0);
  RoundStroke k = which == 0 ? Launch(70, 11, 2700) : Launch(48, 18, 7000);
  if (which == 2) {
    k.kind = RoundStroke::Kind::kPutt;
    k.speed_mps = 3.6;
  }
  for (auto _ : state) benchmark::DoNotOptimize(PlayStroke(Links(), s, st, 0, k));
}
BENCHMARK(BM_Stroke)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

// The referee alone. Arg: 0 a drive's result (at rest on the fairway), 1 a drive into hole 3's
// red creek (the crossing point and the relief options found).
void BM_Judge(benchmark::State& state) {
  RoundSettings s = Settings(1);
  const bool creek = state.range(0) == 1;
  if (creek) s.first_hole = 3;
  const RoundState st = *StartRound(Links(), s);
  RoundStroke k = creek ? Launch(60, 12, 3000) : Launch(70, 11, 2700);
  if (creek) k.aim_deg = 194.0;
  const CourseShot shot = *StrokeShot(Links(), s, st, 0, k);
  const CourseShotResult played = *PlayCourseShot(Links(), shot);
  for (auto _ : state) benchmark::DoNotOptimize(JudgeStroke(Links(), s, st, 0, played));
}
BENCHMARK(BM_Judge)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The fixed policy's next step on `st` (a decision or a stroke by the seat to play).
absl::StatusOr<RoundStep> Next(const RoundSettings& s, const RoundState& st) {
  if (st.decision) {
    return Decide(Links(), s, st, st.decision->seat, {st.decision->choices.back(), std::nullopt});
  }
  const int seat = ToPlay(Links(), s, st);
  const RoundBall& b = st.players[seat].ball;
  const double d = (b.position_m.head<2>() - *Links().Hole(st.hole)->pin_m).norm();
  return PlayStroke(Links(), s, st, seat,
                    ReferenceStroke(d, b.lie == Terrain::kGreen,
                                    st.players[seat].strokes - Links().Hole(st.hole)->par));
}

void BM_Round(benchmark::State& state) {
  const RoundSettings s = Settings(static_cast<int>(state.range(0)));
  int64_t strokes = 0, rounds = 0;
  for (auto _ : state) {
    RoundState st = *StartRound(Links(), s);
    for (int n = 0; n < 2000 && !st.over; ++n) {
      absl::StatusOr<RoundStep> step = Next(s, st);
      if (!step.ok()) {
        state.SkipWithError(std::string(step.status().message()).c_str());
        return;
      }
      st = std::move(step->state);
    }
    strokes += st.strokes;
    ++rounds;
  }
  state.counters["strokes_per_round"] = static_cast<double>(strokes) / static_cast<double>(rounds);
  state.counters["strokes"] = benchmark::Counter(static_cast<double>(strokes),
                                                 benchmark::Counter::kIsRate |
                                                     benchmark::Counter::kInvert);
}
BENCHMARK(BM_Round)->Arg(1)->Arg(4)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace sportsim::golf

BENCHMARK_MAIN();
