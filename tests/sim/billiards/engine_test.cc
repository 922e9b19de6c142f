// The stepped engine beyond the closed forms (event_engine_test.cc has the event engine's): continuous collision detection, invariants over
// random shots on every preset, determinism, rest, pockets, frozen balls, input validation.
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/billiards/cloth.h"
#include "sim/billiards/collision.h"
#include "sim/billiards/cue.h"
#include "sim/billiards/engine.h"
#include "sim/billiards/model.h"
#include "sim/billiards/rack.h"
#include "sim/billiards/shot.h"
#include "sim/core/units.h"

namespace sportsim::billiards {
namespace {

using ::testing::HasSubstr;

TableModel Model(std::string_view preset, PhysicsParams* override_params = nullptr) {
  absl::StatusOr<TableSpec> spec = MakeTablePreset(preset);
  EXPECT_TRUE(spec.ok()) << spec.status();
  if (override_params != nullptr) spec->params = *override_params;
  absl::StatusOr<TableModel> model = TableModel::Create(*spec);
  EXPECT_TRUE(model.ok()) << model.status();
  return *model;
}

Ball BallAt(std::string id, double x, double y, const TableModel& m) {
  Ball b;
  b.id = std::move(id);
  b.r = Eigen::Vector3d(x, y, m.radius());
  return b;
}

int Count(const std::vector<Event>& events, EventKind kind) {
  int n = 0;
  for (const Event& e : events) n += e.kind == kind;
  return n;
}

// Bitwise equality of two states (positions, velocities, spins, orientations, states).
bool SameBits(const TableState& a, const TableState& b) {
  if (a.balls.size() != b.balls.size() || std::memcmp(&a.t_s, &b.t_s, sizeof(double)) != 0) {
    return false;
  }
  for (size_t i = 0; i < a.balls.size(); ++i) {
    const Ball& x = a.balls[i];
    const Ball& y = b.balls[i];
    if (std::memcmp(x.r.data(), y.r.data(), 3 * sizeof(double)) != 0 ||
        std::memcmp(x.v.data(), y.v.data(), 3 * sizeof(double)) != 0 ||
        std::memcmp(x.w.data(), y.w.data(), 3 * sizeof(double)) != 0 ||
        std::memcmp(x.q.coeffs().data(), y.q.coeffs().data(), 4 * sizeof(double)) != 0 ||
        x.state != y.state || x.pocket != y.pocket) {
      return false;
    }
  }
  return true;
}

// The tunnelling pitfall: 13 m/s at a 1/120 s step moves the ball 108 mm per step,
// more than the 76 mm chord through a ball hit at an offset of 1.5 R. Without CCD some phases
// of the step grid jump straight through; with CCD every phase collides.
// WPA's 8-ball rack: the 8 in the middle of the third row, and one ball of each group in the
// two back corners.
TEST(RackTest, EightBallRackHasTheEightCentredAndOneOfEachGroupInTheBackCorners) {
  const TableModel m = Model("pool-9ft");
  absl::StatusOr<std::vector<Ball>> rack = MakeRack("8ball", m);
  ASSERT_TRUE(rack.ok()) << rack.status();
  double back_x = -1e9;
  for (const Ball& b : *rack) back_x = std::max(back_x, b.r.x());
  std::vector<int> corners;
  double max_y = 0.0;
  for (const Ball& b : *rack) {
    if (std::abs(b.r.x() - back_x) < 1e-9) max_y = std::max(max_y, std::abs(b.r.y()));
  }
  for (const Ball& b : *rack) {
    if (std::abs(b.r.x() - back_x) < 1e-9 && std::abs(std::abs(b.r.y()) - max_y) < 1e-9) {
      corners.push_back(std::stoi(b.id));
    }
  }
  ASSERT_EQ(corners.size(), 2u);
  EXPECT_NE(corners[0] > 8, corners[1] > 8) << corners[0] << " and " << corners[1];
  // The 8: third row (two rows behind the apex), centred.
  const Ball* eight = nullptr;
  const Ball* apex = nullptr;
  for (const Ball& b : *rack) {
    if (b.id == "8") eight = &b;
    if (b.id == "1") apex = &b;
  }
  ASSERT_NE(eight, nullptr);
  ASSERT_NE(apex, nullptr);
  EXPECT_NEAR(eight->r.y(), 0.0, 1e-12);
  EXPECT_NEAR(eight->r.x() - apex->r.x(), 2.0 * std::sqrt(3.0) * m.radius(), 1e-6);
}

// The engine can leave a ball at rest on a pocket's lip, between the jaws and beyond the rail
// line (seen on the snooker table's side pocket); such a table must stay playable, while a
// ball beyond a rail away from any pocket, or inside a jaw, is still refused.
TEST(LayoutTest, ABallRestingInAPocketMouthIsOnTheTable) {
  const TableModel m = Model("snooker");
  const double lim_y = 0.5 * m.spec().width_m - m.cushion_contact_distance();
  const Eigen::Vector2d lip(0.0248573, -0.870082);  // past the rail line, between the jaws
  ASSERT_GT(std::abs(lip.y()), lim_y);
  EXPECT_TRUE(InPocketMouth(m, lip));
  TableState on_lip{.balls = {BallAt("red1", lip.x(), lip.y(), m), BallAt("cue", 0.5, 0, m)}};
  EXPECT_TRUE(ValidateLayout(m, on_lip).ok()) << ValidateLayout(m, on_lip);
  TableState beyond_rail{.balls = {BallAt("red1", 0.6, lip.y(), m)}};
  EXPECT_FALSE(InPocketMouth(m, Eigen::Vector2d(0.6, lip.y())));
  EXPECT_THAT(ValidateLayout(m, beyond_rail).message(), HasSubstr("not on the cloth"));
  // In the jaw: near the pocket but within a radius of a jaw segment.
  for (const CushionSegment& c : m.spec().cushions) {
    if (c.name.find("jaw") == std::string::npos) continue;
    const Eigen::Vector2d mid = 0.5 * (c.a + c.b);
    EXPECT_FALSE(InPocketMouth(m, mid)) << c.name;
  }
}

// A ball the engine leaves at rest against a jaw, beyond the rail line, is the cushion
// contact distance from the jaw: less than a radius (the nose is below the ball's equator).
// Seen on a 9-ft table: the cue ball came to rest against a corner jaw and the next shot was
// refused as "not on the cloth". It is playable; a ball pressed into the jaw, or behind it
// inside the rail, is not.
TEST(LayoutTest, ABallRestingAgainstAJawIsOnTheTable) {
  const TableModel m = Model("pool-9ft");
  const double dc = m.cushion_contact_distance();
  ASSERT_LT(dc, m.radius() - 1e-6);
  const double lim_x = 0.5 * m.spec().length_m - dc;
  const double lim_y = 0.5 * m.spec().width_m - dc;
  int checked = 0;
  for (const Pocket& pocket : m.spec().pockets) {
    for (const char* end : {"_a", "_b"}) {
      const std::string name = "jaw_" + pocket.name + end;
      const auto jaw = std::find_if(m.spec().cushions.begin(), m.spec().cushions.end(),
                                    [&](const CushionSegment& c) { return c.name == name; });
      ASSERT_NE(jaw, m.spec().cushions.end()) << name;
      const Eigen::Vector2d mid = 0.5 * (jaw->a + jaw->b), e = (jaw->b - jaw->a).normalized();
      Eigen::Vector2d in(-e.y(), e.x());  // towards the pocket's side
      if (in.dot(pocket.centre - jaw->a) < 0.0) in = -in;
      const Eigen::Vector2d against = mid + (dc + 1e-9) * in;
      if (std::abs(against.x()) <= lim_x && std::abs(against.y()) <= lim_y) continue;
      ++checked;
      EXPECT_TRUE(InPocketMouth(m, against)) << name;
      TableState s{.balls = {BallAt("cue", against.x(), against.y(), m)}};
      EXPECT_TRUE(ValidateLayout(m, s).ok()) << name << ": " << ValidateLayout(m, s);
      EXPECT_FALSE(InPocketMouth(m, mid + (dc - 1e-5) * in)) << name << ": pressed in";
      EXPECT_FALSE(InPocketMouth(m, mid - (dc + 1e-3) * in)) << name << ": behind the jaw";
    }
  }
  EXPECT_GE(checked, 8);  // the corner jaws at least
}

TEST(SteppedEngineTest, CcdStopsTunnellingAt13MpsAndOneTwentiethSecondSteps) {
  const TableModel m = Model("unbounded");
  const double r = m.radius();
  int missed_without_ccd = 0;
  constexpr int kPhases = 24;
  for (int k = 0; k < kPhases; ++k) {
    // Shift the start by a fraction of one step's travel so the grid meets the ball differently.
    const double x0 = -0.6 - (0.108 * k) / kPhases;
    TableState s{.balls = {BallAt("cue", x0, 0.0, m), BallAt("1", 0.0, 1.5 * r, m)}};
    s.balls[0].v = Eigen::Vector3d(13.0, 0.0, 0.0);
    s.balls[0].w = Eigen::Vector3d(0.0, 13.0 / r, 0.0);  // rolling: no curve, no slide
    for (bool ccd : {true, false}) {
      SolverOptions o{.engine = Engine::kStepped, .integrator = Integrator::kRk4, .dt_s = 1.0 / 120.0, .ccd = ccd};
      absl::StatusOr<ShotResult> out = SimulateShot(m, o, s, {.max_time_s = 0.2});
      ASSERT_TRUE(out.ok()) << out.status();
      const int hits = Count(out->events, EventKind::kBallBall);
      if (ccd) {
        EXPECT_EQ(hits, 1) << "phase " << k;
      } else if (hits == 0) {
        ++missed_without_ccd;
      }
    }
  }
  EXPECT_GT(missed_without_ccd, 0) << "the discrete stepper should tunnel at some phase";
}

// 100 seeded random shots on each of the six presets (a quarter of them with Stronge's compliant
// cushions): nothing non-finite, no overlap, no energy gain between samples, every ball on the
// cloth or in a pocket at the end.
TEST(SteppedEngineTest, InvariantsOverRandomShotsOnEveryPreset) {
  // Overlap allowed: contact times are found to 1e-13 s, i.e. < 1e-11 m at 20 m/s; 1e-9 m
  // leaves room for rounding of positions ~1 m in size.
  constexpr double kOverlapTolM = 1e-9;
  // Energy may not grow by more than rounding (relative).
  constexpr double kEnergyTol = 1e-12;
  std::mt19937_64 rng(20261121);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int shots = 0;
  for (std::string_view preset : TablePresetNames()) {
    const TableModel han = Model(preset);
    PhysicsParams compliant = han.params();
    compliant.cushion_model = CushionModel::kStrongeCompliant;
    const TableModel stronge = Model(preset, &compliant);
    const std::string rack = preset == "snooker"     ? "snooker"
                             : preset == "carom"     ? "three-cushion"
                             : preset == "unbounded" ? "chapter19"
                                                     : (shots % 2 ? "9ball" : "8ball");
    for (int i = 0; i < 100; ++i, ++shots) {
      // Every fourth shot on Stronge's compliant cushions, the others on Han's.
      const TableModel& m = i % 4 == 3 ? stronge : han;
      absl::StatusOr<std::vector<Ball>> balls = MakeRack(rack, m, 0.0005 * unit(rng), rng());
      ASSERT_TRUE(balls.ok()) << balls.status();
      TableState s{.balls = *balls};
      const CueStrike strike{.speed_mps = 0.5 + 7.0 * unit(rng),
                             .phi_rad = kTwoPi * unit(rng),
                             .theta_rad = DegToRad(20.0 * unit(rng)),
                             .a = 0.6 * (unit(rng) - 0.5),
                             .b = 0.6 * (unit(rng) - 0.5)};
      const SolverOptions o{.engine = Engine::kStepped,
                            .integrator = static_cast<Integrator>(i % 3), .dt_s = 1.0 / 480.0};
      ASSERT_TRUE(ApplyStrike(m, o.effects, strike, s.Find("cue"), &s).ok());
      // Unbounded runs can roll far: stop them after 20 s.
      absl::StatusOr<ShotResult> out =
          SimulateShot(m, o, s, {.max_time_s = preset == "unbounded" ? 20.0 : 600.0,
                                 .sample_interval_s = 1.0 / 60.0});
      ASSERT_TRUE(out.ok()) << preset << " shot " << i << ": " << out.status();
      if (preset != "unbounded") {
        EXPECT_TRUE(out->at_rest) << preset << " shot " << i;
      }
      double e_prev = std::numeric_limits<double>::infinity();
      for (const Sample& smp : out->samples) {
        // Energy from positions is not in a sample; check overlap here, energy below.
        for (size_t a = 0; a < smp.r.size(); ++a) {
          ASSERT_TRUE(smp.r[a].allFinite());
          if (smp.state[a] == MotionState::kPocketed) continue;
          for (size_t b = a + 1; b < smp.r.size(); ++b) {
            if (smp.state[b] == MotionState::kPocketed) continue;
            ASSERT_GE((smp.r[a] - smp.r[b]).norm(), 2 * m.radius() - kOverlapTolM)
                << preset << " shot " << i << " t " << smp.t_s << " balls " << a << "," << b
                << " overlap " << 2 * m.radius() - (smp.r[a] - smp.r[b]).norm();
          }
        }
      }
      // Energy: replay the shot in chunks and check it never grows.
      TableState replay = s;
      std::vector<Event> ev;
      for (double t = 0.05; t < 3.0 && !replay.AtRest(); t += 0.05) {
        ASSERT_TRUE(Advance(m, o, std::round(t / o.dt_s) * o.dt_s, &replay, &ev).ok());
        const double e = TotalKineticEnergy(m, replay);
        ASSERT_LE(e, e_prev * (1 + kEnergyTol) + 1e-15) << preset << " shot " << i << " t " << t;
        e_prev = e;
      }
      for (const Ball& b : out->final_state.balls) {
        ASSERT_TRUE(b.r.allFinite() && b.v.allFinite() && b.w.allFinite());
        if (b.state == MotionState::kPocketed) {
          EXPECT_GE(b.pocket, 0) << "a ball left the table through a cushion: " << b.id;
          continue;
        }
        if (m.spec().bounded) {
          EXPECT_LE(std::abs(b.r.x()), 0.5 * m.spec().length_m) << b.id;
          EXPECT_LE(std::abs(b.r.y()), 0.5 * m.spec().width_m) << b.id;
        }
      }
    }
  }
}

TEST(SteppedEngineTest, SameShotTwiceIsBitIdentical) {
  const TableModel m = Model("pool-9ft");
  for (Integrator integ : {Integrator::kEuler, Integrator::kSemiImplicitEuler, Integrator::kRk4}) {
    absl::StatusOr<std::vector<Ball>> balls = MakeRack("8ball", m, 0.0002, 7);
    ASSERT_TRUE(balls.ok());
    TableState s{.balls = *balls};
    const SolverOptions o{.engine = Engine::kStepped, .integrator = integ};
    ASSERT_TRUE(ApplyStrike(m, o.effects, {.speed_mps = 8.0, .phi_rad = 0.01, .a = 0.1},
                            s.Find("cue"), &s)
                    .ok());
    absl::StatusOr<ShotResult> one = SimulateShot(m, o, s, {});
    absl::StatusOr<ShotResult> two = SimulateShot(m, o, s, {});
    ASSERT_TRUE(one.ok() && two.ok());
    EXPECT_TRUE(SameBits(one->final_state, two->final_state));
    ASSERT_EQ(one->events.size(), two->events.size());
    for (size_t i = 0; i < one->events.size(); ++i) {
      EXPECT_EQ(std::memcmp(&one->events[i].t_s, &two->events[i].t_s, sizeof(double)), 0);
      EXPECT_EQ(one->events[i].a, two->events[i].a);
      EXPECT_EQ(one->events[i].b, two->events[i].b);
    }
  }
}

// Chunked advances that end on the step grid give the same bits as one advance (what the
// server's ticks rely on), and a ball at rest stays exactly where it is.
TEST(SteppedEngineTest, ChunkedAdvanceMatchesOneAdvanceAndRestingBallsDoNotMove) {
  const TableModel m = Model("pool-9ft");
  TableState s{.balls = {BallAt("cue", -0.8, 0.0, m), BallAt("1", 0.9, 0.5, m)}};
  const SolverOptions o{.engine = Engine::kStepped, .integrator = Integrator::kSemiImplicitEuler, .dt_s = 1.0 / 960.0};
  ASSERT_TRUE(ApplyStrike(m, o.effects, {.speed_mps = 3.0, .phi_rad = DegToRad(-20.0), .b = 0.3},
                          0, &s)
                  .ok());
  const Eigen::Vector3d parked = s.balls[1].r;
  TableState whole = s, chunked = s;
  std::vector<Event> e1, e2;
  ASSERT_TRUE(Advance(m, o, 1.5, &whole, &e1).ok());
  for (int tick = 1; tick <= 180; ++tick) {  // 120 Hz ticks: 8 steps each
    ASSERT_TRUE(Advance(m, o, tick * (8.0 / 960.0), &chunked, &e2).ok());
  }
  EXPECT_TRUE(SameBits(whole, chunked));
  EXPECT_EQ(e1.size(), e2.size());
  EXPECT_EQ(std::memcmp(whole.balls[1].r.data(), parked.data(), 3 * sizeof(double)), 0);
  EXPECT_EQ(whole.balls[1].state, MotionState::kStationary);
}

// Slide -> roll -> rest: exactly one transition each, no chatter, whatever the step.
TEST(SteppedEngineTest, TransitionsHappenOnceWithoutChatter) {
  const TableModel m = Model("unbounded");
  for (double dt : {1e-4, 1.0 / 960.0, 1.0 / 120.0, 0.05}) {
    TableState s{.balls = {BallAt("cue", 0, 0, m)}};
    s.balls[0].v = Eigen::Vector3d(2.0, 1.0, 0.0);
    s.balls[0].w = Eigen::Vector3d(0.0, 0.0, 5.0);
    absl::StatusOr<ShotResult> out = SimulateShot(m, {.engine = Engine::kStepped, .dt_s = dt}, s, {});
    ASSERT_TRUE(out.ok()) << out.status();
    ASSERT_TRUE(out->at_rest);
    std::vector<std::pair<MotionState, MotionState>> seen;
    for (const Event& e : out->events) seen.emplace_back(e.from, e.to);
    // stationary -> sliding at the start, sliding -> rolling, rolling -> spinning or
    // stationary, (spinning -> stationary).
    ASSERT_GE(seen.size(), 3u) << dt;
    EXPECT_LE(seen.size(), 4u) << dt;
    EXPECT_EQ(seen[1], std::make_pair(MotionState::kSliding, MotionState::kRolling)) << dt;
    EXPECT_EQ(out->final_state.balls[0].v, Eigen::Vector3d::Zero());
    EXPECT_EQ(out->final_state.balls[0].w, Eigen::Vector3d::Zero());
  }
}

// Newton's cradle: a line of touching balls, frictionless and elastic, hit by a stun shot (no
// spin, so nothing drives the cue ball on afterwards). The momentum passes down the line: the
// last ball leaves with it, the others stop dead.
TEST(SteppedEngineTest, NewtonsCradleOfFrozenBalls) {
  PhysicsParams p;
  p.e_ball = 1.0;
  const TableModel m = Model("unbounded", &p);
  const double d = 2 * m.radius();
  TableState s{.balls = {BallAt("cue", -0.5, 0, m), BallAt("1", 0, 0, m), BallAt("2", d, 0, m),
                         BallAt("3", 2 * d, 0, m), BallAt("4", 3 * d, 0, m)}};
  s.balls[0].v = Eigen::Vector3d(1.0, 0, 0);
  s.balls[0].r.x() = -d;  // touching: the cascade runs at t = 0
  const SolverOptions o{.engine = Engine::kStepped,
                        .effects = kEffectDisableBallFriction};
  std::vector<Event> ev;
  ASSERT_TRUE(Advance(m, o, 0.6, &s, &ev).ok());
  EXPECT_EQ(Count(ev, EventKind::kBallBall), 4);
  // After the cascade only the last ball moves (the others keep only rounding-level speed).
  for (int i = 0; i < 4; ++i) EXPECT_LT(s.balls[i].v.norm(), 1e-9) << i;
  EXPECT_GT(s.balls[4].v.x(), 0.5);
  // No overlap afterwards.
  for (int i = 0; i + 1 < 5; ++i) {
    EXPECT_GE((s.balls[i + 1].r - s.balls[i].r).norm(), d - 1e-9);
  }
}

TEST(BothEnginesTest, BallAimedAtCornerIsPocketed) {
  const TableModel m = Model("pool-9ft");
  const double hx = 0.5 * m.spec().length_m, hy = 0.5 * m.spec().width_m;
  TableState s{.balls = {BallAt("cue", hx - 0.4, hy - 0.4, m)}};
  s.balls[0].v = Eigen::Vector3d(1.0, 1.0, 0);
  for (const Engine engine : {Engine::kStepped, Engine::kEvent}) {
    TableState t = s;
    std::vector<Event> ev;
    ASSERT_TRUE(Advance(m, {.engine = engine}, 3.0, &t, &ev).ok());
    ASSERT_EQ(Count(ev, EventKind::kBallPocket), 1) << EngineName(engine);
    EXPECT_EQ(t.balls[0].state, MotionState::kPocketed);
    EXPECT_EQ(m.spec().pockets[t.balls[0].pocket].name, "top_right");
    EXPECT_EQ(Count(ev, EventKind::kBallCushion), 0);
  }
}

TEST(BothEnginesTest, CushionsOffLetBallsLeaveTheTable) {
  const TableModel m = Model("carom");
  TableState s{.balls = {BallAt("cue", 0, 0, m)}};
  s.balls[0].v = Eigen::Vector3d(0, 3.0, 0);
  for (const Engine engine : {Engine::kStepped, Engine::kEvent}) {
    TableState t = s;
    std::vector<Event> ev;
    ASSERT_TRUE(
        Advance(m, {.engine = engine, .effects = kEffectDisableCushions}, 2.0, &t, &ev)
            .ok());
    EXPECT_EQ(t.balls[0].state, MotionState::kPocketed) << EngineName(engine);
    EXPECT_EQ(t.balls[0].pocket, -1);
  }
}

// Han-geometry cushion. Without friction the impulse (1 + e_c) m |v.n| acts along the contact
// normal n, tilted down by theta (sin theta = (h - R) / R), and the slate takes its vertical
// part: a head-on ball comes back at ((1 + e_c) cos^2 theta - 1) v. With friction (f_c = 0.2) a
// rolling ball loses kinetic energy and stays on its line. The mirror keeps speed exactly.
TEST(SteppedEngineTest, CushionRebounds) {
  for (CushionModel cm : {CushionModel::kHan, CushionModel::kMirror}) {
    for (double f : {0.0, 0.2}) {
      PhysicsParams p;
      p.cushion_model = cm;
      p.f_cushion = f;
      p.cushion_height_m = 0.635 * 2 * p.ball_radius_m;
      const TableModel m = Model("carom", &p);
      Ball b = BallAt("cue", 0, 0, m);
      b.v = Eigen::Vector3d(0, 2.0, 0);
      b.w = Eigen::Vector3d(-2.0 / m.radius(), 0, 0);  // rolling toward +y
      b.state = MotionState::kRolling;
      const double e0 = KineticEnergy(m, b);
      ASSERT_TRUE(CollideCushion(m, Eigen::Vector2d(0, -1), &b));
      if (cm == CushionModel::kMirror) {
        EXPECT_DOUBLE_EQ(b.v.y(), -2.0);
        continue;
      }
      const double s = (p.cushion_height_m - p.ball_radius_m) / p.ball_radius_m;
      if (f == 0.0) {
        EXPECT_NEAR(b.v.y(), -((1 + p.e_cushion) * (1 - s * s) - 1) * 2.0, 1e-12);
      } else {
        EXPECT_LT(b.v.y(), 0.0);
        EXPECT_LT(KineticEnergy(m, b), e0);
      }
      EXPECT_NEAR(b.v.x(), 0.0, 1e-12);
    }
  }
}

// Drag on a rolling ball: dv/dt = -(mu_r g + 5/7 k v^2), k = rho C_d pi R^2 / (2 m) (5/7 of the
// drag decelerates a rolling ball; the rest spins it down), so it rolls
// x = ln(1 + b v0^2 / a) / (2 b) with a = mu_r g, b = 5/7 k. The event engine refuses drag.
TEST(SteppedEngineTest, DragOnARollingBallMatchesItsClosedFormAndTheEventEngineRefusesIt) {
  const TableModel m = Model("unbounded");
  const PhysicsParams& p = m.params();
  const double v0 = 3.0;
  TableState s{.balls = {BallAt("cue", 0, 0, m)}};
  s.balls[0].v = Eigen::Vector3d(v0, 0, 0);
  s.balls[0].w = Eigen::Vector3d(0, v0 / m.radius(), 0);
  const double k = 0.5 * p.air_density_kgpm3 * p.drag_coefficient * kPi * m.radius() *
                   m.radius() / m.mass();
  const double a = p.mu_roll * p.gravity_mps2, b = 5.0 / 7.0 * k;
  const double expected = std::log(1 + b * v0 * v0 / a) / (2 * b);
  absl::StatusOr<ShotResult> plain = SimulateShot(m, {}, s, {});
  absl::StatusOr<ShotResult> drag = SimulateShot(m, {.engine = Engine::kStepped, .dt_s = 1e-3, .effects = kEffectEnableDrag}, s, {});
  ASSERT_TRUE(plain.ok() && drag.ok());
  // rk4 at 1 ms on a smooth law: far below 1e-6 m; the stop is found by re-predicting until
  // the remaining time is under 1e-9 s.
  EXPECT_NEAR(drag->final_state.balls[0].r.x(), expected, 1e-6);
  EXPECT_NEAR(plain->final_state.balls[0].r.x(), v0 * v0 / (2 * a), 1e-9);
  const absl::Status st = ValidateSolverOptions({.engine = Engine::kEvent, .effects = kEffectEnableDrag});
  EXPECT_EQ(st.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(st.message(), HasSubstr("drag"));
}

TEST(StrikeValidationTest, BadStrikesAndLayoutsAreErrorsThatChangeNothing) {
  const TableModel m = Model("pool-9ft");
  absl::StatusOr<std::vector<Ball>> balls = MakeRack("8ball", m);
  ASSERT_TRUE(balls.ok());
  const TableState base{.balls = *balls};
  const auto expect_error = [&](const CueStrike& strike, absl::StatusCode code,
                                std::string_view text, TableState s) {
    const TableState before = s;
    absl::StatusOr<StrikeOutcome> out = ApplyStrike(m, 0, strike, s.Find("cue"), &s);
    EXPECT_EQ(out.status().code(), code) << out.status();
    EXPECT_THAT(out.status().message(), HasSubstr(text));
    EXPECT_TRUE(SameBits(before, s));
  };
  expect_error({.speed_mps = NAN}, absl::StatusCode::kInvalidArgument, "speed_mps", base);
  expect_error({.speed_mps = INFINITY}, absl::StatusCode::kInvalidArgument, "speed_mps", base);
  expect_error({.speed_mps = -1}, absl::StatusCode::kInvalidArgument, "speed_mps", base);
  expect_error({.speed_mps = 25}, absl::StatusCode::kInvalidArgument, "(0, 20]", base);
  expect_error({.speed_mps = 2, .theta_rad = DegToRad(90)}, absl::StatusCode::kInvalidArgument,
               "theta_deg", base);
  expect_error({.speed_mps = 2, .a = 0.5, .b = 0.3}, absl::StatusCode::kInvalidArgument,
               "miscue", base);
  expect_error({.speed_mps = 2, .a = NAN}, absl::StatusCode::kInvalidArgument, "a must", base);
  TableState off = base;
  off.balls[0].r.x() = 5.0;
  expect_error({.speed_mps = 2}, absl::StatusCode::kInvalidArgument, "not on the cloth", off);
  TableState overlap = base;
  overlap.balls[0].r = overlap.balls[1].r + Eigen::Vector3d(0.01, 0, 0);
  expect_error({.speed_mps = 2}, absl::StatusCode::kInvalidArgument, "overlap", overlap);
  TableState moving = base;
  moving.balls[3].v.x() = 0.1;
  moving.balls[3].state = MotionState::kRolling;
  expect_error({.speed_mps = 2}, absl::StatusCode::kFailedPrecondition, "moving", moving);
  TableState pocketed = base;
  pocketed.balls[0].state = MotionState::kPocketed;
  expect_error({.speed_mps = 2}, absl::StatusCode::kInvalidArgument, "pocketed", pocketed);
}

TEST(ModelTest, ParametersAndPresetsAreValidated) {
  PhysicsParams p;
  EXPECT_TRUE(SetParam("mu_slide", 0.3, &p).ok());
  EXPECT_EQ(p.mu_slide, 0.3);
  EXPECT_THAT(SetParam("mu_slide", NAN, &p).message(), HasSubstr("mu_slide must be finite"));
  EXPECT_THAT(SetParam("mu_slide", 7, &p).message(), HasSubstr("[0.01, 1]"));
  EXPECT_THAT(SetParam("nope", 1, &p).message(), HasSubstr("unknown parameter"));
  EXPECT_EQ(p.mu_slide, 0.3);  // failed calls changed nothing
  EXPECT_FALSE(MakeTablePreset("pool-10ft").ok());
  absl::StatusOr<TableSpec> spec = MakeTablePreset("pool-9ft");
  ASSERT_TRUE(spec.ok());
  spec->params.cushion_height_m = 0.07;  // above the ball
  EXPECT_THAT(TableModel::Create(*spec).status().message(), HasSubstr("cushion_height_m"));
  EXPECT_FALSE(MakeRack("chapter19", Model("pool-9ft")).ok());
  EXPECT_FALSE(MakeRack("10ball", Model("unbounded")).ok());
  // The 10-ball rack: a triangle of four rows, the 1 on the foot spot, the 10 in the centre of
  // the third row, touching neighbours two radii apart.
  absl::StatusOr<std::vector<Ball>> ten = MakeRack("10ball", Model("pool-9ft"));
  ASSERT_TRUE(ten.ok()) << ten.status();
  ASSERT_EQ(ten->size(), 11u);
  const TableModel pool = Model("pool-9ft");
  const double foot = 0.25 * pool.spec().length_m;
  const double d = 2 * pool.radius();
  const auto at = [&](std::string_view id) {
    for (const Ball& b : *ten) {
      if (b.id == id) return Eigen::Vector2d(b.r.head<2>());
    }
    return Eigen::Vector2d(NAN, NAN);
  };
  EXPECT_NEAR((at("1") - Eigen::Vector2d(foot, 0)).norm(), 0, 1e-15);
  EXPECT_NEAR((at("10") - Eigen::Vector2d(foot + 2 * d * std::sqrt(3.0) / 2, 0)).norm(), 0, 1e-15);
  EXPECT_NEAR((at("1") - at("2")).norm(), d, 1e-12);
  EXPECT_NEAR((at("cue") - Eigen::Vector2d(-foot, 0)).norm(), 0, 1e-15);
  // Every preset with pockets has six, each wider than a ball.
  for (std::string_view name : {"pool-7ft", "pool-8ft", "pool-9ft", "snooker"}) {
    const TableModel m = Model(name);
    EXPECT_EQ(m.spec().pockets.size(), 6u) << name;
  }
}

TEST(RackTest, RacksAreTightOrJitteredWithoutOverlap) {
  const TableModel m = Model("pool-9ft");
  absl::StatusOr<std::vector<Ball>> tight = MakeRack("8ball", m);
  ASSERT_TRUE(tight.ok());
  ASSERT_EQ(tight->size(), 16u);
  // Tight: the apex ball touches both balls behind it.
  EXPECT_NEAR((tight->at(1).r - tight->at(2).r).norm(), 2 * m.radius(), 1e-12);
  absl::StatusOr<std::vector<Ball>> j1 = MakeRack("8ball", m, 0.001, 42);
  absl::StatusOr<std::vector<Ball>> j2 = MakeRack("8ball", m, 0.001, 42);
  absl::StatusOr<std::vector<Ball>> j3 = MakeRack("8ball", m, 0.001, 43);
  ASSERT_TRUE(j1.ok() && j2.ok() && j3.ok());
  EXPECT_EQ(j1->at(5).r, j2->at(5).r);
  EXPECT_NE(j1->at(5).r, j3->at(5).r);
  for (size_t a = 1; a < j1->size(); ++a) {
    for (size_t b = a + 1; b < j1->size(); ++b) {
      EXPECT_GE((j1->at(a).r - j1->at(b).r).norm(), 2 * m.radius());
    }
  }
}

}  // namespace
}  // namespace sportsim::billiards
