// Racks: the starting layouts of the games (and of the chapter's demonstration scene).
#ifndef SPORTSIM_SIM_BILLIARDS_RACK_H_
#define SPORTSIM_SIM_BILLIARDS_RACK_H_

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"

namespace sportsim::billiards {

/// empty, 8ball, 9ball, snooker, three-cushion, chapter19.
std::span<const std::string_view> RackNames();

/// Rack jitter must be in [0, this) (m).
inline constexpr double kMaxRackJitterM = 0.01;

/// Balls of a rack on this table, at rest. Racked balls touch (a tight rack); with `jitter_m`
/// > 0 every ball sits on a grid spaced by 2R + jitter_m and is displaced by a seeded random
/// vector shorter than jitter_m / 2, so the gaps vary in [0, 2 jitter_m] and balls never
/// overlap. Ids: "cue", then "1".."15" (pool), "red1".."red15", "yellow", "green", "brown",
/// "blue", "pink", "black" (snooker), "yellow", "red" (three-cushion), "8", "1", "2"
/// (chapter19). Fails when the rack does not fit the table (chapter19 needs 'unbounded' or a
/// table longer than 3 m).
absl::StatusOr<std::vector<Ball>> MakeRack(std::string_view name, const TableModel& model,
                                           double jitter_m = 0.0, uint64_t seed = 0);

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_RACK_H_
