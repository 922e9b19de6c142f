// The real server in-process on an ephemeral loopback port, called through generated stubs.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include "gmock/gmock.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "gtest/gtest.h"
#include "server/billiards/convert.h"
#include "server/app/server_app.h"
#include "server/swing/convert.h"
#include "sim/billiards/shot.h"
#include "sportsim/v1/billiards.grpc.pb.h"
#include "sportsim/v1/common.grpc.pb.h"
#include "sportsim/v1/swing.grpc.pb.h"

namespace sportsim::server {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;

class ServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // The CPU budget is lifted: the shutdown tests' long calls must outlast a sanitizer build's
    // slowdown (5x-10x) without the budget ending them first. The budget has tests of its own.
    ServerConfig config{.listen = "127.0.0.1:0"};
    config.work.cpu_budget = absl::Minutes(5);
    absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start(config);
    ASSERT_TRUE(app.ok()) << app.status();
    app_ = *std::move(app);
    channel_ = grpc::CreateChannel(app_->address(), grpc::InsecureChannelCredentials());
  }
  std::unique_ptr<grpc::ClientContext> Ctx(
      std::chrono::seconds deadline = std::chrono::seconds(30)) {
    auto c = std::make_unique<grpc::ClientContext>();
    c->set_deadline(std::chrono::system_clock::now() + deadline);
    return c;
  }
  // A SimulateSwing of `steps` rk4 steps (1e-6 s each) on its own thread, and shutdown of the
  // server with `grace` once the call has run 200 ms. Fails the test if the call had already
  // ended by then: a shutdown test whose call was not in flight would test nothing.
  struct LongCall {
    grpc::Status status;
    v1::SimulateSwingResponse response;
    double shutdown_wait_s = 0;
  };
  LongCall ShutdownDuringCall(double dt_s, absl::Duration grace) {
    auto stub = v1::Swing::NewStub(channel_);
    v1::SimulateSwingRequest req;
    req.mutable_solver()->set_dt_s(dt_s);
    req.set_stop(v1::SWING_STOP_DURATION);
    req.set_duration_s(10);
    LongCall out;
    std::atomic<bool> done{false};
    std::thread call([&] {
      // A deadline past any grace used here: a sanitizer build on a loaded machine runs the
      // call 10x-50x slower, and only the shutdown may end it.
      out.status = stub->SimulateSwing(Ctx(std::chrono::minutes(5)).get(), req, &out.response);
      done = true;
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    EXPECT_FALSE(done) << "the call ended before shutdown: make it longer";
    const auto t0 = std::chrono::steady_clock::now();
    app_->Shutdown(grace);
    app_->Wait();
    out.shutdown_wait_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    call.join();
    return out;
  }
  std::unique_ptr<ServerApp> app_;
  std::shared_ptr<grpc::Channel> channel_;
};

TEST_F(ServerTest, GetInfoReportsBuildAndCapabilities) {
  auto stub = v1::Server::NewStub(channel_);
  v1::GetInfoResponse info;
  ASSERT_TRUE(stub->GetInfo(Ctx().get(), {}, &info).ok());
  EXPECT_EQ(info.version(), "0.1.0");
  EXPECT_FALSE(info.build_type().empty());
  EXPECT_FALSE(info.compiler().empty());
  EXPECT_EQ(info.grpc_version(), "1.51.1");
  const v1::Capabilities& c = info.capabilities();
  EXPECT_THAT(c.swing_integrators(), ::testing::ElementsAre("book", "euler", "semi_implicit_euler", "rk4", "dp45"));
  EXPECT_THAT(c.services(), Contains("sportsim.v1.Swing"));
  EXPECT_EQ(c.swing_parameters_size(), 11);
}

TEST_F(ServerTest, GetInfoListsTheBilliardsCapabilities) {
  auto stub = v1::Server::NewStub(channel_);
  v1::GetInfoResponse info;
  ASSERT_TRUE(stub->GetInfo(Ctx().get(), {}, &info).ok());
  const v1::Capabilities& c = info.capabilities();
  EXPECT_THAT(c.services(), Contains("sportsim.v1.Billiards"));
  // The default engine first.
  EXPECT_THAT(c.engines(), ::testing::ElementsAre("event", "stepped"));
  EXPECT_THAT(c.integrators(), ::testing::ElementsAre("euler", "semi_implicit_euler", "rk4"));
  EXPECT_THAT(c.table_presets(), ::testing::UnorderedElementsAre(
                                     "pool-7ft", "pool-8ft", "pool-9ft", "snooker", "carom",
                                     "unbounded"));
  EXPECT_THAT(c.racks(), ::testing::UnorderedElementsAre("empty", "8ball", "9ball", "10ball",
                                                         "snooker", "three-cushion", "chapter19"));
  EXPECT_THAT(c.presets(), ::testing::ElementsAreArray(c.table_presets()));
  // The documented effects (docs/cli.md) for --disable.
  EXPECT_THAT(c.effects(), ::testing::UnorderedElementsAre(
                               "drag", "spin_decay", "rolling_resistance", "ball_friction",
                               "cushions", "pockets", "orientation", "squirt"));
  // docs/cli.md: at least these parameters, each with a unit (where it has one), a default
  // inside its range, and a description.
  std::map<std::string, v1::ParameterInfo> params;
  for (const v1::ParameterInfo& p : c.parameters()) {
    EXPECT_TRUE(params.emplace(p.name(), p).second) << "listed twice: " << p.name();
    EXPECT_LE(p.min_value(), p.default_value()) << p.name();
    EXPECT_LE(p.default_value(), p.max_value()) << p.name();
    EXPECT_FALSE(p.description().empty()) << p.name();
  }
  for (const char* name : {"gravity_mps2", "mu_slide", "mu_roll", "spin_decel_rps2", "e_ball",
                           "e_cushion", "f_cushion", "ball_radius_m", "ball_mass_kg",
                           "cue_mass_kg"}) {
    EXPECT_TRUE(params.count(name)) << "GetInfo does not list parameter " << name;
  }
  if (params.count("gravity_mps2")) {
    EXPECT_EQ(params["gravity_mps2"].default_value(), 9.81);
    EXPECT_EQ(params["gravity_mps2"].unit(), "m/s^2");
  }
  for (const auto& [name, unit] : {std::pair<const char*, const char*>{"ball_radius_m", "m"},
                                    {"ball_mass_kg", "kg"}, {"cue_mass_kg", "kg"}}) {
    if (params.count(name)) {
      EXPECT_EQ(params[name].unit(), unit) << name;
    }
  }
}

// A straight 2 m/s shot on an otherwise empty pool-9ft: cue at (-0.5, 0), ball 1 at (0, 0).
v1::SimulateShotRequest StraightShot() {
  v1::SimulateShotRequest req;
  req.mutable_table()->set_preset("pool-9ft");
  req.mutable_table()->set_rack("empty");
  for (const auto& [id, x] : {std::pair<const char*, double>{"cue", -0.5}, {"1", 0.0}}) {
    v1::BallPlacement* b = req.mutable_table()->add_balls();
    b->set_id(id);
    b->set_x_m(x);
    b->set_y_m(0.0);
  }
  req.mutable_strike()->set_ball_speed_mps(2.0);
  req.mutable_strike()->set_phi_deg(0.0);
  return req;
}

TEST_F(ServerTest, SimulateShotComesToRest) {
  auto stub = v1::Billiards::NewStub(channel_);
  v1::SimulateShotResponse resp;
  const grpc::Status s = stub->SimulateShot(Ctx().get(), StraightShot(), &resp);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_TRUE(resp.at_rest());
  EXPECT_GT(resp.t_rest_s(), 0.0);
  EXPECT_LT(resp.t_rest_s(), 600.0);
  ASSERT_EQ(resp.balls_size(), 2);
  for (const v1::BallState& b : resp.balls()) EXPECT_EQ(b.state(), v1::stationary) << b.id();
  EXPECT_GT(resp.balls(1).x_m(), 0.0);  // ball 1 went +x
  ASSERT_GT(resp.events_size(), 0);
  EXPECT_EQ(resp.engine(), "event");
  EXPECT_GE(resp.cpu_s(), 0.0);
  EXPECT_FALSE(resp.has_geometry());
}

TEST_F(ServerTest, SimulateShotIsDeterministicAndBitIdenticalToTheLibrary) {
  auto stub = v1::Billiards::NewStub(channel_);
  v1::SimulateShotRequest req = StraightShot();
  req.set_sample_rate_hz(240);
  req.set_include_geometry(true);
  v1::SimulateShotResponse first, second;
  ASSERT_TRUE(stub->SimulateShot(Ctx().get(), req, &first).ok());
  ASSERT_TRUE(stub->SimulateShot(Ctx().get(), req, &second).ok());
  ASSERT_GT(first.samples_size(), 0);
  first.clear_cpu_s();
  second.clear_cpu_s();
  EXPECT_EQ(first.SerializeAsString(), second.SerializeAsString());

  absl::StatusOr<ShotJob> job = ShotJobFromProto(req);
  ASSERT_TRUE(job.ok()) << job.status();
  absl::StatusOr<billiards::ShotResult> direct =
      billiards::SimulateShot(job->table.model, job->solver, job->table.state, job->shot);
  ASSERT_TRUE(direct.ok()) << direct.status();
  v1::SimulateShotResponse expected;
  ShotResultToProto(*job, *direct, &expected);
  expected.clear_cpu_s();
  EXPECT_EQ(first.SerializeAsString(), expected.SerializeAsString());

  // The break of the default table (many collisions) too.
  v1::SimulateShotRequest brk;
  brk.mutable_strike()->set_speed_mps(8.0);
  brk.mutable_strike()->set_b(-0.2);
  ASSERT_TRUE(stub->SimulateShot(Ctx().get(), brk, &first).ok());
  ASSERT_TRUE(stub->SimulateShot(Ctx().get(), brk, &second).ok());
  EXPECT_GT(first.events_size(), 20);
  first.clear_cpu_s();
  second.clear_cpu_s();
  EXPECT_EQ(first.SerializeAsString(), second.SerializeAsString());
}

// A trajectory over the sample cap is refused, and the message names the request's field.
TEST_F(ServerTest, TooManySamplesIsResourceExhaustedNamingTheField) {
  auto stub = v1::Billiards::NewStub(channel_);
  v1::SimulateShotRequest req;
  req.mutable_table()->set_preset("unbounded");  // the chapter scene: about 33 s to rest
  req.mutable_strike()->set_ball_speed_mps(7);
  req.mutable_solver()->set_dt_s(1e-4);
  req.set_sample_rate_hz(10000);  // 330000 samples, over the 200000 cap
  v1::SimulateShotResponse resp;
  const grpc::Status s = stub->SimulateShot(Ctx().get(), req, &resp);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << s.error_message();
  // Regression: the message once named sample_interval_s, a field the API does not have.
  EXPECT_THAT(s.error_message(), HasSubstr("sample_rate_hz"));
}

TEST_F(ServerTest, InvalidShotIsInvalidArgumentNamingTheField) {
  auto stub = v1::Billiards::NewStub(channel_);
  v1::SimulateShotResponse resp;
  v1::SimulateShotRequest req = StraightShot();
  req.mutable_table()->set_preset("pool-10ft");
  grpc::Status s = stub->SimulateShot(Ctx().get(), req, &resp);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("table.preset"));

  req = StraightShot();
  req.mutable_strike()->set_a(0.6);
  s = stub->SimulateShot(Ctx().get(), req, &resp);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("miscue"));

  req = StraightShot();
  req.mutable_table()->mutable_balls(1)->set_x_m(std::nan(""));
  s = stub->SimulateShot(Ctx().get(), req, &resp);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("table.balls[1]"));

  req = StraightShot();
  req.mutable_solver()->set_engine(v1::ENGINE_EVENT);
  req.mutable_solver()->add_enable("drag");
  s = stub->SimulateShot(Ctx().get(), req, &resp);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("drag"));
}

