// Track files (sim/billiards/track_file.h, client/track_json.h): text bytes -> ParseTracks, a
// shot set (a JSON array), a match-tracking document or one shot as CSV or JSON lines by the
// first line that counts, on a carom table, in a tracker's frame (millimetres from a corner)
// when the last byte is odd. Errors are short,
// name a line, a header or a shot, and have no raw control characters; every accepted shot
// has a spot per ball, finite points after the strike in time order with valid ball indices,
// and a struck ball (if any) that is one of them.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "client/track_json.h"
#include "sim/billiards/track_file.h"
#include "tests/fuzz/fuzz_util.h"

using namespace sportsim;

namespace {

void CheckShot(const billiards::TrackFile& f) {
  FUZZ_CHECK(!f.balls.empty() && f.spots.size() == f.balls.size(), "spots and balls");
  for (const Eigen::Vector2d& s : f.spots) FUZZ_CHECK(s.allFinite(), "spot not finite");
  FUZZ_CHECK(f.cue >= -1 && f.cue < static_cast<int>(f.balls.size()), "cue %d", f.cue);
  for (size_t i = 0; i < f.points.size(); ++i) {
    const billiards::TrackPoint& p = f.points[i];
    FUZZ_CHECK(std::isfinite(p.t_s) && p.t_s > 0 && p.xy.allFinite(), "point %zu", i);
    FUZZ_CHECK(p.ball >= 0 && p.ball < static_cast<int>(f.balls.size()), "ball %d", p.ball);
    if (i > 0) FUZZ_CHECK(f.points[i - 1].t_s <= p.t_s, "points out of order at %zu", i);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  // A carom table; the file in millimetres from its corner when the last byte is odd.
  billiards::TrackFrame frame{.table_m = Eigen::Vector2d(2.84, 1.42)};
  if (size > 0 && (data[size - 1] & 1)) {
    frame.scale = 1e-3;
    frame.origin = -frame.table_m / 2;
  }
  absl::StatusOr<std::vector<cli::NamedTrack>> tracks = cli::ParseTracks(text, frame);
  if (!tracks.ok()) {
    fuzz::CheckMessage("ParseTracks", tracks.status());
    FUZZ_CHECK(tracks.status().code() == absl::StatusCode::kInvalidArgument, "code %s",
               tracks.status().ToString().c_str());
    return 0;
  }
  FUZZ_CHECK(!tracks->empty() && tracks->size() <= cli::kMaxShotsPerSet, "%zu shots",
             tracks->size());
  for (const cli::NamedTrack& t : *tracks) CheckShot(t.file);
  return 0;
}
