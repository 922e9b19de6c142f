// The random batch of the storm study (bench/billiards_storms.cc, BM_RackShots in
// billiards_bench.cc): seeded shots from the tight 8-ball rack on a 9-ft table with FastFiz's
// shot distribution: heading uniform, cue speed 0.5-4.5 m/s, elevation 5-30 degrees, tip
// offsets within +-10 mm of the centre (each of a, b uniform in +-10 mm / R).
#ifndef SPORTSIM_BENCH_BILLIARDS_STORMS_H_
#define SPORTSIM_BENCH_BILLIARDS_STORMS_H_

#include <random>
#include <vector>

#include "sim/billiards/cue.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/model.h"
#include "sim/billiards/rack.h"

namespace sportsim::billiards {

inline std::vector<TableState> StormBatch(const TableModel& m, int shots, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const TableState rack{.balls = *MakeRack("8ball", m)};
  const double offset = 0.010 / m.radius();
  std::vector<TableState> out;
  while (static_cast<int>(out.size()) < shots) {
    TableState s = rack;
    const CueStrike strike{.speed_mps = 0.5 + 4.0 * unit(rng),
                           .phi_rad = 6.283185307179586 * unit(rng),
                           .theta_rad = (5.0 + 25.0 * unit(rng)) * 3.141592653589793 / 180.0,
                           .a = offset * (2.0 * unit(rng) - 1.0),
                           .b = offset * (2.0 * unit(rng) - 1.0)};
    if (ApplyStrike(m, 0, strike, s.Find("cue"), &s).ok()) out.push_back(std::move(s));
  }
  return out;
}

/// The event engine with the default resting-contact treatment, or the legacy one (hops).
inline SolverOptions StormOptions(bool legacy) {
  SolverOptions o{.engine = Engine::kEvent};
  if (legacy) o.resting_contacts = RestingContacts::kHops;
  return o;
}

}  // namespace sportsim::billiards

#endif  // SPORTSIM_BENCH_BILLIARDS_STORMS_H_
