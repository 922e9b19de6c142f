// UploadCalibration's messages for a calibration: the request cut into parts that each stay
// within a server's request limit, however many recorded shots it has.
#ifndef SPORTSIM_CLIENT_CALIBRATION_UPLOAD_H_
#define SPORTSIM_CLIENT_CALIBRATION_UPLOAD_H_

#include <cstddef>
#include <vector>

#include "sportsim/v1/billiards.pb.h"

namespace sportsim::cli {

/// The default size of a part: half the server's default request limit (64 KiB).
inline constexpr size_t kUploadPartBytes = 32 << 10;

/// The messages, in order: `setup` (the request without its shots); then for each shot a
/// `shot` with its fields and as many of its points as keep the message within part_bytes
/// (encoded), and `points` messages with the rest, each within part_bytes. A part holds at
/// least one point whatever its size.
std::vector<v1::CalibrationUpload> CalibrationUploadParts(const v1::CalibrateTableRequest& request,
                                                          size_t part_bytes = kUploadPartBytes);

}  // namespace sportsim::cli

#endif  // SPORTSIM_CLIENT_CALIBRATION_UPLOAD_H_
