// The table checkpoint (server/billiards/table_checkpoint.h): a table at rest encoded and
// decoded bit for bit.
//
// 1. Real states: matches of every ruled game played on the event engine by a simple seeded
//    bot, with the table's noise on every strike, the way TableRegistry does it (the strike's
//    seed from the table's secret, the referee's facts, the judgement, placements, decisions,
//    shot clocks, a concession), every state round-tripped after every action.
// 2. Adversarial values: -0.0, denormals, NaNs with payloads, infinities, extreme integers,
//    empty, long and binary strings, every enum value, optionals present and absent.
// 3. Damaged bytes: every prefix, every flipped bit, other versions, unknown fields and enum
//    values, arrays of the wrong length, missing members: an error naming what is wrong.
// 4. A fuzz-style loop: random bytes, random bodies with a valid checksum, mutated real
//    checkpoints re-sealed: never a crash, and whatever decodes encodes back to itself.
//
// The field counts of the domain types are checked at compile time: a field added to one of
// them fails this test's build until the checkpoint stores it.
#include "server/billiards/table_checkpoint.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "gmock/gmock.h"
#include "absl/strings/str_format.h"
#include "gtest/gtest.h"
#include "server/billiards/game_convert.h"
#include "server/world/world.h"
#include "sim/billiards/cue.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/model.h"
#include "sim/billiards/referee.h"
#include "sim/billiards/shot.h"
#include "sim/games/game.h"
#include "sportsim/store/v1/table_state.pb.h"
#include "sportsim/v1/billiards.pb.h"
#include "tests/server/checkpoint_testing.h"

namespace sportsim::server {
namespace {

namespace b = ::sportsim::billiards;
namespace g = ::sportsim::games;
namespace st = ::sportsim::store::v1;

using ::testing::HasSubstr;

// ---------------------------------------------------------------------------------------------
// Field counts: a new field in a stored type must be added to table_state.proto,
// table_checkpoint.cc (encode, decode, compare) and the adversarial test below, and the
// version bumped; then update its count here.

static_assert(CountFields<b::Ball>() == 7, "billiards::Ball changed: update the checkpoint");
static_assert(CountFields<b::TableState>() == 2, "TableState changed: update the checkpoint");
static_assert(CountFields<b::CueStrike>() == 8, "CueStrike changed: update the checkpoint");
static_assert(CountFields<b::StrikeOutcome>() == 5, "StrikeOutcome changed: update the checkpoint");
static_assert(CountFields<g::ShotCall>() == 5, "ShotCall changed: update the checkpoint");
static_assert(CountFields<g::Verdict>() == 6, "Verdict changed: update the checkpoint");
static_assert(CountFields<g::Decision>() == 2, "Decision changed: update the checkpoint");
static_assert(CountFields<g::GameState>() == 30, "GameState changed: update the checkpoint");
static_assert(CountFields<ShotSummary>() == 15, "ShotSummary changed: update the checkpoint");
static_assert(CountFields<MatchEntry>() == 13, "MatchEntry changed: update the checkpoint");
static_assert(CountFields<TableRestState>() == 10, "TableRestState changed: update the checkpoint");

// ---------------------------------------------------------------------------------------------
// Helpers.

/// CRC-32C, bit by bit (the library's is table-driven): to seal hand-made bodies.
uint32_t Crc32c(std::string_view bytes) {
  uint32_t c = 0xFFFFFFFFu;
  for (char ch : bytes) {
    c ^= static_cast<uint8_t>(ch);
    for (int k = 0; k < 8; ++k) c = (c & 1) != 0 ? (c >> 1) ^ 0x82F63B78u : c >> 1;
  }
  return c ^ 0xFFFFFFFFu;
}

/// A message body with the checkpoint's trailer (field 15, the CRC-32C of the body).
std::string Seal(std::string body) {
  const uint32_t crc = Crc32c(body);
  body.push_back(static_cast<char>((15 << 3) | 5));
  for (int shift = 0; shift < 32; shift += 8) body.push_back(static_cast<char>(crc >> shift));
  return body;
}

std::string Seal(const st::TableRestState& m) { return Seal(m.SerializeAsString()); }

/// Encodes, decodes and compares bit for bit; the decoded state encodes to the same bytes.
void ExpectRoundTrip(const TableRestState& s, const std::string& what) {
  const std::string bytes = EncodeTableRestState(s);
  absl::StatusOr<TableRestState> back = DecodeTableRestState(bytes);
  ASSERT_TRUE(back.ok()) << what << ": " << back.status();
  EXPECT_TRUE(SameRestState(s, *back)) << what << ": " << RestStateDifference(s, *back);
  EXPECT_EQ(RestStateDifference(s, *back), "") << what;
  EXPECT_EQ(EncodeTableRestState(*back), bytes) << what;
}

// ---------------------------------------------------------------------------------------------
// A table as TableRegistry keeps it, played by a seeded bot on the real engine and referees.

b::TableModel ModelFor(g::GameKind game) {
  absl::StatusOr<b::TableSpec> spec = b::MakeTablePreset(GamePreset(game));
  EXPECT_TRUE(spec.ok()) << spec.status();
  absl::StatusOr<b::TableModel> model = b::TableModel::Create(*spec);
  EXPECT_TRUE(model.ok()) << model.status();
  return *std::move(model);
}

class BotTable {
 public:
  static constexpr int64_t kTickHz = 60;

  BotTable(g::GameKind game, uint64_t seed, int race_to, double shot_clock_s, double noise)
      : model_(ModelFor(game)), rng_(seed), table_seed_(seed), noise_(noise) {
    absl::StatusOr<g::Rules> rules = g::MakeRules(game, race_to, shot_clock_s);
    EXPECT_TRUE(rules.ok()) << rules.status();
    rules_ = *rules;
    referee_ = g::RefereeFor(game);
    absl::StatusOr<g::GameState> started =
        g::StartMatch(rules_, model_, g::Start::kBreak, &t_.rest);
    EXPECT_TRUE(started.ok()) << started.status();
    started->seed = DeriveSeed(table_seed_, 0);
    t_.game = *started;
    t_.turn = static_cast<uint32_t>(t_.game.to_play);
    ArmShotClock(0);
  }

