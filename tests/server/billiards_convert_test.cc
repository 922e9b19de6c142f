#include "server/billiards/convert.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "sim/billiards/shot.h"

namespace sportsim::server {
namespace {

namespace b = ::sportsim::billiards;
using ::testing::HasSubstr;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

void Place(v1::SimulateShotRequest* r, const std::string& id, double x, double y) {
  v1::BallPlacement* p = r->mutable_table()->add_balls();
  p->set_id(id);
  p->set_x_m(x);
  p->set_y_m(y);
}

// The smallest valid request: the default table (pool-9ft, 8ball rack) and a 2 m/s strike.
v1::SimulateShotRequest Strike2() {
  v1::SimulateShotRequest r;
  r.mutable_strike()->set_ball_speed_mps(2.0);
  return r;
}

// A straight full-ball shot on an otherwise empty pool-9ft: cue at (-0.5, 0), ball 1 at (0, 0).
v1::SimulateShotRequest StraightShot() {
  v1::SimulateShotRequest r;
  r.mutable_table()->set_preset("pool-9ft");
  r.mutable_table()->set_rack("empty");
  Place(&r, "cue", -0.5, 0.0);
  Place(&r, "1", 0.0, 0.0);
  r.mutable_strike()->set_ball_speed_mps(2.0);
  return r;
}

// The default engine is the event engine; asking for drag without naming an engine picks the
// stepped engine (drag has no closed form), while naming the event engine with drag is an error
// (tested with the rejections below).
// A strike written by StrikeToProto reads back as itself (to the degree-radian rounding), with
// the cue's speed or the ball's as it was.
TEST(BilliardsConvertTest, StrikesRoundTrip) {
  for (bool ball_speed : {false, true}) {
    b::CueStrike s;
    s.ball_speed = ball_speed;
    s.speed_mps = 2.75;
    s.phi_rad = -1.234;
    s.theta_rad = 0.2;
    s.a = 0.31;
    s.b = -0.17;
    v1::CueStrike p;
    StrikeToProto(s, &p);
    EXPECT_EQ(p.has_ball_speed_mps(), ball_speed);
    absl::StatusOr<b::CueStrike> back = StrikeFromProto(p);
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(back->ball_speed, ball_speed);
    EXPECT_EQ(back->speed_mps, 2.75);
    EXPECT_NEAR(back->phi_rad, -1.234, 1e-15);
    EXPECT_NEAR(back->theta_rad, 0.2, 1e-15);
    EXPECT_EQ(back->a, 0.31);
    EXPECT_EQ(back->b, -0.17);
  }
}

TEST(BilliardsConvertTest, DragWithoutAnEngineNamedRunsStepped) {
  v1::SimulateShotRequest r = Strike2();
  r.mutable_solver()->add_enable("drag");
  absl::StatusOr<ShotJob> job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->solver.engine, b::Engine::kStepped);
  EXPECT_NE(job->solver.effects & b::kEffectEnableDrag, 0u);
  r.mutable_solver()->set_engine(v1::ENGINE_STEPPED);
  ASSERT_TRUE(ShotJobFromProto(r).ok());
}

TEST(BilliardsConvertTest, DefaultsArePool9ftWith8BallRack) {
  absl::StatusOr<ShotJob> job = ShotJobFromProto(Strike2());
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.spec().name, "pool-9ft");
  EXPECT_TRUE(job->table.model.spec().bounded);
  EXPECT_EQ(job->table.model.spec().length_m, 2.54);
  EXPECT_EQ(job->table.rack, "8ball");
  const b::TableState& s = job->table.state;
  EXPECT_EQ(s.balls.size(), 16u);  // cue and 1..15
  for (const char* id : {"cue", "1", "8", "15"}) EXPECT_GE(s.Find(id), 0) << id;
  for (const b::Ball& ball : s.balls) EXPECT_EQ(ball.r.z(), job->table.model.radius()) << ball.id;
  EXPECT_EQ(job->table.model.params().cushion_model, b::CushionModel::kHan);
  EXPECT_EQ(job->table.model.params().mu_slide, b::PhysicsParams().mu_slide);
  // Solver defaults.
  EXPECT_EQ(job->solver.engine, b::Engine::kEvent);
  EXPECT_EQ(job->solver.integrator, b::Integrator::kRk4);
  EXPECT_EQ(job->solver.dt_s, 1.0 / 960.0);
  EXPECT_TRUE(job->solver.ccd);
  EXPECT_EQ(job->solver.effects, 0u);  // default physics: drag off
  EXPECT_EQ(job->solver.max_events, 200000);
  // Run defaults.
  EXPECT_EQ(job->shot.max_time_s, 600.0);
  EXPECT_EQ(job->shot.sample_interval_s, 0.0);
  EXPECT_FALSE(job->include_geometry);
  // The strike is applied to the cue ball: 2 m/s along +x (phi 0), no squirt without english.
  ASSERT_TRUE(job->strike.has_value());
  const b::Ball& cue = s.balls[s.Find("cue")];
  EXPECT_NEAR(cue.v.x(), 2.0, 1e-12);
  EXPECT_NEAR(cue.v.y(), 0.0, 1e-12);
  EXPECT_NE(cue.state, b::MotionState::kStationary);
  for (const b::Ball& ball : s.balls) {
    if (ball.id != "cue") {
      EXPECT_EQ(ball.v.norm(), 0.0) << ball.id;
    }
  }
}

