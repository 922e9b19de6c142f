// Swing sessions through gRPC, in-process on a loopback port: the DriveSwing bidirectional
// stream (a driven swing equals SimulateSwing bit for bit, refusals ride on the stream, the
// stream ends at the swing's end or on half-close), its first-message errors, WatchSwing beside
// it, and shutdown mid-swing.
#include <chrono>
#include <thread>

#include <google/protobuf/util/message_differencer.h>
#include <grpcpp/grpcpp.h>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/app/server_app.h"
#include "sportsim/v1/swing.grpc.pb.h"

namespace sportsim::server {
namespace {

using ::google::protobuf::util::MessageDifferencer;
using ::testing::HasSubstr;

class SessionServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start({.listen = "127.0.0.1:0"});
    ASSERT_TRUE(app.ok()) << app.status();
    app_ = *std::move(app);
    stub_ = v1::Swing::NewStub(
        grpc::CreateChannel(app_->address(), grpc::InsecureChannelCredentials()));
  }
  std::unique_ptr<grpc::ClientContext> Ctx() {
    auto c = std::make_unique<grpc::ClientContext>();
    c->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    return c;
  }
  v1::CreateSessionResponse Create(v1::RealismProfile profile = v1::REALISM_PROFILE_REALISTIC) {
    v1::CreateSessionRequest r;
    r.set_profile(profile);
    v1::CreateSessionResponse out;
    const grpc::Status s = stub_->CreateSession(Ctx().get(), r, &out);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return out;
  }
  // SimulateSwing with the chapter's torques and the session defaults (rk4, 0.0025 s).
  v1::SwingImpact ChapterImpact() {
    v1::SimulateSwingRequest r;
    v1::SimulateSwingResponse out;
    const grpc::Status s = stub_->SimulateSwing(Ctx().get(), r, &out);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return out.impact();
  }
  static v1::DriveSwingRequest Start(const v1::CreateSessionResponse& s, double qa, double qb) {
    v1::DriveSwingRequest m;
    m.mutable_start()->set_session_id(s.session_id());
    m.mutable_start()->set_token(s.token());
    m.mutable_start()->set_qalpha_nm(qa);
    m.mutable_start()->set_qbeta_nm(qb);
    return m;
  }
  static v1::DriveSwingRequest Torque(double t, double qa, double qb) {
    v1::DriveSwingRequest m;
    m.mutable_torque()->set_t_s(t);
    m.mutable_torque()->set_qalpha_nm(qa);
    m.mutable_torque()->set_qbeta_nm(qb);
    return m;
  }

  std::unique_ptr<ServerApp> app_;
  std::unique_ptr<v1::Swing::Stub> stub_;
};

TEST_F(SessionServiceTest, DrivenChapterSwingEqualsSimulateSwingAndEndsAtImpact) {
  const v1::CreateSessionResponse s = Create();
  auto ctx = Ctx();
  auto stream = stub_->DriveSwing(ctx.get());
  ASSERT_TRUE(stream->Write(Start(s, 100, -10)));
  ASSERT_TRUE(stream->Write(Torque(0.1, 100, 0)));   // the chapter's wrist release
  ASSERT_TRUE(stream->Write(Torque(0.05, 100, 0)));  // before the previous one: refused
  v1::SwingSnapshot snap;
  std::vector<v1::SwingEvent> events;
  int snapshots = 0;
  size_t largest = 0, total = 0;
  while (stream->Read(&snap)) {
    ++snapshots;
    total += snap.ByteSizeLong();
    largest = std::max(largest, snap.ByteSizeLong());
    for (const v1::SwingEvent& e : snap.events()) events.push_back(e);
  }
  // The server ended the stream at the swing's end, without our half-close.
  const grpc::Status status = stream->Finish();
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(snap.phase(), v1::SWING_PHASE_FINISHED);
  const v1::SwingImpact want = ChapterImpact();
  const v1::SwingEvent* impact = nullptr;
  const v1::SwingEvent* refused = nullptr;
  const v1::SwingEvent* torque = nullptr;
  for (const v1::SwingEvent& e : events) {
    if (e.kind() == v1::SWING_EVENT_IMPACT) impact = &e;
    if (e.kind() == v1::SWING_EVENT_COMMAND_REFUSED) refused = &e;
    if (e.kind() == v1::SWING_EVENT_TORQUE) torque = &e;
  }
  ASSERT_NE(impact, nullptr);
  EXPECT_TRUE(MessageDifferencer::Equals(impact->impact(), want))
      << impact->impact().DebugString() << " vs " << want.DebugString();
  ASSERT_NE(refused, nullptr);
  EXPECT_EQ(refused->code(), static_cast<int>(grpc::StatusCode::OUT_OF_RANGE));
  EXPECT_EQ(refused->command(), 2u);
  ASSERT_NE(torque, nullptr);
  EXPECT_EQ(torque->command(), 1u);
  EXPECT_NEAR(torque->t_s(), 0.1, 1e-12);
  // At 400 Hz, every tick to impact (t ~ 0.29 s) unless a write was still in flight.
  EXPECT_GT(snapshots, 40);
  std::printf("snapshots: %d, %zu bytes on average, %zu at most\n", snapshots,
              total / static_cast<size_t>(snapshots), largest);
}

