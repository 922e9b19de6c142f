// SimulateShotRequest bytes -> ShotJobFromProto -> BoundShotWork (the SimulateShot RPC's
// validation, without running the shot: fuzz_billiards_engines runs the engines).
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/convert_checks.h"

using namespace sportsim;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::set<std::string> fields =
      fuzz::FieldNames(v1::SimulateShotRequest::descriptor());
  v1::SimulateShotRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return -1;
  absl::StatusOr<server::ShotJob> job = server::ShotJobFromProto(request);
  if (!job.ok()) {
    fuzz::CheckRequestError("ShotJobFromProto", job.status(), fields);
    return 0;
  }
  fuzz::CheckFiniteTable(job->table);
  fuzz::CheckFiniteSolver(job->solver);
  FUZZ_CHECK(std::isfinite(job->shot.max_time_s) && job->shot.max_time_s > 0, "max_time_s %g",
             job->shot.max_time_s);
  FUZZ_CHECK(std::isfinite(job->shot.sample_interval_s) && job->shot.sample_interval_s >= 0,
             "sample_interval_s %g", job->shot.sample_interval_s);
  if (job->strike) fuzz::CheckFiniteStrike(*job->strike);
  // The server's reply budget (4 MiB, the gRPC default message size).
  const absl::Status bound = server::BoundShotWork(4 << 20, &*job);
  if (!bound.ok()) {
    fuzz::CheckRequestError("BoundShotWork", bound, fields);
    return 0;
  }
  FUZZ_CHECK(job->shot.max_samples >= 1 && job->solver.max_events >= 1, "bounds");
  v1::SimulateShotResponse reply;  // what the reply would carry besides the run's results
  if (job->strike) server::StrikeReportToProto(*job->strike, reply.mutable_strike());
  server::GeometryToProto(job->table.model, reply.mutable_geometry());
  for (const billiards::Ball& b : job->table.state.balls) {
    server::BallToProto(job->table.model, b, reply.add_balls());
  }
  return 0;
}
