// One host for every kind of authoritative world (billiards tables, swing sessions, and any
// sport that comes next). The host owns what worlds share: the map of worlds and its paging,
// limits, statistics, watchers and the event log, seat authorization, and the tick loop as a
// sequence of named stages (docs/architecture.md describes each). A kind supplies only what
// differs: its data, how to advance a run by one tick and how that run ended, the frame a
// watcher sends, and what happens at a run's end. No gRPC here.
//
// A Kind is a struct with:
//   using Watch = ...;        // the BasicWatcher traits (Frame, Event proto, Snapshot, Options)
//   struct Data;              // a world's own members; World<Kind> derives from it, and they
//                             // are guarded by the world's `mu` unless fixed at creation
//   struct TickOut;           // what advancing reports (domain events), published afterwards
//   struct End;               // how a run ended
//   static constexpr std::string_view kNoun, kIdPrefix, kIdField, kCreateRpc,
//                                     kMaxWorldsFlag, kMaxWatchersFlag;
//   static bool Running(const World<Kind>&);  // a run (shot, swing) is in progress
//   static std::optional<End> AdvanceTick(Host&, World<Kind>&, int64_t k, TickOut*);
//   static OffLockWork OffLock(World<Kind>&, TickOut*);   // may be empty
//   static void Publish(Host&, World<Kind>&, TickOut*, std::vector<EventPtr>* fresh);
//   static void EndRun(Host&, World<Kind>&, const End&, std::vector<EventPtr>* fresh,
//                      Pump* pump);
//   static std::shared_ptr<const Frame> MakeFrame(const World<Kind>&, int64_t k, bool heartbeat,
//                                                 SteadyClock::time_point published);
//   static std::optional<int64_t> RestDeadline(const World<Kind>&);  // at rest: a tick at
//                                     // which something is due (a shot clock), if any
//   static void AtRestDeadline(Host&, World<Kind>&, std::vector<EventPtr>* fresh);  // it is due
//
// Locks: WorldHost::mu_ -> World::mu -> Watcher::mu_ -> TickScheduler::mu_ (never the other
// way). Sinks are pumped only with no lock held.
#ifndef SPORTSIM_SERVER_WORLD_WORLD_HOST_H_
#define SPORTSIM_SERVER_WORLD_WORLD_HOST_H_

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "server/world/event_log.h"
#include "server/world/scheduler.h"
#include "server/world/watcher.h"
#include "server/world/world.h"
#include "sim/core/check.h"

namespace sportsim::server {

/// What a host allows; the same for every kind (each kind's host has its own copy).
struct WorldLimits {
  int max_worlds = 2000;         ///< worlds of this kind (--max_tables, --max_sessions)
  int max_watchers = 64;         ///< readers per world
  int event_log = 512;           ///< events a world holds for resuming readers
  int watcher_backlog = 1024;    ///< events a reader may have unsent before it is resynced
  int workers = 0;               ///< tick threads when the host has its own scheduler; 0: one
                                 ///< per core
  int max_catchup_ticks = 12;    ///< a world further behind slips instead of racing
  absl::Duration heartbeat = absl::Seconds(1);  ///< at rest, a snapshot this often
  /// Table time per wall-clock time: 1 is real time; more runs every world of the host faster
  /// (tests, bots). Outcomes depend on ticks only, never on this.
  double clock_rate = 1.0;
};

/// Counters of one kind of world (monotonic totals, and the current counts).
struct WorldStats {
  int64_t ticks = 0;           ///< ticks advanced
  int64_t late_ticks = 0;      ///< advanced more than one period after their deadline
  int64_t slipped_ticks = 0;   ///< never advanced on time: the catch-up cap moved the world's
                               ///< clock on instead (not counted in ticks or late_ticks)
  int64_t snapshots_sent = 0;
  int64_t snapshots_replaced = 0;  ///< latest wins: offered but overtaken before being sent
  int64_t resyncs = 0;
  int64_t events = 0;          ///< events produced
  int64_t tick_cpu_ns = 0;     ///< thread CPU the scheduler's workers spent (every kind)
  int worlds = 0;
  int running = 0;             ///< worlds with a run (shot, swing) in progress
  int watchers = 0;
};

template <typename Kind>
class WorldHost;

/// Authorize()'s answer for the admin token.
inline constexpr int kAdminSeat = -1;

/// Work a tick does without the world's lock (a ball flight), before it publishes.
using OffLockWork = std::function<void()>;

/// One live world of a kind: what the host keeps for every world, plus the kind's Data.
template <typename Kind>
struct World final : Ticked, Kind::Data, std::enable_shared_from_this<World<Kind>> {
  using Watcher = BasicWatcher<typename Kind::Watch>;
  using Frame = typename Kind::Watch::Frame;
  using Event = typename Kind::Watch::Event;
  using EventPtr = std::shared_ptr<const Event>;
  using Pump = std::vector<std::shared_ptr<Watcher>>;

