// How close each cushion model comes to recorded shots, before and after calibration, and what
// it costs per shot (docs/billiards.md, "Calibration from recorded shots").
//
// Recordings:
//  - synthetic (always): three-cushion shots on a reference table that none of the models is:
//    the carom geometry with Mathavan et al.'s measured cushion (restitution 0.98, friction
//    0.14, their model) and heated-cloth constants (rolling resistance 0.006, sliding 0.2,
//    spin-down 10 rad/s^2), random layouts and strikes, tracked at 50 Hz with 1 mm Gaussian
//    noise like a camera tracker, whose clock starts 0.1 to 0.5 s before the strike (the
//    strike's time is fitted, as a recorded shot's is). What a model loses here is model error
//    plus noise.
//  - --recordings PATH: a track file or a shot set (client/track_json.h: CSV or JSON lines of
//    t, ball, x, y, as `shot simulate --format csv` writes; a JSON array of many shots; or a
//    match tracker's export), or
//    a directory of them (*.csv, *.jsonl, *.json), on the preset --preset (default carom), in
//    the frame --track-origin centre|corner and --track-scale S (metres per unit) say, at most
//    --recorded-shots N of them (spread evenly through the set). Obtain recorded shots from a
//    tracker of your own table or a public set (docs/billiards.md); nothing third-party is
//    committed. --no-synthetic skips the synthetic recordings; --write-set FILE writes them as
//    a shot set, in millimetres from a corner of the table (what --track-origin corner
//    --track-scale 0.001 reads back), to try the importer on shots whose truth is known.
//  - --false-detections F: a fraction F of the synthetic tracks' points are a tracker's false
//    detections, anywhere on the table; every fit sees them, and every score is taken against
//    the clean track (the same noise without them), the truth a false detection hides.
//  - --huber M: every fit under Huber's loss with scale M metres (calibrate.h), instead of
//    squared distances.
//  - --aimed: the synthetic strikes aimed so that the cue ball meets the first object ball
//    first, as in most three-cushion shots (the same layouts, speeds and spins otherwise);
//    source synthetic-aimed.
//  - --scoring: only synthetic shots whose struck ball scores the three-cushion point under the
//    reference table (random shots, aimed, drawn until one does), as most of a match's shots
//    are meant to; source ends in -scoring.
//  - --predict central: every strike fitted on a shot's start is the one whose rest is central
//    among the strikes that fit the start about as well as the best (StrikeBounds::
//    central_rest; the default, best-fit, takes the best fit); sources end in -central.
//  - --intent three-cushion: every strike fitted on a shot's start takes the three-cushion
//    player's intent as its prior (StrikeBounds::intent, games::ThreeCushionIntent: of the
//    strikes that fit the start about as well as the best, only those that score the point);
//    sources end in -intent. --intent pot: the pool player's (games::PotIntent, a ball
//    pocketed and the struck ball kept up), for recorded pool shots (--no-synthetic
//    --recordings PATH --preset pool-9ft); on the synthetic carom shots it is never met.
//  - --elevation LO:HI: the synthetic cues raised LO to HI degrees (a raised cue's side spin
//    curves the path from the start); --fit-elevation fits the cue's elevation with every
//    strike (else level). Raised shots' source ends in -raised.
//
// For each model (han, mathavan2010, stronge), with the preset's constants, with its rolling resistance
// alone fitted, and calibrated (its cloth and cushion constants fitted), each fit on the first
// half of the shots, scored on the second half (held out):
//  - fit: the strike fitted to the whole shot, the median over shots of the mean distance
//    between tracked and simulated centres (every ball, every frame);
//  - rails: the share of shots whose struck ball meets the rails the recording shows, in the
//    same order (the first three; the recording's read from its track alone, TrackedRails);
//  - predict: the strike fitted on the first 0.4 s after it only, the median distance of the struck
//    ball's final position from where it was last tracked, and the share of shots whose struck
//    ball meets the recorded rails (as above);
//  - cpu: the median thread CPU of one shot's simulation (its strike as fitted).
// CSV on stdout: source,model,constants,fit_mm,fit_rails,predict_final_mm,predict_rails,cpu_us,
// shots
//
// Usage: billiards_calibration_study [--quick] [--shots N] [--no-synthetic] [--recordings PATH]
//          [--preset P] [--track-origin centre|corner] [--track-scale S] [--recorded-shots N]
//          [--write-set FILE] [--false-detections F] [--huber M] [--aimed]
//          [--elevation LO:HI] [--fit-elevation] [--resample] [--model M]...
//          [--cushion-on-read-cloth] [--strike-recovery] [--fade-recovery U]
//          [--ball-ball-model alciatore|mathavan2014] [--scoring] [--predict best-fit|central]
//          [--intent three-cushion|pot] [--predict-recovery [--pots]]
//
// --model M: study only cushion model M (han, mathavan2010, stronge; repeatable); default all.
// --ball-ball-model mathavan2014: every row with Mathavan's integrated ball-ball impact
// (BallBallModel::kMathavan2014) instead of TP A-14's single impulse; the model column reads
// e.g. han+mathavan2014.
// --cushion-on-read-cloth: a fourth row per model, cushion_on_read_cloth: the cloth read from
// the training shots' tracks (no model), the spin-down and cushion constants fitted on it.
// --resample: every strike fit resamples its starts between windows (StrikeBounds::resample);
// the synthetic source ends in -resample.
// --fade-recovery U: instead, whether a calibration reads slip-speed friction (u_c = U) back
// from the synthetic shots' tracks, with U = 0 the control (FadeRecovery; --shots, --huber and
// --fit-elevation apply).
// --predict-recovery: instead, what the central rest and the intent gain a prediction from a
// shot's first 0.4 s under the reference table itself or --preset's (PredictRecovery;
// --shots, --aimed, --scoring, --elevation, --huber and --fit-elevation apply). With --pots,
// on long pots of a pool table (--preset, default pool-9ft) under its own constants, the pool
// player's intent weighed (SyntheticPots; --shots, --huber and --fit-elevation apply).
// --strike-recovery: instead, how well the strike fit alone finds the synthetic shots'
// strikes, each start alone and resampled, under the reference table itself or --preset's
// (StrikeRecovery; --shots, --aimed, --huber and --fit-elevation apply).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "client/track_json.h"
#include "sim/billiards/calibrate.h"
#include "sim/billiards/shot.h"
#include "sim/billiards/track_file.h"
#include "sim/core/cpu_clock.h"
#include "sim/games/pool.h"
#include "sim/games/three_cushion.h"