// The event engine and the stepped engine (rk4, exact without drag) agree on a shot.
TEST_F(ServerTest, EventAndSteppedEnginesAgree) {
  auto stub = v1::Billiards::NewStub(channel_);
  v1::SimulateShotResponse ev, st;
  v1::SimulateShotRequest req = StraightShot();
  req.mutable_solver()->set_engine(v1::ENGINE_EVENT);
  ASSERT_TRUE(stub->SimulateShot(Ctx().get(), req, &ev).ok());
  req.mutable_solver()->set_engine(v1::ENGINE_STEPPED);
  ASSERT_TRUE(stub->SimulateShot(Ctx().get(), req, &st).ok());
  ASSERT_EQ(ev.balls_size(), st.balls_size());
  EXPECT_EQ(ev.events_size(), st.events_size());
  for (int i = 0; i < ev.balls_size(); ++i) {
    // Both exact up to rounding and the stepped engine's 1e-13 s contact tolerance.
    EXPECT_NEAR(ev.balls(i).x_m(), st.balls(i).x_m(), 1e-9) << i;
    EXPECT_NEAR(ev.balls(i).y_m(), st.balls(i).y_m(), 1e-9) << i;
  }
}

TEST_F(ServerTest, HealthIsServing) {
  auto stub = grpc::health::v1::Health::NewStub(channel_);
  grpc::health::v1::HealthCheckResponse r;
  ASSERT_TRUE(stub->Check(Ctx().get(), {}, &r).ok());
  EXPECT_EQ(r.status(), grpc::health::v1::HealthCheckResponse::SERVING);
}

