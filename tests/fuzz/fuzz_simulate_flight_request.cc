// SimulateFlightRequest bytes -> FlightJobFromProto (the SimulateFlight RPC's validation; the
// flight itself runs in fuzz_flight_solver).
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/convert_checks.h"

using namespace sportsim;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::set<std::string> fields =
      fuzz::FieldNames(v1::SimulateFlightRequest::descriptor());
  v1::SimulateFlightRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return -1;
  absl::StatusOr<server::FlightJob> job = server::FlightJobFromProto(request);
  if (!job.ok()) {
    fuzz::CheckRequestError("FlightJobFromProto", job.status(), fields);
    return 0;
  }
  fuzz::CheckFiniteFlightJob(*job);
  FUZZ_CHECK(job->launch.ball_speed_mps > 0 && job->launch.ball_speed_mps <= 120, "ball speed %g",
             job->launch.ball_speed_mps);
  if (job->options.accuracy.dt_s) {
    FUZZ_CHECK(*job->options.accuracy.dt_s >= 1e-5, "dt_s %g", *job->options.accuracy.dt_s);
  }
  return 0;
}