TEST(BilliardsConvertTest, PlacedBallMovesARackedIdOrAddsANewOne) {
  v1::SimulateShotRequest r = Strike2();
  Place(&r, "cue", -0.8, 0.2);  // racked: moves
  Place(&r, "x", -0.8, -0.3);   // new: added after the rack
  absl::StatusOr<ShotJob> job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  const b::TableState& s = job->table.state;
  ASSERT_EQ(s.balls.size(), 17u);
  const int cue = s.Find("cue");
  ASSERT_GE(cue, 0);
  EXPECT_EQ(s.balls[cue].r, Eigen::Vector3d(-0.8, 0.2, job->table.model.radius()));
  EXPECT_EQ(s.balls.back().id, "x");
  EXPECT_EQ(s.balls.back().r, Eigen::Vector3d(-0.8, -0.3, job->table.model.radius()));
  EXPECT_EQ(s.balls.back().state, b::MotionState::kStationary);
  EXPECT_EQ(std::count_if(s.balls.begin(), s.balls.end(),
                          [](const b::Ball& ball) { return ball.id == "cue"; }),
            1);
}

TEST(BilliardsConvertTest, ParamsOverrideThePresetDefaults) {
  v1::SimulateShotRequest r = Strike2();
  (*r.mutable_table()->mutable_params())["mu_slide"] = 0.3;
  (*r.mutable_table()->mutable_params())["e_ball"] = 0.9;
  (*r.mutable_table()->mutable_params())["gravity_mps2"] = 9.80665;
  absl::StatusOr<ShotJob> job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.params().mu_slide, 0.3);
  EXPECT_EQ(job->table.model.params().e_ball, 0.9);
  EXPECT_EQ(job->table.model.params().gravity_mps2, 9.80665);
  EXPECT_EQ(job->table.model.params().mu_roll, b::PhysicsParams().mu_roll);  // untouched
}

TEST(BilliardsConvertTest, BallRadiusMovesTheCushionNoseAndTheRack) {
  v1::SimulateShotRequest r = Strike2();
  (*r.mutable_table()->mutable_params())["ball_radius_m"] = 0.03;
  absl::StatusOr<ShotJob> job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.radius(), 0.03);
  EXPECT_DOUBLE_EQ(job->table.model.params().cushion_height_m, 0.635 * 2.0 * 0.03);
  for (const b::Ball& ball : job->table.state.balls) EXPECT_EQ(ball.r.z(), 0.03) << ball.id;
}

// Carom cushions have a fixed nose height (37 mm): another ball size leaves it alone (it was
// once replaced by the pool rule, 63.5 % of the diameter).
TEST(BilliardsConvertTest, BallRadiusKeepsTheCaromNose) {
  v1::SimulateShotRequest r = Strike2();
  r.mutable_table()->set_preset("carom");
  r.mutable_table()->set_rack("three-cushion");
  (*r.mutable_table()->mutable_params())["ball_radius_m"] = 0.03;
  absl::StatusOr<ShotJob> job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.params().cushion_height_m, 0.037);
}

TEST(BilliardsConvertTest, BallBallModel) {
  v1::SimulateShotRequest r = Strike2();
  absl::StatusOr<ShotJob> job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.params().ball_ball_model, b::BallBallModel::kAlciatore);
  r.mutable_table()->set_ball_ball_model(v1::BALL_BALL_MODEL_MATHAVAN_2014);
  job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.params().ball_ball_model, b::BallBallModel::kMathavan2014);
  r.mutable_table()->set_ball_ball_model(v1::BALL_BALL_MODEL_ALCIATORE);
  job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.params().ball_ball_model, b::BallBallModel::kAlciatore);
}

TEST(BilliardsConvertTest, CushionModelMirror) {
  v1::SimulateShotRequest r = Strike2();
  r.mutable_table()->set_cushion_model(v1::CUSHION_MODEL_MIRROR);
  absl::StatusOr<ShotJob> job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.params().cushion_model, b::CushionModel::kMirror);
  r.mutable_table()->set_cushion_model(v1::CUSHION_MODEL_HAN);
  job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.params().cushion_model, b::CushionModel::kHan);
  r.mutable_table()->set_cushion_model(v1::CUSHION_MODEL_MATHAVAN_2010);
  (*r.mutable_table()->mutable_params())["cushion_impulse_steps"] = 1000;
  job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.params().cushion_model, b::CushionModel::kMathavan2010);
  EXPECT_EQ(job->table.model.params().cushion_impulse_steps, 1000);
  (*r.mutable_table()->mutable_params())["cushion_impulse_steps"] = 5;
  EXPECT_THAT(ShotJobFromProto(r).status().message(), ::testing::HasSubstr("cushion_impulse_steps"));
  r.mutable_table()->clear_params();
  r.mutable_table()->set_cushion_model(v1::CUSHION_MODEL_STRONGE_COMPLIANT);
  (*r.mutable_table()->mutable_params())["cushion_poisson_ratio"] = 0.3;
  job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.params().cushion_model, b::CushionModel::kStrongeCompliant);
  EXPECT_EQ(job->table.model.params().cushion_poisson_ratio, 0.3);
  (*r.mutable_table()->mutable_params())["cushion_poisson_ratio"] = 0.6;
  EXPECT_THAT(ShotJobFromProto(r).status().message(),
              ::testing::HasSubstr("cushion_poisson_ratio"));
  // Slip-speed friction: a cloth law's switch and its accuracy, set by name like the rest.
  r.mutable_table()->clear_params();
  (*r.mutable_table()->mutable_params())["slide_fade_speed_mps"] = 0.3;
  (*r.mutable_table()->mutable_params())["slide_fade_bands"] = 8;
  job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.params().slide_fade_speed_mps, 0.3);
  EXPECT_EQ(job->table.model.params().slide_fade_bands, 8);
  (*r.mutable_table()->mutable_params())["slide_fade_bands"] = 8.5;
  absl::Status bad = ShotJobFromProto(r).status();
  EXPECT_EQ(bad.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bad.message(), ::testing::HasSubstr("slide_fade_bands must be a whole number"));
  // The cushion restitution's fall with speed, by name too; past its range, refused naming it.
  r.mutable_table()->clear_params();
  (*r.mutable_table()->mutable_params())["cushion_restitution_exponent"] = 0.5;
  job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->table.model.params().cushion_restitution_exponent, 0.5);
  (*r.mutable_table()->mutable_params())["cushion_restitution_exponent"] = -0.1;
  bad = ShotJobFromProto(r).status();
  EXPECT_EQ(bad.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bad.message(), ::testing::HasSubstr("cushion_restitution_exponent"));
}

