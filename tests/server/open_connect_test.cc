// Launch monitors over GSPro Open Connect v1 (server/rpc/open_connect.h): the message parser
// (units, both spin encodings, malformed and absurd input), the stream splitter, and the
// listener driven by scripted TCP clients against a running server: shots in yards and in
// metres playing a bound seat's strokes, heartbeats, refusals by the round's rules, unbound
// devices, oversized messages, and silent connections that hold nothing.
#include "server/rpc/open_connect.h"

#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "server/app/server_app.h"
#include "server/swing/round_world.h"
#include "sportsim/v1/open_connect.pb.h"

namespace sportsim::server {
namespace {

using ::testing::HasSubstr;
using Clock = std::chrono::steady_clock;

std::string Shot(std::string_view device, std::string_view units, std::string_view spin,
                 double speed_mph = 145.0, int shot_number = 1) {
  return absl::StrFormat(
      R"({"DeviceID": "%s", "Units": "%s", "ShotNumber": %d, "APIversion": "1",
          "BallData": {"Speed": %g, "VLA": 12.5, "HLA": -1.5, %s, "CarryDistance": 250},
          "ClubData": {"Speed": 100.0},
          "ShotDataOptions": {"ContainsBallData": true, "ContainsClubData": true,
                              "LaunchMonitorIsReady": true, "IsHeartBeat": false}})",
      device, units, shot_number, speed_mph, spin);
}

std::string Heartbeat(std::string_view device) {
  return absl::StrFormat(
      R"({"DeviceID": "%s", "Units": "Yards", "ShotNumber": 0, "APIversion": "1",
          "ShotDataOptions": {"ContainsBallData": false, "ContainsClubData": false,
                              "IsHeartBeat": true}})",
      device);
}

TEST(OpenConnectParseTest, AShotBecomesItsLaunch) {
  absl::StatusOr<OpenConnectMessageInfo> m =
      ParseOpenConnect(Shot("LM-1", "Yards", R"("TotalSpin": 2800, "SpinAxis": -4.5)"));
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->kind, OpenConnectMessageInfo::Kind::kShot);
  EXPECT_EQ(m->device_id, "LM-1");
  EXPECT_FALSE(m->metres);
  EXPECT_EQ(m->shot_number, 1);
  EXPECT_DOUBLE_EQ(m->launch.ball_speed_mps, 145.0 * 1609.344 / 3600.0);
  EXPECT_EQ(m->launch.launch_angle_deg, 12.5);
  EXPECT_EQ(m->launch.launch_direction_deg, -1.5);  // + right of the target, as ours
  EXPECT_EQ(m->launch.spin_rpm, 2800);
  EXPECT_EQ(m->launch.spin_axis_deg, -4.5);
  // Units name the distances' unit only: the launch is the same in metres.
  absl::StatusOr<OpenConnectMessageInfo> metres =
      ParseOpenConnect(Shot("LM-1", "Meters", R"("TotalSpin": 2800, "SpinAxis": -4.5)"));
  ASSERT_TRUE(metres.ok());
  EXPECT_TRUE(metres->metres);
  EXPECT_EQ(metres->launch.ball_speed_mps, m->launch.ball_speed_mps);
}

// One shot in both spin encodings gives one launch; when both are sent, TotalSpin and SpinAxis
// win (the protocol's own example has them disagree with its BackSpin and SideSpin).
TEST(OpenConnectParseTest, BothSpinEncodingsGiveTheSameLaunch) {
  const double total = 3000.0, axis = 10.0;
  const double back = total * std::cos(axis * M_PI / 180.0);
  const double side = total * std::sin(axis * M_PI / 180.0);
  auto a = ParseOpenConnect(Shot("d", "Yards", absl::StrFormat(R"("TotalSpin": %.17g, "SpinAxis": %.17g)", total, axis)));
  auto b = ParseOpenConnect(Shot("d", "Yards", absl::StrFormat(R"("BackSpin": %.17g, "SideSpin": %.17g)", back, side)));
  ASSERT_TRUE(a.ok() && b.ok()) << a.status() << b.status();
  EXPECT_NEAR(b->launch.spin_rpm, a->launch.spin_rpm, 1e-9);
  EXPECT_NEAR(b->launch.spin_axis_deg, a->launch.spin_axis_deg, 1e-12);
  // A hook's side spin is negative: the axis tilts left.
  auto hook = ParseOpenConnect(Shot("d", "Yards", R"("BackSpin": 2500, "SideSpin": -400)"));
  ASSERT_TRUE(hook.ok());
  EXPECT_LT(hook->launch.spin_axis_deg, 0.0);
  auto both = ParseOpenConnect(
      Shot("d", "Yards", R"("TotalSpin": 2500, "SpinAxis": 2, "BackSpin": 1800, "SideSpin": -900)"));
  ASSERT_TRUE(both.ok());
  EXPECT_EQ(both->launch.spin_rpm, 2500);
  EXPECT_EQ(both->launch.spin_axis_deg, 2);
}