  explicit World(WorldHost<Kind>* h) : host(h) {}
  void Wake(uint64_t generation, SteadyClock::time_point now) override {
    host->Process(this->shared_from_this(), generation, now);
  }

  WorldHost<Kind>* const host;
  // Fixed once the world is added.
  std::string id;
  double tick_hz = 1.0;
  double period_s = 1.0;
  std::vector<SeatEntry> seats;
  std::string admin_token;  ///< the game backend's ("" : none)

  absl::Mutex mu;
  TickClock clock ABSL_GUARDED_BY(mu);
  int64_t tick ABSL_GUARDED_BY(mu) = 0;  ///< last tick advanced or acted on
  uint64_t sequence ABSL_GUARDED_BY(mu) = 0;
  EventLog<Event> log ABSL_GUARDED_BY(mu);
  std::vector<std::shared_ptr<Watcher>> watchers ABSL_GUARDED_BY(mu);
  bool deleted ABSL_GUARDED_BY(mu) = false;
  bool closed ABSL_GUARDED_BY(mu) = false;  ///< the server is shutting down
  uint64_t wake_generation ABSL_GUARDED_BY(mu) = 0;

  /// UNAVAILABLE while shutting down, NOT_FOUND once deleted.
  absl::Status Gone() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    if (closed) return absl::UnavailableError("the server is shutting down");
    if (deleted) {
      return absl::NotFoundError(
          absl::StrFormat("%s: %s %s was deleted", Kind::kIdField, Kind::kNoun, id));
    }
    return absl::OkStatus();
  }
  /// The seat of `token`, kAdminSeat for the admin token (or a Gone() status). Compares every
  /// token in full, in constant time.
  absl::StatusOr<int> Authorize(const std::string& token) const
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    if (absl::Status gone = Gone(); !gone.ok()) return gone;
    const bool admin = !admin_token.empty() && TokensEqual(admin_token, token);
    const int index = SeatOf(seats, token);
    if (admin) return kAdminSeat;
    if (index < 0) {
      return absl::PermissionDeniedError(absl::StrFormat("token: not a seat of this %s", Kind::kNoun));
    }
    return index;
  }
  /// The tick the clock is at (never behind the last tick advanced).
  int64_t ClockTick(SteadyClock::time_point now) const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    return clock.Tick(now, tick);
  }
  /// The tick now: the last one advanced while a run is in progress, else the clock's.
  int64_t NowTick() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    return Kind::Running(*this) ? tick : ClockTick(SteadyClock::now());
  }
  double WorldTime(int64_t k) const { return static_cast<double>(k) * period_s; }
  /// A frame of tick k. `ticked`: made by a tick, whose latency counts from the tick's
  /// deadline; frames made by calls count from now.
  std::shared_ptr<const Frame> MakeFrame(int64_t k, bool heartbeat, bool ticked = false)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    return Kind::MakeFrame(*this, k, heartbeat, ticked ? clock.Deadline(k) : SteadyClock::now());
  }
  /// Stamps an event with the current sequence and keeps it for resuming readers.
  EventPtr Log(Event e) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    return log.Append(std::move(e), sequence, host->limits().event_log);
  }
  /// Offers a frame (or none: the events wait) and events to every reader; those to pump
  /// once the lock is released go to `pump`.
  void OfferAll(const std::shared_ptr<const Frame>& frame, const std::vector<EventPtr>& fresh,
                Pump* pump) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    for (const std::shared_ptr<Watcher>& w : watchers) {
      if (w->Offer(frame, fresh)) pump->push_back(w);
    }
  }
  void Forget(const Watcher* w) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    watchers.erase(std::remove_if(watchers.begin(), watchers.end(),
                                  [w](const std::shared_ptr<Watcher>& x) { return x.get() == w; }),
                   watchers.end());
  }
};

