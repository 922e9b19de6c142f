#include "server/billiards/table_world.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/strings/str_format.h"
#include "server/billiards/convert.h"
#include "server/world/event_log.h"
#include "server/world/watcher_impl.h"
#include "server/world/world.h"
#include "sim/billiards/cue.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/referee.h"
#include "sim/core/check.h"

namespace sportsim::server {

namespace b = ::sportsim::billiards;

// ---------------------------------------------------------------------------------------------
// Watcher

namespace {

bool SameBall(const b::Ball& x, const b::Ball& y) {
  return x.state == y.state && x.r == y.r && x.v == y.v && x.w == y.w &&
         x.q.coeffs() == y.q.coeffs();
}

}  // namespace

void TableWatch::Fill(const WatchOptions& options, const std::string& table_id,
                      const Frame& frame, const Frame* last_sent, bool full,
                      v1::TableSnapshot* out) {
  out->set_table_id(table_id);
  out->set_tick(frame.tick);
  out->set_t_s(frame.t_s);
  out->set_at_rest(frame.at_rest);
  out->set_turn(frame.turn);
  out->set_shot_id(frame.shot_id);
  out->set_heartbeat(frame.heartbeat);
  if (frame.heartbeat) return;
  const bool all = full || !options.changed_only || last_sent == nullptr ||
                   last_sent->balls.size() != frame.balls.size();
  for (size_t i = 0; i < frame.balls.size(); ++i) {
    const b::Ball& ball = frame.balls[i];
    if (!all && SameBall(ball, last_sent->balls[i])) continue;
    v1::BallState* p = out->add_balls();
    BallToProto(*frame.model, ball, p);
    if (!options.position) { p->clear_x_m(); p->clear_y_m(); }
    if (!options.velocity) { p->clear_vx_mps(); p->clear_vy_mps(); }
    if (!options.spin) { p->clear_wx_rps(); p->clear_wy_rps(); p->clear_wz_rps(); }
    if (!options.orientation) { p->clear_qw(); p->clear_qx(); p->clear_qy(); p->clear_qz(); }
  }
}

template class BasicWatcher<TableWatch>;

// ---------------------------------------------------------------------------------------------
// Table

struct Table : Ticked, std::enable_shared_from_this<Table> {
  explicit Table(TableRegistry* r) : registry(r) {}
  void Wake(uint64_t generation, SteadyClock::time_point now) override {
    registry->Process(shared_from_this(), generation, now);
  }

  TableRegistry* const registry;
  // Fixed at creation.
  std::string id;
  std::string preset;
  std::string rack;
  std::shared_ptr<const b::TableModel> model;
  b::TableState initial;
  b::SolverOptions solver;
  double tick_hz = 120.0;  // == clock.tick_hz
  double period_s = 1.0 / 120.0;
  int64_t steps_per_tick = 0;  // stepped engine: dt_s * steps_per_tick = period
  std::vector<SeatEntry> seats;

  absl::Mutex mu;
  TickClock clock ABSL_GUARDED_BY(mu);
  int64_t tick ABSL_GUARDED_BY(mu) = 0;                 // last tick advanced or acted on
  uint64_t sequence ABSL_GUARDED_BY(mu) = 0;
  uint32_t turn ABSL_GUARDED_BY(mu) = 0;
  b::TableState rest ABSL_GUARDED_BY(mu);                // the balls when no shot moves
  std::unique_ptr<b::TableSimulation> sim ABSL_GUARDED_BY(mu);  // the shot in progress
  std::unique_ptr<b::ShotReferee> referee ABSL_GUARDED_BY(mu);
  b::TableState shot_start ABSL_GUARDED_BY(mu);  // ids for the shot's events
  v1::ShotSummary current ABSL_GUARDED_BY(mu);   // the shot in progress
  v1::ShotSummary last_shot ABSL_GUARDED_BY(mu);
  uint64_t shots ABSL_GUARDED_BY(mu) = 0;
  EventLog<v1::TableEvent> log ABSL_GUARDED_BY(mu);
  std::vector<std::shared_ptr<Watcher>> watchers ABSL_GUARDED_BY(mu);
  bool deleted ABSL_GUARDED_BY(mu) = false;
  bool closed ABSL_GUARDED_BY(mu) = false;  // the server is shutting down

  absl::Status Gone() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    if (closed) return absl::UnavailableError("the server is shutting down");
    if (deleted) return absl::NotFoundError(absl::StrFormat("table_id: table %s was deleted", id));
    return absl::OkStatus();
  }
  uint64_t wake_generation ABSL_GUARDED_BY(mu) = 0;

