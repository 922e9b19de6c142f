// How close each cushion model comes to recorded shots, before and after calibration, and what
// it costs per shot (docs/billiards.md, "Calibration from recorded shots").
//
// Recordings:
//  - synthetic (always): three-cushion shots on a reference table that none of the models is:
//    the carom geometry with Mathavan et al.'s measured cushion (restitution 0.98, friction
//    0.14, their model) and heated-cloth constants (rolling resistance 0.006, sliding 0.2,
//    spin-down 10 rad/s^2), random layouts and strikes, tracked at 50 Hz with 1 mm Gaussian
//    noise like a camera tracker. What a model loses here is model error plus noise.
//  - --recordings DIR: every *.csv track file in DIR (sim/billiards/track_file.h: t, ball, x,
//    y, as `shot simulate --format csv` writes), on the preset --preset (default carom). Obtain
//    recorded shots from a tracker of your own table or a public set (docs/billiards.md);
//    nothing third-party is committed.
//
// For each model (han, mathavan2010, stronge), with the preset's constants, with its rolling resistance
// alone fitted, and calibrated (its cloth and cushion constants fitted), each fit on the first
// half of the shots, scored on the second half (held out):
//  - fit: the strike fitted to the whole shot, the median over shots of the mean distance
//    between tracked and simulated centres (every ball, every frame);
//  - predict: the strike fitted on the first 0.4 s only, the median distance of the struck
//    ball's final position from where it was last tracked, and the share of shots whose struck
//    ball meets the cushions in the same order (the rails, first three hits) as the best fit;
//  - cpu: the median thread CPU of one shot's simulation (its strike as fitted).
// CSV on stdout: source,model,constants,fit_mm,predict_final_mm,predict_rails,cpu_us,shots
//
// Usage: billiards_calibration_study [--quick] [--shots N] [--recordings DIR] [--preset P]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "sim/billiards/calibrate.h"
#include "sim/billiards/shot.h"
#include "sim/billiards/track_file.h"
#include "sim/core/cpu_clock.h"

namespace sportsim::billiards {
namespace {

constexpr double kPredictWindow = 0.4;  // s

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
  return s;
}

std::vector<Recording> Synthetic(int n, uint64_t seed) {
  const TableModel truth = *TableModel::Create(ReferenceTable());
  const double l = truth.spec().length_m, w = truth.spec().width_m, d = 2 * truth.radius();
  std::mt19937_64 rng(seed);
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
    c.phi_rad = std::atan2(to.y(), to.x()) + (u(rng) - 0.5) * 0.5;
    c.a = 0.6 * (u(rng) - 0.5);
    c.b = 0.6 * (u(rng) - 0.5);
    absl::StatusOr<Recording> r = SyntheticRecording(
        truth, SolverOptions{}, s, 0, c,
        SyntheticOptions{.rate_hz = 50, .noise_m = 1e-3, .seed = seed + out.size()});
    if (!r.ok()) continue;
    r->name = "synthetic" + std::to_string(out.size());
    out.push_back(*std::move(r));
  }
  return out;
}

std::vector<Recording> FromDirectory(const std::string& dir, const TableModel& model) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() == ".csv") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<Recording> out;
  for (const auto& path : files) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    absl::StatusOr<TrackFile> f = ParseTrackCsv(text.str());
    if (!f.ok() || f->cue < 0) {
      std::fprintf(stderr, "%s: skipped: %s\n", path.c_str(),
                   f.ok() ? "no ball moves" : std::string(f.status().message()).c_str());
      continue;
    }
    Recording r;
    r.name = path.filename().string();
    for (size_t b = 0; b < f->balls.size(); ++b) {
      r.initial.balls.push_back(Ball{.id = f->balls[b],
                                     .r = Eigen::Vector3d(f->spots[b].x(), f->spots[b].y(), model.radius())});
    }
    r.cue = f->cue;
    r.track = f->points;
    if (absl::Status s = ValidateRecording(model, r); !s.ok()) {
      std::fprintf(stderr, "%s: skipped: %s\n", path.c_str(), std::string(s.message()).c_str());
      continue;
    }
    out.push_back(std::move(r));
  }
  return out;
}

// The cushions met by the struck ball, in order (the first three), and where it rests.
struct Outcome {
  std::vector<int> rails;
  Eigen::Vector2d rest = Eigen::Vector2d::Zero();
  double cpu_s = 0.0;
};
Outcome Play(const TableModel& m, const Recording& rec, const CueStrike& strike) {
  Outcome o;
  TableState s = rec.initial;
  if (!ApplyStrike(m, 0, strike, rec.cue, &s).ok()) return o;
  const double c0 = ThreadCpuSeconds();
  absl::StatusOr<ShotResult> r = SimulateShot(m, SolverOptions{}, s, ShotOptions{});
  o.cpu_s = ThreadCpuSeconds() - c0;
  if (!r.ok()) return o;
  for (const Event& e : r->events) {
    if (e.kind == EventKind::kBallCushion && e.a == rec.cue && o.rails.size() < 3) o.rails.push_back(e.other);
  }
  o.rest = r->final_state.balls[static_cast<size_t>(rec.cue)].r.head<2>();
  return o;
}

