// CalibrateTable: the request as a sim/billiards calibration, and its report as the API's.
// Pure translation, tested without a network. Errors name the field ("shots[2].points[7].t_s").
#ifndef SPORTSIM_SERVER_BILLIARDS_CALIBRATION_H_
#define SPORTSIM_SERVER_BILLIARDS_CALIBRATION_H_

#include <vector>

#include "absl/status/statusor.h"
#include "sim/billiards/calibrate.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/model.h"
#include "sportsim/v1/billiards.pb.h"

namespace sportsim::server {

/// Most shots and tracked points (over all shots) a calibration takes.
inline constexpr int kMaxCalibrationShots = 200;
inline constexpr int kMaxCalibrationPoints = 1000000;

struct CalibrationJob {
  billiards::TableSpec spec;
  billiards::SolverOptions solver;
  std::vector<billiards::Recording> recordings;
  billiards::CalibrationOptions options;  ///< without its callbacks
};

/// Validates the whole request (the table, every shot against it, the options) before any
/// work: INVALID_ARGUMENT naming the field.
absl::StatusOr<CalibrationJob> CalibrationJobFromProto(const v1::CalibrateTableRequest& request);

/// The report as the API's; each strike names its shot's struck ball.
void CalibrationReportToProto(const CalibrationJob& job, const billiards::CalibrationReport& report,
                              v1::CalibrationReport* out);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_BILLIARDS_CALIBRATION_H_