  SteadyClock::time_point Deadline(int64_t k) const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    return clock.Deadline(k);
  }
  // The tick the clock is at (never behind the last tick advanced).
  int64_t ClockTick(SteadyClock::time_point now) const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    return clock.Tick(now, tick);
  }
  // The tick now: the last one advanced while a shot moves, else the clock's.
  int64_t NowTick() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    return sim != nullptr ? tick : ClockTick(SteadyClock::now());
  }
  double TableTime(int64_t k) const { return static_cast<double>(k) * period_s; }
  // The shot's own time at tick k.
  double ShotTime(int64_t k) const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    const int64_t n = k - current.start_tick();
    if (steps_per_tick > 0) return static_cast<double>(n * steps_per_tick) * solver.dt_s;
    return static_cast<double>(n) * period_s;
  }
  const b::TableState& Balls() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    return sim != nullptr ? sim->state() : rest;
  }
  // `ticked`: made by a tick, whose latency counts from the tick's deadline (a late tick counts
  // as late); frames made by calls count from now.
  std::shared_ptr<const Frame> MakeFrame(int64_t k, bool heartbeat, bool ticked = false)
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    auto f = std::make_shared<Frame>();
    f->sequence = sequence;
    f->tick = k;
    f->t_s = TableTime(k);
    f->at_rest = sim == nullptr;
    f->heartbeat = heartbeat;
    f->turn = turn;
    f->shot_id = current.shot_id();
    f->model = model;
    if (!heartbeat) f->balls = Balls().balls;
    f->published = ticked ? Deadline(k) : SteadyClock::now();
    return f;
  }
  // The shot's physics events, in table time, logged; the referee sees each.
  void LogShotEvents(const std::vector<b::Event>& events, int event_log,
                     std::vector<EventPtr>* fresh) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    const double start_t = TableTime(current.start_tick());
    for (const b::Event& be : events) {
      referee->Observe(be);
      v1::TableEvent pe;
      EventToProto(*model, shot_start, be, &pe);
      pe.set_t_s(start_t + be.t_s);
      pe.set_shot_id(current.shot_id());
      fresh->push_back(Log(std::move(pe), event_log));
    }
  }
  // Offers a frame (or none: the events wait) and the events to every watcher; returns those
  // to pump once the lock is released.
  void OfferAll(const std::shared_ptr<const Frame>& frame, const std::vector<EventPtr>& fresh,
                std::vector<std::shared_ptr<Watcher>>* pump) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    for (const std::shared_ptr<Watcher>& w : watchers) {
      if (w->Offer(frame, fresh)) pump->push_back(w);
    }
  }
  // The seat of `token`, which must be the seat to play when `to_play`. Also refuses a table
  // deleted or shutting down.
  absl::StatusOr<int> Authorize(const std::string& token, bool to_play) const
      ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    if (absl::Status gone = Gone(); !gone.ok()) return gone;
    const int seat = SeatOf(seats, token);
    if (seat < 0) return absl::PermissionDeniedError("token: not a seat of this table");
    if (to_play && seat != static_cast<int>(turn)) {
      return absl::PermissionDeniedError(
          absl::StrFormat("token: it is seat %d's turn, not seat %d's", turn, seat));
    }
    return seat;
  }
  EventPtr Log(v1::TableEvent e, int event_log) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu) {
    return log.Append(std::move(e), sequence, event_log);
  }
};

namespace {

absl::Status Unavailable() { return absl::UnavailableError("the server is shutting down"); }

absl::Status CheckTableId(const std::string& id) {
  if (id.empty() || id.size() > 64) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "table_id must be 1 to 64 characters, got %d characters", static_cast<int>(id.size())));
  }
  return absl::OkStatus();
}

v1::TableEvent TableEvent(v1::EventKind kind, double t_s, uint64_t shot_id) {
  v1::TableEvent e;
  e.set_kind(kind);
  e.set_t_s(t_s);
  e.set_shot_id(shot_id);
  return e;
}

// The largest step <= 1/960 s that divides the tick period (the stepped engine's default).
constexpr double kDefaultSteppedDt = 1.0 / 960.0;

}  // namespace

// ---------------------------------------------------------------------------------------------
// Registry

TableRegistry::TableRegistry(TableLimits limits, TickScheduler* scheduler)
    : limits_(limits), counters_(std::make_shared<WatchCounters>()) {
  if (scheduler == nullptr) {
    own_scheduler_ = std::make_unique<TickScheduler>(limits_.workers);
    scheduler = own_scheduler_.get();
  }
  scheduler_ = scheduler;
}

TableRegistry::~TableRegistry() { Shutdown(absl::UnavailableError("the server is shutting down")); }

absl::StatusOr<std::shared_ptr<Table>> TableRegistry::Find(const std::string& id) {
  if (absl::Status s = CheckTableId(id); !s.ok()) return s;
  absl::MutexLock lock(&mu_);
  if (shut_down_) return Unavailable();
  auto it = tables_.find(id);
  if (it == tables_.end()) {
    return absl::NotFoundError(absl::StrFormat("table_id: no table \"%s\"", id));
  }
  return it->second;
}

void TableRegistry::Schedule(Table& t, const std::shared_ptr<Table>& ptr,
                             SteadyClock::time_point when) {
  scheduler_->Schedule(ptr, ++t.wake_generation, when);
}

