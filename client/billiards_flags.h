// The billiards flags shared by `shot simulate` and the `table` commands (defined in
// shot_commands.cc): each builder fills its message from the flags, or returns a usage error.
#ifndef SPORTSIM_CLIENT_BILLIARDS_FLAGS_H_
#define SPORTSIM_CLIENT_BILLIARDS_FLAGS_H_

#include <optional>
#include <string>

#include "sportsim/v1/billiards.pb.h"

namespace sportsim::cli {

/// --table --rack --jitter --rack-seed --ball ... --param ... --cushion-model
std::optional<std::string> BuildSetup(v1::TableSetup* setup);
/// --engine --integrator --dt --no-ccd --disable --enable
std::optional<std::string> BuildSolver(v1::SolverConfig* solver);
/// --speed | --ball-speed, --phi --theta --a --b --noise --seed --strike-ball
std::optional<std::string> BuildStrike(v1::CueStrike* strike);

}  // namespace sportsim::cli

#endif  // SPORTSIM_CLIENT_BILLIARDS_FLAGS_H_