  const TableRestState& state() const { return t_; }
  std::map<std::string, int>& seen() { return seen_; }

  /// One action of the seat to act: a decision, a placement, a shot, or (now and then) a
  /// shot clock running out. False when the match is over.
  bool Step() {
    if (t_.game.match_over()) return false;
    t_.tick += 1 + static_cast<int64_t>(rng_() % 200);
    if (t_.game.decision.pending()) return Decide();
    if (rules_.shot_clock_s > 0 && U01() < 0.05) return ShotClock();
    const int seat = t_.game.to_play;
    const std::string cue_id = StrikerBall(seat);
    const int cue = t_.rest.Find(cue_id);
    const bool in_hand = t_.game.ball_in_hand != g::BallInHand::kNone;
    if (in_hand && !t_.placed &&
        (t_.rest.balls[cue].state == b::MotionState::kPocketed || U01() < 0.5)) {
      return Place(seat, cue_id);
    }
    return Shoot(seat, cue_id);
  }

  /// The seat to play concedes (at rest, the match not over).
  void Concede() {
    const int seat = t_.game.to_play;
    b::TableState balls = t_.rest;
    absl::StatusOr<g::Judgement> j = referee_->Concede(rules_, model_, t_.game, seat, &balls);
    ASSERT_TRUE(j.ok()) << j.status();
    const g::Verdict verdict = j->verdict;
    ApplyCall(*std::move(j), std::move(balls),
              MatchEntry{.kind = MatchEntry::Kind::kConcede, .seat = seat, .verdict = verdict});
    ++seen_["concede"];
  }

 private:
  double U01() { return std::uniform_real_distribution<double>(0, 1)(rng_); }

  std::string StrikerBall(int seat) const {
    return rules_.game == g::GameKind::kThreeCushion && seat == 1 ? "yellow" : "cue";
  }

  void ArmShotClock(int64_t from) {
    t_.clock_deadline.reset();
    if (rules_.shot_clock_s <= 0 || t_.game.match_over() || t_.game.decision.pending()) return;
    t_.clock_deadline =
        from + std::max<int64_t>(1, static_cast<int64_t>(std::ceil(rules_.shot_clock_s * kTickHz)));
  }

  void ApplyJudgement(g::Judgement j) {
    t_.game = std::move(j.state);
    t_.turn = static_cast<uint32_t>(t_.game.to_play);
    ArmShotClock(t_.tick);
  }

  // A decision or a concession (ApplyCallJudgement).
  void ApplyCall(g::Judgement j, b::TableState balls, MatchEntry entry) {
    ++t_.sequence;
    t_.rest = std::move(balls);
    t_.placed = false;
    entry.tick = t_.tick;
    t_.record.push_back(std::move(entry));
    ApplyJudgement(std::move(j));
  }

  bool Decide() {
    const int seat = t_.game.decision.seat;
    const std::vector<std::string> choices = t_.game.decision.choices;
    const std::string choice = choices[rng_() % choices.size()];
    b::TableState balls = t_.rest;
    absl::StatusOr<g::Judgement> j =
        referee_->Decide(rules_, model_, t_.game, seat, choice, &balls);
    EXPECT_TRUE(j.ok()) << j.status();
    if (!j.ok()) return false;
    ApplyCall(*std::move(j), std::move(balls),
              MatchEntry{.kind = MatchEntry::Kind::kDecide, .seat = seat, .choice = choice});
    ++seen_["decide " + choice];
    return true;
  }

  bool ShotClock() {
    const int seat = t_.game.to_play;
    b::TableState balls = t_.rest;
    absl::StatusOr<g::Judgement> j = referee_->ShotClockExpired(rules_, model_, t_.game, &balls);
    if (!j.ok()) return true;  // not now: the next step acts
    ++t_.sequence;
    t_.rest = std::move(balls);
    t_.record.push_back(MatchEntry{.kind = MatchEntry::Kind::kShotClock, .tick = t_.tick,
                                   .seat = seat, .verdict = j->verdict});
    ApplyJudgement(*std::move(j));
    ++seen_["shot_clock"];
    return true;
  }

  bool Place(int seat, const std::string& cue_id) {
    const b::TableSpec& spec = model_.spec();
    for (int attempt = 0; attempt < 20000; ++attempt) {
      const Eigen::Vector2d xy((U01() - 0.5) * spec.length_m, (U01() - 0.5) * spec.width_m);
      if (!referee_->CheckPlacement(rules_, model_, t_.game, seat, t_.rest, cue_id, xy).ok()) {
        continue;
      }
      b::Ball& ball = t_.rest.balls[t_.rest.Find(cue_id)];
      ball.r = Eigen::Vector3d(xy.x(), xy.y(), model_.radius());
      ball.v.setZero();
      ball.w.setZero();
      ball.state = b::MotionState::kStationary;
      ball.pocket = -1;
      ++t_.sequence;
      t_.placed = true;
      t_.record.push_back(MatchEntry{.kind = MatchEntry::Kind::kPlace, .tick = t_.tick,
                                     .seat = seat, .ball = cue_id, .x_m = xy.x(), .y_m = xy.y()});
      ++seen_["place"];
      return true;
    }
    ADD_FAILURE() << "no legal placement found for " << cue_id;
    return false;
  }

  // The calls the bot tries, in order, aiming at `target`: the first the referee accepts.
  std::optional<g::ShotCall> CallFor(int seat, const std::string& target) {
    std::vector<g::ShotCall> calls;
    if (t_.game.push_out_available && U01() < 0.3) calls.push_back({.push_out = true});
    calls.push_back({});
    calls.push_back({.nominate = target});
    for (const b::Pocket& p : model_.spec().pockets) {
      calls.push_back({.ball = target, .pocket = p.name});
      calls.push_back({.ball = target, .pocket = p.name, .nominate = target});
    }
    calls.push_back({.safety = true});
    for (const g::ShotCall& call : calls) {
      if (referee_->CheckShot(rules_, model_, t_.game, seat, call, t_.rest).ok()) return call;
    }
    return std::nullopt;
  }

