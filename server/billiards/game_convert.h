// sportsim.v1 game messages <-> sim/games types: the game a table plays, calls, verdicts, game
// events and the game state. Pure translation, no gRPC.
#ifndef SPORTSIM_SERVER_BILLIARDS_GAME_CONVERT_H_
#define SPORTSIM_SERVER_BILLIARDS_GAME_CONVERT_H_

#include <cstdint>
#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "sim/games/game.h"
#include "sportsim/v1/billiards.pb.h"
#include "sportsim/v1/common.pb.h"

namespace sportsim::server {

/// A table's game, validated: rules, start, noise and seed.
struct GameSetup {
  games::Rules rules;            ///< game kFree: no referee
  games::Start start = games::Start::kBreak;
  double noise = 0.0;            ///< [0, 100]
  std::optional<uint64_t> seed;  ///< as asked (else the table draws one)
};

/// CreateTableRequest.game -> GameSetup. Field names in errors are the proto's ("game.rules").
absl::StatusOr<GameSetup> GameSetupFromProto(const v1::GameConfig& game);

/// The preset and rack a ruled game is played on when the request names none.
std::string GamePreset(games::GameKind game);
std::string GameRack(games::GameKind game);

/// ShootRequest.call, its ids checked (letters, digits, '.', '_', '-'; at most 32 each).
absl::StatusOr<games::ShotCall> ShotCallFromProto(const v1::ShotCall& call);
void ShotCallToProto(const games::ShotCall& call, v1::ShotCall* out);
void VerdictToProto(const games::Verdict& verdict, v1::Verdict* out);
/// The game state as the API shows it; `deadline_s`: the shot clock's (table time), if armed.
void GameStateToProto(const games::GameState& state, std::optional<double> deadline_s,
                      v1::GameState* out);
/// A referee's event as a table event (kinds foul, score, respot, decision, warning,
/// frame_end, match_end).
v1::TableEvent GameEventToProto(const games::GameEvent& e, double t_s, uint64_t shot_id);
/// Every game with its variants, for GetInfo.
void GamesToProto(google::protobuf::RepeatedPtrField<v1::GameInfo>* out);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_BILLIARDS_GAME_CONVERT_H_
