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
//   static uint64_t Runs(const World<Kind>&);  // runs started so far (shots, swings)
//   static std::string Checkpoint(const World<Kind>&);  // the world at rest, encoded
//
// Locks: WorldHost::mu_ -> World::mu -> Watcher::mu_ -> TickScheduler::mu_ (never the other
// way). Sinks are pumped only with no lock held.
#ifndef SPORTSIM_SERVER_WORLD_WORLD_HOST_H_
#define SPORTSIM_SERVER_WORLD_WORLD_HOST_H_

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
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
#include "server/world/journal.h"
#include "server/world/scheduler.h"
#include "server/world/watcher.h"
#include "server/world/world.h"
#include "sim/core/check.h"
#include "sportsim/store/v1/journal.pb.h"

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
  /// With a journal, a world at rest writes a checkpoint (Kind::Checkpoint) once this many
  /// runs have started since its last one (0: never; a restore replays from the creation).
  uint64_t checkpoint_every_runs = 0;
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
  std::string admin_token_hash;  ///< HashToken of the game backend's token ("" : none)

  absl::Mutex mu;
  TickClock clock ABSL_GUARDED_BY(mu);
  int64_t tick ABSL_GUARDED_BY(mu) = 0;  ///< last tick advanced or acted on
  uint64_t sequence ABSL_GUARDED_BY(mu) = 0;
  EventLog<Event> log ABSL_GUARDED_BY(mu);
  std::vector<std::shared_ptr<Watcher>> watchers ABSL_GUARDED_BY(mu);
  bool deleted ABSL_GUARDED_BY(mu) = false;
  bool closed ABSL_GUARDED_BY(mu) = false;  ///< the server is shutting down
  uint64_t wake_generation ABSL_GUARDED_BY(mu) = 0;
  // The journal (journal.h).
  bool committing ABSL_GUARDED_BY(mu) = false;  ///< a command is being made durable: the
                                                ///< world is frozen (no tick, no other call)
  bool wake_skipped ABSL_GUARDED_BY(mu) = false;  ///< a wake came while committing
  bool off_lock ABSL_GUARDED_BY(mu) = false;  ///< a tick's off-lock work runs: calls wait, so
                                              ///< that a call never lands inside a tick
  bool restoring ABSL_GUARDED_BY(mu) = false;   ///< being replayed: no wake acts on it
  std::optional<int64_t> pinned_tick ABSL_GUARDED_BY(mu);  ///< a command's tick while it
                                                           ///< commits and takes effect
  uint64_t journal_index ABSL_GUARDED_BY(mu) = 0;  ///< the world's last journal entry
  uint64_t checkpointed_runs ABSL_GUARDED_BY(mu) = 0;  ///< Kind::Runs at the last checkpoint

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
    const std::string hash = HashToken(token);
    const bool admin = !admin_token_hash.empty() && TokensEqual(admin_token_hash, hash);
    const int index = SeatOf(seats, hash);
    if (admin) return kAdminSeat;
    if (index < 0) {
      return absl::PermissionDeniedError(absl::StrFormat("token: not a seat of this %s", Kind::kNoun));
    }
    return index;
  }
  /// The tick the clock is at (never behind the last tick advanced).
  int64_t ClockTick(SteadyClock::time_point now) const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    if (pinned_tick.has_value()) return *pinned_tick;
    return clock.Tick(now, tick);
  }
  /// The tick now: a command's own tick while it takes effect; else the last one advanced while
  /// a run is in progress, else the clock's.
  int64_t NowTick() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    if (pinned_tick.has_value()) return *pinned_tick;
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
  /// A call's change: the frame of tick k (built only when someone reads) and the events to
  /// every reader.
  void OfferFrameAt(int64_t k, const std::vector<EventPtr>& fresh, Pump* pump,
                    bool ticked = false) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    if (watchers.empty()) return;
    OfferAll(MakeFrame(k, false, ticked), fresh, pump);
  }
  void Forget(const Watcher* w) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    watchers.erase(std::remove_if(watchers.begin(), watchers.end(),
                                  [w](const std::shared_ptr<Watcher>& x) { return x.get() == w; }),
                   watchers.end());
  }
};

