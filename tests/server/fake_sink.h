// A StreamSink for tests: records what it is given. With a reader thread it completes each
// write after a delay; without one (stalled) it never does, like a client that stopped reading.
#ifndef SPORTSIM_TESTS_SERVER_FAKE_SINK_H_
#define SPORTSIM_TESTS_SERVER_FAKE_SINK_H_

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "server/world/watcher.h"

namespace sportsim::server {

// A sink that records what it is given. With a reader thread it completes each write after
// `read_delay`; without one (stalled) it never does, like a client that stopped reading.
template <typename W>
class FakeSinkFor : public StreamSink<typename W::Snapshot> {
 public:
  // Like the gRPC reactor's OnDone: the watcher forgets the sink before it goes.
  ~FakeSinkFor() override {
    StopReading();
    if (watcher_ != nullptr) watcher_->OnDone();
  }
  void Bind(std::shared_ptr<W> w) { watcher_ = std::move(w); }
  void SinkWrite(const typename W::Snapshot* s) override {
    absl::MutexLock lock(&mu_);
    got_.push_back(*s);
    arrival_.push_back(std::chrono::steady_clock::now());
    in_flight_ = true;
  }
  void SinkWriteLast(const typename W::Snapshot* s, const absl::Status& status) override {
    absl::MutexLock lock(&mu_);
    got_.push_back(*s);
    arrival_.push_back(std::chrono::steady_clock::now());
    finished_ = true;
    status_ = status;
  }
  void SinkFinish(const absl::Status& status) override {
    absl::MutexLock lock(&mu_);
    finished_ = true;
    status_ = status;
  }
  void StartReading(std::shared_ptr<W> w, std::chrono::microseconds read_delay) {
    watcher_ = std::move(w);
    reader_ = std::thread([this, read_delay] {
      while (!stop_) {
        bool complete = false;
        {
          absl::MutexLock lock(&mu_);
          complete = in_flight_;
          in_flight_ = false;
        }
        if (complete) watcher_->OnWriteDone(true);
        std::this_thread::sleep_for(read_delay);
      }
    });
  }
  void StopReading() {
    stop_ = true;
    if (reader_.joinable()) reader_.join();
  }
  std::vector<typename W::Snapshot> got() const {
    absl::MutexLock lock(&mu_);
    return got_;
  }
  std::vector<std::chrono::steady_clock::time_point> arrivals() const {
    absl::MutexLock lock(&mu_);
    return arrival_;
  }
  bool finished() const {
    absl::MutexLock lock(&mu_);
    return finished_;
  }
  absl::Status status() const {
    absl::MutexLock lock(&mu_);
    return status_;
  }

 private:
  mutable absl::Mutex mu_;
  std::vector<typename W::Snapshot> got_;
  std::vector<std::chrono::steady_clock::time_point> arrival_;
  bool in_flight_ = false;
  bool finished_ = false;
  absl::Status status_;
  std::shared_ptr<W> watcher_;
  std::thread reader_;
  std::atomic<bool> stop_{false};
};

}  // namespace sportsim::server

#endif  // SPORTSIM_TESTS_SERVER_FAKE_SINK_H_
