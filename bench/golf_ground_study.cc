// The golf ball's ground phase: accuracy against cost of its two integrators (rk4 at a fixed
// step, dp45 error-controlled), on the practice plane and on sportsim_links' terrain.
//
// Three seeded sets of shots, each run with every setting and compared with a converged
// reference (rk4 at 50 us, cross-checked against dp45 at 1e-10 m):
//   plane_putts:   putts toward the hole on the practice plane, Stimp 8-14, slopes up to 80 % of
//                  what the green holds, 0.5-4.5 m/s;
//   course_putts:  putts on sportsim_links' three greens (one two-tiered) toward the pin, from
//                  2-15 m, hard enough to reach it;
//   course_landings: balls landing on the course's first two holes' fairways and greens at
//                  10-30 m/s, 25-55 deg, with backspin: bounces, slopes, surface changes.
// For each setting: the median and largest distance between its rest and the reference's
// (shots whose outcome differs, holed against not, are counted apart), steps, and the median
// CPU per shot over repeats.
//
// Output: CSV (scenario,integrator,setting,shots,differ,median_m,max_m,steps,cpu_us), or with
// --markdown the page docs/golf-ground-accuracy.md. --quick: a few shots, for the smoke test.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "sim/core/cpu_clock.h"
#include "sim/golf/course.h"
#include "sim/golf/ground.h"

namespace g = sportsim::golf;
using sportsim::ode::Integrator;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

struct Shot {
  bool on_course = false;
  int hole = 1;
  g::Surface green;       // plane shots
  g::GroundPlane plane;   // plane shots
  g::GroundStart start;
};

struct Setting {
  Integrator integrator;
  double value;  // rk4: dt_s; dp45: tolerance_m
};

g::GroundOptions Options(const Setting& s) {
  g::GroundOptions o;
  o.sample_interval_s = 0;
  o.integrator = s.integrator;
  if (s.integrator == Integrator::kDp45) {
    o.tolerance_m = s.value;
    o.dt_s = 0.05;
  } else {
    o.dt_s = s.value;
  }
  return o;
}

absl::StatusOr<g::GroundResult> Run(const Shot& shot, const Setting& s) {
  const g::GroundOptions o = Options(s);
  if (shot.on_course) {
    return g::SimulateGroundOnCourse(g::BallSpec{}, **g::BuiltinCourse("sportsim_links"),
                                     shot.hole, g::Hole{}, shot.start, o);
  }
  return g::SimulateGround(g::BallSpec{}, shot.green, shot.plane, g::Hole{}, shot.start, o);
}

std::vector<Shot> PlanePutts(int n) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Shot> out;
  while (static_cast<int>(out.size()) < n) {
    Shot s;
    s.green = *g::GreenOfStimp(8 + 6 * u(rng));
    s.plane = {.slope_pct = 80 * s.green.rolling_resistance * u(rng),
               .slope_toward_deg = 360 * u(rng)};
    const double d = 1 + 9 * u(rng), a = 360 * u(rng) * kDeg;
    const double x = d * std::cos(a), y = d * std::sin(a);
    s.start = g::PuttStart(x, y, 0.5 + 4 * u(rng), std::atan2(-y, -x) / kDeg + 10 * (u(rng) - 0.5));
    out.push_back(s);
  }
  return out;
}

std::vector<Shot> CoursePutts(int n) {
  const g::Course& c = **g::BuiltinCourse("sportsim_links");
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Shot> out;
  while (static_cast<int>(out.size()) < n) {
    Shot s;
    s.on_course = true;
    s.hole = 1 + static_cast<int>(out.size()) % 3;
    const Eigen::Vector2d pin = *c.holes[static_cast<size_t>(s.hole - 1)].pin_m;
    const double d = 2 + 13 * u(rng), a = 360 * u(rng) * kDeg;
    const double x = pin.x() + d * std::cos(a), y = pin.y() + d * std::sin(a);
    if (c.SurfaceAt(x, y).terrain != g::Terrain::kGreen) continue;
    // Enough to roll about the distance on the flat at its green's speed, give or take.
    const double rho = c.Constants(c.SurfaceAt(x, y)).rolling_resistance;
    const double v = std::sqrt(2 * (5.0 / 7.0) * rho * 9.80665 * d) * 1.4 * (0.8 + 0.6 * u(rng));
    s.start = g::PuttStart(x, y, std::min(v, 14.0), std::atan2(pin.y() - y, pin.x() - x) / kDeg +
                                                        6 * (u(rng) - 0.5));
    out.push_back(s);
  }
  return out;
}

