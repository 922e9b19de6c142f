#include "client/calibration_upload.h"

namespace sportsim::cli {

std::vector<v1::CalibrationUpload> CalibrationUploadParts(const v1::CalibrateTableRequest& request,
                                                          size_t part_bytes) {
  std::vector<v1::CalibrationUpload> parts;
  v1::CalibrationUpload& setup = parts.emplace_back();
  *setup.mutable_setup() = request;
  setup.mutable_setup()->clear_shots();
  for (const v1::RecordedShot& shot : request.shots()) {
    v1::CalibrationUpload* part = &parts.emplace_back();
    v1::RecordedShot* head = part->mutable_shot();
    *head = shot;
    head->clear_points();
    size_t bytes = part->ByteSizeLong();
    int in_part = 0;  // points in the current part
    for (const v1::TrackedPoint& p : shot.points()) {
      // A repeated field's entry: its tag, its length and the point (tag and length take at
      // most three bytes for a point, which is under 16 kB).
      const size_t n = p.ByteSizeLong() + 3;
      if (in_part > 0 && bytes + n > part_bytes) {
        part = &parts.emplace_back();
        part->mutable_points();
        bytes = part->ByteSizeLong() + 4;  // the `points` field's own tag and length
        in_part = 0;
      }
      if (part->has_shot()) {
        *part->mutable_shot()->add_points() = p;
      } else {
        *part->mutable_points()->add_points() = p;
      }
      bytes += n;
      ++in_part;
    }
  }
  return parts;
}

}  // namespace sportsim::cli
