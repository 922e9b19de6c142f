// Bots and browsers against the real server in-process on loopback ports: SimulateShots (a
// batch of candidate shots streamed in request order, equal to SimulateShot shot for shot,
// seeded noise, per-strike errors, limits, the CPU budget, cancellation), PreviewShot (aim
// lines: who may ask, no side effect, the paths on SimulateShot's trajectory) and gRPC-Web
// spoken as plain HTTP/1.1 from a socket (unary in binary and text, a server stream closed by
// the client, CORS, the request limit, refused methods, the viewer's static files).
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/strings/ascii.h"
#include "absl/strings/escaping.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/app/server_app.h"
#include "tests/server/web_client.h"
#include "sportsim/v1/billiards.grpc.pb.h"
#include "sportsim/v1/common.grpc.pb.h"
#include "sportsim/v1/swing.grpc.pb.h"

namespace sportsim::server {
namespace {

using ::testing::HasSubstr;
using Clock = std::chrono::steady_clock;

// ---------------------------------------------------------------------------------------------
// Fixture: a server started per test from a config the test may change first.

class BotsTest : public ::testing::Test {
 protected:
  void SetUp() override { config_.listen = "127.0.0.1:0"; }
  void Start() {
    absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start(config_);
    ASSERT_TRUE(app.ok()) << app.status();
    app_ = *std::move(app);
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(64 << 20);
    args.SetMaxSendMessageSize(64 << 20);
    channel_ = grpc::CreateCustomChannel(app_->address(), grpc::InsecureChannelCredentials(), args);
    stub_ = v1::Billiards::NewStub(channel_);
  }
  std::unique_ptr<grpc::ClientContext> Ctx(int seconds = 60) {
    auto c = std::make_unique<grpc::ClientContext>();
    c->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(seconds));
    return c;
  }

