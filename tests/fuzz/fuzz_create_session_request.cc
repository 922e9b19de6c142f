// CreateSessionRequest bytes -> SwingModelFromProto, SwingSolverFromProto, StrikeJobFromProto
// (the CreateSession RPC's validation of the golfer, the solver and the ball).
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/convert_checks.h"

using namespace sportsim;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::set<std::string> fields =
      fuzz::FieldNames(v1::CreateSessionRequest::descriptor());
  v1::CreateSessionRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return -1;
  absl::StatusOr<swing::SwingModel> model =
      server::SwingModelFromProto(request.parameters(), request.disabled_effects());
  if (model.ok()) {
    fuzz::CheckFiniteSwingModel(*model);
  } else {
    fuzz::CheckRequestError("SwingModelFromProto", model.status(), fields);
  }
  absl::StatusOr<swing::SwingSolverOptions> solver = server::SwingSolverFromProto(request.solver());
  if (solver.ok()) {
    fuzz::CheckFiniteSwingSolver(*solver);
  } else {
    fuzz::CheckRequestError("SwingSolverFromProto", solver.status(), fields);
  }
  if (request.has_ball()) {
    absl::StatusOr<server::StrikeJob> strike = server::StrikeJobFromProto(request.ball());
    if (strike.ok()) {
      fuzz::CheckFiniteStrikeJob(*strike);
    } else {
      fuzz::CheckRequestError("StrikeJobFromProto", strike.status(), fields);
    }
  }
  return 0;
}