absl::StatusOr<v1::CreateTableResponse> TableRegistry::Create(
    const v1::CreateTableRequest& request) {
  const double tick_hz = request.tick_hz() == 0 ? 120.0 : request.tick_hz();
  if (absl::Status s = CheckFiniteInRange("tick_hz", tick_hz, 1, false, 1000, false); !s.ok()) {
    return s;
  }
  absl::StatusOr<std::vector<SeatEntry>> seats =
      MakeSeats(request.seats(), request.seat_names(), /*default_count=*/2);
  if (!seats.ok()) return seats.status();
  absl::StatusOr<TableBuild> build = TableFromProto(request.table());
  if (!build.ok()) return build.status();
  absl::StatusOr<b::SolverOptions> solver = SolverFromProto(request.solver());
  if (!solver.ok()) return solver.status();

  auto table = std::make_shared<Table>(this);
  table->tick_hz = tick_hz;
  table->clock.tick_hz = tick_hz;
  table->period_s = 1.0 / tick_hz;
  if (solver->engine == b::Engine::kStepped) {
    // Ticks must end on the step grid, so that a shot's states do not depend on the ticks.
    if (!request.solver().has_dt_s()) {
      solver->dt_s = table->period_s / std::ceil(table->period_s / kDefaultSteppedDt - 1e-9);
    }
    const double n = table->period_s / solver->dt_s;
    const double rounded = std::round(n);
    if (rounded < 1 || std::abs(n - rounded) > 1e-9 * n) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "solver.dt_s: the stepped engine's step must divide the tick period 1/%g s, got %g s "
          "(%.6g steps per tick)",
          tick_hz, solver->dt_s, n));
    }
    table->steps_per_tick = static_cast<int64_t>(rounded);
  }
  {
    // Options are checked by the engine: try them once on the table at rest.
    std::vector<b::Event> ignored;
    absl::StatusOr<std::unique_ptr<b::TableSimulation>> probe =
        b::TableSimulation::Create(build->model, *solver, build->state, &ignored);
    if (!probe.ok()) return PrefixStatus("solver: ", probe.status());
  }
  table->preset = request.table().preset().empty() ? "pool-9ft" : request.table().preset();
  table->rack = build->rack;
  table->model = std::make_shared<const b::TableModel>(std::move(build->model));
  table->initial = build->state;
  table->solver = *solver;
  v1::CreateTableResponse response;
  table->seats = *std::move(seats);
  SeatsToProto(table->seats, /*with_tokens=*/true, response.mutable_seats());
  {
    absl::MutexLock lock(&table->mu);
    table->clock.origin = SteadyClock::now();
    table->rest = table->initial;
  }
  absl::MutexLock lock(&mu_);
  if (shut_down_) return Unavailable();
  if (static_cast<int>(tables_.size()) >= limits_.max_tables) {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "the server holds its maximum of %d tables (--max_tables)", limits_.max_tables));
  }
  do {
    table->id = "t-" + RandomHex(6);
  } while (tables_.count(table->id) > 0);
  tables_[table->id] = table;
  response.set_table_id(table->id);
  response.set_tick_hz(tick_hz);
  response.set_engine(std::string(b::EngineName(solver->engine)));
  if (solver->engine == b::Engine::kStepped) response.set_dt_s(solver->dt_s);
  response.set_tick(0);
  return response;
}

absl::StatusOr<v1::TableInfo> TableRegistry::Get(const v1::GetTableRequest& request) {
  absl::StatusOr<std::shared_ptr<Table>> found = Find(request.table_id());
  if (!found.ok()) return found.status();
  Table& t = **found;
  absl::MutexLock lock(&t.mu);
  v1::TableInfo info;
  info.set_table_id(t.id);
  info.set_preset(t.preset);
  info.set_rack(t.rack);
  info.set_tick_hz(t.tick_hz);
  const int64_t tick = t.NowTick();
  info.set_tick(tick);
  info.set_t_s(t.TableTime(tick));
  info.set_sequence(t.sequence);
  info.set_at_rest(t.sim == nullptr);
  info.set_turn(t.turn);
  SeatsToProto(t.seats, /*with_tokens=*/false, info.mutable_seats());
  for (const b::Ball& ball : t.Balls().balls) BallToProto(*t.model, ball, info.add_balls());
  info.set_shots(t.shots);
  if (t.shots > 0) *info.mutable_last_shot() = t.last_shot;
  info.set_watchers(static_cast<uint32_t>(t.watchers.size()));
  info.set_engine(std::string(b::EngineName(t.solver.engine)));
  if (t.solver.engine == b::Engine::kStepped) info.set_dt_s(t.solver.dt_s);
  if (request.include_geometry()) GeometryToProto(*t.model, info.mutable_geometry());
  return info;
}