  bool Shoot(int seat, const std::string& cue_id) {
    const int cue = t_.rest.Find(cue_id);
    std::vector<std::string> targets;
    for (const std::string& id : t_.game.on) {
      const int i = t_.rest.Find(id);
      if (i >= 0 && t_.rest.balls[i].state != b::MotionState::kPocketed) targets.push_back(id);
    }
    if (targets.empty()) {
      for (const b::Ball& ball : t_.rest.balls) {
        if (ball.id != cue_id && ball.state != b::MotionState::kPocketed) {
          targets.push_back(ball.id);
        }
      }
    }
    const std::string target = targets[rng_() % targets.size()];
    const std::optional<g::ShotCall> call = CallFor(seat, target);
    EXPECT_TRUE(call.has_value()) << "no call accepted for " << target;
    if (!call.has_value()) return false;
    const Eigen::Vector2d d =
        t_.rest.balls[t_.rest.Find(target)].r.head<2>() - t_.rest.balls[cue].r.head<2>();
    v1::CueStrike asked;
    asked.set_ball_speed_mps(0.8 + 4.0 * U01());
    asked.set_phi_deg(std::atan2(d.y(), d.x()) * 180.0 / M_PI + 2.0 * (U01() - 0.5));
    asked.set_theta_deg(U01() < 0.3 ? 5.0 * U01() : 0.0);
    asked.set_a(0.3 * (U01() - 0.5));
    asked.set_b(0.6 * (U01() - 0.5));
    const b::CueStrike strike{.speed_mps = asked.ball_speed_mps(),
                              .ball_speed = true,
                              .phi_rad = asked.phi_deg() * M_PI / 180.0,
                              .theta_rad = asked.theta_deg() * M_PI / 180.0,
                              .a = asked.a(),
                              .b = asked.b(),
                              .noise = noise_,
                              .seed = DeriveSeed(table_seed_, t_.shots + 1)};
    b::TableState struck = t_.rest;
    struck.t_s = 0.0;
    const b::SolverOptions solver;
    absl::StatusOr<b::StrikeOutcome> outcome =
        b::ApplyStrike(model_, solver.effects, strike, cue, &struck);
    EXPECT_TRUE(outcome.ok()) << outcome.status();
    if (!outcome.ok()) return false;
    absl::StatusOr<b::ShotResult> shot = b::SimulateShot(model_, solver, struck, {});
    EXPECT_TRUE(shot.ok()) << shot.status();
    if (!shot.ok() || !shot->at_rest) return false;

    const int64_t start = t_.tick + 1;
    ++t_.sequence;
    ++t_.shots;
    ShotSummary s{.shot_id = t_.shots, .seat = static_cast<uint32_t>(seat),
                  .struck_ball = cue_id, .start_tick = start, .call = *call};
    t_.record.push_back(MatchEntry{.kind = MatchEntry::Kind::kShoot, .tick = start, .seat = seat,
                                   .strike = asked.SerializeAsString(), .call = *call,
                                   .shot_id = t_.shots, .seed = strike.seed,
                                   .applied = *outcome});
    t_.clock_deadline.reset();

    b::ShotReferee facts(cue);
    for (const b::Event& e : shot->events) facts.Observe(e);
    b::TableState after = shot->final_state;
    after.t_s = 0.0;
    const b::ShotFacts& f = facts.facts();
    if (f.first_hit >= 0) s.first_ball_hit = after.balls[f.first_hit].id;
    s.rails = static_cast<uint32_t>(f.rails);
    s.rails_after_contact = static_cast<uint32_t>(f.rails_after_contact);
    for (int i : f.pocketed) s.pocketed.push_back(after.balls[i].id);
    s.struck_ball_pocketed = f.struck_pocketed;
    const int64_t ticks = static_cast<int64_t>(std::ceil(shot->t_rest_s * kTickHz));
    s.end_tick = start + ticks;
    s.duration_s = static_cast<double>(ticks) / kTickHz;
    s.events = shot->events_handled;
    const g::ShotRecord record{.struck = cue, .placed = t_.placed, .before = t_.rest,
                               .events = shot->events, .after = after};
    g::Judgement j = referee_->Judge(rules_, model_, t_.game, *call, record, &after);
    s.verdict = j.verdict;
    t_.record.back().verdict = j.verdict;
    t_.placed = false;
    t_.last_shot = s;
    t_.rest = std::move(after);
    t_.tick = s.end_tick;
    ApplyJudgement(std::move(j));
    ++seen_[s.verdict->foul ? "foul " + s.verdict->reason : "shot"];
    if (!s.pocketed.empty()) ++seen_["pocketed"];
    return true;
  }