namespace sportsim::billiards {
namespace {

constexpr double kPredictWindow = 0.4;  // s

// Every fit's Huber scale (m; 0: squared distances), --huber; what a strike fit may be
// (--fit-elevation).
double huber_m = 0.0;
// --cushion-on-read-cloth: a row more, the cloth read from the training shots' tracks
// (CalibrationOptions::read_cloth) and the spin-down and cushion fitted on it.
bool cushion_on_read_cloth = false;
StrikeBounds strike_bounds;
// The cushion models studied (--model, repeatable; default all three).
std::vector<std::string> models;
// --ball-ball-model: the ball-ball impact of every table studied.
BallBallModel ball_ball_model = BallBallModel::kAlciatore;
// --fade-recovery U: the synthetic recordings' table slides with slip-speed friction u_c = U.
double reference_fade_mps = 0.0;
// --scoring: the synthetic shots are drawn until each scores the three-cushion point.
bool scoring_only = false;

double Median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// The reference table of the synthetic recordings.
TableSpec ReferenceTable() {
  TableSpec s = *MakeTablePreset("carom");
  s.params.cushion_model = CushionModel::kMathavan2010;
  s.params.e_cushion_mathavan = 0.98;
  s.params.f_cushion_mathavan = 0.14;
  s.params.mu_roll = 0.006;
  s.params.slide_fade_speed_mps = reference_fade_mps;
  // Mathavan et al.'s cushion has a constant restitution, and the side spin decays as on the
  // carom preset before its restitution fell with speed (the runs this study's tables report).
  s.params.cushion_restitution_exponent = 0.0;
  s.params.spin_decel_rps2 = 3.1;
  return s;
}

// A synthetic shot's true strike and its time on the tracker's clock.
struct Truth {
  CueStrike strike;
  double time_s = 0.0;
};

// n random three-ball shots. Aimed: each strike's line passes within 0.9 of a ball's diameter
// of the first object ball's centre, so that the cue ball meets it first, as in most
// three-cushion shots; else within +-0.25 rad of its centre, and many miss it.
// A cue elevation in [elevation_deg[0], elevation_deg[1]] degrees (drawn from its own
// generator, so the shots are the same otherwise).
std::vector<Recording> Synthetic(int n, uint64_t seed, double false_detections = 0.0,
                                 bool aimed = false, std::array<double, 2> elevation_deg = {0, 0},
                                 std::vector<Truth>* truths = nullptr) {
  const TableModel truth = *TableModel::Create(ReferenceTable());
  const double l = truth.spec().length_m, w = truth.spec().width_m, d = 2 * truth.radius();
  std::mt19937_64 rng(seed);
  std::mt19937_64 clock_rng(seed + 1);  // the trackers' clocks, apart from the shots
  std::mt19937_64 cue_rng(seed + 2);    // the cue's elevation, apart from the rest
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Recording> out;
  while (static_cast<int>(out.size()) < n) {
    TableState s;
    const char* ids[] = {"white", "yellow", "red"};
    while (s.balls.size() < 3) {
      const Eigen::Vector3d r((u(rng) - 0.5) * 0.8 * l, (u(rng) - 0.5) * 0.8 * w, truth.radius());
      bool clear = true;
      for (const Ball& b : s.balls) clear = clear && (b.r - r).norm() > 4 * d;
      if (clear) s.balls.push_back(Ball{.id = ids[s.balls.size()], .r = r});
    }
    const Eigen::Vector3d to = s.balls[1].r - s.balls[0].r;
    CueStrike c;
    c.ball_speed = true;
    c.speed_mps = 2.0 + 2.5 * u(rng);
    const double spread = u(rng) - 0.5;
    // Aimed: the line misses the ball's centre by up to 0.9 d, and the balls stand over 4 d
    // apart, so the sine is within +-0.23.
    c.phi_rad = std::atan2(to.y(), to.x()) +
                (aimed ? std::asin(1.8 * spread * d / to.head<2>().norm()) : spread * 0.5);
    c.a = 0.6 * (u(rng) - 0.5);
    c.b = 0.6 * (u(rng) - 0.5);
    if (elevation_deg[1] > 0.0) {
      c.theta_rad = (elevation_deg[0] + (elevation_deg[1] - elevation_deg[0]) * u(cue_rng)) *
                    std::numbers::pi / 180.0;
    }
    // A tracker's clock: started 0.1 to 0.5 s before the strike, whose time is not known.
    const double strike_time = 0.1 + 0.4 * u(clock_rng);
    if (scoring_only) {
      TableState struck = s;
      if (!ApplyStrike(truth, 0, c, 0, &struck).ok()) continue;
      absl::StatusOr<ShotResult> shot = SimulateShot(truth, SolverOptions{}, struck, ShotOptions{});
      if (!shot.ok() || !games::ThreeCushionIntent()(s, 0, shot->events)) continue;
    }
    absl::StatusOr<Recording> r = SyntheticRecording(
        truth, SolverOptions{}, s, 0, c,
        SyntheticOptions{.rate_hz = 50,
                         .noise_m = 1e-3,
                         .seed = seed + out.size(),
                         .strike_time_s = strike_time,
                         .keep_strike_time = false,
                         .false_detections = false_detections});
    if (!r.ok()) continue;
    r->name = "synthetic" + std::to_string(out.size());
    if (truths != nullptr) truths->push_back({c, strike_time});
    out.push_back(*std::move(r));
  }
  return out;
}

// n long pots on a pool table under its own constants, tracked at 50 Hz with 1 mm of noise by
// a tracker whose clock starts 0.1-0.5 s before the strike: the object ball 0.25-1 m from a
// pocket (the pockets in turn), the cue ball 0.8-1.8 m behind the ghost ball at a cut of up
// to 35 degrees (so that a 0.4 s window mostly ends before they meet), struck at 1.5-4 m/s
// through the ghost ball's centre with up to 0.4 R of side and 0.5 R of height; drawn until the
// shot pots the object ball and leaves the cue ball up (games::PotIntent).
std::vector<Recording> SyntheticPots(int n, uint64_t seed, const TableSpec& spec) {
  const TableModel m = *TableModel::Create(spec);
  const double r = m.radius();
  const double hx = 0.5 * spec.length_m - 2 * r, hy = 0.5 * spec.width_m - 2 * r;
  std::mt19937_64 rng(seed);
  std::mt19937_64 clock_rng(seed + 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const ShotIntent pot = games::PotIntent();
  std::vector<Recording> out;
  for (size_t k = 0; static_cast<int>(out.size()) < n && k < 1000 * static_cast<size_t>(n); ++k) {
    const Eigen::Vector2d pocket = spec.pockets[k % spec.pockets.size()].centre;
    const double deg = std::numbers::pi / 180.0;
    const Eigen::Vector2d along =
        Eigen::Rotation2Dd((u(rng) - 0.5) * 60 * deg) * (-pocket).normalized();
    const Eigen::Vector2d object = pocket + (0.25 + 0.75 * u(rng)) * along;
    const Eigen::Vector2d line = (pocket - object).normalized();
    const Eigen::Vector2d ghost = object - 2 * r * line;
    const Eigen::Vector2d cue =
        ghost - (0.8 + u(rng)) * (Eigen::Rotation2Dd((u(rng) - 0.5) * 70 * deg) * line);
    const Eigen::Vector2d aim = ghost - cue;
    CueStrike c{.speed_mps = 1.5 + 2.5 * u(rng), .ball_speed = true,
                .phi_rad = std::atan2(aim.y(), aim.x()), .a = 0.8 * (u(rng) - 0.5),
                .b = u(rng) - 0.5};
    const double strike_time = 0.1 + 0.4 * u(clock_rng);
    const auto on_cloth = [&](const Eigen::Vector2d& p) {
      return std::abs(p.x()) < hx && std::abs(p.y()) < hy;
    };
    if (!on_cloth(object) || !on_cloth(cue)) continue;
    TableState s;
    s.balls.push_back(Ball{.id = "cue", .r = Eigen::Vector3d(cue.x(), cue.y(), r)});
    s.balls.push_back(Ball{.id = "1", .r = Eigen::Vector3d(object.x(), object.y(), r)});
    TableState struck = s;
    if (!ApplyStrike(m, 0, c, 0, &struck).ok()) continue;
    absl::StatusOr<ShotResult> shot = SimulateShot(m, SolverOptions{}, struck, ShotOptions{});
    if (!shot.ok() || !pot(s, 0, shot->events)) continue;
    absl::StatusOr<Recording> rec = SyntheticRecording(
        m, SolverOptions{}, s, 0, c,
        SyntheticOptions{.rate_hz = 50, .noise_m = 1e-3, .seed = seed + out.size(),
                         .strike_time_s = strike_time, .keep_strike_time = false});
    if (!rec.ok()) continue;
    rec->name = "pot" + std::to_string(out.size());
    out.push_back(*std::move(rec));
  }
  return out;
}

// The recorded shots at `path` (a file, or a directory of them), at most `max_shots` of them
// spread evenly through the whole; unusable shots are skipped with a note on stderr.
std::vector<Recording> FromPath(const std::string& path, const TableModel& model,
                                const TrackFrame& frame, int max_shots) {
  std::vector<std::filesystem::path> files;
  if (std::filesystem::is_directory(path)) {
    for (const auto& e : std::filesystem::directory_iterator(path)) {
      const std::string ext = e.path().extension().string();
      if (ext == ".csv" || ext == ".jsonl" || ext == ".json") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
  } else {
    files.push_back(path);
  }
  std::vector<Recording> out;
  for (const auto& file : files) {
    std::ifstream in(file);
    std::stringstream text;
    text << in.rdbuf();
    absl::StatusOr<std::vector<cli::NamedTrack>> tracks = cli::ParseTracks(text.str(), frame);
    if (!tracks.ok()) {
      std::fprintf(stderr, "%s: skipped: %s\n", file.c_str(), std::string(tracks.status().message()).c_str());
      continue;
    }
    for (const cli::NamedTrack& t : *tracks) {
      Recording r;
      r.name = file.filename().string() + (t.name.empty() ? "" : "#" + t.name);
      if (t.file.cue < 0) {
        std::fprintf(stderr, "%s: skipped: no ball moves\n", r.name.c_str());
        continue;
      }
      for (size_t b = 0; b < t.file.balls.size(); ++b) {
        r.initial.balls.push_back(Ball{.id = t.file.balls[b],
                                       .r = Eigen::Vector3d(t.file.spots[b].x(), t.file.spots[b].y(),
                                                            model.radius())});
      }
      r.cue = t.file.cue;
      r.track = t.file.points;
      r.strike_time_s.reset();  // a tracker's clock: fitted
      if (absl::Status s = ValidateRecording(model, r); !s.ok()) {
        std::fprintf(stderr, "%s: skipped: %s\n", r.name.c_str(), std::string(s.message()).c_str());
        continue;
      }
      out.push_back(std::move(r));
    }
  }
  if (max_shots > 0 && static_cast<int>(out.size()) > max_shots) {
    std::vector<Recording> some;
    for (int i = 0; i < max_shots; ++i) {
      some.push_back(std::move(out[static_cast<size_t>(i) * out.size() / static_cast<size_t>(max_shots)]));
    }
    out = std::move(some);
  }
  return out;
}

// Writes recordings as a shot set (client/track_json.h) in millimetres from the corner at
// (-length/2, -width/2): where each ball stood at t = 0, then its track.
bool WriteShotSet(const std::string& path, const TableSpec& spec, const std::vector<Recording>& recs) {
  std::ofstream out(path);
  const TrackFrame mm_from_corner = TrackFrameOn(spec, /*from_corner=*/true, 1e-3);
  out << "[";
  for (size_t i = 0; i < recs.size(); ++i) {
    const Recording& r = recs[i];
    out << (i ? ",\n " : "") << "{\"id\": \"" << r.name << "\", \"balls\": {";
    for (size_t b = 0; b < r.initial.balls.size(); ++b) {
      std::string t = "0", x, y;
      auto add = [&](const Eigen::Vector2d& xy) {
        const Eigen::Vector2d mm = (xy - mm_from_corner.origin) / mm_from_corner.scale;
        char buf[64];
        std::snprintf(buf, sizeof buf, "%.17g", mm.x());
        x += (x.empty() ? "" : ", ") + std::string(buf);
        std::snprintf(buf, sizeof buf, "%.17g", mm.y());
        y += (y.empty() ? "" : ", ") + std::string(buf);
      };
      add(r.initial.balls[b].r.head<2>());
      for (const TrackPoint& p : r.track) {
        if (p.ball != static_cast<int>(b)) continue;
        char buf[32];
        std::snprintf(buf, sizeof buf, ", %.17g", p.t_s);
        t += buf;
        add(p.xy);
      }
      out << (b ? ", " : "") << "\"" << r.initial.balls[b].id << "\": {\"t\": [" << t
          << "], \"x\": [" << x << "], \"y\": [" << y << "]}";
    }
    out << "}}";
  }
  out << "]\n";
  return static_cast<bool>(out);
}

// The first three of a sequence of rails.
std::vector<Rail> FirstThree(std::vector<Rail> rails) {
  if (rails.size() > 3) rails.resize(3);
  return rails;
}

// The rails met by the struck ball, in order (the first three), where it rests, and whether
// it scores the three-cushion point; played: whether the engine played the strike at all.
struct Outcome {
  std::vector<Rail> rails;
  Eigen::Vector2d rest = Eigen::Vector2d::Zero();
  bool point = false;
  bool played = false;
  double cpu_s = 0.0;
};
Outcome Play(const TableModel& m, const Recording& rec, const CueStrike& strike,
             const ShotIntent& meant = games::ThreeCushionIntent()) {
  Outcome o;
  TableState s = rec.initial;
  if (!ApplyStrike(m, 0, strike, rec.cue, &s).ok()) return o;
  const double c0 = ThreadCpuSeconds();
  absl::StatusOr<ShotResult> r = SimulateShot(m, SolverOptions{}, s, ShotOptions{});
  o.cpu_s = ThreadCpuSeconds() - c0;
  if (!r.ok()) return o;
  o.rails = FirstThree(SimulatedRails(m.spec(), r->events, rec.cue));
  o.rest = r->final_state.balls[static_cast<size_t>(rec.cue)].r.head<2>();
  o.point = meant(rec.initial, rec.cue, r->events);
  o.played = true;
  return o;
}

// Where the struck ball was last tracked: the median of its last five points (each
// coordinate), which a false detection among them does not move.
Eigen::Vector2d LastTracked(const Recording& rec) {
  std::vector<double> x, y;
  for (auto it = rec.track.rbegin(); it != rec.track.rend() && x.size() < 5; ++it) {
    if (it->ball != rec.cue) continue;
    x.push_back(it->xy.x());
    y.push_back(it->xy.y());
  }
  if (x.empty()) return rec.initial.balls[static_cast<size_t>(rec.cue)].r.head<2>();
  return Eigen::Vector2d(Median(x), Median(y));
}

// Scores the strikes fitted to `test` against `truth` (the same shots' clean tracks, or
// `test` itself).
void Score(const std::string& source, const std::string& model_name, const std::string& constants,
           const TableSpec& spec, const std::vector<Recording>& test,
           const std::vector<Recording>& truth) {
  const TableModel m = *TableModel::Create(spec);
  std::vector<double> fit, final_err, cpu;
  int fit_rails = 0, predict_rails = 0, n = 0, intent_met = 0;
  for (size_t i = 0; i < test.size(); ++i) {
    const Recording& rec = test[i];
    const Recording& clean = truth[i];
    absl::StatusOr<StrikeFit> whole = FitStrike(m, SolverOptions{}, rec, strike_bounds, 1e300, huber_m);
    absl::StatusOr<StrikeFit> early =
        FitStrike(m, SolverOptions{}, rec, strike_bounds, kPredictWindow, huber_m);
    if (!whole.ok() || !early.ok()) continue;
    absl::StatusOr<ShotError> scored =
        ScoreShot(m, SolverOptions{}, clean, whole->strike, 1e300, whole->strike_time_s);
    if (!scored.ok()) continue;
    ++n;
    intent_met += early->intent_met;
    fit.push_back(scored->mean_m);
    const Outcome best = Play(m, rec, whole->strike);
    const Outcome predicted = Play(m, rec, early->strike);
    final_err.push_back((predicted.rest - LastTracked(clean)).norm());
    const std::vector<Rail> recorded = FirstThree(TrackedRails(m, clean, clean.cue));
    fit_rails += best.rails == recorded;
    predict_rails += predicted.rails == recorded;
    cpu.push_back(best.cpu_s);
  }
  const auto share = [n](int k) { return n > 0 ? static_cast<double>(k) / n : 0.0; };
  if (strike_bounds.intent) {
    std::fprintf(stderr, "%s %s %s: %d of %d predictions meet the intent\n", source.c_str(),
                 model_name.c_str(), constants.c_str(), intent_met, n);
  }
  std::printf("%s,%s,%s,%.1f,%.2f,%.0f,%.2f,%.0f,%d\n", source.c_str(), model_name.c_str(),
              constants.c_str(), 1e3 * Median(fit), share(fit_rails), 1e3 * Median(final_err),
              share(predict_rails), 1e6 * Median(cpu), n);
  std::fflush(stdout);
}

// Fits on the first half of `all`, scores on the second half against `truths` (the clean
// tracks of the same shots; `all` itself when empty).
void Study(const std::string& source, const TableSpec& preset, const std::vector<Recording>& all,
           const std::vector<Recording>& truths = {}) {
  const size_t half = all.size() / 2;
  const std::vector<Recording> train(all.begin(), all.begin() + static_cast<long>(half));
  const std::vector<Recording> test(all.begin() + static_cast<long>(half), all.end());
  const std::vector<Recording>& clean_all = truths.empty() ? all : truths;
  const std::vector<Recording> truth(clean_all.begin() + static_cast<long>(half), clean_all.end());
  for (CushionModel cm : {CushionModel::kHan, CushionModel::kMathavan2010,
                          CushionModel::kStrongeCompliant}) {
    const std::string name = cm == CushionModel::kHan            ? "han"
                             : cm == CushionModel::kMathavan2010 ? "mathavan2010"
                                                                 : "stronge";
    if (!models.empty() && std::find(models.begin(), models.end(), name) == models.end()) continue;
    const auto row_name = [&](const std::string& n) {
      return ball_ball_model == BallBallModel::kMathavan2014 ? n + "+mathavan2014" : n;
    };
    TableSpec spec = preset;
    spec.params.cushion_model = cm;
    spec.params.ball_ball_model = ball_ball_model;
    Score(source, row_name(name), "preset", spec, test, truth);
    // The rolling resistance alone: what one constant from the right cloth is worth.
    CalibrationOptions roll;
    roll.params.push_back({.name = "mu_roll"});
    roll.huber_m = huber_m;
    roll.strike_bounds = strike_bounds;
    if (absl::StatusOr<CalibrationReport> r = Calibrate(spec, SolverOptions{}, train, roll); r.ok()) {
      TableSpec s = spec;
      s.params = r->params;
      Score(source, row_name(name), "rolling_only", s, test, truth);
    }
    // The spin-down and the model's own cushion constants; calibrated: the cloth's with them.
    std::vector<FitParam> cushion = {{.name = "spin_decel_rps2"}};
    if (cm != CushionModel::kMathavan2010) {
      cushion.push_back({.name = "e_cushion"});
      cushion.push_back({.name = "f_cushion"});
    } else {
      cushion.push_back({.name = "e_cushion_mathavan"});
      cushion.push_back({.name = "f_cushion_mathavan"});
    }
    const auto calibrate = [&](const std::string& row, bool read_cloth,
                               std::vector<FitParam> params) {
      CalibrationOptions o;
      o.huber_m = huber_m;
      o.strike_bounds = strike_bounds;
      o.read_cloth = read_cloth;
      o.params = std::move(params);
      absl::StatusOr<CalibrationReport> r = Calibrate(spec, SolverOptions{}, train, o);
      if (!r.ok()) {
        std::fprintf(stderr, "%s %s: %s failed: %s\n", source.c_str(), name.c_str(), row.c_str(),
                     r.status().ToString().c_str());
        return;
      }
      std::fprintf(stderr, "%s %s: %s in %lld simulations, %d iterations, start %d of %d kept\n",
                   source.c_str(), name.c_str(), row.c_str(),
                   static_cast<long long>(r->simulations), r->iterations, r->start_kept,
                   static_cast<int>(r->start_rms_m.size()));
      if (r->cloth) {
        std::fprintf(stderr, "%s %s: cloth read: mu_roll %g (%d stretches), mu_slide %g (%d)\n",
                     source.c_str(), name.c_str(), r->cloth->mu_roll, r->cloth->reading.rolling,
                     r->cloth->mu_slide, r->cloth->reading.sliding);
      }
      for (const ParamReport& p : r->fitted) {
        std::fprintf(stderr, "%s %s: %s %g -> %g (standard error %.2g%s)\n", source.c_str(),
                     name.c_str(), p.name.c_str(), p.before, p.after, p.standard_error,
                     p.at_bound ? ", at a bound" : "");
      }
      TableSpec s = spec;
      s.params = r->params;
      Score(source, row_name(name), row, s, test, truth);
    };
    std::vector<FitParam> every = {{.name = "mu_slide"}, {.name = "mu_roll"}};
    every.insert(every.end(), cushion.begin(), cushion.end());
    calibrate("calibrated", false, std::move(every));
    if (cushion_on_read_cloth) calibrate("cushion_on_read_cloth", true, cushion);
  }
}

// How well FitStrike finds the strikes of the synthetic recordings under the reference table
// itself (no model error), or with --preset P under that preset's table: for each shot, the
// mean distance of the true strike's shot from the track (the noise, under the reference
// table), and of the strike fitted each start alone (the default) and resampled
// (StrikeBounds::resample), with each fit's simulations. CSV on stdout; on stderr, how many
// fits are more than 5 % above the true strike's error.
void StrikeRecovery(int n, bool aimed, const TableSpec& spec) {
  std::vector<Truth> truths;
  const std::vector<Recording> recs = Synthetic(n, 33, 0.0, aimed, {0, 0}, &truths);
  const TableModel m = *TableModel::Create(spec);
  std::printf("shot,true_mm,fit_mm,resampled_mm,simulations,resampled_simulations\n");
  int misses = 0, resampled_misses = 0, scored = 0;
  for (size_t i = 0; i < recs.size(); ++i) {
    const Truth& t = truths[i];
    absl::StatusOr<ShotError> truth = ScoreShot(m, SolverOptions{}, recs[i], t.strike, 1e300, t.time_s);
    StrikeBounds resampling = strike_bounds;
    resampling.resample = true;
    absl::StatusOr<StrikeFit> alone = FitStrike(m, SolverOptions{}, recs[i], strike_bounds, 1e300, huber_m);
    absl::StatusOr<StrikeFit> resampled = FitStrike(m, SolverOptions{}, recs[i], resampling, 1e300, huber_m);
    if (!truth.ok() || !alone.ok() || !resampled.ok()) {
      std::fprintf(stderr, "%s: %s\n", recs[i].name.c_str(),
                   (!truth.ok() ? truth.status() : !alone.ok() ? alone.status() : resampled.status())
                       .ToString().c_str());
      continue;
    }
    ++scored;
    misses += alone->error.mean_m > 1.05 * truth->mean_m;
    resampled_misses += resampled->error.mean_m > 1.05 * truth->mean_m;
    std::printf("%zu,%.2f,%.2f,%.2f,%lld,%lld\n", i, 1e3 * truth->mean_m, 1e3 * alone->error.mean_m,
                1e3 * resampled->error.mean_m, static_cast<long long>(alone->simulations),
                static_cast<long long>(resampled->simulations));
    std::fflush(stdout);
  }
  std::fprintf(stderr, "strike recovery: fits more than 5 %% above the true strike's error: %d of %d "
               "each start alone, %d resampled\n", misses, scored, resampled_misses);
}

// What a prediction from a shot's first 0.4 s gains from weighing its plausible strikes
// (StrikeBounds::central_rest) and from the player's intent (intent), at best: the recordings
// (synthetic, made under `spec`) fitted under `spec` itself (no model error) on their first
// 0.4 s: the best fit, the central rest, and the central rest of the strikes that do what was
// meant (`meant`: the three-cushion point, or a pot; its words name it in the summaries). Per
// shot and way: where the struck ball ends against where it was last tracked (mm) and whether
// the fitted shot does what was meant (the CSV's "scores" columns); the simulations of each.
// On stderr the medians, and in how many shots each way's struck ball meets the first three
// rails its track shows, in order (TrackedRails, as the study's rows).
struct Meant {
  ShotIntent intent;
  const char* intended;  // "the point intended"
  const char* met;       // "the point scored"
};
void PredictRecovery(const std::vector<Recording>& recs, const TableSpec& spec,
                     const Meant& meant) {
  const TableModel m = *TableModel::Create(spec);
  const ShotIntent& point = meant.intent;
  std::array<StrikeBounds, 3> ways = {strike_bounds, strike_bounds, strike_bounds};
  ways[0].central_rest = false;
  ways[0].intent = nullptr;
  ways[1].central_rest = true;
  ways[1].intent = nullptr;
  ways[2].central_rest = true;
  ways[2].intent = point;
  std::printf("shot,best_fit_mm,central_mm,intent_mm,best_fit_scores,central_scores,intent_scores,"
              "best_fit_simulations,central_simulations,intent_simulations\n");
  std::array<std::vector<double>, 3> err;
  std::array<int, 3> scores = {0, 0, 0}, rails = {0, 0, 0};
  for (size_t i = 0; i < recs.size(); ++i) {
    const std::vector<Rail> recorded = FirstThree(TrackedRails(m, recs[i], recs[i].cue));
    std::array<double, 3> e{};
    std::array<int, 3> scored{}, railed{};
    std::array<long long, 3> sims{};
    bool ok = true;
    for (size_t w = 0; w < ways.size() && ok; ++w) {
      absl::StatusOr<StrikeFit> fit = FitStrike(m, SolverOptions{}, recs[i], ways[w], kPredictWindow, huber_m);
      if (!fit.ok()) {
        std::fprintf(stderr, "%s: %s\n", recs[i].name.c_str(), fit.status().ToString().c_str());
        ok = false;
        break;
      }
      const Outcome o = Play(m, recs[i], fit->strike, point);
      if (!o.played) {
        ok = false;
        break;
      }
      e[w] = (o.rest - LastTracked(recs[i])).norm();
      scored[w] = o.point ? 1 : 0;
      railed[w] = o.rails == recorded ? 1 : 0;
      sims[w] = fit->simulations;
    }
    if (!ok) continue;
    for (size_t w = 0; w < ways.size(); ++w) {
      err[w].push_back(e[w]);
      scores[w] += scored[w];
      rails[w] += railed[w];
    }
    std::printf("%zu,%.0f,%.0f,%.0f,%d,%d,%d,%lld,%lld,%lld\n", i, 1e3 * e[0], 1e3 * e[1], 1e3 * e[2],
                scored[0], scored[1], scored[2], sims[0], sims[1], sims[2]);
    std::fflush(stdout);
  }
  std::fprintf(stderr, "predict recovery: median final position %.0f mm (best fit), %.0f mm "
               "(central rest), %.0f mm (central rest, %s); %s in %d, %d and %d of %zu\n",
               1e3 * Median(err[0]), 1e3 * Median(err[1]), 1e3 * Median(err[2]), meant.intended,
               meant.met, scores[0], scores[1], scores[2], err[0].size());
  std::fprintf(stderr, "predict recovery: the track's first three rails met in %d, %d and %d of %zu\n",
               rails[0], rails[1], rails[2], err[0].size());
}

// Slip-speed friction read back from tracks: n synthetic recordings made with u_c = `fade` (the
// reference table otherwise, tracked at 50 Hz with 1 mm noise), calibrated from the reference
// table with the fade off, u_c alone fitted in [0, 1] m/s: on all n shots, then on each half
// (trained on it, scored on the other). `fade` 0 is the control: what the noise alone reads.
// CSV on stdout.
void FadeRecovery(int n, double fade) {
  reference_fade_mps = fade;
  const std::vector<Recording> recs = Synthetic(n, 47);
  TableSpec spec = ReferenceTable();
  spec.params.slide_fade_speed_mps = 0.0;
  std::printf("true_fade_mps,trained_on,heldout,fitted_fade_mps,standard_error,at_bound,"
              "train_before_mm,train_after_mm,heldout_before_mm,heldout_after_mm,simulations\n");
  const int half = n / 2;
  for (const std::string_view split : {"all", "first_half", "second_half"}) {
    CalibrationOptions o;
    o.params.push_back({.name = "slide_fade_speed_mps", .lo = 0.0, .hi = 1.0});
    o.strike_bounds = strike_bounds;
    o.huber_m = huber_m;
    for (int i = 0; i < n; ++i) {
      if ((split == "first_half" && i >= half) || (split == "second_half" && i < half)) {
        o.heldout.push_back(i);
      }
    }
    absl::StatusOr<CalibrationReport> r = Calibrate(spec, SolverOptions{}, recs, o);
    if (!r.ok()) {
      std::fprintf(stderr, "fade recovery (%s): %s\n", std::string(split).c_str(),
                   r.status().ToString().c_str());
      continue;
    }
    const ParamReport& p = r->fitted[0];
    std::printf("%.3f,%s,%zu,%.4f,%.2g,%d,%.2f,%.2f,%.2f,%.2f,%lld\n", fade,
                std::string(split).c_str(),
                o.heldout.size(), p.after, p.standard_error, p.at_bound ? 1 : 0,
                1e3 * r->train_before_m, 1e3 * r->train_after_m, 1e3 * r->heldout_before_m,
                1e3 * r->heldout_after_m, static_cast<long long>(r->simulations));
    std::fflush(stdout);
  }
}

// The cloth read from the tracks alone (TrackedStretches, ReadCloth): every stretch as a CSV
// row, then the reading of each source as a comment line. Returns whether the synthetic
// recordings' reading finds the reference table's cloth: its rolling resistance within 3 %
// and its sliding friction within 10 %.
bool ReadClothOf(const std::string& source, const std::vector<Recording>& recs, const TableSpec* truth) {
  for (const Recording& r : recs) {
    for (int b = 0; b < static_cast<int>(r.initial.balls.size()); ++b) {
      for (const TrackedStretch& s : TrackedStretches(r, b)) {
        std::printf("%s,%s,%s,%.3f,%.3f,%d,%.3f,%d,%.3f,%.3f,%.3f,%.4f,%.4f,%.5f,%.5f,%.5f,%s\n",
                    source.c_str(), r.name.c_str(), r.initial.balls[static_cast<size_t>(b)].id.c_str(),
                    s.t0_s, s.t1_s, s.points, std::min(s.roll_from_s, s.t1_s), s.slide_points,
                    s.v0_mps, s.v_roll_mps, s.v1_mps, s.slide_mps2, s.slide_se_mps2,
                    s.roll_decel_mps2, s.roll_lateral_mps2, s.roll_se_mps2,
                    s.slide_read ? (s.roll_read ? "both" : "slide") : (s.roll_read ? "roll" : "none"));
      }
    }
  }
  const ClothReading c = ReadCloth(recs);
  std::printf("# %s: rolling resistance %.5f (quartiles %.5f-%.5f, %d stretches), sliding friction "
              "%.4f (quartiles %.4f-%.4f, %d stretches), %zu shots\n",
              source.c_str(), c.mu_roll, c.mu_roll_q1, c.mu_roll_q3, c.rolling, c.mu_slide,
              c.mu_slide_q1, c.mu_slide_q3, c.sliding, recs.size());
  if (truth == nullptr) return true;
  const bool ok = std::abs(c.mu_roll / truth->params.mu_roll - 1.0) <= 0.03 &&
                  std::abs(c.mu_slide / truth->params.mu_slide - 1.0) <= 0.10;
  std::printf("# %s: the reference table's rolling resistance %.5f and sliding friction %.4f: %s\n",
              source.c_str(), truth->params.mu_roll, truth->params.mu_slide, ok ? "found" : "missed");
  return ok;
}

}  // namespace
}  // namespace sportsim::billiards

int main(int argc, char** argv) {
  using namespace sportsim::billiards;
  int shots = 24, recorded_shots = 0;
  bool synthetic = true;
  std::string path, preset = "carom", origin = "centre", write_set;
  double scale = 1.0, false_detections = 0.0;
  bool aimed = false, strike_recovery = false, predict_recovery = false, preset_given = false, read_cloth = false;
  bool pots = false;
  double fade_recovery = -1.0;
  std::array<double, 2> elevation = {0.0, 0.0};
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--strike-recovery")) {
      strike_recovery = true;
    } else if (!std::strcmp(argv[i], "--predict-recovery")) {
      predict_recovery = true;
    } else if (!std::strcmp(argv[i], "--pots")) {
      pots = true;
    } else if (!std::strcmp(argv[i], "--fade-recovery") && i + 1 < argc) {
      fade_recovery = std::atof(argv[++i]);
      if (!(fade_recovery >= 0.0 && fade_recovery <= 1.0)) {
        std::fprintf(stderr, "--fade-recovery: a slip in [0, 1] m/s\n");
        return 2;
      }
    } else if (!std::strcmp(argv[i], "--read-cloth")) {
      read_cloth = true;
    } else if (!std::strcmp(argv[i], "--quick")) {
      shots = 4;
    } else if (!std::strcmp(argv[i], "--shots") && i + 1 < argc) {
      shots = std::max(2, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--no-synthetic")) {
      synthetic = false;
    } else if (!std::strcmp(argv[i], "--recordings") && i + 1 < argc) {
      path = argv[++i];
    } else if (!std::strcmp(argv[i], "--preset") && i + 1 < argc) {
      preset = argv[++i];
      preset_given = true;
    } else if (!std::strcmp(argv[i], "--track-origin") && i + 1 < argc) {
      origin = argv[++i];
    } else if (!std::strcmp(argv[i], "--track-scale") && i + 1 < argc) {
      scale = std::atof(argv[++i]);
    } else if (!std::strcmp(argv[i], "--write-set") && i + 1 < argc) {
      write_set = argv[++i];
    } else if (!std::strcmp(argv[i], "--recorded-shots") && i + 1 < argc) {
      recorded_shots = std::max(2, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--predict") && i + 1 < argc) {
      const std::string w = argv[++i];
      if (w != "best-fit" && w != "central") {
        std::fprintf(stderr, "--predict: best-fit or central\n");
        return 2;
      }
      strike_bounds.central_rest = w == "central";
    } else if (!std::strcmp(argv[i], "--scoring")) {
      scoring_only = true;
    } else if (!std::strcmp(argv[i], "--intent") && i + 1 < argc) {
      const std::string_view intent = argv[++i];
      if (intent == "three-cushion") {
        strike_bounds.intent = sportsim::games::ThreeCushionIntent();
      } else if (intent == "pot") {
        strike_bounds.intent = sportsim::games::PotIntent();
      } else {
        std::fprintf(stderr, "--intent: three-cushion or pot\n");
        return 2;
      }
    } else if (!std::strcmp(argv[i], "--aimed")) {
      aimed = true;
    } else if (!std::strcmp(argv[i], "--fit-elevation")) {
      strike_bounds.fit_elevation = true;
    } else if (!std::strcmp(argv[i], "--cushion-on-read-cloth")) {
      cushion_on_read_cloth = true;
    } else if (!std::strcmp(argv[i], "--resample")) {
      strike_bounds.resample = true;
    } else if (!std::strcmp(argv[i], "--model") && i + 1 < argc) {
      const std::string m = argv[++i];
      if (m != "han" && m != "mathavan2010" && m != "stronge") {
        std::fprintf(stderr, "--model: han, mathavan2010 or stronge\n");
        return 2;
      }
      models.push_back(m);
    } else if (!std::strcmp(argv[i], "--ball-ball-model") && i + 1 < argc) {
      const std::string m = argv[++i];
      if (m != "alciatore" && m != "mathavan2014") {
        std::fprintf(stderr, "--ball-ball-model: alciatore or mathavan2014\n");
        return 2;
      }
      ball_ball_model =
          m == "mathavan2014" ? BallBallModel::kMathavan2014 : BallBallModel::kAlciatore;
    } else if (!std::strcmp(argv[i], "--elevation") && i + 1 < argc) {
      if (std::sscanf(argv[++i], "%lf:%lf", &elevation[0], &elevation[1]) != 2 ||
          !(elevation[0] >= 0.0 && elevation[1] >= elevation[0] && elevation[1] <= 30.0)) {
        std::fprintf(stderr, "--elevation: LO:HI degrees, 0 <= LO <= HI <= 30\n");
        return 2;
      }
    } else if (!std::strcmp(argv[i], "--false-detections") && i + 1 < argc) {
      false_detections = std::atof(argv[++i]);
      if (!(false_detections >= 0.0 && false_detections <= 0.5)) {
        std::fprintf(stderr, "--false-detections: a fraction in [0, 0.5]\n");
        return 2;
      }
    } else if (!std::strcmp(argv[i], "--huber") && i + 1 < argc) {
      huber_m = std::atof(argv[++i]);
      if (!(huber_m >= 0.0 && huber_m <= kMaxHuberScale)) {
        std::fprintf(stderr, "--huber: a scale in [0, %g] m\n", kMaxHuberScale);
        return 2;
      }
    } else {
      std::fprintf(stderr,
                   "usage: billiards_calibration_study [--quick] [--shots N] [--no-synthetic] "
                   "[--recordings PATH] [--preset P] [--track-origin centre|corner] "
                   "[--track-scale S] [--recorded-shots N] [--write-set FILE] "
                   "[--false-detections F] [--huber M] [--aimed] [--elevation LO:HI] "
                   "[--fit-elevation] [--resample] [--model M]... [--cushion-on-read-cloth] "
                   "[--strike-recovery] [--predict-recovery [--pots]] [--read-cloth] "
                   "[--fade-recovery U] "
                   "[--ball-ball-model alciatore|mathavan2014] [--scoring] "
                   "[--predict best-fit|central] [--intent three-cushion|pot]\n");
      return 2;
    }
  }
  if (fade_recovery >= 0.0) {
    FadeRecovery(shots, fade_recovery);
    return 0;
  }
  if (pots && !predict_recovery) {
    std::fprintf(stderr, "--pots: only with --predict-recovery\n");
    return 2;
  }
  if (predict_recovery && pots) {
    absl::StatusOr<TableSpec> spec = MakeTablePreset(preset_given ? preset : "pool-9ft");
    if (!spec.ok() || spec->pockets.empty()) {
      std::fprintf(stderr, "--pots: --preset must be a table with pockets\n");
      return 2;
    }
    PredictRecovery(SyntheticPots(shots, 61, *spec), *spec,
                    {sportsim::games::PotIntent(), "a pot intended", "a pot made"});
    return 0;
  }
  if (strike_recovery || predict_recovery) {
    absl::StatusOr<TableSpec> spec = MakeTablePreset(preset);
    if (preset_given && !spec.ok()) {
      std::fprintf(stderr, "--preset: %s\n", std::string(spec.status().message()).c_str());
      return 2;
    }
    if (strike_recovery) {
      StrikeRecovery(shots, aimed, preset_given ? *spec : ReferenceTable());
    } else {
      PredictRecovery(Synthetic(shots, 33, 0.0, aimed, elevation),
                      preset_given ? *spec : ReferenceTable(),
                      {sportsim::games::ThreeCushionIntent(), "the point intended",
                       "the point scored"});
    }
    return 0;
  }
  // The recorded shots at --recordings, on --preset's table, in the tracker's frame; exits
  // 2 for a bad flag, 1 for fewer than two usable shots.
  TableSpec recorded_spec;
  std::vector<Recording> recorded;
  if (!path.empty()) {
    absl::StatusOr<TableSpec> spec = MakeTablePreset(preset);
    if (!spec.ok()) {
      std::fprintf(stderr, "--preset: %s\n", std::string(spec.status().message()).c_str());
      return 2;
    }
    if (origin != "centre" && origin != "corner") {
      std::fprintf(stderr, "--track-origin: centre or corner\n");
      return 2;
    }
    const TrackFrame frame = TrackFrameOn(*spec, origin == "corner", scale);
    if (absl::Status s = ValidateTrackFrame(frame); !s.ok()) {
      std::fprintf(stderr, "--track-scale: %s\n", std::string(s.message()).c_str());
      return 2;
    }
    recorded = FromPath(path, *TableModel::Create(*spec), frame, recorded_shots);
    if (recorded.size() < 2) {
      std::fprintf(stderr, "%s: fewer than two usable recordings\n", path.c_str());
      return 1;
    }
    recorded_spec = *spec;
  }
  if (read_cloth) {
    std::printf("source,shot,ball,t0_s,t1_s,points,roll_from_s,slide_points,v0_mps,v_roll_mps,"
                "v1_mps,slide_mps2,slide_se_mps2,roll_decel_mps2,roll_lateral_mps2,roll_se_mps2,"
                "read\n");
    bool found = true;
    if (synthetic) {
      const TableSpec reference = ReferenceTable();
      found = ReadClothOf("synthetic", Synthetic(shots, 33, false_detections, aimed, elevation),
                          &reference);
    }
    if (!recorded.empty()) ReadClothOf("recorded", recorded, nullptr);
    return found ? 0 : 3;
  }
  std::printf("source,model,constants,fit_mm,fit_rails,predict_final_mm,predict_rails,cpu_us,shots\n");
  if (!write_set.empty() && !WriteShotSet(write_set, *MakeTablePreset("carom"), Synthetic(shots, 33))) {
    std::fprintf(stderr, "%s: cannot write\n", write_set.c_str());
    return 1;
  }
  if (synthetic) {
    const std::string source = std::string("synthetic") + (aimed ? "-aimed" : "") +
                               (scoring_only ? "-scoring" : "") +
                               (elevation[1] > 0.0 ? "-raised" : "") +
                               (strike_bounds.resample ? "-resample" : "") +
                               (strike_bounds.central_rest ? "-central" : "") +
                               (strike_bounds.intent ? "-intent" : "");
    if (false_detections > 0.0) {
      Study(source, *MakeTablePreset("carom"),
            Synthetic(shots, 33, false_detections, aimed, elevation),
            Synthetic(shots, 33, 0.0, aimed, elevation));
    } else {
      Study(source, *MakeTablePreset("carom"), Synthetic(shots, 33, 0.0, aimed, elevation));
    }
  }
  if (!recorded.empty()) {
    Study(std::string("recorded") + (strike_bounds.resample ? "-resample" : "") +
              (strike_bounds.central_rest ? "-central" : "") +
              (strike_bounds.intent ? "-intent" : ""),
          recorded_spec, recorded);
  }
  return 0;
}
