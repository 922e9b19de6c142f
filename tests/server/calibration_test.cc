// CalibrateTable against the real server in-process: recorded shots made by SimulateShot's own
// trajectories (a carom table with another rolling resistance, sampled at 50 Hz) calibrate the
// preset back to it, with the report equal to the offline calibration's bit for bit; progress
// in order; bad requests refused naming the field before any work; the CPU budget and the
// client's cancellation stop the job.
#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/strings/match.h"
#include "absl/time/time.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/app/server_app.h"
#include "server/billiards/calibration.h"
#include "sim/billiards/calibrate.h"
#include "sportsim/v1/billiards.grpc.pb.h"
#include "sportsim/v1/common.grpc.pb.h"

namespace sportsim::server {
namespace {

using ::testing::HasSubstr;

class CalibrationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    config_.listen = "127.0.0.1:0";
    // Recorded shots are larger than the requests the server takes by default (64 KiB): an
    // operator who calibrates raises --max_request_bytes.
    config_.max_receive_message_bytes = 8 << 20;
    // A calibration takes seconds of CPU (ten times more under the sanitizers): more than a
    // request's default budget.
    config_.work.cpu_budget = absl::Seconds(600);
  }
  void Start() {
    absl::StatusOr<std::unique_ptr<ServerApp>> app = ServerApp::Start(config_);
    ASSERT_TRUE(app.ok()) << app.status();
    app_ = *std::move(app);
    channel_ = grpc::CreateChannel(app_->address(), grpc::InsecureChannelCredentials());
    stub_ = v1::Billiards::NewStub(channel_);
  }
  std::unique_ptr<grpc::ClientContext> Ctx(int seconds = 120) {
    auto c = std::make_unique<grpc::ClientContext>();
    c->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(seconds));
    return c;
  }

  // A recorded shot: SimulateShot's trajectory at 50 Hz of a strike on three balls of a carom
  // table whose rolling resistance is 0.006 (the preset's is 0.01).
  v1::RecordedShot Record(double x_cue, double y_cue, double phi_deg, double speed, double b) {
    v1::SimulateShotRequest req;
    v1::TableSetup* t = req.mutable_table();
    t->set_preset("carom");
    t->set_rack("empty");
    (*t->mutable_params())["mu_roll"] = 0.006;
    auto place = [&](const char* id, double x, double y) {
      v1::BallPlacement* p = t->add_balls();
      p->set_id(id);
      p->set_x_m(x);
      p->set_y_m(y);
    };
    place("white", x_cue, y_cue);
    place("yellow", 0.4, 0.2);
    place("red", -0.5, -0.3);
    v1::CueStrike* s = req.mutable_strike();
    s->set_ball("white");
    s->set_ball_speed_mps(speed);
    s->set_phi_deg(phi_deg);
    s->set_b(b);
    req.set_sample_rate_hz(50);
    v1::SimulateShotResponse r;
    const grpc::Status st = stub_->SimulateShot(Ctx().get(), req, &r);
    EXPECT_TRUE(st.ok()) << st.error_message();
    v1::RecordedShot shot;
    shot.set_name("shot");
    *shot.mutable_balls() = t->balls();
    shot.set_cue_ball("white");
    for (const v1::ShotSample& sample : r.samples()) {
      if (sample.t_s() <= 0) continue;
      for (int i = 0; i < sample.x_m_size(); ++i) {
        v1::TrackedPoint* p = shot.add_points();
        p->set_t_s(sample.t_s());
        p->set_ball(static_cast<uint32_t>(i));
        p->set_x_m(sample.x_m(i));
        p->set_y_m(sample.y_m(i));
      }
    }
    return shot;
  }

  v1::CalibrateTableRequest Request() {
    v1::CalibrateTableRequest req;
    req.mutable_table()->set_preset("carom");
    *req.add_shots() = Record(-1.0, 0.1, 20, 2.5, 0.2);
    *req.add_shots() = Record(0.9, -0.4, 160, 3.0, -0.1);
    req.add_fit()->set_name("mu_roll");
    return req;
  }

  // Runs a calibration to its end: the messages and the status.
  grpc::Status Calibrate(const v1::CalibrateTableRequest& req,
                         std::vector<v1::CalibrateTableResponse>* out,
                         grpc::ClientContext* ctx = nullptr) {
    std::unique_ptr<grpc::ClientContext> own;
    if (ctx == nullptr) {
      own = Ctx();
      ctx = own.get();
    }
    std::unique_ptr<grpc::ClientReader<v1::CalibrateTableResponse>> reader =
        stub_->CalibrateTable(ctx, req);
    v1::CalibrateTableResponse r;
    while (reader->Read(&r)) out->push_back(r);
    return reader->Finish();
  }

  ServerConfig config_;
  std::unique_ptr<ServerApp> app_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Billiards::Stub> stub_;
};

