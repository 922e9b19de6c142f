#include "server/billiards/table_world.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "absl/strings/str_format.h"
#include "server/billiards/convert.h"
#include "server/billiards/game_convert.h"
#include "server/billiards/table_checkpoint.h"
#include "server/world/event_log.h"
#include "server/world/watcher_impl.h"
#include "sportsim/store/v1/journal.pb.h"
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
  if (frame.game != nullptr) *out->mutable_game() = *frame.game;
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
// The table kind

namespace {

// The shot's own time at tick k.
double ShotTime(const Table& t, int64_t k) ABSL_EXCLUSIVE_LOCKS_REQUIRED(t.mu) {
  const int64_t n = k - t.current.start_tick;
  if (t.steps_per_tick > 0) return static_cast<double>(n * t.steps_per_tick) * t.solver.dt_s;
  return static_cast<double>(n) * t.period_s;
}

const b::TableState& Balls(const Table& t) ABSL_EXCLUSIVE_LOCKS_REQUIRED(t.mu) {
  return t.sim != nullptr ? t.sim->state() : t.rest;
}

v1::TableEvent TableEvent(v1::EventKind kind, double t_s, uint64_t shot_id) {
  v1::TableEvent e;
  e.set_kind(kind);
  e.set_t_s(t_s);
  e.set_shot_id(shot_id);
  return e;
}

// A table that plays a ruled game (a referee decides what every shot means).
bool Ruled(const Table& t) { return t.game_referee != nullptr; }

// The ball a seat strikes: its own cue ball (three-cushion: seat 0 "cue", seat 1 "yellow").
std::string StrikerBall(const Table& t, int seat) {
  return t.rules.game == games::GameKind::kThreeCushion && seat == 1 ? "yellow" : "cue";
}

// The API's view of the game state, made once per change and shared by every frame.
void RefreshGameView(Table& t) ABSL_EXCLUSIVE_LOCKS_REQUIRED(t.mu) {
  if (!Ruled(t)) return;
  auto view = std::make_shared<v1::GameState>();
  std::optional<double> deadline_s;
  if (t.clock_deadline.has_value()) deadline_s = t.WorldTime(*t.clock_deadline);
  GameStateToProto(t.game, deadline_s, view.get());
  t.game_view = std::move(view);
}

// The shot clock of the seat to play starts at tick `from` (when it is on, the match goes on
// and nobody has a decision to make).
void ArmShotClock(Table& t, int64_t from) ABSL_EXCLUSIVE_LOCKS_REQUIRED(t.mu) {
  t.clock_deadline.reset();
  if (!Ruled(t) || t.rules.shot_clock_s <= 0 || t.game.match_over() ||
      t.game.decision.pending()) {
    return;
  }
  const int64_t ticks = std::max<int64_t>(
      1, static_cast<int64_t>(std::ceil(t.rules.shot_clock_s * t.tick_hz - 1e-9)));
  t.clock_deadline = from + ticks;
}

// A referee's judgement takes effect at `tick`: the game state, its events (logged in order),
// the turn, the shot clock and the view.
void ApplyJudgement(Table& t, games::Judgement j, int64_t tick, uint64_t shot_id,
                    std::vector<EventPtr>* fresh) ABSL_EXCLUSIVE_LOCKS_REQUIRED(t.mu) {
  t.game = std::move(j.state);
  for (const games::GameEvent& ge : j.events) {
    fresh->push_back(t.Log(GameEventToProto(ge, t.WorldTime(tick), shot_id)));
  }
  const uint32_t to_play = static_cast<uint32_t>(t.game.to_play);
  if (to_play != t.turn) {
    t.turn = to_play;
    v1::TableEvent e = TableEvent(v1::turn, t.WorldTime(tick), shot_id);
    e.set_seat(t.turn);
    fresh->push_back(t.Log(std::move(e)));
  }
  ArmShotClock(t, tick);
  RefreshGameView(t);
}

// The shot's physics events, in table time, logged; the referee sees each.
void LogShotEvents(Table& t, const std::vector<b::Event>& events,
                   std::vector<EventPtr>* fresh) ABSL_EXCLUSIVE_LOCKS_REQUIRED(t.mu) {
  const double start_t = t.WorldTime(t.current.start_tick);
  for (const b::Event& be : events) {
    t.referee->Observe(be);
    if (Ruled(t)) t.shot_events.push_back(be);
    v1::TableEvent pe;
    EventToProto(*t.model, t.shot_start, be, &pe);
    pe.set_t_s(start_t + be.t_s);
    pe.set_shot_id(t.current.shot_id);
    fresh->push_back(t.Log(std::move(pe)));
  }
}

// Ends the shot in progress: a summary, the shot_end event, the balls at rest.
void EndShot(TableHost& host, Table& t, int64_t end_tick, const TableKind::End& end,
             std::vector<EventPtr>* fresh) ABSL_EXCLUSIVE_LOCKS_REQUIRED(t.mu) {
  if (t.sim == nullptr) return;
  // A failed engine (non-finite state, event cap) voids the shot: the balls go back.
  b::TableState state = end.voided ? t.shot_start : t.sim->state();
  if (!end.error.empty() && !end.voided) {
    // Frozen where the engine stopped: every ball still moving is put at rest.
    for (b::Ball& ball : state.balls) {
      if (ball.state == b::MotionState::kPocketed) continue;
      ball.v.setZero();
      ball.w.setZero();
      ball.state = b::MotionState::kStationary;
    }
  }
  state.t_s = 0.0;
  ShotSummary& s = t.current;
  if (t.referee != nullptr) {
    const b::ShotFacts& f = t.referee->facts();
    if (f.first_hit >= 0) s.first_ball_hit = state.balls[f.first_hit].id;
    s.rails = static_cast<uint32_t>(f.rails);
    s.rails_after_contact = static_cast<uint32_t>(f.rails_after_contact);
    for (int i : f.pocketed) s.pocketed.push_back(state.balls[i].id);
    s.struck_ball_pocketed = f.struck_pocketed;
  }
  s.end_tick = end_tick;
  s.duration_s = ShotTime(t, end_tick);
  s.events = t.sim->events_processed();
  s.error = end.error;
  std::optional<games::Judgement> judged;
  if (Ruled(t) && !end.voided) {
    // The referee reads the engine's own events and the balls at rest; it may respot balls
    // or rack the next frame.
    games::ShotRecord record{.struck = t.shot_start.Find(s.struck_ball),
                             .placed = t.placed,
                             .before = t.shot_start,
                             .events = std::move(t.shot_events),
                             .after = state};
    judged = t.game_referee->Judge(t.rules, *t.model, t.game, s.call, record, &state);
    s.verdict = judged->verdict;
    for (auto it = t.record.rbegin(); it != t.record.rend(); ++it) {
      if (it->kind == MatchEntry::Kind::kShoot && it->shot_id == s.shot_id) {
        it->verdict = judged->verdict;
        break;
      }
    }
    t.placed = false;
  }
  t.shot_events.clear();
  t.last_shot = s;
  t.rest = std::move(state);
  t.sim = nullptr;
  t.referee = nullptr;
  host.RunEnded();
  v1::TableEvent e = TableEvent(v1::shot_end, t.WorldTime(end_tick), s.shot_id);
  e.set_seat(s.seat);
  e.add_balls(s.struck_ball);
  ShotSummaryToProto(s, e.mutable_summary());
  fresh->push_back(t.Log(std::move(e)));
  if (judged.has_value()) {
    ApplyJudgement(t, *std::move(judged), end_tick, s.shot_id, fresh);
  } else if (Ruled(t)) {
    // A voided shot: the balls went back and the same seat plays again.
    ArmShotClock(t, end_tick);
    RefreshGameView(t);
  }
}

// The shot clock ran out at its tick (t.tick): the game's penalty.
void ExpireShotClock(Table& t, std::vector<EventPtr>* fresh) ABSL_EXCLUSIVE_LOCKS_REQUIRED(t.mu) {
  const int seat = t.game.to_play;
  t.clock_deadline.reset();
  b::TableState balls = t.rest;
  absl::StatusOr<games::Judgement> j =
      t.game_referee->ShotClockExpired(t.rules, *t.model, t.game, &balls);
  if (!j.ok()) {
    RefreshGameView(t);
    return;
  }
  t.rest = std::move(balls);
  t.record.push_back(MatchEntry{.kind = MatchEntry::Kind::kShotClock, .tick = t.tick,
                                .seat = seat, .verdict = j->verdict});
  ApplyJudgement(t, *std::move(j), t.tick, t.current.shot_id, fresh);
}

}  // namespace