TEST_F(SessionServiceTest, HalfCloseEndsTheStreamAndTheSwingGoesOn) {
  const v1::CreateSessionResponse s = Create();
  auto ctx = Ctx();
  auto stream = stub_->DriveSwing(ctx.get());
  ASSERT_TRUE(stream->Write(Start(s, 100, -10)));
  ASSERT_TRUE(stream->Write(Torque(0.1, 100, 0)));
  v1::SwingSnapshot snap;
  ASSERT_TRUE(stream->Read(&snap));
  ASSERT_TRUE(stream->WritesDone());
  while (stream->Read(&snap)) {
  }
  ASSERT_TRUE(stream->Finish().ok());
  // The queued command still applies and the swing ends as the chapter's.
  v1::SessionInfo info;
  for (int i = 0; i < 500; ++i) {
    v1::GetSessionRequest g;
    g.set_session_id(s.session_id());
    ASSERT_TRUE(stub_->GetSession(Ctx().get(), g, &info).ok());
    if (info.phase() == v1::SWING_PHASE_FINISHED) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(info.phase(), v1::SWING_PHASE_FINISHED);
  EXPECT_TRUE(MessageDifferencer::Equals(info.last_impact(), ChapterImpact()));
  EXPECT_EQ(info.watchers(), 0u);
}

TEST_F(SessionServiceTest, FirstMessageErrors) {
  const v1::CreateSessionResponse s = Create();
  const auto first = [&](const v1::DriveSwingRequest& m) {
    auto ctx = Ctx();
    auto stream = stub_->DriveSwing(ctx.get());
    stream->Write(m);
    stream->WritesDone();
    v1::SwingSnapshot snap;
    while (stream->Read(&snap)) {
    }
    return stream->Finish();
  };
  EXPECT_EQ(first(Torque(0, 1, 1)).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  v1::DriveSwingRequest wrong = Start(s, 100, -10);
  wrong.mutable_start()->set_token("00");
  EXPECT_EQ(first(wrong).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  v1::DriveSwingRequest unknown = Start(s, 100, -10);
  unknown.mutable_start()->set_session_id("s-nope");
  EXPECT_EQ(first(unknown).error_code(), grpc::StatusCode::NOT_FOUND);
  const grpc::Status nan = first(Start(s, std::nan(""), 0));
  EXPECT_EQ(nan.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(nan.error_message(), HasSubstr("start.qalpha_nm"));
  const grpc::Status human = first(Start(s, 1000, 0));
  EXPECT_EQ(human.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(human.error_message(), HasSubstr("human"));
  // None of them started a swing.
  v1::GetSessionRequest g;
  g.set_session_id(s.session_id());
  v1::SessionInfo info;
  ASSERT_TRUE(stub_->GetSession(Ctx().get(), g, &info).ok());
  EXPECT_EQ(info.swings(), 0u);
  EXPECT_EQ(info.phase(), v1::SWING_PHASE_ADDRESS);
}

TEST_F(SessionServiceTest, ShutdownMidSwingEndsDriverAndWatcherWithUnavailable) {
  const v1::CreateSessionResponse s = Create();
  auto wctx = Ctx();
  v1::WatchSwingRequest w;
  w.set_session_id(s.session_id());
  auto watch = stub_->WatchSwing(wctx.get(), w);
  v1::SwingSnapshot snap;
  ASSERT_TRUE(watch->Read(&snap));  // registered
  auto dctx = Ctx();
  auto drive = stub_->DriveSwing(dctx.get());
  // A slow swing: small torques and a 5 s duration, so it is still going at shutdown.
  v1::DriveSwingRequest start = Start(s, 5, 0);
  start.mutable_start()->set_stop(v1::SWING_STOP_DURATION);
  start.mutable_start()->set_duration_s(5);
  ASSERT_TRUE(drive->Write(start));
  ASSERT_TRUE(drive->Read(&snap));
  EXPECT_EQ(snap.phase(), v1::SWING_PHASE_SWINGING);
  const auto t0 = std::chrono::steady_clock::now();
  app_->Shutdown(absl::Seconds(1));
  while (drive->Read(&snap)) {
  }
  EXPECT_EQ(drive->Finish().error_code(), grpc::StatusCode::UNAVAILABLE);
  while (watch->Read(&snap)) {
  }
  EXPECT_EQ(watch->Finish().error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_TRUE(snap.has_state());  // the last snapshot is a full one
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(3));
}

}  // namespace
}  // namespace sportsim::server