  static v1::TableSetup NineBall() {
    v1::TableSetup t;
    t.set_preset("pool-9ft");
    t.set_rack("9ball");
    return t;
  }
  // Reproducible candidate strikes of the cue ball: every heading, speeds from soft to a
  // break, a little spin.
  static std::vector<v1::CueStrike> RandomStrikes(int n, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> speed(0.5, 6.0), phi(-180, 180), tip(-0.3, 0.3);
    std::vector<v1::CueStrike> out;
    for (int i = 0; i < n; ++i) {
      v1::CueStrike s;
      s.set_ball_speed_mps(speed(rng));
      s.set_phi_deg(phi(rng));
      s.set_a(tip(rng));
      s.set_b(tip(rng));
      out.push_back(s);
    }
    return out;
  }
  static v1::SimulateShotsRequest Batch(const std::vector<v1::CueStrike>& strikes) {
    v1::SimulateShotsRequest r;
    *r.mutable_table() = NineBall();
    for (const v1::CueStrike& s : strikes) *r.add_strikes() = s;
    return r;
  }
  struct BatchResult {
    grpc::Status status;
    std::vector<v1::ShotOutcome> outcomes;
    int messages = 0;
  };
  BatchResult RunBatch(const v1::SimulateShotsRequest& request, int seconds = 120) {
    BatchResult out;
    auto ctx = Ctx(seconds);
    auto reader = stub_->SimulateShots(ctx.get(), request);
    v1::SimulateShotsResponse r;
    while (reader->Read(&r)) {
      ++out.messages;
      for (const v1::ShotOutcome& o : r.outcomes()) out.outcomes.push_back(o);
    }
    out.status = reader->Finish();
    return out;
  }
  // What SimulateShot says of the same strike, in SimulateShots' summary terms.
  struct Summary {
    std::string first_contact;
    std::vector<std::string> pocketed, pockets;
    double t_rest_s = 0;
    v1::SimulateShotResponse full;
  };
  Summary SimulateOne(const v1::TableSetup& table, const v1::CueStrike& strike,
                      double sample_rate_hz = 0) {
    v1::SimulateShotRequest req;
    *req.mutable_table() = table;
    *req.mutable_strike() = strike;
    req.set_sample_rate_hz(sample_rate_hz);
    Summary s;
    const grpc::Status st = stub_->SimulateShot(Ctx().get(), req, &s.full);
    EXPECT_TRUE(st.ok()) << st.error_message();
    const std::string cue = strike.ball().empty() ? "cue" : strike.ball();
    for (const v1::TableEvent& e : s.full.events()) {
      if (e.kind() == v1::ball_ball && s.first_contact.empty() && e.balls_size() == 2 &&
          (e.balls(0) == cue || e.balls(1) == cue)) {
        s.first_contact = e.balls(0) == cue ? e.balls(1) : e.balls(0);
      }
      if (e.kind() == v1::ball_pocket) {
        s.pocketed.push_back(e.balls(0));
        s.pockets.push_back(e.pocket());
      }
    }
    s.t_rest_s = s.full.t_rest_s();
    return s;
  }
  // Polls `done` every 10 ms for up to `seconds`.
  template <typename Fn>
  static bool Eventually(Fn done, double seconds) {
    const auto until = Clock::now() + std::chrono::duration<double>(seconds);
    while (Clock::now() < until) {
      if (done()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return done();
  }

  ServerConfig config_;
  std::unique_ptr<ServerApp> app_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Billiards::Stub> stub_;
};

std::vector<std::string> Strings(const google::protobuf::RepeatedPtrField<std::string>& r) {
  return {r.begin(), r.end()};
}

// ---------------------------------------------------------------------------------------------
// SimulateShots

TEST_F(BotsTest, BatchStreamsEveryOutcomeInRequestOrderOverSeveralMessages) {
  Start();
  v1::SimulateShotsRequest req = Batch(RandomStrikes(40, 1));
  req.set_samples_per_strike(5);
  req.set_noise(0.5);
  req.set_seed(11);
  const BatchResult r = RunBatch(req);
  ASSERT_TRUE(r.status.ok()) << r.status.error_message();
  ASSERT_EQ(r.outcomes.size(), 40u * 5u);
  EXPECT_GT(r.messages, 1) << "200 outcomes in one message: not streamed";
  for (size_t n = 0; n < r.outcomes.size(); ++n) {
    EXPECT_EQ(r.outcomes[n].index(), n / 5) << n;
    EXPECT_EQ(r.outcomes[n].sample(), n % 5) << n;
    EXPECT_EQ(r.outcomes[n].error(), "") << n;
    EXPECT_GT(r.outcomes[n].t_rest_s(), 0) << n;
    EXPECT_GT(r.outcomes[n].events_handled(), 0u) << n;
  }
}

TEST_F(BotsTest, SamplesPerStrikeZeroMeansOne) {
  Start();
  const BatchResult r = RunBatch(Batch(RandomStrikes(3, 2)));
  ASSERT_TRUE(r.status.ok()) << r.status.error_message();
  ASSERT_EQ(r.outcomes.size(), 3u);
  for (uint32_t i = 0; i < 3; ++i) {
    EXPECT_EQ(r.outcomes[i].index(), i);
    EXPECT_EQ(r.outcomes[i].sample(), 0u);
  }
}

TEST_F(BotsTest, NoiselessOutcomesEqualSimulateShotBitForBit) {
  Start();
  std::vector<v1::CueStrike> strikes = RandomStrikes(24, 3);
  // A break (many balls fall) and a straight shot at the rack.
  v1::CueStrike brk;
  brk.set_ball_speed_mps(8);
  brk.set_phi_deg(0.2);
  strikes.push_back(brk);
  v1::SimulateShotsRequest req = Batch(strikes);
  req.set_samples_per_strike(2);  // without noise, every sample is the strike itself
  req.set_outcome(v1::SHOT_OUTCOME_FINAL);
  const BatchResult r = RunBatch(req);
  ASSERT_TRUE(r.status.ok()) << r.status.error_message();
  ASSERT_EQ(r.outcomes.size(), strikes.size() * 2);
  int with_contact = 0, with_pocket = 0;
  for (size_t n = 0; n < r.outcomes.size(); ++n) {
    const v1::ShotOutcome& o = r.outcomes[n];
    const Summary want = SimulateOne(NineBall(), strikes[n / 2]);
    EXPECT_EQ(o.first_contact(), want.first_contact) << n;
    EXPECT_EQ(Strings(o.pocketed()), want.pocketed) << n;
    EXPECT_EQ(Strings(o.pockets()), want.pockets) << n;
    EXPECT_EQ(o.t_rest_s(), want.t_rest_s) << n;  // bit-equal
    ASSERT_EQ(o.balls_size(), want.full.balls_size()) << n;
    for (int i = 0; i < o.balls_size(); ++i) {
      EXPECT_EQ(o.balls(i).SerializeAsString(), want.full.balls(i).SerializeAsString())
          << n << " ball " << o.balls(i).id();
    }
    with_contact += !o.first_contact().empty();
    with_pocket += o.pocketed_size() > 0;
  }
  // The comparison means something: contacts and pocketed balls were there to compare.
  EXPECT_GT(with_contact, 10);
  EXPECT_GT(with_pocket, 0);
}

TEST_F(BotsTest, NoisySamplesDifferAndTheSeedReproducesTheBatch) {
  Start();
  v1::SimulateShotsRequest req = Batch(RandomStrikes(6, 4));
  req.set_samples_per_strike(8);
  req.set_noise(1);
  req.set_seed(2024);
  req.set_outcome(v1::SHOT_OUTCOME_FINAL);
  const BatchResult a = RunBatch(req);
  ASSERT_TRUE(a.status.ok()) << a.status.error_message();
  ASSERT_EQ(a.outcomes.size(), 48u);
  for (int i = 0; i < 6; ++i) {
    std::set<std::string> finals;
    std::set<double> t_rest;
    for (int k = 0; k < 8; ++k) {
      const v1::ShotOutcome& o = a.outcomes[static_cast<size_t>(i * 8 + k)];
      ASSERT_EQ(o.error(), "");
      std::string balls;
      for (const v1::BallState& b : o.balls()) balls += b.SerializeAsString();
      finals.insert(balls);
      t_rest.insert(o.t_rest_s());
    }
    EXPECT_EQ(finals.size(), 8u) << "strike " << i << ": noise samples that are the same shot";
    EXPECT_EQ(t_rest.size(), 8u) << "strike " << i;
  }
  const BatchResult again = RunBatch(req);
  ASSERT_TRUE(again.status.ok());
  ASSERT_EQ(again.outcomes.size(), a.outcomes.size());
  for (size_t n = 0; n < a.outcomes.size(); ++n) {
    EXPECT_EQ(again.outcomes[n].SerializeAsString(), a.outcomes[n].SerializeAsString()) << n;
  }
  req.set_seed(2025);
  const BatchResult other = RunBatch(req);
  ASSERT_TRUE(other.status.ok());
  ASSERT_EQ(other.outcomes.size(), a.outcomes.size());
  int same = 0;
  for (size_t n = 0; n < a.outcomes.size(); ++n) {
    same += other.outcomes[n].SerializeAsString() == a.outcomes[n].SerializeAsString();
  }
  EXPECT_EQ(same, 0) << "another seed, yet outcomes identical";
}

// billiards.proto: "sample k of strike i: a seed derived from seed, i and k". So asking for
// more samples keeps the ones already seen (a bot refines its best candidates that way).
TEST_F(BotsTest, ASamplesNoiseDependsOnTheSeedTheStrikeAndTheSampleOnly) {
  Start();
  v1::SimulateShotsRequest req = Batch(RandomStrikes(3, 14));
  req.set_noise(1);
  req.set_seed(99);
  req.set_outcome(v1::SHOT_OUTCOME_FINAL);
  req.set_samples_per_strike(2);
  const BatchResult two = RunBatch(req);
  req.set_samples_per_strike(4);
  const BatchResult four = RunBatch(req);
  ASSERT_TRUE(two.status.ok() && four.status.ok());
  ASSERT_EQ(two.outcomes.size(), 6u);
  ASSERT_EQ(four.outcomes.size(), 12u);
  for (size_t i = 0; i < 3; ++i) {
    for (size_t k = 0; k < 2; ++k) {
      EXPECT_EQ(two.outcomes[i * 2 + k].SerializeAsString(),
                four.outcomes[i * 4 + k].SerializeAsString())
          << "strike " << i << " sample " << k;
    }
  }
}

TEST_F(BotsTest, AStrikeThatCannotBePlayedCarriesAnErrorAndTheOthersGoOn) {
  Start();
  std::vector<v1::CueStrike> strikes = RandomStrikes(5, 5);
  v1::CueStrike miscue = strikes[0];
  miscue.set_a(0.9);
  miscue.set_b(0.9);  // far outside the miscue limit
  strikes.insert(strikes.begin() + 2, miscue);
  v1::CueStrike ghost = strikes[0];
  ghost.set_ball("ghost");  // no such ball
  strikes.push_back(ghost);
  v1::CueStrike seeded = strikes[0];
  seeded.set_noise(1);  // noise is the batch's
  strikes.push_back(seeded);
  v1::SimulateShotsRequest req = Batch(strikes);
  req.set_samples_per_strike(2);
  const BatchResult r = RunBatch(req);
  ASSERT_TRUE(r.status.ok()) << r.status.error_message();
  ASSERT_EQ(r.outcomes.size(), strikes.size() * 2);
  for (size_t n = 0; n < r.outcomes.size(); ++n) {
    const v1::ShotOutcome& o = r.outcomes[n];
    const size_t i = n / 2;
    EXPECT_EQ(o.index(), i);
    if (i == 2 || i == strikes.size() - 2 || i == strikes.size() - 1) {
      EXPECT_NE(o.error(), "") << n;
      EXPECT_EQ(o.pocketed_size(), 0) << n;
      EXPECT_EQ(o.t_rest_s(), 0) << n;
    } else {
      EXPECT_EQ(o.error(), "") << n;
      EXPECT_GT(o.t_rest_s(), 0) << n;
    }
  }
  EXPECT_THAT(r.outcomes[4].error(), HasSubstr("miscue"));
  EXPECT_THAT(r.outcomes[2 * (strikes.size() - 2)].error(), HasSubstr("ghost"));
  EXPECT_THAT(r.outcomes[2 * (strikes.size() - 1)].error(), HasSubstr("noise"));
}

TEST_F(BotsTest, OutcomeKindsCarryBallsAndEvents) {
  Start();
  const std::vector<v1::CueStrike> strikes = RandomStrikes(4, 6);
  v1::SimulateShotsRequest req = Batch(strikes);
  const BatchResult summary = RunBatch(req);
  req.set_outcome(v1::SHOT_OUTCOME_FINAL);
  const BatchResult final_ = RunBatch(req);
  req.set_outcome(v1::SHOT_OUTCOME_EVENTS);
  const BatchResult events = RunBatch(req);
  ASSERT_TRUE(summary.status.ok() && final_.status.ok() && events.status.ok());
  ASSERT_EQ(summary.outcomes.size(), 4u);
  ASSERT_EQ(final_.outcomes.size(), 4u);
  ASSERT_EQ(events.outcomes.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(summary.outcomes[i].balls_size(), 0);
    EXPECT_EQ(summary.outcomes[i].events_size(), 0);
    EXPECT_EQ(final_.outcomes[i].balls_size(), 10);
    EXPECT_EQ(final_.outcomes[i].events_size(), 0);
    EXPECT_EQ(events.outcomes[i].balls_size(), 10);
    // The summary's facts are the same whatever the kind.
    EXPECT_EQ(final_.outcomes[i].t_rest_s(), summary.outcomes[i].t_rest_s());
    EXPECT_EQ(events.outcomes[i].t_rest_s(), summary.outcomes[i].t_rest_s());
    EXPECT_EQ(events.outcomes[i].first_contact(), summary.outcomes[i].first_contact());
    // Every event SimulateShot reports, in order.
    const Summary want = SimulateOne(NineBall(), strikes[i]);
    ASSERT_EQ(events.outcomes[i].events_size(), want.full.events_size()) << i;
    for (int k = 0; k < want.full.events_size(); ++k) {
      EXPECT_EQ(events.outcomes[i].events(k).SerializeAsString(),
                want.full.events(k).SerializeAsString())
          << i << " event " << k;
    }
    EXPECT_GT(events.outcomes[i].events_size(), 0);
  }
}

TEST_F(BotsTest, BatchLimitsAreResourceExhaustedNamingTheField) {
  // Requests this large need more than the default 64 KiB request limit (see
  // DefaultRequestLimitCarriesTheLargestBatch).
  config_.max_receive_message_bytes = 8 << 20;
  Start();
  v1::CueStrike one;
  one.set_ball_speed_mps(1);
  v1::SimulateShotsRequest req;
  *req.mutable_table() = NineBall();
  for (int i = 0; i < 10001; ++i) *req.add_strikes() = one;
  BatchResult r = RunBatch(req);
  EXPECT_EQ(r.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(r.status.error_message(), HasSubstr("strikes"));
  EXPECT_TRUE(r.outcomes.empty());

  req.mutable_strikes()->DeleteSubrange(0, 10001 - 1001);
  req.set_samples_per_strike(100);  // 100100 outcomes
  r = RunBatch(req);
  EXPECT_EQ(r.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(r.status.error_message(), HasSubstr("samples_per_strike"));
  EXPECT_TRUE(r.outcomes.empty());

  req.mutable_strikes()->DeleteSubrange(0, 1000);
  req.set_samples_per_strike(1001);
  r = RunBatch(req);
  EXPECT_EQ(r.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(r.status.error_message(), HasSubstr("samples_per_strike"));

  // At the limits: accepted (summaries of gentle taps, so it stays quick).
  v1::SimulateShotsRequest at_limit;
  *at_limit.mutable_table() = NineBall();
  v1::CueStrike tap;
  tap.set_ball_speed_mps(0.05);
  for (int i = 0; i < 10000; ++i) *at_limit.add_strikes() = tap;
  r = RunBatch(at_limit);
  EXPECT_TRUE(r.status.ok()) << r.status.error_message();
  EXPECT_EQ(r.outcomes.size(), 10000u);
}

// The request limit (--max_request_bytes, 64 KiB by default) bounds a batch before its
// 10000-strike limit does, as the proto documents: about 1700 plain strikes (speed, heading,
// spin) fit, 10000 are refused with RESOURCE_EXHAUSTED before any work.
TEST_F(BotsTest, DefaultRequestLimitCarriesAboutSeventeenHundredStrikes) {
  Start();
  v1::SimulateShotsRequest fits = Batch(RandomStrikes(1600, 7));
  fits.set_max_time_s(0.001);  // the outcomes do not matter here, the request's size does
  ASSERT_LT(fits.ByteSizeLong(), 64u << 10);
  const BatchResult ok = RunBatch(fits);
  EXPECT_TRUE(ok.status.ok()) << ok.status.error_message();
  EXPECT_EQ(ok.outcomes.size(), 1600u);
  v1::SimulateShotsRequest big = Batch(RandomStrikes(10000, 7));
  big.set_max_time_s(0.001);
  const BatchResult refused = RunBatch(big);
  EXPECT_EQ(refused.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED)
      << refused.status.error_message();
  EXPECT_TRUE(refused.outcomes.empty());
}

TEST_F(BotsTest, ATinyCpuBudgetStopsABigBatch) {
  config_.work.cpu_budget = absl::Milliseconds(10);
  Start();
  v1::SimulateShotsRequest req = Batch(RandomStrikes(1000, 8));
  req.set_samples_per_strike(20);
  req.set_noise(0.5);
  const auto t0 = Clock::now();
  const BatchResult r = RunBatch(req);
  EXPECT_EQ(r.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(r.status.error_message(), HasSubstr("--max_request_cpu"));
  EXPECT_LT(r.outcomes.size(), 20000u);
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 10.0);
  // What was streamed before the budget ran out is in order and has no stopped shots in it.
  for (size_t n = 0; n < r.outcomes.size(); ++n) {
    EXPECT_EQ(r.outcomes[n].index() * 20 + r.outcomes[n].sample(), n);
    EXPECT_EQ(r.outcomes[n].error(), "") << n;
  }
  EXPECT_TRUE(Eventually([&] { return app_->pool().running() == 0; }, 5));
}

// A single shot that needs more CPU than the budget: the batch fails like a big one does; the
// shot stopped midway is not an outcome (its "error" would read as a property of the strike).
TEST_F(BotsTest, ATinyCpuBudgetStopsALongShotAsTheBatchsError) {
  config_.work.cpu_budget = absl::Milliseconds(10);
  Start();
  v1::SimulateShotsRequest req;
  *req.mutable_table() = NineBall();
  req.mutable_solver()->set_engine(v1::ENGINE_STEPPED);
  req.mutable_solver()->set_dt_s(1e-6);  // a break of several seconds: millions of steps
  v1::CueStrike brk;
  brk.set_ball_speed_mps(8);
  *req.add_strikes() = brk;
  const BatchResult r = RunBatch(req);
  EXPECT_EQ(r.status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED)
      << r.status.error_message();
  EXPECT_THAT(r.status.error_message(), HasSubstr("--max_request_cpu"));
  for (const v1::ShotOutcome& o : r.outcomes) {
    ADD_FAILURE() << "outcome " << o.index() << " streamed with error '" << o.error()
                  << "' and t_rest_s " << o.t_rest_s();
  }
}

// A flight is held to the same budget: RK4 at the smallest step the request allows, over a
// driver's ~6 s flight, is ~6e5 steps (~0.3 s of CPU in a release build, far more than 50 ms).
TEST_F(BotsTest, ATinyCpuBudgetStopsALongFlight) {
  config_.work.cpu_budget = absl::Milliseconds(50);
  Start();
  auto swing = v1::Swing::NewStub(channel_);
  v1::SimulateFlightRequest req;
  req.mutable_launch()->set_ball_speed_mps(75);
  req.mutable_launch()->set_launch_angle_deg(11);
  req.mutable_launch()->set_spin_rpm(2700);
  req.set_dt_s(1e-5);
  v1::SimulateFlightResponse resp;
  const grpc::Status st = swing->SimulateFlight(Ctx().get(), req, &resp);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
  EXPECT_THAT(st.error_message(), HasSubstr("--max_request_cpu"));
  // The same flight at 5 ms steps (~1,300, so the budget is polled once) takes ~0.5 ms of CPU
  // in a release build and a few ms under ASan: it fits.
  req.set_dt_s(5e-3);
  const grpc::Status fine = swing->SimulateFlight(Ctx().get(), req, &resp);
  EXPECT_TRUE(fine.ok()) << fine.error_message();
  EXPECT_GT(resp.carry_m(), 200.0);
  std::printf("a flight at 5 ms steps: %.2f ms of CPU (budget 50 ms)\n", 1e3 * resp.cpu_s());
}

TEST_F(BotsTest, AClientThatCancelsMidStreamEndsTheWork) {
  Start();
  v1::SimulateShotsRequest req = Batch(RandomStrikes(1000, 9));
  req.set_samples_per_strike(100);
  req.set_noise(0.5);
  grpc::ClientContext ctx;
  auto reader = stub_->SimulateShots(&ctx, req);
  v1::SimulateShotsResponse r;
  int messages = 0;
  while (messages < 2 && reader->Read(&r)) ++messages;
  ASSERT_EQ(messages, 2);
  EXPECT_GT(app_->pool().running() + app_->pool().queued(), 0) << "no work left to cancel";
  ctx.TryCancel();
  while (reader->Read(&r)) {
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
  EXPECT_TRUE(Eventually(
      [&] { return app_->pool().running() == 0 && app_->pool().queued() == 0; }, 3))
      << "running " << app_->pool().running() << ", queued " << app_->pool().queued();
  // And the pool serves the next call.
  const BatchResult next = RunBatch(Batch(RandomStrikes(2, 10)));
  EXPECT_TRUE(next.status.ok()) << next.status.error_message();
  EXPECT_EQ(next.outcomes.size(), 2u);
}

TEST_F(BotsTest, TheDeadlineStopsTheBatch) {
  Start();
  v1::SimulateShotsRequest req = Batch(RandomStrikes(1000, 13));
  req.set_samples_per_strike(100);
  req.set_noise(0.5);
  grpc::ClientContext ctx;
  ctx.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(300));
  const auto t0 = Clock::now();
  auto reader = stub_->SimulateShots(&ctx, req);
  v1::SimulateShotsResponse r;
  size_t outcomes = 0;
  while (reader->Read(&r)) outcomes += static_cast<size_t>(r.outcomes_size());
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  EXPECT_LT(outcomes, 100000u);
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 3.0);
  EXPECT_TRUE(Eventually(
      [&] { return app_->pool().running() == 0 && app_->pool().queued() == 0; }, 3));
}

TEST_F(BotsTest, BadRequestsAreInvalidArgumentNamingTheField) {
  Start();
  v1::SimulateShotsRequest req = Batch(RandomStrikes(2, 11));
  req.set_noise(101);
  BatchResult r = RunBatch(req);
  EXPECT_EQ(r.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(r.status.error_message(), HasSubstr("noise"));
  req.set_noise(0);
  req.mutable_strikes()->Clear();
  r = RunBatch(req);
  EXPECT_EQ(r.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(r.status.error_message(), HasSubstr("strikes"));
  req = Batch(RandomStrikes(2, 11));
  req.mutable_table()->set_preset("no-such-table");
  r = RunBatch(req);
  EXPECT_EQ(r.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(r.status.error_message(), HasSubstr("preset"));
}

// ---------------------------------------------------------------------------------------------
// PreviewShot

class PreviewTest : public BotsTest {
 protected:
  v1::CreateTableResponse CreateTable(std::optional<bool> aim_lines = std::nullopt,
                                      const v1::TableSetup& setup = NineBall()) {
    v1::CreateTableRequest r;
    *r.mutable_table() = setup;
    if (aim_lines.has_value()) r.set_aim_lines(*aim_lines);
    v1::CreateTableResponse t;
    const grpc::Status s = stub_->CreateTable(Ctx().get(), r, &t);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return t;
  }
  grpc::Status Preview(const v1::CreateTableResponse& t, int seat, const v1::CueStrike& strike,
                       v1::PreviewShotResponse* out, uint32_t max_events = 0) {
    v1::PreviewShotRequest r;
    r.set_table_id(t.table_id());
    r.set_token(t.seats(seat).token());
    *r.mutable_strike() = strike;
    r.set_max_events(max_events);
    return stub_->PreviewShot(Ctx().get(), r, out);
  }
  v1::TableInfo Get(const std::string& id) {
    v1::GetTableRequest r;
    r.set_table_id(id);
    v1::TableInfo info;
    EXPECT_TRUE(stub_->GetTable(Ctx().get(), r, &info).ok());
    return info;
  }
  static v1::CueStrike Aim(double speed, double phi) {
    v1::CueStrike s;
    s.set_ball_speed_mps(speed);
    s.set_phi_deg(phi);
    return s;
  }
};

TEST_F(PreviewTest, OnlyTheSeatToPlayMayPreview) {
  Start();
  const v1::CreateTableResponse t = CreateTable();
  v1::PreviewShotResponse p;
  const grpc::Status other = Preview(t, 1, Aim(3, 0.3), &p);
  EXPECT_EQ(other.error_code(), grpc::StatusCode::PERMISSION_DENIED) << other.error_message();
  EXPECT_TRUE(Preview(t, 0, Aim(3, 0.3), &p).ok());
  v1::PreviewShotRequest wrong;
  wrong.set_table_id(t.table_id());
  wrong.set_token("not-a-token");
  *wrong.mutable_strike() = Aim(3, 0.3);
  EXPECT_EQ(stub_->PreviewShot(Ctx().get(), wrong, &p).error_code(),
            grpc::StatusCode::PERMISSION_DENIED);
  wrong.set_table_id("no-such-table");
  wrong.set_token(t.seats(0).token());
  EXPECT_EQ(stub_->PreviewShot(Ctx().get(), wrong, &p).error_code(),
            grpc::StatusCode::NOT_FOUND);
}

TEST_F(PreviewTest, RefusedWhereAimLinesAreOff) {
  Start();
  const v1::CreateTableResponse off = CreateTable(false);
  v1::PreviewShotResponse p;
  const grpc::Status s = Preview(off, 0, Aim(3, 0.3), &p);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION);
  EXPECT_THAT(s.error_message(), HasSubstr("aim_lines"));
  EXPECT_TRUE(Preview(CreateTable(true), 0, Aim(3, 0.3), &p).ok());
}

TEST_F(PreviewTest, RefusedWhileBallsMove) {
  Start();
  const v1::CreateTableResponse t = CreateTable();
  v1::ShootRequest shoot;
  shoot.set_table_id(t.table_id());
  shoot.set_token(t.seats(0).token());
  *shoot.mutable_strike() = Aim(6, 0.3);
  v1::ShootResponse shot;
  ASSERT_TRUE(stub_->Shoot(Ctx().get(), shoot, &shot).ok());
  v1::PreviewShotResponse p;
  const grpc::Status s = Preview(t, 0, Aim(3, 0.3), &p);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::FAILED_PRECONDITION) << s.error_message();
}

TEST_F(PreviewTest, BadRequestsAreInvalidArgument) {
  Start();
  const v1::CreateTableResponse t = CreateTable();
  v1::PreviewShotResponse p;
  EXPECT_EQ(Preview(t, 0, Aim(3, 0.3), &p, 4).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  v1::CueStrike noisy = Aim(3, 0.3);
  noisy.set_noise(1);
  EXPECT_EQ(Preview(t, 0, noisy, &p).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(Preview(t, 0, Aim(25, 0.3), &p).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(PreviewTest, HasNoSideEffect) {
  Start();
  const v1::CreateTableResponse t = CreateTable();
  const v1::TableInfo before = Get(t.table_id());
  for (int i = 0; i < 5; ++i) {
    v1::PreviewShotResponse p;
    ASSERT_TRUE(Preview(t, 0, Aim(2 + i, 0.3 * i), &p).ok());
    EXPECT_EQ(p.paths_size(), 2);
  }
  const v1::TableInfo after = Get(t.table_id());
  EXPECT_EQ(after.sequence(), before.sequence());
  EXPECT_EQ(after.shots(), before.shots());
  EXPECT_EQ(after.turn(), before.turn());
  EXPECT_TRUE(after.at_rest());
  ASSERT_EQ(after.balls_size(), before.balls_size());
  for (int i = 0; i < after.balls_size(); ++i) {
    EXPECT_EQ(after.balls(i).SerializeAsString(), before.balls(i).SerializeAsString()) << i;
  }
}

TEST_F(PreviewTest, PathsLieOnSimulateShotsTrajectory) {
  Start();
  // A cut into the rack with spin, and a plain shot at the head ball; and an empty table with
  // two balls where the first contact is a cushion.
  struct Case {
    v1::TableSetup setup;
    v1::CueStrike strike;
  };
  v1::TableSetup two;
  two.set_preset("pool-9ft");
  two.set_rack("empty");
  auto* cue = two.add_balls();
  cue->set_id("cue");
  cue->set_x_m(-0.6);
  cue->set_y_m(0.1);
  auto* one = two.add_balls();
  one->set_id("1");
  one->set_x_m(0.3);
  one->set_y_m(-0.2);
  v1::CueStrike spin = Aim(2.5, 1.5);
  spin.set_a(0.2);
  spin.set_b(-0.3);
  v1::CueStrike bank = Aim(2.0, 80);  // off the side cushion first, then towards ball 1?
  const std::vector<Case> cases = {
      {NineBall(), Aim(3, 0.3)}, {NineBall(), spin}, {two, Aim(1.5, -15.3)}, {two, bank}};
  int with_target = 0;
  for (size_t c = 0; c < cases.size(); ++c) {
    const v1::CreateTableResponse t = CreateTable(std::nullopt, cases[c].setup);
    v1::PreviewShotResponse p;
    const grpc::Status s = Preview(t, 0, cases[c].strike, &p);
    ASSERT_TRUE(s.ok()) << s.error_message();
    ASSERT_GE(p.paths_size(), 1) << c;
    const Summary sim = SimulateOne(cases[c].setup, cases[c].strike, 200);
    const v1::SimulateShotResponse& full = sim.full;
    ASSERT_GT(full.samples_size(), 1);
    // The struck ball's path starts where the cue ball stands.
    const v1::TableInfo info = Get(t.table_id());
    const v1::BallPath& struck = p.paths(0);
    EXPECT_EQ(struck.ball(), "cue");
    ASSERT_GT(struck.points_size(), 1);
    int cue_index = -1;
    for (int i = 0; i < info.balls_size(); ++i) {
      if (info.balls(i).id() == "cue") cue_index = i;
    }
    ASSERT_GE(cue_index, 0);
    EXPECT_EQ(struck.points(0).t_s(), 0);
    EXPECT_EQ(struck.points(0).x_m(), info.balls(cue_index).x_m());
    EXPECT_EQ(struck.points(0).y_m(), info.balls(cue_index).y_m());
    // The second path is the first ball the cue ball meets.
    if (sim.first_contact.empty()) {
      EXPECT_EQ(p.paths_size(), 1) << c;
    } else {
      ASSERT_EQ(p.paths_size(), 2) << c;
      EXPECT_EQ(p.paths(1).ball(), sim.first_contact) << c;
      ++with_target;
    }
    // Every point on SimulateShot's trajectory sampled at 200 Hz (5 ms apart, as the preview's).
    for (const v1::BallPath& path : p.paths()) {
      int ball = -1;
      for (int i = 0; i < full.balls_size(); ++i) {
        if (full.balls(i).id() == path.ball()) ball = i;
      }
      ASSERT_GE(ball, 0) << path.ball();
      double last_t = -1;
      for (int k = 0; k < path.points_size(); ++k) {
        const v1::PathPoint& pt = path.points(k);
        EXPECT_GT(pt.t_s(), last_t) << c << " " << path.ball() << " point " << k;
        last_t = pt.t_s();
        if (&path != &p.paths(0) && k == 0) {
          // The met ball's path starts where it stood when it was met, at that instant.
          EXPECT_EQ(pt.x_m(), info.balls(ball).x_m()) << c << " " << path.ball();
          EXPECT_EQ(pt.y_m(), info.balls(ball).y_m()) << c << " " << path.ball();
          continue;
        }
        const long j = std::lround(pt.t_s() / 0.005);
        ASSERT_LT(j, full.samples_size()) << c << " " << path.ball() << " t " << pt.t_s();
        const v1::ShotSample& sample = full.samples(static_cast<int>(j));
        ASSERT_NEAR(sample.t_s(), pt.t_s(), 1e-12) << c << " " << path.ball() << " point " << k;
        EXPECT_NEAR(pt.x_m(), sample.x_m(ball), 1e-9)
            << c << " " << path.ball() << " point " << k << " t " << pt.t_s();
        EXPECT_NEAR(pt.y_m(), sample.y_m(ball), 1e-9)
            << c << " " << path.ball() << " point " << k << " t " << pt.t_s();
      }
    }
    // The events are SimulateShot's (the first ones of the two balls).
    for (const v1::TableEvent& e : p.events()) {
      bool found = false;
      for (const v1::TableEvent& w : full.events()) {
        found |= w.SerializeAsString() == e.SerializeAsString();
      }
      EXPECT_TRUE(found) << c << ": preview event " << e.ShortDebugString()
                         << " is not among SimulateShot's";
    }
  }
  EXPECT_GE(with_target, 3);
}

// The met ball's path, like the struck ball's, starts where the ball stands ("from the
// strike", BallPath in billiards.proto): an aim line is drawn from the object ball.
TEST_F(PreviewTest, TheMetBallsPathStartsWhereItStands) {
  Start();
  v1::TableSetup two;
  two.set_preset("pool-9ft");
  two.set_rack("empty");
  auto* cue = two.add_balls();
  cue->set_id("cue");
  cue->set_x_m(-0.5);
  cue->set_y_m(0);
  auto* one = two.add_balls();
  one->set_id("1");
  one->set_x_m(0);
  one->set_y_m(0.02);
  const v1::CreateTableResponse t = CreateTable(std::nullopt, two);
  v1::PreviewShotResponse p;
  ASSERT_TRUE(Preview(t, 0, Aim(2, 0), &p).ok());
  ASSERT_EQ(p.paths_size(), 2);
  const v1::BallPath& met = p.paths(1);
  EXPECT_EQ(met.ball(), "1");
  ASSERT_GE(met.points_size(), 2);
  EXPECT_EQ(met.points(0).x_m(), 0) << "first point at t " << met.points(0).t_s();
  EXPECT_EQ(met.points(0).y_m(), 0.02) << "first point at t " << met.points(0).t_s();
  // It starts moving at the contact, the struck ball's first event.
  ASSERT_GE(p.events_size(), 1);
  EXPECT_EQ(p.events(0).kind(), v1::ball_ball);
  EXPECT_LE(met.points(0).t_s(), p.events(0).t_s());
}

TEST_F(PreviewTest, AtMostMaxEventsPerBall) {
  Start();
  const v1::CreateTableResponse t = CreateTable();
  for (uint32_t max_events : {1u, 2u, 3u, 0u}) {
    const int cap = max_events == 0 ? 3 : static_cast<int>(max_events);
    for (const v1::CueStrike& strike : {Aim(6, 0.3), Aim(4, 1.1), Aim(3, -0.8)}) {
      v1::PreviewShotResponse p;
      ASSERT_TRUE(Preview(t, 0, strike, &p, max_events).ok());
      ASSERT_GE(p.paths_size(), 1);
      std::map<std::string, int> per_ball;
      for (const v1::TableEvent& e : p.events()) {
        EXPECT_NE(e.kind(), v1::transition);
        for (const std::string& id : e.balls()) ++per_ball[id];
      }
      for (const v1::BallPath& path : p.paths()) {
        EXPECT_LE(per_ball[path.ball()], cap) << "max_events " << max_events << " " << path.ball();
        EXPECT_GE(per_ball[path.ball()], 1) << "max_events " << max_events << " " << path.ball();
      }
      EXPECT_LE(p.events_size(), 2 * cap);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// gRPC-Web, as plain HTTP/1.1 from a socket

class GrpcWebTest : public BotsTest {
 protected:
  void SetUp() override {
    BotsTest::SetUp();
    root_ = std::filesystem::path(::testing::TempDir()) /
            ("sportsim-web-" + std::to_string(::getpid()));
    std::filesystem::create_directories(root_);
    std::ofstream(root_ / "index.html") << "<!doctype html><title>sportsim viewer</title>\n";
    std::ofstream(root_ / "app.js") << "console.log('viewer');\n";
    std::ofstream(root_ / ".hidden") << "secret\n";
    config_.http_listen = "127.0.0.1:0";
    config_.web_root = root_.string();
    config_.http_cors_origins = {"https://good.example"};
    Start();
    ASSERT_GT(app_->http_port(), 0);
  }
  void TearDown() override {
    app_.reset();
    std::error_code ec;
    std::filesystem::remove_all(root_, ec);
  }
  static std::string Post(const std::string& path, const std::string& body, bool text,
                          const std::string& extra = "") {
    return absl::StrCat("POST ", path, " HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: ",
                        text ? "application/grpc-web-text" : "application/grpc-web+proto",
                        "\r\nX-Grpc-Web: 1\r\nConnection: close\r\n", extra,
                        "Content-Length: ", body.size(), "\r\n\r\n", body);
  }
  // One gRPC-Web call, read to the end.
  WebCall Call(const std::string& path, const google::protobuf::Message& request, bool text) {
    std::string body = WebFrameBytes(0, request.SerializeAsString());
    if (text) body = absl::Base64Escape(body);
    return CallRaw(path, body, text);
  }
  WebCall CallRaw(const std::string& path, const std::string& body, bool text) {
    WebCall out;
    Http http(app_->http_port());
    EXPECT_TRUE(http.ok());
    EXPECT_TRUE(http.Send(Post(path, body, text)));
    out.http = http.ReadAll();
    std::string bytes = out.http.body;
    if (text) {
      EXPECT_TRUE(DecodeText(out.http.body, &bytes)) << out.http.body;
    }
    std::vector<WebFrame> frames;
    EXPECT_TRUE(SplitFrames(bytes, &frames));
    for (const WebFrame& f : frames) {
      if (f.flag & 0x80) {
        out.trailers = Trailers(f.payload);
      } else {
        EXPECT_TRUE(out.trailers.empty()) << "a message after the trailers";
        out.messages.push_back(f.payload);
      }
    }
    if (out.trailers.count("grpc-status")) {
      EXPECT_TRUE(absl::SimpleAtoi(out.trailers["grpc-status"], &out.grpc_status));
    }
    out.grpc_message = out.trailers["grpc-message"];
    return out;
  }
  HttpResponse Request(const std::string& raw) {
    Http http(app_->http_port());
    EXPECT_TRUE(http.ok());
    EXPECT_TRUE(http.Send(raw));
    return http.ReadAll();
  }
  std::filesystem::path root_;
};

TEST_F(GrpcWebTest, UnaryCallInBinaryAndTextDecodesToTheSameMessage) {
  v1::GetInfoResponse direct;
  ASSERT_TRUE(v1::Server::NewStub(channel_)->GetInfo(Ctx().get(), {}, &direct).ok());
  std::vector<v1::GetInfoResponse> got;
  for (bool text : {false, true}) {
    const WebCall c = Call("/sportsim.v1.Server/GetInfo", v1::GetInfoRequest(), text);
    EXPECT_EQ(c.http.status, 200);
    EXPECT_EQ(c.http.headers.at("content-type"),
              text ? "application/grpc-web-text+proto" : "application/grpc-web+proto");
    EXPECT_EQ(c.grpc_status, 0) << c.grpc_message;
    ASSERT_EQ(c.messages.size(), 1u);
    v1::GetInfoResponse info;
    ASSERT_TRUE(info.ParseFromString(c.messages[0]));
    got.push_back(info);
  }
  EXPECT_EQ(got[0].SerializeAsString(), got[1].SerializeAsString());
  EXPECT_EQ(got[0].SerializeAsString(), direct.SerializeAsString());
  EXPECT_EQ(got[0].version(), "0.1.0");
}

// The standard health service is served over gRPC-Web too (a browser or a load balancer that
// speaks only HTTP/1.1 can check the server), though it is gRPC's built-in one.
TEST_F(GrpcWebTest, HealthCheckIsServed) {
  // The messages by hand, so that this test links no health.proto code of its own (the
  // server's gateway must bring the descriptors): HealthCheckRequest{service: ""} is empty,
  // HealthCheckResponse{status: SERVING} is field 1, varint 1.
  for (bool text : {false, true}) {
    std::string body = WebFrameBytes(0, "");
    if (text) body = absl::Base64Escape(body);
    const WebCall c = CallRaw("/grpc.health.v1.Health/Check", body, text);
    EXPECT_EQ(c.http.status, 200);
    EXPECT_EQ(c.grpc_status, 0) << c.grpc_message;
    ASSERT_EQ(c.messages.size(), 1u);
    EXPECT_EQ(c.messages[0], std::string("\x08\x01", 2));
  }
}

TEST_F(GrpcWebTest, ErrorsComeAsGrpcStatusInTheTrailers) {
  v1::GetTableRequest r;
  r.set_table_id("no-such-table");
  for (bool text : {false, true}) {
    const WebCall c = Call("/sportsim.v1.Billiards/GetTable", r, text);
    EXPECT_EQ(c.http.status, 200);
    EXPECT_EQ(c.grpc_status, 5) << c.grpc_message;  // NOT_FOUND
    EXPECT_TRUE(c.messages.empty());
  }
}

TEST_F(GrpcWebTest, AServerStreamClosedByTheClientLeavesNoWatcher) {
  for (bool text : {false, true}) {
    v1::CreateTableRequest create;
    *create.mutable_table() = NineBall();
    v1::CreateTableResponse t;
    ASSERT_TRUE(stub_->CreateTable(Ctx().get(), create, &t).ok());
    const auto watchers = [&] {
      v1::GetTableRequest g;
      g.set_table_id(t.table_id());
      v1::TableInfo info;
      EXPECT_TRUE(stub_->GetTable(Ctx().get(), g, &info).ok());
      return info.watchers();
    };
    v1::WatchTableRequest w;
    w.set_table_id(t.table_id());
    std::string body = WebFrameBytes(0, w.SerializeAsString());
    if (text) body = absl::Base64Escape(body);
    Http http(app_->http_port());
    ASSERT_TRUE(http.ok());
    ASSERT_TRUE(http.Send(Post("/sportsim.v1.Billiards/WatchTable", body, text)));
    HttpResponse head;
    ASSERT_TRUE(http.ReadHead(&head));
    EXPECT_EQ(head.status, 200);
    // A break: the table moves for seconds.
    v1::ShootRequest shoot;
    shoot.set_table_id(t.table_id());
    shoot.set_token(t.seats(0).token());
    shoot.mutable_strike()->set_ball_speed_mps(8);
    shoot.mutable_strike()->set_phi_deg(0.3);
    v1::ShootResponse shot;
    const grpc::Status s = stub_->Shoot(Ctx().get(), shoot, &shot);
    ASSERT_TRUE(s.ok()) << s.error_message();
    std::string pending;
    int frames = 0;
    uint64_t last_sequence = 0;
    while (frames < 3) {
      std::string piece;
      ASSERT_TRUE(http.ReadBodyPiece(&piece)) << "the stream ended after " << frames;
      std::string bytes = piece;
      if (text) {
        ASSERT_TRUE(DecodeText(piece, &bytes));
      }
      pending += bytes;
      std::vector<WebFrame> split;
      if (!SplitFrames(pending, &split)) continue;  // a frame across pieces
      pending.clear();
      for (const WebFrame& f : split) {
        ASSERT_EQ(f.flag, 0) << "trailers before 3 snapshots: " << f.payload;
        v1::TableSnapshot snap;
        ASSERT_TRUE(snap.ParseFromString(f.payload));
        EXPECT_GE(snap.sequence(), last_sequence);
        last_sequence = snap.sequence();
        EXPECT_EQ(snap.table_id(), t.table_id());
        ++frames;
      }
    }
    EXPECT_EQ(watchers(), 1u);
    http.Close();
    // Still moving: the watcher goes because the client went, not because the shot ended.
    EXPECT_TRUE(Eventually([&] { return watchers() == 0; }, 5))
        << (text ? "text" : "binary") << ": the closed stream's watcher is still held";
    v1::GetTableRequest g;
    g.set_table_id(t.table_id());
    v1::TableInfo info;
    ASSERT_TRUE(stub_->GetTable(Ctx().get(), g, &info).ok());
    EXPECT_FALSE(info.at_rest()) << "the shot ended first: the test proves nothing";
  }
}

// The same, with the table at rest while the client goes away: nothing moves, so only the
// stream's heartbeats can tell the gateway.
TEST_F(GrpcWebTest, AServerStreamClosedWhileTheTableRestsLeavesNoWatcher) {
  v1::CreateTableRequest create;
  *create.mutable_table() = NineBall();
  v1::CreateTableResponse t;
  ASSERT_TRUE(stub_->CreateTable(Ctx().get(), create, &t).ok());
  v1::WatchTableRequest w;
  w.set_table_id(t.table_id());
  Http http(app_->http_port());
  ASSERT_TRUE(http.ok());
  ASSERT_TRUE(http.Send(Post("/sportsim.v1.Billiards/WatchTable", WebFrameBytes(0, w.SerializeAsString()),
                             false)));
  HttpResponse head;
  ASSERT_TRUE(http.ReadHead(&head));
  std::string piece;
  ASSERT_TRUE(http.ReadBodyPiece(&piece));  // the table as it is
  v1::GetTableRequest g;
  g.set_table_id(t.table_id());
  v1::TableInfo info;
  ASSERT_TRUE(stub_->GetTable(Ctx().get(), g, &info).ok());
  EXPECT_EQ(info.watchers(), 1u);
  http.Close();
  EXPECT_TRUE(Eventually(
      [&] { return stub_->GetTable(Ctx().get(), g, &info).ok() && info.watchers() == 0; }, 15))
      << "the watcher of a closed gRPC-Web stream is still held 15 s later";
}

TEST_F(GrpcWebTest, OpenStreamsPerClientAreCappedAndFreedWhenClosed) {
  v1::CreateTableRequest create;
  *create.mutable_table() = NineBall();
  v1::CreateTableResponse t;
  ASSERT_TRUE(stub_->CreateTable(Ctx().get(), create, &t).ok());
  v1::WatchTableRequest w;
  w.set_table_id(t.table_id());
  const std::string body = WebFrameBytes(0, w.SerializeAsString());
  std::vector<std::unique_ptr<Http>> open;
  for (int i = 0; i < 4; ++i) {  // --http_max_streams_per_client's default
    open.push_back(std::make_unique<Http>(app_->http_port()));
    ASSERT_TRUE(open.back()->Send(Post("/sportsim.v1.Billiards/WatchTable", body, false)));
    HttpResponse head;
    ASSERT_TRUE(open.back()->ReadHead(&head));
    std::string piece;
    ASSERT_TRUE(open.back()->ReadBodyPiece(&piece)) << i;  // the first snapshot: it is open
  }
  const WebCall fifth = CallRaw("/sportsim.v1.Billiards/WatchTable", body, false);
  EXPECT_EQ(fifth.grpc_status, 8) << fifth.grpc_message;
  // A unary call is not a stream: it goes through.
  EXPECT_EQ(Call("/sportsim.v1.Server/GetInfo", v1::GetInfoRequest(), false).grpc_status, 0);
  // One closed: a new stream is accepted once the server has noticed (a heartbeat, 1 s).
  open.front()->Close();
  EXPECT_TRUE(Eventually(
      [&] {
        Http http(app_->http_port());
        if (!http.Send(Post("/sportsim.v1.Billiards/WatchTable", body, false))) return false;
        HttpResponse head;
        std::string piece;
        if (!http.ReadHead(&head) || !http.ReadBodyPiece(&piece)) return false;
        std::vector<WebFrame> frames;
        return SplitFrames(piece, &frames) && frames.size() == 1 && frames[0].flag == 0;
      },
      10));
}

TEST_F(GrpcWebTest, CorsPreflightForAnAllowedAndARefusedOrigin) {
  const auto preflight = [&](const std::string& origin) {
    return Request(absl::StrCat(
        "OPTIONS /sportsim.v1.Billiards/GetTable HTTP/1.1\r\nHost: 127.0.0.1\r\nOrigin: ", origin,
        "\r\nAccess-Control-Request-Method: POST\r\nAccess-Control-Request-Headers: "
        "content-type,x-grpc-web\r\nConnection: close\r\n\r\n"));
  };
  const HttpResponse ok = preflight("https://good.example");
  EXPECT_GE(ok.status, 200);
  EXPECT_LT(ok.status, 300);
  ASSERT_TRUE(ok.headers.count("access-control-allow-origin"));
  EXPECT_EQ(ok.headers.at("access-control-allow-origin"), "https://good.example");
  EXPECT_THAT(absl::AsciiStrToLower(ok.header("access-control-allow-headers")),
              HasSubstr("x-grpc-web"));
  EXPECT_THAT(ok.header("access-control-allow-methods"), HasSubstr("POST"));
  EXPECT_THAT(ok.header("access-control-expose-headers"), HasSubstr("grpc-status"));

  const HttpResponse refused = preflight("https://evil.example");
  EXPECT_FALSE(refused.headers.count("access-control-allow-origin"));
  EXPECT_TRUE(refused.status < 200 || refused.status >= 300) << refused.status;

  // The call itself: the allowed origin gets the header, the refused one does not.
  v1::GetInfoRequest info;
  const std::string body = WebFrameBytes(0, info.SerializeAsString());
  const HttpResponse a = Request(Post("/sportsim.v1.Server/GetInfo", body, false,
                                      "Origin: https://good.example\r\n"));
  EXPECT_EQ(a.header("access-control-allow-origin"), "https://good.example");
  const HttpResponse b = Request(Post("/sportsim.v1.Server/GetInfo", body, false,
                                      "Origin: https://evil.example\r\n"));
  EXPECT_FALSE(b.headers.count("access-control-allow-origin"));
}

TEST_F(GrpcWebTest, AnOversizedMessageIsResourceExhausted) {
  // A batch of strikes larger than the 64 KiB request limit.
  v1::SimulateShotsRequest req = Batch(RandomStrikes(3000, 12));
  ASSERT_GT(req.ByteSizeLong(), 64u << 10);
  for (bool text : {false, true}) {
    const WebCall c = Call("/sportsim.v1.Billiards/SimulateShots", req, text);
    EXPECT_EQ(c.http.status, 200);
    EXPECT_EQ(c.grpc_status, 8) << c.grpc_message;
    EXPECT_TRUE(c.messages.empty());
  }
  // Just under the limit goes through (as a message, refused for what it says, not its size).
  v1::SimulateShotsRequest small = Batch(RandomStrikes(10, 12));
  const WebCall ok = Call("/sportsim.v1.Billiards/SimulateShots", small, false);
  EXPECT_EQ(ok.grpc_status, 0) << ok.grpc_message;
  size_t outcomes = 0;
  for (const std::string& m : ok.messages) {
    v1::SimulateShotsResponse r;
    ASSERT_TRUE(r.ParseFromString(m));
    outcomes += static_cast<size_t>(r.outcomes_size());
  }
  EXPECT_EQ(outcomes, 10u);
}

TEST_F(GrpcWebTest, BidirectionalAndUnknownMethodsAreUnimplemented) {
  v1::DriveSwingRequest drive;
  const WebCall d = Call("/sportsim.v1.Swing/DriveSwing", drive, false);
  EXPECT_EQ(d.http.status, 200);
  EXPECT_EQ(d.grpc_status, 12);
  EXPECT_THAT(d.grpc_message, HasSubstr("DriveSwing"));
  EXPECT_THAT(d.grpc_message, HasSubstr("gRPC-Web"));
  EXPECT_EQ(d.http.header("grpc-status"), "12");
  const WebCall u = Call("/sportsim.v1.Billiards/NoSuchMethod", v1::GetTableRequest(), false);
  EXPECT_EQ(u.grpc_status, 12) << u.grpc_message;
  const WebCall s = Call("/no.such.Service/Get", v1::GetTableRequest(), true);
  EXPECT_EQ(s.grpc_status, 12) << s.grpc_message;
}

TEST_F(GrpcWebTest, TheViewerIsServedAndNothingElse) {
  const auto get = [&](const std::string& path) {
    return Request(absl::StrCat("GET ", path, " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: "
                                "close\r\n\r\n"));
  };
  const std::string index = "<!doctype html><title>sportsim viewer</title>\n";
  for (const char* page : {"/", "/table/t-123", "/swing/s-9"}) {
    const HttpResponse r = get(page);
    EXPECT_EQ(r.status, 200) << page;
    EXPECT_EQ(r.body, index) << page;
    EXPECT_THAT(r.header("content-type"), HasSubstr("text/html")) << page;
  }
  const HttpResponse js = get("/app.js");
  EXPECT_EQ(js.status, 200);
  EXPECT_THAT(js.header("content-type"), HasSubstr("javascript"));
  for (const char* bad : {"/../etc/passwd", "/.hidden", "/%2e%2e/etc/passwd",
                          "/..%2fetc%2fpasswd", "/no-such-file.js"}) {
    const HttpResponse r = get(bad);
    EXPECT_EQ(r.status, 404) << bad;
    EXPECT_THAT(r.body, ::testing::Not(HasSubstr("root:"))) << bad;
    EXPECT_THAT(r.body, ::testing::Not(HasSubstr("secret"))) << bad;
  }
}

}  // namespace
}  // namespace sportsim::server