namespace {

// A restore from a checkpoint: the table at rest as it was.
absl::Status LoadCheckpoint(Table& t, const std::string& bytes)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(t.mu) {
  absl::StatusOr<TableRestState> state = DecodeTableRestState(bytes);
  if (!state.ok()) return state.status();
  t.tick = state->tick;
  t.sequence = state->sequence;
  t.turn = state->turn;
  t.rest = std::move(state->rest);
  t.last_shot = std::move(state->last_shot);
  t.current = t.last_shot;  // at rest, the current shot is the last one
  t.shots = state->shots;
  t.game = std::move(state->game);
  t.placed = state->placed;
  t.clock_deadline = state->clock_deadline;
  t.record = std::move(state->record);
  if (Ruled(t)) RefreshGameView(t);
  return absl::OkStatus();
}

}  // namespace

bool TableKind::Running(const Table& t) ABSL_NO_THREAD_SAFETY_ANALYSIS { return t.sim != nullptr; }

std::optional<TableKind::End> TableKind::AdvanceTick(TableHost& /*host*/, Table& t, int64_t k,
                                                     TickOut* out) {
  const double shot_t = ShotTime(t, k);
  if (const absl::Status st = t.sim->AdvanceTo(shot_t, &out->events); !st.ok()) {
    return End{.error = absl::StrFormat("%s; the balls were put back where the shot started",
                                        st.message()),
               .voided = true};
  }
  if (t.sim->AtRest()) return End{};
  if (shot_t >= t.max_shot_s) {
    return End{.error = absl::StrFormat("the shot was stopped after %g s of simulated time",
                                        t.max_shot_s)};
  }
  return std::nullopt;
}

void TableKind::Publish(TableHost& /*host*/, Table& t, TickOut* out,
                        std::vector<EventPtr>* fresh) {
  LogShotEvents(t, out->events, fresh);
}

void TableKind::EndRun(TableHost& host, Table& t, const End& end, std::vector<EventPtr>* fresh,
                       Table::Pump* /*pump*/) {
  EndShot(host, t, t.tick, end, fresh);
}

uint64_t TableKind::Runs(const Table& t) ABSL_NO_THREAD_SAFETY_ANALYSIS { return t.shots; }

std::string TableKind::Checkpoint(const Table& t) ABSL_NO_THREAD_SAFETY_ANALYSIS {
  return EncodeTableRestState(TableRestState{.tick = t.tick,
                                             .sequence = t.sequence,
                                             .turn = t.turn,
                                             .rest = t.rest,
                                             .last_shot = t.last_shot,
                                             .shots = t.shots,
                                             .game = t.game,
                                             .placed = t.placed,
                                             .clock_deadline = t.clock_deadline,
                                             .record = t.record});
}

std::optional<int64_t> TableKind::RestDeadline(const Table& t) ABSL_NO_THREAD_SAFETY_ANALYSIS {
  if (!Ruled(t) || t.sim != nullptr) return std::nullopt;
  return t.clock_deadline;
}

void TableKind::AtRestDeadline(TableHost& /*host*/, Table& t, std::vector<EventPtr>* fresh) {
  ExpireShotClock(t, fresh);
}

std::shared_ptr<const Frame> TableKind::MakeFrame(const Table& t, int64_t k, bool heartbeat,
                                                  SteadyClock::time_point published)
    ABSL_NO_THREAD_SAFETY_ANALYSIS {
  auto f = std::make_shared<Frame>();
  f->sequence = t.sequence;
  f->tick = k;
  f->t_s = t.WorldTime(k);
  f->at_rest = t.sim == nullptr;
  f->heartbeat = heartbeat;
  f->turn = t.turn;
  f->shot_id = t.current.shot_id;
  f->model = t.model;
  if (!heartbeat) {
    f->balls = Balls(t).balls;
    f->game = t.game_view;
  }
  f->published = published;
  return f;
}

