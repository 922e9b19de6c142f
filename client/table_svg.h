// Top views of a billiards table as SVG: the cloth, cushions and pockets, each ball's path,
// collisions marked. Used by `shot simulate --svg` (and the table watch).
#ifndef SPORTSIM_CLIENT_TABLE_SVG_H_
#define SPORTSIM_CLIENT_TABLE_SVG_H_

#include <string>
#include <string_view>
#include <vector>

#include "sportsim/v1/billiards.pb.h"

namespace sportsim::cli {

/// Text for SVG (ids and titles come from users): & < > " ' escaped.
std::string SvgEscape(std::string_view text);

/// One ball's path: points in time order, and where it started and ended.
struct BallPath {
  std::string id;
  std::vector<double> t_s, x_m, y_m;
  bool pocketed = false;
};

struct TableDrawing {
  v1::TableGeometry geometry;
  std::vector<BallPath> paths;
  std::vector<v1::TableEvent> events;  ///< ball_ball and ball_cushion are marked
  std::string title;
};

/// Paths from a shot's samples (ball order of response.balls), stopping where a ball is pocketed.
std::vector<BallPath> PathsFromShot(const v1::SimulateShotResponse& shot);

/// The SVG document.
std::string TableSvg(const TableDrawing& drawing);

}  // namespace sportsim::cli

#endif  // SPORTSIM_CLIENT_TABLE_SVG_H_
