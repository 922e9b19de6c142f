// Tables through gRPC, in-process on a loopback port: a shot watched to rest equals
// SimulateShot bit for bit; a stalled reader never delays another; a reader that goes away
// leaves nothing behind; shutdown ends streams with UNAVAILABLE after a last snapshot.
#include <atomic>
#include <chrono>
#include <thread>

#include <grpcpp/grpcpp.h>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/app/server_app.h"
#include "sportsim/v1/billiards.grpc.pb.h"

namespace sportsim::server {
namespace {

using ::testing::HasSubstr;
using Clock = std::chrono::steady_clock;

class TableServiceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start({.listen = "127.0.0.1:0"});
    ASSERT_TRUE(app.ok()) << app.status();
    app_ = *std::move(app);
    stub_ = v1::Billiards::NewStub(
        grpc::CreateChannel(app_->address(), grpc::InsecureChannelCredentials()));
  }
  std::unique_ptr<grpc::ClientContext> Ctx() {
    auto c = std::make_unique<grpc::ClientContext>();
    c->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
    return c;
  }
  // A 9-ball rack on heavy cloth at 240 Hz: a 3 m/s break is over in about a second.
  v1::CreateTableRequest Quick() {
    v1::CreateTableRequest r;
    r.mutable_table()->set_rack("9ball");
    (*r.mutable_table()->mutable_params())["mu_roll"] = 0.3;
    (*r.mutable_table()->mutable_params())["spin_decel_rps2"] = 100;
    r.set_tick_hz(240);
    return r;
  }
  v1::CreateTableResponse Create(const v1::CreateTableRequest& r) {
    v1::CreateTableResponse t;
    const grpc::Status s = stub_->CreateTable(Ctx().get(), r, &t);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return t;
  }
  v1::CueStrike Strike() {
    v1::CueStrike s;
    s.set_ball_speed_mps(3);
    s.set_phi_deg(0.3);
    s.set_a(0.1);
    return s;
  }
  grpc::Status Shoot(const v1::CreateTableResponse& t, int seat, v1::ShootResponse* out) {
    v1::ShootRequest r;
    r.set_table_id(t.table_id());
    r.set_token(t.seats(seat).token());
    *r.mutable_strike() = Strike();
    return stub_->Shoot(Ctx().get(), r, out);
  }
  std::unique_ptr<ServerApp> app_;
  std::unique_ptr<v1::Billiards::Stub> stub_;
};

TEST_F(TableServiceTest, WatchedShotEndsBitIdenticalToSimulateShot) {
  const v1::CreateTableRequest req = Quick();
  const v1::CreateTableResponse t = Create(req);
  grpc::ClientContext watch_ctx;
  v1::WatchTableRequest w;
  w.set_table_id(t.table_id());
  w.set_rate_hz(60);
  auto reader = stub_->WatchTable(&watch_ctx, w);
  v1::TableSnapshot snap;
  ASSERT_TRUE(reader->Read(&snap));  // the table as it is: at rest, full state
  EXPECT_TRUE(snap.at_rest());
  EXPECT_EQ(snap.balls_size(), 10);
  v1::ShootResponse shot;
  ASSERT_TRUE(Shoot(t, 0, &shot).ok());
  EXPECT_EQ(shot.shot_id(), 1u);
  bool ended = false;
  int snapshots = 0;
  while (!ended && reader->Read(&snap)) {
    ++snapshots;
    for (const v1::TableEvent& e : snap.events()) ended |= e.kind() == v1::shot_end;
  }
  ASSERT_TRUE(ended);
  EXPECT_TRUE(snap.at_rest());
  EXPECT_GT(snapshots, 10);
  watch_ctx.TryCancel();
  (void)reader->Finish();

  v1::SimulateShotRequest sim;
  *sim.mutable_table() = req.table();
  *sim.mutable_strike() = Strike();
  v1::SimulateShotResponse want;
  ASSERT_TRUE(stub_->SimulateShot(Ctx().get(), sim, &want).ok());
  ASSERT_EQ(snap.balls_size(), want.balls_size());
  for (int i = 0; i < want.balls_size(); ++i) {
    EXPECT_EQ(snap.balls(i).SerializeAsString(), want.balls(i).SerializeAsString()) << i;
  }
}

TEST_F(TableServiceTest, ErrorsCarryTheirCodes) {
  const v1::CreateTableResponse t = Create(Quick());
  v1::ShootResponse shot;
  EXPECT_EQ(Shoot(t, 1, &shot).error_code(), grpc::StatusCode::PERMISSION_DENIED);
  v1::CreateTableRequest bad = Quick();
  bad.set_tick_hz(std::numeric_limits<double>::infinity());
  v1::CreateTableResponse none;
  const grpc::Status s = stub_->CreateTable(Ctx().get(), bad, &none);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("tick_hz"));
  grpc::ClientContext ctx;
  v1::WatchTableRequest w;
  w.set_table_id("t-unknown");
  auto reader = stub_->WatchTable(&ctx, w);
  v1::TableSnapshot snap;
  EXPECT_FALSE(reader->Read(&snap));
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::NOT_FOUND);
  // Oversized: a table setup of 100k placements is far over the request limit.
  v1::CreateTableRequest huge = Quick();
  for (int i = 0; i < 100000; ++i) {
    v1::BallPlacement* p = huge.mutable_table()->add_balls();
    p->set_id("ball-with-a-long-name");
  }
  EXPECT_EQ(stub_->CreateTable(Ctx().get(), huge, &none).error_code(),
            grpc::StatusCode::RESOURCE_EXHAUSTED);
  v1::ListTablesResponse list;
  ASSERT_TRUE(stub_->ListTables(Ctx().get(), {}, &list).ok());
  EXPECT_EQ(list.total(), 1u);
}