TEST_F(ServerTest, SimulateSwingIsBitIdenticalToTheLibrary) {
  auto stub = v1::Swing::NewStub(channel_);
  v1::SimulateSwingRequest req;
  req.mutable_solver()->set_integrator(v1::SWING_INTEGRATOR_RK4);
  req.mutable_solver()->set_dt_s(0.0025);
  v1::SimulateSwingResponse resp;
  ASSERT_TRUE(stub->SimulateSwing(Ctx().get(), req, &resp).ok());
  ASSERT_TRUE(resp.has_impact());

  absl::StatusOr<SwingJob> job = SwingJobFromProto(req);
  ASSERT_TRUE(job.ok());
  absl::StatusOr<swing::SwingRunResult> direct =
      swing::SimulateSwing(job->model, job->program, job->solver, job->run);
  ASSERT_TRUE(direct.ok());
  v1::SimulateSwingResponse expected;
  SwingResultToProto(*direct, resp.cpu_s(), &expected);
  EXPECT_EQ(resp.SerializeAsString(), expected.SerializeAsString());
  EXPECT_NEAR(resp.impact().t_s(), 0.291391708, 1e-7);
  EXPECT_GT(resp.cpu_s(), 0.0);
}

TEST_F(ServerTest, InvalidSwingIsInvalidArgumentNamingTheField) {
  auto stub = v1::Swing::NewStub(channel_);
  v1::SimulateSwingRequest req;
  req.mutable_parameters()->set_arm_length_m(std::nan(""));
  v1::SimulateSwingResponse resp;
  const grpc::Status s = stub->SimulateSwing(Ctx().get(), req, &resp);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("parameters.arm_length_m"));

  req.Clear();
  req.mutable_solver()->set_dt_s(0.05);  // under-resolved: a clear error, not numbers
  const grpc::Status s2 = stub->SimulateSwing(Ctx().get(), req, &resp);
  EXPECT_EQ(s2.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s2.error_message(), HasSubstr("dt_s = 0.05 s is too large"));
}

