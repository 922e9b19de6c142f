// Stroboscopic side views of a golf swing as SVG: the arm rod (shoulder to wrists) and the club
// rod (wrists to clubhead) drawn at regular swing times, the clubhead's path, and the impact
// pose in red with its clubhead speed. Used by `swing watch --svg` and `swing drive --svg`.
// Frame and angles: docs/swing.md (shoulder at the origin, x toward the backswing side, y up;
// the wrists at R (sin theta, -cos theta), the clubhead at the wrists + L (sin phi, -cos phi)).
#ifndef SPORTSIM_CLIENT_SWING_SVG_H_
#define SPORTSIM_CLIENT_SWING_SVG_H_

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sportsim/v1/swing.pb.h"

namespace sportsim::cli {

struct SwingDrawing {
  std::vector<v1::SwingSample> samples;   ///< one swing's states, in time order
  std::optional<v1::SwingImpact> impact;  ///< that swing's impact, if it came
  /// R and L (m). Unset: solved from the samples' clubhead positions and angles (two equations,
  /// two unknowns, well posed when the wrists are cocked), else the chapter's 0.62 and 1.1.
  std::optional<double> arm_length_m;
  std::optional<double> club_length_m;
  int poses = 25;                         ///< about this many poses drawn
  std::string title;
  // Collection state (AddSnapshot).
  uint64_t swing_id = 0;                  ///< the swing drawn (0: none yet)
  std::optional<v1::SwingSample> address; ///< the last address state seen, the swing's first pose
};

/// Adds a snapshot's state and impact: the drawing keeps the latest swing only (a new swing id
/// starts it over, from the address pose seen before it). Heartbeats add nothing.
void AddSnapshot(const v1::SwingSnapshot& snapshot, SwingDrawing* drawing);

/// The SVG document.
std::string SwingSvg(const SwingDrawing& drawing);

}  // namespace sportsim::cli

#endif  // SPORTSIM_CLIENT_SWING_SVG_H_