namespace {

// The largest step <= 1/960 s that divides the tick period (the stepped engine's default).
constexpr double kDefaultSteppedDt = 1.0 / 960.0;

// The seat a call acts for. A seat acts for itself (and must be the seat to play when
// `to_play`); the admin token acts for the seat to play in free play, and never plays in a
// ruled game.
absl::StatusOr<int> ActingSeat(const Table& t, int seat, bool to_play)
    ABSL_EXCLUSIVE_LOCKS_REQUIRED(t.mu) {
  if (seat == kAdminSeat) {
    if (t.game_referee != nullptr) {
      return absl::PermissionDeniedError(
          "token: the admin token does not play in a ruled game; use a seat's token");
    }
    return static_cast<int>(t.turn);
  }
  if (to_play && seat != static_cast<int>(t.turn)) {
    return absl::PermissionDeniedError(
        absl::StrFormat("token: it is seat %d's turn, not seat %d's", t.turn, seat));
  }
  return seat;
}

// A call's judgement (a decision, a concession) takes effect now: the balls, the record, the
// game state and its events, offered to every reader; the rest timers restart.
void ApplyCallJudgement(TableHost& host, Table& t, games::Judgement j, b::TableState balls,
                        MatchEntry entry, Table::Pump* pump) ABSL_EXCLUSIVE_LOCKS_REQUIRED(t.mu) {
  const int64_t tick = t.ClockTick(SteadyClock::now());
  t.tick = tick;
  ++t.sequence;
  t.rest = std::move(balls);
  t.placed = false;
  entry.tick = tick;
  t.record.push_back(std::move(entry));
  std::vector<EventPtr> fresh;
  ApplyJudgement(t, std::move(j), tick, t.current.shot_id, &fresh);
  host.CountEvents(fresh.size());
  t.OfferFrameAt(tick, fresh, pump);
  host.ScheduleRest(t);
}

// A random 64-bit seed (the table's secret noise seed when the creator names none).
uint64_t RandomSeed() {
  const std::string hex = RandomHex(8);
  return std::stoull(hex, nullptr, 16);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Registry

TableRegistry::TableRegistry(TableLimits limits, TickScheduler* scheduler)
    : limits_(limits), host_(limits.world, scheduler) {}

TableRegistry::~TableRegistry() { Shutdown(absl::UnavailableError("the server is shutting down")); }

absl::StatusOr<v1::CreateTableResponse> TableRegistry::Create(
    const v1::CreateTableRequest& request) {
  const std::shared_ptr<Table> table = host_.Make();
  std::vector<std::string> tokens;
  absl::StatusOr<v1::CreateTableResponse> made = MakeTable(request, std::nullopt, *table, &tokens);
  if (!made.ok()) return made.status();
  v1::CreateTableResponse response = *std::move(made);
  const std::string admin_token = RandomHex(16);
  table->admin_token_hash = HashToken(admin_token);
  SeatsToProto(table->seats, &tokens, response.mutable_seats());
  response.set_admin_token(admin_token);
  ::sportsim::store::v1::TableCreated created;
  created.set_request(table->create_request);
  created.set_seed(table->seed);
  if (absl::Status s = host_.Add(table, created.SerializeAsString()); !s.ok()) return s;
  response.set_table_id(table->id);
  // A clock that runs while nobody shoots needs a wake at its deadline.
  if (Ruled(*table) && table->rules.shot_clock_s > 0) {
    absl::MutexLock lock(&table->mu);
    host_.ScheduleRest(*table);
  }
  return response;
}

absl::StatusOr<v1::CreateTableResponse> TableRegistry::MakeTable(
    const v1::CreateTableRequest& request, std::optional<uint64_t> seed, Table& made,
    std::vector<std::string>* tokens) {
  const double tick_hz = request.tick_hz() == 0 ? 120.0 : request.tick_hz();
  if (absl::Status s = CheckFiniteInRange("tick_hz", tick_hz, 1, false, 1000, false); !s.ok()) {
    return s;
  }
  absl::StatusOr<GameSetup> game = GameSetupFromProto(request.game());
  if (!game.ok()) return game.status();
  const bool ruled = game->rules.game != games::GameKind::kFree;
  if (ruled && ((request.seats() != 0 && request.seats() != 2) ||
                (request.seat_names_size() != 0 && request.seat_names_size() != 2))) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "seats: a %s table has 2 seats, got %d", games::GameName(game->rules.game),
        std::max<int>(static_cast<int>(request.seats()), request.seat_names_size())));
  }
  absl::StatusOr<std::vector<SeatEntry>> seats =
      MakeSeats(request.seats(), request.seat_names(), /*default_count=*/2, tokens);
  if (!seats.ok()) return seats.status();
  v1::TableSetup setup = request.table();
  if (ruled) {
    // A ruled game is played on its own table; a break starts from its own rack, racked by
    // the referee, and a position in play from the balls given.
    if (setup.preset().empty()) setup.set_preset(GamePreset(game->rules.game));
    if (setup.rack().empty()) setup.set_rack("empty");
  }
  absl::StatusOr<TableBuild> build = TableFromProto(setup);
  if (!build.ok()) return build.status();
  absl::StatusOr<b::SolverOptions> solver = SolverFromProto(request.solver());
  if (!solver.ok()) return solver.status();
  if (ruled) {
    const uint32_t needed = game->rules.game == games::GameKind::kThreeCushion
                                ? b::kEffectDisableCushions
                                : b::kEffectDisableCushions | b::kEffectDisablePockets;
    if ((solver->effects & needed) != 0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "solver.disable: %s needs its cushions%s; they cannot be disabled",
          games::GameName(game->rules.game),
          game->rules.game == games::GameKind::kThreeCushion ? "" : " and pockets"));
    }
  }

  Table* const table = &made;
  table->tick_hz = tick_hz;
  table->period_s = 1.0 / tick_hz;
  table->max_shot_s = limits_.max_shot_s;
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
  table->preset = setup.preset().empty() ? "pool-9ft" : setup.preset();
  table->rack = build->rack;
  table->model = std::make_shared<const b::TableModel>(std::move(build->model));
  table->solver = *solver;
  table->rules = game->rules;
  table->start = game->start;
  table->noise = game->noise;
  table->seed = seed.has_value()         ? *seed
                : game->seed.has_value() ? *game->seed
                                         : RandomSeed();
  std::optional<games::GameState> state;
  if (ruled) {
    table->game_referee = games::RefereeFor(game->rules.game);
    if (table->game_referee == nullptr) {
      return absl::UnimplementedError(absl::StrFormat(
          "game.name: %s has no referee in this build", games::GameName(game->rules.game)));
    }
    absl::StatusOr<games::GameState> started =
        games::StartMatch(game->rules, *table->model, game->start, &build->state);
    if (!started.ok()) return PrefixStatus("game: ", started.status());
    started->seed = DeriveSeed(table->seed, 0);
    state = *std::move(started);
    if (game->start == games::Start::kBreak) table->rack = GameRack(game->rules.game);
  }
  table->initial = build->state;
  table->create_request = request.SerializeAsString();
  table->aim_lines = !request.has_aim_lines() || request.aim_lines();
  v1::CreateTableResponse response;
  if (table->seats.empty()) table->seats = *std::move(seats);  // a restore keeps its own
  {
    absl::MutexLock lock(&table->mu);
    table->clock.tick_hz = tick_hz * host_.limits().clock_rate;
    table->clock.origin = SteadyClock::now();
    table->rest = table->initial;
    if (state.has_value()) {
      table->game = *std::move(state);
      table->turn = static_cast<uint32_t>(table->game.to_play);
      ArmShotClock(*table, 0);
      RefreshGameView(*table);
      *response.mutable_game() = *table->game_view;
    }
  }
  response.set_tick_hz(tick_hz);
  response.set_engine(std::string(b::EngineName(solver->engine)));
  if (solver->engine == b::Engine::kStepped) response.set_dt_s(solver->dt_s);
  response.set_tick(0);
  return response;
}

