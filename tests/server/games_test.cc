// Server-level tests of the ruled games (docs/games.md): the real server in-process on an
// ephemeral loopback port, called through the generated stubs over a real gRPC channel, with
// table time running kClockRate times faster than real time.
//
// 1. Whole matches (8-ball, 9-ball, 10-ball, snooker, three-cushion), race to 2, played to the
//    end by a scripted bot that verifies every candidate shot with SimulateShot (noise 0: the
//    table does exactly what SimulateShot predicts). Frame 1 starts in play near its end; the
//    later frames start from the referee's own rack with a break the bot plays.
// 2. Match records replayed on a new table, bit for bit (one table with noise, whose seed
//    stays hidden until the match ends).
// 3. The cheating list: each request refused with its code and a message naming the rule,
//    changing nothing.
// 4. The shot clock's penalty at its deadline tick.
// 5. Free play keeps every seat's (and the admin's) rights.
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <google/protobuf/util/message_differencer.h>
#include <grpcpp/grpcpp.h>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/app/server_app.h"
#include "sportsim/v1/billiards.grpc.pb.h"

namespace sportsim::server {
namespace {

using ::google::protobuf::util::MessageDifferencer;
using ::testing::HasSubstr;

constexpr double kClockRate = 50.0;
constexpr double kPi = 3.14159265358979323846;
using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::unique_ptr<grpc::ClientContext> Ctx(int seconds = 30) {
  auto c = std::make_unique<grpc::ClientContext>();
  c->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(seconds));
  return c;
}

struct V2 {
  double x = 0, y = 0;
  V2 operator+(V2 o) const { return {x + o.x, y + o.y}; }
  V2 operator-(V2 o) const { return {x - o.x, y - o.y}; }
  V2 operator*(double s) const { return {x * s, y * s}; }
  double norm() const { return std::hypot(x, y); }
  V2 unit() const { const double n = norm(); return {x / n, y / n}; }
  double dot(V2 o) const { return x * o.x + y * o.y; }
};

struct Placed {
  std::string id;
  double x, y;
};

struct TableHandle {
  std::string id;
  std::string admin;
  std::array<std::string, 2> tokens;
  v1::CreateTableResponse created;
};

// ---------------------------------------------------------------------------------------------
// A WatchTable reader on its own thread, keeping every event and the game of each snapshot.

class Watch {
 public:
  Watch(v1::Billiards::Stub* stub, const std::string& id) {
    v1::WatchTableRequest req;
    req.set_table_id(id);
    req.set_rate_hz(30);
    req.set_from_sequence(0);  // every event since the table was created
    req.add_fields(v1::SNAPSHOT_FIELD_POSITION);
    reader_ = stub->WatchTable(&ctx_, req);
    thread_ = std::thread([this] {
      v1::TableSnapshot s;
      while (reader_->Read(&s)) {
        std::lock_guard<std::mutex> lock(mu_);
        if (s.resync()) ++resyncs_;
        for (const v1::TableEvent& e : s.events()) events_.push_back(e);
        if (s.events_size() > 0) snapshots_.push_back(s);
      }
    });
  }
  ~Watch() {
    ctx_.TryCancel();
    thread_.join();
    (void)reader_->Finish();
  }
  std::vector<v1::TableEvent> Events(std::optional<v1::EventKind> kind = std::nullopt) {
    std::lock_guard<std::mutex> lock(mu_);
    std::vector<v1::TableEvent> out;
    for (const v1::TableEvent& e : events_) {
      if (!kind.has_value() || e.kind() == *kind) out.push_back(e);
    }
    return out;
  }
  std::vector<v1::TableSnapshot> Snapshots() {
    std::lock_guard<std::mutex> lock(mu_);
    return snapshots_;
  }
  int resyncs() {
    std::lock_guard<std::mutex> lock(mu_);
    return resyncs_;
  }
  // Waits (wall time) until `count` events of `kind` have arrived.
  bool WaitFor(v1::EventKind kind, size_t count = 1, double timeout_s = 10) {
    const auto t0 = Clock::now();
    while (Seconds(t0) < timeout_s) {
      if (Events(kind).size() >= count) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  }

 private:
  grpc::ClientContext ctx_;
  std::unique_ptr<grpc::ClientReader<v1::TableSnapshot>> reader_;
  std::thread thread_;
  std::mutex mu_;
  std::vector<v1::TableEvent> events_;
  std::vector<v1::TableSnapshot> snapshots_;
  int resyncs_ = 0;
};

// ---------------------------------------------------------------------------------------------
// Calls

class Api {
 public:
  explicit Api(v1::Billiards::Stub* stub) : stub_(stub) {}

