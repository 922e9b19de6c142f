#include "client/swing_svg.h"
#include "client/table_svg.h"

#include <algorithm>
#include <cmath>
#include <string_view>

#include "absl/strings/str_format.h"

namespace sportsim::cli {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDefaultArmM = 0.62;   // the chapter's R
constexpr double kDefaultClubM = 1.1;   // the chapter's L
constexpr double kMinSinBeta = 0.2;     // below this the lengths are not solved from a sample
constexpr double kBallRadiusM = 0.02135;

double Rad(double deg) { return deg * kPi / 180.0; }

struct Point {
  double x = 0, y = 0;
};

// u(a) = (sin a, -cos a): a rod hanging at angle a from straight down.
Point Along(Point from, double length, double angle_rad) {
  return {from.x + length * std::sin(angle_rad), from.y - length * std::cos(angle_rad)};
}

struct Lengths {
  double arm_m = kDefaultArmM;
  double club_m = kDefaultClubM;
  bool solved = false;
};

// c = R u(theta) + L u(phi) solved for R and L (Cramer; the determinant is sin(phi - theta) =
// sin beta), from the sample with the most cocked wrists.
Lengths FindLengths(const SwingDrawing& d) {
  Lengths out;
  double best = kMinSinBeta;
  for (const v1::SwingSample& s : d.samples) {
    const double theta = Rad(s.theta_deg()), phi = Rad(s.phi_deg());
    const double det = std::sin(phi - theta);
    const double cx = s.clubhead_x_m(), cy = s.clubhead_y_m();
    if (!(std::abs(det) > best) || (cx == 0 && cy == 0)) continue;
    const double r = (-cx * std::cos(phi) - cy * std::sin(phi)) / det;
    const double l = (cx * std::cos(theta) + cy * std::sin(theta)) / det;
    if (!(r > 0 && l > 0 && std::isfinite(r) && std::isfinite(l))) continue;
    best = std::abs(det);
    out.arm_m = r;
    out.club_m = l;
    out.solved = true;
  }
  if (d.arm_length_m) out.arm_m = *d.arm_length_m;
  if (d.club_length_m) out.club_m = *d.club_length_m;
  return out;
}

struct Pose {
  double t_s = 0;
  Point wrist, clubhead;
};

Pose PoseOf(const v1::SwingSample& s, const Lengths& len) {
  Pose p;
  p.t_s = s.t_s();
  p.wrist = Along({}, len.arm_m, Rad(s.theta_deg()));
  if (s.clubhead_x_m() != 0 || s.clubhead_y_m() != 0) {
    p.clubhead = {s.clubhead_x_m(), s.clubhead_y_m()};
  } else {
    p.clubhead = Along(p.wrist, len.club_m, Rad(s.phi_deg()));
  }
  return p;
}

}  // namespace

void AddSnapshot(const v1::SwingSnapshot& s, SwingDrawing* d) {
  if (s.heartbeat()) return;
  const bool swinging =
      s.phase() == v1::SWING_PHASE_SWINGING || s.phase() == v1::SWING_PHASE_FINISHED;
  if (s.has_state() && s.phase() == v1::SWING_PHASE_ADDRESS) d->address = s.state();
  if (swinging && s.swing_id() != d->swing_id) {
    d->swing_id = s.swing_id();
    d->samples.clear();
    d->impact.reset();
    if (d->address && (!s.has_state() || d->address->t_s() < s.state().t_s())) {
      d->samples.push_back(*d->address);
    }
  }
  if (swinging && s.has_state() &&
      (d->samples.empty() || s.state().t_s() > d->samples.back().t_s())) {
    d->samples.push_back(s.state());
  }
  for (const v1::SwingEvent& e : s.events()) {
    if (e.kind() == v1::SWING_EVENT_IMPACT && e.has_impact()) d->impact = e.impact();
  }
}

