// SimulateGolfShot: the request's validation (each bad field named, nothing run), the shot run
// against the library (frames, events, the hole), and the RPC on the real server in-process.
#include "server/swing/golf_shot.h"

#include <cmath>
#include <numbers>

#include <grpcpp/grpcpp.h>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/app/server_app.h"
#include "sim/golf/course_shot.h"
#include "sim/golf/ground.h"
#include "sportsim/v1/swing.grpc.pb.h"

namespace sportsim::server {
namespace {

using ::testing::HasSubstr;

v1::SimulateGolfShotRequest Putt(double speed, double direction_deg) {
  v1::SimulateGolfShotRequest r;
  r.mutable_putt()->set_speed_mps(speed);
  r.mutable_putt()->set_direction_deg(direction_deg);
  return r;
}

std::string Error(const v1::SimulateGolfShotRequest& r) {
  absl::StatusOr<GolfShotJob> job = GolfShotJobFromProto(r);
  EXPECT_FALSE(job.ok()) << r.ShortDebugString();
  if (job.ok()) return "";
  EXPECT_EQ(job.status().code(), absl::StatusCode::kInvalidArgument);
  return std::string(job.status().message());
}

TEST(GolfShotTest, BadRequestsNameTheirField) {
  v1::SimulateGolfShotRequest r = Putt(2, 0);
  r.set_course("moon");
  EXPECT_THAT(Error(r), HasSubstr("course"));
  r = Putt(2, 0);
  r.set_stimp_ft(0.5);
  EXPECT_THAT(Error(r), HasSubstr("stimp_ft"));
  r = Putt(2, 0);
  r.set_slope_pct(NAN);
  EXPECT_THAT(Error(r), HasSubstr("slope_pct"));
  r = Putt(2, 0);
  r.set_slope_pct(9);  // a Stimp-10 green holds a ball up to 7.8 %
  EXPECT_THAT(Error(r), HasSubstr("slope_pct"));
  r = Putt(std::numeric_limits<double>::infinity(), 0);
  EXPECT_THAT(Error(r), HasSubstr("putt.speed_mps"));
  r = Putt(2, 0);
  r.set_from_x_m(0.02);
  r.set_from_y_m(0);
  EXPECT_THAT(Error(r), HasSubstr("from_x_m"));
  r = Putt(2, 0);
  r.set_course("range");
  r.set_fairway("icy");
  EXPECT_THAT(Error(r), HasSubstr("fairway"));
  r.set_course(std::string("x\n\x01y", 4) + std::string(100, 'z'));  // quoted short and clean
  const std::string quoted = Error(r);
  EXPECT_THAT(quoted, HasSubstr("course"));
  EXPECT_LT(quoted.size(), 120u);
  EXPECT_EQ(quoted.find('\n'), std::string::npos);
  r = Putt(2, 0);
  r.set_aim_deg(10);
  EXPECT_THAT(Error(r), HasSubstr("aim_deg"));
  r = Putt(2, 0);
  r.set_course("range");
  r.set_flagstick(true);
  EXPECT_THAT(Error(r), HasSubstr("flagstick"));
  v1::SimulateGolfShotRequest none;
  EXPECT_THAT(Error(none), HasSubstr("shot"));
  v1::SimulateGolfShotRequest launch;
  launch.mutable_launch()->set_ball_speed_mps(40);
  launch.mutable_launch()->set_launch_angle_deg(20);
  launch.mutable_launch()->set_spin_rpm(-5);
  EXPECT_THAT(Error(launch), HasSubstr("launch.spin_rpm"));
}

v1::SimulateGolfShotRequest OnLinks(int hole) {
  v1::SimulateGolfShotRequest r;
  r.set_course("sportsim_links");
  r.set_hole(static_cast<uint32_t>(hole));
  return r;
}

TEST(GolfShotTest, BadCourseRequestsNameTheirField) {
  v1::SimulateGolfShotRequest r = OnLinks(9);
  *r.mutable_putt() = Putt(1, 0).putt();
  EXPECT_THAT(Error(r), HasSubstr("hole: 9 is not a hole of sportsim_links (1 to 3)"));
  r = OnLinks(2);
  *r.mutable_putt() = Putt(1, 0).putt();
  r.set_tee("gold");
  EXPECT_THAT(Error(r), HasSubstr("tee: \"gold\" is not a tee of hole 2 (white, red)"));
  r.set_tee("white");
  r.set_from_x_m(1);
  EXPECT_THAT(Error(r), HasSubstr("tee: give a tee or from_x_m"));
  r = OnLinks(1);
  *r.mutable_putt() = Putt(1, 0).putt();
  r.set_stimp_ft(11);
  EXPECT_THAT(Error(r), HasSubstr("stimp_ft"));
  r = OnLinks(1);
  *r.mutable_putt() = Putt(1, 0).putt();
  r.set_from_x_m(-158);
  r.set_from_y_m(318);
  EXPECT_THAT(Error(r), HasSubstr("out of bounds"));
  r = Putt(1, 0);
  r.set_hole(2);
  EXPECT_THAT(Error(r), HasSubstr("hole, tee"));
}

// A shot on a course is PlayCourseShot's, to the bit: from the hole's tee by default, aimed at
// the pin, the course's air; its rest, lie and events reach the response.
TEST(GolfShotTest, ACourseShotIsTheLibrarysShot) {
  const golf::Course& links = **golf::BuiltinCourse("sportsim_links");
  v1::SimulateGolfShotRequest r = OnLinks(2);
  r.set_tee("white");
  v1::LaunchConditions* l = r.mutable_launch();
  l->set_ball_speed_mps(50);
  l->set_launch_angle_deg(17);
  l->set_spin_rpm(7000);
  absl::StatusOr<GolfShotJob> job = GolfShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  v1::SimulateGolfShotResponse out;
  ASSERT_TRUE(RunGolfShot(*job, {}, &out).ok());
  const golf::CourseHole& h2 = links.holes[1];
  golf::CourseShot shot;
  shot.hole = 2;
  shot.from_m = h2.tees[0].position_m;
  shot.aim_deg = std::atan2(h2.pin_m->y() - shot.from_m.y(), h2.pin_m->x() - shot.from_m.x()) /
                 (std::numbers::pi / 180);
  shot.launch = {.ball_speed_mps = 50, .launch_angle_deg = 17, .spin_rpm = 7000};
  absl::StatusOr<golf::CourseShotResult> direct = golf::PlayCourseShot(links, shot);
  ASSERT_TRUE(direct.ok()) << direct.status();
  EXPECT_EQ(out.rest().x_m(), direct->ground.rest_m.x());
  EXPECT_EQ(out.rest().y_m(), direct->ground.rest_m.y());
  EXPECT_EQ(out.rest().lie(), golf::TerrainTag(direct->lie));
  EXPECT_EQ(out.rest().distance_to_pin_m(), direct->distance_to_pin_m);
  EXPECT_EQ(out.carry_m(), direct->flight->carry_m);
  EXPECT_EQ(out.events_size(), static_cast<int>(direct->ground.events.size()));
  EXPECT_EQ(out.events(0).kind(), "landing");
  EXPECT_FALSE(out.events(0).surface().empty());
  EXPECT_EQ(out.rest().surface(), direct->ground.rest_surface);
  // The path starts on the tee's ground and ends at the rest.
  ASSERT_GT(out.path_size(), 2);
  EXPECT_NEAR(out.path(0).z_m(), links.terrain.HeightAt(shot.from_m.x(), shot.from_m.y()), 1e-9);
}

TEST(GolfShotTest, CoursesAreListedAndShown) {
  const v1::ListCoursesResponse list = ListCourses();
  ASSERT_EQ(list.courses_size(), 3);
  EXPECT_EQ(list.courses(0).name(), "sportsim_links");
  const v1::CourseInfo& links = list.courses(0);
  ASSERT_EQ(links.holes_size(), 3);
  EXPECT_EQ(links.holes(0).par() + links.holes(1).par() + links.holes(2).par(), 12u);
  EXPECT_EQ(links.areas_size(), 0);  // no geometry in a list
  EXPECT_GT(links.max_z_m() - links.min_z_m(), 5);
  EXPECT_EQ(links.surfaces(0).name(), "tee");
  v1::GetCourseRequest get;
  get.set_name("sportsim_links");
  get.set_hole(2);
  get.set_geometry(true);
  absl::StatusOr<v1::CourseInfo> one = GetCourse(get);
  ASSERT_TRUE(one.ok()) << one.status();
  ASSERT_EQ(one->holes_size(), 1);
  EXPECT_EQ(one->holes(0).number(), 2u);
  EXPECT_EQ(one->holes(0).par(), 3u);
  EXPECT_GT(one->areas_size(), 10);
  EXPECT_EQ(one->heightfield().z_m_size(),
            static_cast<int>(one->heightfield().columns() * one->heightfield().rows()));
  get.set_name("augusta");
  EXPECT_EQ(GetCourse(get).status().code(), absl::StatusCode::kNotFound);
  get.set_name("sportsim_links");
  get.set_hole(4);
  EXPECT_EQ(GetCourse(get).status().code(), absl::StatusCode::kInvalidArgument);
}

// A putt on practice is the library's putt from the same point: the same rest to the bit; a
// putt of the right speed straight at the hole drops.
TEST(GolfShotTest, APuttIsTheLibrarysPuttAndTheHoleTakesIt) {
  v1::SimulateGolfShotRequest r = Putt(2.0, 10);
  r.set_stimp_ft(11);
  r.set_slope_pct(1.5);
  r.set_slope_toward_deg(-60);
  r.set_from_x_m(-3);
  r.set_from_y_m(1);
  absl::StatusOr<GolfShotJob> job = GolfShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  v1::SimulateGolfShotResponse out;
  ASSERT_TRUE(RunGolfShot(*job, {}, &out).ok());
  const absl::StatusOr<golf::GroundResult> direct = golf::SimulateGround(
      golf::BallSpec{}, *golf::GreenOfStimp(11), {.slope_pct = 1.5, .slope_toward_deg = -60},
      golf::Hole{}, golf::PuttStart(-3, 1, 2.0, 10), golf::GroundOptions{});
  ASSERT_TRUE(direct.ok());
  EXPECT_EQ(out.rest().x_m(), direct->rest_m.x());
  EXPECT_EQ(out.rest().y_m(), direct->rest_m.y());
  EXPECT_EQ(out.events_size(), static_cast<int>(direct->events.size()));
  EXPECT_EQ(out.rest().surface(), "green");
  EXPECT_NEAR(out.rest().distance_to_pin_m(), std::hypot(direct->rest_m.x(), direct->rest_m.y()),
              1e-12);
  EXPECT_EQ(out.carry_m(), 0.0);
  EXPECT_FALSE(out.has_flight());

  // Straight at the hole from 3 m on the flat, rolling 1 m/s at the rim: holed.
  const golf::Surface green = *golf::GreenOfStimp(10);
  const double a = 5.0 / 7.0 * green.rolling_resistance * 9.80665;
  v1::SimulateGolfShotRequest holed;
  holed.mutable_roll()->set_speed_mps(std::sqrt(1.0 + 2 * a * (3 - 0.054)));
  holed.mutable_roll()->set_direction_deg(0);
  holed.set_from_x_m(-3);
  holed.set_from_y_m(0);
  job = GolfShotJobFromProto(holed);
  ASSERT_TRUE(job.ok());
  v1::SimulateGolfShotResponse in;
  ASSERT_TRUE(RunGolfShot(*job, {}, &in).ok());
  EXPECT_TRUE(in.rest().holed());
  EXPECT_EQ(in.rest().distance_to_pin_m(), 0.0);
  EXPECT_EQ(in.events(in.events_size() - 1).kind(), "holed");

  // 1.8 m/s at the rim: over the open hole, into the flagstick.
  holed.mutable_roll()->set_speed_mps(std::sqrt(1.8 * 1.8 + 2 * a * (3 - 0.054)));
  v1::SimulateGolfShotResponse open, stick;
  ASSERT_TRUE(RunGolfShot(*GolfShotJobFromProto(holed), {}, &open).ok());
  holed.set_flagstick(true);
  ASSERT_TRUE(RunGolfShot(*GolfShotJobFromProto(holed), {}, &stick).ok());
  EXPECT_FALSE(open.rest().holed());
  EXPECT_TRUE(stick.rest().holed());

  // The slope switched off: a putt across a tilted green runs as on the flat (the plane keeps
  // its tilt, so only the heights differ), and a slope the green could not hold is accepted.
  v1::SimulateGolfShotRequest across = Putt(2.0, 90);
  across.set_from_x_m(-3);
  across.set_from_y_m(-2);
  across.set_slope_pct(9);
  across.set_slope_toward_deg(0);
  EXPECT_THAT(Error(across), HasSubstr("slope_pct"));
  across.set_no_slope(true);
  v1::SimulateGolfShotResponse flat_run, tilted;
  ASSERT_TRUE(RunGolfShot(*GolfShotJobFromProto(across), {}, &tilted).ok());
  across.set_slope_pct(0);
  across.set_no_slope(false);
  ASSERT_TRUE(RunGolfShot(*GolfShotJobFromProto(across), {}, &flat_run).ok());
  EXPECT_NEAR(tilted.rest().x_m(), flat_run.rest().x_m(), 1e-9);
  EXPECT_GT(tilted.total_m(), 1.0);
  across.set_slope_pct(5);  // with the pull: it breaks down the fall line (+x)
  v1::SimulateGolfShotResponse breaking;
  ASSERT_TRUE(RunGolfShot(*GolfShotJobFromProto(across), {}, &breaking).ok());
  EXPECT_GT(breaking.rest().x_m(), flat_run.rest().x_m() + 0.05);
}

// A launch on the range: the flight's carry, then the ground; the frame turns with the aim (a
// shot aimed north lands north of the tee); total beyond carry; the path starts at the tee.
TEST(GolfShotTest, ALaunchFliesAlongItsAimThenRollsOut) {
  v1::SimulateGolfShotRequest r;
  r.set_course("range");
  r.set_aim_deg(90);
  r.set_from_x_m(5);
  r.set_from_y_m(-2);
  v1::LaunchConditions* l = r.mutable_launch();
  l->set_ball_speed_mps(167 * golf::kMphToMps);
  l->set_launch_angle_deg(10.9);
  l->set_spin_rpm(2686);
  absl::StatusOr<GolfShotJob> job = GolfShotJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  v1::SimulateGolfShotResponse out;
  ASSERT_TRUE(RunGolfShot(*job, {}, &out).ok());
  EXPECT_NEAR(out.carry_m(), out.flight().carry_m(), 1e-12);
  EXPECT_GT(out.total_m(), out.carry_m() + 10);
  EXPECT_NEAR(out.rest().x_m(), 5, 1e-6);  // straight north
  EXPECT_NEAR(out.rest().y_m(), -2 + out.total_m(), 1e-6);
  EXPECT_NEAR(out.lateral_m(), 0, 1e-6);
  EXPECT_EQ(out.rest().surface(), "fairway");
  EXPECT_FALSE(out.rest().has_distance_to_pin_m());
  ASSERT_GT(out.path_size(), 10);
  EXPECT_EQ(out.path(0).x_m(), 5);
  EXPECT_EQ(out.path(0).y_m(), -2);
  EXPECT_EQ(out.events(0).kind(), "landing");
  EXPECT_NEAR(out.events(0).y_m(), -2 + out.carry_m(), 1e-6);
  EXPECT_EQ(out.flight().samples_size(), 0);  // the path carries them
  // A firm fairway rolls farther than a soft one.
  r.set_fairway("firm");
  v1::SimulateGolfShotResponse firm, soft;
  ASSERT_TRUE(RunGolfShot(*GolfShotJobFromProto(r), {}, &firm).ok());
  r.set_fairway("soft");
  ASSERT_TRUE(RunGolfShot(*GolfShotJobFromProto(r), {}, &soft).ok());
  EXPECT_GT(firm.total_m(), soft.total_m() + 20);
}

// SimulateFlight with `fairway` goes on to rest: the library's ground phase from the flight's
// landing, total beyond carry; without it nothing of the ground is set; a bad value is named.
TEST(GolfShotTest, AFlightRollsOutWhenAsked) {
  v1::SimulateFlightRequest r;
  r.mutable_launch()->set_ball_speed_mps(60);
  r.mutable_launch()->set_launch_angle_deg(12);
  r.mutable_launch()->set_spin_rpm(3000);
  r.mutable_launch()->set_spin_axis_deg(-4);
  r.set_fairway("firm");
  absl::StatusOr<FlightJob> job = FlightJobFromProto(r);
  ASSERT_TRUE(job.ok()) << job.status();
  job->options.sample_interval_s = 0;
  const absl::StatusOr<golf::FlightResult> flight =
      golf::SimulateFlight(job->ball, job->launch, job->atmosphere, job->wind, job->options);
  ASSERT_TRUE(flight.ok());
  v1::SimulateFlightResponse out;
  FlightResultToProto(*flight, 0, &out);
  ASSERT_TRUE(RollOutToProto(*job, *flight, &out).ok());
  golf::GroundOptions o;
  o.hole = false;
  o.sample_interval_s = 0;
  const absl::StatusOr<golf::GroundResult> g =
      golf::SimulateGround(golf::BallSpec{}, *golf::SurfaceByName("fairway_firm"), {}, {},
                           golf::LandingFromFlight(*flight), o);
  ASSERT_TRUE(g.ok());
  ASSERT_TRUE(out.has_total_m());
  EXPECT_EQ(out.total_m(), std::hypot(g->rest_m.x(), g->rest_m.y()));
  EXPECT_GT(out.total_m(), out.carry_m() + 5);
  EXPECT_EQ(out.rest().surface(), "fairway_firm");
  EXPECT_EQ(out.ground_events(0).kind(), "landing");
  EXPECT_EQ(out.ground_events(out.ground_events_size() - 1).kind(), "rest");
  EXPECT_LT(out.total_lateral_m(), 0.0);  // a draw axis: left, on the ground too
  r.set_fairway("");
  job = FlightJobFromProto(r);
  v1::SimulateFlightResponse bare;
  ASSERT_TRUE(RollOutToProto(*job, *flight, &bare).ok());
  EXPECT_FALSE(bare.has_total_m());
  EXPECT_FALSE(bare.has_rest());
  r.set_fairway("wet");
  EXPECT_FALSE(FlightJobFromProto(r).ok());
  EXPECT_THAT(std::string(FlightJobFromProto(r).status().message()), HasSubstr("fairway"));
  v1::BallStrike strike;
  strike.set_club("7-iron");
  strike.set_fairway("ice");
  EXPECT_THAT(std::string(StrikeJobFromProto(strike).status().message()), HasSubstr("ball.fairway"));
}

// Over gRPC: the same answer as the run in-process, and a bad field named.
TEST(GolfShotTest, OverGrpc) {
  ServerConfig config;
  config.listen = "127.0.0.1:0";
  absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start(config);
  ASSERT_TRUE(app.ok()) << app.status();
  auto stub = v1::Swing::NewStub(
      grpc::CreateChannel((*app)->address(), grpc::InsecureChannelCredentials()));
  v1::SimulateGolfShotRequest r = Putt(2.4, 3);
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  v1::SimulateGolfShotResponse resp;
  ASSERT_TRUE(stub->SimulateGolfShot(&ctx, r, &resp).ok());
  v1::SimulateGolfShotResponse local;
  ASSERT_TRUE(RunGolfShot(*GolfShotJobFromProto(r), {}, &local).ok());
  local.set_cpu_s(resp.cpu_s());
  EXPECT_EQ(resp.SerializeAsString(), local.SerializeAsString());
  EXPECT_GT(resp.cpu_s(), 0.0);
  r.mutable_putt()->set_direction_deg(NAN);
  grpc::ClientContext ctx2;
  const grpc::Status bad = stub->SimulateGolfShot(&ctx2, r, &resp);
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(bad.error_message(), HasSubstr("putt.direction_deg"));
  // The courses, and a shot on one.
  grpc::ClientContext ctx3, ctx4, ctx5;
  v1::ListCoursesResponse list;
  ASSERT_TRUE(stub->ListCourses(&ctx3, v1::ListCoursesRequest(), &list).ok());
  EXPECT_EQ(list.SerializeAsString(), ListCourses().SerializeAsString());
  v1::GetCourseRequest get;
  get.set_name("nowhere");
  v1::CourseInfo info;
  EXPECT_EQ(stub->GetCourse(&ctx4, get, &info).error_code(), grpc::StatusCode::NOT_FOUND);
  v1::SimulateGolfShotRequest on = OnLinks(1);
  *on.mutable_roll() = Putt(3, 0).putt();
  on.set_from_x_m(300);
  on.set_from_y_m(0);
  v1::SimulateGolfShotResponse remote_roll, local_roll;
  ASSERT_TRUE(stub->SimulateGolfShot(&ctx5, on, &remote_roll).ok());
  ASSERT_TRUE(RunGolfShot(*GolfShotJobFromProto(on), {}, &local_roll).ok());
  local_roll.set_cpu_s(remote_roll.cpu_s());
  EXPECT_EQ(remote_roll.SerializeAsString(), local_roll.SerializeAsString());
  (*app)->Shutdown(absl::Seconds(1));
}

}  // namespace
}  // namespace sportsim::server