absl::StatusOr<v1::ListTablesResponse> TableRegistry::List(const v1::ListTablesRequest& request) {
  if (request.page_size() > 1000) {
    return absl::InvalidArgumentError(
        absl::StrFormat("page_size must be in [0, 1000], got %d", request.page_size()));
  }
  const size_t page = request.page_size() == 0 ? 100 : request.page_size();
  std::vector<std::shared_ptr<Table>> tables;
  v1::ListTablesResponse response;
  {
    absl::MutexLock lock(&mu_);
    if (shut_down_) return Unavailable();
    response.set_total(static_cast<uint32_t>(tables_.size()));
    for (auto it = tables_.upper_bound(request.page_token());
         it != tables_.end() && tables.size() <= page; ++it) {
      tables.push_back(it->second);
    }
  }
  if (tables.size() > page) {
    tables.pop_back();
    response.set_next_page_token(tables.back()->id);
  }
  const SteadyClock::time_point now = SteadyClock::now();
  for (const std::shared_ptr<Table>& p : tables) {
    Table& t = *p;
    absl::MutexLock lock(&t.mu);
    v1::TableBrief* brief = response.add_tables();
    brief->set_table_id(t.id);
    brief->set_preset(t.preset);
    brief->set_at_rest(t.sim == nullptr);
    brief->set_tick(t.sim != nullptr ? t.tick : t.ClockTick(now));
    uint32_t on = 0;
    for (const b::Ball& ball : t.Balls().balls) on += ball.state != b::MotionState::kPocketed;
    brief->set_balls_on_table(on);
    brief->set_seats(static_cast<uint32_t>(t.seats.size()));
    brief->set_watchers(static_cast<uint32_t>(t.watchers.size()));
    brief->set_shots(t.shots);
  }
  return response;
}

absl::Status TableRegistry::Delete(const v1::DeleteTableRequest& request) {
  if (absl::Status s = CheckTableId(request.table_id()); !s.ok()) return s;
  if (absl::Status s = CheckToken(request.token(), "CreateTable"); !s.ok()) return s;
  std::shared_ptr<Table> table;
  {
    absl::MutexLock lock(&mu_);
    if (shut_down_) return Unavailable();
    auto it = tables_.find(request.table_id());
    if (it == tables_.end()) {
      return absl::NotFoundError(absl::StrFormat("table_id: no table \"%s\"", request.table_id()));
    }
    table = it->second;
    // The token is checked before anything changes.
    if (SeatOf(table->seats, request.token()) < 0) {
      return absl::PermissionDeniedError("token: not a seat of this table");
    }
    tables_.erase(it);
  }
  std::vector<std::shared_ptr<Watcher>> pump;
  {
    absl::MutexLock lock(&table->mu);
    table->deleted = true;
    if (table->sim != nullptr) moving_.fetch_sub(1);
    const std::shared_ptr<const Frame> last =
        table->MakeFrame(table->NowTick(),
                         false);
    const absl::Status gone =
        absl::NotFoundError(absl::StrFormat("table %s was deleted", table->id));
    for (const std::shared_ptr<Watcher>& w : table->watchers) {
      if (w->Close(gone, last)) pump.push_back(w);
    }
    table->sim = nullptr;
  }
  for (const std::shared_ptr<Watcher>& w : pump) w->Pump();
  return absl::OkStatus();
}

namespace {

// Ends the shot in progress: a summary, the shot_end event, the balls at rest.
void EndShot(Table& t, int64_t end_tick, const std::string& error, bool voided, int event_log,
             std::vector<EventPtr>* fresh) ABSL_EXCLUSIVE_LOCKS_REQUIRED(t.mu) {
  if (t.sim == nullptr) return;
  // A failed engine (non-finite state, event cap) voids the shot: the balls go back.
  b::TableState state = voided ? t.shot_start : t.sim->state();
  if (!error.empty() && !voided) {
    // Frozen where the engine stopped: every ball still moving is put at rest.
    for (b::Ball& ball : state.balls) {
      if (ball.state == b::MotionState::kPocketed) continue;
      ball.v.setZero();
      ball.w.setZero();
      ball.state = b::MotionState::kStationary;
    }
  }
  state.t_s = 0.0;
  v1::ShotSummary& s = t.current;
  if (t.referee != nullptr) {
    const b::ShotFacts& f = t.referee->facts();
    if (f.first_hit >= 0) s.set_first_ball_hit(state.balls[f.first_hit].id);
    s.set_rails(static_cast<uint32_t>(f.rails));
    s.set_rails_after_contact(static_cast<uint32_t>(f.rails_after_contact));
    for (int i : f.pocketed) s.add_pocketed(state.balls[i].id);
    s.set_struck_ball_pocketed(f.struck_pocketed);
  }
  s.set_end_tick(end_tick);
  s.set_duration_s(t.ShotTime(end_tick));
  s.set_events(t.sim->events_processed());
  s.set_error(error);
  t.last_shot = s;
  t.rest = std::move(state);
  t.sim = nullptr;
  t.referee = nullptr;
  v1::TableEvent e = TableEvent(v1::shot_end, t.TableTime(end_tick), s.shot_id());
  e.set_seat(s.seat());
  e.add_balls(s.struck_ball());
  *e.mutable_summary() = s;
  fresh->push_back(t.Log(std::move(e), event_log));
}

}  // namespace

