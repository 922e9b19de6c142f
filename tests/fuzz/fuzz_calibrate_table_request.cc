// CalibrateTableRequest bytes -> CalibrationJobFromProto (the CalibrateTable RPC's validation,
// before any work), then, for a valid job on the event engine, one shot scored with a fixed
// strike: errors name a request field, are short and have no raw control characters; an
// accepted job has valid recordings and finite scores.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "server/billiards/calibration.h"
#include "tests/fuzz/convert_checks.h"

using namespace sportsim;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::set<std::string> fields =
      fuzz::FieldNames(v1::CalibrateTableRequest::descriptor());
  v1::CalibrateTableRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return -1;
  absl::StatusOr<server::CalibrationJob> job = server::CalibrationJobFromProto(request);
  if (!job.ok()) {
    fuzz::CheckRequestError("CalibrationJobFromProto", job.status(), fields);
    return 0;
  }
  FUZZ_CHECK(!job->recordings.empty(), "a job without recordings");
  absl::StatusOr<billiards::TableModel> model = billiards::TableModel::Create(job->spec);
  FUZZ_CHECK(model.ok(), "the job's table does not build: %s", model.status().ToString().c_str());
  FUZZ_CHECK(billiards::ValidateCalibration(job->spec, job->solver, job->recordings, job->options).ok(),
             "an accepted job does not validate");
  // Scored on the event engine only, whose cost is per event (capped below): a stepped engine
  // at a microsecond step would spend the fuzzer's per-input time limit on one input (the
  // server holds such a request to its CPU budget).
  if (job->solver.engine != billiards::Engine::kEvent) return 0;
  const billiards::Recording& rec = job->recordings.front();
  billiards::CueStrike strike;
  strike.ball_speed = true;
  strike.speed_mps = 1.0;
  job->solver.max_events = std::min<int64_t>(job->solver.max_events, 20000);
  absl::StatusOr<billiards::ShotError> e =
      billiards::ScoreShot(*model, job->solver, rec, strike, 2.0);
  if (e.ok()) {
    FUZZ_CHECK(std::isfinite(e->mean_m) && std::isfinite(e->rms_m) && e->mean_m >= 0,
               "score not finite: %g", e->mean_m);
  } else {
    fuzz::CheckMessage("ScoreShot", e.status());
  }
  return 0;
}
