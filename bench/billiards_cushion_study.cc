// Each cushion model against Mathavan, Jackson and Parkin's (2010) rebound curves, and what it
// costs per impact (docs/billiards.md, "The cushion models against Mathavan's rebound curves").
//
// The reference: Mathavan et al.'s model with the constants they fitted to their snooker
// cushion experiments (restitution 0.98, cushion friction 0.14, slate friction 0.212; the nose
// at 7R/5, a 52.5 mm ball), integrated with a fallback impulse step of 1/5000, over the range
// where they found it valid (normal speeds up to 2.5 m/s): approach angles 10-90 deg to the
// rail, speeds 0.5-2.5 m/s, stun or natural roll, no side spin or half the speed's worth (w_z R
// = +-V/2). What each model gives just after the impact is compared with it: the rebound angle
// to the rail (deg), the rebound speed (relative) and the spin (R w, over the approach speed;
// not fitted).
//
// Each of Han's and Stronge's models is scored with the snooker preset's constants (restitution
// 0.924, friction 0.2) and with its restitution and friction fitted to the curves (least squares
// of the angle in radians and the relative speed, on a grid refined twice); Stronge's model at
// the rubber's Poisson ratio 0.5 and at 0.3. Mathavan's own model at its default fallback step
// (1/500) shows what that step changes. CPU: the median over 5 passes of the calling thread's
// CPU per impact.
//
// CSV on stdout: model,constants,e,f,angle_rms_deg,angle_max_deg,speed_rms_pct,spin_rms_pct,
// cpu_ns
// Usage: billiards_cushion_study [--quick]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "sim/billiards/collision.h"
#include "sim/billiards/model.h"
#include "sim/core/cpu_clock.h"

namespace sportsim::billiards {
namespace {

struct Approach {
  Eigen::Vector3d v, w;
};

// Mathavan et al.'s geometry: the snooker ball, the nose at 7R/5, their slate friction.
TableSpec MathavanTable() {
  TableSpec s = *MakeTablePreset("snooker");
  s.params.cushion_height_m = 1.4 * s.params.ball_radius_m;
  s.params.mu_slide = 0.212;
  return s;
}

std::vector<Approach> Approaches(double radius) {
  std::vector<Approach> out;
  for (int deg = 10; deg <= 90; deg += 10) {
    const double a = deg * M_PI / 180.0;
    for (double speed : {0.5, 1.0, 1.5, 2.0, 2.5}) {
      const Eigen::Vector3d v = speed * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
      for (bool rolling : {false, true}) {
        for (double side : {-0.5, 0.0, 0.5}) {
          Eigen::Vector3d w = Eigen::Vector3d::Zero();
          if (rolling) w = Eigen::Vector3d::UnitZ().cross(v) / radius;
          w.z() = side * speed / radius;
          out.push_back({v, w});
        }
      }
    }
  }
  return out;
}

// The ball just after the impact into the cushion whose normal into the table is -y.
Ball Rebound(const TableModel& model, const Approach& a) {
  Ball b;
  b.r = Eigen::Vector3d(0.0, 0.0, model.radius());
  b.v = a.v;
  b.w = a.w;
  CollideCushion(model, Eigen::Vector2d(0.0, -1.0), &b);
  return b;
}

double AngleDeg(const Eigen::Vector3d& v) { return std::atan2(-v.y(), v.x()) * 180.0 / M_PI; }

struct Score {
  double angle_rms_deg = 0, angle_max_deg = 0, speed_rms = 0, spin_rms = 0, loss = 0;
};

Score Compare(const TableModel& model, const std::vector<Approach>& in,
              const std::vector<Ball>& ref) {
  Score s;
  for (size_t i = 0; i < in.size(); ++i) {
    const Ball b = Rebound(model, in[i]);
    const double da = AngleDeg(b.v) - AngleDeg(ref[i].v);
    const double ds = b.v.norm() / ref[i].v.norm() - 1.0;
    const double dw = model.radius() * (b.w - ref[i].w).norm() / in[i].v.norm();
    s.angle_rms_deg += da * da;
    s.angle_max_deg = std::max(s.angle_max_deg, std::abs(da));
    s.speed_rms += ds * ds;
    s.spin_rms += dw * dw;
  }
  const double n = static_cast<double>(in.size());
  s.loss = s.angle_rms_deg * (M_PI / 180.0) * (M_PI / 180.0) + s.speed_rms;
  s.angle_rms_deg = std::sqrt(s.angle_rms_deg / n);
  s.speed_rms = std::sqrt(s.speed_rms / n);
  s.spin_rms = std::sqrt(s.spin_rms / n);
  return s;
}

TableModel WithCushion(TableSpec spec, CushionModel cm, double e, double f, double poisson) {
  spec.params.cushion_model = cm;
  spec.params.e_cushion = e;
  spec.params.f_cushion = f;
  spec.params.cushion_poisson_ratio = poisson;
  return *TableModel::Create(std::move(spec));
}

double CpuNsPerImpact(const TableModel& model, const std::vector<Approach>& in) {
  std::vector<double> passes;
  for (int pass = 0; pass < 5; ++pass) {
    const double t0 = ThreadCpuSeconds();
    volatile double sink = 0.0;  // keeps the impacts from being optimised away
    for (int rep = 0; rep < 20; ++rep) {
      for (const Approach& a : in) sink = sink + Rebound(model, a).v.x();
    }
    passes.push_back((ThreadCpuSeconds() - t0) / (20.0 * in.size()));
  }
  std::sort(passes.begin(), passes.end());
  return 1e9 * passes[passes.size() / 2];
}

void Report(const std::string& model_name, const std::string& constants, const TableModel& model,
            const std::vector<Approach>& in, const std::vector<Ball>& ref) {
  const Score s = Compare(model, in, ref);
  const PhysicsParams& p = model.params();
  const bool mathavan = p.cushion_model == CushionModel::kMathavan2010;
  std::printf("%s,%s,%.3f,%.3f,%.2f,%.2f,%.1f,%.1f,%.0f\n", model_name.c_str(),
              constants.c_str(), mathavan ? p.e_cushion_mathavan : p.e_cushion,
              mathavan ? p.f_cushion_mathavan : p.f_cushion, s.angle_rms_deg, s.angle_max_deg,
              100.0 * s.speed_rms, 100.0 * s.spin_rms, CpuNsPerImpact(model, in));
  std::fflush(stdout);
}

// Restitution and friction by least squares on a grid over [0.5, 1] x [0, 0.4], refined twice
// around the best point.
TableModel Fit(const TableSpec& spec, CushionModel cm, double poisson, bool quick,
               const std::vector<Approach>& in, const std::vector<Ball>& ref) {
  double e_lo = 0.5, e_hi = 1.0, f_lo = 0.0, f_hi = 0.4;
  double best_e = 0.85, best_f = 0.2;
  const int n = quick ? 6 : 26;
  for (int level = 0; level < 3; ++level) {
    double best = INFINITY;
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n; ++j) {
        const double e = e_lo + (e_hi - e_lo) * i / n, f = f_lo + (f_hi - f_lo) * j / n;
        const double loss = Compare(WithCushion(spec, cm, e, f, poisson), in, ref).loss;
        if (loss < best) {
          best = loss;
          best_e = e;
          best_f = f;
        }
      }
    }
    const double de = 2.0 * (e_hi - e_lo) / n, df = 2.0 * (f_hi - f_lo) / n;
    e_lo = std::max(0.0, best_e - de);
    e_hi = std::min(1.0, best_e + de);
    f_lo = std::max(0.0, best_f - df);
    f_hi = std::min(2.0, best_f + df);
  }
  return WithCushion(spec, cm, best_e, best_f, poisson);
}

}  // namespace
}  // namespace sportsim::billiards