TEST(BilliardsConvertTest, OtherPresetsTakeTheirGamesRack) {
  const std::pair<const char*, const char*> cases[] = {
      {"snooker", "snooker"}, {"carom", "three-cushion"}, {"unbounded", "chapter19"},
      {"pool-7ft", "8ball"}};
  for (const auto& [preset, rack] : cases) {
    v1::SimulateShotRequest r = Strike2();
    r.mutable_table()->set_preset(preset);
    absl::StatusOr<ShotJob> job = ShotJobFromProto(r);
    ASSERT_TRUE(job.ok()) << preset << ": " << job.status();
    EXPECT_EQ(job->table.rack, rack) << preset;
    EXPECT_EQ(job->table.model.spec().name, preset);
  }
}

TEST(BilliardsConvertTest, CarriesSolverAndRunOptions) {
  v1::SimulateShotRequest r = Strike2();
  v1::SolverConfig* s = r.mutable_solver();
  s->set_engine(v1::ENGINE_STEPPED);
  s->set_integrator(v1::BILLIARDS_INTEGRATOR_SEMI_IMPLICIT_EULER);
  s->set_dt_s(0.002);
  s->set_no_ccd(true);
  s->add_disable("cushions");
  s->add_disable("pockets");
  s->add_enable("drag");
  s->set_max_events(1000);
  r.set_sample_rate_hz(100);
  r.set_max_time_s(5);
  r.set_include_geometry(true);
  absl::StatusOr<ShotJob> job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->solver.engine, b::Engine::kStepped);
  EXPECT_EQ(job->solver.integrator, b::Integrator::kSemiImplicitEuler);
  EXPECT_EQ(job->solver.dt_s, 0.002);
  EXPECT_FALSE(job->solver.ccd);
  EXPECT_EQ(job->solver.effects, static_cast<uint32_t>(b::kEffectDisableCushions |
                                                      b::kEffectDisablePockets |
                                                      b::kEffectEnableDrag));
  EXPECT_EQ(job->solver.max_events, 1000);
  EXPECT_DOUBLE_EQ(job->shot.sample_interval_s, 0.01);
  EXPECT_EQ(job->shot.max_time_s, 5.0);
  EXPECT_TRUE(job->include_geometry);

  r.mutable_solver()->set_integrator(v1::BILLIARDS_INTEGRATOR_EULER);
  job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_EQ(job->solver.integrator, b::Integrator::kEuler);
}

TEST(BilliardsConvertTest, MotionsSetVelocityAndSpinWithoutAStrike) {
  v1::SimulateShotRequest r;
  v1::BallMotion* m = r.add_motions();
  m->set_id("cue");
  m->set_vx_mps(1.0);
  m->set_vy_mps(-0.5);
  m->set_wz_rps(3.0);
  absl::StatusOr<ShotJob> job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_FALSE(job->strike.has_value());
  const b::Ball& cue = job->table.state.balls[job->table.state.Find("cue")];
  EXPECT_EQ(cue.v, Eigen::Vector3d(1.0, -0.5, 0.0));
  EXPECT_EQ(cue.w, Eigen::Vector3d(0.0, 0.0, 3.0));
}

TEST(BilliardsConvertTest, StrikeOnANamedBallAndCueSpeed) {
  v1::SimulateShotRequest r;
  r.mutable_table()->set_rack("empty");
  Place(&r, "7", 0.0, 0.0);
  r.mutable_strike()->set_ball("7");
  r.mutable_strike()->set_speed_mps(2.0);  // cue speed: the ball leaves faster (M > m)
  r.mutable_strike()->set_phi_deg(90);
  absl::StatusOr<ShotJob> job = ShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  ASSERT_TRUE(job->strike.has_value());
  EXPECT_EQ(job->strike->cue_speed_mps, 2.0);
  const b::Ball& ball = job->table.state.balls[job->table.state.Find("7")];
  EXPECT_NEAR(ball.v.x(), 0.0, 1e-12);
  EXPECT_GT(ball.v.y(), 2.0);  // 2 V0 / (1 + m/M) with m/M = 0.17/0.54
}

// ---- Rejections: each one INVALID_ARGUMENT (unless said), naming the field. ----

struct BadRequest {
  const char* name;
  void (*edit)(v1::SimulateShotRequest*);
  const char* message;            // must appear in the status message
  const char* also = nullptr;     // and this too, when set
  absl::StatusCode code = absl::StatusCode::kInvalidArgument;
};

void PrintTo(const BadRequest& bad, std::ostream* os) { *os << bad.name; }

class BilliardsConvertRejectsTest : public ::testing::TestWithParam<BadRequest> {};

