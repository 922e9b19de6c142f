#include "server/billiards/calibration.h"

#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "server/billiards/convert.h"
#include "server/world/world.h"
#include "sim/core/units.h"
#include "sim/games/pool.h"
#include "sim/games/three_cushion.h"

namespace sportsim::server {
namespace {

namespace b = ::sportsim::billiards;

void ErrorToProto(const b::ShotError& e, v1::ShotError* out) {
  out->set_mean_m(e.mean_m);
  out->set_rms_m(e.rms_m);
  out->set_max_m(e.max_m);
  out->set_points(static_cast<uint32_t>(e.points));
}

absl::StatusOr<b::Recording> ShotFromProto(const b::TableModel& model, const v1::RecordedShot& shot,
                                           const std::string& field) {
  b::Recording rec;
  if (shot.name().size() > 64) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".name: at most 64 characters"));
  }
  rec.name = shot.name();
  if (shot.balls_size() < 1 || shot.balls_size() > kMaxBalls) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s.balls: 1 to %d balls, got %d", field, kMaxBalls, shot.balls_size()));
  }
  for (int i = 0; i < shot.balls_size(); ++i) {
    const v1::BallPlacement& p = shot.balls(i);
    const std::string f = absl::StrFormat("%s.balls[%d]", field, i);
    if (absl::Status s = CheckId(f + ".id", p.id()); !s.ok()) return s;
    if (rec.initial.Find(p.id()) >= 0) {
      return absl::InvalidArgumentError(absl::StrCat(f, ".id: \"", p.id(), "\" twice"));
    }
    if (!std::isfinite(p.x_m()) || !std::isfinite(p.y_m())) {
      return absl::InvalidArgumentError(absl::StrCat(f, ": x_m and y_m must be finite"));
    }
    rec.initial.balls.push_back(
        b::Ball{.id = p.id(), .r = Eigen::Vector3d(p.x_m(), p.y_m(), model.radius())});
  }
  if (absl::Status s = CheckId(field + ".cue_ball", shot.cue_ball()); !s.ok()) return s;
  rec.cue = rec.initial.Find(shot.cue_ball());
  if (rec.cue < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ".cue_ball: \"", shot.cue_ball(), "\" is not one of the shot's balls"));
  }
  rec.track.reserve(static_cast<size_t>(shot.points_size()));
  for (int i = 0; i < shot.points_size(); ++i) {
    const v1::TrackedPoint& p = shot.points(i);
    if (p.ball() >= static_cast<uint32_t>(shot.balls_size())) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s.points[%d].ball: %d is not an index into balls (0..%d)", field, i, p.ball(),
          shot.balls_size() - 1));
    }
    rec.track.push_back(b::TrackPoint{.t_s = p.t_s(), .ball = static_cast<int>(p.ball()),
                                      .xy = Eigen::Vector2d(p.x_m(), p.y_m())});
  }
  if (shot.has_strike()) {
    absl::StatusOr<b::CueStrike> strike = StrikeFromProto(shot.strike());
    if (!strike.ok()) return PrefixStatus(field + ".", strike.status());
    rec.strike = *strike;
  }
  // Given, or 0 with a given strike (the strike's time before the field was there), or fitted.
  rec.strike_time_s = shot.has_strike_time_s()
                          ? std::optional<double>(shot.strike_time_s())
                          : shot.has_strike() ? std::optional<double>(0.0) : std::nullopt;
  if (absl::Status s = b::ValidateRecording(model, rec); !s.ok()) {
    // The library's field names, as the request spells them.
    std::string message(s.message());
    for (const auto& [from, to] : {std::pair<std::string_view, std::string_view>{"track", "points"},
                                   {"initial", "balls"},
                                   {"cue", "cue_ball"}}) {
      if (message.rfind(from, 0) == 0) {
        message = std::string(to) + message.substr(from.size());
        break;
      }
    }
    return absl::InvalidArgumentError(absl::StrCat(field, ".", message));
  }
  return rec;
}

}  // namespace

absl::Status CalibrationUploadAssembler::Add(const v1::CalibrationUpload& part) {
  const std::string at = absl::StrFormat("upload[%d]", index_++);
  switch (part.part_case()) {
    case v1::CalibrationUpload::kSetup:
      if (setup_) return absl::InvalidArgumentError(at + ".setup: only the first message is `setup`");
      if (part.setup().shots_size() > 0) {
        return absl::InvalidArgumentError(
            at + ".setup.shots: must be empty: send each shot as a `shot` message");
      }
      request_ = part.setup();
      setup_ = true;
      return absl::OkStatus();
    case v1::CalibrationUpload::kShot:
      if (!setup_) return absl::InvalidArgumentError(at + ": the first message must be `setup`");
      if (request_.shots_size() == kMaxCalibrationShots) {
        return absl::InvalidArgumentError(
            absl::StrFormat("%s.shot: at most %d recorded shots", at, kMaxCalibrationShots));
      }
      points_ += part.shot().points_size();
      if (points_ > kMaxCalibrationPoints) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "%s.shot.points: at most %d tracked points in all", at, kMaxCalibrationPoints));
      }
      *request_.add_shots() = part.shot();
      return absl::OkStatus();
    case v1::CalibrationUpload::kPoints:
      if (!setup_) return absl::InvalidArgumentError(at + ": the first message must be `setup`");
      if (request_.shots_size() == 0) {
        return absl::InvalidArgumentError(at + ".points: no `shot` yet to add them to");
      }
      points_ += part.points().points_size();
      if (points_ > kMaxCalibrationPoints) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "%s.points: at most %d tracked points in all", at, kMaxCalibrationPoints));
      }
      request_.mutable_shots(request_.shots_size() - 1)->mutable_points()->MergeFrom(part.points().points());
      return absl::OkStatus();
    case v1::CalibrationUpload::PART_NOT_SET:
      break;
  }
  return absl::InvalidArgumentError(at + ": empty: give `setup`, `shot` or `points`");
}

