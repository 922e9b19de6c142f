// CreateTableRequest bytes -> TableFromProto, SolverFromProto, GameSetupFromProto (the
// CreateTable RPC's validation), then, for a ruled game, StartMatch on the table built.
#include <cstddef>
#include <cstdint>

#include "sim/games/game.h"
#include "tests/fuzz/convert_checks.h"

using namespace sportsim;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::set<std::string> fields =
      fuzz::FieldNames(v1::CreateTableRequest::descriptor());
  v1::CreateTableRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return -1;

  absl::StatusOr<billiards::SolverOptions> solver = server::SolverFromProto(request.solver());
  if (solver.ok()) {
    fuzz::CheckFiniteSolver(*solver);
  } else {
    fuzz::CheckRequestError("SolverFromProto", solver.status(), fields);
  }
  absl::StatusOr<server::GameSetup> game = server::GameSetupFromProto(request.game());
  if (game.ok()) {
    FUZZ_CHECK(game->rules.race_to >= 1 && game->rules.race_to <= 99, "race_to %d",
               game->rules.race_to);
    FUZZ_CHECK(std::isfinite(game->rules.shot_clock_s) && game->rules.shot_clock_s >= 0,
               "shot_clock_s %g", game->rules.shot_clock_s);
    FUZZ_CHECK(std::isfinite(game->noise) && game->noise >= 0 && game->noise <= 100, "noise %g",
               game->noise);
  } else {
    fuzz::CheckRequestError("GameSetupFromProto", game.status(), fields);
  }
  // A ruled game plays on its own preset and rack unless the request names them (as the server).
  v1::TableSetup setup = request.table();
  if (game.ok() && game->rules.game != games::GameKind::kFree) {
    if (setup.preset().empty()) setup.set_preset(server::GamePreset(game->rules.game));
    if (setup.rack().empty()) setup.set_rack(server::GameRack(game->rules.game));
  }
  absl::StatusOr<server::TableBuild> table = server::TableFromProto(setup);
  if (!table.ok()) {
    fuzz::CheckRequestError("TableFromProto", table.status(), fields);
    return 0;
  }
  fuzz::CheckFiniteTable(*table);
  if (game.ok() && game->rules.game != games::GameKind::kFree) {
    billiards::TableState balls = table->state;
    absl::StatusOr<games::GameState> state =
        games::StartMatch(game->rules, table->model, game->start, &balls);
    if (!state.ok()) {
      fuzz::CheckMessage("StartMatch", state.status());
      return 0;
    }
    FUZZ_CHECK(state->to_play == 0 || state->to_play == 1, "to_play %d", state->to_play);
    FUZZ_CHECK(state->frame == 1, "frame %d", state->frame);
    fuzz::CheckFiniteBalls(balls);
    v1::GameState out;
    server::GameStateToProto(*state, std::nullopt, &out);
  }
  return 0;
}
