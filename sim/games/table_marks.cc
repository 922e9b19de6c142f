#include "sim/games/table_marks.h"

#include <cmath>

namespace sportsim::games {

PoolMarks PoolTableMarks(const billiards::TableModel& model) {
  const double half = 0.5 * model.spec().length_m;
  PoolMarks m;
  m.head_rail_x = -half;
  m.foot_rail_x = half;
  // WPA: head and foot strings a quarter of the playing length from their rails.
  m.head_string_x = -half + 0.25 * model.spec().length_m;
  m.foot_string_x = half - 0.25 * model.spec().length_m;
  m.head_spot = Eigen::Vector2d(m.head_string_x, 0.0);
  m.foot_spot = Eigen::Vector2d(m.foot_string_x, 0.0);
  m.centre_spot = Eigen::Vector2d::Zero();
  m.long_string_dir = Eigen::Vector2d::UnitX();
  return m;
}

Eigen::Vector2d FromHeadRail(const billiards::TableModel& model, double distance_m) {
  return Eigen::Vector2d(-0.5 * model.spec().length_m + distance_m, 0.0);
}

bool BehindHeadString(const billiards::TableModel& model, Eigen::Vector2d xy) {
  return xy.x() <= PoolTableMarks(model).head_string_x;
}

bool OnCloth(const billiards::TableModel& model, Eigen::Vector2d xy) {
  const double c = model.cushion_contact_distance();
  const double hx = 0.5 * model.spec().length_m - c;
  const double hy = 0.5 * model.spec().width_m - c;
  return std::isfinite(xy.x()) && std::isfinite(xy.y()) && std::abs(xy.x()) <= hx &&
         std::abs(xy.y()) <= hy;
}

}  // namespace sportsim::games