/// A request as the journal keeps it: serialized, its token cleared.
template <typename Request>
std::string JournalBody(Request request) {
  request.clear_token();
  return request.SerializeAsString();
}

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

  /// The journal every accepted command of this host goes to (null: none, everything in
  /// memory). Set before the first world is added.
  void SetJournal(Journal* journal) { journal_ = journal; }
  Journal* journal() const { return journal_; }

  /// Gives the world a fresh id and keeps it: RESOURCE_EXHAUSTED past max_worlds. With a
  /// journal, the creation (the seats' token hashes and `kind_body`, the kind's encoding of its
  /// creation) is durable first: UNAVAILABLE, and nothing kept, when it cannot be made so.
  absl::Status Add(const std::shared_ptr<WorldT>& world, std::string kind_body = {}) {
    {
      absl::MutexLock lock(&mu_);
      if (shut_down_) return Unavailable();
      if (static_cast<int>(worlds_.size()) + adding_ >= limits_.max_worlds) {
        return absl::ResourceExhaustedError(absl::StrFormat(
            "the server holds its maximum of %d %ss (%s)", limits_.max_worlds, Kind::kNoun,
            Kind::kMaxWorldsFlag));
      }
      do {
        world->id = std::string(Kind::kIdPrefix) + RandomHex(6);
      } while (worlds_.count(world->id) > 0);
      ++adding_;
    }
    absl::Status durable = absl::OkStatus();
    if (journal_ != nullptr) {
      ::sportsim::store::v1::CreatedWorld created;
      created.set_version(1);
      for (const SeatEntry& seat : world->seats) {
        ::sportsim::store::v1::StoredSeat* s = created.add_seats();
        s->set_name(seat.name);
        s->set_token_sha256(seat.token_hash);
      }
      created.set_admin_token_sha256(world->admin_token_hash);
      created.set_tick_hz(world->tick_hz);
      created.set_kind_body(std::move(kind_body));
      durable = journal_->Append(JournalEntry{.world_id = world->id,
                                              .kind = std::string(Kind::kNoun),
                                              .index = 1,
                                              .tick = 0,
                                              .seat = kAdminSeat,
                                              .type = 0,
                                              .body = created.SerializeAsString(),
                                              .anchor_s = journal_->NodeSeconds()});
    }
    absl::MutexLock lock(&mu_);
    --adding_;
    if (!durable.ok()) return durable;
    {
      absl::MutexLock wlock(&world->mu);
      world->journal_index = 1;
    }
    worlds_[world->id] = world;
    return absl::OkStatus();
  }

  /// Makes a command durable before it takes effect. A kind calls it under the world's lock
  /// from a call's function (Act), after every check and before any change: on an error
  /// (UNAVAILABLE: the store is down) the call returns it and nothing changed. The command's
  /// tick is the world's tick now; the world is frozen meanwhile (no tick advances, no other
  /// call acts: the lock is released only for the wait), so the command takes effect at that
  /// very tick, after it is durable, and the reply follows. `seat` is the seat the call was
  /// authorized as, `body` the kind's encoding of the command (no token in it). While a world
  /// is replayed, nothing is written.
  absl::Status Commit(WorldT& w, int seat, uint32_t type, std::string body)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    w.pinned_tick = w.NowTick();
    if (!w.restoring && journal_ != nullptr) {
      absl::Status durable = WaitDurable(w, seat, type, std::move(body), /*remove=*/false);
      if (!durable.ok()) {
        w.pinned_tick.reset();
        return durable;
      }
    }
    ++w.journal_index;
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
      WorldT& w = **found;
      absl::MutexLock lock(&w.mu);
      AwaitCommitted(w);
      // What fell due at rest before this call (a shot clock) takes effect first, at its own
      // tick: ticks decide, not which worker or call got to the world first.
      if (!Kind::Running(w) && RestDeadline(w, SteadyClock::now(), &pump)) {
        ScheduleRest(w);
      }
      absl::StatusOr<int> seat = w.Authorize(token);
      if (!seat.ok()) return seat.status();
      result = fn(*found, *seat, pump);
      AfterCall(w);
    }
    PumpAll(pump);
    return result;
  }

  /// Waits (releasing the lock meanwhile) until no command of `w` is being made durable and
  /// no tick of it is running its off-lock work: a call acts between ticks, never inside one.
  static void AwaitCommitted(WorldT& w) ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    w.mu.Await(absl::Condition(&Quiet, &w));
  }
  /// After a call's function: the command's tick is released, and a wake skipped while it
  /// committed is made up for.
  void AfterCall(WorldT& w) ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    MaybeCheckpoint(w);  // a call may have ended a run (a reset) or changed the world at rest
    w.pinned_tick.reset();
    if (w.wake_skipped) {
      w.wake_skipped = false;
      if (Kind::Running(w)) {
        ScheduleNextTick(w);
      } else {
        ScheduleRest(w);
      }
    }
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
  /// With a journal, the deletion is durable first (the world leaves the store); `body` is
  /// the kind's encoding of the request (no token).
  template <typename MayDelete, typename OnDelete>
  absl::Status Delete(const std::string& id, const std::string& token, MayDelete may_delete,
                      OnDelete on_delete, uint32_t type = 0, std::string body = {}) {
    if (absl::Status s = CheckWorldId(id); !s.ok()) return s;
    if (absl::Status s = CheckToken(token, Kind::kCreateRpc); !s.ok()) return s;
    absl::StatusOr<std::shared_ptr<WorldT>> found = Find(id);
    if (!found.ok()) return found.status();
    std::shared_ptr<WorldT> world = *std::move(found);
    {
      // The token is checked before anything changes; the world is frozen while its deletion
      // is made durable.
      absl::MutexLock wlock(&world->mu);
      AwaitCommitted(*world);
      absl::StatusOr<int> seat = world->Authorize(token);
      if (!seat.ok()) return seat.status();
      if (absl::Status s = may_delete(*world, *seat); !s.ok()) return s;
      absl::Status durable = absl::OkStatus();
      if (journal_ != nullptr) {
        durable = WaitDurable(*world, *seat, type, std::move(body), /*remove=*/true);
      }
      if (!durable.ok()) {
        AfterCall(*world);
        return durable;
      }
      // From here every other call finds the world gone (a second delete too) and its wakes
      // are dropped; no call ends after this one (it has no AfterCall), so nothing of the world
      // is written after its removal (no checkpoint).
      world->deleted = true;
    }
    {
      absl::MutexLock lock(&mu_);
      worlds_.erase(id);
    }
    Pump pump;
    {
      absl::MutexLock lock(&world->mu);
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
    if (w.committing) {
      // A command is being made durable at the world's current tick: nothing moves until it
      // took effect; the call reschedules this wake.
      w.wake_skipped = true;
      w.mu.Unlock();
      return;
    }
    if (!Kind::Running(w)) {
      RestDeadline(w, now, &pump);
      Heartbeat(w, now, &pump);
      ScheduleRest(w, now);
    } else if (const std::optional<CatchUpPlan> plan = CatchUp(w, now); plan.has_value()) {
      typename Kind::TickOut out;
      std::vector<EventPtr> fresh;
      OffLockWork work;
      const Advanced advanced = AdvanceTicks(w, *plan, &out, &fresh, &work, /*count=*/true);
      if (work) {
        // Heavy work of this tick (a ball flight) runs without the world's lock: readers go on
        // meanwhile; calls wait for the tick to end (a call takes effect between ticks, as its
        // replay does). A shutdown supersedes the tick.
        const uint64_t held = w.wake_generation;
        w.off_lock = true;
        w.mu.Unlock();
        work();
        w.mu.Lock();
        w.off_lock = false;
        if (Superseded(w, held)) {
          // The ticks published before this one still reach the readers.
          w.OfferAll(nullptr, fresh, &pump);
          w.mu.Unlock();
          PumpAll(pump);
          return;
        }
      }
      PublishTick(w, &out, &fresh);
      if (advanced.end.has_value()) EndRun(w, *advanced.end, &fresh, &pump);
      CountEvents(fresh.size());
      OfferFrames(w, advanced.end.has_value(), fresh, &pump);
      Reschedule(w, advanced.end.has_value(), now);
    }
    w.mu.Unlock();
    PumpAll(pump);
  }

  /// Recreates a world from the journal (journal.h) and keeps it under its own id:
  /// `make(world, kind_body)` fills the kind's data as at creation (tick_hz is set);
  /// `load(world, checkpoint)` puts the world as it was at rest (its tick and sequence too);
  /// `replay(world, entry, pump)` applies one command as the call did (through the same code,
  /// with the entry's seat; Commit then writes nothing). Between entries the world advances
  /// tick by tick exactly as its ticks did, then on to the tick it had reached when its server
  /// stopped (its clock paused meanwhile), and it goes on ticking from there. As fast as the
  /// CPU allows; no reader sees the replay, and the event log is rebuilt by it.
  template <typename MakeFn, typename LoadFn, typename ReplayFn>
  absl::Status Restore(const StoredWorld& stored, MakeFn make, LoadFn load, ReplayFn replay) {
    if (stored.entries.empty() || stored.entries.front().index != 1) {
      return absl::DataLossError(absl::StrFormat("%s %s: the journal has no creation",
                                                 Kind::kNoun, stored.world_id));
    }
    ::sportsim::store::v1::CreatedWorld created;
    if (!created.ParseFromString(stored.entries.front().body) || created.tick_hz() <= 0) {
      return absl::DataLossError(absl::StrFormat("%s %s: its creation does not parse",
                                                 Kind::kNoun, stored.world_id));
    }
    std::shared_ptr<WorldT> world = Make();
    WorldT& w = *world;
    w.id = stored.world_id;
    for (const ::sportsim::store::v1::StoredSeat& seat : created.seats()) {
      w.seats.push_back(SeatEntry{.name = seat.name(), .token_hash = seat.token_sha256()});
    }
    w.admin_token_hash = created.admin_token_sha256();
    w.tick_hz = created.tick_hz();
    w.period_s = 1.0 / w.tick_hz;
    if (absl::Status s = make(w, created.kind_body()); !s.ok()) {
      return PrefixStatus(absl::StrFormat("%s %s: ", Kind::kNoun, stored.world_id), s);
    }
    Pump pump;  // nobody reads yet
    {
      absl::MutexLock lock(&w.mu);
      w.restoring = true;
      w.journal_index = 1;
      w.clock.tick_hz = w.tick_hz * limits_.clock_rate;
      if (!stored.checkpoint.empty()) {
        if (absl::Status s = load(w, stored.checkpoint); !s.ok()) {
          return PrefixStatus(
              absl::StrFormat("%s %s: checkpoint: ", Kind::kNoun, stored.world_id), s);
        }
        w.log.MarkEvicted(w.sequence);
        w.journal_index = stored.checkpoint_index;
        w.checkpointed_runs = Kind::Runs(w);
      }
      for (const JournalEntry& e : stored.entries) {
        if (e.index <= w.journal_index) continue;
        if (e.index != w.journal_index + 1) {
          return absl::DataLossError(absl::StrFormat("%s %s: journal entry %d is missing",
                                                     Kind::kNoun, stored.world_id,
                                                     w.journal_index + 1));
        }
        ReplayTo(w, e.tick, &pump);
        w.pinned_tick = e.tick;
        absl::Status applied = replay(w, e, pump);
        w.pinned_tick.reset();
        if (!applied.ok()) {
          // The call took effect when it was made; the same code on the same state must too.
          return absl::DataLossError(absl::StrFormat(
              "%s %s: journal entry %d (type %d, tick %d) did not replay: %s", Kind::kNoun,
              stored.world_id, e.index, e.type, e.tick, applied.message()));
        }
        w.journal_index = e.index;
      }
      // The tick the world had reached when its server stopped.
      const double ran_s = std::max(0.0, stored.clock_s - stored.anchor_s);
      const int64_t reached = std::max(
          w.tick, stored.anchor_tick + static_cast<int64_t>(std::floor(ran_s * w.tick_hz)));
      ReplayTo(w, reached, &pump);
      const SteadyClock::time_point now = SteadyClock::now();
      w.clock.origin =
          now - std::chrono::nanoseconds(std::llround(static_cast<double>(reached) * 1e9 /
                                                      w.clock.tick_hz));
      w.restoring = false;
      if (Kind::Running(w)) {
        ScheduleNextTick(w);
      } else {
        ScheduleRest(w, now);
      }
      if (journal_ != nullptr) journal_->Anchor(w.id, reached, journal_->NodeSeconds());
    }
    absl::MutexLock lock(&mu_);
    if (shut_down_) return Unavailable();
    if (!worlds_.emplace(w.id, world).second) {
      return absl::AlreadyExistsError(
          absl::StrFormat("%s %s is already served", Kind::kNoun, w.id));
    }
    return absl::OkStatus();
  }

  /// Replay: advances `w` to tick `target` as its ticks would (runs tick by tick, published
  /// the same way; at rest, what falls due by then), with no clock and no reader.
  void ReplayTo(WorldT& w, int64_t target, Pump* pump) ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    for (;;) {
      if (!Kind::Running(w)) {
        const std::optional<int64_t> d = Kind::RestDeadline(w);
        if (!d.has_value() || *d > target) return;
        FireRestDeadline(w, *d, pump);
        continue;
      }
      if (w.tick >= target) return;
      typename Kind::TickOut out;
      std::vector<EventPtr> fresh;
      OffLockWork work;
      const Advanced advanced =
          AdvanceTicks(w, CatchUpPlan{.due = w.tick + 1, .target = target}, &out, &fresh, &work,
                       /*count=*/false);
      if (work) work();
      PublishTick(w, &out, &fresh);
      if (advanced.end.has_value()) EndRun(w, *advanced.end, &fresh, pump);
    }
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

  // The next journal entry of `w` at its tick now, made durable (`remove`: the world's deletion,
  // after which it leaves the store) with the world frozen: its lock is released only for the
  // wait, with `committing` set, so that no tick and no other call acts meanwhile.
  absl::Status WaitDurable(WorldT& w, int seat, uint32_t type, std::string body, bool remove)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    JournalEntry entry{.world_id = w.id,
                       .kind = std::string(Kind::kNoun),
                       .index = w.journal_index + 1,
                       .tick = w.NowTick(),
                       .seat = seat,
                       .type = type,
                       .body = std::move(body),
                       .anchor_s = journal_->NodeSeconds()};
    w.committing = true;
    w.mu.Unlock();
    absl::Status durable =
        remove ? journal_->Remove(std::move(entry)) : journal_->Append(std::move(entry));
    w.mu.Lock();
    w.committing = false;
    return durable;
  }

  // Stage 1: a wake for a world deleted, closed or scheduled again since is dropped.
  static bool Superseded(const WorldT& w, uint64_t generation) ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    return w.deleted || w.closed || w.restoring || generation != w.wake_generation;
  }
  static bool Quiet(WorldT* w) ABSL_NO_THREAD_SAFETY_ANALYSIS {
    return !w->committing && !w->off_lock;
  }

  // Stage 2a (at rest): what falls due at a tick while nothing moves (a shot clock), at that
  // very tick however late the wake, published like a tick.
  // Returns whether something fell due.
  bool RestDeadline(WorldT& w, SteadyClock::time_point now, Pump* pump)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    const std::optional<int64_t> deadline = Kind::RestDeadline(w);
    if (!deadline.has_value() || w.clock.DueTick(now) < *deadline) return false;
    FireRestDeadline(w, *deadline, pump);
    return true;
  }
  void FireRestDeadline(WorldT& w, int64_t deadline, Pump* pump)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    w.tick = std::max(w.tick, deadline);
    ++w.sequence;
    std::vector<EventPtr> fresh;
    Kind::AtRestDeadline(*this, w, &fresh);
    CountEvents(fresh.size());
    w.OfferFrameAt(w.tick, fresh, pump, /*ticked=*/true);
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
  // how many ticks one wake covers. Every tick but the last is published as it is advanced
  // (its own sequence number, its own events), so that sequence numbers and the event log are
  // a function of ticks and commands, never of how ticks were grouped into wakes (a restore
  // replays them exactly). The last tick (the target, the run's end, or a tick with off-lock
  // work, which ends the wake early) is left in `out` for the later stages. Then count the
  // ticks and the late ones (advanced more than a period after their deadline).
  Advanced AdvanceTicks(WorldT& w, const CatchUpPlan& plan, typename Kind::TickOut* out,
                        std::vector<EventPtr>* fresh, OffLockWork* work, bool count)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    Advanced a;
    const int64_t from = w.tick;
    while (w.tick < plan.target) {
      const int64_t k = w.tick + 1;
      a.end = Kind::AdvanceTick(*this, w, k, out);
      w.tick = k;
      *work = Kind::OffLock(w, out);
      if (a.end.has_value() || *work || k == plan.target) break;
      PublishTick(w, out, fresh);
      *out = typename Kind::TickOut{};
    }
    if (count) {
      const int64_t late = std::min(w.tick, plan.due - 1) - from;
      if (late > 0) late_ticks_.fetch_add(late);
      ticks_.fetch_add(w.tick - from);
    }
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
    MaybeCheckpoint(w);
  }

  // A checkpoint of w at rest, covering its journal so far, once checkpoint_every_runs runs
  // have started since the last one: at a run's end, or after a call (however the last run
  // ended, a reset included). Not while w is replayed: its checkpoint is in the store already,
  // or will be at its next live rest.
  void MaybeCheckpoint(WorldT& w) ABSL_EXCLUSIVE_LOCKS_REQUIRED(w.mu) {
    const uint64_t every = limits_.checkpoint_every_runs;
    if (journal_ == nullptr || every == 0 || w.restoring || Kind::Running(w) ||
        Kind::Runs(w) - w.checkpointed_runs < every) {
      return;
    }
    w.checkpointed_runs = Kind::Runs(w);
    journal_->Checkpoint(w.id, w.journal_index, w.tick, Kind::Checkpoint(w));
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
  int adding_ ABSL_GUARDED_BY(mu_) = 0;  ///< worlds whose creation is being made durable
  bool shut_down_ ABSL_GUARDED_BY(mu_) = false;
  Journal* journal_ = nullptr;
  std::unique_ptr<TickScheduler> own_scheduler_;
  TickScheduler* scheduler_;
  std::atomic<int64_t> ticks_{0}, late_ticks_{0}, slipped_ticks_{0}, events_{0};
  std::atomic<int> running_{0};
};

}  // namespace sportsim::server

#endif  // SPORTSIM_SERVER_WORLD_WORLD_HOST_H_
