// Recorded shots as JSON lines, the other form `table calibrate` reads beside CSV: one JSON
// object a line, a ball at a time,
//
//   {"t": 0, "ball": "white", "x": -0.7, "y": 0.2}
//   {"t": 0.02, "ball": "white", "x": -0.66, "y": 0.21, "frame": 1}
//
// with the keys t (or t_s), ball (or id; a string or a whole number), x (or x_m), y (or y_m),
// other keys ignored; blank lines and lines starting with '#' skipped. The rows mean what
// they mean in a CSV track file (sim/billiards/track_file.h).
#ifndef SPORTSIM_CLIENT_TRACK_JSON_H_
#define SPORTSIM_CLIENT_TRACK_JSON_H_

#include <string_view>

#include "absl/status/statusor.h"
#include "sim/billiards/track_file.h"

namespace sportsim::cli {

/// Parses JSON lines. InvalidArgument naming the line for a line that is not a JSON object, a
/// missing key, a value of the wrong kind or out of range, or what ParseTrackCsv refuses.
absl::StatusOr<billiards::TrackFile> ParseTrackJsonLines(std::string_view text);

/// A track file either way: JSON lines when its first line that is not blank or a comment
/// starts with '{', else CSV.
absl::StatusOr<billiards::TrackFile> ParseTrackText(std::string_view text);

}  // namespace sportsim::cli

#endif  // SPORTSIM_CLIENT_TRACK_JSON_H_
