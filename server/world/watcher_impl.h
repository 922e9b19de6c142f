// Member definitions of BasicWatcher (watcher.h). Include only from the .cc file that
// instantiates a kind: `template class BasicWatcher<Kind>;`.
#ifndef SPORTSIM_SERVER_WATCHER_IMPL_H_
#define SPORTSIM_SERVER_WATCHER_IMPL_H_

#include <algorithm>
#include <utility>

#include "server/world/watcher.h"

namespace sportsim::server {

template <typename T>
BasicWatcher<T>::BasicWatcher(std::string id, Options options, double interval_ticks,
                              int backlog, std::shared_ptr<WatchCounters> counters)
    : id_(std::move(id)),
      options_(std::move(options)),
      interval_ticks_(std::max(1.0, interval_ticks)),
      backlog_(backlog),
      counters_(counters != nullptr ? std::move(counters) : std::make_shared<WatchCounters>()) {}

template <typename T>
void BasicWatcher<T>::Attach(Sink* sink) {
  absl::MutexLock lock(&mu_);
  sink_ = sink;
}

template <typename T>
bool BasicWatcher<T>::Offer(std::shared_ptr<const Frame> frame,
                            const std::vector<EventPtr>& events) {
  absl::MutexLock lock(&mu_);
  if (finished_ || closing_) return false;
  if (static_cast<int>(events_.size() + events.size()) > backlog_) {
    // Too far behind: drop what is queued and send the full state with a resync marker.
    lost_ += events_.size() + events.size();
    events_.clear();
    if (!resync_) counters_->resyncs.fetch_add(1);
    resync_ = true;
  } else {
    events_.insert(events_.end(), events.begin(), events.end());
  }
  if (frame != nullptr) {
    if (pending_ != nullptr && !pending_->heartbeat) {
      ++replaced_;
      counters_->replaced.fetch_add(1);
    }
    pending_ = std::move(frame);
  }
  return !in_flight_;
}

template <typename T>
bool BasicWatcher<T>::OfferHeartbeat(std::shared_ptr<const Frame> frame) {
  absl::MutexLock lock(&mu_);
  if (finished_ || closing_ || pending_ != nullptr) return false;
  pending_ = std::move(frame);
  return !in_flight_;
}

template <typename T>
void BasicWatcher<T>::MarkResync() {
  absl::MutexLock lock(&mu_);
  if (!resync_) counters_->resyncs.fetch_add(1);
  resync_ = true;
}

template <typename T>
bool BasicWatcher<T>::Due(int64_t tick) {
  absl::MutexLock lock(&mu_);
  const double k = static_cast<double>(tick);
  if (k < next_due_) return false;
  next_due_ += interval_ticks_;
  if (next_due_ <= k) next_due_ = k + interval_ticks_;
  return true;
}

template <typename T>
bool BasicWatcher<T>::Close(const absl::Status& status, std::shared_ptr<const Frame> last) {
  absl::MutexLock lock(&mu_);
  if (finished_ || closing_) return false;
  closing_ = true;
  close_status_ = status;
  if (last != nullptr) {
    if (pending_ != nullptr && !pending_->heartbeat) {
      ++replaced_;
      counters_->replaced.fetch_add(1);
    }
    pending_ = std::move(last);
  }
  return !in_flight_;
}

template <typename T>
void BasicWatcher<T>::Build(Snapshot* out) {
  out->Clear();
  // Pump builds only with a frame pending (events alone wait for one).
  const std::shared_ptr<const Frame> frame = std::move(pending_);
  pending_ = nullptr;
  uint64_t sequence = std::max(last_sequence_, frame->sequence);
  T::Fill(options_, id_, *frame, last_sent_.get(), resync_ || last_sent_ == nullptr, out);
  if (!frame->heartbeat) {
    counters_->publish_to_write.Add(std::chrono::duration_cast<std::chrono::nanoseconds>(
        SteadyClock::now() - frame->published));
    last_sent_ = frame;
  }
  for (const EventPtr& e : events_) {
    *out->add_events() = *e;
    sequence = std::max(sequence, e->sequence());
  }
  events_.clear();
  out->set_sequence(sequence);
  last_sequence_ = sequence;
  // A resync is announced with the full state; a heartbeat leaves it for the next.
  const bool full_state = !frame->heartbeat;
  out->set_resync(resync_ && full_state);
  out->set_events_lost(lost_);
  out->set_snapshots_replaced(static_cast<uint64_t>(replaced_));
  if (full_state) resync_ = false;
  ++sent_;
  counters_->sent.fetch_add(1);
}

template <typename T>
void BasicWatcher<T>::Pump() {
  enum { kNothing, kWrite, kWriteLast, kFinish } action = kNothing;
  Sink* sink = nullptr;
  absl::Status status;
  {
    absl::MutexLock lock(&mu_);
    if (sink_ == nullptr || in_flight_ || finished_) return;
    sink = sink_;
    if (cancelled_) {
      finished_ = true;
      action = kFinish;
      status = absl::CancelledError("the watcher went away");
    } else if (pending_ != nullptr) {
      // Events alone wait for the next snapshot (they ride along; the rate holds).
      Build(&out_);
      in_flight_ = true;
      if (closing_ && pending_ == nullptr && events_.empty()) {
        finished_ = true;
        action = kWriteLast;
        status = close_status_;
      } else {
        action = kWrite;
      }
    } else if (closing_) {
      finished_ = true;
      action = kFinish;
      status = close_status_;
    }
  }
  // The sink is alive: it is only destroyed after it was finished (OnDone), and we are the
  // ones who decide to finish it.
  switch (action) {
    case kNothing: break;
    case kWrite: sink->SinkWrite(&out_); break;
    case kWriteLast: sink->SinkWriteLast(&out_, status); break;
    case kFinish: sink->SinkFinish(status); break;
  }
}

template <typename T>
void BasicWatcher<T>::OnWriteDone(bool ok) {
  {
    absl::MutexLock lock(&mu_);
    in_flight_ = false;
    if (!ok) cancelled_ = true;  // the stream broke: finish it
  }
  Pump();
}

template <typename T>
void BasicWatcher<T>::OnCancel() {
  {
    absl::MutexLock lock(&mu_);
    cancelled_ = true;
  }
  Pump();
}

template <typename T>
void BasicWatcher<T>::OnDone() {
  absl::MutexLock lock(&mu_);
  sink_ = nullptr;
  finished_ = true;
  pending_ = nullptr;
  events_.clear();
  last_sent_ = nullptr;
}

template <typename T>
int64_t BasicWatcher<T>::sent() const {
  absl::MutexLock lock(&mu_);
  return sent_;
}
template <typename T>
int64_t BasicWatcher<T>::replaced() const {
  absl::MutexLock lock(&mu_);
  return replaced_;
}
template <typename T>
bool BasicWatcher<T>::closed() const {
  absl::MutexLock lock(&mu_);
  return finished_ || closing_;
}

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_WATCHER_IMPL_H_
