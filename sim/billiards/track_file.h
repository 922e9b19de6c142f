// Recorded shots as text: a table of tracked positions, one row a ball at a time, as trackers
// and `sportsim shot simulate --format csv` write them.
//
//   t_s,id,x_m,y_m[,...]      header: the columns t (or t_s), ball (or id), x (or x_m), y (or
//   0,white,-0.7,0.2                  y_m) in any order, other columns ignored
//   0.02,white,-0.66,0.21     seconds from the strike; metres in the table frame (origin at
//   ...                               the centre of the playing area)
//
// A tracker's own frame maps onto the table's through a TrackFrame (its origin and units).
// Lines starting with '#' and blank lines are skipped. Rows with t <= 0 say where a ball
// stood before the strike (its last such row); a ball without one starts where it is first
// tracked. Rows with t > 0 are its track. The struck ball is the first whose tracked position
// leaves its spot by a centimetre, kStruckDistance (or one named by the caller).
#ifndef SPORTSIM_SIM_BILLIARDS_TRACK_FILE_H_
#define SPORTSIM_SIM_BILLIARDS_TRACK_FILE_H_

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "Eigen/Core"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "sim/billiards/calibrate.h"
#include "sim/billiards/model.h"

namespace sportsim::billiards {

struct TrackFile {
  std::vector<std::string> balls;        ///< ids, in order of first appearance
  std::vector<Eigen::Vector2d> spots;    ///< where each stood before the strike
  int cue = -1;  ///< the first ball to depart from its spot (index; Departs), -1: none moved
  std::vector<TrackPoint> points;        ///< t > 0, in time order (a file's order among ties)
};

/// Most rows a track file may hold.
inline constexpr int kMaxTrackRows = 1000000;

/// Where a file's coordinates sit in the table frame: a file's (x, y) is the table's
/// origin + scale (x, y). The default is the table frame itself. A tracker that measures from
/// a corner of the playing area in metres has origin (-length/2, -width/2) and scale 1.
struct TrackFrame {
  double scale = 1.0;                                ///< metres per file unit, > 0
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();  ///< the file's (0, 0), table frame (m)
  /// The playing area's length and width (m), for files that measure in fractions of it (a
  /// match-tracking document, client/track_json.h); zero: not given.
  Eigen::Vector2d table_m = Eigen::Vector2d::Zero();
};

/// The frame of files on `spec`'s table (its playing area as table_m) whose unit is `scale`
/// metres and whose (0, 0) is the table's centre, or with `from_corner` its corner
/// (-length/2, -width/2), x along the length. Not validated (ValidateTrackFrame).
TrackFrame TrackFrameOn(const TableSpec& spec, bool from_corner, double scale);

/// InvalidArgument naming the field for a scale that is not finite and in (0, 1e6], an
/// origin that is not finite and within 1e6 m, or a table size that is not finite and in
/// [0, 1e3] m.
absl::Status ValidateTrackFrame(const TrackFrame& frame);

/// Gathers a track file's rows, in whatever form they come (CSV here; JSON lines in the CLI,
/// client/track_json.h): each a ball's centre at a time, meaning what a CSV row means.
class TrackBuilder {
 public:
  /// Rows in `frame` (valid: ValidateTrackFrame), kept in the table frame.
  explicit TrackBuilder(const TrackFrame& frame = {}) : frame_(frame) {}

  /// Adds one row; `line` names it in errors. InvalidArgument for a t, x or y that is not a
  /// finite number within 1e6 (as written, before the frame maps it), an empty id, or more
  /// than kMaxTrackRows rows.
  absl::Status Add(int line, double t, std::string_view id, double x, double y);
  /// The file: its spots, struck ball and points in time order. InvalidArgument without rows.
  absl::StatusOr<TrackFile> Finish() &&;

 private:
  TrackFrame frame_;
  TrackFile out_;
  int rows_ = 0;
  std::map<std::string, int, std::less<>> index_;
  std::vector<std::optional<Eigen::Vector2d>> before_;                  // last spot, t <= 0
  std::vector<std::optional<std::pair<double, Eigen::Vector2d>>> first_;  // first tracked
};

/// Parses a track file. InvalidArgument naming the line and the column for a missing or
/// malformed header, a row with too few cells, a number that does not parse or is not finite,
/// an empty ball id, more than kMaxTrackRows rows, or an invalid frame. Rows need not be in
/// time order. Positions are in `frame` (the table's by default).
absl::StatusOr<TrackFile> ParseTrackCsv(std::string_view text, const TrackFrame& frame = {});

}  // namespace sportsim::billiards

#endif  // SPORTSIM_SIM_BILLIARDS_TRACK_FILE_H_