absl::StatusOr<v1::CalibrateTableRequest> CalibrationUploadAssembler::Finish() && {
  if (!setup_) return absl::InvalidArgumentError("upload: no `setup` message");
  return std::move(request_);
}

absl::StatusOr<CalibrationJob> CalibrationJobFromProto(const v1::CalibrateTableRequest& request) {
  if (request.table().balls_size() > 0 || !request.table().rack().empty()) {
    return absl::InvalidArgumentError(
        "table: give the preset, params and cushion model only; each shot places its balls");
  }
  v1::TableSetup setup = request.table();
  setup.set_rack("empty");
  absl::StatusOr<TableBuild> table = TableFromProto(setup);
  if (!table.ok()) return table.status();
  absl::StatusOr<b::SolverOptions> solver = SolverFromProto(request.solver());
  if (!solver.ok()) return solver.status();
  CalibrationJob job{.spec = table->model.spec(), .solver = *solver};
  if (request.shots_size() < 1 || request.shots_size() > kMaxCalibrationShots) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "shots: 1 to %d recorded shots, got %d", kMaxCalibrationShots, request.shots_size()));
  }
  int64_t points = 0;
  for (const v1::RecordedShot& s : request.shots()) points += s.points_size();
  if (points > kMaxCalibrationPoints) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "shots: at most %d tracked points in all, got %d", kMaxCalibrationPoints, points));
  }
  for (int i = 0; i < request.shots_size(); ++i) {
    absl::StatusOr<b::Recording> rec =
        ShotFromProto(table->model, request.shots(i), absl::StrFormat("shots[%d]", i));
    if (!rec.ok()) return rec.status();
    job.recordings.push_back(*std::move(rec));
  }
  b::CalibrationOptions& o = job.options;
  for (int i = 0; i < request.fit_size(); ++i) {
    const v1::FitParameter& p = request.fit(i);
    const std::string f = absl::StrFormat("fit[%d]", i);
    if (absl::Status s = CheckId(f + ".name", p.name()); !s.ok()) return s;
    if (p.has_lo() != p.has_hi()) {
      return absl::InvalidArgumentError(absl::StrCat(f, ": give both lo and hi, or neither"));
    }
    b::FitParam fp{.name = p.name()};
    if (p.has_lo()) {
      if (!std::isfinite(p.lo()) || !std::isfinite(p.hi()) || !(p.lo() < p.hi())) {
        return absl::InvalidArgumentError(absl::StrCat(f, ": lo and hi must be finite, lo < hi"));
      }
      fp.lo = p.lo();
      fp.hi = p.hi();
    }
    o.params.push_back(std::move(fp));
  }
  for (uint32_t h : request.heldout()) {
    if (h >= static_cast<uint32_t>(request.shots_size())) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "heldout: %d is not a shot's index (0..%d)", h, request.shots_size() - 1));
    }
    o.heldout.push_back(static_cast<int>(h));
  }
  if (request.has_strike_window_s()) {
    if (!(request.strike_window_s() > 0.0) || request.strike_window_s() > 3600.0) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "strike_window_s must be in (0, 3600] s, got %g", request.strike_window_s()));
    }
    o.strike_window_s = request.strike_window_s();
  }
  if (request.has_max_iterations()) {
    if (request.max_iterations() < 1 || request.max_iterations() > 1000) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "max_iterations must be in [1, 1000], got %d", request.max_iterations()));
    }
    o.max_iterations = request.max_iterations();
  }
  if (request.has_max_simulations()) {
    if (request.max_simulations() < 1 || request.max_simulations() > 1000000000) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "max_simulations must be in [1, 1e9], got %d", request.max_simulations()));
    }
    o.max_simulations = request.max_simulations();
  }
  o.strike_bounds.fit_elevation = request.fit_elevation();
  switch (request.prediction()) {
    case v1::STRIKE_PREDICTION_UNSPECIFIED:
    case v1::STRIKE_PREDICTION_BEST_FIT:
      break;
    case v1::STRIKE_PREDICTION_CENTRAL_REST:
      o.strike_bounds.central_rest = true;
      break;
    default:
      return absl::InvalidArgumentError(absl::StrFormat(
          "prediction: %d is not a StrikePrediction (BEST_FIT, CENTRAL_REST)", request.prediction()));
  }
  switch (request.intent()) {
    case v1::SHOT_INTENT_UNSPECIFIED:
    case v1::SHOT_INTENT_NONE:
      break;
    case v1::SHOT_INTENT_THREE_CUSHION_POINT:
      for (size_t i = 0; i < job.recordings.size(); ++i) {
        const size_t balls = job.recordings[i].initial.balls.size();
        if (balls != 3) {
          return absl::InvalidArgumentError(absl::StrFormat(
              "intent: THREE_CUSHION_POINT needs three balls on the table; shots[%d] has %d", i,
              balls));
        }
      }
      o.strike_bounds.intent = games::ThreeCushionIntent();
      break;
    case v1::SHOT_INTENT_POT:
      if (job.spec.pockets.empty()) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "intent: POT needs a table with pockets; table '%s' has none", job.spec.name));
      }
      o.strike_bounds.intent = games::PotIntent();
      break;
    default:
      return absl::InvalidArgumentError(absl::StrFormat(
          "intent: %d is not a ShotIntent (NONE, THREE_CUSHION_POINT, POT)", request.intent()));
  }
  o.huber_m = request.huber_m();  // checked with the rest below
  o.read_cloth = request.read_cloth();
  // The options against the table and shots: parameter names and bounds.
  if (absl::Status s = b::ValidateCalibration(job.spec, job.solver, job.recordings, o); !s.ok()) {
    std::string message(s.message());
    if (message.rfind("params: ", 0) == 0) message = "fit: " + message.substr(8);
    return absl::InvalidArgumentError(message);
  }
  return job;
}