TEST(OpenConnectParseTest, HeartbeatsAndStatusMessagesAreNotShots) {
  auto h = ParseOpenConnect(Heartbeat("d"));
  ASSERT_TRUE(h.ok()) << h.status();
  EXPECT_EQ(h->kind, OpenConnectMessageInfo::Kind::kHeartbeat);
  auto ready = ParseOpenConnect(
      R"({"DeviceID": "d", "ShotDataOptions": {"LaunchMonitorIsReady": true, "LaunchMonitorBallDetected": true}})");
  ASSERT_TRUE(ready.ok()) << ready.status();
  EXPECT_EQ(ready->kind, OpenConnectMessageInfo::Kind::kStatus);
}

TEST(OpenConnectParseTest, BadMessagesAreRefusedNamingTheField) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"{\"DeviceID\": \"d\", ", "JSON"},
      {"[1, 2]", "JSON"},
      {R"({"DeviceID": "d", "BallData": {"Speed": "fast"}})", "JSON"},
      {Shot("", "Yards", R"("TotalSpin": 2800)"), "DeviceID"},
      {Shot("d", "Furlongs", R"("TotalSpin": 2800)"), "Units"},
      {Shot("d", "Yards", R"("TotalSpin": 2800)", 1000.0), "BallData.Speed"},
      {Shot("d", "Yards", R"("TotalSpin": -5)"), "BallData.TotalSpin"},
      {Shot("d", "Yards", R"("TotalSpin": 2800, "SpinAxis": 400)"), "BallData.SpinAxis"},
      {Shot("d", "Yards", R"("CarryDistance": 1)"), "BallData"},
      {R"({"DeviceID": "d", "ShotDataOptions": {"ContainsBallData": true}, "BallData": {"VLA": 10, "TotalSpin": 1}})",
       "BallData.Speed"},
      {R"({"DeviceID": "d", "ShotDataOptions": {"ContainsBallData": true}, "BallData": {"Speed": 100, "TotalSpin": 1}})",
       "BallData.VLA"},
      {R"({"DeviceID": "d", "APIversion": "2"})", "APIversion"},
  };
  for (const auto& [text, field] : cases) {
    absl::StatusOr<OpenConnectMessageInfo> m = ParseOpenConnect(text);
    ASSERT_FALSE(m.ok()) << text;
    EXPECT_EQ(m.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(m.status().message(), HasSubstr(field)) << text;
  }
}

TEST(JsonObjectSplitterTest, CutsObjectsBackToBackRespectingStrings) {
  JsonObjectSplitter split(1000);
  std::vector<std::string> out;
  ASSERT_TRUE(split.Feed(R"({"a": "}{\"", "b": {"c": [1, {}]}})" "\n {\"x\"", &out).ok());
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], R"({"a": "}{\"", "b": {"c": [1, {}]}})");
  ASSERT_TRUE(split.Feed(": 1}{\"y\": 2}", &out).ok());
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[1], "{\"x\": 1}");
  EXPECT_EQ(out[2], "{\"y\": 2}");
  JsonObjectSplitter small(16);
  EXPECT_FALSE(small.Feed(R"({"long": "0123456789abcdef"})", &out).ok());
  JsonObjectSplitter junk(1000);
  EXPECT_FALSE(junk.Feed("hello", &out).ok());
}

// --- the listener, over TCP --------------------------------------------------------------------

class OpenConnectTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ServerConfig config;
    config.listen = "127.0.0.1:0";
    config.open_connect.listen = "127.0.0.1:0";
    config.open_connect.idle_timeout = absl::Seconds(1);
    config.open_connect.max_message_bytes = 4096;
    absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start(config);
    ASSERT_TRUE(app.ok()) << app.status();
    app_ = *std::move(app);
    ASSERT_GT(app_->open_connect_port(), 0);
  }

  // A two-player round on hole 2 (fast-forward: each stroke comes to rest at the next tick),
  // seat 0's DeviceID bound.
  v1::CreateRoundResponse Round(const std::string& device) {
    v1::CreateRoundRequest c;
    c.set_first_hole(2);
    c.set_last_hole(2);
    c.add_players()->set_name("Ann");
    c.add_players()->set_name("Bob");
    c.set_fast_forward(true);
    c.set_seed(5);
    absl::StatusOr<v1::CreateRoundResponse> made = app_->rounds().Create(c);
    EXPECT_TRUE(made.ok()) << made.status();
    v1::BindMonitorRequest b;
    b.set_round_id(made->round_id());
    b.set_token(made->seats(0).token());
    b.set_device_id(device);
    absl::StatusOr<v1::BindMonitorResponse> bound = app_->rounds().BindMonitor(b);
    EXPECT_TRUE(bound.ok()) << bound.status();
    EXPECT_EQ(bound->seat(), 0u);
    EXPECT_EQ(bound->listen(), absl::StrCat("127.0.0.1:", app_->open_connect_port()));
    return *made;
  }

  int Connect() {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(app_->open_connect_port()));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)), 0);
    return fd;
  }
  static void Write(int fd, const std::string& text) {
    ASSERT_EQ(::send(fd, text.data(), text.size(), MSG_NOSIGNAL), static_cast<ssize_t>(text.size()));
  }
  // The next `n` replies (fewer if the connection closes or `seconds` pass).
  std::vector<v1::OpenConnectReply> Read(int fd, size_t n, double seconds = 10) {
    std::vector<v1::OpenConnectReply> out;
    auto& split = splitters_[fd];
    if (!split) split = std::make_unique<JsonObjectSplitter>(1 << 16);
    const auto until = Clock::now() + std::chrono::duration<double>(seconds);
    while (out.size() < n && Clock::now() < until) {
      for (; !pending_[fd].empty() && out.size() < n; pending_[fd].erase(pending_[fd].begin())) {
        v1::OpenConnectReply r;
        EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(pending_[fd].front(), &r).ok());
        out.push_back(r);
      }
      if (out.size() >= n) break;
      pollfd p{fd, POLLIN, 0};
      if (poll(&p, 1, 50) <= 0) continue;
      char buf[4096];
      const ssize_t got = ::recv(fd, buf, sizeof(buf), 0);
      if (got <= 0) {
        closed_[fd] = true;
        break;
      }
      EXPECT_TRUE(split->Feed(std::string_view(buf, static_cast<size_t>(got)), &pending_[fd]).ok());
    }
    return out;
  }
  v1::RoundState State(const std::string& id) {
    v1::GetRoundRequest g;
    g.set_round_id(id);
    return app_->rounds().Get(g)->round();
  }

  std::unique_ptr<ServerApp> app_;
  std::map<int, std::unique_ptr<JsonObjectSplitter>> splitters_;
  std::map<int, std::vector<std::string>> pending_;
  std::map<int, bool> closed_;
};

// The same shot sent in yards to one round and in metres to its twin plays the same stroke;
// each gets 200 at once, then 201 at rest with the next club and the distance in its units.
TEST_F(OpenConnectTest, ShotsInYardsAndMetresPlayTheBoundSeatsStroke) {
  const v1::CreateRoundResponse a = Round("LM-YARDS");
  const v1::CreateRoundResponse b = Round("LM-METRES");
  const int fa = Connect(), fb = Connect();
  Write(fa, Heartbeat("LM-YARDS"));
  std::vector<v1::OpenConnectReply> hb = Read(fa, 1);
  ASSERT_EQ(hb.size(), 1u);
  EXPECT_EQ(hb[0].code(), 200);
  const std::string spin = R"("TotalSpin": 6500, "SpinAxis": 1.5)";
  Write(fa, Shot("LM-YARDS", "Yards", spin, 85.0));
  Write(fb, Shot("LM-METRES", "Meters", spin, 85.0));
  std::vector<v1::OpenConnectReply> ra = Read(fa, 2), rb = Read(fb, 2);
  ASSERT_EQ(ra.size(), 2u);
  ASSERT_EQ(rb.size(), 2u);
  EXPECT_EQ(ra[0].code(), 200) << ra[0].message();
  EXPECT_EQ(ra[1].code(), 201);
  EXPECT_EQ(rb[1].code(), 201);
  const v1::RoundState sa = State(a.round_id()), sb = State(b.round_id());
  EXPECT_EQ(sa.players(0).strokes(), 1u);
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(sa.players(0), sb.players(0)));
  const double d = sa.players(0).ball().distance_to_pin_m();
  EXPECT_NEAR(ra[1].player().distancetotarget(), d / 0.9144, 0.051);
  EXPECT_NEAR(rb[1].player().distancetotarget(), d, 0.051);
  EXPECT_EQ(ra[1].player().club(), SuggestClub(d, sa.players(0).ball().lie() == "green"));
  // The stroke is in the round's record like a PlayStroke's.
  v1::GetRoundRecordRequest rr;
  rr.set_round_id(a.round_id());
  absl::StatusOr<v1::RoundRecord> record = app_->rounds().Record(rr);
  ASSERT_TRUE(record.ok());
  ASSERT_EQ(record->commands_size(), 1);
  EXPECT_NEAR(record->commands(0).stroke().launch().ball_speed_mps(), 85.0 * 0.44704, 1e-12);
  // Seat 0 again: Bob tees next (or, in the pond, Ann's relief comes first), so the round's
  // rules refuse it (500) and nothing changes.
  Write(fa, Shot("LM-YARDS", "Yards", spin, 85.0, 2));
  std::vector<v1::OpenConnectReply> again = Read(fa, 1);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(again[0].code(), 500);
  EXPECT_THAT(again[0].message(), HasSubstr("FAILED_PRECONDITION"));
  EXPECT_THAT(again[0].message(), HasSubstr("Rule "));
  EXPECT_EQ(State(a.round_id()).players(0).strokes(), 1u);
  close(fa);
  close(fb);
  EXPECT_EQ(app_->open_connect()->shots(), 2);
}