  v1::TableInfo Get(const std::string& id, bool geometry = false) {
    v1::GetTableRequest req;
    req.set_table_id(id);
    req.set_include_geometry(geometry);
    v1::TableInfo info;
    const grpc::Status s = stub_->GetTable(Ctx().get(), req, &info);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return info;
  }
  // The table without the fields that move with the clock alone.
  v1::TableInfo Still(const std::string& id) {
    v1::TableInfo info = Get(id);
    info.clear_tick();
    info.clear_t_s();
    info.clear_watchers();
    return info;
  }
  // Waits until shot `shot_id` has ended (every ball at rest). Fails the test after 60 s.
  v1::TableInfo WaitShot(const std::string& id, uint64_t shot_id) {
    const auto t0 = Clock::now();
    while (true) {
      v1::TableInfo info = Get(id);
      if (info.at_rest() && info.shots() >= shot_id) return info;
      if (Seconds(t0) > 60) {
        ADD_FAILURE() << "shot " << shot_id << " of " << id << " did not end within 60 s";
        return info;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  grpc::Status Shoot(const std::string& id, const std::string& token, const v1::CueStrike& strike,
                     const v1::ShotCall* call = nullptr, v1::ShootResponse* out = nullptr,
                     std::optional<uint32_t> next_seat = std::nullopt) {
    v1::ShootRequest req;
    req.set_table_id(id);
    req.set_token(token);
    *req.mutable_strike() = strike;
    if (call != nullptr) *req.mutable_call() = *call;
    if (next_seat.has_value()) req.set_next_seat(*next_seat);
    v1::ShootResponse resp;
    const grpc::Status s = stub_->Shoot(Ctx().get(), req, &resp);
    if (out != nullptr) *out = resp;
    return s;
  }
  grpc::Status Place(const std::string& id, const std::string& token, const std::string& ball,
                     double x, double y) {
    v1::PlaceBallRequest req;
    req.set_table_id(id);
    req.set_token(token);
    req.mutable_ball()->set_id(ball);
    req.mutable_ball()->set_x_m(x);
    req.mutable_ball()->set_y_m(y);
    v1::PlaceBallResponse resp;
    return stub_->PlaceBall(Ctx().get(), req, &resp);
  }
  grpc::Status Decide(const std::string& id, const std::string& token, const std::string& choice) {
    v1::DecideRequest req;
    req.set_table_id(id);
    req.set_token(token);
    req.set_choice(choice);
    v1::DecideResponse resp;
    return stub_->Decide(Ctx().get(), req, &resp);
  }
  grpc::Status Concede(const std::string& id, const std::string& token,
                       std::optional<uint32_t> seat = std::nullopt,
                       std::optional<uint32_t> frame = std::nullopt) {
    v1::ConcedeRequest req;
    req.set_table_id(id);
    req.set_token(token);
    if (seat.has_value()) req.set_seat(*seat);
    if (frame.has_value()) req.set_frame(*frame);
    v1::ConcedeResponse resp;
    return stub_->Concede(Ctx().get(), req, &resp);
  }
  grpc::Status SetTurn(const std::string& id, const std::string& token, uint32_t seat) {
    v1::SetTurnRequest req;
    req.set_table_id(id);
    req.set_token(token);
    req.set_seat(seat);
    v1::SetTurnResponse resp;
    return stub_->SetTurn(Ctx().get(), req, &resp);
  }
  grpc::Status Reset(const std::string& id, const std::string& token) {
    v1::ResetTableRequest req;
    req.set_table_id(id);
    req.set_token(token);
    v1::ResetTableResponse resp;
    return stub_->ResetTable(Ctx().get(), req, &resp);
  }
  grpc::Status Delete(const std::string& id, const std::string& token) {
    v1::DeleteTableRequest req;
    req.set_table_id(id);
    req.set_token(token);
    v1::DeleteTableResponse resp;
    return stub_->DeleteTable(Ctx().get(), req, &resp);
  }
  v1::MatchRecord Record(const std::string& id) {
    v1::GetMatchRecordRequest req;
    req.set_table_id(id);
    v1::MatchRecord rec;
    const grpc::Status s = stub_->GetMatchRecord(Ctx().get(), req, &rec);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return rec;
  }
  absl::StatusOr<TableHandle> Create(const v1::CreateTableRequest& req) {
    v1::CreateTableResponse resp;
    const grpc::Status s = stub_->CreateTable(Ctx().get(), req, &resp);
    if (!s.ok()) return absl::InternalError(s.error_message());
    TableHandle t;
    t.id = resp.table_id();
    t.admin = resp.admin_token();
    for (const v1::Seat& seat : resp.seats()) {
      if (seat.seat() < 2) t.tokens[seat.seat()] = seat.token();
    }
    t.created = resp;
    return t;
  }
  v1::SimulateShotResponse Simulate(const v1::SimulateShotRequest& req) {
    v1::SimulateShotResponse resp;
    const grpc::Status s = stub_->SimulateShot(Ctx().get(), req, &resp);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return resp;
  }
  v1::Billiards::Stub* stub() { return stub_; }

 private:
  v1::Billiards::Stub* stub_;
};

v1::CreateTableRequest GameRequest(const std::string& game, uint32_t race_to,
                                   const std::string& start, const std::vector<Placed>& balls,
                                   const std::map<std::string, std::string>& rules = {},
                                   double noise = 0.0, double shot_clock_s = 0.0) {
  v1::CreateTableRequest req;
  req.mutable_game()->set_name(game);
  req.mutable_game()->set_race_to(race_to);
  req.mutable_game()->set_start(start);
  req.mutable_game()->set_noise(noise);
  req.mutable_game()->set_shot_clock_s(shot_clock_s);
  for (const auto& [k, v] : rules) (*req.mutable_game()->mutable_rules())[k] = v;
  for (const Placed& p : balls) {
    v1::BallPlacement* b = req.mutable_table()->add_balls();
    b->set_id(p.id);
    b->set_x_m(p.x);
    b->set_y_m(p.y);
  }
  return req;
}

// ---------------------------------------------------------------------------------------------
// What a simulated shot did, read from its events.

struct Outcome {
  std::vector<std::string> first;  // the struck ball's first contact(s)
  double first_t = -1;
  std::map<std::string, std::string> pocketed;  // id -> pocket ("off_table")
  bool cushion_after_first = false;
  std::set<std::string> railed;  // balls (other than the struck one) that reached a cushion
  bool point = false;            // three-cushion: a point for the struck ball
  std::string first_object;      // three-cushion: the first ball the struck ball touched
  bool Pocketed(const std::string& id) const { return pocketed.count(id) > 0; }
  bool OffTable() const {
    for (const auto& [id, p] : pocketed) {
      if (p == "off_table") return true;
    }
    return false;
  }
};

Outcome Analyze(const v1::SimulateShotResponse& r, const std::string& cue) {
  Outcome o;
  int cue_cushions = 0;
  std::vector<std::string> touched;
  for (const v1::TableEvent& e : r.events()) {
    if (e.kind() == v1::ball_ball && e.balls_size() == 2) {
      const bool has_cue = e.balls(0) == cue || e.balls(1) == cue;
      if (!has_cue) continue;
      const std::string other = e.balls(0) == cue ? e.balls(1) : e.balls(0);
      if (o.first_t < 0) {
        o.first_t = e.t_s();
        o.first.push_back(other);
      } else if (std::abs(e.t_s() - o.first_t) < 1e-9 &&
                 std::find(o.first.begin(), o.first.end(), other) == o.first.end()) {
        o.first.push_back(other);
      }
      if (std::find(touched.begin(), touched.end(), other) == touched.end()) {
        if (touched.size() == 1) o.point = cue_cushions >= 3;
        touched.push_back(other);
      }
    } else if (e.kind() == v1::ball_cushion && e.balls_size() >= 1) {
      if (o.first_t >= 0 && e.t_s() >= o.first_t) o.cushion_after_first = true;
      if (e.balls(0) == cue) {
        if (touched.size() < 2) ++cue_cushions;
      } else {
        o.railed.insert(e.balls(0));
      }
    } else if (e.kind() == v1::ball_pocket && e.balls_size() >= 1) {
      o.pocketed[e.balls(0)] = e.has_pocket() ? e.pocket() : "";
    }
  }
  if (!touched.empty()) o.first_object = touched.front();
  return o;
}

// ---------------------------------------------------------------------------------------------
// The bot: ghost-ball aiming, every candidate checked with SimulateShot before it is played.

struct Plan {
  std::optional<V2> place;  // ball in hand: where the cue ball goes first
  v1::CueStrike strike;
  v1::ShotCall call;
  int quality = 0;  // 2: pots (or scores), 1: a legal safety, 0: whatever
  std::string what;
};

class Bot {
 public:
  Bot(Api* api, TableHandle table) : api_(api), t_(std::move(table)) {
    const v1::TableInfo info = api_->Get(t_.id, /*geometry=*/true);
    geo_ = info.geometry();
    preset_ = info.preset();
    game_ = info.game().name();
    R_ = geo_.ball_radius_m();
  }

  // Plays the match to its end: answers decisions, places the cue ball, shoots and waits for
  // each shot to end. Returns the table at the end.
  v1::TableInfo PlayMatch(int max_actions, double max_wall_s, int* shots_out = nullptr) {
    const auto t0 = Clock::now();
    int shots = 0;
    for (int i = 0; i < max_actions; ++i) {
      v1::TableInfo info = api_->Get(t_.id);
      if (!info.game().result().empty()) {
        if (shots_out) *shots_out = shots;
        return info;
      }
      if (Seconds(t0) > max_wall_s) {
        ADD_FAILURE() << game_ << ": the match did not end within " << max_wall_s << " s ("
                      << shots << " shots); game: " << info.game().ShortDebugString();
        return info;
      }
      if (!Step(info)) {
        if (shots_out) *shots_out = shots;
        return api_->Get(t_.id);
      }
      shots += info.game().has_decision() ? 0 : 1;
    }
    v1::TableInfo info = api_->Get(t_.id);
    if (info.game().result().empty()) {
      ADD_FAILURE() << game_ << ": the match did not end within " << max_actions
                    << " actions; game: " << info.game().ShortDebugString();
    }
    if (shots_out) *shots_out = shots;
    return info;
  }

  // One action: a decision, or a (placement and) shot played to rest.
  bool Step(const v1::TableInfo& info) {
    const v1::GameState& g = info.game();
    if (g.has_decision() && g.decision().choices_size() > 0) {
      const std::string choice = Choose(g.decision());
      const grpc::Status s = api_->Decide(t_.id, t_.tokens[g.decision().seat()], choice);
      EXPECT_TRUE(s.ok()) << "decide " << choice << ": " << s.error_message();
      return s.ok();
    }
    const Plan plan = MakePlan(info);
    const std::string& token = t_.tokens[g.to_play()];
    if (plan.place.has_value()) {
      const grpc::Status s = api_->Place(t_.id, token, "cue", plan.place->x, plan.place->y);
      EXPECT_TRUE(s.ok()) << "place: " << s.error_message() << " game "
                          << g.ShortDebugString();
      if (!s.ok()) return false;
    }
    v1::ShootResponse resp;
    const grpc::Status s = api_->Shoot(t_.id, token, plan.strike, &plan.call, &resp);
    EXPECT_TRUE(s.ok()) << "shoot (" << plan.what << "): " << s.error_message() << "; game "
                        << g.ShortDebugString() << "\nthe shot before: "
                        << last_plan_.strike.ShortDebugString() << " "
                        << last_plan_.place.has_value() << " from balls "
                        << last_info_.ShortDebugString();
    if (!s.ok()) return false;
    last_plan_ = plan;
    last_info_ = info;
    api_->WaitShot(t_.id, resp.shot_id());
    return true;
  }

  Plan MakePlan(const v1::TableInfo& info) {
    const v1::GameState& g = info.game();
    const int seat = static_cast<int>(g.to_play());
    cue_ = game_ == "three-cushion" && seat == 1 ? "yellow" : "cue";
    balls_.clear();
    for (const v1::BallState& b : info.balls()) {
      if (b.state() != v1::pocketed) balls_.push_back({b.id(), b.x_m(), b.y_m()});
    }
    on_.assign(g.on().begin(), g.on().end());
    g_ = g;
    if (game_ == "three-cushion") return CaromPlan();
    if (g.is_break() && game_ != "snooker") return BreakPlan();
    const bool cue_on = Find(cue_) != nullptr;
    const bool in_hand = g.ball_in_hand() != "none";
    // 1. A pot from where the cue ball lies.
    if (cue_on) {
      if (std::optional<Plan> p = PotFrom(std::nullopt, 40)) return *p;
    }
    // 2. A pot after placing the cue ball straight behind a ball on.
    if (in_hand) {
      int tried = 0;
      for (const std::string& target : on_) {
        const Placed* b = Find(target);
        if (b == nullptr) continue;
        for (const v1::PocketCircle& pocket : geo_.pockets()) {
          const V2 T{b->x, b->y};
          const V2 dir = (V2{pocket.x_m(), pocket.y_m()} - T).unit();
          for (double back : {0.15, 0.3, 0.5}) {
            const V2 c = T - dir * (2 * R_ + back);
            if (!Placeable(c)) continue;
            if (++tried > 30) break;
            if (std::optional<Plan> p = PotFrom(c, 3, target, pocket.name())) return *p;
          }
        }
      }
    }
    // 3. A legal safety from where the cue ball lies (or from a free place in the zone).
    std::optional<V2> place;
    if (!cue_on) {
      place = AnyPlace();
    }
    if (std::optional<Plan> p = Safety(place)) return *p;
    Plan any;
    any.place = place;
    any.strike.set_ball_speed_mps(2.0);
    any.strike.set_phi_deg(0);
    any.strike.set_ball(cue_);
    if (g.call_required()) any.call.set_safety(true);
    if (g.phase() == "colour" && !on_.empty()) any.call.set_nominate(on_.front());
    any.what = "anything";
    return any;
  }

  const Plan& last_plan() const { return last_plan_; }

 private:
  static std::string Choose(const v1::PendingDecision& d) {
    for (const char* pref : {"spot_eight", "accept_table", "shoot", "play", "rebreak", "re_rack"}) {
      for (const std::string& c : d.choices()) {
        if (c == pref) return c;
      }
    }
    return d.choices(0);
  }

  const Placed* Find(const std::string& id) const {
    for (const Placed& b : balls_) {
      if (b.id == id) return &b;
    }
    return nullptr;
  }

  bool OnCloth(V2 p) const {
    const double mx = 0.5 * geo_.length_m() - geo_.cushion_contact_m() - 2e-3;
    const double my = 0.5 * geo_.width_m() - geo_.cushion_contact_m() - 2e-3;
    if (std::abs(p.x) > mx || std::abs(p.y) > my) return false;
    for (const v1::PocketCircle& pk : geo_.pockets()) {
      if ((p - V2{pk.x_m(), pk.y_m()}).norm() < pk.radius_m() + 3e-3) return false;
    }
    return true;
  }
  bool InZone(V2 p) const {
    const std::string& zone = g_.ball_in_hand();
    if (!OnCloth(p)) return false;
    if (zone == "kitchen") return p.x <= -0.25 * geo_.length_m() - 1e-3;
    if (zone == "d") {
      const double baulk = -0.5 * geo_.length_m() + 0.737;
      return p.x <= baulk - 1e-3 && (p - V2{baulk, 0}).norm() <= 0.292 - 2e-3;
    }
    return true;
  }
  bool Placeable(V2 p) const {
    if (!InZone(p)) return false;
    for (const Placed& b : balls_) {
      if (b.id == cue_) continue;
      if ((V2{b.x, b.y} - p).norm() < 2 * R_ + 2e-3) return false;
    }
    return true;
  }
  std::optional<V2> AnyPlace() const {
    const double hx = 0.5 * geo_.length_m(), hy = 0.5 * geo_.width_m();
    for (int i = 0; i <= 40; ++i) {
      for (int j = 0; j <= 20; ++j) {
        const V2 p{-hx + (2 * hx) * i / 40.0, -hy + (2 * hy) * j / 20.0};
        if (Placeable(p)) return p;
      }
    }
    ADD_FAILURE() << "no free place for the cue ball in zone " << g_.ball_in_hand();
    return std::nullopt;
  }

  v1::SimulateShotRequest SimRequest(std::optional<V2> cue_at, const v1::CueStrike& s) const {
    v1::SimulateShotRequest req;
    req.mutable_table()->set_preset(preset_);
    req.mutable_table()->set_rack("empty");
    bool cue_added = false;
    for (const Placed& b : balls_) {
      v1::BallPlacement* p = req.mutable_table()->add_balls();
      p->set_id(b.id);
      if (b.id == cue_ && cue_at.has_value()) {
        p->set_x_m(cue_at->x);
        p->set_y_m(cue_at->y);
        cue_added = true;
      } else {
        p->set_x_m(b.x);
        p->set_y_m(b.y);
        cue_added |= b.id == cue_;
      }
    }
    if (!cue_added && cue_at.has_value()) {
      v1::BallPlacement* p = req.mutable_table()->add_balls();
      p->set_id(cue_);
      p->set_x_m(cue_at->x);
      p->set_y_m(cue_at->y);
    }
    *req.mutable_strike() = s;
    return req;
  }
  Outcome Try(std::optional<V2> cue_at, const v1::CueStrike& s) {
    ++sims_;
    v1::SimulateShotResponse resp;
    const grpc::Status st = api_->stub()->SimulateShot(Ctx().get(), SimRequest(cue_at, s), &resp);
    if (!st.ok()) {
      if (sim_errors_++ == 0) ADD_FAILURE() << "SimulateShot refused the table's balls: " << st.error_message();
      return Outcome{};
    }
    return Analyze(resp, cue_);
  }

  bool IsOn(const std::string& id) const {
    return std::find(on_.begin(), on_.end(), id) != on_.end();
  }
  bool Snooker() const { return game_ == "snooker"; }

  // The pocketed balls a legal stroke may pot; the first ball it must hit.
  bool LegalFirst(const Outcome& o, const std::string& target) const {
    if (o.first.empty()) return false;
    if (Snooker() && g_.phase() != "reds") return o.first.size() == 1 && o.first[0] == target;
    for (const std::string& f : o.first) {
      if (!IsOn(f)) return false;
    }
    return true;
  }
  bool LegalPots(const Outcome& o, const std::string& target) const {
    if (o.Pocketed(cue_) || o.OffTable()) return false;
    for (const auto& [id, pocket] : o.pocketed) {
      if (Snooker()) {
        if (g_.phase() == "reds" ? id.rfind("red", 0) != 0 : id != target) return false;
      } else if (game_ == "8ball" && id == "8" && target != "8") {
        return false;
      } else if (game_ == "10ball" && id == "10" && target != "10") {
        return false;
      }
    }
    return true;
  }
  bool Legal(const Outcome& o, const std::string& target) const {
    if (!LegalFirst(o, target) || !LegalPots(o, target)) return false;
    if (Snooker()) return true;
    return !o.pocketed.empty() || o.cushion_after_first;
  }

  // Pots a ball on from `cue_at` (or from where the cue ball lies): ghost-ball aiming over
  // every ball on and pocket (or only `target`/`pocket_name`), easiest cuts first.
  std::optional<Plan> PotFrom(std::optional<V2> cue_at, int max_candidates,
                              const std::string& only_target = "",
                              const std::string& only_pocket = "") {
    V2 C;
    if (cue_at.has_value()) {
      C = *cue_at;
    } else {
      const Placed* c = Find(cue_);
      if (c == nullptr) return std::nullopt;
      C = {c->x, c->y};
    }
    struct Cand {
      double score;
      double phi_deg;
      std::string target, pocket;
      double dist;
    };
    std::vector<Cand> cands;
    for (const std::string& target : on_) {
      if (!only_target.empty() && target != only_target) continue;
      const Placed* b = Find(target);
      if (b == nullptr) continue;
      const V2 T{b->x, b->y};
      for (const v1::PocketCircle& pocket : geo_.pockets()) {
        if (!only_pocket.empty() && pocket.name() != only_pocket) continue;
        const V2 P{pocket.x_m(), pocket.y_m()};
        const V2 dir = (P - T).unit();
        const V2 G = T - dir * (2 * R_);
        const V2 v = G - C;
        if (v.norm() < 1e-6) continue;
        const double cut = std::acos(std::clamp(v.unit().dot(dir), -1.0, 1.0));
        if (cut > 70.0 * kPi / 180.0) continue;
        const double dist = v.norm() + (P - T).norm();
        cands.push_back({cut + 0.15 * dist, std::atan2(v.y, v.x) * 180.0 / kPi, target,
                         pocket.name(), dist});
      }
    }
    std::sort(cands.begin(), cands.end(),
              [](const Cand& a, const Cand& b) { return a.score < b.score; });
    int tried = 0;
    for (const Cand& c : cands) {
      if (tried++ >= max_candidates) break;
      const double base = std::clamp(1.0 + 0.9 * c.dist, 1.2, 4.0);
      for (double speed : {base, base * 1.5, base * 0.7}) {
        for (double dphi : {0.0, 0.3, -0.3}) {
          v1::CueStrike s;
          s.set_ball(cue_);
          s.set_ball_speed_mps(std::min(speed, 6.0));
          s.set_phi_deg(c.phi_deg + dphi);
          const Outcome o = Try(cue_at, s);
          if (!o.Pocketed(c.target) || o.pocketed.at(c.target) == "off_table") continue;
          if (!Legal(o, c.target)) continue;
          if (game_ == "10ball" && c.target == "10" && o.pocketed.size() > 1) continue;
          Plan p;
          p.place = cue_at;
          p.strike = s;
          p.quality = 2;
          p.what = "pot " + c.target + " in " + o.pocketed.at(c.target);
          if (g_.call_required()) {
            p.call.set_ball(c.target);
            p.call.set_pocket(o.pocketed.at(c.target));  // where it goes (noise 0: exactly)
          }
          if (Snooker() && g_.phase() == "colour") p.call.set_nominate(c.target);
          return p;
        }
      }
    }
    return std::nullopt;
  }

  // A legal stroke that pots nothing of the shooter's: full and thin hits on each ball on.
  std::optional<Plan> Safety(std::optional<V2> cue_at) {
    V2 C;
    if (cue_at.has_value()) {
      C = *cue_at;
    } else {
      const Placed* c = Find(cue_);
      if (c == nullptr) return std::nullopt;
      C = {c->x, c->y};
    }
    std::vector<std::pair<double, std::string>> targets;
    for (const std::string& target : on_) {
      if (const Placed* b = Find(target)) targets.push_back({(V2{b->x, b->y} - C).norm(), target});
    }
    std::sort(targets.begin(), targets.end());
    int tried = 0;
    for (const auto& [d, target] : targets) {
      if (tried++ >= 6) break;
      const Placed* b = Find(target);
      const V2 v = V2{b->x, b->y} - C;
      const double phi0 = std::atan2(v.y, v.x) * 180.0 / kPi;
      const double half = std::asin(std::min(1.0, 2 * R_ / v.norm())) * 180.0 / kPi;
      for (double frac : {0.0, 0.5, -0.5, 0.85, -0.85}) {
        for (double speed : {1.5, 2.5, 4.0}) {
          v1::CueStrike s;
          s.set_ball(cue_);
          s.set_ball_speed_mps(speed);
          s.set_phi_deg(phi0 + frac * half);
          const Outcome o = Try(cue_at, s);
          if (!Legal(o, target)) continue;
          Plan p;
          p.place = cue_at;
          p.strike = s;
          p.quality = 1;
          p.what = "safety on " + target;
          if (g_.call_required()) p.call.set_safety(true);
          if (Snooker() && g_.phase() == "colour") p.call.set_nominate(target);
          return p;
        }
      }
    }
    return std::nullopt;
  }

  // A pool break from where the cue ball lies: at the front ball of the rack, a few headings
  // and speeds, the best legal one (9-ball: the 9 down wins the rack).
  Plan BreakPlan() {
    const Placed* c = Find(cue_);
    Plan best;
    best.strike.set_ball(cue_);
    best.strike.set_ball_speed_mps(7.0);
    best.strike.set_phi_deg(0.0);
    best.what = "break (unchecked)";
    if (c == nullptr) return best;
    const Placed* apex = nullptr;
    for (const Placed& b : balls_) {
      if (b.id != cue_ && (apex == nullptr || b.x < apex->x)) apex = &b;
    }
    if (apex == nullptr) return best;
    const double phi0 = std::atan2(apex->y - c->y, apex->x - c->x) * 180.0 / kPi;
    double best_score = -1;
    for (double speed : {7.0, 9.0}) {
      for (double dphi : {0.0, 0.15, -0.15, 0.4, -0.4, 0.8, -0.8}) {
        v1::CueStrike s;
        s.set_ball(cue_);
        s.set_ball_speed_mps(speed);
        s.set_phi_deg(phi0 + dphi);
        s.set_b(-0.2);
        const Outcome o = Try(std::nullopt, s);
        if (o.first.empty() || o.Pocketed(cue_) || o.OffTable()) continue;
        if (game_ != "8ball" && std::find(o.first.begin(), o.first.end(), "1") == o.first.end()) {
          continue;
        }
        if (o.pocketed.empty() && o.railed.size() < 4) continue;
        if (game_ == "8ball" && o.Pocketed("8")) continue;
        double score = 10.0 * static_cast<double>(o.pocketed.size());
        if (game_ == "9ball" && o.Pocketed("9")) score += 100;
        if (game_ == "10ball" && o.Pocketed("10")) score -= 5;
        if (score > best_score) {
          best_score = score;
          best.strike = s;
          best.quality = 2;
          best.what = "break";
        }
      }
    }
    return best;
  }

  // Three-cushion: search headings, speeds and side spin for a point.
  Plan CaromPlan() {
    Plan fallback;
    fallback.strike.set_ball(cue_);
    fallback.strike.set_ball_speed_mps(3.0);
    fallback.strike.set_phi_deg(0.0);
    fallback.what = "carom (no point found)";
    bool have_fallback = false;
    const bool red_first = on_.size() == 1 && on_[0] == "red";
    for (double a : {0.0, 0.4, -0.4}) {
      for (double speed : {3.5, 5.0, 2.5}) {
        for (int k = 0; k < 180; ++k) {
          v1::CueStrike s;
          s.set_ball(cue_);
          s.set_ball_speed_mps(speed);
          s.set_phi_deg(k * 2.0 + (a != 0 ? 1.0 : 0.0));
          s.set_a(a);
          s.set_b(0.2);
          const Outcome o = Try(std::nullopt, s);
          if (o.OffTable()) continue;
          const bool first_ok = !red_first || o.first_object == "red";
          if (first_ok && o.point) {
            Plan p;
            p.strike = s;
            p.quality = 2;
            p.what = "point";
            return p;
          }
          if (first_ok && !have_fallback && !o.first.empty()) {
            fallback.strike = s;
            fallback.quality = 1;
            have_fallback = true;
          }
        }
      }
    }
    return fallback;
  }

  Api* api_;
  TableHandle t_;
  v1::TableGeometry geo_;
  std::string preset_, game_;
  double R_ = 0;
  // The position being planned.
  std::string cue_;
  std::vector<Placed> balls_;
  std::vector<std::string> on_;
  v1::GameState g_;
  Plan last_plan_;
  v1::TableInfo last_info_;
  int64_t sims_ = 0;
  int sim_errors_ = 0;
};

// ---------------------------------------------------------------------------------------------

class GamesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ServerConfig config;
    config.listen = "127.0.0.1:0";
    config.tables.world.clock_rate = kClockRate;
    absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start(config);
    ASSERT_TRUE(app.ok()) << app.status();
    app_ = *std::move(app);
    channel_ = grpc::CreateChannel(app_->address(), grpc::InsecureChannelCredentials());
    stub_ = v1::Billiards::NewStub(channel_);
    api_ = std::make_unique<Api>(stub_.get());
  }

  TableHandle MustCreate(const v1::CreateTableRequest& req) {
    absl::StatusOr<TableHandle> t = api_->Create(req);
    EXPECT_TRUE(t.ok()) << t.status() << " for " << req.ShortDebugString();
    return t.ok() ? *t : TableHandle{};
  }

  // The match ended "won" by the rules: a winner with 2 frames, every frame ended on the table
  // (never by concession), and the frame_end / match_end events on the stream agree.
  void ExpectWonByRules(const v1::TableInfo& info, Watch& watch, const std::string& table_id,
                        const std::string& frame1_reason, int frame1_winner) {
    const v1::GameState& g = info.game();
    ASSERT_EQ(g.result(), "won") << g.ShortDebugString();
    ASSERT_TRUE(g.has_winner()) << g.ShortDebugString();
    const uint32_t w = g.winner();
    ASSERT_LT(w, 2u);
    ASSERT_EQ(g.frames_won_size(), 2);
    EXPECT_EQ(g.frames_won(static_cast<int>(w)), 2u) << g.ShortDebugString();
    EXPECT_LT(g.frames_won(static_cast<int>(1 - w)), 2u) << g.ShortDebugString();
    const uint32_t frames = g.frames_won(0) + g.frames_won(1);
    EXPECT_GE(frames, 2u);
    EXPECT_EQ(g.frame(), frames) << "the frame counter stays on the last frame played";
    ASSERT_TRUE(watch.WaitFor(v1::match_end)) << "no match_end event on the stream";
    const std::vector<v1::TableEvent> frame_ends = watch.Events(v1::frame_end);
    const std::vector<v1::TableEvent> match_ends = watch.Events(v1::match_end);
    EXPECT_EQ(watch.resyncs(), 0) << "the stream lost events";
    ASSERT_EQ(frame_ends.size(), frames);
    std::array<uint32_t, 2> counted{};
    for (const v1::TableEvent& e : frame_ends) {
      ASSERT_TRUE(e.has_winner()) << e.ShortDebugString();
      ++counted[e.winner()];
      EXPECT_NE(e.reason(), "conceded") << e.ShortDebugString();
      EXPECT_NE(e.reason(), "three_fouls") << e.ShortDebugString();
    }
    EXPECT_EQ(counted[0], g.frames_won(0));
    EXPECT_EQ(counted[1], g.frames_won(1));
    EXPECT_EQ(frame_ends.front().reason(), frame1_reason) << frame_ends.front().ShortDebugString();
    if (frame1_winner >= 0) {
      EXPECT_EQ(frame_ends.front().winner(), static_cast<uint32_t>(frame1_winner))
          << "seat 0 plays frame 1's only shot";
    }
    ASSERT_EQ(match_ends.size(), 1u);
    EXPECT_TRUE(match_ends[0].has_winner());
    EXPECT_EQ(match_ends[0].winner(), w);
    EXPECT_EQ(match_ends[0].reason(), "won");
    EXPECT_EQ(frame_ends.back().winner(), w);
    // The match_end comes after the last frame_end.
    const std::vector<v1::TableEvent> all = watch.Events();
    int last_frame_end = -1, match_end = -1;
    for (int i = 0; i < static_cast<int>(all.size()); ++i) {
      if (all[i].kind() == v1::frame_end) last_frame_end = i;
      if (all[i].kind() == v1::match_end) match_end = i;
    }
    EXPECT_GT(match_end, last_frame_end);
    // The record: no concession, at least one shot after frame 1 (the break of frame 2).
    const v1::MatchRecord rec = api_->Record(table_id);
    int shots = 0;
    for (const v1::MatchAction& a : rec.actions()) {
      EXPECT_NE(a.kind(), v1::MatchAction::CONCEDE);
      EXPECT_NE(a.kind(), v1::MatchAction::RESET);
      shots += a.kind() == v1::MatchAction::SHOOT;
    }
    EXPECT_GE(shots, 2);
    EXPECT_TRUE(rec.ended());
  }

  // Replays the record of an ended match on a new table created from record.create and checks
  // the verdicts, the final game state and every ball, bit for bit.
  void ReplayAndCompare(const TableHandle& orig) {
    const v1::MatchRecord rec = api_->Record(orig.id);
    ASSERT_TRUE(rec.ended());
    ASSERT_TRUE(rec.create().game().has_seed()) << "an ended match reveals its seed";
    for (const v1::MatchAction& a : rec.actions()) {
      if (a.kind() == v1::MatchAction::SHOOT) {
        EXPECT_TRUE(a.has_seed()) << "shot " << a.shot_id() << ": seed not revealed";
        EXPECT_TRUE(a.has_applied()) << "shot " << a.shot_id() << ": applied strike not revealed";
      }
    }
    TableHandle r = MustCreate(rec.create());
    ASSERT_FALSE(r.id.empty());
    for (const v1::MatchAction& a : rec.actions()) {
      const std::string& token = t_token(r, a.seat());
      switch (a.kind()) {
        case v1::MatchAction::SHOOT: {
          v1::ShootResponse resp;
          const grpc::Status s = api_->Shoot(r.id, token, a.strike(), &a.call(), &resp);
          ASSERT_TRUE(s.ok()) << "replay shot " << a.shot_id() << ": " << s.error_message();
          EXPECT_EQ(resp.shot_id(), a.shot_id());
          const v1::TableInfo info = api_->WaitShot(r.id, resp.shot_id());
          EXPECT_TRUE(MessageDifferencer::Equals(info.last_shot().verdict(), a.verdict()))
              << "shot " << a.shot_id() << ": replayed verdict "
              << info.last_shot().verdict().ShortDebugString() << " vs recorded "
              << a.verdict().ShortDebugString();
          break;
        }
        case v1::MatchAction::PLACE: {
          const grpc::Status s =
              api_->Place(r.id, token, a.place().id(), a.place().x_m(), a.place().y_m());
          ASSERT_TRUE(s.ok()) << "replay place: " << s.error_message();
          break;
        }
        case v1::MatchAction::DECIDE: {
          const grpc::Status s = api_->Decide(r.id, token, a.choice());
          ASSERT_TRUE(s.ok()) << "replay decide: " << s.error_message();
          break;
        }
        case v1::MatchAction::CONCEDE: {
          const grpc::Status s = api_->Concede(r.id, token);
          ASSERT_TRUE(s.ok()) << "replay concede: " << s.error_message();
          break;
        }
        default:
          FAIL() << "action kind " << a.kind() << " cannot be replayed by a request";
      }
    }
    const v1::TableInfo a = api_->Get(orig.id);
    const v1::TableInfo b = api_->Get(r.id);
    EXPECT_TRUE(MessageDifferencer::Equals(a.game(), b.game()))
        << "original " << a.game().ShortDebugString() << "\nreplay   "
        << b.game().ShortDebugString();
    ASSERT_EQ(a.balls_size(), b.balls_size());
    for (int i = 0; i < a.balls_size(); ++i) {
      EXPECT_EQ(a.balls(i).SerializeAsString(), b.balls(i).SerializeAsString())
          << "ball " << i << "\noriginal " << a.balls(i).ShortDebugString() << "\nreplay   "
          << b.balls(i).ShortDebugString();
    }
    EXPECT_EQ(a.shots(), b.shots());
    // The replay's own record: the same seeds and applied strikes.
    const v1::MatchRecord rec2 = api_->Record(r.id);
    ASSERT_EQ(rec2.actions_size(), rec.actions_size());
    for (int i = 0; i < rec.actions_size(); ++i) {
      EXPECT_EQ(rec2.actions(i).seed(), rec.actions(i).seed()) << "action " << i;
      EXPECT_TRUE(MessageDifferencer::Equals(rec2.actions(i).applied(), rec.actions(i).applied()))
          << "action " << i;
      EXPECT_TRUE(MessageDifferencer::Equals(rec2.actions(i).verdict(), rec.actions(i).verdict()))
          << "action " << i;
    }
  }
  static const std::string& t_token(const TableHandle& t, uint32_t seat) {
    return t.tokens[std::min<uint32_t>(seat, 1)];
  }

  void PlayWholeMatch(const std::string& game, const std::vector<Placed>& in_play,
                      const std::map<std::string, std::string>& rules,
                      const std::string& frame1_reason, int max_actions = 400,
                      int frame1_winner = 0,
                      const std::function<void(Watch&)>& extra = nullptr) {
    const auto t0 = Clock::now();
    TableHandle t = MustCreate(GameRequest(game, 2, "in-play", in_play, rules));
    ASSERT_FALSE(t.id.empty());
    Watch watch(stub_.get(), t.id);
    Bot bot(api_.get(), t);
    int shots = 0;
    const v1::TableInfo info = bot.PlayMatch(max_actions, 120, &shots);
    const double play_s = Seconds(t0);
    ExpectWonByRules(info, watch, t.id, frame1_reason, frame1_winner);
    if (extra) extra(watch);
    const auto t1 = Clock::now();
    ReplayAndCompare(t);
    std::printf("[ games ] %s: %d shots, frames %u-%u, winner %u, played in %.1f s, replayed in "
                "%.1f s\n",
                game.c_str(), shots, info.game().frames_won(0), info.game().frames_won(1),
                info.game().winner(), play_s, Seconds(t1));
  }

  std::unique_ptr<ServerApp> app_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Billiards::Stub> stub_;
  std::unique_ptr<Api> api_;
};

// ---------------------------------------------------------------------------------------------
// 1 (and 2). Whole matches, race to 2, replayed bit for bit.

TEST_F(GamesTest, NineBallMatchPlayedToTheEnd) {
  // Frame 1: only the 9 left; frame 2 from the rack, broken by seat 1.
  PlayWholeMatch("9ball", {{"cue", 0.3, 0.0}, {"9", 0.8, 0.25}}, {}, "nine_pocketed");
}

TEST_F(GamesTest, TenBallMatchPlayedToTheEnd) {
  PlayWholeMatch("10ball", {{"cue", 0.3, 0.0}, {"10", 0.8, 0.25}}, {}, "ten_pocketed");
}

TEST_F(GamesTest, EightBallMatchPlayedToTheEnd) {
  // An open table: the 1 (solids) and the 9 (stripes) left with the 8. The first called ball
  // legally pocketed sets the groups; then the 8, called, wins.
  PlayWholeMatch("8ball",
                 {{"cue", 0.0, 0.0}, {"1", 0.8, 0.3}, {"9", -0.3, 0.35}, {"8", 0.7, -0.35}}, {},
                 "eight_pocketed", 400, /*frame1_winner=*/-1, [](Watch& watch) {
                   // The calls resolved the open table in frame 1: groups were set.
                   bool open = false, groups = false;
                   for (const v1::TableSnapshot& s : watch.Snapshots()) {
                     if (!s.has_game() || s.game().frame() != 1) continue;
                     open |= s.game().groups_size() == 0 && s.game().result().empty();
                     groups |= s.game().groups_size() == 2 &&
                               s.game().groups().at("0") != s.game().groups().at("1");
                   }
                   EXPECT_TRUE(open) << "frame 1 starts with an open table";
                   EXPECT_TRUE(groups) << "no call set the groups in frame 1";
                 });
}

// Frame 2 is a whole frame from the break (it once stuck at shot 12 on a ball resting in a
// pocket's mouth: see ABallRestingInAPocketMouthLeavesTheTablePlayable).
TEST_F(GamesTest, SnookerMatchPlayedToTheEnd) {
  // Only the black left: potting it wins frame 1 on points (7-0).
  PlayWholeMatch("snooker", {{"cue", 0.5, 0.2}, {"black", 1.2, 0.5}}, {}, "points", 1500);
}

TEST_F(GamesTest, ThreeCushionMatchPlayedToTheEnd) {
  PlayWholeMatch("three-cushion", {{"cue", -0.5, -0.2}, {"yellow", 0.3, 0.3}, {"red", 0.6, -0.2}},
                 {{"target", "1"}}, "target", 200);
}

// The engine can leave a ball at rest in a pocket's mouth, between the jaws and outside the
// capture circle, beyond the cushion-nose box. Found by SnookerMatchPlayedToTheEnd (frame 2,
// shot 12): the layout check once refused such a table, so every later shot was refused and
// the match was stuck. The ball stays where it rests, and the next seat plays. (Since the
// snooker preset took a measured table's cloth and cushion, the shot that leaves the black in
// the corner's mouth is 2.1324 m/s, not 2.1574: found by scanning speeds around it.)
TEST_F(GamesTest, ABallRestingInAPocketMouthLeavesTheTablePlayable) {
  const std::vector<Placed> balls = {
      {"cue", 1.1008095983422446, -0.071330023524710864},
      {"red1", 0.22848157857416118, -0.75600294048520145},
      {"red2", 0.98508934464750819, -0.038619682606189032},
      {"red4", 0.38981006898453385, -0.64071308615103018},
      {"red5", 1.0353069355948554, 0.004610402707325767},
      {"red7", 0.54572057306419586, -0.83201895589836927},
      {"red8", 1.0857751070484785, -0.014605517431487003},
      {"red10", 1.0790561485872345, 0.34473999873161554},
      {"red12", 1.0954616086704738, -0.4707192826471901},
      {"red13", 1.1796645479474936, 0.2329757537227487},
      {"red14", 1.4251450098742116, 0.15232158736494816},
      {"red15", 0.917649080217004, 0.78386596026815},
      {"yellow", -1.0474999999999999, -0.292},
      {"green", -1.0474999999999999, 0.292},
      {"brown", -1.0474999999999999, 0},
      {"blue", 0, 0},
      {"pink", 0.34313583679837067, -0.10256899929870721},
      {"black", 1.4605, 0}};
  TableHandle t = MustCreate(GameRequest("snooker", 1, "in-play", balls));
  ASSERT_FALSE(t.id.empty());
  v1::CueStrike strike;
  strike.set_ball_speed_mps(2.132371434327395);
  strike.set_phi_deg(3.679609631955445);
  v1::ShootResponse resp;
  ASSERT_TRUE(api_->Shoot(t.id, t.tokens[0], strike, nullptr, &resp).ok());
  v1::TableInfo info = api_->WaitShot(t.id, resp.shot_id());
  const v1::TableGeometry geo = api_->Get(t.id, true).geometry();
  const double lim_y = 0.5 * geo.width_m() - geo.cushion_contact_m();
  bool in_mouth = false;
  for (const v1::BallState& b : info.balls()) {
    if (b.state() != v1::pocketed && std::abs(b.y_m()) > lim_y + 1e-9) in_mouth = true;
  }
  ASSERT_TRUE(in_mouth) << "the shot no longer leaves a ball in the pocket's mouth; "
                        << "this test needs a new position";
  // Whoever plays next must be able to shoot (or the rules must deal with the ball).
  for (int i = 0; i < 3 && info.game().has_decision(); ++i) {
    ASSERT_TRUE(api_->Decide(t.id, t.tokens[info.game().decision().seat()], "play").ok());
    info = api_->Get(t.id);
  }
  ASSERT_TRUE(info.game().result().empty());
  v1::ShotCall call;
  if (info.game().phase() == "colour") call.set_nominate(info.game().on(0));
  v1::CueStrike next;
  next.set_ball_speed_mps(1.0);
  next.set_phi_deg(180);
  const grpc::Status st = api_->Shoot(t.id, t.tokens[info.game().to_play()], next, &call, &resp);
  EXPECT_TRUE(st.ok()) << "the table refuses every shot: " << st.error_message();
}

// 2. A noisy table: the seed stays secret until the match ends, then the match replays.
TEST_F(GamesTest, NoisyMatchRecordHidesSeedsUntilTheEndAndReplaysBitForBit) {
  TableHandle t = MustCreate(GameRequest("8ball", 2, "break", {}, {}, /*noise=*/0.5));
  ASSERT_FALSE(t.id.empty());
  // Seat 0 "breaks" away from the rack: an illegal break, seat 1 decides.
  v1::CueStrike soft;
  soft.set_ball_speed_mps(0.4);
  soft.set_phi_deg(90);
  v1::ShootResponse resp;
  ASSERT_TRUE(api_->Shoot(t.id, t.tokens[0], soft, nullptr, &resp).ok());
  v1::TableInfo info = api_->WaitShot(t.id, resp.shot_id());
  ASSERT_EQ(info.last_shot().verdict().reason(), "illegal_break")
      << info.last_shot().ShortDebugString();
  ASSERT_TRUE(info.game().has_decision());
  EXPECT_EQ(info.game().decision().seat(), 1u);

  // Before the end: nothing reveals the seeds.
  v1::MatchRecord rec = api_->Record(t.id);
  EXPECT_FALSE(rec.ended());
  EXPECT_FALSE(rec.create().game().has_seed()) << "the table's seed leaked before the end";
  ASSERT_GE(rec.actions_size(), 1);
  for (const v1::MatchAction& a : rec.actions()) {
    EXPECT_FALSE(a.has_seed()) << "shot " << a.shot_id() << "'s seed leaked before the end";
    EXPECT_FALSE(a.has_applied()) << "shot " << a.shot_id() << "'s noisy strike leaked";
  }
  EXPECT_EQ(rec.actions(0).kind(), v1::MatchAction::SHOOT);
  EXPECT_EQ(rec.actions(0).verdict().reason(), "illegal_break");

  // Seat 1 re-racks and breaks; a few shots; then the seat to play concedes frame 1; frame 2
  // is played to the end (and a third if needed).
  ASSERT_TRUE(api_->Decide(t.id, t.tokens[1], "re_rack").ok());
  Bot bot(api_.get(), t);
  for (int i = 0; i < 2; ++i) {
    info = api_->Get(t.id);
    if (info.game().frame() != 1) break;
    ASSERT_TRUE(bot.Step(info));
  }
  for (int i = 0; i < 10; ++i) {
    info = api_->Get(t.id);
    if (!info.game().has_decision()) break;
    ASSERT_TRUE(bot.Step(info));
  }
  info = api_->Get(t.id);
  ASSERT_EQ(info.game().frame(), 1u) << "frame 1 ended before the concession";
  ASSERT_FALSE(info.game().has_decision());
  ASSERT_TRUE(api_->Concede(t.id, t.tokens[info.game().to_play()]).ok());
  rec = api_->Record(t.id);
  EXPECT_FALSE(rec.create().game().has_seed());
  info = bot.PlayMatch(400, 120);
  ASSERT_FALSE(info.game().result().empty()) << info.game().ShortDebugString();
  rec = api_->Record(t.id);
  ASSERT_TRUE(rec.ended());
  ASSERT_TRUE(rec.create().game().has_seed());
  std::set<v1::MatchAction::Kind> kinds;
  for (const v1::MatchAction& a : rec.actions()) kinds.insert(a.kind());
  EXPECT_TRUE(kinds.count(v1::MatchAction::SHOOT));
  EXPECT_TRUE(kinds.count(v1::MatchAction::DECIDE));
  EXPECT_TRUE(kinds.count(v1::MatchAction::CONCEDE));
  ReplayAndCompare(t);

  // The seed matters: the first three actions (the illegal break, re_rack, the re-break) on a
  // table with the same seed and on one with another seed.
  const auto first_three = [&](uint64_t seed) {
    v1::CreateTableRequest req = rec.create();
    req.mutable_game()->set_seed(seed);
    TableHandle o = MustCreate(req);
    for (int i = 0; i < 3; ++i) {
      const v1::MatchAction& a = rec.actions(i);
      if (a.kind() == v1::MatchAction::SHOOT) {
        v1::ShootResponse r;
        EXPECT_TRUE(api_->Shoot(o.id, o.tokens[a.seat()], a.strike(), &a.call(), &r).ok());
        api_->WaitShot(o.id, r.shot_id());
      } else if (a.kind() == v1::MatchAction::DECIDE) {
        EXPECT_TRUE(api_->Decide(o.id, o.tokens[a.seat()], a.choice()).ok());
      }
    }
    std::string balls;
    const v1::TableInfo end = api_->Get(o.id);
    for (const v1::BallState& b : end.balls()) balls += b.SerializeAsString();
    return balls;
  };
  ASSERT_EQ(rec.actions(2).kind(), v1::MatchAction::SHOOT);
  const uint64_t seed = rec.create().game().seed();
  EXPECT_EQ(first_three(seed), first_three(seed));
  EXPECT_NE(first_three(seed), first_three(seed ^ 0x5555)) << "the noise seed changed nothing";
}

// ---------------------------------------------------------------------------------------------
// 3. The cheating list.

class CheatTest : public GamesTest {
 protected:
  // Runs `call`, expects `code` and a message containing `rule`, and that the table (and its
  // match record) did not change.
  void ExpectRefused(const std::string& id, const std::string& what,
                     const std::function<grpc::Status()>& call, grpc::StatusCode code,
                     const std::string& rule) {
    const v1::TableInfo before = api_->Still(id);
    const int actions = api_->Record(id).actions_size();
    const grpc::Status s = call();
    EXPECT_EQ(s.error_code(), code) << what << ": got " << s.error_code() << " "
                                    << s.error_message();
    EXPECT_THAT(s.error_message(), HasSubstr(rule)) << what;
    const v1::TableInfo after = api_->Still(id);
    EXPECT_TRUE(MessageDifferencer::Equals(before, after))
        << what << " changed the table:\nbefore " << before.ShortDebugString() << "\nafter  "
        << after.ShortDebugString();
    EXPECT_EQ(api_->Record(id).actions_size(), actions) << what << " was recorded";
  }
  static v1::CueStrike Strike(double speed, double phi) {
    v1::CueStrike s;
    s.set_ball_speed_mps(speed);
    s.set_phi_deg(phi);
    return s;
  }
};

TEST_F(CheatTest, EightBallBreakAndDecisionRefusals) {
  TableHandle t = MustCreate(GameRequest("8ball", 1, "break", {}));
  ASSERT_FALSE(t.id.empty());
  const std::string& id = t.id;
  const std::string& s0 = t.tokens[0];
  const std::string& s1 = t.tokens[1];
  using C = grpc::StatusCode;
  v1::TableInfo info = api_->Get(id);
  ASSERT_EQ(info.game().ball_in_hand(), "kitchen");
  ASSERT_EQ(info.game().to_play(), 0u);
  const v1::CueStrike ok = Strike(0.4, 90);

  ExpectRefused(id, "seat 0 passes the turn", [&] { return api_->SetTurn(id, s0, 1); },
                C::FAILED_PRECONDITION, "nobody sets the turn");
  ExpectRefused(id, "seat 1 takes the turn", [&] { return api_->SetTurn(id, s1, 1); },
                C::FAILED_PRECONDITION, "nobody sets the turn");
  ExpectRefused(id, "the admin sets the turn", [&] { return api_->SetTurn(id, t.admin, 1); },
                C::FAILED_PRECONDITION, "nobody sets the turn");
  ExpectRefused(id, "shoot with next_seat",
                [&] { return api_->Shoot(id, s0, ok, nullptr, nullptr, 0u); },
                C::FAILED_PRECONDITION, "next_seat");
  ExpectRefused(id, "place the 8 in the kitchen",
                [&] { return api_->Place(id, s0, "8", -0.9, 0.2); }, C::INVALID_ARGUMENT,
                "only the cue ball");
  ExpectRefused(id, "add a ball 99", [&] { return api_->Place(id, s0, "99", -0.9, 0.2); },
                C::INVALID_ARGUMENT, "only the cue ball");
  ExpectRefused(id, "place the cue ball past the head string",
                [&] { return api_->Place(id, s0, "cue", 0.5, 0.1); }, C::INVALID_ARGUMENT,
                "head string");
  ExpectRefused(id, "the seat not to play places the cue ball",
                [&] { return api_->Place(id, s1, "cue", -0.9, 0.2); }, C::FAILED_PRECONDITION,
                "not your turn");
  v1::CueStrike eight = ok;
  eight.set_ball("8");
  ExpectRefused(id, "strike the 8", [&] { return api_->Shoot(id, s0, eight); },
                C::FAILED_PRECONDITION, "own cue ball");
  v1::CueStrike noisy = ok;
  noisy.set_noise(0.001);
  ExpectRefused(id, "a shooter's own noise", [&] { return api_->Shoot(id, s0, noisy); },
                C::FAILED_PRECONDITION, "table's noise applies");
  v1::CueStrike seeded = ok;
  seeded.set_seed(42);
  ExpectRefused(id, "a shooter's own seed", [&] { return api_->Shoot(id, s0, seeded); },
                C::FAILED_PRECONDITION, "table's noise applies");
  ExpectRefused(id, "seat 1 resets", [&] { return api_->Reset(id, s1); }, C::PERMISSION_DENIED,
                "only the admin token resets");
  ExpectRefused(id, "seat 0 resets", [&] { return api_->Reset(id, s0); }, C::PERMISSION_DENIED,
                "only the admin token resets");
  ExpectRefused(id, "seat 1 deletes", [&] { return api_->Delete(id, s1); }, C::PERMISSION_DENIED,
                "only the admin token deletes");
  ExpectRefused(id, "seat 0 deletes", [&] { return api_->Delete(id, s0); }, C::PERMISSION_DENIED,
                "only the admin token deletes");
  ExpectRefused(id, "seat 1 shoots out of turn", [&] { return api_->Shoot(id, s1, ok); },
                C::FAILED_PRECONDITION, "not your turn");
  ExpectRefused(id, "the admin shoots", [&] { return api_->Shoot(id, t.admin, ok); },
                C::PERMISSION_DENIED, "admin token does not play");
  ExpectRefused(id, "the admin places", [&] { return api_->Place(id, t.admin, "cue", -0.9, 0.2); },
                C::PERMISSION_DENIED, "admin token does not play");
  ExpectRefused(id, "decide with nothing pending",
                [&] { return api_->Decide(id, s1, "accept_table"); }, C::FAILED_PRECONDITION,
                "no decision is pending");
  ExpectRefused(id, "a wrong token", [&] { return api_->Shoot(id, "not-a-token", ok); },
                C::PERMISSION_DENIED, "token");

  // A break that touches nothing: illegal, seat 1 chooses.
  v1::ShootResponse resp;
  ASSERT_TRUE(api_->Shoot(id, s0, ok, nullptr, &resp).ok());
  info = api_->WaitShot(id, resp.shot_id());
  ASSERT_EQ(info.last_shot().verdict().reason(), "illegal_break");
  ASSERT_TRUE(info.game().has_decision());
  ASSERT_EQ(info.game().decision().seat(), 1u);
  ExpectRefused(id, "seat 1 shoots while its decision is pending",
                [&] { return api_->Shoot(id, s1, ok); }, C::FAILED_PRECONDITION,
                "decision is pending");
  ExpectRefused(id, "seat 0 shoots while a decision is pending",
                [&] { return api_->Shoot(id, s0, ok); }, C::FAILED_PRECONDITION,
                "decision is pending");
  ExpectRefused(id, "seat 1 places while its decision is pending",
                [&] { return api_->Place(id, s1, "cue", -0.9, 0.2); }, C::FAILED_PRECONDITION,
                "decision is pending");
  ExpectRefused(id, "seat 0 decides for seat 1",
                [&] { return api_->Decide(id, s0, "accept_table"); }, C::FAILED_PRECONDITION,
                "seat 1's");
  ExpectRefused(id, "a choice not offered", [&] { return api_->Decide(id, s1, "shoot"); },
                C::INVALID_ARGUMENT, "choice must be one of accept_table, re_rack");
  ExpectRefused(id, "the admin decides", [&] { return api_->Decide(id, t.admin, "re_rack"); },
                C::PERMISSION_DENIED, "decision is the seat's");
  ExpectRefused(id, "seat 1 resets instead of deciding", [&] { return api_->Reset(id, s1); },
                C::PERMISSION_DENIED, "only the admin token resets");

  ASSERT_TRUE(api_->Decide(id, s1, "accept_table").ok());
  info = api_->Get(id);
  ASSERT_EQ(info.game().to_play(), 1u);
  ASSERT_EQ(info.game().ball_in_hand(), "none");
  ASSERT_TRUE(info.game().call_required());
  ExpectRefused(id, "a shot without the required call",
                [&] { return api_->Shoot(id, s1, Strike(1.0, 0)); }, C::FAILED_PRECONDITION,
                "must be called");
  ExpectRefused(id, "placing without ball in hand",
                [&] { return api_->Place(id, s1, "cue", -0.9, 0.2); }, C::FAILED_PRECONDITION,
                "no ball in hand");
  ExpectRefused(id, "seat 0 shoots out of turn",
                [&] {
                  v1::ShotCall call;
                  call.set_safety(true);
                  return api_->Shoot(id, s0, Strike(1.0, 0), &call);
                },
                C::FAILED_PRECONDITION, "not your turn");
  ExpectRefused(id, "seat 0 (not to play) deletes mid-match", [&] { return api_->Delete(id, s0); },
                C::PERMISSION_DENIED, "only the admin token deletes");

  // The admin's rights: reset, then delete.
  ASSERT_TRUE(api_->Reset(id, t.admin).ok());
  info = api_->Get(id);
  EXPECT_EQ(info.game().to_play(), 0u);
  EXPECT_TRUE(info.game().is_break());
  EXPECT_FALSE(info.game().has_decision());
  ASSERT_TRUE(api_->Delete(id, t.admin).ok());
  v1::GetTableRequest gone;
  gone.set_table_id(id);
  v1::TableInfo none;
  EXPECT_EQ(stub_->GetTable(Ctx().get(), gone, &none).error_code(), C::NOT_FOUND);
}

TEST_F(CheatTest, SnookerNominationIsRequiredAfterARed) {
  // A red straight in front of the top right corner pocket, with the colours on their spots.
  const double L = 3.569, half_w = 0.889;
  (void)half_w;
  std::vector<Placed> balls = {{"cue", 0.9, 0.2},         {"red1", 1.3, 0.5},
                               {"yellow", -1.047, -0.292}, {"green", -1.047, 0.292},
                               {"brown", -1.047, 0.0},     {"blue", 0.0, 0.0},
                               {"pink", 0.25 * L, 0.0},    {"black", 0.5 * L - 0.324, 0.0}};
  TableHandle t = MustCreate(GameRequest("snooker", 1, "in-play", balls));
  ASSERT_FALSE(t.id.empty());
  v1::TableInfo info = api_->Get(t.id);
  ASSERT_EQ(info.game().phase(), "reds") << info.game().ShortDebugString();
  ExpectRefused(t.id, "a nomination while a red is on",
                [&] {
                  v1::ShotCall call;
                  call.set_nominate("black");
                  return api_->Shoot(t.id, t.tokens[0], Strike(1.0, 0), &call);
                },
                grpc::StatusCode::FAILED_PRECONDITION, "no nomination is due");
  Bot bot(api_.get(), t);
  const Plan plan = bot.MakePlan(info);
  ASSERT_EQ(plan.quality, 2) << "no pot found for the red: " << plan.what;
  ASSERT_THAT(plan.what, HasSubstr("red1"));
  ASSERT_TRUE(bot.Step(info));
  info = api_->Get(t.id);
  ASSERT_EQ(info.last_shot().verdict().points(), 1) << info.last_shot().ShortDebugString();
  ASSERT_EQ(info.game().phase(), "colour");
  ASSERT_EQ(info.game().to_play(), 0u);
  ExpectRefused(t.id, "a shot after a red without a nomination",
                [&] { return api_->Shoot(t.id, t.tokens[0], Strike(1.0, 180)); },
                grpc::StatusCode::FAILED_PRECONDITION, "must nominate a colour");
  ExpectRefused(t.id, "a nomination of a ball not on",
                [&] {
                  v1::ShotCall call;
                  call.set_nominate("red1");
                  return api_->Shoot(t.id, t.tokens[0], Strike(1.0, 180), &call);
                },
                grpc::StatusCode::INVALID_ARGUMENT, "not on the table");
  ExpectRefused(t.id, "seat 1 plays the colour",
                [&] {
                  v1::ShotCall call;
                  call.set_nominate("blue");
                  return api_->Shoot(t.id, t.tokens[1], Strike(1.0, 180), &call);
                },
                grpc::StatusCode::FAILED_PRECONDITION, "not your turn");
}

TEST_F(CheatTest, NoMoveAfterTheMatchEnds) {
  TableHandle t = MustCreate(GameRequest("9ball", 1, "in-play", {{"cue", 0.3, 0.0}, {"9", 0.8, 0.25}}));
  ASSERT_FALSE(t.id.empty());
  Bot bot(api_.get(), t);
  const v1::TableInfo info = bot.PlayMatch(50, 30);
  ASSERT_EQ(info.game().result(), "won");
  const uint32_t next = info.game().to_play();
  ExpectRefused(t.id, "a shot after the match",
                [&] { return api_->Shoot(t.id, t.tokens[next], Strike(1.0, 0)); },
                grpc::StatusCode::FAILED_PRECONDITION, "the match is over");
  ExpectRefused(t.id, "a concession after the match",
                [&] { return api_->Concede(t.id, t.tokens[0]); },
                grpc::StatusCode::FAILED_PRECONDITION, "the match is over");
}

// ---------------------------------------------------------------------------------------------
// 4. The shot clock.

TEST_F(GamesTest, ShotClockPenaltyAtTheDeadlineTick) {
  constexpr double kClockS = 2.0;
  TableHandle t = MustCreate(GameRequest("9ball", 1, "in-play",
                                         {{"cue", 0.3, 0.0}, {"1", 0.6, 0.2}, {"9", 0.8, 0.25}}, {},
                                         0.0, kClockS));
  ASSERT_FALSE(t.id.empty());
  ASSERT_TRUE(t.created.game().has_shot_clock_deadline_s());
  EXPECT_DOUBLE_EQ(t.created.game().shot_clock_deadline_s(), kClockS);
  Watch watch(stub_.get(), t.id);
  // Nobody shoots: seat 0 fouls at 2 s, seat 1 at 4 s, seat 0 at 6 s (warned), seat 1 at 8 s
  // (warned), seat 0's third foul at 10 s loses the rack (race to 1: the match).
  ASSERT_TRUE(watch.WaitFor(v1::match_end, 1, 20)) << "the clock never ended the match";
  const std::vector<v1::TableEvent> fouls = watch.Events(v1::foul);
  ASSERT_EQ(fouls.size(), 5u);
  for (size_t i = 0; i < fouls.size(); ++i) {
    EXPECT_EQ(fouls[i].seat(), i % 2) << fouls[i].ShortDebugString();
    EXPECT_DOUBLE_EQ(fouls[i].t_s(), kClockS * static_cast<double>(i + 1))
        << "the penalty happens at the deadline tick: " << fouls[i].ShortDebugString();
    EXPECT_EQ(fouls[i].reason(), i == 4 ? "three_fouls" : "shot_clock");
  }
  const std::vector<v1::TableEvent> warnings = watch.Events(v1::warning);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[0].seat(), 0u);
  EXPECT_DOUBLE_EQ(warnings[0].t_s(), 3 * kClockS);
  EXPECT_EQ(warnings[1].seat(), 1u);
  const std::vector<v1::TableEvent> ends = watch.Events(v1::match_end);
  ASSERT_EQ(ends.size(), 1u);
  EXPECT_EQ(ends[0].winner(), 1u);
  EXPECT_EQ(ends[0].reason(), "three_fouls");
  const std::vector<v1::TableEvent> turns = watch.Events(v1::turn);
  ASSERT_GE(turns.size(), 4u);
  EXPECT_EQ(turns[0].seat(), 1u);
  EXPECT_DOUBLE_EQ(turns[0].t_s(), kClockS);

