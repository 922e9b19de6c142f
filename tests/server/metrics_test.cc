// The Prometheus endpoint, scraped over HTTP on loopback as Prometheus would: world gauges,
// RPCs by method and code, rejected inputs, the tick-duration histogram, and no ids as labels.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <sstream>
#include <thread>
#include <string>

#include <grpcpp/grpcpp.h>

#include "absl/strings/str_format.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/app/server_app.h"
#include "sportsim/v1/billiards.grpc.pb.h"
#include "sportsim/v1/swing.grpc.pb.h"

namespace sportsim::server {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

// GET /metrics on 127.0.0.1:port; the whole HTTP response.
std::string Scrape(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) != 0) {
    close(fd);
    return "";
  }
  const std::string request =
      "GET /metrics HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n";
  send(fd, request.data(), request.size(), 0);
  std::string out;
  char buf[4096];
  for (ssize_t n; (n = recv(fd, buf, sizeof(buf), 0)) > 0;) out.append(buf, static_cast<size_t>(n));
  close(fd);
  return out;
}

// The value of the sample whose line starts with `name` and contains every label in `labels`.
double Value(const std::string& text, const std::string& name,
             const std::vector<std::string>& labels) {
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(name, 0) != 0 || (line.size() > name.size() && line[name.size()] != '{' &&
                                     line[name.size()] != ' ')) {
      continue;
    }
    bool all = true;
    for (const std::string& l : labels) all = all && line.find(l) != std::string::npos;
    if (all) return std::stod(line.substr(line.rfind(' ') + 1));
  }
  return -1;
}

TEST(MetricsTest, ScrapeShowsWorldsRpcsRejectionsAndTicks) {
  absl::StatusOr<std::unique_ptr<ServerApp>> app =
      ServerApp::Start({.listen = "127.0.0.1:0", .metrics_listen = "127.0.0.1:0"});
  ASSERT_TRUE(app.ok()) << app.status();
  ASSERT_GT((*app)->metrics_port(), 0);
  auto channel = grpc::CreateChannel((*app)->address(), grpc::InsecureChannelCredentials());
  auto billiards = v1::Billiards::NewStub(channel);
  auto swing = v1::Swing::NewStub(channel);

  v1::CreateTableResponse table;
  {
    grpc::ClientContext ctx;
    ASSERT_TRUE(billiards->CreateTable(&ctx, v1::CreateTableRequest(), &table).ok());
  }
  for (int i = 0; i < 2; ++i) {  // NOT_FOUND twice
    grpc::ClientContext ctx;
    v1::GetTableRequest r;
    r.set_table_id("t-missing");
    v1::TableInfo info;
    EXPECT_EQ(billiards->GetTable(&ctx, r, &info).error_code(), grpc::StatusCode::NOT_FOUND);
  }
  v1::CreateSessionResponse session;
  {
    grpc::ClientContext ctx;
    ASSERT_TRUE(swing->CreateSession(&ctx, v1::CreateSessionRequest(), &session).ok());
  }
  {
    // A swing, so that ticks run (and the tick histogram fills).
    grpc::ClientContext ctx;
    v1::StartSwingRequest r;
    r.set_session_id(session.session_id());
    r.set_token(session.token());
    v1::StartSwingResponse out;
    ASSERT_TRUE(swing->StartSwing(&ctx, r, &out).ok());
  }
  for (int i = 0; i < 300 && (*app)->sessions().stats().running > 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }

  const std::string text = Scrape((*app)->metrics_port());
  ASSERT_THAT(text, HasSubstr("200 OK"));
  EXPECT_EQ(Value(text, "sportsim_worlds", {"world=\"table\""}), 1);
  EXPECT_EQ(Value(text, "sportsim_worlds", {"world=\"session\""}), 1);
  EXPECT_EQ(Value(text, "sportsim_rpcs_total",
                  {"method=\"/sportsim.v1.Billiards/GetTable\"", "code=\"NOT_FOUND\""}),
            2);
  EXPECT_EQ(Value(text, "sportsim_rpcs_total",
                  {"method=\"/sportsim.v1.Swing/StartSwing\"", "code=\"OK\""}),
            1);
  EXPECT_EQ(Value(text, "sportsim_rejected_inputs_total", {"code=\"NOT_FOUND\""}), 2);
  // The chapter's swing takes about 0.29 s: over 100 ticks at 400 Hz.
  const double session_ticks = Value(text, "sportsim_ticks_total", {"world=\"session\""});
  EXPECT_GT(session_ticks, 100);
  // The histogram counts wakes, and one wake of a world that fell behind advances up to
  // max_catchup_ticks (12 by default) ticks at once: a loaded machine (a sanitizer build, other
  // jobs) has fewer wakes than ticks, never fewer than ticks / 12.
  EXPECT_GE(Value(text, "sportsim_tick_duration_seconds_count", {}), session_ticks / 12);
  EXPECT_THAT(text, HasSubstr("sportsim_tick_duration_seconds_bucket{le=\"+Inf\"}"));
  EXPECT_GE(Value(text, "sportsim_late_ticks_total", {"world=\"table\""}), 0);
  // Ids never become labels.
  EXPECT_THAT(text, Not(HasSubstr(table.table_id())));
  EXPECT_THAT(text, Not(HasSubstr(session.session_id())));
}