absl::StatusOr<v1::TableInfo> TableRegistry::Get(const v1::GetTableRequest& request) {
  absl::StatusOr<std::shared_ptr<Table>> found = host_.Find(request.table_id());
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
  info.set_t_s(t.WorldTime(tick));
  info.set_sequence(t.sequence);
  info.set_at_rest(t.sim == nullptr);
  info.set_turn(t.turn);
  SeatsToProto(t.seats, nullptr, info.mutable_seats());
  for (const b::Ball& ball : Balls(t).balls) BallToProto(*t.model, ball, info.add_balls());
  info.set_shots(t.shots);
  if (t.shots > 0) ShotSummaryToProto(t.last_shot, info.mutable_last_shot());
  info.set_watchers(static_cast<uint32_t>(t.watchers.size()));
  info.set_engine(std::string(b::EngineName(t.solver.engine)));
  if (t.solver.engine == b::Engine::kStepped) info.set_dt_s(t.solver.dt_s);
  info.set_aim_lines(t.aim_lines);
  if (request.include_geometry()) GeometryToProto(*t.model, info.mutable_geometry());
  if (t.game_view != nullptr) *info.mutable_game() = *t.game_view;
  return info;
}

absl::StatusOr<v1::ListTablesResponse> TableRegistry::List(const v1::ListTablesRequest& request) {
  v1::ListTablesResponse response;
  const SteadyClock::time_point now = SteadyClock::now();
  absl::StatusOr<uint32_t> total = host_.List(
      PageRequest{.page_size = request.page_size(), .page_token = request.page_token()},
      response.mutable_next_page_token(), [&](const Table& t) ABSL_NO_THREAD_SAFETY_ANALYSIS {
        v1::TableBrief* brief = response.add_tables();
        brief->set_table_id(t.id);
        brief->set_preset(t.preset);
        brief->set_at_rest(t.sim == nullptr);
        brief->set_tick(t.sim != nullptr ? t.tick : t.ClockTick(now));
        uint32_t on = 0;
        for (const b::Ball& ball : Balls(t).balls) on += ball.state != b::MotionState::kPocketed;
        brief->set_balls_on_table(on);
        brief->set_seats(static_cast<uint32_t>(t.seats.size()));
        brief->set_watchers(static_cast<uint32_t>(t.watchers.size()));
        brief->set_shots(t.shots);
      });
  if (!total.ok()) return total.status();
  response.set_total(*total);
  return response;
}

absl::Status TableRegistry::Delete(const v1::DeleteTableRequest& request) {
  return host_.Delete(
      request.table_id(), request.token(),
      [](const Table& t, int seat) ABSL_NO_THREAD_SAFETY_ANALYSIS {
        if (Ruled(t) && seat != kAdminSeat) {
          return absl::PermissionDeniedError(
              "token: in a ruled game only the admin token deletes the table");
        }
        return absl::OkStatus();
      },
      [&](Table& t, std::vector<EventPtr>* /*fresh*/, Table::Pump* /*pump*/)
          ABSL_NO_THREAD_SAFETY_ANALYSIS {
        if (t.sim != nullptr) host_.RunEnded();
        t.sim = nullptr;
      },
      static_cast<uint32_t>(TableCommand::kDelete), JournalBody(request));
}

absl::StatusOr<v1::ResetTableResponse> TableRegistry::Reset(const v1::ResetTableRequest& request) {
  return host_.Act<v1::ResetTableResponse>(
      request.table_id(), request.token(),
      [&](const std::shared_ptr<Table>& ptr, int seat, Table::Pump& pump) {
        return ResetOn(*ptr, seat, request, pump);
      });
}