TEST_F(ServerTest, OversizedRequestIsResourceExhausted) {
  auto stub = v1::Swing::NewStub(channel_);
  v1::SimulateSwingRequest req;
  auto* qa = req.mutable_torques()->mutable_qalpha();
  for (int i = 0; i < 100000; ++i) {  // ~2 MB, over the 1 MiB request limit
    auto* k = qa->add_knots();
    k->set_t_s(i);
    k->set_torque_nm(1);
  }
  v1::SimulateSwingResponse resp;
  const grpc::Status s = stub->SimulateSwing(Ctx().get(), req, &resp);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
}

TEST_F(ServerTest, SecondServerOnABusyPortFailsClearly) {
  absl::StatusOr<std::unique_ptr<ServerApp>> second =
      ServerApp::Start({.listen = app_->address()});
  ASSERT_FALSE(second.ok());
  EXPECT_EQ(second.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(second.status().message(), HasSubstr("cannot listen on"));
  EXPECT_THAT(second.status().message(), HasSubstr("in use"));
}

TEST_F(ServerTest, ShutdownLetsAnInFlightCallFinish) {
  // 2e6 rk4 steps (~0.5 s; 4 s under ASan, 20 s and more when the machine is busy): in flight
  // at shutdown, inside the grace. The grace is long because the test waits only as long as
  // the call runs.
  const LongCall c = ShutdownDuringCall(5e-6, absl::Minutes(4));
  EXPECT_TRUE(c.status.ok()) << c.status.error_message();
  EXPECT_EQ(c.response.end_t_s(), 10.0);
}

// Idle connections do not hold the shutdown: gRPC waits for every connection to close, and a
// client that keeps its channel open (or a socket that never speaks) would otherwise keep a
// SIGTERM waiting the whole grace. The grace here is a minute; the shutdown ends in seconds.
TEST(ServerShutdownTest, IdleConnectionsDoNotHoldTheGrace) {
  ServerConfig config{.listen = "127.0.0.1:0", .http_listen = "127.0.0.1:0"};
  absl::StatusOr<std::unique_ptr<ServerApp>> started = ServerApp::Start(config);
  ASSERT_TRUE(started.ok()) << started.status();
  std::unique_ptr<ServerApp> app = *std::move(started);
  // Three connected channels, each idle after one call.
  std::vector<std::shared_ptr<grpc::Channel>> channels;
  for (int i = 0; i < 3; ++i) {
    grpc::ChannelArguments args;
    args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);  // a connection each
    channels.push_back(grpc::CreateCustomChannel(app->address(),
                                                 grpc::InsecureChannelCredentials(), args));
    grpc::ClientContext ctx;
    v1::GetInfoResponse info;
    ASSERT_TRUE(v1::Server::NewStub(channels.back())->GetInfo(&ctx, {}, &info).ok());
  }
  // A raw socket on each port that never sends a byte.
  std::vector<int> sockets;
  for (int port : {app->port(), app->http_port()}) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    ASSERT_GE(fd, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<uint16_t>(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
    sockets.push_back(fd);
  }
  const auto t0 = std::chrono::steady_clock::now();
  app->Shutdown(absl::Minutes(1));
  app->Wait();
  const double waited_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("shutdown with 3 idle channels and 2 silent sockets: %.3f s (grace 60 s)\n",
              waited_s);
  EXPECT_LT(waited_s, 20.0) << "idle connections held the shutdown's grace";
  for (int fd : sockets) ::close(fd);
}

TEST_F(ServerTest, SimulateFlightIsBitIdenticalToTheLibrary) {
  auto stub = v1::Swing::NewStub(channel_);
  v1::SimulateFlightRequest req;
  req.mutable_launch()->set_ball_speed_mps(60);
  req.mutable_launch()->set_launch_angle_deg(14);
  req.mutable_launch()->set_spin_rpm(4000);
  req.mutable_launch()->set_spin_axis_deg(5);
  req.mutable_wind()->set_speed_mps(3);
  v1::SimulateFlightResponse resp;
  ASSERT_TRUE(stub->SimulateFlight(Ctx().get(), req, &resp).ok());
  absl::StatusOr<FlightJob> job = FlightJobFromProto(req);
  ASSERT_TRUE(job.ok());
  absl::StatusOr<golf::FlightResult> direct =
      golf::SimulateFlight(job->ball, job->launch, job->atmosphere, job->wind, job->options);
  ASSERT_TRUE(direct.ok());
  v1::SimulateFlightResponse expected;
  FlightResultToProto(*direct, resp.cpu_s(), &expected);
  EXPECT_EQ(resp.SerializeAsString(), expected.SerializeAsString());
  EXPECT_GT(resp.lateral_m(), 0.0);  // positive axis tilt curves right
  EXPECT_GT(resp.samples_size(), 100);

  req.mutable_launch()->set_spin_rpm(std::nan(""));
  const grpc::Status bad = stub->SimulateFlight(Ctx().get(), req, &resp);
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(bad.error_message(), HasSubstr("launch.spin_rpm"));
}

TEST_F(ServerTest, SimulateSwingLaunchesAndFliesTheBallFromItsImpact) {
  // The chapter's swing hits a 7-iron: the ball's launch is the library's oblique impact of the
  // swing's own impact (ground speed, attack angle from the ground velocity), and the flight is
  // SimulateFlight of that launch, bit for bit.
  auto stub = v1::Swing::NewStub(channel_);
  v1::SimulateSwingRequest req;
  req.mutable_solver()->set_integrator(v1::SWING_INTEGRATOR_RK4);
  req.mutable_solver()->set_dt_s(0.0025);
  req.mutable_ball()->set_club("7-iron");
  req.mutable_ball()->set_face_angle_deg(2);
  req.mutable_ball()->set_sample_interval_s(0.05);
  v1::SimulateSwingResponse resp;
  ASSERT_TRUE(stub->SimulateSwing(Ctx().get(), req, &resp).ok());
  ASSERT_TRUE(resp.has_impact());
  ASSERT_TRUE(resp.has_ball());
  const v1::BallLaunch& ball = resp.ball();
  EXPECT_EQ(ball.error(), "");
  EXPECT_EQ(ball.club(), "7-iron");
  EXPECT_EQ(ball.clubhead_speed_mps(), resp.impact().clubhead_speed_ground_mps());
  EXPECT_EQ(ball.attack_angle_deg(), resp.impact().clubhead_direction_deg());

  absl::StatusOr<golf::ClubSpec> club = golf::ClubPreset("7-iron");
  ASSERT_TRUE(club.ok());
  absl::StatusOr<golf::ImpactResult> hit = golf::SimulateImpact(
      {.clubhead_speed_mps = ball.clubhead_speed_mps(),
       .attack_angle_deg = ball.attack_angle_deg(),
       .face_angle_deg = 2},
      *club, {});
  ASSERT_TRUE(hit.ok()) << hit.status();
  EXPECT_EQ(ball.launch().ball_speed_mps(), hit->launch.ball_speed_mps);
  EXPECT_EQ(ball.launch().launch_angle_deg(), hit->launch.launch_angle_deg);
  EXPECT_EQ(ball.launch().spin_rpm(), hit->launch.spin_rpm);
  EXPECT_EQ(ball.launch().spin_axis_deg(), hit->launch.spin_axis_deg);
  EXPECT_EQ(ball.smash_factor(), hit->smash_factor);
  // An open face starts the ball right of the target.
  EXPECT_GT(ball.launch().launch_direction_deg(), 0.0);

  v1::SimulateFlightRequest flight;
  *flight.mutable_launch() = ball.launch();
  flight.set_sample_interval_s(0.05);
  absl::StatusOr<FlightJob> job = FlightJobFromProto(flight);
  ASSERT_TRUE(job.ok()) << job.status();
  absl::StatusOr<golf::FlightResult> direct =
      golf::SimulateFlight(job->ball, job->launch, job->atmosphere, job->wind, job->options);
  ASSERT_TRUE(direct.ok());
  v1::SimulateFlightResponse expected;
  FlightResultToProto(*direct, ball.flight().cpu_s(), &expected);
  EXPECT_EQ(ball.flight().SerializeAsString(), expected.SerializeAsString());
  EXPECT_GT(ball.flight().carry_m(), 50.0);

  // Without `ball`, no ball.
  req.clear_ball();
  ASSERT_TRUE(stub->SimulateSwing(Ctx().get(), req, &resp).ok());
  EXPECT_FALSE(resp.has_ball());
}

TEST_F(ServerTest, SimulateSwingRefusesABadBallStrikeNamingTheField) {
  auto stub = v1::Swing::NewStub(channel_);
  struct Case {
    void (*edit)(v1::BallStrike*);
    const char* field;
  };
  const Case cases[] = {
      {[](v1::BallStrike* b) { b->set_club("putter"); }, "ball.club"},
      {[](v1::BallStrike* b) { b->set_face_angle_deg(std::nan("")); }, "ball."},
      {[](v1::BallStrike* b) { b->set_face_angle_deg(80); }, "face_angle"},
      {[](v1::BallStrike* b) { b->set_cor(1.5); }, "ball.cor"},
      {[](v1::BallStrike* b) { b->mutable_atmosphere()->set_altitude_m(1e6); },
       "ball.atmosphere.altitude_m"},
      {[](v1::BallStrike* b) { b->set_aero_fit(static_cast<v1::AeroFit>(9)); }, "ball.aero_fit"},
      {[](v1::BallStrike* b) { b->set_sample_interval_s(-1); }, "ball.sample_interval_s"},
      {[](v1::BallStrike* b) { b->mutable_wind()->set_speed_mps(std::nan("")); },
       "ball.wind speed_mps"},
      {[](v1::BallStrike* b) { b->mutable_wind()->set_speed_mps(500); }, "ball.wind speed_mps"},
      {[](v1::BallStrike* b) { b->add_disabled_flight_effects(static_cast<v1::FlightEffect>(42)); },
       "ball.disabled_flight_effects[0]"},
  };
  for (const Case& c : cases) {
    v1::SimulateSwingRequest req;
    c.edit(req.mutable_ball());
    v1::SimulateSwingResponse resp;
    const grpc::Status s = stub->SimulateSwing(Ctx().get(), req, &resp);
    EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << c.field;
    EXPECT_THAT(s.error_message(), HasSubstr(c.field));
  }
}

// Shutdown with a short grace cancels a long call, and the run notices (it polls IsCancelled):
// the server stops within the grace plus one poll, not when the simulation would have ended.
TEST_F(ServerTest, ShutdownGraceCancelsALongRun) {
  // 1e7 rk4 steps (~2.5 s if left alone) against a 100 ms grace.
  const LongCall c = ShutdownDuringCall(1e-6, absl::Milliseconds(100));
  EXPECT_FALSE(c.status.ok());
  EXPECT_LT(c.shutdown_wait_s, 1.5);
}

TEST(ListenAddressTest, ParsesAndRejects) {
  EXPECT_EQ(ParseListenAddress("127.0.0.1:50051")->port, 50051);
  EXPECT_EQ(ParseListenAddress("[::1]:0")->host, "::1");
  EXPECT_EQ(ParseListenAddress("localhost:80")->host, "localhost");
  for (const char* bad : {"localhost", "127.0.0.1:", "127.0.0.1:99999", ":80", "::1:80",
                          "[::1]80", "127.0.0.1:8o", "127.0.0.1:-1"}) {
    absl::StatusOr<ListenAddress> a = ParseListenAddress(bad);
    EXPECT_FALSE(a.ok()) << bad;
    EXPECT_THAT(a.status().message(), HasSubstr("--listen must be host:port")) << bad;
  }
}

}  // namespace
}  // namespace sportsim::server