// The shape of every seat's call: check the token, find the table, then under its lock check
// the seat (and the turn) and run `fn`, which offers to the watchers it names in `pump`; pump
// them once the lock is released.
template <typename Response, typename Fn>
absl::StatusOr<Response> TableRegistry::Act(const std::string& table_id, const std::string& token,
                                            bool to_play, Fn fn) {
  if (absl::Status s = CheckToken(token, "CreateTable"); !s.ok()) return s;
  absl::StatusOr<std::shared_ptr<Table>> found = Find(table_id);
  if (!found.ok()) return found.status();
  std::vector<std::shared_ptr<Watcher>> pump;
  absl::StatusOr<Response> response;
  {
    absl::MutexLock lock(&(*found)->mu);
    absl::StatusOr<int> seat = (*found)->Authorize(token, to_play);
    if (!seat.ok()) return seat.status();
    response = fn(*found, *seat, pump);
  }
  for (const std::shared_ptr<Watcher>& w : pump) w->Pump();
  return response;
}

absl::StatusOr<v1::ResetTableResponse> TableRegistry::Reset(const v1::ResetTableRequest& request) {
  return Act<v1::ResetTableResponse>(
      request.table_id(), request.token(), /*to_play=*/false,
      [&](const std::shared_ptr<Table>& ptr, int seat,
          std::vector<std::shared_ptr<Watcher>>& pump) -> absl::StatusOr<v1::ResetTableResponse> {
    Table& t = *ptr;
    v1::ResetTableResponse response;
    const int64_t tick = t.NowTick();
    ++t.sequence;
    std::vector<EventPtr> fresh;
    if (t.sim != nullptr) {
      EndShot(t, tick, "the table was reset during the shot", false, limits_.event_log, &fresh);
      moving_.fetch_sub(1);
      // The tick wake is void; the watchers (if any) get heartbeats again.
      if (!t.watchers.empty()) {
        Schedule(t, ptr, SteadyClock::now() + absl::ToChronoNanoseconds(limits_.heartbeat));
      } else {
        ++t.wake_generation;
      }
    }
    t.rest = t.initial;
    t.tick = tick;
    v1::TableEvent e = TableEvent(v1::table_reset, t.TableTime(tick), 0);
    e.set_seat(static_cast<uint32_t>(seat));
    fresh.push_back(t.Log(std::move(e), limits_.event_log));
    events_.fetch_add(static_cast<int64_t>(fresh.size()));
    const std::shared_ptr<const Frame> frame = t.MakeFrame(tick, false);
    t.OfferAll(frame, fresh, &pump);
    response.set_sequence(t.sequence);
    response.set_tick(tick);
    return response;
  });
}

absl::StatusOr<v1::PlaceBallResponse> TableRegistry::Place(const v1::PlaceBallRequest& request) {
  const v1::BallPlacement& p = request.ball();
  if (absl::Status s = CheckId("ball.id", p.id()); !s.ok()) return s;
  if (!std::isfinite(p.x_m()) || !std::isfinite(p.y_m())) {
    return absl::InvalidArgumentError(
        absl::StrFormat("ball: x_m and y_m must be finite, got (%g, %g)", p.x_m(), p.y_m()));
  }
  return Act<v1::PlaceBallResponse>(
      request.table_id(), request.token(), /*to_play=*/true,
      [&](const std::shared_ptr<Table>& ptr, int seat,
          std::vector<std::shared_ptr<Watcher>>& pump) -> absl::StatusOr<v1::PlaceBallResponse> {
    Table& t = *ptr;
    v1::PlaceBallResponse response;
    if (t.sim != nullptr) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "balls are still moving (shot %d); place balls when every ball is at rest",
          t.current.shot_id()));
    }
    b::TableState state = t.rest;
    int k = state.Find(p.id());
    if (k < 0) {
      if (static_cast<int>(state.balls.size()) >= kMaxBalls) {
        return absl::InvalidArgumentError(
            absl::StrFormat("ball.id: a table holds at most %d balls", kMaxBalls));
      }
      state.balls.push_back(b::Ball{.id = p.id()});
      k = static_cast<int>(state.balls.size()) - 1;
    }
    b::Ball& ball = state.balls[k];
    ball.r = Eigen::Vector3d(p.x_m(), p.y_m(), t.model->radius());
    ball.v.setZero();
    ball.w.setZero();
    ball.state = b::MotionState::kStationary;
    ball.pocket = -1;
    if (absl::Status s = b::ValidateLayout(*t.model, state); !s.ok()) {
      return PrefixStatus("ball: ", s);
    }
    for (const b::Pocket& pocket : t.model->spec().pockets) {
      if ((ball.r.head<2>() - pocket.centre).norm() < pocket.radius_m) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "ball: (%g, %g) m is inside pocket %s's capture circle", p.x_m(), p.y_m(),
            pocket.name));
      }
    }
    const int64_t tick = t.ClockTick(SteadyClock::now());
    t.tick = tick;
    t.rest = std::move(state);
    ++t.sequence;
    v1::TableEvent e = TableEvent(v1::ball_placed, t.TableTime(tick), 0);
    e.set_seat(static_cast<uint32_t>(seat));
    e.add_balls(p.id());
    std::vector<EventPtr> fresh{t.Log(std::move(e), limits_.event_log)};
    events_.fetch_add(1);
    const std::shared_ptr<const Frame> frame = t.MakeFrame(tick, false);
    t.OfferAll(frame, fresh, &pump);
    response.set_sequence(t.sequence);
    response.set_tick(tick);
    return response;
  });
}

