#include "client/table_svg.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string_view>

#include "absl/strings/str_format.h"

namespace sportsim::cli {
namespace {

// Ball colours: the usual pool set (solids 1-7 and stripes 9-15 share colours), snooker and
// carom names, anything else grey.
std::string BallColour(const std::string& id) {
  static const std::map<std::string, std::string> named = {
      {"cue", "#f8f8f0"}, {"yellow", "#f2d21b"}, {"red", "#d2232a"},   {"green", "#1f8a3a"},
      {"brown", "#7b4a20"}, {"blue", "#1d4fb8"},  {"pink", "#f29ab8"},  {"black", "#111111"},
      {"8", "#111111"}};
  if (auto it = named.find(id); it != named.end()) return it->second;
  if (id.rfind("red", 0) == 0) return "#d2232a";
  static const char* pool[] = {"#f2c81b", "#1d4fb8", "#d2232a", "#6a2c91",
                               "#f47b20", "#1f8a3a", "#7b1f1f"};
  int n = 0;
  if (std::all_of(id.begin(), id.end(), [](char c) { return c >= '0' && c <= '9'; }) &&
      !id.empty() && id.size() < 4) {
    n = std::stoi(id);
  }
  if (n >= 1 && n <= 7) return pool[n - 1];
  if (n >= 9 && n <= 15) return pool[n - 9];
  return "#9a9a9a";
}

bool Striped(const std::string& id) {
  if (id.empty() || id.size() > 2) return false;
  if (!std::all_of(id.begin(), id.end(), [](char c) { return c >= '0' && c <= '9'; })) return false;
  const int n = std::stoi(id);
  return n >= 9 && n <= 15;
}

// Position of a path at time t (linear between samples).
bool PathAt(const BallPath& p, double t, double* x, double* y) {
  if (p.t_s.empty() || t < p.t_s.front() - 1e-9) return false;
  const auto it = std::upper_bound(p.t_s.begin(), p.t_s.end(), t);
  if (it == p.t_s.end()) {
    *x = p.x_m.back();
    *y = p.y_m.back();
    return true;
  }
  const size_t i = static_cast<size_t>(it - p.t_s.begin());
  if (i == 0) {
    *x = p.x_m[0];
    *y = p.y_m[0];
    return true;
  }
  const double f = (t - p.t_s[i - 1]) / (p.t_s[i] - p.t_s[i - 1]);
  *x = p.x_m[i - 1] + f * (p.x_m[i] - p.x_m[i - 1]);
  *y = p.y_m[i - 1] + f * (p.y_m[i] - p.y_m[i - 1]);
  return true;
}

}  // namespace

std::string SvgEscape(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}

std::vector<BallPath> PathsFromShot(const v1::SimulateShotResponse& shot) {
  std::vector<BallPath> paths(shot.balls_size());
  for (int i = 0; i < shot.balls_size(); ++i) paths[i].id = shot.balls(i).id();
  for (const v1::ShotSample& s : shot.samples()) {
    for (int i = 0; i < s.x_m_size() && i < static_cast<int>(paths.size()); ++i) {
      BallPath& p = paths[i];
      if (p.pocketed) continue;
      p.t_s.push_back(s.t_s());
      p.x_m.push_back(s.x_m(i));
      p.y_m.push_back(s.y_m(i));
      if (s.state(i) == v1::pocketed) p.pocketed = true;
    }
  }
  return paths;
}

std::string TableSvg(const TableDrawing& d) {
  const v1::TableGeometry& g = d.geometry;
  const double r = g.ball_radius_m() > 0 ? g.ball_radius_m() : 0.028575;
  // World box: the table plus its rails, or the paths' extent on an open cloth.
  double x0, x1, y0, y1;
  if (g.bounded()) {
    const double rail = 0.12;
    x0 = -0.5 * g.length_m() - rail;
    x1 = 0.5 * g.length_m() + rail;
    y0 = -0.5 * g.width_m() - rail;
    y1 = 0.5 * g.width_m() + rail;
  } else {
    x0 = y0 = std::numeric_limits<double>::infinity();
    x1 = y1 = -x0;
    for (const BallPath& p : d.paths) {
      for (size_t i = 0; i < p.x_m.size(); ++i) {
        x0 = std::min(x0, p.x_m[i]);
        x1 = std::max(x1, p.x_m[i]);
        y0 = std::min(y0, p.y_m[i]);
        y1 = std::max(y1, p.y_m[i]);
      }
    }
    if (!std::isfinite(x0)) x0 = y0 = -1, x1 = y1 = 1;
    const double pad = 0.05 * std::max(x1 - x0, y1 - y0) + 4 * r;
    x0 -= pad, x1 += pad, y0 -= pad, y1 += pad;
  }
  const double width_px = 1200.0;
  const double scale = width_px / (x1 - x0);
  const double height_px = (y1 - y0) * scale;
  const double top = 40.0;  // room for the title
  const auto X = [&](double x) { return (x - x0) * scale; };
  const auto Y = [&](double y) { return top + (y1 - y) * scale; };
  // Markers and strokes scale with the ball, but never below what the eye can see.
  const double ball_px = std::max(r * scale, 3.0);
  std::string svg = absl::StrFormat(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
      "viewBox=\"0 0 %.0f %.0f\" font-family=\"sans-serif\">\n",
      width_px, height_px + top + 30, width_px, height_px + top + 30);
  absl::StrAppendFormat(&svg, "<rect width=\"100%%\" height=\"100%%\" fill=\"#ffffff\"/>\n");
  absl::StrAppendFormat(&svg, "<text x=\"10\" y=\"26\" font-size=\"18\">%s</text>\n",
                        SvgEscape(d.title));
  if (g.bounded()) {
    // Wooden rails, cloth inside the cushion noses, cushions, pockets.
    absl::StrAppendFormat(&svg,
                          "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" rx=\"12\" "
                          "fill=\"#5b3a1e\"/>\n",
                          X(x0), Y(y1), (x1 - x0) * scale, (y1 - y0) * scale);
    absl::StrAppendFormat(
        &svg, "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"#1e7a46\"/>\n",
        X(-0.5 * g.length_m()), Y(0.5 * g.width_m()), g.length_m() * scale, g.width_m() * scale);
    for (const v1::PocketCircle& p : g.pockets()) {
      absl::StrAppendFormat(&svg,
                            "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"#0b0b0b\"/>\n",
                            X(p.x_m()), Y(p.y_m()), p.radius_m() * scale);
    }
    for (const v1::CushionLine& c : g.cushions()) {
      absl::StrAppendFormat(&svg,
                            "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" "
                            "stroke=\"#0f4d2a\" stroke-width=\"4\" stroke-linecap=\"round\"/>\n",
                            X(c.x1_m()), Y(c.y1_m()), X(c.x2_m()), Y(c.y2_m()));
    }
  } else {
    absl::StrAppendFormat(&svg,
                          "<rect x=\"0\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" "
                          "fill=\"#1e7a46\"/>\n",
                          top, width_px, height_px);
  }
  // Paths, then start positions (dashed outlines), then final positions on top.
  for (const BallPath& p : d.paths) {
    if (p.x_m.size() < 2) continue;
    std::string pts;
    for (size_t i = 0; i < p.x_m.size(); ++i) {
      absl::StrAppendFormat(&pts, "%.1f,%.1f ", X(p.x_m[i]), Y(p.y_m[i]));
    }
    const std::string colour = BallColour(p.id);
    absl::StrAppendFormat(&svg,
                          "<polyline points=\"%s\" fill=\"none\" stroke=\"%s\" "
                          "stroke-width=\"2\" stroke-opacity=\"0.9\"%s/>\n",
                          pts, colour == "#111111" ? "#000000" : colour,
                          Striped(p.id) ? " stroke-dasharray=\"8 4\"" : "");
  }
  for (const BallPath& p : d.paths) {
    if (p.x_m.empty()) continue;
    absl::StrAppendFormat(&svg,
                          "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"none\" "
                          "stroke=\"#ffffff\" stroke-opacity=\"0.6\" stroke-dasharray=\"3 3\"/>\n",
                          X(p.x_m.front()), Y(p.y_m.front()), ball_px);
  }
  // Collisions: ball-ball as red rings at the contact point, cushion hits as orange dots.
  std::map<std::string, const BallPath*> by_id;
  for (const BallPath& p : d.paths) by_id[p.id] = &p;
  for (const v1::TableEvent& e : d.events) {
    if (e.kind() == v1::ball_ball && e.balls_size() == 2) {
      double xa, ya, xb, yb;
      auto ia = by_id.find(e.balls(0));
      auto ib = by_id.find(e.balls(1));
      if (ia == by_id.end() || ib == by_id.end()) continue;
      if (!PathAt(*ia->second, e.t_s(), &xa, &ya) || !PathAt(*ib->second, e.t_s(), &xb, &yb)) {
        continue;
      }
      absl::StrAppendFormat(&svg,
                            "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"none\" "
                            "stroke=\"#ff2d2d\" stroke-width=\"2\"/>\n",
                            X(0.5 * (xa + xb)), Y(0.5 * (ya + yb)), 0.6 * ball_px);
    } else if (e.kind() == v1::ball_cushion && e.balls_size() == 1) {
      double x, y;
      auto it = by_id.find(e.balls(0));
      if (it == by_id.end() || !PathAt(*it->second, e.t_s(), &x, &y)) continue;
      absl::StrAppendFormat(&svg,
                            "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"#ffa31a\"/>\n",
                            X(x), Y(y), 0.45 * ball_px);
    }
  }
  for (const BallPath& p : d.paths) {
    if (p.x_m.empty()) continue;
    const double x = X(p.x_m.back()), y = Y(p.y_m.back());
    absl::StrAppendFormat(&svg,
                          "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"%s\" "
                          "stroke=\"#000000\" stroke-width=\"1\"%s/>\n",
                          x, y, ball_px, BallColour(p.id), p.pocketed ? " opacity=\"0.5\"" : "");
    // The id inside the ball when it fits (racked balls touch: labels beside them would
    // overlap their neighbours), else beside it.
    const double font_px = std::min(12.0, 1.1 * ball_px);
    if (ball_px >= 6 && static_cast<double>(p.id.size()) * 0.62 * font_px <= 2 * ball_px) {
      absl::StrAppendFormat(&svg,
                            "<text x=\"%.1f\" y=\"%.1f\" font-size=\"%.1f\" "
                            "text-anchor=\"middle\" fill=\"#000000\" stroke=\"#ffffff\" "
                            "stroke-width=\"2\" paint-order=\"stroke\">%s</text>\n",
                            x, y + 0.35 * font_px, font_px, SvgEscape(p.id));
    } else {
      absl::StrAppendFormat(&svg,
                            "<text x=\"%.1f\" y=\"%.1f\" font-size=\"10\" fill=\"#ffffff\" "
                            "stroke=\"#000000\" stroke-width=\"0.4\">%s</text>\n",
                            x + ball_px + 2, y - ball_px - 2, SvgEscape(p.id));
    }
  }
  absl::StrAppendFormat(&svg,
                        "<text x=\"10\" y=\"%.0f\" font-size=\"13\">paths: solid lines (stripes "
                        "dashed); dashed rings: start; red rings: ball-ball contacts; orange: "
                        "cushion hits; scale %.0f px/m</text>\n",
                        height_px + top + 22, scale);
  svg += "</svg>\n";
  return svg;
}

}  // namespace sportsim::cli
