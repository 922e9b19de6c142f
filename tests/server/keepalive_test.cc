// Keepalive settings of the server (ServerConfig, docs/operations.md): the durations are
// checked, and the client-ping policy is the one configured. A client pinging faster than
// min_client_ping_interval loses its connection (GOAWAY too_many_pings) and with it an open
// stream; the same client against a server that allows its rate keeps the stream.
#include <chrono>
#include <future>
#include <memory>
#include <thread>

#include <grpcpp/grpcpp.h>

#include "absl/time/time.h"
#include "gmock/gmock.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "gtest/gtest.h"
#include "server/app/server_app.h"

namespace sportsim::server {
namespace {

using ::testing::HasSubstr;

TEST(KeepaliveTest, OutOfRangeDurationsAreRefusedByName) {
  ServerConfig config{.listen = "127.0.0.1:0"};
  config.keepalive_time = absl::ZeroDuration();
  absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start(config);
  ASSERT_FALSE(app.ok());
  EXPECT_EQ(app.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(app.status().message(), HasSubstr("--keepalive_time"));

  config = ServerConfig{.listen = "127.0.0.1:0"};
  config.keepalive_timeout = absl::InfiniteDuration();
  app = ServerApp::Start(config);
  ASSERT_FALSE(app.ok());
  EXPECT_THAT(app.status().message(), HasSubstr("--keepalive_timeout"));

  config = ServerConfig{.listen = "127.0.0.1:0"};
  config.min_client_ping_interval = absl::Seconds(-1);
  app = ServerApp::Start(config);
  ASSERT_FALSE(app.ok());
  EXPECT_THAT(app.status().message(), HasSubstr("--min_client_ping_interval"));
}

// Opens a health Watch stream (one message, then silence) on a channel with a 50 ms keepalive
// time, waits `window`, and returns how the stream ended: UNAVAILABLE when the server dropped
// the connection, CANCELLED when it was still open and we cancelled it. (gRPC 1.51's client
// holds a connection with an open call to one ping a second whatever it is asked, so this
// client pings at ~0.05, 1.05, 2.05, ... s.)
grpc::StatusCode WatchWithEagerPings(const ServerApp& app, std::chrono::milliseconds window) {
  grpc::ChannelArguments args;
  args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, 50);
  args.SetInt(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 5000);
  args.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  args.SetInt(GRPC_ARG_HTTP2_MAX_PINGS_WITHOUT_DATA, 0);
  auto channel =
      grpc::CreateCustomChannel(app.address(), grpc::InsecureChannelCredentials(), args);
  auto stub = grpc::health::v1::Health::NewStub(channel);
  grpc::ClientContext ctx;
  auto reader = stub->Watch(&ctx, grpc::health::v1::HealthCheckRequest());
  grpc::health::v1::HealthCheckResponse first;
  EXPECT_TRUE(reader->Read(&first));
  EXPECT_EQ(first.status(), grpc::health::v1::HealthCheckResponse::SERVING);
  std::future<grpc::Status> ended = std::async(std::launch::async, [&] {
    grpc::health::v1::HealthCheckResponse more;
    while (reader->Read(&more)) {
    }
    return reader->Finish();
  });
  if (ended.wait_for(window) == std::future_status::timeout) ctx.TryCancel();
  return ended.get().error_code();
}

TEST(KeepaliveTest, ClientsPingingFasterThanAllowedLoseTheConnection) {
  ServerConfig strict{.listen = "127.0.0.1:0"};
  strict.min_client_ping_interval = absl::Seconds(10);
  absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start(strict);
  ASSERT_TRUE(app.ok()) << app.status();
  // Pings a second apart against a 10 s minimum: the pings after the first are strikes, and
  // past the two allowed the server sends GOAWAY (too_many_pings); the stream ends ~3 s in.
  EXPECT_EQ(WatchWithEagerPings(**app, std::chrono::milliseconds(8000)),
            grpc::StatusCode::UNAVAILABLE);
}

TEST(KeepaliveTest, ClientsPingingWithinThePolicyKeepTheirStreams) {
  ServerConfig lenient{.listen = "127.0.0.1:0"};
  lenient.min_client_ping_interval = absl::Milliseconds(500);
  absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start(lenient);
  ASSERT_TRUE(app.ok()) << app.status();
  // The same client, pinging a second apart for 5 s (the strict server drops it at ~3 s),
  // stays within a 500 ms minimum: the stream is still open when cancelled.
  EXPECT_EQ(WatchWithEagerPings(**app, std::chrono::milliseconds(5000)),
            grpc::StatusCode::CANCELLED);
}

}  // namespace
}  // namespace sportsim::server
