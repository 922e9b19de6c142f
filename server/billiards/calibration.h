// CalibrateTable: the request as a sim/billiards calibration, and its report as the API's.
// Pure translation, tested without a network. Errors name the field ("shots[2].points[7].t_s").
#ifndef SPORTSIM_SERVER_BILLIARDS_CALIBRATION_H_
#define SPORTSIM_SERVER_BILLIARDS_CALIBRATION_H_

#include <cstdint>
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

/// UploadCalibration's messages put back together into one CalibrateTableRequest, checking
/// each as it comes so that an upload never holds more than a calibration may take: the
/// first must be `setup` with no shots, then `shot` and `points` parts, at most
/// kMaxCalibrationShots shots and kMaxCalibrationPoints points. INVALID_ARGUMENT names the
/// message (`upload[3].points`). The whole request is checked by CalibrationJobFromProto.
class CalibrationUploadAssembler {
 public:
  absl::Status Add(const v1::CalibrationUpload& part);
  /// The request; INVALID_ARGUMENT when no `setup` came.
  absl::StatusOr<v1::CalibrateTableRequest> Finish() &&;

 private:
  int index_ = 0;        // messages added
  int64_t points_ = 0;   // tracked points in all
  bool setup_ = false;
  v1::CalibrateTableRequest request_;
};

/// The report as the API's; each strike names its shot's struck ball.
void CalibrationReportToProto(const CalibrationJob& job, const billiards::CalibrationReport& report,
                              v1::CalibrationReport* out);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_BILLIARDS_CALIBRATION_H_
