// CalibrateTable against the real server in-process: recorded shots made by SimulateShot's own
// trajectories (a carom table with another rolling resistance, sampled at 50 Hz) calibrate the
// preset back to it, with the report equal to the offline calibration's bit for bit; progress
// in order; bad requests refused naming the field before any work; the CPU budget and the
// client's cancellation stop the job. UploadCalibration: the same calibration in parts, each
// within the default request limit, with its own checks, the server's upload budget and its stall
// timeout.
#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <google/protobuf/util/message_differencer.h>
#include <grpcpp/grpcpp.h>

#include "absl/strings/match.h"
#include "absl/time/time.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "client/calibration_upload.h"
#include "server/app/server_app.h"
#include "server/billiards/calibration.h"
#include "server/billiards/convert.h"
#include "sim/billiards/calibrate.h"
#include "sim/billiards/cue.h"
#include "sim/billiards/shot.h"
#include "sim/games/three_cushion.h"
#include "sportsim/v1/billiards.grpc.pb.h"
#include "sportsim/v1/common.grpc.pb.h"

namespace sportsim::server {
namespace {

using ::testing::HasSubstr;

class CalibrationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    config_.listen = "127.0.0.1:0";
    // Recorded shots are larger than the requests the server takes by default (64 KiB):
    // CalibrateTable, the whole request in one message, needs --max_request_bytes raised
    // (UploadCalibration does not; its tests set the default back).
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
  // A deadline far past a calibration's time here: 3-5 s in Release, 21-52 s under ASan on an
  // idle 2-core machine, and past 120 s under ASan with builds sharing the cores.
  std::unique_ptr<grpc::ClientContext> Ctx(int seconds = 300) {
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

  // The report is the offline calibration's of the same request, bit for bit.
  static void ExpectTheOfflineReport(const v1::CalibrateTableRequest& req,
                                     const v1::CalibrationReport& rep) {
    absl::StatusOr<CalibrationJob> job = CalibrationJobFromProto(req);
    ASSERT_TRUE(job.ok()) << job.status();
    absl::StatusOr<billiards::CalibrationReport> offline =
        billiards::Calibrate(job->spec, job->solver, job->recordings, job->options);
    ASSERT_TRUE(offline.ok()) << offline.status();
    EXPECT_EQ(offline->params.mu_roll, rep.params().at("mu_roll"));
    ASSERT_EQ(rep.fitted_size(), 1);
    EXPECT_EQ(offline->fitted[0].standard_error, rep.fitted(0).standard_error());
    EXPECT_EQ(offline->fitted[0].at_bound, rep.fitted(0).at_bound());
    EXPECT_EQ(offline->simulations, rep.simulations());
    EXPECT_EQ(offline->shots[1].after.mean_m, rep.shots(1).after().mean_m());
    ASSERT_EQ(static_cast<int>(offline->start_rms_m.size()), rep.start_rms_m_size());
    for (int k = 0; k < rep.start_rms_m_size(); ++k) {
      EXPECT_EQ(offline->start_rms_m[static_cast<size_t>(k)], rep.start_rms_m(k));
    }
    EXPECT_EQ(offline->start_kept, static_cast<int>(rep.start_kept()));
    EXPECT_EQ(rep.start_kept(), 1u);  // one constant: one start
  }

  // Runs an upload of `parts` to its end: the messages and the status.
  grpc::Status Upload(const std::vector<v1::CalibrationUpload>& parts,
                      std::vector<v1::CalibrateTableResponse>* out) {
    std::unique_ptr<grpc::ClientContext> ctx = Ctx();
    auto stream = stub_->UploadCalibration(ctx.get());
    for (const v1::CalibrationUpload& part : parts) {
      if (!stream->Write(part)) break;
    }
    stream->WritesDone();
    v1::CalibrateTableResponse r;
    while (stream->Read(&r)) out->push_back(r);
    return stream->Finish();
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
  EXPECT_EQ(rep.fitted(0).before(), 0.0047);  // the carom preset's
  ASSERT_EQ(rep.shots_size(), 2);
  for (const v1::ShotCalibration& s : rep.shots()) {
    EXPECT_GT(s.before().mean_m(), 0.01);
    EXPECT_LT(s.after().mean_m(), 1e-3);
    EXPECT_TRUE(s.strike_after().has_ball_speed_mps());
    EXPECT_EQ(s.strike_after().ball(), "white");
  }
  EXPECT_GT(rep.simulations(), 0);
  EXPECT_GT(rep.cpu_s(), 0.0);

  ExpectTheOfflineReport(req, rep);
}

// A tracker's clock that runs before the strike: the same shots with 0.3 s of the balls at
// rest before them. The strike's time is fitted (to well within a 50 Hz frame) and the
// calibration comes out as before; a strike time given is kept.
TEST_F(CalibrationTest, FitsTheStrikesTimeOnATrackersClock) {
  Start();
  v1::CalibrateTableRequest req = Request();
  constexpr double kLead = 0.3;
  for (v1::RecordedShot& shot : *req.mutable_shots()) {
    v1::RecordedShot early = shot;
    early.clear_points();
    for (int k = 1; k <= 15; ++k) {  // 50 Hz, up to the strike
      for (int b = 0; b < shot.balls_size(); ++b) {
        v1::TrackedPoint* p = early.add_points();
        p->set_t_s(k * 0.02);
        p->set_ball(static_cast<uint32_t>(b));
        p->set_x_m(shot.balls(b).x_m());
        p->set_y_m(shot.balls(b).y_m());
      }
    }
    for (v1::TrackedPoint p : shot.points()) {
      p.set_t_s(p.t_s() + kLead);
      *early.add_points() = p;
    }
    shot = early;
  }
  std::vector<v1::CalibrateTableResponse> msgs;
  grpc::Status st = Calibrate(req, &msgs);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_TRUE(msgs.back().has_report());
  const v1::CalibrationReport& rep = msgs.back().report();
  EXPECT_NEAR(rep.params().at("mu_roll"), 0.006, 0.006 * 0.01);
  for (const v1::ShotCalibration& s : rep.shots()) {
    EXPECT_NEAR(s.strike_time_after_s(), kLead, 1e-3);
    EXPECT_LT(s.after().mean_m(), 1e-3);
  }
  ExpectTheOfflineReport(req, rep);

  req.mutable_shots(0)->set_strike_time_s(kLead);
  msgs.clear();
  st = Calibrate(req, &msgs);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_TRUE(msgs.back().has_report());
  EXPECT_EQ(msgs.back().report().shots(0).strike_time_before_s(), kLead);
  EXPECT_EQ(msgs.back().report().shots(0).strike_time_after_s(), kLead);
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
  req.mutable_shots(1)->set_strike_time_s(-0.5);
  EXPECT_THAT(refused(req), HasSubstr("shots[1].strike_time_s must be finite and in [0, 3600]"));
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
  req = good;
  req.set_huber_m(-0.01);
  EXPECT_THAT(refused(req), HasSubstr("huber_m must be in [0, 1] m"));
  req = good;
  req.set_prediction(static_cast<v1::StrikePrediction>(7));
  EXPECT_THAT(refused(req), HasSubstr("prediction: 7 is not a StrikePrediction"));
  req = good;
  req.set_intent(static_cast<v1::ShotIntent>(9));
  EXPECT_THAT(refused(req), HasSubstr("intent: 9 is not a ShotIntent"));
  // The three-cushion point on a table of two balls: the red and its points taken away.
  req = good;
  req.set_intent(v1::SHOT_INTENT_THREE_CUSHION_POINT);
  v1::RecordedShot* two = req.mutable_shots(1);
  two->mutable_balls()->RemoveLast();
  v1::RecordedShot kept = *two;
  kept.clear_points();
  for (const v1::TrackedPoint& p : two->points()) {
    if (p.ball() < 2) *kept.add_points() = p;
  }
  *two = kept;
  EXPECT_THAT(refused(req), HasSubstr("intent: THREE_CUSHION_POINT needs three balls on the table; "
                                      "shots[1] has 2"));
  // A pot on a table without pockets; on a pool table the same shots take the pot's intent.
  req = good;
  req.set_intent(v1::SHOT_INTENT_POT);
  EXPECT_THAT(refused(req), HasSubstr("intent: POT needs a table with pockets; table 'carom' has "
                                      "none"));
  req.mutable_table()->set_preset("pool-9ft");
  absl::StatusOr<CalibrationJob> pool = CalibrationJobFromProto(req);
  ASSERT_TRUE(pool.ok()) << pool.status();
  EXPECT_TRUE(static_cast<bool>(pool->options.strike_bounds.intent));
}

// A held-out shot fitted on its first 0.4 s only, its strike taken as the plausible strikes'
// central rest among those that score the three-cushion point: the report says how many were
// weighed and whether the strike taken scores, the training shot's fit weighs none, and the
// report is the offline calibration's, bit for bit. Without a prediction asked, none is
// weighed.
TEST_F(CalibrationTest, HeldOutShotsPredictedFromTheirStartWeighThePlausibleStrikes) {
  Start();
  v1::CalibrateTableRequest req = Request();
  req.clear_fit();  // the strikes only
  req.add_heldout(1);
  req.set_strike_window_s(0.4);
  req.set_prediction(v1::STRIKE_PREDICTION_CENTRAL_REST);
  req.set_intent(v1::SHOT_INTENT_THREE_CUSHION_POINT);
  std::vector<v1::CalibrateTableResponse> msgs;
  grpc::Status st = Calibrate(req, &msgs);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_TRUE(msgs.back().has_report());
  const v1::CalibrationReport& rep = msgs.back().report();
  ASSERT_EQ(rep.shots_size(), 2);
  EXPECT_EQ(rep.shots(0).plausible(), 0u);
  EXPECT_GT(rep.shots(1).plausible(), 1u);

  absl::StatusOr<CalibrationJob> job = CalibrationJobFromProto(req);
  ASSERT_TRUE(job.ok()) << job.status();
  EXPECT_TRUE(job->options.strike_bounds.central_rest);
  absl::StatusOr<billiards::CalibrationReport> offline =
      billiards::Calibrate(job->spec, job->solver, job->recordings, job->options);
  ASSERT_TRUE(offline.ok()) << offline.status();
  EXPECT_EQ(offline->shots[1].plausible, static_cast<int>(rep.shots(1).plausible()));
  EXPECT_EQ(offline->shots[1].intent_met, rep.shots(1).intent_met());
  EXPECT_EQ(offline->shots[1].strike_after.speed_mps, rep.shots(1).strike_after().ball_speed_mps());
  EXPECT_EQ(offline->shots[1].strike_after.a, rep.shots(1).strike_after().a());
  EXPECT_EQ(offline->shots[1].strike_after.b, rep.shots(1).strike_after().b());
  EXPECT_EQ(offline->shots[1].after.mean_m, rep.shots(1).after().mean_m());
  // Whether the strike taken scores is the referee's word on its shot.
  billiards::TableState table = job->recordings[1].initial;
  const billiards::TableModel model = *billiards::TableModel::Create(job->spec);
  ASSERT_TRUE(billiards::ApplyStrike(model, 0, offline->shots[1].strike_after, job->recordings[1].cue,
                                     &table).ok());
  absl::StatusOr<billiards::ShotResult> played =
      billiards::SimulateShot(model, job->solver, table, billiards::ShotOptions{});
  ASSERT_TRUE(played.ok()) << played.status();
  EXPECT_EQ(games::ThreeCushionIntent()(job->recordings[1].initial, job->recordings[1].cue,
                                        played->events),
            rep.shots(1).intent_met());

  req.clear_prediction();
  req.clear_intent();
  msgs.clear();
  st = Calibrate(req, &msgs);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_TRUE(msgs.back().has_report());
  EXPECT_EQ(msgs.back().report().shots(1).plausible(), 0u);
  EXPECT_FALSE(msgs.back().report().shots(1).intent_met());
}

// A tracker's false detections: every 17th point of each shot a metre off. Under Huber's loss
// (1 cm) the rolling resistance comes back as from the clean tracks, each shot's fit lies
// within a millimetre of its clean track, and the report is the offline calibration's, bit
// for bit; by least squares the fit is pulled off.
TEST_F(CalibrationTest, HubersLossFitsThroughFalseDetections) {
  Start();
  v1::CalibrateTableRequest req = Request();
  const v1::CalibrateTableRequest clean = req;
  for (v1::RecordedShot& shot : *req.mutable_shots()) {
    for (int i = 16; i < shot.points_size(); i += 17) {
      v1::TrackedPoint* p = shot.mutable_points(i);
      p->set_x_m(p->x_m() > 0 ? p->x_m() - 1.0 : p->x_m() + 1.0);
    }
  }
  req.set_huber_m(0.01);
  std::vector<v1::CalibrateTableResponse> msgs;
  grpc::Status st = Calibrate(req, &msgs);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_TRUE(msgs.back().has_report());
  const v1::CalibrationReport robust = msgs.back().report();
  EXPECT_NEAR(robust.params().at("mu_roll"), 0.006, 0.006 * 0.01);
  ExpectTheOfflineReport(req, robust);
  // Each shot's fitted strike against its clean track.
  absl::StatusOr<CalibrationJob> job = CalibrationJobFromProto(clean);
  ASSERT_TRUE(job.ok()) << job.status();
  billiards::TableSpec spec = job->spec;
  spec.params.mu_roll = robust.params().at("mu_roll");
  const billiards::TableModel model = *billiards::TableModel::Create(spec);
  for (int i = 0; i < robust.shots_size(); ++i) {
    absl::StatusOr<billiards::CueStrike> strike = StrikeFromProto(robust.shots(i).strike_after());
    ASSERT_TRUE(strike.ok()) << strike.status();
    absl::StatusOr<billiards::ShotError> e =
        billiards::ScoreShot(model, job->solver, job->recordings[static_cast<size_t>(i)], *strike,
                             1e300, robust.shots(i).strike_time_after_s());
    ASSERT_TRUE(e.ok()) << e.status();
    EXPECT_LT(e->mean_m, 1e-3) << i;
  }

  req.clear_huber_m();
  msgs.clear();
  st = Calibrate(req, &msgs);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_TRUE(msgs.back().has_report());
  EXPECT_GT(std::abs(msgs.back().report().params().at("mu_roll") - 0.006),
            10 * std::abs(robust.params().at("mu_roll") - 0.006));
}

// read_cloth: the cloth read from the tracks (three shots, a millimetre of a tracker's noise)
// is the table's, taken for the preset's before the strikes are fitted, reported with its
// stretches and in the report's params, and the offline calibration's bit for bit; tracks too
// short to read are refused naming the option.
TEST_F(CalibrationTest, ReadsTheClothFromTheTracks) {
  Start();
  v1::CalibrateTableRequest req = Request();
  *req.add_shots() = Record(0.2, 0.5, -70, 3.5, 0.1);
  req.clear_fit();
  std::mt19937_64 rng(12345);
  std::normal_distribution<double> noise(0.0, 1e-3);
  for (v1::RecordedShot& shot : *req.mutable_shots()) {
    for (v1::TrackedPoint& p : *shot.mutable_points()) {
      p.set_x_m(p.x_m() + noise(rng));
      p.set_y_m(p.y_m() + noise(rng));
    }
  }
  req.set_read_cloth(true);
  std::vector<v1::CalibrateTableResponse> msgs;
  grpc::Status st = Calibrate(req, &msgs);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_TRUE(msgs.back().has_report());
  const v1::CalibrationReport& rep = msgs.back().report();
  ASSERT_TRUE(rep.has_cloth());
  const v1::ClothReading& c = rep.cloth();
  EXPECT_TRUE(c.mu_roll_taken());
  EXPECT_GE(c.rolling_stretches(), 3u);
  EXPECT_NEAR(c.mu_roll(), 0.006, 0.03 * 0.006);
  EXPECT_LE(c.mu_roll_q1(), c.mu_roll());
  EXPECT_GE(c.mu_roll_q3(), c.mu_roll());
  EXPECT_EQ(c.mu_roll_before(), 0.0047);  // the carom preset's
  EXPECT_EQ(c.mu_roll_start(), c.mu_roll());
  EXPECT_EQ(rep.params().at("mu_roll"), c.mu_roll());
  EXPECT_EQ(rep.fitted_size(), 0);
  if (c.mu_slide_taken()) {
    EXPECT_EQ(rep.params().at("mu_slide"), c.mu_slide_start());
  } else {
    EXPECT_EQ(rep.params().count("mu_slide"), 0u);
  }
  absl::StatusOr<CalibrationJob> job = CalibrationJobFromProto(req);
  ASSERT_TRUE(job.ok()) << job.status();
  absl::StatusOr<billiards::CalibrationReport> offline =
      billiards::Calibrate(job->spec, job->solver, job->recordings, job->options);
  ASSERT_TRUE(offline.ok()) << offline.status();
  ASSERT_TRUE(offline->cloth.has_value());
  EXPECT_EQ(offline->cloth->reading.mu_roll, c.mu_roll());
  EXPECT_EQ(offline->cloth->reading.sliding, static_cast<int>(c.sliding_stretches()));
  EXPECT_EQ(offline->shots[1].before.mean_m, rep.shots(1).before().mean_m());

  // The first 0.12 s of each shot, fewer points than a stretch takes: nothing to read.
  for (v1::RecordedShot& shot : *req.mutable_shots()) {
    google::protobuf::RepeatedPtrField<v1::TrackedPoint> kept;
    for (const v1::TrackedPoint& p : shot.points()) {
      if (p.t_s() <= 0.12) *kept.Add() = p;
    }
    *shot.mutable_points() = kept;
  }
  msgs.clear();
  st = Calibrate(req, &msgs);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << st.error_message();
  EXPECT_THAT(st.error_message(), HasSubstr("read_cloth: the training shots' tracks show 0"));
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

// Cut into parts of 16 kB, the calibration that the default request limit refuses in one
// message runs, and reports what the offline calibration of the whole request does, bit for
// bit. The parts put back together are the request.
TEST_F(CalibrationTest, UploadedInPartsItRunsUnderTheDefaultLimit) {
  config_.max_receive_message_bytes = 64 << 10;
  Start();
  const v1::CalibrateTableRequest req = Request();
  ASSERT_GT(req.ByteSizeLong(), size_t{64} << 10);
  const std::vector<v1::CalibrationUpload> parts = cli::CalibrationUploadParts(req, 16 << 10);
  ASSERT_GT(parts.size(), 4u);  // the setup, and each shot over several parts
  CalibrationUploadAssembler assembler;
  for (const v1::CalibrationUpload& part : parts) {
    EXPECT_LE(part.ByteSizeLong(), size_t{16} << 10);
    ASSERT_TRUE(assembler.Add(part).ok());
  }
  absl::StatusOr<v1::CalibrateTableRequest> back = std::move(assembler).Finish();
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equals(*back, req));

  std::vector<v1::CalibrateTableResponse> msgs;
  const grpc::Status st = Upload(parts, &msgs);
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_FALSE(msgs.empty());
  ASSERT_TRUE(msgs.back().has_report());
  const v1::CalibrationReport& rep = msgs.back().report();
  EXPECT_NEAR(rep.params().at("mu_roll"), 0.006, 0.006 * 0.01);
  ExpectTheOfflineReport(req, rep);
}

// An upload out of order, or over a calibration's limits, is refused naming the message; the
// assembled request is checked as CalibrateTable's is.
TEST_F(CalibrationTest, BadUploadsAreInvalidArgumentNamingTheMessage) {
  Start();
  const std::vector<v1::CalibrationUpload> parts = cli::CalibrationUploadParts(Request());
  auto refused = [&](const std::vector<v1::CalibrationUpload>& upload) {
    std::vector<v1::CalibrateTableResponse> msgs;
    const grpc::Status st = Upload(upload, &msgs);
    EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << st.error_message();
    EXPECT_TRUE(msgs.empty());
    return st.error_message();
  };
  EXPECT_THAT(refused({}), HasSubstr("upload: no `setup`"));
  EXPECT_THAT(refused({parts[1]}), HasSubstr("upload[0]: the first message must be `setup`"));
  EXPECT_THAT(refused({parts[0], parts[0]}), HasSubstr("upload[1].setup: only the first"));
  v1::CalibrationUpload points;
  points.mutable_points()->add_points()->set_t_s(0.02);
  EXPECT_THAT(refused({parts[0], points}), HasSubstr("upload[1].points: no `shot` yet"));
  EXPECT_THAT(refused({parts[0], v1::CalibrationUpload()}), HasSubstr("upload[1]: empty"));
  v1::CalibrationUpload with_shots = parts[0];
  *with_shots.mutable_setup()->add_shots() = Request().shots(0);
  EXPECT_THAT(refused({with_shots}), HasSubstr("upload[0].setup.shots: must be empty"));
  std::vector<v1::CalibrationUpload> many = {parts[0]};
  for (int i = 0; i <= kMaxCalibrationShots; ++i) many.push_back(parts[1]);
  EXPECT_THAT(refused(many), HasSubstr("upload[201].shot: at most 200 recorded shots"));
  // Assembled, the request is CalibrateTable's: its checks name the shot and the field.
  std::vector<v1::CalibrationUpload> bad = parts;
  v1::RecordedShot* last = bad[1].mutable_shot();
  last->set_cue_ball("blue");
  EXPECT_THAT(refused(bad), HasSubstr("shots[0].cue_ball"));
}

// An upload whose client sends a few parts and then nothing is ended after
// --stream_stall_timeout, with the flag named, and gives its bytes back; an upload that sends
// slowly but steadily, each part within the timeout, goes through, however long it takes in
// all and however long its calibration then runs.
TEST_F(CalibrationTest, AnUploadThatStallsIsEndedAndGivesItsBytesBack) {
  config_.streams.stall_timeout = absl::Seconds(1);
  config_.streams.upload_bytes = 80 << 10;  // one shot (about 64 KiB), not one and a half
  Start();
  v1::CalibrateTableRequest one = Request();
  one.mutable_shots()->RemoveLast();
  const std::vector<v1::CalibrationUpload> parts = cli::CalibrationUploadParts(one, 16 << 10);
  ASSERT_GE(parts.size(), 4u);
  {
    std::unique_ptr<grpc::ClientContext> ctx = Ctx();
    auto stream = stub_->UploadCalibration(ctx.get());
    ASSERT_TRUE(stream->Write(parts[0]));
    ASSERT_TRUE(stream->Write(parts[1]));
    ASSERT_TRUE(stream->Write(parts[2]));
    const auto t0 = std::chrono::steady_clock::now();
    v1::CalibrateTableResponse r;
    EXPECT_FALSE(stream->Read(&r));  // until the server ends the call
    const grpc::Status st = stream->Finish();
    const double waited =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
    EXPECT_THAT(st.error_message(), HasSubstr("sent nothing for 1s (--stream_stall_timeout)"));
    EXPECT_GE(waited, 0.9);
    EXPECT_LT(waited, 20.0);  // two alarm periods, and a sanitizer's slowness
  }
  // Its parts are given back before its status went out: the whole shot fits the budget
  // again (it would not beside them), sent a part every 0.4 s, 0.4 s before the half-close.
  std::vector<v1::CalibrateTableResponse> msgs;
  std::unique_ptr<grpc::ClientContext> ctx = Ctx();
  auto stream = stub_->UploadCalibration(ctx.get());
  for (const v1::CalibrationUpload& part : parts) {
    std::this_thread::sleep_for(std::chrono::milliseconds(400));
    ASSERT_TRUE(stream->Write(part));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  stream->WritesDone();
  v1::CalibrateTableResponse r;
  while (stream->Read(&r)) msgs.push_back(r);
  const grpc::Status st = stream->Finish();
  ASSERT_TRUE(st.ok()) << st.error_message();
  ASSERT_FALSE(msgs.empty());
  EXPECT_TRUE(msgs.back().has_report());
}

// The uploads in progress share --max_upload_bytes: one that would pass it is refused, and
// what a call held is given back when it ends.
TEST_F(CalibrationTest, UploadsShareTheServersBudget) {
  config_.streams.upload_bytes = 96 << 10;  // less than the two shots' 130 kB
  Start();
  const std::vector<v1::CalibrationUpload> parts = cli::CalibrationUploadParts(Request(), 16 << 10);
  std::vector<v1::CalibrateTableResponse> msgs;
  grpc::Status st = Upload(parts, &msgs);
  EXPECT_EQ(st.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << st.error_message();
  EXPECT_THAT(st.error_message(), HasSubstr("--max_upload_bytes"));
  // Uploads cancelled half way give back what they held too (four would hold more than the
  // budget).
  for (int i = 0; i < 4; ++i) {
    std::unique_ptr<grpc::ClientContext> ctx = Ctx();
    auto stream = stub_->UploadCalibration(ctx.get());
    ASSERT_TRUE(stream->Write(parts[0]));
    ASSERT_TRUE(stream->Write(parts[1]));
    ASSERT_TRUE(stream->Write(parts[2]));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));  // the server reads them
    ctx->TryCancel();
    EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  }
  // The server hears of a cancellation a little after the client's Finish: once it has, one
  // shot fits (a leak would never let it).
  v1::CalibrateTableRequest small = Request();
  small.mutable_shots()->RemoveLast();
  for (int tries = 0;; ++tries) {
    msgs.clear();
    st = Upload(cli::CalibrationUploadParts(small, 16 << 10), &msgs);
    if (st.ok() || tries == 100) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_TRUE(st.ok()) << st.error_message();
  // Then again and again: a finished call has given back what it held before its client
  // has the status.
  for (int i = 0; i < 3; ++i) {
    msgs.clear();
    st = Upload(cli::CalibrationUploadParts(small, 16 << 10), &msgs);
    EXPECT_TRUE(st.ok()) << i << ": " << st.error_message();
  }
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