/// A page of worlds (ListTables, ListSessions).
struct PageRequest {
  uint32_t page_size = 0;  ///< 0: 100; at most 1000
  std::string page_token;  ///< the last id of the previous page
};

template <typename Kind>
class WorldHost {
 public:
  using WorldT = World<Kind>;
  using Watcher = typename WorldT::Watcher;
  using Frame = typename WorldT::Frame;
  using Event = typename WorldT::Event;
  using EventPtr = typename WorldT::EventPtr;
  using Pump = typename WorldT::Pump;
  using Options = typename Kind::Watch::Options;

  /// Ticks run on `scheduler` (shared with the other kinds; its owner stops it before
  /// destroying the host), or on a scheduler of the host's own with limits.workers threads.
  WorldHost(WorldLimits limits, TickScheduler* scheduler)
      : limits_(limits), counters_(std::make_shared<WatchCounters>()) {
    if (scheduler == nullptr) {
      own_scheduler_ = std::make_unique<TickScheduler>(limits_.workers);
      scheduler = own_scheduler_.get();
    }
    scheduler_ = scheduler;
  }
  ~WorldHost() { Shutdown(absl::UnavailableError("the server is shutting down")); }
  WorldHost(const WorldHost&) = delete;
  WorldHost& operator=(const WorldHost&) = delete;

  const WorldLimits& limits() const { return limits_; }
  const LatencyHistogram& publish_to_write() const { return counters_->publish_to_write; }

  /// A new world for the kind to fill before Add().
  std::shared_ptr<WorldT> Make() { return std::make_shared<WorldT>(this); }