TEST_P(BilliardsConvertRejectsTest, InvalidArgumentNamingTheField) {
  v1::SimulateShotRequest r = Strike2();
  GetParam().edit(&r);
  absl::StatusOr<ShotJob> job = ShotJobFromProto(r);
  ASSERT_FALSE(job.ok());
  const std::string message(job.status().message());
  EXPECT_EQ(job.status().code(), GetParam().code) << message;
  EXPECT_THAT(message, HasSubstr(GetParam().message));
  if (GetParam().also != nullptr) {
    EXPECT_THAT(message, HasSubstr(GetParam().also));
  }
}

void PlaceMany(v1::SimulateShotRequest* r, int n) {
  // On a grid 0.1 m apart: no overlaps, all on the cloth.
  for (int i = 0; i < n; ++i) {
    Place(r, absl::StrCat("b", i), -1.0 + 0.1 * (i % 20), -0.5 + 0.1 * (i / 20));
  }
}

INSTANTIATE_TEST_SUITE_P(
    Fields, BilliardsConvertRejectsTest,
    ::testing::Values(
        // table
        BadRequest{"unknown_preset", [](auto* r) { r->mutable_table()->set_preset("pool-10ft"); },
                   "table.preset", "pool-10ft"},
        BadRequest{"unknown_rack", [](auto* r) { r->mutable_table()->set_rack("7ball"); },
                   "table.rack", "7ball"},
        BadRequest{"rack_does_not_fit", [](auto* r) { r->mutable_table()->set_rack("chapter19"); },
                   "table.rack", "chapter19"},
        // Regression: a bad rack with jitter was blamed on table.rack_jitter_m.
        BadRequest{"unknown_rack_with_jitter",
                   [](auto* r) {
                     r->mutable_table()->set_rack("7ball");
                     r->mutable_table()->set_rack_jitter_m(0.001);
                   },
                   "table.rack: ", "7ball"},
        BadRequest{"rack_jitter_out_of_range",
                   [](auto* r) { r->mutable_table()->set_rack_jitter_m(0.5); },
                   "table.rack_jitter_m"},
        BadRequest{"param_unknown",
                   [](auto* r) { (*r->mutable_table()->mutable_params())["mu_foo"] = 1; },
                   "table.params", "mu_foo"},
        BadRequest{"param_out_of_range",
                   [](auto* r) { (*r->mutable_table()->mutable_params())["mu_slide"] = 5; },
                   "table.params", "mu_slide must be finite and in [0.01, 1]"},
        BadRequest{"param_nan",
                   [](auto* r) { (*r->mutable_table()->mutable_params())["e_ball"] = kNan; },
                   "table.params", "e_ball must be finite"},
        BadRequest{"param_inf",
                   [](auto* r) { (*r->mutable_table()->mutable_params())["gravity_mps2"] = kInf; },
                   "table.params", "gravity_mps2 must be finite"},
        BadRequest{"unknown_cushion_model",
                   [](auto* r) {
                     // An enum value from a newer client: set through reflection, as on the wire.
                     v1::TableSetup* setup = r->mutable_table();
                     setup->GetReflection()->SetEnumValue(
                         setup, setup->GetDescriptor()->FindFieldByName("cushion_model"), 42);
                   },
                   "table.cushion_model: unknown value 42"},
        BadRequest{"unknown_ball_ball_model",
                   [](auto* r) {
                     v1::TableSetup* setup = r->mutable_table();
                     setup->GetReflection()->SetEnumValue(
                         setup, setup->GetDescriptor()->FindFieldByName("ball_ball_model"), 7);
                   },
                   "table.ball_ball_model: unknown value 7"},
        BadRequest{"ball_nan", [](auto* r) { Place(r, "cue", kNan, 0.0); }, "table.balls[0]",
                   "must be finite"},
        BadRequest{"ball_inf", [](auto* r) { Place(r, "cue", 0.0, -kInf); }, "table.balls[0]",
                   "must be finite"},
        BadRequest{"second_ball_nan",
                   [](auto* r) {
                     Place(r, "x", 0.0, 0.3);
                     Place(r, "y", kNan, kNan);
                   },
                   "table.balls[1]", "must be finite"},
        BadRequest{"ball_empty_id", [](auto* r) { Place(r, "", 0.0, 0.3); }, "table.balls[0].id"},
        BadRequest{"ball_long_id", [](auto* r) { Place(r, std::string(33, 'x'), 0.0, 0.3); },
                   "table.balls[0].id", "1 to 32 characters"},
        BadRequest{"ball_off_cloth", [](auto* r) { Place(r, "cue", 5.0, 0.0); }, "table.balls",
                   "not on the cloth"},
        BadRequest{"balls_overlap",
                   [](auto* r) {
                     r->mutable_table()->set_rack("empty");
                     Place(r, "cue", 0.0, 0.0);
                     Place(r, "1", 0.03, 0.0);  // centres 30 mm apart, diameter 57 mm
                   },
                   "table.balls", "overlap"},
        BadRequest{"placed_ball_overlaps_the_rack",
                   [](auto* r) {
                     // The 8ball rack's apex sits on the foot spot (x = L/4).
                     Place(r, "x", 2.54 / 4, 0.0);
                   },
                   "table.balls", "overlap"},
        BadRequest{"more_than_64_placed",
                   [](auto* r) {
                     r->mutable_table()->set_rack("empty");
                     PlaceMany(r, 65);
                   },
                   "table.balls", "at most 64"},
        BadRequest{"more_than_64_with_the_rack",
                   [](auto* r) { PlaceMany(r, 49); },  // 16 racked + 49 new = 65
                   "table.balls", "at most 64"},
        // solver
        BadRequest{"unknown_disable", [](auto* r) { r->mutable_solver()->add_disable("gravity"); },
                   "solver.disable", "gravity"},
        BadRequest{"unknown_enable", [](auto* r) { r->mutable_solver()->add_enable("wind"); },
                   "solver.enable", "wind"},
        BadRequest{"enable_and_disable",
                   [](auto* r) {
                     r->mutable_solver()->add_disable("cushions");
                     r->mutable_solver()->add_enable("cushions");
                   },
                   "solver", "cushions"},
        BadRequest{"dt_too_big", [](auto* r) { r->mutable_solver()->set_dt_s(0.5); },
                   "solver.dt_s must be finite and in [1e-06, 0.1]"},
        BadRequest{"dt_too_small", [](auto* r) { r->mutable_solver()->set_dt_s(1e-7); },
                   "solver.dt_s"},
        BadRequest{"dt_zero", [](auto* r) { r->mutable_solver()->set_dt_s(0); }, "solver.dt_s"},
        BadRequest{"dt_nan", [](auto* r) { r->mutable_solver()->set_dt_s(kNan); },
                   "solver.dt_s must be finite"},
        BadRequest{"max_events_zero", [](auto* r) { r->mutable_solver()->set_max_events(0); },
                   "solver.max_events"},
        BadRequest{"unknown_engine",
                   [](auto* r) {
                     v1::SolverConfig* s = r->mutable_solver();
                     s->GetReflection()->SetEnumValue(s, s->GetDescriptor()->FindFieldByName("engine"), 9);
                   },
                   "solver.engine: unknown value 9"},
        BadRequest{"unknown_integrator",
                   [](auto* r) {
                     v1::SolverConfig* s = r->mutable_solver();
                     s->GetReflection()->SetEnumValue(s, s->GetDescriptor()->FindFieldByName("integrator"), 9);
                   },
                   "solver.integrator: unknown value 9"},
        // strike
        BadRequest{"strike_without_speed",
                   [](auto* r) {
                     r->mutable_strike()->Clear();
                     r->mutable_strike()->set_phi_deg(10);
                   },
                   "strike", "speed_mps"},
        BadRequest{"strike_nan_speed", [](auto* r) { r->mutable_strike()->set_speed_mps(kNan); },
                   "strike.speed_mps must be finite"},
        BadRequest{"strike_nan_ball_speed",
                   [](auto* r) { r->mutable_strike()->set_ball_speed_mps(kNan); },
                   "strike.ball_speed_mps must be finite"},
        BadRequest{"strike_zero_speed", [](auto* r) { r->mutable_strike()->set_speed_mps(0); },
                   "strike.speed_mps"},
        BadRequest{"strike_too_fast", [](auto* r) { r->mutable_strike()->set_ball_speed_mps(25); },
                   "strike.ball_speed_mps"},
        BadRequest{"strike_phi_out_of_range",
                   [](auto* r) { r->mutable_strike()->set_phi_deg(400); }, "strike.phi_deg"},
        BadRequest{"strike_theta_out_of_range",
                   [](auto* r) { r->mutable_strike()->set_theta_deg(95); }, "strike.theta_deg"},
        BadRequest{"strike_a_out_of_range", [](auto* r) { r->mutable_strike()->set_a(1.5); },
                   "strike.a"},
        BadRequest{"strike_noise_nan", [](auto* r) { r->mutable_strike()->set_noise(kNan); },
                   "strike.noise"},
        BadRequest{"miscue", [](auto* r) { r->mutable_strike()->set_a(0.6); }, "miscue",
                   "strike"},
        BadRequest{"miscue_diagonal",
                   [](auto* r) {
                     r->mutable_strike()->set_a(0.4);
                     r->mutable_strike()->set_b(-0.4);  // 0.566 R
                   },
                   "miscue"},
        BadRequest{"strike_missing_ball", [](auto* r) { r->mutable_strike()->set_ball("ghost"); },
                   "strike.ball", "ghost"},
        BadRequest{"strike_on_an_empty_table",
                   [](auto* r) { r->mutable_table()->set_rack("empty"); }, "strike.ball", "cue"},
        // strike vs motions
        BadRequest{"strike_and_motions",
                   [](auto* r) {
                     v1::BallMotion* m = r->add_motions();
                     m->set_id("cue");
                     m->set_vx_mps(1);
                   },
                   "strike", "motions"},
        BadRequest{"neither_strike_nor_motions", [](auto* r) { r->clear_strike(); }, "strike",
                   "motions"},
        // motions
        BadRequest{"motion_nan",
                   [](auto* r) {
                     r->clear_strike();
                     v1::BallMotion* m = r->add_motions();
                     m->set_id("cue");
                     m->set_vx_mps(kNan);
                   },
                   "motions[0].vx_mps must be finite"},
        BadRequest{"motion_out_of_range",
                   [](auto* r) {
                     r->clear_strike();
                     v1::BallMotion* m = r->add_motions();
                     m->set_id("cue");
                     m->set_vy_mps(25);
                   },
                   "motions[0].vy_mps must be finite and in [-20, 20]"},
        BadRequest{"second_motion_inf",
                   [](auto* r) {
                     r->clear_strike();
                     r->add_motions()->set_id("cue");
                     v1::BallMotion* m = r->add_motions();
                     m->set_id("1");
                     m->set_vx_mps(-kInf);
                   },
                   "motions[1].vx_mps"},
        BadRequest{"motion_spin_out_of_range",
                   [](auto* r) {
                     r->clear_strike();
                     v1::BallMotion* m = r->add_motions();
                     m->set_id("cue");
                     m->set_wz_rps(3000);
                   },
                   "motions[0].wz_rps"},
        BadRequest{"motion_unknown_ball",
                   [](auto* r) {
                     r->clear_strike();
                     r->add_motions()->set_id("ghost");
                   },
                   "motions[0].id", "ghost"},
        // run options
        BadRequest{"sample_rate_too_low", [](auto* r) { r->set_sample_rate_hz(0.5); },
                   "sample_rate_hz must be finite and in [1, 10000]"},
        BadRequest{"sample_rate_too_high", [](auto* r) { r->set_sample_rate_hz(20000); },
                   "sample_rate_hz"},
        BadRequest{"sample_rate_negative", [](auto* r) { r->set_sample_rate_hz(-10); },
                   "sample_rate_hz"},
        BadRequest{"sample_rate_nan", [](auto* r) { r->set_sample_rate_hz(kNan); },
                   "sample_rate_hz"},
        BadRequest{"max_time_negative", [](auto* r) { r->set_max_time_s(-1); },
                   "max_time_s must be finite and in (0, 3600]"},
        BadRequest{"max_time_too_long", [](auto* r) { r->set_max_time_s(4000); }, "max_time_s"},
        BadRequest{"max_time_nan", [](auto* r) { r->set_max_time_s(kNan); }, "max_time_s"},
        BadRequest{"max_time_inf", [](auto* r) { r->set_max_time_s(kInf); }, "max_time_s"},
        // Regression: drag, off by default, was exempt from the conflict check, so this pair
        // silently enabled it.
        BadRequest{"drag_enabled_and_disabled",
                   [](auto* r) {
                     r->mutable_solver()->add_disable("drag");
                     r->mutable_solver()->add_enable("drag");
                   },
                   "both enabled and disabled", "drag"},
        // engines
        // Regression: the message once read "solver.the event engine ...", naming no field.
        BadRequest{"event_engine_with_drag",
                   [](auto* r) {
                     r->mutable_solver()->set_engine(v1::ENGINE_EVENT);
                     r->mutable_solver()->add_enable("drag");
                   },
                   "drag", "solver.engine"}),
    [](const auto& param_info) { return std::string(param_info.param.name); });