Eigen::Vector2d LastTracked(const Recording& rec) {
  for (auto it = rec.track.rbegin(); it != rec.track.rend(); ++it) {
    if (it->ball == rec.cue) return it->xy;
  }
  return rec.initial.balls[static_cast<size_t>(rec.cue)].r.head<2>();
}

void Score(const std::string& source, const std::string& model_name, const std::string& constants,
           const TableSpec& spec, const std::vector<Recording>& test) {
  const TableModel m = *TableModel::Create(spec);
  std::vector<double> fit, final_err, cpu;
  int same_rails = 0, n = 0;
  for (const Recording& rec : test) {
    absl::StatusOr<StrikeFit> whole = FitStrike(m, SolverOptions{}, rec);
    absl::StatusOr<StrikeFit> early = FitStrike(m, SolverOptions{}, rec, StrikeBounds{}, kPredictWindow);
    if (!whole.ok() || !early.ok()) continue;
    ++n;
    fit.push_back(whole->error.mean_m);
    const Outcome best = Play(m, rec, whole->strike);
    const Outcome predicted = Play(m, rec, early->strike);
    final_err.push_back((predicted.rest - LastTracked(rec)).norm());
    same_rails += predicted.rails == best.rails;
    cpu.push_back(best.cpu_s);
  }
  std::printf("%s,%s,%s,%.1f,%.0f,%.2f,%.0f,%d\n", source.c_str(), model_name.c_str(),
              constants.c_str(), 1e3 * Median(fit), 1e3 * Median(final_err),
              n > 0 ? static_cast<double>(same_rails) / n : 0.0, 1e6 * Median(cpu), n);
  std::fflush(stdout);
}

void Study(const std::string& source, const TableSpec& preset, const std::vector<Recording>& all) {
  const size_t half = all.size() / 2;
  const std::vector<Recording> train(all.begin(), all.begin() + static_cast<long>(half));
  const std::vector<Recording> test(all.begin() + static_cast<long>(half), all.end());
  for (CushionModel cm : {CushionModel::kHan, CushionModel::kMathavan2010,
                          CushionModel::kStrongeCompliant}) {
    const std::string name = cm == CushionModel::kHan            ? "han"
                             : cm == CushionModel::kMathavan2010 ? "mathavan2010"
                                                                 : "stronge";
    TableSpec spec = preset;
    spec.params.cushion_model = cm;
    Score(source, name, "preset", spec, test);
    // The rolling resistance alone: what one constant from the right cloth is worth.
    CalibrationOptions roll;
    roll.params.push_back({.name = "mu_roll"});
    if (absl::StatusOr<CalibrationReport> r = Calibrate(spec, SolverOptions{}, train, roll); r.ok()) {
      TableSpec s = spec;
      s.params = r->params;
      Score(source, name, "rolling_only", s, test);
    }
    CalibrationOptions o;
    for (const char* p : {"mu_slide", "mu_roll", "spin_decel_rps2"}) o.params.push_back({.name = p});
    if (cm != CushionModel::kMathavan2010) {
      o.params.push_back({.name = "e_cushion"});
      o.params.push_back({.name = "f_cushion"});
    } else {
      o.params.push_back({.name = "e_cushion_mathavan"});
      o.params.push_back({.name = "f_cushion_mathavan"});
    }
    absl::StatusOr<CalibrationReport> r = Calibrate(spec, SolverOptions{}, train, o);
    if (!r.ok()) {
      std::fprintf(stderr, "%s %s: calibration failed: %s\n", source.c_str(), name.c_str(),
                   r.status().ToString().c_str());
      continue;
    }
    for (const ParamReport& p : r->fitted) {
      std::fprintf(stderr, "%s %s: %s %g -> %g\n", source.c_str(), name.c_str(), p.name.c_str(),
                   p.before, p.after);
    }
    spec.params = r->params;
    Score(source, name, "calibrated", spec, test);
  }
}

}  // namespace
}  // namespace sportsim::billiards

int main(int argc, char** argv) {
  using namespace sportsim::billiards;
  int shots = 24;
  std::string dir, preset = "carom";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) {
      shots = 4;
    } else if (!std::strcmp(argv[i], "--shots") && i + 1 < argc) {
      shots = std::max(2, std::atoi(argv[++i]));
    } else if (!std::strcmp(argv[i], "--recordings") && i + 1 < argc) {
      dir = argv[++i];
    } else if (!std::strcmp(argv[i], "--preset") && i + 1 < argc) {
      preset = argv[++i];
    } else {
      std::fprintf(stderr,
                   "usage: billiards_calibration_study [--quick] [--shots N] [--recordings DIR] "
                   "[--preset P]\n");
      return 2;
    }
  }
  std::printf("source,model,constants,fit_mm,predict_final_mm,predict_rails,cpu_us,shots\n");
  Study("synthetic", *MakeTablePreset("carom"), Synthetic(shots, 33));
  if (!dir.empty()) {
    absl::StatusOr<TableSpec> spec = MakeTablePreset(preset);
    if (!spec.ok()) {
      std::fprintf(stderr, "--preset: %s\n", std::string(spec.status().message()).c_str());
      return 2;
    }
    const std::vector<Recording> recs = FromDirectory(dir, *TableModel::Create(*spec));
    if (recs.size() < 2) {
      std::fprintf(stderr, "%s: fewer than two usable recordings\n", dir.c_str());
      return 1;
    }
    Study("recorded", *spec, recs);
  }
  return 0;
}