absl::StatusOr<v1::ResetTableResponse> TableRegistry::ResetOn(Table& t, int seat,
                                                   const v1::ResetTableRequest& request,
                                                   Table::Pump& pump) {
  const int asked = seat;
  v1::ResetTableResponse response;
  if (Ruled(t) && seat != kAdminSeat) {
    return absl::PermissionDeniedError(
        "token: in a ruled game only the admin token resets the table");
  }
  std::optional<games::GameState> restarted;
  b::TableState balls = t.initial;
  if (Ruled(t)) {
    // The match starts again from the creation's start.
    absl::StatusOr<games::GameState> started =
        games::StartMatch(t.rules, *t.model, t.start, &balls);
    if (!started.ok()) return PrefixStatus("game: ", started.status());
    started->seed = DeriveSeed(t.seed, 0);
    restarted = *std::move(started);
  }
  if (absl::Status s = host_.Commit(t, asked, static_cast<uint32_t>(TableCommand::kReset),
                                    JournalBody(request));
      !s.ok()) {
    return s;
  }
  const int64_t tick = t.NowTick();
  ++t.sequence;
  std::vector<EventPtr> fresh;
  if (t.sim != nullptr) {
    // A ruled game restarts: the interrupted shot is void, not judged.
    EndShot(host_, t, tick,
            TableKind::End{.error = "the table was reset during the shot", .voided = Ruled(t)},
            &fresh);
    host_.AfterRunEndedByCall(t);
  }
  t.rest = std::move(balls);
  t.tick = tick;
  t.placed = false;
  v1::TableEvent e = TableEvent(v1::table_reset, t.WorldTime(tick), 0);
  if (seat >= 0) e.set_seat(static_cast<uint32_t>(seat));
  fresh.push_back(t.Log(std::move(e)));
  if (restarted.has_value()) {
    t.record.push_back(MatchEntry{.kind = MatchEntry::Kind::kReset, .tick = tick, .seat = seat});
    ApplyJudgement(t, games::Judgement{.state = *std::move(restarted)}, tick, 0, &fresh);
    host_.ScheduleRest(t);
  }
  host_.CountEvents(fresh.size());
  t.OfferFrameAt(tick, fresh, &pump);
  response.set_sequence(t.sequence);
  response.set_tick(tick);
  return response;
}

absl::StatusOr<v1::PlaceBallResponse> TableRegistry::Place(const v1::PlaceBallRequest& request) {
  const v1::BallPlacement& p = request.ball();
  if (absl::Status s = CheckId("ball.id", p.id()); !s.ok()) return s;
  if (!std::isfinite(p.x_m()) || !std::isfinite(p.y_m())) {
    return absl::InvalidArgumentError(
        absl::StrFormat("ball: x_m and y_m must be finite, got (%g, %g)", p.x_m(), p.y_m()));
  }
  return host_.Act<v1::PlaceBallResponse>(
      request.table_id(), request.token(),
      [&](const std::shared_ptr<Table>& ptr, int seat, Table::Pump& pump) {
        return PlaceOn(*ptr, seat, request, pump);
      });
}

absl::StatusOr<v1::PlaceBallResponse> TableRegistry::PlaceOn(Table& t, int seat,
                                                   const v1::PlaceBallRequest& request,
                                                   Table::Pump& pump) {
  const int asked = seat;
  const v1::BallPlacement& p = request.ball();
  absl::StatusOr<int> acting = ActingSeat(t, seat, /*to_play=*/!Ruled(t));
  if (!acting.ok()) return acting.status();
  seat = *acting;
  v1::PlaceBallResponse response;
  if (t.sim != nullptr) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "balls are still moving (shot %d); place balls when every ball is at rest",
        t.current.shot_id));
  }
  if (Ruled(t)) {
    // Ball in hand only: the seat that has it, its own cue ball, inside the zone.
    if (absl::Status s = t.game_referee->CheckPlacement(
            t.rules, *t.model, t.game, seat, t.rest, p.id(), Eigen::Vector2d(p.x_m(), p.y_m()));
        !s.ok()) {
      return s;
    }
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
  if (absl::Status s = host_.Commit(t, asked, static_cast<uint32_t>(TableCommand::kPlace),
                                    JournalBody(request));
      !s.ok()) {
    return s;
  }
  const int64_t tick = t.ClockTick(SteadyClock::now());
  t.tick = tick;
  t.rest = std::move(state);
  ++t.sequence;
  if (Ruled(t)) {
    t.placed = true;
    t.record.push_back(MatchEntry{.kind = MatchEntry::Kind::kPlace, .tick = tick, .seat = seat,
                                  .ball = p.id(), .x_m = p.x_m(), .y_m = p.y_m()});
  }
  v1::TableEvent e = TableEvent(v1::ball_placed, t.WorldTime(tick), 0);
  e.set_seat(static_cast<uint32_t>(seat));
  e.add_balls(p.id());
  std::vector<EventPtr> fresh{t.Log(std::move(e))};
  host_.CountEvents(1);
  t.OfferFrameAt(tick, fresh, &pump);
  response.set_sequence(t.sequence);
  response.set_tick(tick);
  return response;
}

absl::StatusOr<v1::ShootResponse> TableRegistry::Shoot(const v1::ShootRequest& request) {
  if (!request.has_strike()) return absl::InvalidArgumentError("strike: required");
  absl::StatusOr<b::CueStrike> strike = StrikeFromProto(request.strike());
  if (!strike.ok()) return strike.status();
  return host_.Act<v1::ShootResponse>(
      request.table_id(), request.token(),
      [&](const std::shared_ptr<Table>& ptr, int seat, Table::Pump& pump) {
        return ShootOn(*ptr, seat, request, pump);
      });
}