// Malformed, absurd and unbound messages get 5xx and change nothing; the connection goes on.
// An oversized message closes it (the stream cannot be resynchronised).
TEST_F(OpenConnectTest, BadMessagesGetErrorsAndChangeNothing) {
  const v1::CreateRoundResponse a = Round("LM-1");
  const int fd = Connect();
  Write(fd, "{\"DeviceID\": \"LM-1\", \"BallData\": {\"Speed\": \"fast\"}}");
  Write(fd, Shot("LM-1", "Yards", R"("TotalSpin": 2800)", 900.0));
  Write(fd, Shot("LM-UNBOUND", "Yards", R"("TotalSpin": 2800)"));
  Write(fd, Heartbeat("LM-1"));
  std::vector<v1::OpenConnectReply> r = Read(fd, 4);
  ASSERT_EQ(r.size(), 4u);
  EXPECT_EQ(r[0].code(), 501);
  EXPECT_THAT(r[0].message(), HasSubstr("JSON"));
  EXPECT_EQ(r[1].code(), 501);
  EXPECT_THAT(r[1].message(), HasSubstr("BallData.Speed"));
  EXPECT_EQ(r[2].code(), 502);
  EXPECT_THAT(r[2].message(), HasSubstr("round monitor"));
  EXPECT_EQ(r[3].code(), 200);
  EXPECT_EQ(State(a.round_id()).strokes(), 0u);
  Write(fd, "{\"DeviceID\": \"" + std::string(5000, 'x') + "\"}");
  std::vector<v1::OpenConnectReply> big = Read(fd, 1);
  ASSERT_EQ(big.size(), 1u);
  EXPECT_EQ(big[0].code(), 501);
  EXPECT_THAT(big[0].message(), HasSubstr("longer than 4096 bytes"));
  Read(fd, 1, 2);
  EXPECT_TRUE(closed_[fd]);
  close(fd);
}

// A silent connection holds nothing: another device's shot is answered meanwhile, and the
// silent one is closed after the idle timeout (1 s here).
TEST_F(OpenConnectTest, ASilentConnectionHoldsNothingAndIsClosed) {
  const v1::CreateRoundResponse a = Round("LM-1");
  const int silent = Connect();
  Write(silent, "{\"DeviceID\": ");  // half a message, then nothing
  const int fd = Connect();
  const auto t0 = Clock::now();
  Write(fd, Shot("LM-1", "Yards", R"("TotalSpin": 6000, "SpinAxis": 0)", 80.0));
  std::vector<v1::OpenConnectReply> r = Read(fd, 1);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].code(), 200);
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 5.0);
  std::vector<v1::OpenConnectReply> idle = Read(silent, 1, 5);
  ASSERT_EQ(idle.size(), 1u);
  EXPECT_EQ(idle[0].code(), 504);
  Read(silent, 1, 2);
  EXPECT_TRUE(closed_[silent]);
  close(silent);
  close(fd);
}

// Without a listener a binding is refused; only a seat binds (not the admin, not a stranger).
TEST_F(OpenConnectTest, BindingNeedsAListenerAndASeat) {
  const v1::CreateRoundResponse a = Round("LM-1");
  v1::BindMonitorRequest b;
  b.set_round_id(a.round_id());
  b.set_device_id("LM-2");
  b.set_token(a.admin_token());
  EXPECT_EQ(app_->rounds().BindMonitor(b).status().code(), absl::StatusCode::kPermissionDenied);
  b.set_token("0123456789abcdef0123456789abcdef");
  EXPECT_FALSE(app_->rounds().BindMonitor(b).ok());
  b.set_token(a.seats(1).token());
  b.set_device_id(std::string(80, 'd'));
  EXPECT_THAT(app_->rounds().BindMonitor(b).status().message(), HasSubstr("device_id"));
  RoundRegistry alone(RoundLimits{}, nullptr, 1);
  b.set_device_id("LM-2");
  EXPECT_EQ(alone.BindMonitor(b).status().code(), absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace sportsim::server
