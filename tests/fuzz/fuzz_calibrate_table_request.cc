// CalibrateTableRequest bytes -> CalibrationJobFromProto (the CalibrateTable RPC's validation,
// before any work), then, for a valid job on the event engine, one shot scored with a fixed
// strike: errors name a request field, are short and have no raw control characters; an
// accepted job has valid recordings and finite scores. The request cut into UploadCalibration's
// parts (client/calibration_upload.h; the part size from the input's length) and put back
// together is the request again, unless the assembler refuses it, and then so does the job.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>

#include <google/protobuf/util/field_comparator.h>
#include <google/protobuf/util/message_differencer.h>

#include "client/calibration_upload.h"
#include "server/billiards/calibration.h"
#include "tests/fuzz/convert_checks.h"

using namespace sportsim;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::set<std::string> fields =
      fuzz::FieldNames(v1::CalibrateTableRequest::descriptor());
  v1::CalibrateTableRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return -1;
  absl::StatusOr<server::CalibrationJob> job = server::CalibrationJobFromProto(request);
  server::CalibrationUploadAssembler assembler;
  absl::Status added;
  for (const v1::CalibrationUpload& part : cli::CalibrationUploadParts(request, 64 + size % 4096)) {
    added = assembler.Add(part);
    if (!added.ok()) break;
  }
  if (added.ok()) {
    absl::StatusOr<v1::CalibrateTableRequest> back = std::move(assembler).Finish();
    // Compared field by field (a map's serialization follows its iteration order, which
    // copies need not keep), a NaN equal to itself.
    google::protobuf::util::DefaultFieldComparator same_nan;
    same_nan.set_treat_nan_as_equal(true);
    google::protobuf::util::MessageDifferencer differ;
    differ.set_field_comparator(&same_nan);
    FUZZ_CHECK(back.ok() && differ.Compare(*back, request),
               "the uploaded parts do not make the request");
  } else {
    fuzz::CheckMessage("CalibrationUploadAssembler", added);
    FUZZ_CHECK(!job.ok(), "an upload refused (%s) of a request accepted in one message",
               added.ToString().c_str());
  }
  if (!job.ok()) {
    fuzz::CheckRequestError("CalibrationJobFromProto", job.status(), fields);
    return 0;
  }
  FUZZ_CHECK(!job->recordings.empty(), "a job without recordings");
  absl::StatusOr<billiards::TableModel> model = billiards::TableModel::Create(job->spec);
  FUZZ_CHECK(model.ok(), "the job's table does not build: %s", model.status().ToString().c_str());
  FUZZ_CHECK(billiards::ValidateCalibration(job->spec, job->solver, job->recordings, job->options).ok(),
             "an accepted job does not validate");
  // The cloth read from the first recording's tracks (read_cloth), on tracks of a few thousand
  // points (its cost is linear in them): counts and readings finite, each median between its
  // quartiles, the readings within what a stretch reads.
  if (const billiards::Recording& first = job->recordings.front(); first.track.size() <= 4000) {
    const billiards::ClothReading c = billiards::ReadCloth(
        std::span<const billiards::Recording>(&first, 1), job->spec.params.gravity_mps2);
    FUZZ_CHECK(c.rolling >= 0 && c.sliding >= 0, "negative stretch counts");
    FUZZ_CHECK(std::isfinite(c.mu_roll) && std::isfinite(c.mu_slide), "a reading not finite");
    FUZZ_CHECK(c.mu_roll_q1 <= c.mu_roll && c.mu_roll <= c.mu_roll_q3 &&
                   c.mu_slide_q1 <= c.mu_slide && c.mu_slide <= c.mu_slide_q3,
               "a median outside its quartiles");
    const double g = job->spec.params.gravity_mps2;
    FUZZ_CHECK(c.mu_roll >= 0 && c.mu_roll <= billiards::kRollingMaxAccel / g + 1e-12 &&
                   (c.sliding == 0 || (c.mu_slide >= billiards::kSlidingMinAccel / g - 1e-12 &&
                                       c.mu_slide <= billiards::kSlidingMaxAccel / g + 1e-12)),
               "a reading outside what a stretch reads: %g, %g", c.mu_roll, c.mu_slide);
  }
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
