// Landmarks of a table, derived from its playing area (TableSpec length_m x width_m, between
// the cushion noses), never from per-table numbers. Frame as in model.h: origin at the centre,
// x along the length, the head (breaking) end at -x, the foot end at +x.
//
// Sources: WPA equipment specifications, "Table markings": the head string is the line
// across the table a quarter of the playing length from the head rail (through the second
// diamonds); the head spot and the foot spot are the centres of the head and foot strings;
// the long string runs along the centre line from the foot spot to the foot rail.
// Snooker's baulk line, D and colour spots (WPBSA) are the snooker referee's (snooker.h); it
// may use FromHeadRail() to measure from the baulk cushion.
#ifndef SPORTSIM_SIM_GAMES_TABLE_MARKS_H_
#define SPORTSIM_SIM_GAMES_TABLE_MARKS_H_

#include "Eigen/Core"
#include "sim/billiards/model.h"

namespace sportsim::games {

struct PoolMarks {
  double head_rail_x = 0.0;    ///< head cushion nose line (m)
  double foot_rail_x = 0.0;    ///< foot cushion nose line (m)
  double head_string_x = 0.0;  ///< head string: a quarter of the length from the head rail (m)
  double foot_string_x = 0.0;  ///< foot string: a quarter of the length from the foot rail (m)
  Eigen::Vector2d head_spot = Eigen::Vector2d::Zero();    ///< centre of the head string (m)
  Eigen::Vector2d foot_spot = Eigen::Vector2d::Zero();    ///< centre of the foot string (m)
  Eigen::Vector2d centre_spot = Eigen::Vector2d::Zero();  ///< centre of the table (m)
  /// Unit direction of the long string, from the foot spot towards the foot rail (+x).
  Eigen::Vector2d long_string_dir = Eigen::Vector2d::UnitX();
};

/// The pool markings of this table (any bounded table: pool, snooker, carom).
PoolMarks PoolTableMarks(const billiards::TableModel& model);

/// A point on the centre line `distance_m` from the head (baulk) rail's nose (m).
Eigen::Vector2d FromHeadRail(const billiards::TableModel& model, double distance_m);

/// The ball's centre is behind the head string or on it (WPA: in the kitchen). A ball's
/// position relative to a line is that of its centre (WPA definitions, "behind the head
/// string").
bool BehindHeadString(const billiards::TableModel& model, Eigen::Vector2d xy);

/// The ball's centre is on the cloth: inside the cushion noses by the contact distance on the
/// long sides and the ends.
bool OnCloth(const billiards::TableModel& model, Eigen::Vector2d xy);

}  // namespace sportsim::games

#endif  // SPORTSIM_SIM_GAMES_TABLE_MARKS_H_