void CalibrationReportToProto(const CalibrationJob& job, const b::CalibrationReport& report,
                              v1::CalibrationReport* out) {
  for (const b::ParamReport& p : report.fitted) {
    (*out->mutable_params())[p.name] = p.after;
    v1::FittedParameter* f = out->add_fitted();
    f->set_name(p.name);
    f->set_before(p.before);
    f->set_after(p.after);
    f->set_lo(p.lo);
    f->set_hi(p.hi);
    f->set_standard_error(p.standard_error);
    f->set_at_bound(p.at_bound);
  }
  for (size_t i = 0; i < report.shots.size(); ++i) {
    const b::ShotReport& s = report.shots[i];
    const b::Recording& rec = job.recordings[i];
    const std::string& cue = rec.initial.balls[static_cast<size_t>(rec.cue)].id;
    v1::ShotCalibration* c = out->add_shots();
    c->set_name(s.name);
    c->set_heldout(s.heldout);
    StrikeToProto(s.strike_before, c->mutable_strike_before());
    StrikeToProto(s.strike_after, c->mutable_strike_after());
    c->mutable_strike_before()->set_ball(cue);
    c->mutable_strike_after()->set_ball(cue);
    ErrorToProto(s.before, c->mutable_before());
    ErrorToProto(s.after, c->mutable_after());
    c->set_strike_time_before_s(s.strike_time_before_s);
    c->set_strike_time_after_s(s.strike_time_after_s);
    c->set_plausible(static_cast<uint32_t>(s.plausible));
    c->set_intent_met(s.intent_met);
  }
  out->set_train_before_m(report.train_before_m);
  out->set_train_after_m(report.train_after_m);
  out->set_heldout_before_m(report.heldout_before_m);
  out->set_heldout_after_m(report.heldout_after_m);
  out->set_iterations(static_cast<uint32_t>(report.iterations));
  out->set_simulations(report.simulations);
  for (double d : report.start_rms_m) out->add_start_rms_m(d);
  out->set_start_kept(static_cast<uint32_t>(report.start_kept));
  if (report.cloth) {
    const b::ClothTaken& c = *report.cloth;
    v1::ClothReading* r = out->mutable_cloth();
    r->set_rolling_stretches(static_cast<uint32_t>(c.reading.rolling));
    r->set_sliding_stretches(static_cast<uint32_t>(c.reading.sliding));
    r->set_mu_roll(c.reading.mu_roll);
    r->set_mu_roll_q1(c.reading.mu_roll_q1);
    r->set_mu_roll_q3(c.reading.mu_roll_q3);
    r->set_mu_slide(c.reading.mu_slide);
    r->set_mu_slide_q1(c.reading.mu_slide_q1);
    r->set_mu_slide_q3(c.reading.mu_slide_q3);
    r->set_mu_roll_taken(c.mu_roll_taken);
    r->set_mu_slide_taken(c.mu_slide_taken);
    r->set_mu_roll_before(c.mu_roll_before);
    r->set_mu_slide_before(c.mu_slide_before);
    r->set_mu_roll_start(c.mu_roll);
    r->set_mu_slide_start(c.mu_slide);
    // The table the report describes takes the read constants too (a fitted one is there
    // already, at its fitted value).
    if (c.mu_roll_taken) out->mutable_params()->insert({"mu_roll", report.params.mu_roll});
    if (c.mu_slide_taken) out->mutable_params()->insert({"mu_slide", report.params.mu_slide});
  }
}

}  // namespace sportsim::server