std::vector<Shot> CourseLandings(int n) {
  const g::Course& c = **g::BuiltinCourse("sportsim_links");
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Shot> out;
  while (static_cast<int>(out.size()) < n) {
    Shot s;
    s.on_course = true;
    s.hole = 1 + static_cast<int>(out.size()) % 2;
    // Hole 1's landing area and green, or hole 2's green and its surrounds.
    const double x = s.hole == 1 ? 180 + 200 * u(rng) : 370 + 50 * u(rng);
    const double y = s.hole == 1 ? -25 + 50 * u(rng) : 200 + 50 * u(rng);
    const g::Terrain t = c.SurfaceAt(x, y).terrain;
    if (t == g::Terrain::kOutOfBounds || g::IsPenaltyArea(t)) continue;
    const double v = 10 + 20 * u(rng), d = (25 + 30 * u(rng)) * kDeg;
    const double heading = (s.hole == 1 ? 0 : 90) + 10 * (u(rng) - 0.5);
    const Eigen::Vector3d dir(std::cos(heading * kDeg), std::sin(heading * kDeg), 0);
    s.start.kind = g::GroundStartKind::kLanding;
    s.start.position_m = Eigen::Vector3d(x, y, 0);
    s.start.velocity_mps = v * (std::cos(d) * dir - std::sin(d) * Eigen::Vector3d::UnitZ());
    s.start.spin_radps = Eigen::Vector3d(-dir.y(), dir.x(), 0) * (100 + 600 * u(rng));
    out.push_back(s);
  }
  return out;
}

struct Row {
  std::string scenario, integrator, setting;
  int shots = 0, differ = 0;
  double median_m = 0, max_m = 0, steps = 0, cpu_us = 0;
};