// ---- ShotResultToProto ----

struct ShotRun {
  std::optional<ShotJob> job;  // ShotJob has no default constructor
  b::ShotResult result;
  v1::SimulateShotResponse response;
};

ShotRun Simulate(const v1::SimulateShotRequest& request) {
  ShotRun run;
  absl::StatusOr<ShotJob> job = ShotJobFromProto(request);
  EXPECT_TRUE(job.ok()) << job.status();
  if (!job.ok()) return run;
  run.job = *std::move(job);
  absl::StatusOr<b::ShotResult> result =
      b::SimulateShot(run.job->table.model, run.job->solver, run.job->table.state, run.job->shot);
  EXPECT_TRUE(result.ok()) << result.status();
  if (!result.ok()) return run;
  run.result = *std::move(result);
  ShotResultToProto(*run.job, run.result, &run.response);
  return run;
}

TEST(BilliardsResultToProtoTest, StraightShotEventsBallsAndSamples) {
  v1::SimulateShotRequest req = StraightShot();
  req.set_sample_rate_hz(120);
  const ShotRun run = Simulate(req);
  const v1::SimulateShotResponse& out = run.response;
  ASSERT_TRUE(out.at_rest());
  EXPECT_GT(out.t_rest_s(), 0.0);
  EXPECT_EQ(out.t_rest_s(), run.result.t_rest_s);
  EXPECT_EQ(out.cpu_s(), run.result.cpu_s);
  EXPECT_EQ(out.engine(), "event");
  EXPECT_EQ(out.integrator(), "");  // the event engine has no integrator or step
  EXPECT_EQ(out.dt_s(), 0.0);

  // Balls: the final state, in the table's ball order, every one with a motion state.
  ASSERT_EQ(out.balls_size(), 2);
  EXPECT_EQ(out.balls(0).id(), "cue");
  EXPECT_EQ(out.balls(1).id(), "1");
  for (const v1::BallState& ball : out.balls()) {
    EXPECT_EQ(ball.state(), v1::stationary) << ball.id();  // at rest
    EXPECT_TRUE(ball.pocket().empty()) << ball.id();
    EXPECT_NEAR(ball.qw() * ball.qw() + ball.qx() * ball.qx() + ball.qy() * ball.qy() +
                    ball.qz() * ball.qz(),
                1.0, 1e-9);
  }
  EXPECT_GT(out.balls(1).x_m(), 0.0);  // a full-ball hit sends ball 1 along +x

  // Events: in time order, as many as the library reported.
  ASSERT_EQ(out.events_size(), static_cast<int>(run.result.events.size()));
  ASSERT_GT(out.events_size(), 0);
  for (int i = 1; i < out.events_size(); ++i) {
    EXPECT_LE(out.events(i - 1).t_s(), out.events(i).t_s()) << i;
  }
  int ball_ball = 0, transitions = 0;
  for (const v1::TableEvent& e : out.events()) {
    EXPECT_NE(e.kind(), v1::event_kind_unspecified);
    ASSERT_GE(e.balls_size(), 1);
    switch (e.kind()) {
      case v1::ball_ball:
        ++ball_ball;
        ASSERT_EQ(e.balls_size(), 2);
        ASSERT_EQ(e.after_size(), 2);
        EXPECT_EQ(e.after(0).id(), e.balls(0));
        EXPECT_EQ(e.after(1).id(), e.balls(1));
        EXPECT_FALSE(e.has_from());
        EXPECT_FALSE(e.has_to());
        break;
      case v1::transition:
        ++transitions;
        EXPECT_EQ(e.balls_size(), 1);
        ASSERT_TRUE(e.has_from());
        ASSERT_TRUE(e.has_to());
        EXPECT_NE(e.from(), e.to());
        EXPECT_NE(e.from(), v1::motion_state_unspecified);
        EXPECT_NE(e.to(), v1::motion_state_unspecified);
        EXPECT_EQ(e.after_size(), 0);
        break;
      case v1::ball_cushion:
        EXPECT_EQ(e.balls_size(), 1);
        EXPECT_TRUE(e.has_cushion());
        EXPECT_FALSE(e.cushion().empty());
        EXPECT_EQ(e.after_size(), 1);
        break;
      case v1::ball_pocket:
        EXPECT_TRUE(e.has_pocket());
        break;
      default:
        ADD_FAILURE() << "unexpected kind " << e.kind();
    }
  }
  EXPECT_GE(ball_ball, 1);
  EXPECT_GE(transitions, 2);  // each ball at least ends stationary
  // The first collision: the cue ball hits ball 1 and nearly stops (e = 0.95), ball 1 goes +x.
  const auto first = std::find_if(out.events().begin(), out.events().end(),
                                  [](const v1::TableEvent& e) { return e.kind() == v1::ball_ball; });
  ASSERT_NE(first, out.events().end());
  EXPECT_THAT(first->balls(), ::testing::ElementsAre("cue", "1"));
  EXPECT_GT(first->after(1).vx_mps(), 1.0);
  EXPECT_LT(std::abs(first->after(0).vx_mps()), 0.1 * first->after(1).vx_mps());
  EXPECT_NEAR(first->after(0).vy_mps(), 0.0, 1e-9);
  EXPECT_NEAR(first->after(1).vy_mps(), 0.0, 1e-9);
  // The cue ball travels 0.5 m less a diameter, slowing down from 2 m/s.
  EXPECT_GT(first->t_s(), (0.5 - 2 * 0.028575) / 2.0);

  // Samples: one x, y and state per ball, starting at t = 0 at the placed positions.
  ASSERT_GT(out.samples_size(), 2);
  for (const v1::ShotSample& s : out.samples()) {
    EXPECT_EQ(s.x_m_size(), out.balls_size());
    EXPECT_EQ(s.y_m_size(), out.balls_size());
    EXPECT_EQ(s.state_size(), out.balls_size());
  }
  EXPECT_EQ(out.samples(0).t_s(), 0.0);
  EXPECT_EQ(out.samples(0).x_m(0), -0.5);
  EXPECT_EQ(out.samples(0).x_m(1), 0.0);
  for (int i = 1; i < out.samples_size(); ++i) {
    EXPECT_LT(out.samples(i - 1).t_s(), out.samples(i).t_s()) << i;
  }
  const v1::ShotSample& last = out.samples(out.samples_size() - 1);
  EXPECT_EQ(last.x_m(1), out.balls(1).x_m());
  EXPECT_EQ(last.y_m(0), out.balls(0).y_m());

  // The strike report.
  ASSERT_TRUE(out.has_strike());
  EXPECT_NEAR(out.strike().ball_speed_mps(), 2.0, 1e-12);
  EXPECT_GT(out.strike().cue_speed_mps(), 0.0);
  EXPECT_EQ(out.strike().phi_deg(), 0.0);
  EXPECT_EQ(out.strike().squirt_deg(), 0.0);

  // No geometry unless asked for.
  EXPECT_FALSE(out.has_geometry());
}

