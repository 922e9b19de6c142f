// Shots shared by the billiards study and benchmarks: a straight draw shot, a cut, a two-rail
// bank (also with air drag, the one effect without a closed form) and the 9-ball break, each as
// a table model and a struck state.
#ifndef SPORTSIM_BENCH_BILLIARDS_SCENES_H_
#define SPORTSIM_BENCH_BILLIARDS_SCENES_H_

#include <cstdlib>
#include <string>
#include <vector>

#include "sim/billiards/cue.h"
#include "sim/billiards/model.h"
#include "sim/billiards/rack.h"
#include "sim/core/units.h"

namespace sportsim::billiards {

struct Scene {
  std::string name;
  TableModel model;
  TableState state;  ///< struck, ready to simulate
  uint32_t effects = 0;  ///< SolverOptions::effects for this scene
};

inline Ball PlaceBall(std::string id, double x, double y, const TableModel& m) {
  Ball b;
  b.id = std::move(id);
  b.r = Eigen::Vector3d(x, y, m.radius());
  return b;
}

inline Scene MakeScene(const std::string& name) {
  TableModel m = *TableModel::Create(*MakeTablePreset("pool-9ft"));
  TableState s;
  CueStrike strike;
  const double r = m.radius();
  if (name == "straight") {
    // Straight draw shot: 3 m/s with draw into a ball 0.9 m away.
    s.balls = {PlaceBall("cue", -0.6, 0.0, m), PlaceBall("1", 0.3, 0.0, m)};
    strike = {.speed_mps = 3.0, .ball_speed = true, .b = -0.3};
  } else if (name == "cut") {
    // 30 degree cut with a little follow.
    s.balls = {PlaceBall("cue", -0.6, 0.0, m), PlaceBall("1", 0.0, 2 * r * 0.5, m)};
    strike = {.speed_mps = 2.5, .ball_speed = true, .b = 0.2};
  } else if (name == "bank" || name == "bank-drag") {
    // Two-rail bank: top rail, then the right rail, with running english.
    s.balls = {PlaceBall("cue", -0.8, -0.3, m)};
    strike = {.speed_mps = 3.0, .ball_speed = true, .phi_rad = DegToRad(30.0), .a = -0.2};
  } else if (name == "break") {
    // 9-ball break at 10 m/s from the head spot.
    s.balls = *MakeRack("9ball", m);
    strike = {.speed_mps = 10.0, .ball_speed = true};
  } else {
    std::abort();
  }
  if (!ApplyStrike(m, 0, strike, s.Find("cue"), &s).ok()) std::abort();
  return {name, std::move(m), std::move(s), name == "bank-drag" ? uint32_t{kEffectEnableDrag} : 0u};
}

}  // namespace sportsim::billiards

#endif  // SPORTSIM_BENCH_BILLIARDS_SCENES_H_