  b::TableModel model_;
  g::Rules rules_;
  const g::Referee* referee_ = nullptr;
  std::mt19937_64 rng_;
  uint64_t table_seed_;
  double noise_;
  TableRestState t_;
  std::map<std::string, int> seen_;
};

/// Plays up to `actions` actions, round-tripping the table after each; returns the states.
std::vector<TableRestState> Play(BotTable& table, int actions, const std::string& what) {
  std::vector<TableRestState> states{table.state()};
  ExpectRoundTrip(table.state(), what + " at creation");
  for (int i = 0; i < actions; ++i) {
    if (!table.Step()) break;
    states.push_back(table.state());
    ExpectRoundTrip(table.state(), what + " after action " + std::to_string(i + 1));
    if (::testing::Test::HasFatalFailure()) break;
  }
  return states;
}

std::string Seen(const std::map<std::string, int>& seen) {
  std::string out;
  for (const auto& [k, n] : seen) out += k + "=" + std::to_string(n) + " ";
  return out;
}

// ---------------------------------------------------------------------------------------------
// 1. Real states.

struct GameCase {
  g::GameKind game;
  int race_to;
  int actions;
};

class RealGameTest : public ::testing::TestWithParam<GameCase> {};

TEST_P(RealGameTest, EveryStateOfAMatchRoundTripsBitForBit) {
  const GameCase c = GetParam();
  for (uint64_t seed : {1u, 2u, 3u}) {
    BotTable table(c.game, seed, c.race_to, /*shot_clock_s=*/30.0, /*noise=*/1.0);
    const std::string what = std::string(g::GameName(c.game)) + " seed " + std::to_string(seed);
    std::vector<TableRestState> states = Play(table, c.actions, what);
    if (!table.state().game.match_over()) {
      table.Concede();
      states.push_back(table.state());
      ExpectRoundTrip(table.state(), what + " after the concession");
    }
    std::cout << what << ": " << states.size() << " states, " << table.state().record.size()
              << " entries, " << EncodeTableRestState(table.state()).size() << " bytes; "
              << Seen(table.seen()) << "\n";
    // The states differ from one another (the comparison sees real changes).
    for (size_t i = 1; i < states.size(); ++i) {
      EXPECT_FALSE(SameRestState(states[i - 1], states[i])) << what << " state " << i;
    }
    EXPECT_GT(table.state().shots, 0u) << what;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Games, RealGameTest,
    ::testing::Values(GameCase{g::GameKind::kNineBall, 2, 60},
                      GameCase{g::GameKind::kEightBall, 1, 40},
                      GameCase{g::GameKind::kTenBall, 1, 40},
                      GameCase{g::GameKind::kSnooker, 1, 60},
                      GameCase{g::GameKind::kThreeCushion, 1, 30}),
    [](const ::testing::TestParamInfo<GameCase>& p) {
      std::string name(g::GameName(p.param.game));
      std::string out;
      for (char ch : name) {
        if (std::isalnum(static_cast<unsigned char>(ch))) out += ch;
      }
      return "g" + out;
    });

TEST(TableCheckpointTest, RealStatesCoverDecisionsVerdictsAndReplayPositions) {
  // Over many snooker and 9-ball actions, the fields that only some states fill are filled
  // in at least one round-tripped state: a pending decision, fouls, a replay position, a
  // placement, a shot clock, a push-out.
  std::set<std::string> covered;
  for (g::GameKind game : {g::GameKind::kSnooker, g::GameKind::kNineBall}) {
    for (uint64_t seed = 10; seed < 16; ++seed) {
      BotTable table(game, seed, 2, 30.0, 1.0);
      const std::vector<TableRestState> states = Play(table, 80, std::string(g::GameName(game)));
      for (const TableRestState& s : states) {
        if (s.game.decision.pending()) covered.insert("decision");
        if (!s.game.replay_position.balls.empty()) covered.insert("replay_position");
        if (s.last_shot.verdict.has_value() && s.last_shot.verdict->foul) covered.insert("foul");
        if (s.last_shot.verdict.has_value() && !s.last_shot.verdict->respotted.empty()) {
          covered.insert("respotted");
        }
        if (s.placed) covered.insert("placed");
        if (!s.clock_deadline.has_value()) covered.insert("no deadline");
        if (s.clock_deadline.has_value()) covered.insert("deadline");
        if (s.game.pushed_out) covered.insert("pushed_out");
        if (s.game.free_ball) covered.insert("free_ball");
        for (const MatchEntry& e : s.record) {
          covered.insert("entry " + std::to_string(static_cast<int>(e.kind)));
        }
      }
    }
  }
  std::string all;
  for (const std::string& c : covered) all += c + ", ";
  std::cout << "covered: " << all << "\n";
  for (const char* want : {"decision", "replay_position", "foul", "placed", "deadline",
                           "no deadline", "entry 0", "entry 1", "entry 2", "entry 4"}) {
    EXPECT_TRUE(covered.count(want)) << want << " never seen; covered: " << all;
  }
}

/// The bytes each entry of `s.record` adds to the encoding, by kind.
void EntrySizes(const TableRestState& s, std::map<MatchEntry::Kind, std::vector<size_t>>* out) {
  TableRestState one = s;
  one.record.clear();
  const size_t without = EncodeTableRestState(one).size();
  for (const MatchEntry& e : s.record) {
    one.record = {e};
    (*out)[e.kind].push_back(EncodeTableRestState(one).size() - without);
  }
}

TEST(TableCheckpointTest, SizesForTheRecord) {
  // A fresh 9-ball table (no shot clock), a snooker table mid-frame, and the bytes each match
  // entry adds (the encoding with and without it), over a snooker frame and a 9-ball match.
  BotTable nine(g::GameKind::kNineBall, 7, 1, 0.0, 1.0);
  const size_t fresh = EncodeTableRestState(nine.state()).size();
  TableRestState no_balls = nine.state();
  no_balls.rest.balls.clear();
  const size_t per_ball = (fresh - EncodeTableRestState(no_balls).size()) /
                          nine.state().rest.balls.size();
  BotTable snooker(g::GameKind::kSnooker, 7, 1, 0.0, 1.0);
  for (int i = 0; i < 30 && snooker.Step(); ++i) {
  }
  const TableRestState mid = snooker.state();
  TableRestState no_record = mid;
  no_record.record.clear();
  const size_t mid_size = EncodeTableRestState(mid).size();
  const size_t mid_no_record = EncodeTableRestState(no_record).size();
  std::cout << "fresh 9-ball table: " << fresh << " bytes (" << nine.state().rest.balls.size()
            << " balls racked, " << per_ball << " bytes each)\n";
  std::cout << "snooker mid-frame: " << mid_size << " bytes (" << mid.rest.balls.size()
            << " balls, replay position of " << mid.game.replay_position.balls.size()
            << " balls, " << mid.record.size() << " entries, shot " << mid.game.shot
            << "), without the record " << mid_no_record << " bytes\n";

  std::map<MatchEntry::Kind, std::vector<size_t>> per_kind;
  EntrySizes(mid, &per_kind);
  BotTable match(g::GameKind::kNineBall, 1, 2, 30.0, 1.0);
  for (int i = 0; i < 60 && match.Step(); ++i) {
  }
  match.Concede();
  EntrySizes(match.state(), &per_kind);
  for (const auto& [kind, sizes] : per_kind) {
    size_t lo = sizes[0], hi = sizes[0], sum = 0;
    for (size_t n : sizes) {
      lo = std::min(lo, n);
      hi = std::max(hi, n);
      sum += n;
    }
    std::cout << "entry kind " << static_cast<int>(kind) << ": " << sizes.size()
              << " entries, " << lo << ".." << hi << " bytes, mean "
              << static_cast<double>(sum) / static_cast<double>(sizes.size()) << "\n";
  }
  EXPECT_LT(fresh, 2000u);
  EXPECT_GT(mid_size, mid_no_record);
}

// ---------------------------------------------------------------------------------------------
// 2. Adversarial values.

/// Doubles no physics gives but the encoding must keep: signed zeros, denormals, NaNs with
/// payloads (quiet and signalling, both signs), infinities, extremes.
std::vector<double> OddDoubles() {
  return {0.0,
          -0.0,
          std::numeric_limits<double>::denorm_min(),
          -std::numeric_limits<double>::denorm_min(),
          Bits(0x000FFFFFFFFFFFFFull),  // the largest denormal
          std::numeric_limits<double>::min(),
          std::numeric_limits<double>::max(),
          -std::numeric_limits<double>::max(),
          std::numeric_limits<double>::infinity(),
          -std::numeric_limits<double>::infinity(),
          Bits(0x7FF8000000000001ull),  // quiet NaN, payload 1
          Bits(0xFFF8DEADBEEF1234ull),  // negative quiet NaN with a payload
          Bits(0x7FF0000000000001ull),  // signalling NaN
          Bits(0x7FF4000000C0FFEEull),  // signalling NaN with a payload
          std::numeric_limits<double>::epsilon(),
          0.1,
          -1.0 / 3.0};
}

std::string LongString(size_t n) {
  std::string s(n, '\0');
  for (size_t i = 0; i < n; ++i) s[i] = static_cast<char>(i * 7 + 3);
  return s;
}

/// Every field set to something other than its default, from `k` (different k, different
/// values; doubles cycle through OddDoubles).
struct Filler {
  size_t k = 0;
  double D() { return OddDoubles()[k++ % OddDoubles().size()]; }
  Eigen::Vector3d V() {
    const double x = D(), y = D(), z = D();
    return Eigen::Vector3d(x, y, z);
  }
  std::string S() {
    static const std::vector<std::string> strings = {
        "", "cue", std::string("a\0b", 3), "\xff\xfe invalid utf-8 \xc3", LongString(300),
        "9", std::string(1, '\0')};
    return strings[k++ % strings.size()];
  }
  std::vector<std::string> Ss() {
    std::vector<std::string> out;
    const size_t n = k++ % 4;
    for (size_t i = 0; i < n; ++i) out.push_back(S());
    return out;
  }
  int I() {
    static const std::vector<int> ints = {std::numeric_limits<int>::min(), -1, 0, 1, 7,
                                          std::numeric_limits<int>::max()};
    return ints[k++ % ints.size()];
  }
  int64_t I64() {
    static const std::vector<int64_t> ints = {std::numeric_limits<int64_t>::min(), -1, 0,
                                              std::numeric_limits<int64_t>::max(), 1LL << 40};
    return ints[k++ % ints.size()];
  }
  uint64_t U64() {
    static const std::vector<uint64_t> ints = {std::numeric_limits<uint64_t>::max(), 0, 1,
                                               1ULL << 63, 0x0123456789ABCDEFull};
    return ints[k++ % ints.size()];
  }
  uint32_t U32() {
    static const std::vector<uint32_t> ints = {std::numeric_limits<uint32_t>::max(), 0, 1,
                                               0x80000000u, 12345};
    return ints[k++ % ints.size()];
  }
  bool B() { return (k++ % 3) != 0; }

  b::Ball Ball(int state) {
    b::Ball ball;
    ball.id = S();
    ball.r = V();
    ball.v = V();
    ball.w = V();
    const double w = D(), x = D(), y = D(), z = D();
    ball.q = Eigen::Quaterniond(w, x, y, z);
    ball.state = static_cast<b::MotionState>(state);
    ball.pocket = I();
    return ball;
  }
  b::TableState Table(size_t n) {
    b::TableState s;
    for (size_t i = 0; i < n; ++i) s.balls.push_back(Ball(static_cast<int>(i % 6)));
    s.t_s = D();
    return s;
  }
  g::ShotCall Call() { return {.ball = S(), .pocket = S(), .safety = B(), .push_out = B(),
                               .nominate = S()}; }
  g::Verdict Verdict() {
    return {.foul = B(), .reason = S(), .points = I(), .turn_passes = B(), .respotted = Ss(),
            .frame_over = B()};
  }
  b::StrikeOutcome Outcome() {
    b::StrikeOutcome o;
    o.applied = {.speed_mps = D(), .ball_speed = B(), .phi_rad = D(), .theta_rad = D(),
                 .a = D(), .b = D(), .noise = D(), .seed = U64()};
    o.cue_speed_mps = D();
    o.squirt_rad = D();
    o.v = V();
    o.w = V();
    return o;
  }
  g::GameState Game(int e) {
    g::GameState s;
    s.game = static_cast<g::GameKind>(e % 6);
    s.frame = I();
    s.race_to = I();
    s.frames_won = {I(), I()};
    s.to_play = I();
    s.ball_in_hand = static_cast<g::BallInHand>(e % 4);
    s.on = Ss();
    s.groups = {static_cast<g::Group>(e % 3), static_cast<g::Group>((e + 1) % 3)};
    s.scores = {I(), I()};
    s.fouls_in_row = {I(), I()};
    s.warned = {B(), B()};
    s.call_required = B();
    s.push_out_available = B();
    s.decision = {.seat = e % 2 == 0 ? -1 : I(), .choices = Ss()};
    s.winner = I();
    s.result = static_cast<g::MatchResult>(e % 6);
    s.breaker = I();
    s.is_break = B();
    s.shot = I();
    s.innings = {I(), I()};
    s.last_shooter = I();
    s.pushed_out = B();
    s.phase = S();
    s.nominated = S();
    s.free_ball = B();
    s.misses_in_row = I();
    s.replay_position = Table(static_cast<size_t>(e % 3));
    s.opening = B();
    s.replay_phase = S();
    s.seed = U64();
    return s;
  }
  ShotSummary Summary(bool verdict) {
    ShotSummary s{.shot_id = U64(), .seat = U32(), .struck_ball = S(), .first_ball_hit = S(),
                  .rails = U32(), .rails_after_contact = U32(), .pocketed = Ss(),
                  .struck_ball_pocketed = B(), .start_tick = I64(), .end_tick = I64(),
                  .duration_s = D(), .events = I64(), .error = S(), .call = Call()};
    if (verdict) s.verdict = Verdict();
    return s;
  }
  MatchEntry Entry(int kind, bool verdict) {
    MatchEntry e{.kind = static_cast<MatchEntry::Kind>(kind), .tick = I64(), .seat = I(),
                 .strike = S(), .call = Call(), .shot_id = U64(), .seed = U64(),
                 .applied = Outcome(), .ball = S(), .x_m = D(), .y_m = D(), .choice = S()};
    if (verdict) e.verdict = Verdict();
    return e;
  }
  TableRestState State(int e) {
    TableRestState s;
    s.tick = I64();
    s.sequence = U64();
    s.turn = U32();
    s.rest = Table(static_cast<size_t>(3 + e % 4));
    s.last_shot = Summary(e % 2 == 0);
    s.shots = U64();
    s.game = Game(e);
    s.placed = B();
    if (e % 3 != 0) s.clock_deadline = I64();
    for (int i = 0; i < 6 + e % 3; ++i) s.record.push_back(Entry(i % 6, (i + e) % 2 == 0));
    return s;
  }
};

TEST(TableCheckpointTest, AdversarialValuesRoundTrip) {
  for (int e = 0; e < 36; ++e) {
    Filler f{.k = static_cast<size_t>(e) * 5};
    ExpectRoundTrip(f.State(e), "filler " + std::to_string(e));
  }
}

TEST(TableCheckpointTest, DefaultsAndEmptiesRoundTrip) {
  ExpectRoundTrip(TableRestState{}, "default");
  TableRestState s;
  s.clock_deadline = 0;  // present, zero
  s.last_shot.verdict = g::Verdict{};
  s.record.push_back(MatchEntry{});
  s.record.push_back(MatchEntry{.verdict = g::Verdict{}});
  s.game.decision = g::Decision{.seat = 0, .choices = {}};  // pending, no choices
  s.rest.balls.push_back(b::Ball{});
  s.game.replay_position.balls.push_back(b::Ball{});
  ExpectRoundTrip(s, "empties");
  absl::StatusOr<TableRestState> back = DecodeTableRestState(EncodeTableRestState(s));
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_TRUE(back->clock_deadline.has_value());
  EXPECT_TRUE(back->last_shot.verdict.has_value());
  EXPECT_FALSE(back->record[0].verdict.has_value());
  EXPECT_TRUE(back->record[1].verdict.has_value());
  EXPECT_TRUE(back->game.decision.pending());
}

TEST(TableCheckpointTest, EveryDoubleKeepsItsBits) {
  // Each odd double in every double field of a ball, and in the stand-alone doubles.
  for (double d : OddDoubles()) {
    TableRestState s;
    b::Ball ball;
    ball.r = Eigen::Vector3d(d, -d, d);
    ball.v = Eigen::Vector3d(d, d, -d);
    ball.w = Eigen::Vector3d(-d, d, d);
    ball.q = Eigen::Quaterniond(d, d, -d, d);
    s.rest.balls = {ball};
    s.rest.t_s = d;
    s.last_shot.duration_s = d;
    s.game.replay_position = s.rest;
    MatchEntry e;
    e.x_m = d;
    e.y_m = -d;
    e.applied.applied = {.speed_mps = d, .phi_rad = d, .theta_rad = d, .a = d, .b = d,
                         .noise = d};
    e.applied.cue_speed_mps = d;
    e.applied.squirt_rad = d;
    e.applied.v = ball.v;
    e.applied.w = ball.w;
    s.record = {e};
    ExpectRoundTrip(s, "double " + std::to_string(std::bit_cast<uint64_t>(d)));
    absl::StatusOr<TableRestState> back = DecodeTableRestState(EncodeTableRestState(s));
    ASSERT_TRUE(back.ok());
    EXPECT_EQ(std::bit_cast<uint64_t>(back->rest.balls[0].q.w()), std::bit_cast<uint64_t>(d));
    EXPECT_EQ(std::bit_cast<uint64_t>(back->record[0].y_m), std::bit_cast<uint64_t>(-d));
  }
  // The comparison itself tells -0.0 from 0.0 and NaN payloads apart.
  TableRestState a, b2;
  a.rest.t_s = 0.0;
  b2.rest.t_s = -0.0;
  EXPECT_FALSE(SameRestState(a, b2));
  EXPECT_THAT(RestStateDifference(a, b2), HasSubstr("rest.t_s"));
  a.rest.t_s = Bits(0x7FF8000000000001ull);
  b2.rest.t_s = Bits(0x7FF8000000000002ull);
  EXPECT_FALSE(SameRestState(a, b2));
  b2.rest.t_s = a.rest.t_s;
  EXPECT_TRUE(SameRestState(a, b2));
}

TEST(TableCheckpointTest, EveryEnumValueRoundTrips) {
  TableRestState s;
  for (int v = 0; v <= static_cast<int>(b::MotionState::kPocketed); ++v) {
    b::Ball ball;
    ball.id = std::to_string(v);
    ball.state = static_cast<b::MotionState>(v);
    s.rest.balls.push_back(ball);
  }
  for (int v = 0; v <= static_cast<int>(MatchEntry::Kind::kReset); ++v) {
    s.record.push_back(MatchEntry{.kind = static_cast<MatchEntry::Kind>(v)});
  }
  ExpectRoundTrip(s, "motion states and entry kinds");
  for (int v = 0; v <= static_cast<int>(g::GameKind::kThreeCushion); ++v) {
    s.game.game = static_cast<g::GameKind>(v);
    ExpectRoundTrip(s, "game kind " + std::to_string(v));
  }
  for (int v = 0; v <= static_cast<int>(g::BallInHand::kD); ++v) {
    s.game.ball_in_hand = static_cast<g::BallInHand>(v);
    ExpectRoundTrip(s, "ball in hand " + std::to_string(v));
  }
  for (int v = 0; v <= static_cast<int>(g::Group::kStripes); ++v) {
    for (int w = 0; w <= static_cast<int>(g::Group::kStripes); ++w) {
      s.game.groups = {static_cast<g::Group>(v), static_cast<g::Group>(w)};
      ExpectRoundTrip(s, "groups " + std::to_string(v) + "," + std::to_string(w));
    }
  }
  for (int v = 0; v <= static_cast<int>(g::MatchResult::kAbandoned); ++v) {
    s.game.result = static_cast<g::MatchResult>(v);
    ExpectRoundTrip(s, "result " + std::to_string(v));
  }
  // The names mirror the C++ enums' last values (a value added there shows up here too).
  EXPECT_EQ(g::GameNames().size(), 6u);
  EXPECT_EQ(st::Ball::MotionState_ARRAYSIZE, 6);
  EXPECT_EQ(st::GameState::GameKind_ARRAYSIZE, 6);
  EXPECT_EQ(st::GameState::BallInHand_ARRAYSIZE, 4);
  EXPECT_EQ(st::GameState::Group_ARRAYSIZE, 3);
  EXPECT_EQ(st::GameState::MatchResult_ARRAYSIZE, 6);
  EXPECT_EQ(st::MatchEntry::Kind_ARRAYSIZE, 6);
}

TEST(TableCheckpointTest, LongStringsAndManyEntriesRoundTrip) {
  TableRestState s;
  s.last_shot.error = LongString(1 << 20);
  s.game.phase = LongString(70000);
  for (int i = 0; i < 2000; ++i) {
    s.record.push_back(MatchEntry{.kind = MatchEntry::Kind::kPlace, .tick = i, .seat = i % 2,
                                  .ball = "cue", .x_m = i * 1e-3, .y_m = -i * 1e-3});
  }
  ExpectRoundTrip(s, "long");
}

TEST(TableCheckpointTest, VersionAndTrailerAreWritten) {
  ExpectVersionAndTrailer<st::TableRestState>(EncodeTableRestState(TableRestState{}),
                                             kTableCheckpointVersion);
  EXPECT_EQ(Crc32c("123456789"), 0xE3069283u);  // this file's own CRC, which seals below
}

// ---------------------------------------------------------------------------------------------
// 3. Damaged bytes.

TableRestState RealState() {
  BotTable table(g::GameKind::kNineBall, 5, 1, 30.0, 1.0);
  for (int i = 0; i < 6; ++i) table.Step();
  return table.state();
}

TEST(TableCheckpointTest, EveryPrefixAndEveryFlippedBitIsRefused) {
  const TableRestState s = RealState();
  const std::string bytes = EncodeTableRestState(s);
  ExpectEveryPrefixAndFlipRefused(bytes, DecodeTableRestState, "table checkpoint: ");
  EXPECT_FALSE(DecodeTableRestState(bytes + bytes).ok());
  absl::StatusOr<TableRestState> empty = DecodeTableRestState("");
  ASSERT_FALSE(empty.ok());
  EXPECT_THAT(empty.status().message(), HasSubstr("0 bytes"));
}

/// The decoder's answer to a hand-made message, sealed with a valid trailer.
absl::Status DecodeSealed(const st::TableRestState& m) {
  return DecodeTableRestState(Seal(m)).status();
}

TEST(TableCheckpointTest, ChecksumMismatchIsNamed) {
  std::string bytes = EncodeTableRestState(RealState());
  bytes[10] = static_cast<char>(bytes[10] ^ 0x40);
  const absl::Status s = DecodeTableRestState(bytes).status();
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), HasSubstr("crc32c"));
  EXPECT_THAT(s.message(), HasSubstr("damaged or cut short"));
}

TEST(TableCheckpointTest, OtherVersionsAreRefused) {
  const st::TableRestState good = Parsed<st::TableRestState>(EncodeTableRestState(RealState()));
  EXPECT_TRUE(DecodeSealed(good).ok());
  for (uint32_t v : {0u, 2u, 1000u, 0xFFFFFFFFu}) {
    st::TableRestState m = good;
    m.set_version(v);
    const absl::Status s = DecodeSealed(m);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << v << ": " << s;
    EXPECT_THAT(s.message(), HasSubstr(absl::StrFormat("version %d", v)));
  }
  // A sealed empty body: version 0.
  EXPECT_EQ(DecodeTableRestState(Seal("")).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(TableCheckpointTest, StructuralDamageIsNamed) {
  const st::TableRestState good = Parsed<st::TableRestState>(EncodeTableRestState(RealState()));
  ASSERT_GE(good.record_size(), 2);
  ASSERT_GE(good.rest().balls_size(), 2);
  struct Case {
    std::string name;
    std::function<void(st::TableRestState*)> damage;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"no rest", [](st::TableRestState* m) { m->clear_rest(); }, "rest: missing"},
      {"no last_shot", [](st::TableRestState* m) { m->clear_last_shot(); }, "last_shot: missing"},
      {"no game", [](st::TableRestState* m) { m->clear_game(); }, "game: missing"},
      {"no ball position",
       [](st::TableRestState* m) { m->mutable_rest()->mutable_balls(1)->clear_r(); },
       "rest.balls[1].r: missing"},
      {"no ball orientation",
       [](st::TableRestState* m) { m->mutable_rest()->mutable_balls(0)->clear_q(); },
       "rest.balls[0].q: missing"},
      {"no velocity", [](st::TableRestState* m) { m->mutable_rest()->mutable_balls(0)->clear_v(); },
       "rest.balls[0].v: missing"},
      {"no spin", [](st::TableRestState* m) { m->mutable_rest()->mutable_balls(0)->clear_w(); },
       "rest.balls[0].w: missing"},
      {"motion state 6",
       [](st::TableRestState* m) {
         m->mutable_rest()->mutable_balls(1)->set_state(static_cast<st::Ball::MotionState>(6));
       },
       "rest.balls[1].state: unknown motion state 6"},
      {"negative motion state",
       [](st::TableRestState* m) {
         m->mutable_rest()->mutable_balls(0)->set_state(static_cast<st::Ball::MotionState>(-3));
       },
       "rest.balls[0].state: unknown motion state -3"},
      {"game kind 9",
       [](st::TableRestState* m) {
         m->mutable_game()->set_game(static_cast<st::GameState::GameKind>(9));
       },
       "game.game: unknown game 9"},
      {"ball in hand 4",
       [](st::TableRestState* m) {
         m->mutable_game()->set_ball_in_hand(static_cast<st::GameState::BallInHand>(4));
       },
       "game.ball_in_hand: unknown ball in hand 4"},
      {"group 3",
       [](st::TableRestState* m) {
         m->mutable_game()->set_groups(1, static_cast<st::GameState::Group>(3));
       },
       "game.groups[1]: unknown group 3"},
      {"result 6",
       [](st::TableRestState* m) {
         m->mutable_game()->set_result(static_cast<st::GameState::MatchResult>(6));
       },
       "game.result: unknown match result 6"},
      {"entry kind 6",
       [](st::TableRestState* m) {
         m->mutable_record(1)->set_kind(static_cast<st::MatchEntry::Kind>(6));
       },
       "record[1].kind: unknown entry kind 6"},
      {"three scores", [](st::TableRestState* m) { m->mutable_game()->add_scores(1); },
       "game.scores: 3 values, want 2"},
      {"one frames_won",
       [](st::TableRestState* m) { m->mutable_game()->mutable_frames_won()->RemoveLast(); },
       "game.frames_won: 1 values, want 2"},
      {"no warned", [](st::TableRestState* m) { m->mutable_game()->clear_warned(); },
       "game.warned: 0 values, want 2"},
      {"no groups", [](st::TableRestState* m) { m->mutable_game()->clear_groups(); },
       "game.groups: 0 values, want 2"},
      {"no fouls_in_row", [](st::TableRestState* m) { m->mutable_game()->clear_fouls_in_row(); },
       "game.fouls_in_row: 0 values, want 2"},
      {"no innings", [](st::TableRestState* m) { m->mutable_game()->clear_innings(); },
       "game.innings: 0 values, want 2"},
      {"no decision", [](st::TableRestState* m) { m->mutable_game()->clear_decision(); },
       "game.decision: missing"},
      {"no replay position",
       [](st::TableRestState* m) { m->mutable_game()->clear_replay_position(); },
       "game.replay_position: missing"},
      {"no call", [](st::TableRestState* m) { m->mutable_last_shot()->clear_call(); },
       "last_shot.call: missing"},
      {"no entry call", [](st::TableRestState* m) { m->mutable_record(0)->clear_call(); },
       "record[0].call: missing"},
      {"no applied", [](st::TableRestState* m) { m->mutable_record(1)->clear_applied(); },
       "record[1].applied: missing"},
      {"no applied strike",
       [](st::TableRestState* m) { m->mutable_record(0)->mutable_applied()->clear_applied(); },
       "record[0].applied.applied: missing"},
      {"no applied v",
       [](st::TableRestState* m) { m->mutable_record(0)->mutable_applied()->clear_v(); },
       "record[0].applied.v: missing"},
      {"unknown top field",
       [](st::TableRestState* m) {
         m->GetReflection()->MutableUnknownFields(m)->AddVarint(12, 5);
       },
       "(top): unknown field 12"},
      {"unknown field in a ball",
       [](st::TableRestState* m) {
         st::Ball* ball = m->mutable_rest()->mutable_balls(1);
         ball->GetReflection()->MutableUnknownFields(ball)->AddFixed64(99, 1);
       },
       "rest.balls[1]: unknown field 99"},
      {"unknown field in a verdict",
       [](st::TableRestState* m) {
         st::Verdict* v = m->mutable_record(0)->mutable_verdict();
         v->GetReflection()->MutableUnknownFields(v)->AddLengthDelimited(7, "x");
       },
       "record[0].verdict: unknown field 7"},
      {"crc32c in the body", [](st::TableRestState* m) { m->set_crc32c(5); },
       "crc32c: found before the end"},
  };
  for (const Case& c : cases) {
    st::TableRestState m = good;
    c.damage(&m);
    const absl::Status s = DecodeSealed(m);
    EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss) << c.name << ": " << s;
    EXPECT_THAT(s.message(), HasSubstr("table checkpoint: " + c.message)) << c.name;
  }
}

// ---------------------------------------------------------------------------------------------
// 4. Fuzz-style.

void ExpectStableIfDecoded(const std::string& bytes) {
  absl::StatusOr<TableRestState> back = DecodeTableRestState(bytes);
  if (!back.ok()) {
    EXPECT_TRUE(back.status().code() == absl::StatusCode::kDataLoss ||
                back.status().code() == absl::StatusCode::kInvalidArgument)
        << back.status();
    EXPECT_THAT(back.status().message(), HasSubstr("table checkpoint: "));
    return;
  }
  absl::StatusOr<TableRestState> again = DecodeTableRestState(EncodeTableRestState(*back));
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ(RestStateDifference(*back, *again), "");
}

TEST(TableCheckpointTest, TenThousandRandomByteStrings) {
  std::mt19937_64 rng(20261201);
  int decoded = 0;
  for (int i = 0; i < 10000; ++i) {
    const size_t n = rng() % 600;
    std::string bytes(n, '\0');
    for (char& c : bytes) c = static_cast<char>(rng());
    // Half of them raw (the checksum refuses them), half sealed: the parser and the structure
    // checks see them.
    const std::string input = i % 2 == 0 ? bytes : Seal(bytes);
    ExpectStableIfDecoded(input);
    if (DecodeTableRestState(input).ok()) ++decoded;
  }
  std::cout << decoded << " of 10000 random byte strings decoded\n";
}

TEST(TableCheckpointTest, TenThousandMutatedCheckpoints) {
  const std::string real = EncodeTableRestState(RealState());
  const std::string body = real.substr(0, real.size() - 5);
  std::mt19937_64 rng(7);
  int decoded = 0;
  std::map<std::string, int> errors;
  for (int i = 0; i < 10000; ++i) {
    std::string m = body;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits && !m.empty(); ++e) {
      const size_t at = rng() % m.size();
      switch (rng() % 4) {
        case 0: m[at] = static_cast<char>(rng()); break;
        case 1: m.erase(at, 1 + rng() % 8); break;
        case 2: m.insert(at, std::string(1 + rng() % 4, static_cast<char>(rng()))); break;
        case 3: m.resize(at); break;
      }
    }
    const std::string sealed = Seal(m);
    ExpectStableIfDecoded(sealed);
    absl::StatusOr<TableRestState> back = DecodeTableRestState(sealed);
    if (back.ok()) {
      ++decoded;
    } else {
      std::string msg(back.status().message());
      ++errors[msg.substr(0, std::min<size_t>(msg.size(), 48))];
    }
    if (HasFailure()) break;
  }
  std::cout << decoded << " of 10000 mutated checkpoints decoded; " << errors.size()
            << " distinct error prefixes\n";
}

}  // namespace
}  // namespace sportsim::server