absl::StatusOr<v1::ShootResponse> TableRegistry::Shoot(const v1::ShootRequest& request) {
  if (!request.has_strike()) return absl::InvalidArgumentError("strike: required");
  absl::StatusOr<b::CueStrike> strike = StrikeFromProto(request.strike());
  if (!strike.ok()) return strike.status();
  return Act<v1::ShootResponse>(
      request.table_id(), request.token(), /*to_play=*/true,
      [&](const std::shared_ptr<Table>& ptr, int seat,
          std::vector<std::shared_ptr<Watcher>>& pump) -> absl::StatusOr<v1::ShootResponse> {
    Table& t = *ptr;
    v1::ShootResponse response;
    if (request.has_next_seat() && request.next_seat() >= t.seats.size()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "next_seat must be in [0, %d], got %d", t.seats.size() - 1, request.next_seat()));
    }
    if (t.sim != nullptr) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "balls are still moving (shot %d): shoot when every ball is at rest",
          t.current.shot_id()));
    }
    const std::string id = request.strike().ball().empty() ? "cue" : request.strike().ball();
    const int cue = t.rest.Find(id);
    if (cue < 0) {
      return absl::InvalidArgumentError(
          absl::StrFormat("strike.ball: no ball \"%s\" on the table", id));
    }
    if (t.rest.balls[cue].state == b::MotionState::kPocketed) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "strike.ball: ball \"%s\" is pocketed; put it back with PlaceBall first", id));
    }
    b::TableState state = t.rest;
    state.t_s = 0.0;
    absl::StatusOr<b::StrikeOutcome> outcome =
        b::ApplyStrike(*t.model, t.solver.disabled, *strike, cue, &state);
    if (!outcome.ok()) return PrefixStatus("strike.", outcome.status());
    std::vector<b::Event> events;
    absl::StatusOr<std::unique_ptr<b::TableSimulation>> sim =
        b::TableSimulation::Create(*t.model, t.solver, std::move(state), &events);
    if (!sim.ok()) return sim.status();

    // Accepted: from here on nothing fails.
    const SteadyClock::time_point now = SteadyClock::now();
    const int64_t start = t.ClockTick(now) + 1;
    t.tick = start;
    ++t.sequence;
    ++t.shots;
    const uint64_t shot_id = t.shots;
    t.current.Clear();
    t.current.set_shot_id(shot_id);
    t.current.set_seat(static_cast<uint32_t>(seat));
    t.current.set_struck_ball(id);
    t.current.set_start_tick(start);
    t.sim = *std::move(sim);
    t.referee = std::make_unique<b::ShotReferee>(cue);
    t.shot_start = t.rest;
    moving_.fetch_add(1);
    std::vector<EventPtr> fresh;
    v1::TableEvent e = TableEvent(v1::shot, t.TableTime(start), shot_id);
    e.set_seat(static_cast<uint32_t>(seat));
    e.add_balls(id);
    fresh.push_back(t.Log(std::move(e), limits_.event_log));
    t.LogShotEvents(events, limits_.event_log, &fresh);
    if (request.has_next_seat() && request.next_seat() != t.turn) {
      t.turn = request.next_seat();
      v1::TableEvent te = TableEvent(v1::turn, t.TableTime(start), shot_id);
      te.set_seat(t.turn);
      fresh.push_back(t.Log(std::move(te), limits_.event_log));
    }
    events_.fetch_add(static_cast<int64_t>(fresh.size()));
    const std::shared_ptr<const Frame> frame = t.MakeFrame(start, false);
    t.OfferAll(frame, fresh, &pump);
    response.set_shot_id(shot_id);
    response.set_start_tick(start);
    StrikeReportToProto(*outcome, response.mutable_strike());
    Schedule(t, ptr, t.Deadline(start + 1));
    return response;
  });
}

