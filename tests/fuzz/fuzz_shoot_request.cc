// ShootRequest bytes -> StrikeFromProto and ShotCallFromProto (the Shoot RPC's validation),
// then the strike on a pool table (ComputeStrike: refused cleanly or finite).
#include <cstddef>
#include <cstdint>

#include "server/world/world.h"
#include "sim/billiards/cue.h"
#include "tests/fuzz/convert_checks.h"

using namespace sportsim;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::set<std::string> fields = fuzz::FieldNames(v1::ShootRequest::descriptor());
  static const billiards::TableModel model =
      *billiards::TableModel::Create(*billiards::MakeTablePreset("pool-9ft"));
  v1::ShootRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return -1;
  absl::StatusOr<games::ShotCall> call = server::ShotCallFromProto(request.call());
  if (call.ok()) {
    for (const std::string* id : {&call->ball, &call->pocket, &call->nominate}) {
      FUZZ_CHECK(id->size() <= 32, "call id of %zu characters accepted", id->size());
    }
    v1::ShotCall back;
    server::ShotCallToProto(*call, &back);
  } else {
    fuzz::CheckRequestError("ShotCallFromProto", call.status(), fields);
  }
  absl::StatusOr<billiards::CueStrike> strike = server::StrikeFromProto(request.strike());
  if (!strike.ok()) {
    fuzz::CheckRequestError("StrikeFromProto", strike.status(), fields);
    return 0;
  }
  // The effects of a table: fuzz them with the seed's low bits.
  const uint32_t effects = static_cast<uint32_t>(request.strike().seed() >> 32) &
                           billiards::kEffectKnownBits & ~billiards::kEffectEnableDrag;
  absl::StatusOr<billiards::StrikeOutcome> out = billiards::ComputeStrike(model, effects, *strike);
  if (!out.ok()) {
    fuzz::CheckRequestError("ComputeStrike", server::PrefixStatus("strike.", out.status()), fields);
    return 0;
  }
  fuzz::CheckFiniteStrike(*out);
  FUZZ_CHECK(out->v.head<2>().norm() <= 3 * billiards::kMaxStrikeSpeed,
             "ball speed %g from a strike", out->v.head<2>().norm());
  v1::StrikeReport report;
  server::StrikeReportToProto(*out, &report);
  return 0;
}