Row Study(const std::string& scenario, const std::vector<Shot>& shots,
          const std::vector<g::GroundResult>& ref, const Setting& s, int repeats) {
  Row row{scenario, std::string(sportsim::ode::IntegratorName(s.integrator)),
          absl::StrFormat("%g", s.value)};
  std::vector<double> errors;
  std::vector<double> cpu;
  for (int r = 0; r < repeats; ++r) {
    const double t0 = sportsim::ThreadCpuSeconds();
    int64_t steps = 0;
    errors.clear();
    row.differ = 0;
    for (size_t i = 0; i < shots.size(); ++i) {
      const absl::StatusOr<g::GroundResult> res = Run(shots[i], s);
      if (!res.ok()) {
        ++row.differ;
        continue;
      }
      steps += res->steps + res->rejected_steps;
      if (res->holed != ref[i].holed || res->penalty_area != ref[i].penalty_area ||
          res->out_of_bounds != ref[i].out_of_bounds) {
        ++row.differ;
        continue;
      }
      errors.push_back((res->rest_m - ref[i].rest_m).norm());
    }
    cpu.push_back((sportsim::ThreadCpuSeconds() - t0) / static_cast<double>(shots.size()) * 1e6);
    row.steps = static_cast<double>(steps) / static_cast<double>(shots.size());
  }
  row.shots = static_cast<int>(shots.size());
  std::sort(errors.begin(), errors.end());
  std::sort(cpu.begin(), cpu.end());
  if (!errors.empty()) {
    row.median_m = errors[errors.size() / 2];
    row.max_m = errors.back();
  }
  row.cpu_us = cpu[cpu.size() / 2];
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, markdown = false;
  for (int i = 1; i < argc; ++i) {
    quick |= std::strcmp(argv[i], "--quick") == 0;
    markdown |= std::strcmp(argv[i], "--markdown") == 0;
  }
  const int n = quick ? 4 : 100;
  const int repeats = quick ? 1 : 3;
  const Setting reference{Integrator::kRk4, quick ? 1e-4 : 5e-5};
  const Setting check{Integrator::kDp45, 1e-10};
  const std::vector<Setting> settings = {
      {Integrator::kRk4, 0.01},    {Integrator::kRk4, 0.005},  {Integrator::kRk4, 0.002},
      {Integrator::kRk4, 0.001},   {Integrator::kRk4, 0.0005}, {Integrator::kRk4, 0.0002},
      {Integrator::kDp45, 1e-3},   {Integrator::kDp45, 1e-4},  {Integrator::kDp45, 1e-5},
      {Integrator::kDp45, 1e-6},   {Integrator::kDp45, 1e-7},  {Integrator::kDp45, 1e-8},
  };
  const std::pair<std::string, std::vector<Shot>> scenarios[] = {
      {"plane_putts", PlanePutts(n)},
      {"course_putts", CoursePutts(n)},
      {"course_landings", CourseLandings(n)},
  };
  std::vector<Row> rows;
  std::vector<std::string> checks;
  for (const auto& [name, shots] : scenarios) {
    std::vector<g::GroundResult> ref;
    for (const Shot& s : shots) {
      absl::StatusOr<g::GroundResult> r = Run(s, reference);
      if (!r.ok()) {
        std::fprintf(stderr, "reference failed: %s\n", std::string(r.status().message()).c_str());
        return 1;
      }
      ref.push_back(*r);
    }
    const Row agree = Study(name, shots, ref, check, 1);
    checks.push_back(absl::StrFormat("%s: dp45 at 1e-10 m rests at most %.2g m from it (median "
                                     "%.2g m), %d of %d outcomes differing",
                                     name, agree.max_m, agree.median_m, agree.differ, agree.shots));
    std::fprintf(stderr, "%s: reference done\n", name.c_str());
    for (const Setting& s : settings) {
      rows.push_back(Study(name, shots, ref, s, repeats));
      std::fprintf(stderr, "  %s %g: %.1f us\n", rows.back().integrator.c_str(), s.value,
                   rows.back().cpu_us);
    }
  }
  if (!markdown) {
    std::printf("scenario,integrator,setting,shots,differ,median_m,max_m,steps,cpu_us\n");
    for (const Row& r : rows) {
      std::printf("%s,%s,%s,%d,%d,%.3g,%.3g,%.0f,%.1f\n", r.scenario.c_str(),
                  r.integrator.c_str(), r.setting.c_str(), r.shots, r.differ, r.median_m,
                  r.max_m, r.steps, r.cpu_us);
    }
    for (const std::string& c : checks) std::fprintf(stderr, "%s\n", c.c_str());
    return 0;
  }
  std::printf(
      "# The ground phase: accuracy against cost\n\n"
      "Generated by `build/bin/golf_ground_study --markdown > docs/golf-ground-accuracy.md` "
      "(bench/golf_ground_study.cc; the target `golf_ground_accuracy_doc` does it). Release "
      "build, AMD EPYC, 2 cores, Debian 12.\n\n"
      "## The question\n"
      "Which integrator and setting should the ground phase use? Its skid and roll are closed "
      "form on the flat (one piece each) and integrated elsewhere: by RK4 at a fixed step "
      "(`dt_s`, the default 5 ms) or by Dormand-Prince 5(4) controlled by a tolerance "
      "(`tolerance_m`: a step's position error, and its velocity and slip errors times 0.1 s, at "
      "most this; its largest step 50 ms here). Both locate the ends of the skid and the roll "
      "(the steps halve toward them to a last piece of 0.1 ms, taken at constant "
      "acceleration) and every surface change (bisection to 1 ns).\n\n"
      "## The shots\n"
      "- `plane_putts`: %d putts toward the hole on the practice plane, Stimp 8-14, slopes up to "
      "80 %% of what the green holds, 0.5-4.5 m/s, from 1-10 m;\n"
      "- `course_putts`: %d putts on sportsim_links' three greens (the second two-tiered) toward "
      "the pin from 2-15 m;\n"
      "- `course_landings`: %d balls landing on the first two holes at 10-30 m/s, 25-55 deg, with "
      "backspin: bounces, the terrain's slopes, surface changes, water and bunkers.\n\n"
      "## The converged reference\n"
      "RK4 at 50 us. Cross-checked:\n\n",
      n, n, n);
  for (const std::string& c : checks) std::printf("- %s\n", c.c_str());
  std::printf(
      "\n## Results\n"
      "Rest error: the distance between a setting's rest and the reference's, median and largest "
      "over the shots whose outcome (holed, in water, out of bounds) is the reference's; "
      "`differ` counts the others. Steps: accepted and rejected, per shot. CPU: the median of %d "
      "runs of the whole set, per shot (thread CPU time).\n\n"
      "| shots | integrator | dt_s or tolerance_m | differ | median rest error (m) | largest "
      "(m) | steps | CPU per shot (us) |\n|---|---|---:|---:|---:|---:|---:|---:|\n",
      repeats);
  for (const Row& r : rows) {
    // The defaults: RK4 at 5 ms on the plane (GroundOptions), dp45 at 1e-8 m on a course
    // (CourseGroundOptions).
    const bool plane = r.scenario == "plane_putts";
    const bool is_default = (plane && r.integrator == "rk4" && r.setting == "0.005") ||
                            (!plane && r.integrator == "dp45" && r.setting == "1e-08");
    std::printf("| %s | %s | %s%s | %d | %.2g | %.2g | %.0f | %.1f |\n", r.scenario.c_str(),
                r.integrator.c_str(), r.setting.c_str(), is_default ? " (default)" : "", r.differ,
                r.median_m, r.max_m, r.steps, r.cpu_us);
  }
  std::printf(
      "\n## Reading it\n"
      "- On the plane every setting rests within a few hundredths of a millimetre of the "
      "reference: the skid and the roll are smooth, and their ends are located, so RK4's step "
      "hardly matters. The largest error, about 24 um, is one putt that every setting shares "
      "with dp45 at 1e-10 m, so it is the reference's own. RK4 at 5 ms stays the plane's default, "
      "and dp45 is about three times cheaper for the same rest.\n"
      "- On the course the ground bends under the ball: its curvature enters the normal force, "
      "and a ball crossing a cell edge meets a jump in it. RK4's largest error falls with its "
      "step, about as its square down to 2 ms and more slowly below, but at 5 ms it is still "
      "several millimetres on landings. dp45 puts its steps where the ground bends. At 1e-8 m "
      "it rests within a tenth of a millimetre on landings, at about half of RK4's 5 ms cost, "
      "and within a millimetre on putts. The putts' largest errors, for every setting, come from "
      "one or two putts that die on the tier's face near the steepest slope the green holds: "
      "there even dp45 at 1e-10 m and the reference differ by a third of a millimetre. So "
      "courses default to dp45 at 1e-8 m (`CourseGroundOptions`), and the defaults rest within "
      "1 mm of the reference on every set.\n"
      "- Looser tolerances than 1e-6 m buy nothing: the largest step (50 ms) and the located "
      "ends bound the step count.\n");
  return 0;
}
