// SimulateSwingRequest bytes -> SwingJobFromProto (the SimulateSwing RPC's validation; the swing
// itself runs in fuzz_swing_solver).
#include <cstddef>
#include <cstdint>

#include "tests/fuzz/convert_checks.h"

using namespace sportsim;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const std::set<std::string> fields =
      fuzz::FieldNames(v1::SimulateSwingRequest::descriptor());
  v1::SimulateSwingRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return -1;
  absl::StatusOr<server::SwingJob> job = server::SwingJobFromProto(request);
  if (!job.ok()) {
    fuzz::CheckRequestError("SwingJobFromProto", job.status(), fields);
    return 0;
  }
  fuzz::CheckFiniteSwingModel(job->model);
  fuzz::CheckFiniteSwingSolver(job->solver);
  FUZZ_CHECK(std::isfinite(job->run.duration_s) && job->run.duration_s > 0 &&
                 job->run.duration_s <= 10,
             "duration_s %g", job->run.duration_s);
  FUZZ_CHECK(job->run.sample_stride >= 1, "sample_stride %d", job->run.sample_stride);
  FUZZ_CHECK(std::isfinite(job->run.sample_interval_s) && job->run.sample_interval_s >= 0,
             "sample_interval_s %g", job->run.sample_interval_s);
  for (const swing::TorqueSchedule* s : {&job->program.q_alpha(), &job->program.q_beta()}) {
    FUZZ_CHECK(!s->knots.empty() && s->knots.size() <= swing::TorqueProgram::kMaxKnots, "knots");
    for (const swing::TorqueKnot& k : s->knots) {
      FUZZ_CHECK(std::isfinite(k.t_s) && std::isfinite(k.torque_nm), "knot (%g, %g)", k.t_s,
                 k.torque_nm);
    }
  }
  // Fixed steps: the sample count is bounded up front (SimulateSwing refuses above kMaxSamples).
  if (job->solver.integrator != swing::SwingIntegrator::kDp45) {
    const double samples = job->run.duration_s / job->solver.dt() / job->run.sample_stride;
    FUZZ_CHECK(samples <= swing::SwingRunOptions::kMaxSamples + 2, "%g samples accepted", samples);
  }
  if (job->strike) fuzz::CheckFiniteStrikeJob(*job->strike);
  return 0;
}