TEST(BilliardsResultToProtoTest, NoSamplesUnlessAsked) {
  const ShotRun run = Simulate(StraightShot());
  EXPECT_EQ(run.response.samples_size(), 0);
  EXPECT_FALSE(run.response.has_geometry());
}

TEST(BilliardsResultToProtoTest, GeometryWhenIncluded) {
  v1::SimulateShotRequest req = StraightShot();
  req.set_include_geometry(true);
  const ShotRun run = Simulate(req);
  ASSERT_TRUE(run.response.has_geometry());
  const v1::TableGeometry& g = run.response.geometry();
  EXPECT_EQ(g.preset(), "pool-9ft");
  EXPECT_TRUE(g.bounded());
  EXPECT_EQ(g.length_m(), 2.54);
  EXPECT_EQ(g.width_m(), 1.27);
  EXPECT_EQ(g.ball_radius_m(), 0.028575);
  EXPECT_GT(g.cushion_contact_m(), 0.0);
  EXPECT_LE(g.cushion_contact_m(), g.ball_radius_m());
  EXPECT_EQ(g.pockets_size(), 6);
  EXPECT_GE(g.cushions_size(), 6);
  std::set<std::string> names;
  for (const v1::PocketCircle& p : g.pockets()) {
    EXPECT_GT(p.radius_m(), 0.0);
    names.insert(p.name());
  }
  for (const v1::CushionLine& c : g.cushions()) names.insert(c.name());
  EXPECT_EQ(names.size(), static_cast<size_t>(g.pockets_size() + g.cushions_size()));  // unique
  // Every cushion event names a cushion of the geometry.
  for (const v1::TableEvent& e : run.response.events()) {
    if (e.kind() != v1::ball_cushion) continue;
    EXPECT_TRUE(names.count(e.cushion())) << e.cushion();
  }

  v1::SimulateShotRequest open;
  open.mutable_table()->set_preset("unbounded");
  open.mutable_strike()->set_ball_speed_mps(7);
  open.set_include_geometry(true);
  const ShotRun chapter = Simulate(open);
  ASSERT_TRUE(chapter.response.has_geometry());
  EXPECT_FALSE(chapter.response.geometry().bounded());
  EXPECT_EQ(chapter.response.geometry().pockets_size(), 0);
  EXPECT_EQ(chapter.response.geometry().cushions_size(), 0);
}