std::string SwingSvg(const SwingDrawing& d) {
  const Lengths len = FindLengths(d);
  std::vector<Pose> all;
  all.reserve(d.samples.size());
  for (const v1::SwingSample& s : d.samples) all.push_back(PoseOf(s, len));
  std::optional<Pose> impact;
  if (d.impact) {
    Pose p;
    p.t_s = d.impact->t_s();
    p.wrist = Along({}, len.arm_m, Rad(d.impact->theta_deg()));
    p.clubhead = Along(p.wrist, len.club_m, Rad(d.impact->phi_deg()));
    impact = p;
  }

  // Poses at regular swing times: a whole number of milliseconds apart, about d.poses of them,
  // and the last state.
  std::vector<const Pose*> strobe;
  double interval_s = 0;
  if (!all.empty()) {
    const double span = all.back().t_s - all.front().t_s;
    const int poses = std::max(2, d.poses);
    interval_s = span > 0 ? std::max(0.001, std::ceil(span / (poses - 1) * 1000.0) / 1000.0) : 0;
    double next_t = all.front().t_s;
    for (size_t i = 0; i < all.size(); ++i) {
      const bool last = i + 1 == all.size();
      if (all[i].t_s >= next_t - 1e-12 || last) {
        strobe.push_back(&all[i]);
        if (interval_s > 0) {
          while (next_t <= all[i].t_s + 1e-12) next_t += interval_s;
        }
      }
    }
  }

  // World box: the shoulder, every wrist and clubhead, the ball; padded.
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  const auto extend = [&](Point q) {
    x0 = std::min(x0, q.x);
    x1 = std::max(x1, q.x);
    y0 = std::min(y0, q.y);
    y1 = std::max(y1, q.y);
  };
  for (const Pose& p : all) {
    extend(p.wrist);
    extend(p.clubhead);
  }
  if (impact) {
    extend(impact->wrist);
    extend({impact->clubhead.x, impact->clubhead.y - 2 * kBallRadiusM});
  }
  if (all.empty() && !impact) {
    x0 = y0 = -(len.arm_m + len.club_m);
    x1 = y1 = len.arm_m + len.club_m;
  }
  const double pad = 0.12 * std::max({x1 - x0, y1 - y0, 0.5});
  x0 -= pad, x1 += pad, y0 -= pad, y1 += pad;
  const double width_px = 900.0;
  const double scale = width_px / (x1 - x0);
  const double height_px = (y1 - y0) * scale;
  const double top = 40.0;  // room for the title
  const auto X = [&](double x) { return (x - x0) * scale; };
  const auto Y = [&](double y) { return top + (y1 - y) * scale; };

  std::string svg = absl::StrFormat(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
      "viewBox=\"0 0 %.0f %.0f\" font-family=\"sans-serif\">\n",
      width_px, height_px + top + 76, width_px, height_px + top + 76);
  absl::StrAppendFormat(&svg, "<rect width=\"100%%\" height=\"100%%\" fill=\"#ffffff\"/>\n");
  absl::StrAppendFormat(&svg, "<text x=\"10\" y=\"26\" font-size=\"18\">%s</text>\n",
                        SvgEscape(d.title));
  // The ground under the ball at impact, and the ball.
  if (impact) {
    const double ground = impact->clubhead.y - kBallRadiusM;
    absl::StrAppendFormat(&svg,
                          "<line x1=\"0\" y1=\"%.1f\" x2=\"%.0f\" y2=\"%.1f\" stroke=\"#6b8e23\" "
                          "stroke-width=\"2\" stroke-dasharray=\"6 4\"/>\n",
                          Y(ground), width_px, Y(ground));
    absl::StrAppendFormat(&svg,
                          "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"#ffffff\" "
                          "stroke=\"#000000\"/>\n",
                          X(impact->clubhead.x - kBallRadiusM), Y(ground + kBallRadiusM),
                          std::max(kBallRadiusM * scale, 3.0));
  }
  // The clubhead's path through every state.
  if (all.size() >= 2) {
    std::string pts;
    for (const Pose& p : all) {
      absl::StrAppendFormat(&pts, "%.1f,%.1f ", X(p.clubhead.x), Y(p.clubhead.y));
    }
    absl::StrAppendFormat(&svg,
                          "<polyline points=\"%s\" fill=\"none\" stroke=\"#9a9a9a\" "
                          "stroke-width=\"1.5\"/>\n",
                          pts);
  }
  // The strobe: arm rods blue, club rods dark, fading in with time.
  const double t_first = all.empty() ? 0.0 : all.front().t_s;
  const double t_span = all.empty() ? 0.0 : all.back().t_s - t_first;
  for (const Pose* p : strobe) {
    const double f = t_span > 0 ? (p->t_s - t_first) / t_span : 1.0;
    const double opacity = 0.25 + 0.65 * f;
    absl::StrAppendFormat(&svg,
                          "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" "
                          "stroke=\"#1d4fb8\" stroke-width=\"3\" stroke-linecap=\"round\" "
                          "stroke-opacity=\"%.2f\"/>\n",
                          X(0), Y(0), X(p->wrist.x), Y(p->wrist.y), opacity);
    absl::StrAppendFormat(&svg,
                          "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" "
                          "stroke=\"#222222\" stroke-width=\"2\" stroke-linecap=\"round\" "
                          "stroke-opacity=\"%.2f\"/>\n",
                          X(p->wrist.x), Y(p->wrist.y), X(p->clubhead.x), Y(p->clubhead.y),
                          opacity);
  }
  // The impact pose in red, with its label.
  if (impact) {
    absl::StrAppendFormat(&svg,
                          "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" "
                          "stroke=\"#e01b1b\" stroke-width=\"4\" stroke-linecap=\"round\"/>\n",
                          X(0), Y(0), X(impact->wrist.x), Y(impact->wrist.y));
    absl::StrAppendFormat(&svg,
                          "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" "
                          "stroke=\"#e01b1b\" stroke-width=\"3\" stroke-linecap=\"round\"/>\n",
                          X(impact->wrist.x), Y(impact->wrist.y), X(impact->clubhead.x),
                          Y(impact->clubhead.y));
    absl::StrAppendFormat(&svg,
                          "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"5\" fill=\"#e01b1b\"/>\n",
                          X(impact->clubhead.x), Y(impact->clubhead.y));
    // The label runs away from the nearer edge, so that it stays in the picture.
    const bool right_half = X(impact->clubhead.x) > width_px / 2;
    absl::StrAppendFormat(&svg,
                          "<text x=\"%.1f\" y=\"%.1f\" font-size=\"14\" fill=\"#e01b1b\" "
                          "text-anchor=\"%s\">impact t = %.4f s: clubhead %.2f m/s (%.2f m/s "
                          "over the ground)</text>\n",
                          X(impact->clubhead.x) + (right_half ? -10 : 10),
                          Y(impact->clubhead.y) + 22, right_half ? "end" : "start",
                          d.impact->t_s(), d.impact->clubhead_speed_mps(),
                          d.impact->clubhead_speed_ground_mps());
  }
  // The shoulder.
  absl::StrAppendFormat(&svg, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"6\" fill=\"#000000\"/>\n",
                        X(0), Y(0));
  const std::string every =
      interval_s > 0 ? absl::StrFormat("poses every %.0f ms", interval_s * 1e3) : "one pose";
  // The caption on three short lines (one would run past the picture's 900 px).
  absl::StrAppendFormat(
      &svg,
      "<text x=\"10\" y=\"%.0f\" font-size=\"13\">shoulder frame, target to the left; %s of "
      "%d states</text>\n",
      height_px + top + 22, every, static_cast<int>(all.size()));
  absl::StrAppendFormat(
      &svg,
      "<text x=\"10\" y=\"%.0f\" font-size=\"13\">arm blue (R = %.3f m), club dark (L = %.3f "
      "m%s); grey: clubhead path; red: impact</text>\n",
      height_px + top + 40, len.arm_m, len.club_m, len.solved ? ", from the states" : "");
  absl::StrAppendFormat(&svg,
                        "<text x=\"10\" y=\"%.0f\" font-size=\"13\">&#8592; target (-x); scale "
                        "%.0f px/m</text>\n",
                        height_px + top + 58, scale);
  svg += "</svg>\n";
  return svg;
}

}  // namespace sportsim::cli