absl::StatusOr<v1::ShootResponse> TableRegistry::ShootOn(Table& t, int seat,
                                                   const v1::ShootRequest& request,
                                                   Table::Pump& pump) {
  const int asked = seat;
  if (!request.has_strike()) return absl::InvalidArgumentError("strike: required");
  absl::StatusOr<b::CueStrike> strike = StrikeFromProto(request.strike());
  if (!strike.ok()) return strike.status();
  absl::StatusOr<int> acting = ActingSeat(t, seat, /*to_play=*/!Ruled(t));
  if (!acting.ok()) return acting.status();
  seat = *acting;
  v1::ShootResponse response;
  b::CueStrike struck = *strike;
  absl::StatusOr<games::ShotCall> parsed = ShotCallFromProto(request.call());
  if (!parsed.ok()) return parsed.status();
  const games::ShotCall call = *std::move(parsed);
  if (Ruled(t)) {
    if (request.has_next_seat()) {
      return absl::FailedPreconditionError(
          "next_seat: in a ruled game the referee decides who plays next");
    }
    const std::string own = StrikerBall(t, seat);
    if (!request.strike().ball().empty() && request.strike().ball() != own) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "strike.ball: seat %d strikes only its own cue ball \"%s\"", seat, own));
    }
    if (request.strike().noise() != 0 || request.strike().seed() != 0) {
      return absl::FailedPreconditionError(
          "strike.noise, strike.seed: in a ruled game the table's noise applies, with a seed "
          "no shooter chooses");
    }
    if (t.sim == nullptr) {
      if (absl::Status s =
              t.game_referee->CheckShot(t.rules, *t.model, t.game, seat, call, t.rest);
          !s.ok()) {
        return s;
      }
    }
    struck.noise = t.noise;
    struck.seed = DeriveSeed(t.seed, t.shots + 1);
  } else if (request.has_call()) {
    return absl::FailedPreconditionError("call: free play has no referee to call a shot to");
  }
  if (request.has_next_seat() && request.next_seat() >= t.seats.size()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "next_seat must be in [0, %d], got %d", t.seats.size() - 1, request.next_seat()));
  }
  if (t.sim != nullptr) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "balls are still moving (shot %d): shoot when every ball is at rest",
        t.current.shot_id));
  }
  const std::string id = Ruled(t)                         ? StrikerBall(t, seat)
                         : request.strike().ball().empty() ? "cue"
                                                           : request.strike().ball();
  const int cue = t.rest.Find(id);
  if (cue < 0) {
    return absl::InvalidArgumentError(
        absl::StrFormat("strike.ball: no ball %s on the table", Quote(id)));
  }
  if (t.rest.balls[cue].state == b::MotionState::kPocketed) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "strike.ball: ball %s is pocketed; put it back with PlaceBall first", Quote(id)));
  }
  b::TableState state = t.rest;
  state.t_s = 0.0;
  absl::StatusOr<b::StrikeOutcome> outcome =
      b::ApplyStrike(*t.model, t.solver.effects, struck, cue, &state);
  if (!outcome.ok()) return PrefixStatus("strike.", outcome.status());
  std::vector<b::Event> events;
  absl::StatusOr<std::unique_ptr<b::TableSimulation>> sim =
      b::TableSimulation::Create(*t.model, t.solver, std::move(state), &events);
  if (!sim.ok()) return sim.status();

  // Accepted: from here on nothing fails.
  if (absl::Status s = host_.Commit(t, asked, static_cast<uint32_t>(TableCommand::kShoot),
                                    JournalBody(request));
      !s.ok()) {
    return s;
  }
  const SteadyClock::time_point now = SteadyClock::now();
  const int64_t start = t.ClockTick(now) + 1;
  t.tick = start;
  ++t.sequence;
  ++t.shots;
  const uint64_t shot_id = t.shots;
  t.current = ShotSummary{.shot_id = shot_id, .seat = static_cast<uint32_t>(seat),
                          .struck_ball = id, .start_tick = start, .call = call};
  if (Ruled(t)) {
    t.record.push_back(MatchEntry{.kind = MatchEntry::Kind::kShoot, .tick = start,
                                  .seat = seat, .strike = request.strike().SerializeAsString(),
                                  .call = call, .shot_id = shot_id, .seed = struck.seed,
                                  .applied = *outcome});
    t.clock_deadline.reset();
    t.shot_events.clear();
    RefreshGameView(t);
  }
  t.sim = *std::move(sim);
  t.referee = std::make_unique<b::ShotReferee>(cue);
  t.shot_start = t.rest;
  host_.RunStarted();
  std::vector<EventPtr> fresh;
  v1::TableEvent e = TableEvent(v1::shot, t.WorldTime(start), shot_id);
  e.set_seat(static_cast<uint32_t>(seat));
  e.add_balls(id);
  fresh.push_back(t.Log(std::move(e)));
  LogShotEvents(t, events, &fresh);
  if (request.has_next_seat() && request.next_seat() != t.turn) {
    t.turn = request.next_seat();
    v1::TableEvent te = TableEvent(v1::turn, t.WorldTime(start), shot_id);
    te.set_seat(t.turn);
    fresh.push_back(t.Log(std::move(te)));
  }
  host_.CountEvents(fresh.size());
  t.OfferFrameAt(start, fresh, &pump);
  response.set_shot_id(shot_id);
  response.set_start_tick(start);
  StrikeReportToProto(*outcome, response.mutable_strike());
  host_.ScheduleNextTick(t);
  return response;
}

absl::StatusOr<v1::SetTurnResponse> TableRegistry::SetTurn(const v1::SetTurnRequest& request) {
  // Only the seat to play passes the turn.
  return host_.Act<v1::SetTurnResponse>(
      request.table_id(), request.token(),
      [&](const std::shared_ptr<Table>& ptr, int seat, Table::Pump& pump) {
        return SetTurnOn(*ptr, seat, request, pump);
      });
}

absl::StatusOr<v1::SetTurnResponse> TableRegistry::SetTurnOn(Table& t, int seat,
                                                   const v1::SetTurnRequest& request,
                                                   Table::Pump& pump) {
  const int asked = seat;
  if (Ruled(t)) {
    return absl::FailedPreconditionError(
        "turn: in a ruled game the referee decides who plays next; nobody sets the turn");
  }
  if (absl::StatusOr<int> acting = ActingSeat(t, seat, /*to_play=*/true); !acting.ok()) {
    return acting.status();
  }
  v1::SetTurnResponse response;
  if (request.seat() >= t.seats.size()) {
    return absl::InvalidArgumentError(absl::StrFormat("seat must be in [0, %d], got %d",
                                                      t.seats.size() - 1, request.seat()));
  }
  if (request.seat() != t.turn) {
    if (absl::Status s = host_.Commit(t, asked, static_cast<uint32_t>(TableCommand::kSetTurn),
                                      JournalBody(request));
        !s.ok()) {
      return s;
    }
    const int64_t tick = t.NowTick();
    ++t.sequence;
    t.turn = request.seat();
    v1::TableEvent e = TableEvent(v1::turn, t.WorldTime(tick), t.current.shot_id);
    e.set_seat(t.turn);
    std::vector<EventPtr> fresh{t.Log(std::move(e))};
    host_.CountEvents(1);
    // At rest the turn goes out now; while balls move it rides with the next snapshot.
    if (t.sim == nullptr) {
      t.OfferFrameAt(tick, fresh, &pump);
    } else {
      t.OfferAll(nullptr, fresh, &pump);
    }
  }
  response.set_sequence(t.sequence);
  return response;
}