  /// Gives the world a fresh id and keeps it: RESOURCE_EXHAUSTED past max_worlds.
  absl::Status Add(const std::shared_ptr<WorldT>& world) {
    absl::MutexLock lock(&mu_);
    if (shut_down_) return Unavailable();
    if (static_cast<int>(worlds_.size()) >= limits_.max_worlds) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "the server holds its maximum of %d %ss (%s)", limits_.max_worlds, Kind::kNoun,
          Kind::kMaxWorldsFlag));
    }
    do {
      world->id = std::string(Kind::kIdPrefix) + RandomHex(6);
    } while (worlds_.count(world->id) > 0);
    worlds_[world->id] = world;
    return absl::OkStatus();
  }

  /// The world with this id: INVALID_ARGUMENT for a malformed id, NOT_FOUND, UNAVAILABLE.
  absl::StatusOr<std::shared_ptr<WorldT>> Find(const std::string& id) {
    if (absl::Status s = CheckWorldId(id); !s.ok()) return s;
    absl::MutexLock lock(&mu_);
    return FindLocked(id);
  }

  /// A seat's call: checks the token, finds the world, and under its lock authorizes the seat
  /// and runs fn(world_ptr, seat, pump); readers offered to are pumped after the lock.
  template <typename R, typename Fn>
  absl::StatusOr<R> Act(const std::string& id, const std::string& token, Fn fn) {
    if (absl::Status s = CheckToken(token, Kind::kCreateRpc); !s.ok()) return s;
    absl::StatusOr<std::shared_ptr<WorldT>> found = Find(id);
    if (!found.ok()) return found.status();
    Pump pump;
    absl::StatusOr<R> result;
    {
      absl::MutexLock lock(&(*found)->mu);
      // What fell due at rest before this call (a shot clock) takes effect first, at its own
      // tick: ticks decide, not which worker or call got to the world first.
      if (!Kind::Running(**found) && RestDeadline(**found, SteadyClock::now(), &pump)) {
        ScheduleRest(**found);
      }
      absl::StatusOr<int> seat = (*found)->Authorize(token);
      if (!seat.ok()) return seat.status();
      result = fn(*found, *seat, pump);
    }
    PumpAll(pump);
    return result;
  }

  /// One page of worlds in id order; `brief(world)` is called under each world's lock.
  /// Returns the total and sets `next_page_token` when more follow.
  template <typename Fn>
  absl::StatusOr<uint32_t> List(const PageRequest& request, std::string* next_page_token,
                                Fn brief) {
    if (request.page_size > 1000) {
      return absl::InvalidArgumentError(
          absl::StrFormat("page_size must be in [0, 1000], got %d", request.page_size));
    }
    if (request.page_token.size() > 64) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "page_token must be a %s id from the previous page (at most 64 characters), got %d "
          "characters",
          Kind::kNoun, request.page_token.size()));
    }
    const size_t page = request.page_size == 0 ? 100 : static_cast<size_t>(request.page_size);
    std::vector<std::shared_ptr<WorldT>> worlds;
    uint32_t total = 0;
    {
      absl::MutexLock lock(&mu_);
      if (shut_down_) return Unavailable();
      total = static_cast<uint32_t>(worlds_.size());
      for (auto it = worlds_.upper_bound(request.page_token);
           it != worlds_.end() && worlds.size() <= page; ++it) {
        worlds.push_back(it->second);
      }
    }
    if (worlds.size() > page) {
      worlds.pop_back();
      *next_page_token = worlds.back()->id;
    }
    for (const std::shared_ptr<WorldT>& w : worlds) {
      absl::MutexLock lock(&w->mu);
      brief(*w);
    }
    return total;
  }

  /// Removes a world (any seat's token; `may_delete(world, seat)` may refuse under its lock),
  /// ends its run with `on_delete`, and closes every reader after a last frame.
  template <typename MayDelete, typename OnDelete>
  absl::Status Delete(const std::string& id, const std::string& token, MayDelete may_delete,
                      OnDelete on_delete) {
    if (absl::Status s = CheckWorldId(id); !s.ok()) return s;
    if (absl::Status s = CheckToken(token, Kind::kCreateRpc); !s.ok()) return s;
    std::shared_ptr<WorldT> world;
    {
      absl::MutexLock lock(&mu_);
      absl::StatusOr<std::shared_ptr<WorldT>> found = FindLocked(id);
      if (!found.ok()) return found.status();
      world = *std::move(found);
      {
        // The token is checked before anything changes.
        absl::MutexLock wlock(&world->mu);
        absl::StatusOr<int> seat = world->Authorize(token);
        if (!seat.ok()) return seat.status();
        if (absl::Status s = may_delete(*world, *seat); !s.ok()) return s;
      }
      worlds_.erase(id);
    }
    Pump pump;
    {
      absl::MutexLock lock(&world->mu);
      world->deleted = true;
      std::vector<EventPtr> fresh;
      on_delete(*world, &fresh, &pump);
      const std::shared_ptr<const Frame> last = world->MakeFrame(world->NowTick(), false);
      const absl::Status gone = absl::NotFoundError(
          absl::StrFormat("%s: %s %s was deleted", Kind::kIdField, Kind::kNoun, world->id));
      for (const std::shared_ptr<Watcher>& w : world->watchers) {
        w->Offer(nullptr, fresh);  // the run's end rides with the last snapshot
        if (w->Close(gone, last)) pump.push_back(w);
      }
    }
    PumpAll(pump);
    return absl::OkStatus();
  }

  /// Readers: the ticks between snapshots for a rate (0: every tick; above the tick rate is
  /// every tick). INVALID_ARGUMENT (naming `field`) outside (0, 1000].
  static absl::StatusOr<double> IntervalTicks(std::string_view field, double rate_hz,
                                              double tick_hz) {
    if (rate_hz == 0) return 1.0;
    if (absl::Status s = sportsim::CheckFiniteInRange(field, rate_hz, 0, true, 1000, false); !s.ok()) {
      return s;
    }
    return std::max(1.0, tick_hz / rate_hz);
  }

  /// A reader of `world` writing to `sink` (null: Attach one before pumping).
  std::shared_ptr<Watcher> NewWatcher(const WorldT& world, Options options,
                                      double interval_ticks, StreamSink<typename Kind::Watch::Snapshot>* sink) {
    auto watcher = std::make_shared<Watcher>(world.id, std::move(options), interval_ticks,
                                             limits_.watcher_backlog, counters_);
    watcher->Attach(sink);
    return watcher;
  }

  /// RESOURCE_EXHAUSTED when the world has its maximum of readers.
  absl::Status CheckWatcherRoom(const WorldT& world) const ABSL_EXCLUSIVE_LOCKS_REQUIRED(world.mu) {
    if (static_cast<int>(world.watchers.size()) >= limits_.max_watchers) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "%s %s has its maximum of %d watchers (%s)", Kind::kNoun, world.id,
          limits_.max_watchers, Kind::kMaxWatchersFlag));
    }
    return absl::OkStatus();
  }

  /// Registers a spectator and queues its first snapshot (and, from `from_sequence`, the
  /// events after it); the caller Pump()s it. Errors change nothing.
  absl::StatusOr<std::shared_ptr<Watcher>> Watch(const std::string& id, double rate_hz,
                                                 Options options,
                                                 std::optional<uint64_t> from_sequence,
                                                 StreamSink<typename Kind::Watch::Snapshot>* sink) {
    absl::StatusOr<std::shared_ptr<WorldT>> found = Find(id);
    if (!found.ok()) return found.status();
    WorldT& w = **found;
    absl::StatusOr<double> interval = IntervalTicks("rate_hz", rate_hz, w.tick_hz);
    if (!interval.ok()) return interval.status();
    std::shared_ptr<Watcher> watcher = NewWatcher(w, std::move(options), *interval, sink);
    absl::MutexLock lock(&w.mu);
    if (absl::Status gone = w.Gone(); !gone.ok()) return gone;
    if (absl::Status room = CheckWatcherRoom(w); !room.ok()) return room;
    std::vector<EventPtr> replay;
    if (from_sequence.has_value()) {
      bool lost = false;
      absl::StatusOr<std::vector<EventPtr>> after =
          w.log.After(*from_sequence, w.sequence, Kind::kNoun, &lost);
      if (!after.ok()) return after.status();
      if (lost) watcher->MarkResync();
      replay = *std::move(after);
    }
    const int64_t tick = w.NowTick();
    watcher->Due(tick);  // the first snapshot is now
    watcher->Offer(w.MakeFrame(tick, false), replay);
    w.watchers.push_back(watcher);
    if (!Kind::Running(w) && w.watchers.size() == 1) ScheduleRest(w);
    return watcher;
  }

  /// Forgets a reader whose stream is done.
  void Unwatch(const std::string& id, const Watcher* watcher) {
    std::shared_ptr<WorldT> world;
    {
      absl::MutexLock lock(&mu_);
      auto it = worlds_.find(id);
      if (it == worlds_.end()) return;
      world = it->second;
    }
    absl::MutexLock lock(&world->mu);
    world->Forget(watcher);
  }

  /// Wakes a worker for `w` at `when`, superseding its previous wake.
  void Schedule(WorldT& w, SteadyClock::time_point when) ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    scheduler_->Schedule(w.shared_from_this(), ++w.wake_generation, when);
  }
  void ScheduleNextTick(WorldT& w) ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    Schedule(w, w.clock.Deadline(w.tick + 1));
  }
  /// At rest: the next heartbeat if anyone reads, or the rest deadline if sooner; no wake
  /// when neither (a pending wake is voided).
  void ScheduleRest(WorldT& w, SteadyClock::time_point now = SteadyClock::now())
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    std::optional<SteadyClock::time_point> next;
    if (!w.watchers.empty()) next = now + absl::ToChronoNanoseconds(limits_.heartbeat);
    if (const std::optional<int64_t> d = Kind::RestDeadline(w); d.has_value()) {
      const SteadyClock::time_point at = w.clock.Deadline(*d);
      if (!next.has_value() || at < *next) next = at;
    }
    if (next.has_value()) {
      Schedule(w, *next);
    } else {
      ++w.wake_generation;
    }
  }
  /// A run ended by a call (reset, delete): its pending tick wake is void, and the rest timers
  /// take over.
  void AfterRunEndedByCall(WorldT& w) ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) { ScheduleRest(w); }

  // Counters the kinds keep up to date.
  void CountEvents(size_t n) { events_.fetch_add(static_cast<int64_t>(n)); }
  void RunStarted() { running_.fetch_add(1); }
  void RunEnded() { running_.fetch_sub(1); }

  /// The tick loop: one wake of one world, as named stages (see docs/architecture.md).
  void Process(const std::shared_ptr<WorldT>& ptr, uint64_t generation,
               SteadyClock::time_point now) {
    WorldT& w = *ptr;
    Pump pump;
    w.mu.Lock();
    if (Superseded(w, generation)) {
      w.mu.Unlock();
      return;
    }
    if (!Kind::Running(w)) {
      RestDeadline(w, now, &pump);
      Heartbeat(w, now, &pump);
      ScheduleRest(w, now);
    } else if (const std::optional<CatchUpPlan> plan = CatchUp(w, now); plan.has_value()) {
      typename Kind::TickOut out;
      const Advanced advanced = AdvanceTicks(w, *plan, &out);
      if (OffLockWork work = Kind::OffLock(w, &out)) {
        // Heavy work of this tick (a ball flight) runs without the world's lock: readers and
        // calls go on meanwhile. A call that ended the run or the world supersedes the tick.
        const uint64_t held = w.wake_generation;
        w.mu.Unlock();
        work();
        w.mu.Lock();
        if (Superseded(w, held)) {
          w.mu.Unlock();
          return;
        }
      }
      std::vector<EventPtr> fresh;
      PublishTick(w, &out, &fresh);
      if (advanced.end.has_value()) EndRun(w, *advanced.end, &fresh, &pump);
      CountEvents(fresh.size());
      OfferFrames(w, advanced.end.has_value(), fresh, &pump);
      Reschedule(w, advanced.end.has_value(), now);
    }
    w.mu.Unlock();
    PumpAll(pump);
  }

  /// Ends every stream with `status` after a last snapshot and stops ticking (stops the
  /// host's own scheduler). Afterwards every call fails with UNAVAILABLE. Idempotent.
  template <typename OnClose>
  void Shutdown(const absl::Status& status, OnClose on_close) {
    std::vector<std::shared_ptr<WorldT>> worlds;
    {
      absl::MutexLock lock(&mu_);
      if (shut_down_) return;
      shut_down_ = true;
      for (auto& [id, w] : worlds_) worlds.push_back(w);
    }
    Pump pump;
    for (const std::shared_ptr<WorldT>& p : worlds) {
      absl::MutexLock lock(&p->mu);
      p->closed = true;
      const std::shared_ptr<const Frame> last = p->MakeFrame(p->NowTick(), false);
      on_close(*p);
      for (const std::shared_ptr<Watcher>& w : p->watchers) {
        if (w->Close(status, last)) pump.push_back(w);
      }
    }
    PumpAll(pump);
    // A wake in progress has finished (it saw the world closed, or ran before); pending go.
    if (own_scheduler_ != nullptr) own_scheduler_->Stop();
  }
  void Shutdown(const absl::Status& status) {
    Shutdown(status, [](WorldT&) {});
  }

  WorldStats stats() const {
    WorldStats s;
    s.ticks = ticks_.load();
    s.late_ticks = late_ticks_.load();
    s.slipped_ticks = slipped_ticks_.load();
    s.events = events_.load();
    s.tick_cpu_ns = scheduler_->cpu_ns();
    s.running = running_.load();
    std::vector<std::shared_ptr<WorldT>> worlds;
    {
      absl::MutexLock lock(&mu_);
      s.worlds = static_cast<int>(worlds_.size());
      for (const auto& [id, w] : worlds_) worlds.push_back(w);
    }
    for (const std::shared_ptr<WorldT>& w : worlds) {
      absl::MutexLock lock(&w->mu);
      s.watchers += static_cast<int>(w->watchers.size());
    }
    s.snapshots_sent = counters_->sent.load();
    s.snapshots_replaced = counters_->replaced.load();
    s.resyncs = counters_->resyncs.load();
    return s;
  }

  static void PumpAll(const Pump& pump) {
    for (const std::shared_ptr<Watcher>& w : pump) w->Pump();
  }

 private:
  struct CatchUpPlan {
    int64_t due = 0;     // the last tick whose deadline has passed
    int64_t target = 0;  // the tick to advance to (due, or less when slipping)
  };
  struct Advanced {
    std::optional<typename Kind::End> end;
  };

  static absl::Status Unavailable() { return absl::UnavailableError("the server is shutting down"); }

  absl::StatusOr<std::shared_ptr<WorldT>> FindLocked(const std::string& id)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (shut_down_) return Unavailable();
    auto it = worlds_.find(id);
    if (it == worlds_.end()) {
      return absl::NotFoundError(
          absl::StrFormat("%s: no %s %s", Kind::kIdField, Kind::kNoun, Quote(id)));
    }
    return it->second;
  }

  static absl::Status CheckWorldId(const std::string& id) {
    if (id.empty() || id.size() > 64) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s must be 1 to 64 characters, got %d characters", Kind::kIdField,
                          static_cast<int>(id.size())));
    }
    return absl::OkStatus();
  }

  // Stage 1: a wake for a world deleted, closed or scheduled again since is dropped.
  static bool Superseded(const WorldT& w, uint64_t generation) ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    return w.deleted || w.closed || generation != w.wake_generation;
  }

  // Stage 2a (at rest): what falls due at a tick while nothing moves (a shot clock), at that
  // very tick however late the wake, published like a tick.
  // Returns whether something fell due.
  bool RestDeadline(WorldT& w, SteadyClock::time_point now, Pump* pump)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    const std::optional<int64_t> deadline = Kind::RestDeadline(w);
    if (!deadline.has_value() || w.clock.DueTick(now) < *deadline) return false;
    w.tick = std::max(w.tick, *deadline);
    ++w.sequence;
    std::vector<EventPtr> fresh;
    Kind::AtRestDeadline(*this, w, &fresh);
    CountEvents(fresh.size());
    w.OfferAll(w.MakeFrame(w.tick, false, true), fresh, pump);
    return true;
  }

  // Stage 2b (at rest): a heartbeat for the readers.
  void Heartbeat(WorldT& w, SteadyClock::time_point now, Pump* pump)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    if (w.watchers.empty()) return;
    const std::shared_ptr<const Frame> beat = w.MakeFrame(w.ClockTick(now), true);
    for (const std::shared_ptr<Watcher>& r : w.watchers) {
      if (r->OfferHeartbeat(beat)) pump->push_back(r);
    }
  }

  // Stage 3: which tick to advance to. Nothing due yet: sleep until the next deadline. Too far
  // behind: advance max_catchup_ticks and move the clock on (the world slips).
  std::optional<CatchUpPlan> CatchUp(WorldT& w, SteadyClock::time_point now)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    const int64_t due = w.clock.DueTick(now);
    if (due <= w.tick) {
      ScheduleNextTick(w);
      return std::nullopt;
    }
    int64_t slipped = 0;
    const int64_t target = w.clock.CatchUp(w.tick, due, limits_.max_catchup_ticks, &slipped);
    if (slipped > 0) slipped_ticks_.fetch_add(slipped);
    return CatchUpPlan{.due = due, .target = target};
  }

  // Stage 4: tick by tick to the target, so that the tick a run ends on does not depend on
  // how many ticks one wake covers; then count the ticks and the late ones (advanced more than
  // a period after their deadline).
  Advanced AdvanceTicks(WorldT& w, const CatchUpPlan& plan, typename Kind::TickOut* out)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    Advanced a;
    int64_t k = w.tick;
    while (k < plan.target && !a.end.has_value()) {
      ++k;
      a.end = Kind::AdvanceTick(*this, w, k, out);
    }
    const int64_t late = std::min(k, plan.due - 1) - w.tick;
    if (late > 0) late_ticks_.fetch_add(late);
    ticks_.fetch_add(k - w.tick);
    w.tick = k;
    return a;
  }

  // Stage 5: a new sequence number, and the tick's events converted once and logged.
  void PublishTick(WorldT& w, typename Kind::TickOut* out, std::vector<EventPtr>* fresh)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    ++w.sequence;
    Kind::Publish(*this, w, out, fresh);
  }

  // Stage 6: the run's end (summary, end event, the kind's consequences).
  void EndRun(WorldT& w, const typename Kind::End& end, std::vector<EventPtr>* fresh, Pump* pump)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    Kind::EndRun(*this, w, end, fresh, pump);
  }

  // Stage 7: each reader due (its own rate, or the run's end) gets the one shared frame of
  // this tick, built at most once; every reader gets the events.
  void OfferFrames(WorldT& w, bool ended, const std::vector<EventPtr>& fresh, Pump* pump)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    std::shared_ptr<const Frame> frame;
    for (const std::shared_ptr<Watcher>& r : w.watchers) {
      const bool due_now = r->Due(w.tick) || ended;
      if (due_now && frame == nullptr) frame = w.MakeFrame(w.tick, false, true);
      if (r->Offer(due_now ? frame : nullptr, fresh)) pump->push_back(r);
    }
  }

  // Stage 8: the next tick's deadline while running; after the end, the rest timers.
  void Reschedule(WorldT& w, bool ended, SteadyClock::time_point now)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    if (!ended) {
      ScheduleNextTick(w);
    } else {
      ScheduleRest(w, now);
    }
  }

  const WorldLimits limits_;
  const std::shared_ptr<WatchCounters> counters_;
  mutable absl::Mutex mu_;
  std::map<std::string, std::shared_ptr<WorldT>, std::less<>> worlds_ ABSL_GUARDED_BY(mu_);
  bool shut_down_ ABSL_GUARDED_BY(mu_) = false;
  std::unique_ptr<TickScheduler> own_scheduler_;
  TickScheduler* scheduler_;
  std::atomic<int64_t> ticks_{0}, late_ticks_{0}, slipped_ticks_{0}, events_{0};
  std::atomic<int> running_{0};
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_WORLD_WORLD_HOST_H_