absl::StatusOr<v1::SetTurnResponse> TableRegistry::SetTurn(const v1::SetTurnRequest& request) {
  // Only the seat to play passes the turn.
  return Act<v1::SetTurnResponse>(
      request.table_id(), request.token(), /*to_play=*/true,
      [&](const std::shared_ptr<Table>& ptr, int /*seat*/,
          std::vector<std::shared_ptr<Watcher>>& pump) -> absl::StatusOr<v1::SetTurnResponse> {
    Table& t = *ptr;
    v1::SetTurnResponse response;
    if (request.seat() >= t.seats.size()) {
      return absl::InvalidArgumentError(absl::StrFormat("seat must be in [0, %d], got %d",
                                                        t.seats.size() - 1, request.seat()));
    }
    if (request.seat() != t.turn) {
      const int64_t tick = t.NowTick();
      ++t.sequence;
      t.turn = request.seat();
      v1::TableEvent e = TableEvent(v1::turn, t.TableTime(tick), t.current.shot_id());
      e.set_seat(t.turn);
      std::vector<EventPtr> fresh{t.Log(std::move(e), limits_.event_log)};
      events_.fetch_add(1);
      // At rest the turn goes out now; while balls move it rides with the next snapshot.
      const std::shared_ptr<const Frame> frame =
          t.sim == nullptr ? t.MakeFrame(tick, false) : nullptr;
      t.OfferAll(frame, fresh, &pump);
    }
    response.set_sequence(t.sequence);
    return response;
  });
}

absl::StatusOr<std::shared_ptr<Watcher>> TableRegistry::Watch(
    const v1::WatchTableRequest& request, SnapshotSink* sink) {
  absl::StatusOr<std::shared_ptr<Table>> found = Find(request.table_id());
  if (!found.ok()) return found.status();
  const std::shared_ptr<Table>& ptr = *found;
  Table& t = *ptr;
  WatchOptions options;
  options.changed_only = request.changed_only();
  double interval_ticks = 1.0;
  if (request.rate_hz() != 0) {
    if (absl::Status s = CheckFiniteInRange("rate_hz", request.rate_hz(), 0, true, 1000, false);
        !s.ok()) {
      return s;
    }
    // Above the table's tick rate is every tick.
    interval_ticks = std::max(1.0, t.tick_hz / request.rate_hz());
  }
  if (request.fields_size() > 0) {
    options.position = options.velocity = options.spin = options.orientation = false;
    for (int i = 0; i < request.fields_size(); ++i) {
      switch (request.fields(i)) {
        case v1::SNAPSHOT_FIELD_POSITION: options.position = true; break;
        case v1::SNAPSHOT_FIELD_VELOCITY: options.velocity = true; break;
        case v1::SNAPSHOT_FIELD_SPIN: options.spin = true; break;
        case v1::SNAPSHOT_FIELD_ORIENTATION: options.orientation = true; break;
        default:
          return absl::InvalidArgumentError(
              absl::StrFormat("fields[%d]: unknown field %d", i, request.fields(i)));
      }
    }
  }
  auto watcher = std::make_shared<Watcher>(t.id, options, interval_ticks,
                                           limits_.watcher_backlog, counters_);
  watcher->Attach(sink);
  {
    absl::MutexLock lock(&t.mu);
    if (absl::Status gone = t.Gone(); !gone.ok()) return gone;
    if (static_cast<int>(t.watchers.size()) >= limits_.max_watchers_per_table) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "table %s has its maximum of %d watchers (--max_watchers_per_table)", t.id,
          limits_.max_watchers_per_table));
    }
    std::vector<EventPtr> replay;
    if (request.has_from_sequence()) {
      bool lost = false;
      absl::StatusOr<std::vector<EventPtr>> after =
          t.log.After(request.from_sequence(), t.sequence, "table", &lost);
      if (!after.ok()) return after.status();
      if (lost) watcher->MarkResync();
      replay = *std::move(after);
    }
    const int64_t tick = t.NowTick();
    watcher->Due(tick);  // the first snapshot is now
    watcher->Offer(t.MakeFrame(tick, false), replay);
    t.watchers.push_back(watcher);
    if (t.sim == nullptr && t.watchers.size() == 1) {
      Schedule(t, ptr, SteadyClock::now() + absl::ToChronoNanoseconds(limits_.heartbeat));
    }
  }
  return watcher;
}

void TableRegistry::Unwatch(const std::string& table_id, const Watcher* watcher) {
  std::shared_ptr<Table> table;
  {
    absl::MutexLock lock(&mu_);
    auto it = tables_.find(table_id);
    if (it == tables_.end()) return;
    table = it->second;
  }
  absl::MutexLock lock(&table->mu);
  auto& ws = table->watchers;
  ws.erase(std::remove_if(ws.begin(), ws.end(),
                          [watcher](const std::shared_ptr<Watcher>& w) { return w.get() == watcher; }),
           ws.end());
}

