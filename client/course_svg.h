// A golf course from above as SVG: elevation shading, the surfaces (OpenStreetMap's golf
// classes), the boundary, tees and pins, and optionally a shot's path, events and rest.
#ifndef SPORTSIM_CLIENT_COURSE_SVG_H_
#define SPORTSIM_CLIENT_COURSE_SVG_H_

#include <string>

#include "sportsim/v1/swing.pb.h"

namespace sportsim::cli {

/// `course` must carry its geometry (GetCourse with geometry). `hole` (1-based) frames that
/// hole (its tees and pin, and the shot if given); 0 frames the whole course. `shot` may be null.
std::string CourseSvg(const v1::CourseInfo& course, int hole,
                      const v1::SimulateGolfShotResponse* shot);

}  // namespace sportsim::cli

#endif  // SPORTSIM_CLIENT_COURSE_SVG_H_
