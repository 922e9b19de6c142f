// The last events of a world, for readers resuming with from_sequence (tables and swing
// sessions). Not thread safe: the world's lock guards it.
#ifndef SPORTSIM_SERVER_EVENT_LOG_H_
#define SPORTSIM_SERVER_EVENT_LOG_H_

#include <algorithm>
#include <cstdint>
#include <deque>
#include <memory>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_format.h"

namespace sportsim::server {

template <typename Event>
class EventLog {
 public:
  using Ptr = std::shared_ptr<const Event>;

  /// Stamps `e` with `sequence`, keeps it (the oldest go past `capacity`), and returns it.
  Ptr Append(Event e, uint64_t sequence, int capacity) {
    e.set_sequence(sequence);
    auto p = std::make_shared<const Event>(std::move(e));
    events_.push_back(p);
    while (static_cast<int>(events_.size()) > capacity) {
      evicted_ = events_.front()->sequence();
      events_.pop_front();
    }
    return p;
  }

  /// The events after sequence `from`, for a reader resuming there; `*lost` when some of them
  /// are no longer held (the reader must resync). OUT_OF_RANGE when `from` is ahead of
  /// `current`, the world's sequence (`world`: "table", "session").
  absl::StatusOr<std::vector<Ptr>> After(uint64_t from, uint64_t current, std::string_view world,
                                         bool* lost) const {
    if (from > current) {
      return absl::OutOfRangeError(absl::StrFormat(
          "from_sequence %d is ahead of the %s's sequence %d", from, world, current));
    }
    *lost = evicted_ > from;
    std::vector<Ptr> out;
    for (const Ptr& e : events_) {
      if (e->sequence() > from) out.push_back(e);
    }
    return out;
  }

  /// Events up to `sequence` are not held (a world restored from a checkpoint): a reader that
  /// resumes from before it is told it lost events.
  void MarkEvicted(uint64_t sequence) { evicted_ = std::max(evicted_, sequence); }

 private:
  std::deque<Ptr> events_;
  uint64_t evicted_ = 0;  // the highest sequence no longer held
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_EVENT_LOG_H_