TEST_F(TableServiceTest, AStalledWatcherNeverDelaysAReader) {
  v1::CreateTableRequest req = Quick();
  req.set_tick_hz(120);
  (*req.mutable_table()->mutable_params())["mu_roll"] = 0.05;  // a few seconds of motion
  const v1::CreateTableResponse t = Create(req);
  // The stalled client, on its own connection with a small flow-control window, asks for every
  // tick and every field, then never reads: the server's writes to it stop completing.
  grpc::ChannelArguments small;
  small.SetInt(GRPC_ARG_HTTP2_BDP_PROBE, 0);
  small.SetInt(GRPC_ARG_HTTP2_STREAM_LOOKAHEAD_BYTES, 8192);
  auto stalled_stub = v1::Billiards::NewStub(grpc::CreateCustomChannel(
      app_->address(), grpc::InsecureChannelCredentials(), small));
  grpc::ClientContext stalled_ctx;
  v1::WatchTableRequest all;
  all.set_table_id(t.table_id());
  auto stalled = stalled_stub->WatchTable(&stalled_ctx, all);
  grpc::ClientContext ctx;
  v1::WatchTableRequest w;
  w.set_table_id(t.table_id());
  w.set_rate_hz(60);
  auto reader = stub_->WatchTable(&ctx, w);
  v1::TableSnapshot snap;
  ASSERT_TRUE(reader->Read(&snap));
  v1::ShootResponse shot;
  ASSERT_TRUE(Shoot(t, 0, &shot).ok());
  std::vector<Clock::time_point> arrivals;
  bool ended = false;
  int64_t last_tick = snap.tick();
  while (!ended && reader->Read(&snap)) {
    arrivals.push_back(Clock::now());
    EXPECT_GE(snap.tick(), last_tick);
    last_tick = snap.tick();
    for (const v1::TableEvent& e : snap.events()) ended |= e.kind() == v1::shot_end;
  }
  ASSERT_TRUE(ended);
  ASSERT_GT(arrivals.size(), 60u);
  // Snapshots every 1/60 s; a loaded 2-core machine (or AddressSanitizer) gets 0.5 s for the
  // worst gap, still far less than the stalled stream's wait.
  double worst = 0;
  for (size_t i = 1; i < arrivals.size(); ++i) {
    worst = std::max(worst, std::chrono::duration<double>(arrivals[i] - arrivals[i - 1]).count());
  }
  EXPECT_LT(worst, 0.5);
  EXPECT_EQ(app_->tables().stats().watchers, 2);
  // Now the stalled client reads: what was buffered, then the newest snapshot with every event
  // it missed. Its own counter shows snapshots were replaced while it stalled.
  bool stalled_saw_end = false;
  uint64_t stalled_replaced = 0;
  while (!stalled_saw_end && stalled->Read(&snap)) {
    stalled_replaced = std::max(stalled_replaced, snap.snapshots_replaced());
    for (const v1::TableEvent& e : snap.events()) stalled_saw_end |= e.kind() == v1::shot_end;
  }
  EXPECT_TRUE(stalled_saw_end);
  EXPECT_GT(stalled_replaced, 0u);
  // Disconnecting both leaves no watcher behind.
  stalled_ctx.TryCancel();
  ctx.TryCancel();
  (void)stalled->Finish();
  (void)reader->Finish();
  v1::GetTableRequest get;
  get.set_table_id(t.table_id());
  v1::TableInfo info;
  for (int i = 0; i < 100; ++i) {
    ASSERT_TRUE(stub_->GetTable(Ctx().get(), get, &info).ok());
    if (info.watchers() == 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(info.watchers(), 0u);
}

TEST_F(TableServiceTest, ShutdownEndsStreamsWithUnavailableAfterALastSnapshot) {
  v1::CreateTableRequest req = Quick();
  (*req.mutable_table()->mutable_params())["mu_roll"] = 0.01;  // still moving at shutdown
  const v1::CreateTableResponse t = Create(req);
  grpc::ClientContext ctx;
  v1::WatchTableRequest w;
  w.set_table_id(t.table_id());
  w.set_rate_hz(30);
  auto reader = stub_->WatchTable(&ctx, w);
  v1::TableSnapshot snap;
  ASSERT_TRUE(reader->Read(&snap));
  v1::ShootResponse shot;
  ASSERT_TRUE(Shoot(t, 0, &shot).ok());
  ASSERT_TRUE(reader->Read(&snap));
  std::atomic<bool> stopped{false};
  const Clock::time_point t0 = Clock::now();
  std::thread stopper([&] {
    app_->Shutdown(absl::Seconds(3));
    app_->Wait();
    stopped = true;
  });
  v1::TableSnapshot last;
  int after = 0;
  while (reader->Read(&snap)) {
    last = snap;
    ++after;
  }
  const grpc::Status end = reader->Finish();
  stopper.join();
  const double took = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_EQ(end.error_code(), grpc::StatusCode::UNAVAILABLE) << end.error_message();
  ASSERT_GE(after, 1);
  EXPECT_EQ(last.balls_size(), 10);  // the last snapshot is a full state
  EXPECT_FALSE(last.at_rest());
  EXPECT_LT(took, 2.0);  // streams end at once, not at the grace
}

}  // namespace
}  // namespace sportsim::server