  // The state right after the first penalty: ball in hand anywhere for seat 1, a new deadline.
  bool checked = false;
  for (const v1::TableSnapshot& s : watch.Snapshots()) {
    int n_fouls = 0;
    for (const v1::TableEvent& e : s.events()) n_fouls += e.kind() == v1::foul;
    if (n_fouls == 1 && s.events(0).t_s() <= kClockS + 1e-9 && s.has_game() &&
        s.game().shot() == 0 && s.game().fouls_in_row(0) == 1 && s.game().fouls_in_row(1) == 0) {
      EXPECT_EQ(s.game().to_play(), 1u);
      EXPECT_EQ(s.game().ball_in_hand(), "anywhere");
      ASSERT_TRUE(s.game().has_shot_clock_deadline_s());
      EXPECT_DOUBLE_EQ(s.game().shot_clock_deadline_s(), 2 * kClockS);
      EXPECT_DOUBLE_EQ(s.t_s(), kClockS);
      checked = true;
    }
  }
  EXPECT_TRUE(checked) << "no snapshot carried the state after the first penalty alone";

  const v1::TableInfo info = api_->Get(t.id);
  EXPECT_EQ(info.game().result(), "three_fouls");
  EXPECT_EQ(info.game().winner(), 1u);
  EXPECT_FALSE(info.game().has_shot_clock_deadline_s()) << "no clock after the match";
  const v1::MatchRecord rec = api_->Record(t.id);
  ASSERT_EQ(rec.actions_size(), 5);
  for (int i = 0; i < 5; ++i) {
    EXPECT_EQ(rec.actions(i).kind(), v1::MatchAction::SHOT_CLOCK);
    EXPECT_EQ(rec.actions(i).seat(), static_cast<uint32_t>(i % 2));
    EXPECT_EQ(rec.actions(i).tick(), static_cast<int64_t>(240 * (i + 1)))
        << "2 s at 120 Hz per penalty";
    EXPECT_TRUE(rec.actions(i).verdict().foul());
  }
}

TEST_F(GamesTest, ShotClockBallInHandWhenPolled) {
  // A longer clock (10 s of table time, 0.2 s of wall time at the test's rate) to read the
  // state between two penalties with GetTable.
  constexpr double kClockS = 10.0;
  TableHandle t = MustCreate(GameRequest("9ball", 1, "in-play",
                                         {{"cue", 0.3, 0.0}, {"1", 0.6, 0.2}, {"9", 0.8, 0.25}}, {},
                                         0.0, kClockS));
  ASSERT_FALSE(t.id.empty());
  const auto t0 = Clock::now();
  v1::TableInfo info;
  do {
    info = api_->Get(t.id);
    if (info.game().fouls_in_row(0) == 1) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  } while (Seconds(t0) < 10);
  ASSERT_EQ(info.game().fouls_in_row(0), 1u) << info.game().ShortDebugString();
  if (info.game().fouls_in_row(1) == 0) {
    EXPECT_EQ(info.game().to_play(), 1u);
    EXPECT_EQ(info.game().ball_in_hand(), "anywhere");
    EXPECT_DOUBLE_EQ(info.game().shot_clock_deadline_s(), 2 * kClockS);
    EXPECT_GE(info.t_s(), kClockS);
    EXPECT_LT(info.t_s(), 2 * kClockS);
    // Seat 1 uses its ball in hand in time: the clock restarts at the shot's end.
    ASSERT_TRUE(api_->Place(t.id, t.tokens[1], "cue", 0.0, -0.3).ok());
    v1::ShotCall none;
    v1::CueStrike s;
    s.set_ball_speed_mps(1.5);
    s.set_phi_deg(std::atan2(0.2 + 0.3, 0.6) * 180.0 / kPi);
    v1::ShootResponse resp;
    const grpc::Status st = api_->Shoot(t.id, t.tokens[1], s, &none, &resp);
    ASSERT_TRUE(st.ok()) << st.error_message();
    info = api_->WaitShot(t.id, resp.shot_id());
    EXPECT_FALSE(info.last_shot().verdict().reason() == "shot_clock");
    if (info.game().result().empty()) {
      ASSERT_TRUE(info.game().has_shot_clock_deadline_s());
      EXPECT_NEAR(info.game().shot_clock_deadline_s(),
                  static_cast<double>(info.last_shot().end_tick()) / 120.0 + kClockS, 1e-9)
          << "the clock restarts when the balls come to rest";
    }
  } else {
    GTEST_SKIP() << "the poller was too slow to see the state between two penalties";
  }
}

// ---------------------------------------------------------------------------------------------
// 5. Free play keeps today's rights.

TEST_F(GamesTest, FreePlayKeepsEverySeatsRightsAndTheAdminHasThemToo) {
  v1::CreateTableRequest req;
  req.mutable_table()->set_rack("9ball");
  TableHandle t = MustCreate(req);
  ASSERT_FALSE(t.id.empty());
  EXPECT_FALSE(t.admin.empty());
  EXPECT_FALSE(t.created.has_game());
  const std::string& id = t.id;
  // The admin passes the turn, places any ball, resets.
  ASSERT_TRUE(api_->SetTurn(id, t.admin, 1).ok());
  EXPECT_EQ(api_->Get(id).turn(), 1u);
  ASSERT_TRUE(api_->Place(id, t.admin, "9", 0.0, 0.3).ok());
  ASSERT_TRUE(api_->Place(id, t.admin, "99", 0.0, -0.3).ok());
  ASSERT_TRUE(api_->Reset(id, t.admin).ok());
  // Seat 1 (to play) passes back; seat 0 places any ball anywhere, shoots passing the turn.
  ASSERT_TRUE(api_->SetTurn(id, t.tokens[1], 0).ok());
  ASSERT_TRUE(api_->Place(id, t.tokens[0], "8", 0.5, 0.4).ok());
  ASSERT_TRUE(api_->Place(id, t.tokens[0], "cue", 0.6, -0.4).ok());
  v1::CueStrike s;
  s.set_ball("8");  // any ball may be struck in free play
  s.set_ball_speed_mps(1.0);
  s.set_phi_deg(180);
  s.set_noise(0.5);  // and a shooter's own noise and seed are fine
  s.set_seed(7);
  v1::ShootResponse resp;
  grpc::Status st = api_->Shoot(id, t.tokens[0], s, nullptr, &resp, 1u);
  ASSERT_TRUE(st.ok()) << st.error_message();
  v1::TableInfo info = api_->WaitShot(id, resp.shot_id());
  EXPECT_EQ(info.turn(), 1u);
  // The admin shoots for the seat to play.
  s.set_ball("cue");
  s.clear_noise();
  s.clear_seed();
  st = api_->Shoot(id, t.admin, s, nullptr, &resp);
  ASSERT_TRUE(st.ok()) << st.error_message();
  info = api_->WaitShot(id, resp.shot_id());
  EXPECT_EQ(info.last_shot().seat(), 1u);
  // Any seat resets, not only the one to play.
  ASSERT_TRUE(api_->Reset(id, t.tokens[0]).ok());
  ASSERT_TRUE(api_->Reset(id, t.tokens[1]).ok());
  // No referee: no record, no decisions, no concession, no calls.
  v1::GetMatchRecordRequest rr;
  rr.set_table_id(id);
  v1::MatchRecord rec;
  EXPECT_EQ(stub_->GetMatchRecord(Ctx().get(), rr, &rec).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_EQ(api_->Decide(id, t.tokens[1], "shoot").error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_EQ(api_->Concede(id, t.tokens[1]).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  // A seat deletes; and the admin deletes another table.
  ASSERT_TRUE(api_->Delete(id, t.tokens[1]).ok());
  TableHandle u = MustCreate(req);
  ASSERT_TRUE(api_->Delete(u.id, u.admin).ok());
}

// A concession names its frame: three simultaneous concessions of frame 1 concede it once, and
// a concession of a frame not being played is refused and changes nothing.
TEST_F(GamesTest, AFrameIsConcededOnce) {
  TableHandle t = MustCreate(GameRequest("9ball", 3, "in-play", {{"cue", 0.3, 0.0}, {"9", 0.8, 0.25}}));
  v1::TableInfo before = api_->Get(t.id);
  ASSERT_EQ(before.game().frame(), 1u);
  const uint32_t seat = before.game().to_play();
  const grpc::Status future = api_->Concede(t.id, t.tokens[seat], std::nullopt, 2u);
  EXPECT_EQ(future.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(future.error_message(), HasSubstr("frame"));
  const v1::TableInfo unchanged = api_->Get(t.id);
  EXPECT_TRUE(MessageDifferencer::Equals(before.game(), unchanged.game()))
      << unchanged.game().ShortDebugString();
  std::vector<grpc::Status> results(3);
  std::vector<std::thread> threads;
  for (int i = 0; i < 3; ++i) {
    threads.emplace_back([&, i] { results[i] = api_->Concede(t.id, t.tokens[seat], std::nullopt, 1u); });
  }
  for (std::thread& th : threads) th.join();
  int ok = 0;
  for (const grpc::Status& r : results) {
    if (r.ok()) {
      ++ok;
    } else {
      EXPECT_EQ(r.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << r.error_message();
    }
  }
  EXPECT_EQ(ok, 1);
  const v1::TableInfo after = api_->Get(t.id);
  EXPECT_EQ(after.game().frame(), 2u) << after.game().ShortDebugString();
  int conceded = 0;
  const v1::MatchRecord record = api_->Record(t.id);  // kept: the loop reads into it
  for (const v1::MatchAction& a : record.actions()) {
    conceded += a.kind() == v1::MatchAction::CONCEDE;
  }
  EXPECT_EQ(conceded, 1);
}

}  // namespace
}  // namespace sportsim::server