absl::StatusOr<v1::DecideResponse> TableRegistry::Decide(const v1::DecideRequest& request) {
  if (request.choice().empty() || request.choice().size() > 32) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "choice must be 1 to 32 characters, got %d: %s", request.choice().size(),
        Quote(request.choice())));
  }
  return host_.Act<v1::DecideResponse>(
      request.table_id(), request.token(),
      [&](const std::shared_ptr<Table>& ptr, int seat, Table::Pump& pump) {
        return DecideOn(*ptr, seat, request, pump);
      });
}

absl::StatusOr<v1::DecideResponse> TableRegistry::DecideOn(Table& t, int seat,
                                                   const v1::DecideRequest& request,
                                                   Table::Pump& pump) {
  const int asked = seat;
  if (!Ruled(t)) {
    return absl::FailedPreconditionError("decide: free play has no decisions");
  }
  if (seat == kAdminSeat) {
    return absl::PermissionDeniedError("token: a decision is the seat's, not the admin's");
  }
  if (t.sim != nullptr) {
    return absl::FailedPreconditionError("balls are still moving: decide when they are at rest");
  }
  b::TableState balls = t.rest;
  absl::StatusOr<games::Judgement> j =
      t.game_referee->Decide(t.rules, *t.model, t.game, seat, request.choice(), &balls);
  if (!j.ok()) return j.status();
  if (absl::Status s = host_.Commit(t, asked, static_cast<uint32_t>(TableCommand::kDecide),
                                    JournalBody(request));
      !s.ok()) {
    return s;
  }
  ApplyCallJudgement(host_, t, *std::move(j), std::move(balls),
                     MatchEntry{.kind = MatchEntry::Kind::kDecide, .seat = seat,
                                .choice = request.choice()},
                     &pump);
  v1::DecideResponse response;
  response.set_sequence(t.sequence);
  *response.mutable_game() = *t.game_view;
  return response;
}

absl::StatusOr<v1::ConcedeResponse> TableRegistry::Concede(const v1::ConcedeRequest& request) {
  return host_.Act<v1::ConcedeResponse>(
      request.table_id(), request.token(),
      [&](const std::shared_ptr<Table>& ptr, int seat, Table::Pump& pump) {
        return ConcedeOn(*ptr, seat, request, pump);
      });
}

absl::StatusOr<v1::ConcedeResponse> TableRegistry::ConcedeOn(Table& t, int seat,
                                                   const v1::ConcedeRequest& request,
                                                   Table::Pump& pump) {
  const int asked = seat;
  if (!Ruled(t)) {
    return absl::FailedPreconditionError("concede: free play has no frames to concede");
  }
  int conceding = seat;
  if (seat == kAdminSeat) {
    if (!request.has_seat() || request.seat() > 1) {
      return absl::InvalidArgumentError(
          "seat: the admin token concedes for a seat, 0 or 1, which it must name");
    }
    conceding = static_cast<int>(request.seat());
  } else if (request.has_seat() && static_cast<int>(request.seat()) != seat) {
    return absl::PermissionDeniedError("seat: a seat concedes only for itself");
  }
  if (t.sim != nullptr) {
    return absl::FailedPreconditionError(
        "balls are still moving: concede when they are at rest");
  }
  if (t.game.match_over()) {
    return absl::FailedPreconditionError("the match is over: nothing left to concede");
  }
  if (request.has_frame() && static_cast<int64_t>(request.frame()) != t.game.frame) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "frame: the concession names frame %u, but the match is on frame %d (a frame is "
        "conceded once)",
        request.frame(), t.game.frame));
  }
  b::TableState balls = t.rest;
  absl::StatusOr<games::Judgement> j =
      t.game_referee->Concede(t.rules, *t.model, t.game, conceding, &balls);
  if (!j.ok()) return j.status();
  if (absl::Status s = host_.Commit(t, asked, static_cast<uint32_t>(TableCommand::kConcede),
                                    JournalBody(request));
      !s.ok()) {
    return s;
  }
  const games::Verdict verdict = j->verdict;
  ApplyCallJudgement(host_, t, *std::move(j), std::move(balls),
                     MatchEntry{.kind = MatchEntry::Kind::kConcede, .seat = conceding,
                                .verdict = verdict},
                     &pump);
  v1::ConcedeResponse response;
  response.set_sequence(t.sequence);
  *response.mutable_game() = *t.game_view;
  return response;
}

absl::StatusOr<v1::MatchRecord> TableRegistry::GetMatchRecord(
    const v1::GetMatchRecordRequest& request) {
  absl::StatusOr<std::shared_ptr<Table>> found = host_.Find(request.table_id());
  if (!found.ok()) return found.status();
  Table& t = **found;
  absl::MutexLock lock(&t.mu);
  if (!Ruled(t)) {
    return absl::FailedPreconditionError("table_id: a free-play table keeps no match record");
  }
  v1::MatchRecord out;
  out.set_table_id(t.id);
  // The seeds stay secret while the match goes on: they would let a seat predict its noise.
  const bool ended = t.game.match_over();
  out.set_ended(ended);
  out.mutable_create()->ParseFromString(t.create_request);
  if (ended) {
    out.mutable_create()->mutable_game()->set_seed(t.seed);
  } else {
    out.mutable_create()->mutable_game()->clear_seed();  // even one its creator chose
  }
  for (const MatchEntry& m : t.record) {
    v1::MatchAction* a = out.add_actions();
    a->set_tick(m.tick);
    a->set_seat(static_cast<uint32_t>(std::max(m.seat, 0)));
    switch (m.kind) {
      case MatchEntry::Kind::kShoot:
        a->set_kind(v1::MatchAction::SHOOT);
        a->mutable_strike()->ParseFromString(m.strike);
        ShotCallToProto(m.call, a->mutable_call());
        a->set_shot_id(m.shot_id);
        if (ended) {
          a->set_seed(m.seed);
          StrikeReportToProto(m.applied, a->mutable_applied());
        }
        break;
      case MatchEntry::Kind::kPlace:
        a->set_kind(v1::MatchAction::PLACE);
        a->mutable_place()->set_id(m.ball);
        a->mutable_place()->set_x_m(m.x_m);
        a->mutable_place()->set_y_m(m.y_m);
        break;
      case MatchEntry::Kind::kDecide:
        a->set_kind(v1::MatchAction::DECIDE);
        a->set_choice(m.choice);
        break;
      case MatchEntry::Kind::kConcede: a->set_kind(v1::MatchAction::CONCEDE); break;
      case MatchEntry::Kind::kShotClock: a->set_kind(v1::MatchAction::SHOT_CLOCK); break;
      case MatchEntry::Kind::kReset: a->set_kind(v1::MatchAction::RESET); break;
    }
    if (m.verdict.has_value()) VerdictToProto(*m.verdict, a->mutable_verdict());
  }
  *out.mutable_game() = *t.game_view;
  return out;
}