void TableRegistry::Process(const std::shared_ptr<Table>& ptr, uint64_t generation,
                            SteadyClock::time_point now) {
  Table& t = *ptr;
  std::vector<std::shared_ptr<Watcher>> pump;
  {
    absl::MutexLock lock(&t.mu);
    if (t.deleted || t.closed || generation != t.wake_generation) return;  // superseded
    if (t.sim == nullptr) {
      // At rest: a heartbeat for the watchers, then sleep until the next one.
      if (t.watchers.empty()) return;
      const std::shared_ptr<const Frame> beat = t.MakeFrame(t.ClockTick(now), true);
      for (const std::shared_ptr<Watcher>& w : t.watchers) {
        if (w->OfferHeartbeat(beat)) pump.push_back(w);
      }
      Schedule(t, ptr, now + absl::ToChronoNanoseconds(limits_.heartbeat));
    } else {
      const int64_t due = t.clock.DueTick(now);
      if (due <= t.tick) {
        Schedule(t, ptr, t.Deadline(t.tick + 1));
      } else {
        int64_t slipped = 0;
        int64_t target = t.clock.CatchUp(t.tick, due, limits_.max_catchup_ticks, &slipped);
        if (slipped > 0) slipped_ticks_.fetch_add(slipped);
        // Tick by tick, so that the tick a shot ends on (or is stopped on) does not depend on
        // how many ticks one visit covers. For the event engine a tick without events is a
        // few evaluations; the stepped engine does the same steps either way.
        std::vector<b::Event> events;
        std::string error;
        bool voided = false;
        bool ended = false;
        int64_t k = t.tick;
        while (k < target && !ended) {
          ++k;
          const absl::Status st = t.sim->AdvanceTo(t.ShotTime(k), &events);
          if (!st.ok()) {
            error = absl::StrFormat("%s; the balls were put back where the shot started",
                                    st.message());
            voided = ended = true;
          } else if (t.sim->AtRest()) {
            ended = true;
          } else if (t.ShotTime(k) >= limits_.max_shot_s) {
            error = absl::StrFormat("the shot was stopped after %g s of simulated time",
                                    limits_.max_shot_s);
            ended = true;
          }
        }
        // Late: advanced more than a period after its deadline.
        const int64_t late = std::min(k, due - 1) - t.tick;
        if (late > 0) late_ticks_.fetch_add(late);
        ticks_.fetch_add(k - t.tick);
        t.tick = k;
        target = k;
        ++t.sequence;
        std::vector<EventPtr> fresh;
        t.LogShotEvents(events, limits_.event_log, &fresh);
        if (ended) {
          EndShot(t, target, error, voided, limits_.event_log, &fresh);
          moving_.fetch_sub(1);
        }
        events_.fetch_add(static_cast<int64_t>(fresh.size()));
        std::shared_ptr<const Frame> frame;
        for (const std::shared_ptr<Watcher>& w : t.watchers) {
          const bool due_now = w->Due(target) || ended;
          if (due_now && frame == nullptr) frame = t.MakeFrame(target, false, true);
          if (w->Offer(due_now ? frame : nullptr, fresh)) pump.push_back(w);
        }
        if (!ended) {
          Schedule(t, ptr, t.Deadline(t.tick + 1));
        } else if (!t.watchers.empty()) {
          Schedule(t, ptr, now + absl::ToChronoNanoseconds(limits_.heartbeat));
        }
      }
    }
  }
  for (const std::shared_ptr<Watcher>& w : pump) w->Pump();
}

void TableRegistry::Shutdown(const absl::Status& status) {
  // No new call gets a table from here on; calls that already hold one see it closed below.
  std::vector<std::shared_ptr<Table>> tables;
  {
    absl::MutexLock lock(&mu_);
    if (shut_down_) return;
    shut_down_ = true;
    for (auto& [id, t] : tables_) tables.push_back(t);
  }
  std::vector<std::shared_ptr<Watcher>> pump;
  for (const std::shared_ptr<Table>& p : tables) {
    absl::MutexLock lock(&p->mu);
    p->closed = true;
    const std::shared_ptr<const Frame> last =
        p->MakeFrame(p->NowTick(), false);
    for (const std::shared_ptr<Watcher>& w : p->watchers) {
      if (w->Close(status, last)) pump.push_back(w);
    }
  }
  for (const std::shared_ptr<Watcher>& w : pump) w->Pump();
  // A wake in progress has finished (it saw the table closed, or ran before); pending ones go.
  if (own_scheduler_ != nullptr) own_scheduler_->Stop();
}

TableStats TableRegistry::stats() const {
  TableStats s;
  s.ticks = ticks_.load();
  s.late_ticks = late_ticks_.load();
  s.slipped_ticks = slipped_ticks_.load();
  s.events = events_.load();
  s.tick_cpu_ns = scheduler_->cpu_ns();
  s.moving = moving_.load();
  std::vector<std::shared_ptr<Table>> tables;
  {
    absl::MutexLock lock(&mu_);
    s.tables = static_cast<int>(tables_.size());
    for (const auto& [id, t] : tables_) tables.push_back(t);
  }
  for (const std::shared_ptr<Table>& t : tables) {
    absl::MutexLock lock(&t->mu);
    s.watchers += static_cast<int>(t->watchers.size());
  }
  s.snapshots_sent = counters_->sent.load();
  s.snapshots_replaced = counters_->replaced.load();
  s.resyncs = counters_->resyncs.load();
  return s;
}

}  // namespace sportsim::server