TEST(MetricsTest, OffByDefaultAndABusyPortIsAnError) {
  absl::StatusOr<std::unique_ptr<ServerApp>> plain = ServerApp::Start({.listen = "127.0.0.1:0"});
  ASSERT_TRUE(plain.ok()) << plain.status();
  EXPECT_EQ((*plain)->metrics_port(), 0);
  absl::StatusOr<std::unique_ptr<ServerApp>> first =
      ServerApp::Start({.listen = "127.0.0.1:0", .metrics_listen = "127.0.0.1:0"});
  ASSERT_TRUE(first.ok()) << first.status();
  absl::StatusOr<std::unique_ptr<ServerApp>> second = ServerApp::Start(
      {.listen = "127.0.0.1:0",
       .metrics_listen = absl::StrFormat("127.0.0.1:%d", (*first)->metrics_port())});
  ASSERT_FALSE(second.ok());
  EXPECT_EQ(second.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(second.status().message(), HasSubstr("metrics_listen"));
}

TEST(MetricsTest, TheJournalCountsItsCommitsAndSaysItIsUp) {
  char dir_template[] = "/tmp/sportsim-metrics-XXXXXX";
  ASSERT_NE(mkdtemp(dir_template), nullptr);
  ServerConfig config{.listen = "127.0.0.1:0", .metrics_listen = "127.0.0.1:0"};
  config.store.data_dir = dir_template;
  {
    absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start(config);
    ASSERT_TRUE(app.ok()) << app.status();
    const std::string before = Scrape((*app)->metrics_port());
    EXPECT_EQ(Value(before, "sportsim_journal_up", {}), 1);
    const double writes = Value(before, "sportsim_journal_writes_total", {});
    ASSERT_GE(writes, 0);
    absl::StatusOr<v1::CreateTableResponse> table =
        (*app)->tables().Create(v1::CreateTableRequest());
    ASSERT_TRUE(table.ok()) << table.status();
    v1::SetTurnRequest turn;
    turn.set_table_id(table->table_id());
    turn.set_token(table->seats(0).token());
    turn.set_seat(1);
    ASSERT_TRUE((*app)->tables().SetTurn(turn).ok());
    const std::string after = Scrape((*app)->metrics_port());
    // The creation and the turn, each durable before its reply.
    EXPECT_EQ(Value(after, "sportsim_journal_writes_total", {}), writes + 2);
    EXPECT_GE(Value(after, "sportsim_journal_commits_total", {}), 2);
    EXPECT_EQ(Value(after, "sportsim_journal_failed_commits_total", {}), 0);
  }
  std::filesystem::remove_all(dir_template);
}

}  // namespace
}  // namespace sportsim::server