// The preset's rolling resistance comes back to the table's 0.006 from exact tracks, the
// shots' errors fall to nothing, the progress rises to 1, and the report is the offline
// calibration's, bit for bit.
TEST_F(CalibrationTest, RecoversTheTablesRollingResistanceAsTheOfflineCalibrationDoes) {
  Start();
  const v1::CalibrateTableRequest req = Request();
  std::vector<v1::CalibrateTableResponse> msgs;
  const grpc::Status st = Calibrate(req, &msgs);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_GE(msgs.size(), 2u);
  for (size_t i = 1; i < msgs.size(); ++i) {
    EXPECT_GE(msgs[i].fraction(), msgs[i - 1].fraction());
    EXPECT_EQ(msgs[i - 1].has_report(), false);
  }
  ASSERT_TRUE(msgs.back().has_report());
  EXPECT_EQ(msgs.back().fraction(), 1.0);
  const v1::CalibrationReport& rep = msgs.back().report();
  ASSERT_EQ(rep.fitted_size(), 1);
  EXPECT_NEAR(rep.params().at("mu_roll"), 0.006, 0.006 * 0.01);
  EXPECT_EQ(rep.fitted(0).before(), 0.01);
  ASSERT_EQ(rep.shots_size(), 2);
  for (const v1::ShotCalibration& s : rep.shots()) {
    EXPECT_GT(s.before().mean_m(), 0.01);
    EXPECT_LT(s.after().mean_m(), 1e-3);
    EXPECT_TRUE(s.strike_after().has_ball_speed_mps());
    EXPECT_EQ(s.strike_after().ball(), "white");
  }
  EXPECT_GT(rep.simulations(), 0);
  EXPECT_GT(rep.cpu_s(), 0.0);

  absl::StatusOr<CalibrationJob> job = CalibrationJobFromProto(req);
  ASSERT_TRUE(job.ok()) << job.status();
  absl::StatusOr<billiards::CalibrationReport> offline =
      billiards::Calibrate(job->spec, job->solver, job->recordings, job->options);
  ASSERT_TRUE(offline.ok()) << offline.status();
  EXPECT_EQ(offline->params.mu_roll, rep.params().at("mu_roll"));
  EXPECT_EQ(offline->simulations, rep.simulations());
  EXPECT_EQ(offline->shots[1].after.mean_m, rep.shots(1).after().mean_m());
}

// Refused before any work, with the field named.
TEST_F(CalibrationTest, BadRequestsAreInvalidArgumentNamingTheField) {
  Start();
  const v1::CalibrateTableRequest good = Request();
  auto refused = [&](const v1::CalibrateTableRequest& req) {
    std::vector<v1::CalibrateTableResponse> msgs;
    const grpc::Status st = Calibrate(req, &msgs);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << st.error_message();
    EXPECT_TRUE(msgs.empty());
    return st.error_message();
  };
  v1::CalibrateTableRequest req = good;
  req.clear_shots();
  EXPECT_THAT(refused(req), HasSubstr("shots: 1 to 200"));
  req = good;
  req.mutable_shots(1)->mutable_points(3)->set_ball(9);
  EXPECT_THAT(refused(req), HasSubstr("shots[1].points[3].ball"));
  req = good;
  req.mutable_shots(0)->mutable_points(5)->set_t_s(-1);
  EXPECT_THAT(refused(req), HasSubstr("shots[0].points[5].t_s"));
  req = good;
  req.mutable_shots(0)->set_cue_ball("blue");
  EXPECT_THAT(refused(req), HasSubstr("shots[0].cue_ball"));
  req = good;
  req.mutable_shots(0)->mutable_balls(1)->set_x_m(-1.0);  // onto the white
  req.mutable_shots(0)->mutable_balls(1)->set_y_m(0.1);
  EXPECT_THAT(refused(req), HasSubstr("shots[0].balls"));
  req = good;
  req.mutable_fit(0)->set_name("mu_rol");
  EXPECT_THAT(refused(req), HasSubstr("fit: unknown parameter"));
  req = good;
  req.mutable_fit(0)->set_lo(0.5);
  EXPECT_THAT(refused(req), HasSubstr("fit[0]: give both lo and hi"));
  req = good;
  req.add_heldout(2);
  EXPECT_THAT(refused(req), HasSubstr("heldout: 2"));
  req = good;
  req.mutable_table()->set_rack("8ball");
  EXPECT_THAT(refused(req), HasSubstr("table: give the preset"));
  req = good;
  req.set_max_iterations(0);
  EXPECT_THAT(refused(req), HasSubstr("max_iterations"));
}

// Under the default request size limit, two recorded shots at 50 Hz are refused by gRPC.
TEST_F(CalibrationTest, TheRequestSizeLimitHolds) {
  config_.max_receive_message_bytes = 64 << 10;
  Start();
  std::vector<v1::CalibrateTableResponse> msgs;
  const grpc::Status st = Calibrate(Request(), &msgs);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
  EXPECT_TRUE(msgs.empty());
}

// A calibration is held to --max_request_cpu like any request, and stops when its client goes.
TEST_F(CalibrationTest, TheCpuBudgetAndCancellationStopIt) {
  config_.work.cpu_budget = absl::Milliseconds(50);
  Start();
  std::vector<v1::CalibrateTableResponse> msgs;
  grpc::Status st = Calibrate(Request(), &msgs);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
  EXPECT_THAT(st.error_message(), HasSubstr("--max_request_cpu"));
  EXPECT_THAT(st.error_message(), HasSubstr("fewer shots"));

  app_.reset();
  config_.work.cpu_budget = absl::Seconds(600);
  Start();
  v1::CalibrateTableRequest big = Request();
  for (const char* p : {"mu_slide", "e_cushion", "f_cushion"}) big.add_fit()->set_name(p);
  grpc::ClientContext ctx;
  std::thread cancel([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ctx.TryCancel();
  });
  const auto t0 = std::chrono::steady_clock::now();
  msgs.clear();
  st = Calibrate(big, &msgs, &ctx);
  cancel.join();
  EXPECT_EQ(st.error_code(), grpc::StatusCode::CANCELLED) << st.error_message();
  // The server's worker is free again soon: a small calibration runs to its end.
  std::vector<v1::CalibrateTableResponse> after;
  v1::CalibrateTableRequest small = Request();
  small.mutable_shots()->RemoveLast();
  st = Calibrate(small, &after);
  EXPECT_TRUE(st.ok()) << st.error_message();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(60));
}

}  // namespace
}  // namespace sportsim::server