absl::StatusOr<PreviewJob> TableRegistry::PreparePreview(const v1::PreviewShotRequest& request) {
  if (request.max_events() > kMaxPreviewEvents) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "max_events must be in [0, %d] (0: %d), got %d", kMaxPreviewEvents, kMaxPreviewEvents,
        request.max_events()));
  }
  if (!request.has_strike()) return absl::InvalidArgumentError("strike: required");
  if (request.strike().noise() != 0 || request.strike().seed() != 0) {
    return absl::InvalidArgumentError("strike.noise, strike.seed: a preview has no noise");
  }
  absl::StatusOr<b::CueStrike> strike = StrikeFromProto(request.strike());
  if (!strike.ok()) return strike.status();
  return host_.Act<PreviewJob>(
      request.table_id(), request.token(),
      [&](const std::shared_ptr<Table>& ptr, int seat,
          Table::Pump& /*pump*/) -> absl::StatusOr<PreviewJob> {
    Table& t = *ptr;
    if (!t.aim_lines) {
      return absl::FailedPreconditionError(
          "aim lines are off on this table (CreateTableRequest.aim_lines)");
    }
    absl::StatusOr<int> acting = ActingSeat(t, seat, /*to_play=*/true);
    if (!acting.ok()) return acting.status();
    if (t.sim != nullptr) {
      return absl::FailedPreconditionError("balls are still moving: preview when they are at rest");
    }
    if (Ruled(t) && (t.game.match_over() || t.game.decision.pending())) {
      return absl::FailedPreconditionError("no shot to preview: the match is over or a decision "
                                           "is pending");
    }
    const std::string id = Ruled(t)                         ? StrikerBall(t, *acting)
                           : request.strike().ball().empty() ? "cue"
                                                             : request.strike().ball();
    if (Ruled(t) && !request.strike().ball().empty() && request.strike().ball() != id) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "strike.ball: seat %d strikes only its own cue ball \"%s\"", *acting, id));
    }
    PreviewJob job;
    job.cue = t.rest.Find(id);
    if (job.cue < 0 || t.rest.balls[job.cue].state == b::MotionState::kPocketed) {
      return absl::FailedPreconditionError(
          absl::StrFormat("strike.ball: ball %s is not on the table", Quote(id)));
    }
    job.model = t.model;
    job.solver = t.solver;
    job.balls = t.rest;
    job.strike = *strike;
    job.max_events = request.max_events() == 0 ? kMaxPreviewEvents
                                               : static_cast<int>(request.max_events());
    return job;
  });
}

absl::StatusOr<std::shared_ptr<Watcher>> TableRegistry::Watch(
    const v1::WatchTableRequest& request, SnapshotSink* sink) {
  WatchOptions options;
  options.changed_only = request.changed_only();
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
  std::optional<uint64_t> from;
  if (request.has_from_sequence()) from = request.from_sequence();
  return host_.Watch(request.table_id(), request.rate_hz(), options, from, sink);
}

void TableRegistry::Unwatch(const std::string& table_id, const Watcher* watcher) {
  host_.Unwatch(table_id, watcher);
}

void TableRegistry::Shutdown(const absl::Status& status) { host_.Shutdown(status); }

template <typename Req, typename Resp>
absl::Status TableRegistry::ReplayAs(
    absl::StatusOr<Resp> (TableRegistry::*on)(Table&, int, const Req&, Table::Pump&), Table& t,
    const JournalEntry& e, Table::Pump& pump) {
  Req request;
  if (!request.ParseFromString(e.body)) {
    return absl::DataLossError(absl::StrFormat("entry %d: the command does not parse", e.index));
  }
  return (this->*on)(t, e.seat, request, pump).status();
}

absl::Status TableRegistry::Replay(Table& t, const JournalEntry& e, Table::Pump& pump) {
  switch (static_cast<TableCommand>(e.type)) {
    case TableCommand::kReset: return ReplayAs(&TableRegistry::ResetOn, t, e, pump);
    case TableCommand::kPlace: return ReplayAs(&TableRegistry::PlaceOn, t, e, pump);
    case TableCommand::kShoot: return ReplayAs(&TableRegistry::ShootOn, t, e, pump);
    case TableCommand::kSetTurn: return ReplayAs(&TableRegistry::SetTurnOn, t, e, pump);
    case TableCommand::kDecide: return ReplayAs(&TableRegistry::DecideOn, t, e, pump);
    case TableCommand::kConcede: return ReplayAs(&TableRegistry::ConcedeOn, t, e, pump);
    case TableCommand::kCreate:
    case TableCommand::kDelete:
      break;
  }
  return absl::DataLossError(
      absl::StrFormat("entry %d: no table command of type %d", e.index, e.type));
}

absl::Status TableRegistry::Restore(const StoredWorld& stored) {
  return host_.Restore(
      stored,
      [&](Table& t, const std::string& kind_body) -> absl::Status {
        ::sportsim::store::v1::TableCreated created;
        v1::CreateTableRequest request;
        if (!created.ParseFromString(kind_body) || !request.ParseFromString(created.request())) {
          return absl::DataLossError("its creation does not parse");
        }
        std::vector<std::string> unused;
        return MakeTable(request, created.seed(), t, &unused).status();
      },
      [&](Table& t, const std::string& checkpoint) ABSL_NO_THREAD_SAFETY_ANALYSIS {
        return LoadCheckpoint(t, checkpoint);
      },
      [&](Table& t, const JournalEntry& e, Table::Pump& pump) ABSL_NO_THREAD_SAFETY_ANALYSIS {
        return Replay(t, e, pump);
      });
}

}  // namespace sportsim::server
