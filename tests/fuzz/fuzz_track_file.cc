// Track files (sim/billiards/track_file.h, client/track_json.h): text bytes -> ParseTrackText,
// CSV or JSON lines by the first line that counts. Errors are short, name
// a line (or the header) and have no raw control characters; an accepted file has a spot per
// ball, finite points after the strike in time order with valid ball indices, and a struck
// ball (if any) that is one of them.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "client/track_json.h"
#include "sim/billiards/track_file.h"
#include "tests/fuzz/fuzz_util.h"

using namespace sportsim;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  absl::StatusOr<billiards::TrackFile> f = cli::ParseTrackText(text);
  if (!f.ok()) {
    fuzz::CheckMessage("ParseTrackText", f.status());
    FUZZ_CHECK(f.status().code() == absl::StatusCode::kInvalidArgument, "code %s",
               f.status().ToString().c_str());
    return 0;
  }
  FUZZ_CHECK(!f->balls.empty() && f->spots.size() == f->balls.size(), "spots and balls");
  for (const Eigen::Vector2d& s : f->spots) FUZZ_CHECK(s.allFinite(), "spot not finite");
  FUZZ_CHECK(f->cue >= -1 && f->cue < static_cast<int>(f->balls.size()), "cue %d", f->cue);
  for (size_t i = 0; i < f->points.size(); ++i) {
    const billiards::TrackPoint& p = f->points[i];
    FUZZ_CHECK(std::isfinite(p.t_s) && p.t_s > 0 && p.xy.allFinite(), "point %zu", i);
    FUZZ_CHECK(p.ball >= 0 && p.ball < static_cast<int>(f->balls.size()), "ball %d", p.ball);
    if (i > 0) FUZZ_CHECK(f->points[i - 1].t_s <= p.t_s, "points out of order at %zu", i);
  }
  return 0;
}
