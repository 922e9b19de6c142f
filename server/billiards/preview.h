// Aim lines (PreviewShot): from a live table's balls at rest, the paths of the struck ball and
// of the first ball it meets, up to a few events each, without noise and with no side effect.
// The table's state is copied under its lock (TableRegistry::PreparePreview); the simulation
// runs anywhere (the simulation pool). No gRPC here.
#ifndef SPORTSIM_SERVER_BILLIARDS_PREVIEW_H_
#define SPORTSIM_SERVER_BILLIARDS_PREVIEW_H_

#include <functional>
#include <memory>

#include "absl/status/status.h"
#include "sim/billiards/cue.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/model.h"
#include "sim/billiards/state.h"
#include "sportsim/v1/billiards.pb.h"

namespace sportsim::server {

/// Most events of each followed ball a preview reports.
inline constexpr int kMaxPreviewEvents = 3;

struct PreviewJob {
  std::shared_ptr<const billiards::TableModel> model;
  billiards::SolverOptions solver;
  billiards::TableState balls;    ///< at rest
  billiards::CueStrike strike;    ///< without noise
  int cue = -1;                   ///< the struck ball
  int max_events = kMaxPreviewEvents;
};

/// Simulates the preview, polling `stop` (CANCELLED when it says so). Path points every 5 ms
/// of simulated time and at the end; events as TableEvents.
absl::Status RunPreview(const PreviewJob& job, const std::function<bool()>& stop,
                        v1::PreviewShotResponse* out);

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_BILLIARDS_PREVIEW_H_