int main(int argc, char** argv) {
  using namespace sportsim::billiards;
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) {
      quick = true;
    } else {
      std::fprintf(stderr, "usage: billiards_cushion_study [--quick]\n");
      return 2;
    }
  }
  const TableSpec table = MathavanTable();
  TableSpec reference = table;
  reference.params.cushion_model = CushionModel::kMathavan2010;
  reference.params.e_cushion_mathavan = 0.98;
  reference.params.f_cushion_mathavan = 0.14;
  reference.params.cushion_impulse_steps = 5000;
  const TableModel truth = *TableModel::Create(reference);
  const std::vector<Approach> in = Approaches(truth.radius());
  std::vector<Ball> ref;
  for (const Approach& a : in) ref.push_back(Rebound(truth, a));

  std::printf("model,constants,e,f,angle_rms_deg,angle_max_deg,speed_rms_pct,spin_rms_pct,cpu_ns\n");
  TableSpec mathavan500 = reference;
  mathavan500.params.cushion_impulse_steps = 500;
  Report("mathavan2010", "500 steps", *TableModel::Create(mathavan500), in, ref);
  const double e0 = table.params.e_cushion, f0 = table.params.f_cushion;
  Report("han", "preset", WithCushion(table, CushionModel::kHan, e0, f0, 0.5), in, ref);
  Report("han", "fitted", Fit(table, CushionModel::kHan, 0.5, quick, in, ref), in, ref);
  for (double poisson : {0.5, 0.3}) {
    const std::string nu = poisson == 0.5 ? " nu 0.5" : " nu 0.3";
    Report("stronge", "preset" + nu,
           WithCushion(table, CushionModel::kStrongeCompliant, e0, f0, poisson), in, ref);
    Report("stronge", "fitted" + nu,
           Fit(table, CushionModel::kStrongeCompliant, poisson, quick, in, ref), in, ref);
  }
  return 0;
}