TEST(BilliardsResultToProtoTest, PocketedBallNamesItsPocket) {
  // Ball 1 on the diagonal 0.2 m (in x and y) off the top-right corner, hit straight at it.
  v1::SimulateShotRequest req;
  req.mutable_table()->set_rack("empty");
  Place(&req, "cue", 1.27 - 0.5, 0.635 - 0.5);
  Place(&req, "1", 1.27 - 0.2, 0.635 - 0.2);
  req.mutable_strike()->set_ball_speed_mps(2);
  req.mutable_strike()->set_phi_deg(45);
  const ShotRun run = Simulate(req);
  ASSERT_TRUE(run.response.at_rest());
  const v1::BallState& one = run.response.balls(1);
  EXPECT_EQ(one.state(), v1::pocketed);
  EXPECT_FALSE(one.pocket().empty());
  EXPECT_NE(one.pocket(), "off_table");
  int pocket_events = 0;
  for (const v1::TableEvent& e : run.response.events()) {
    if (e.kind() != v1::ball_pocket) continue;
    ++pocket_events;
    ASSERT_EQ(e.balls_size(), 1);
    EXPECT_TRUE(e.has_pocket());
    EXPECT_EQ(e.pocket(), run.response.balls(run.job->table.state.Find(e.balls(0))).pocket());
  }
  EXPECT_GE(pocket_events, 1);
}

