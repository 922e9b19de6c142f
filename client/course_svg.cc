#include "client/course_svg.h"

#include <algorithm>
#include <cmath>
#include <string_view>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "client/table_svg.h"

namespace sportsim::cli {

namespace {

struct Style {
  std::string_view golf, fill, stroke;
};
// Colours by surface class; water keeps its stakes' colour as its outline.
constexpr Style kStyles[] = {
    {"tee", "#86c96a", "#5a8f44"},        {"fairway", "#8fd16a", "none"},
    {"first_cut", "#79bd58", "none"},     {"rough", "#5e9e45", "none"},
    {"bunker", "#ead9a2", "#c9b77a"},     {"green", "#b4e88a", "#6fae4c"},
    {"fringe", "#9cd873", "none"},        {"cartpath", "#b5b5b5", "#8a8a8a"},
    {"water_hazard", "#4a8fd6", "#e6c619"}, {"lateral_water_hazard", "#4a8fd6", "#d9342b"},
    {"out_of_bounds", "#d9d9d9", "#ffffff"},
};

const Style& StyleOf(std::string_view golf) {
  for (const Style& s : kStyles) {
    if (s.golf == golf) return s;
  }
  return kStyles[3];
}

}  // namespace

std::string CourseSvg(const v1::CourseInfo& c, int hole, const v1::SimulateGolfShotResponse* shot) {
  constexpr double kSize = 900, kPad = 40;
  const v1::CourseHeightfield& h = c.heightfield();
  // The frame: the whole map, or one hole's tees and pin (and the shot) with a margin.
  double x0 = h.x0_m(), x1 = h.x0_m() + h.spacing_m() * (h.columns() - 1);
  double y0 = h.y0_m(), y1 = h.y0_m() + h.spacing_m() * (h.rows() - 1);
  const v1::CourseHoleInfo* framed = nullptr;
  for (const v1::CourseHoleInfo& hi : c.holes()) {
    if (static_cast<int>(hi.number()) == hole) framed = &hi;
  }
  if (framed != nullptr) {
    double a0 = framed->pin().x_m(), a1 = a0, b0 = framed->pin().y_m(), b1 = b0;
    auto grow = [&](double x, double y) {
      a0 = std::min(a0, x), a1 = std::max(a1, x), b0 = std::min(b0, y), b1 = std::max(b1, y);
    };
    for (const v1::CourseTee& t : framed->tees()) grow(t.x_m(), t.y_m());
    if (shot != nullptr) {
      for (const v1::GolfPathPoint& p : shot->path()) grow(p.x_m(), p.y_m());
      grow(shot->rest().x_m(), shot->rest().y_m());
    }
    x0 = std::max(x0, a0 - 40), x1 = std::min(x1, a1 + 40);
    y0 = std::max(y0, b0 - 40), y1 = std::min(y1, b1 + 40);
  }
  const double span = std::max({x1 - x0, y1 - y0, 1.0});
  const double scale = (kSize - 2 * kPad) / span;
  const double width = std::max((x1 - x0) * scale + 2 * kPad, 560.0);
  const double height = (y1 - y0) * scale + 2 * kPad;
  auto px = [&](double x) { return kPad + (x - x0) * scale; };
  auto py = [&](double y) { return height - kPad - (y - y0) * scale; };
  std::string out = absl::StrFormat(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n"
      "<rect width=\"100%%\" height=\"100%%\" fill=\"%s\"/>\n",
      width, height + 30, StyleOf("rough").fill);
  // Elevation: the grid's cells (every few, at most about 120 across) shaded darker the lower
  // they lie, over the whole picture, under the surfaces.
  const double zlo = c.min_z_m(), zhi = std::max(c.max_z_m(), c.min_z_m() + 1e-9);
  const int stride = std::max(1, static_cast<int>(std::ceil(span / h.spacing_m() / 120)));
  const double vx0 = x0 - kPad / scale, vx1 = x0 + (width - kPad) / scale;
  const double vy0 = y0 - kPad / scale, vy1 = y1 + kPad / scale;
  out += "<g id=\"elevation\" shape-rendering=\"crispEdges\">\n";
  for (uint32_t j = 0; j + 1 < h.rows(); j += stride) {
    for (uint32_t i = 0; i + 1 < h.columns(); i += stride) {
      const double x = h.x0_m() + i * h.spacing_m(), y = h.y0_m() + j * h.spacing_m();
      const double w = stride * h.spacing_m();
      if (x + w < vx0 || x > vx1 || y + w < vy0 || y > vy1) continue;
      const double z = h.z_m(static_cast<int>(j * h.columns() + i));
      const double f = (z - zlo) / (zhi - zlo);
      // Whole pixels, edge to edge: no seams where neighbours overlap or part.
      const long l = std::lround(px(x)), r = std::lround(px(x + w));
      const long t = std::lround(py(y + w)), b = std::lround(py(y));
      if (r <= l || b <= t) continue;
      out += absl::StrFormat(
          "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"#000\" "
          "fill-opacity=\"%.3f\"/>\n",
          l, t, r - l, b - t, 0.45 * (1.0 - f));
    }
  }
  out += "</g>\n<g id=\"surfaces\">\n";
  auto points = [&](const auto& xy) {
    std::string s;
    for (int k = 0; k + 1 < xy.size(); k += 2) {
      absl::StrAppend(&s, absl::StrFormat("%.1f,%.1f ", px(xy[k]), py(xy[k + 1])));
    }
    return s;
  };
  for (const v1::CourseArea& a : c.areas()) {
    const Style& s = StyleOf(a.golf());
    out += absl::StrFormat(
        "<polygon points=\"%s\" fill=\"%s\" fill-opacity=\"0.8\" stroke=\"%s\" "
        "stroke-width=\"1.5\"><title>%s</title></polygon>\n",
        points(a.xy_m()), s.fill, s.stroke, SvgEscape(a.golf()));
  }
  out += "</g>\n";
  if (c.boundary_xy_m_size() >= 6) {
    out += absl::StrFormat(
        "<polygon points=\"%s\" fill=\"none\" stroke=\"white\" stroke-width=\"2\" "
        "stroke-dasharray=\"6,4\"><title>boundary (out of bounds beyond)</title></polygon>\n",
        points(c.boundary_xy_m()));
  }
  for (const v1::CourseHoleInfo& hi : c.holes()) {
    for (const v1::CourseTee& t : hi.tees()) {
      out += absl::StrFormat(
          "<rect x=\"%.1f\" y=\"%.1f\" width=\"6\" height=\"6\" fill=\"white\" stroke=\"#000\">"
          "<title>hole %u tee %s</title></rect>\n",
          px(t.x_m()) - 3, py(t.y_m()) - 3, hi.number(), SvgEscape(t.name()));
    }
    const double fx = px(hi.pin().x_m()), fy = py(hi.pin().y_m());
    out += absl::StrFormat(
        "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3\" fill=\"#222\"/>\n"
        "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#c00\" stroke-width=\"2\"/>\n"
        "<text x=\"%.1f\" y=\"%.1f\" font-weight=\"bold\">%u</text>\n",
        fx, fy, fx, fy, fx, fy - 22, fx + 4, fy - 12, hi.number());
  }
  if (shot != nullptr) {
    std::string line;
    for (const v1::GolfPathPoint& p : shot->path()) {
      absl::StrAppend(&line, absl::StrFormat("%.1f,%.1f ", px(p.x_m()), py(p.y_m())));
    }
    absl::StrAppend(&line, absl::StrFormat("%.1f,%.1f", px(shot->rest().x_m()), py(shot->rest().y_m())));
    out += absl::StrFormat(
        "<polyline points=\"%s\" fill=\"none\" stroke=\"#1f5fbf\" stroke-width=\"2\"/>\n", line);
    for (const v1::GolfEvent& e : shot->events()) {
      out += absl::StrFormat(
          "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3\" fill=\"#e08000\"><title>%s at %.2f s (%s)"
          "</title></circle>\n",
          px(e.x_m()), py(e.y_m()), SvgEscape(e.kind()), e.t_s(), SvgEscape(e.surface()));
    }
    out += absl::StrFormat(
        "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"6\" fill=\"white\" stroke=\"#000\"/>\n",
        px(shot->rest().x_m()), py(shot->rest().y_m()));
  }
  double bar = std::pow(10.0, std::floor(std::log10(span / 4)));
  if (bar * 5 <= span / 4) bar *= 5;
  else if (bar * 2 <= span / 4) bar *= 2;
  out += absl::StrFormat(
      "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#000\" stroke-width=\"2\"/>\n"
      "<text x=\"%.1f\" y=\"%.1f\">%g m (north up); ground %.1f-%.1f m, darker lower</text>\n",
      kPad, height + 20, kPad + bar * scale, height + 20, kPad + bar * scale + 8, height + 24, bar,
      c.min_z_m(), c.max_z_m());
  out += "</svg>\n";
  return out;
}

}  // namespace sportsim::cli
