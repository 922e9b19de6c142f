// Recorded shots as JSON lines, the other form `table calibrate` reads beside CSV: one JSON
// object a line, a ball at a time,
//
//   {"t": 0, "ball": "white", "x": -0.7, "y": 0.2}
//   {"t": 0.02, "ball": "white", "x": -0.66, "y": 0.21, "frame": 1}
//
// with the keys t (or t_s), ball (or id; a string or a whole number), x (or x_m), y (or y_m),
// other keys ignored; blank lines and lines starting with '#' skipped. The rows mean what
// they mean in a CSV track file (sim/billiards/track_file.h).
//
// A shot set holds many recorded shots in one JSON document, as public three-cushion tracking
// sets are published: an array of shots, each an object with a "balls" object that maps a
// ball's id to its samples as three arrays of the same length,
//
//   [{"id": 7, "balls": {"1": {"t": [0, 0.02, ...], "x": [...], "y": [...]}, "2": {...}}}, ...]
//
// ("t_s", "x_m", "y_m" also name them; other keys ignored). A shot's name is its "id" (or
// "name", "shotID"; a string or a whole number), else its index. A sample at t <= 0 is where
// the ball stood before the strike, as in a track file.
//
// A match-tracking document is the other layout, a match tracker's export as the 3cushiontool
// project reads it: {"Match": {"Sets": [{"Entries": [{"PathTrackingId": 392699, "PathTracking":
// {"DataSets": [{"BallColor": 1, "Coords": [{"DeltaT_500us": 0, "X": 0.21, "Y": 0.64}, ...]}]}}]}]}},
// each tracked entry a shot named by its PathTrackingId, X and Y fractions of the playing
// area's length and width from a corner, times in ticks of 500 us. It sets its own frame, so
// it needs the table's size (TrackFrame::table_m) and no origin or scale. A tracker also
// exports one entry on its own, {"PathTracking": {...}, ...}: a document of one shot.
#ifndef SPORTSIM_CLIENT_TRACK_JSON_H_
#define SPORTSIM_CLIENT_TRACK_JSON_H_

#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "sim/billiards/track_file.h"

namespace sportsim::cli {

/// Parses JSON lines. InvalidArgument naming the line for a line that is not a JSON object, a
/// missing key, a value of the wrong kind or out of range, or what ParseTrackCsv refuses.
absl::StatusOr<billiards::TrackFile> ParseTrackJsonLines(std::string_view text,
                                                         const billiards::TrackFrame& frame = {});

/// A track file either way: JSON lines when its first line that is not blank or a comment
/// starts with '{', else CSV.
absl::StatusOr<billiards::TrackFile> ParseTrackText(std::string_view text,
                                                    const billiards::TrackFrame& frame = {});

/// One recorded shot of a file.
struct NamedTrack {
  std::string name;        ///< the shot's name in a shot set; empty for a one-shot file
  billiards::TrackFile file;
};

/// Most shots a shot set may hold, and most samples in all its shots.
inline constexpr int kMaxShotsPerSet = 10000;
inline constexpr int kMaxShotSetSamples = 4000000;

/// Parses a shot set, a match-tracking document or a tracker's entry. InvalidArgument naming
/// the shot (its index or its path in the document) and the ball for a document that is none
/// of them, a shot without balls, a ball without its samples or with arrays of different
/// lengths, a sample that is not a finite number within 1e6, a ball tracked twice, more than
/// kMaxShotsPerSet shots or kMaxShotSetSamples samples, or an invalid frame. A shot set's balls are in the order of
/// their ids (a document's keys have no order); a match's in the order of its data sets.
absl::StatusOr<std::vector<NamedTrack>> ParseShotSet(std::string_view text,
                                                     const billiards::TrackFrame& frame = {});

/// The shots of a file in any of the forms: a shot set when it starts with '[' (after blanks),
/// a match-tracking document when it is one JSON object with a "Match" key, a tracker's entry
/// when one with a "PathTracking" key, else one shot (ParseTrackText), unnamed.
absl::StatusOr<std::vector<NamedTrack>> ParseTracks(std::string_view text,
                                                    const billiards::TrackFrame& frame = {});

}  // namespace sportsim::cli

#endif  // SPORTSIM_CLIENT_TRACK_JSON_H_