TEST(BilliardsResultToProtoTest, MotionsStartWithATransitionAtTimeZero) {
  v1::SimulateShotRequest req;
  req.mutable_table()->set_rack("empty");
  Place(&req, "cue", 0.0, 0.0);
  v1::BallMotion* m = req.add_motions();
  m->set_id("cue");
  m->set_vy_mps(0.5);
  const ShotRun run = Simulate(req);
  ASSERT_GT(run.response.events_size(), 0);
  const v1::TableEvent& e = run.response.events(0);
  EXPECT_EQ(e.t_s(), 0.0);
  EXPECT_EQ(e.kind(), v1::transition);
  EXPECT_THAT(e.balls(), ::testing::ElementsAre("cue"));
  ASSERT_TRUE(e.has_from() && e.has_to());
  EXPECT_EQ(e.from(), v1::stationary);
  EXPECT_EQ(e.to(), v1::sliding);
  EXPECT_FALSE(run.response.has_strike());  // no strike, no strike report
  EXPECT_TRUE(run.response.at_rest());
  EXPECT_GT(run.response.balls(0).y_m(), 0.0);
}

TEST(BilliardsResultToProtoTest, MaxTimeStopsTheRunNotAtRest) {
  v1::SimulateShotRequest req = StraightShot();
  req.set_max_time_s(0.1);  // before the cue ball reaches ball 1
  const ShotRun run = Simulate(req);
  EXPECT_FALSE(run.response.at_rest());
  EXPECT_DOUBLE_EQ(run.response.t_rest_s(), 0.1);
  EXPECT_NE(run.response.balls(0).state(), v1::stationary);
  EXPECT_GT(run.response.balls(0).vx_mps(), 0.0);
}

// GetInfo says its parameter defaults are the pool-9ft ones (billiards_convert.h, and `sportsim
// info` prints "billiards parameters (pool-9ft defaults)"): each must equal what a pool-9ft
// table actually uses.
TEST(BilliardsCapabilitiesTest, DefaultsAreThePool9ftValues) {
  v1::Capabilities caps;
  AddBilliardsCapabilities(&caps);
  absl::StatusOr<b::TableSpec> spec = b::MakeTablePreset("pool-9ft");
  ASSERT_TRUE(spec.ok());
  ASSERT_EQ(caps.parameters_size(), static_cast<int>(b::ParamInfos().size()));
  for (int i = 0; i < caps.parameters_size(); ++i) {
    const b::ParamInfo& p = b::ParamInfos()[i];
    ASSERT_EQ(caps.parameters(i).name(), p.name);
    // Regression: GetInfo once listed PhysicsParams' 0.036 m, not the preset's 0.635 * 2R.
    EXPECT_EQ(caps.parameters(i).default_value(), spec->params.*p.field) << p.name;
  }
}

TEST(BilliardsResultToProtoTest, MotionStateAndKindNamesAreTheJsonSpelling) {
  EXPECT_EQ(v1::EventKind_Name(v1::ball_ball), "ball_ball");
  EXPECT_EQ(v1::EventKind_Name(v1::ball_cushion), "ball_cushion");
  EXPECT_EQ(v1::EventKind_Name(v1::ball_pocket), "ball_pocket");
  EXPECT_EQ(v1::EventKind_Name(v1::transition), "transition");
  const std::pair<b::MotionState, const char*> states[] = {
      {b::MotionState::kStationary, "stationary"}, {b::MotionState::kSpinning, "spinning"},
      {b::MotionState::kSliding, "sliding"},       {b::MotionState::kRolling, "rolling"},
      {b::MotionState::kAirborne, "airborne"},     {b::MotionState::kPocketed, "pocketed"}};
  for (const auto& [s, name] : states) {
    EXPECT_EQ(v1::MotionState_Name(MotionStateToProto(s)), name);
    EXPECT_EQ(b::MotionStateName(s), name);
  }
}

TEST(BilliardsResultToProtoTest, SameJobSameResponse) {
  v1::SimulateShotRequest req = Strike2();  // the break: many collisions
  req.set_sample_rate_hz(60);
  ShotRun a = Simulate(req);
  ShotRun c = Simulate(req);
  a.response.clear_cpu_s();
  c.response.clear_cpu_s();
  EXPECT_EQ(a.response.SerializeAsString(), c.response.SerializeAsString());
}

}  // namespace
}  // namespace sportsim::server
