// `sportsim golf ...`: a golf shot to rest on a practice course or a course (SimulateGolfShot).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/flags/declare.h"
#include "absl/flags/flag.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "client/cli.h"
#include "client/course_svg.h"
#include "client/swing_flags.h"
#include "client/table_svg.h"
#include "sportsim/v1/swing.grpc.pb.h"

// Shared with `flight simulate` (flight_commands.cc) and `swing simulate` (swing_commands.cc).
ABSL_DECLARE_FLAG(std::optional<double>, ball_speed);
ABSL_DECLARE_FLAG(std::optional<double>, launch_deg);
ABSL_DECLARE_FLAG(std::optional<double>, spin_rpm);
ABSL_DECLARE_FLAG(double, spin_axis_deg);
ABSL_DECLARE_FLAG(double, launch_direction_deg);
ABSL_DECLARE_FLAG(std::optional<double>, sample_interval);
ABSL_DECLARE_FLAG(std::vector<std::string>, disable);
ABSL_DECLARE_FLAG(std::string, svg);

ABSL_FLAG(std::string, course, "practice",
          "golf: practice (a plane green, hole at the origin), range (a flat fairway) or a "
          "course of `course list`");
ABSL_FLAG(std::optional<int>, hole, std::nullopt, "golf: a course's hole (1-based; default 1)");
ABSL_FLAG(std::string, tee, "", "golf: a course's tee by name (default the hole's first)");
ABSL_FLAG(std::optional<double>, stimp, std::nullopt, "golf practice: green speed (ft); default 10");
ABSL_FLAG(double, slope_pct, 0.0, "golf practice: the green's grade along its fall line (%)");
ABSL_FLAG(double, slope_toward_deg, 0.0,
          "golf practice: heading the fall line points toward (deg, ccw from +x)");
ABSL_FLAG(std::string, fairway, "", "golf range: firm, normal (default) or soft");
ABSL_FLAG(std::string, from, "", "golf: the ball's position X,Y (m)");
ABSL_FLAG(std::optional<double>, aim_deg, std::nullopt,
          "golf: a launch's target line (deg, ccw from +x); default toward the pin");
ABSL_FLAG(std::optional<double>, putt_speed, std::nullopt, "golf: a putt's speed (m/s)");
ABSL_FLAG(double, putt_direction_deg, 0.0, "golf: a putt's heading (deg, ccw from +x)");
ABSL_FLAG(std::optional<double>, roll_speed, std::nullopt,
          "golf: a ball already rolling: its speed (m/s)");
ABSL_FLAG(double, roll_direction_deg, 0.0, "golf: the rolling ball's heading (deg, ccw from +x)");
ABSL_FLAG(bool, flagstick, false, "golf practice: the flagstick is in the hole");

namespace sportsim::cli {
namespace {

constexpr double kMetresPerYard = 0.9144;

std::optional<std::string> BuildRequest(v1::SimulateGolfShotRequest* r) {
  r->set_course(absl::GetFlag(FLAGS_course));
  if (auto v = absl::GetFlag(FLAGS_stimp)) r->set_stimp_ft(*v);
  r->set_slope_pct(absl::GetFlag(FLAGS_slope_pct));
  r->set_slope_toward_deg(absl::GetFlag(FLAGS_slope_toward_deg));
  r->set_fairway(absl::GetFlag(FLAGS_fairway));
  r->set_flagstick(absl::GetFlag(FLAGS_flagstick));
  if (auto h = absl::GetFlag(FLAGS_hole)) {
    if (*h < 1 || *h > 36) return InvalidValue(absl::StrFormat("--hole: must be in [1, 36], got %d", *h));
    r->set_hole(static_cast<uint32_t>(*h));
  }
  r->set_tee(absl::GetFlag(FLAGS_tee));
  if (!r->tee().empty() && !absl::GetFlag(FLAGS_from).empty()) {
    return "give --tee or --from, not both";
  }
  if (const std::string from = absl::GetFlag(FLAGS_from); !from.empty()) {
    const std::vector<std::string> xy = absl::StrSplit(from, ',');
    double x = 0, y = 0;
    if (xy.size() != 2 || !absl::SimpleAtod(xy[0], &x) || !absl::SimpleAtod(xy[1], &y)) {
      return "--from must be X,Y in metres, got '" + from.substr(0, 40) + "'";
    }
    r->set_from_x_m(x);
    r->set_from_y_m(y);
  }
  if (auto v = absl::GetFlag(FLAGS_aim_deg)) r->set_aim_deg(*v);
  if (auto v = absl::GetFlag(FLAGS_sample_interval)) r->set_sample_interval_s(*v);
  const auto speed = absl::GetFlag(FLAGS_ball_speed);
  const auto putt = absl::GetFlag(FLAGS_putt_speed);
  const auto roll = absl::GetFlag(FLAGS_roll_speed);
  const int shots = (speed ? 1 : 0) + (putt ? 1 : 0) + (roll ? 1 : 0);
  if (shots != 1) {
    return "golf simulate needs one shot: a launch (--ball-speed --launch-deg --spin-rpm), a "
           "putt (--putt-speed) or a rolling ball (--roll-speed)";
  }
  if (speed) {
    const auto launch = absl::GetFlag(FLAGS_launch_deg);
    const auto spin = absl::GetFlag(FLAGS_spin_rpm);
    if (!launch || !spin) return "a launch needs --ball-speed, --launch-deg and --spin-rpm";
    v1::LaunchConditions* l = r->mutable_launch();
    l->set_ball_speed_mps(*speed);
    l->set_launch_angle_deg(*launch);
    l->set_spin_rpm(*spin);
    l->set_spin_axis_deg(absl::GetFlag(FLAGS_spin_axis_deg));
    l->set_launch_direction_deg(absl::GetFlag(FLAGS_launch_direction_deg));
    v1::SimulateFlightRequest air;
    if (auto bad = BuildFlightAir(&air)) return bad;
    if (air.has_atmosphere()) *r->mutable_atmosphere() = air.atmosphere();
    if (air.has_wind()) *r->mutable_wind() = air.wind();
  } else {
    v1::GroundStroke* st = putt ? r->mutable_putt() : r->mutable_roll();
    st->set_speed_mps(putt ? *putt : *roll);
    st->set_direction_deg(putt ? absl::GetFlag(FLAGS_putt_direction_deg)
                               : absl::GetFlag(FLAGS_roll_direction_deg));
  }
  for (const std::string& e : absl::GetFlag(FLAGS_disable)) {
    if (e == "ground_spin") r->set_no_spin(true);
    else if (e == "ground_slope") r->set_no_slope(true);
    else return "--disable for golf takes ground_spin, ground_slope; got '" + e.substr(0, 40) + "'";
  }
  return std::nullopt;
}

void PrintText(const v1::SimulateGolfShotResponse& r) {
  const v1::GolfRest& rest = r.rest();
  if (r.has_flight()) {
    std::printf("carry %.2f m (%.1f yd), total %.2f m (%.1f yd), %.2f m %s of the aim line\n",
                r.carry_m(), r.carry_m() / kMetresPerYard, r.total_m(),
                r.total_m() / kMetresPerYard, std::abs(r.lateral_m()),
                r.lateral_m() >= 0 ? "right" : "left");
  } else {
    std::printf("rolled %.2f m (%.1f ft), %.2f m %s of its line\n", r.total_m(),
                r.total_m() / 0.3048, std::abs(r.lateral_m()),
                r.lateral_m() >= 0 ? "right" : "left");
  }
  if (rest.holed()) {
    std::printf("holed at %.2f s\n", r.t_rest_s());
  } else if (rest.out_of_bounds()) {
    std::printf("out of bounds at (%.2f, %.2f) m after %.2f s\n", rest.x_m(), rest.y_m(),
                r.t_rest_s());
  } else if (rest.penalty_area()) {
    std::printf("in the %s (a penalty area), entered at (%.2f, %.2f) m after %.2f s\n",
                rest.surface() == "lateral_water_hazard" ? "red penalty area's water"
                                                         : "yellow penalty area's water",
                rest.x_m(), rest.y_m(), r.t_rest_s());
  } else {
    const std::string lie = !rest.lie().empty() && rest.lie() != rest.surface()
                                ? " (its lie: " + rest.lie() + ")"
                                : "";
    std::printf("at rest on the %s%s at (%.2f, %.2f, %.3f) m after %.2f s",
                rest.surface().c_str(), lie.c_str(), rest.x_m(), rest.y_m(), rest.z_m(),
                r.t_rest_s());
    if (rest.has_distance_to_pin_m()) {
      std::printf(", %.2f m (%.1f ft) from the pin", rest.distance_to_pin_m(),
                  rest.distance_to_pin_m() / 0.3048);
    }
    std::printf("\n");
  }
  for (const v1::GolfEvent& e : r.events()) {
    std::printf("  %7.3f s  %-13s (%8.2f, %8.2f, %6.3f) m  %6.2f m/s  %6.0f rpm  %s\n", e.t_s(),
                e.kind().c_str(), e.x_m(), e.y_m(), e.z_m(), e.speed_mps(), e.spin_rpm(),
                e.surface().c_str());
  }
  std::printf("%u bounces; %.3f ms CPU\n", r.bounces(), r.cpu_s() * 1e3);
}

void PrintCsv(const v1::SimulateGolfShotResponse& r) {
  std::cout << "t_s,x_m,y_m,z_m\n";
  for (const v1::GolfPathPoint& p : r.path()) {
    std::cout << Num(p.t_s()) << ',' << Num(p.x_m()) << ',' << Num(p.y_m()) << ','
              << Num(p.z_m()) << '\n';
  }
}

// The path from above, at one scale across and up (north up), with the hole, the start, the
// landing, bounces and the rest marked, and a scale bar.
std::string ShotSvg(const v1::SimulateGolfShotResponse& r, const v1::SimulateGolfShotRequest& q) {
  constexpr double kSize = 800, kPad = 60;
  // The path starts where the ball was (the server's default when --from is not given).
  const double from_x = r.path().empty() ? r.rest().x_m() : r.path(0).x_m();
  const double from_y = r.path().empty() ? r.rest().y_m() : r.path(0).y_m();
  double x0 = from_x, x1 = from_x, y0 = from_y, y1 = from_y;
  auto grow = [&](double x, double y) {
    x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
  };
  for (const v1::GolfPathPoint& p : r.path()) grow(p.x_m(), p.y_m());
  grow(r.rest().x_m(), r.rest().y_m());
  const bool pin = r.rest().has_distance_to_pin_m();
  if (pin) grow(0, 0);
  const double span = std::max({x1 - x0, y1 - y0, 1.0}) * 1.1;
  const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
  const double scale = (kSize - 2 * kPad) / span;
  auto px = [&](double x) { return kSize / 2 + (x - cx) * scale; };
  auto py = [&](double y) { return kSize / 2 - (y - cy) * scale; };
  const bool green = q.course().empty() || q.course() == "practice";
  std::string out = absl::StrFormat(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
      "font-family=\"sans-serif\" font-size=\"13\">\n"
      "<rect width=\"100%%\" height=\"100%%\" fill=\"%s\"/>\n",
      kSize, kSize + 40, green ? "#cfe8c4" : "#b9d9a5");
  if (pin) {
    out += absl::StrFormat(
        "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"#222\"/>\n"
        "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#c00\" stroke-width=\"2\"/>\n",
        px(0), py(0), std::max(3.0, 0.054 * scale), px(0), py(0), px(0), py(0) - 30);
  }
  std::string line;
  for (const v1::GolfPathPoint& p : r.path()) {
    line += absl::StrFormat("%.1f,%.1f ", px(p.x_m()), py(p.y_m()));
  }
  line += absl::StrFormat("%.1f,%.1f", px(r.rest().x_m()), py(r.rest().y_m()));
  out += absl::StrFormat(
      "<polyline points=\"%s\" fill=\"none\" stroke=\"#1f5fbf\" stroke-width=\"2\"/>\n", line);
  out += absl::StrFormat("<circle cx=\"%.1f\" cy=\"%.1f\" r=\"4\" fill=\"#1f5fbf\"/>\n",
                         px(from_x), py(from_y));
  for (const v1::GolfEvent& e : r.events()) {
    const char* colour = e.kind() == "landing" || e.kind() == "bounce" ? "#e08000"
                         : e.kind() == "roll"                           ? "#2a2"
                         : e.kind() == "lip_out"                        ? "#c00"
                                                                        : "#000";
    out += absl::StrFormat(
        "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3\" fill=\"%s\"><title>%s at %.2f s</title>"
        "</circle>\n",
        px(e.x_m()), py(e.y_m()), colour, SvgEscape(e.kind()), e.t_s());
  }
  out += absl::StrFormat(
      "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"6\" fill=\"white\" stroke=\"#000\"/>\n",
      px(r.rest().x_m()), py(r.rest().y_m()));
  // A scale bar of a round length.
  double bar = std::pow(10.0, std::floor(std::log10(span / 4)));
  if (bar * 5 <= span / 4) bar *= 5;
  else if (bar * 2 <= span / 4) bar *= 2;
  out += absl::StrFormat(
      "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#000\" stroke-width=\"2\"/>\n"
      "<text x=\"%.1f\" y=\"%.1f\">%g m (north up)</text>\n",
      kPad, kSize - 20, kPad + bar * scale, kSize - 20, kPad, kSize - 28, bar);
  out += absl::StrFormat(
      "<text x=\"%.0f\" y=\"%.0f\">%s: total %.2f m%s%s</text>\n</svg>\n", kPad, kSize + 25,
      green ? "practice green" : "range", r.total_m(),
      r.has_flight() ? absl::StrFormat(", carry %.2f m", r.carry_m()) : std::string(),
      r.rest().holed() ? ", holed" : "");
  return out;
}

int RunSimulate(const Context& ctx, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("golf simulate takes flags only, got '" + args[0] + "'");
  v1::SimulateGolfShotRequest request;
  if (auto bad = BuildRequest(&request)) return UsageError(*bad);
  auto stub = v1::Swing::NewStub(ctx.channel);
  v1::SimulateGolfShotResponse response;
  const grpc::Status status = stub->SimulateGolfShot(ctx.NewCall().get(), request, &response);
  if (!status.ok()) return ReportRpcError(status);
  if (const std::string svg = absl::GetFlag(FLAGS_svg); !svg.empty()) {
    const std::string& course = request.course();
    std::string drawing;
    if (course.empty() || course == "practice" || course == "range") {
      drawing = ShotSvg(response, request);
    } else {
      v1::GetCourseRequest get;
      get.set_name(course);
      get.set_geometry(true);
      v1::CourseInfo info;
      const grpc::Status got = stub->GetCourse(ctx.NewCall().get(), get, &info);
      if (!got.ok()) return ReportRpcError(got);
      drawing = CourseSvg(info, request.hole() == 0 ? 1 : static_cast<int>(request.hole()),
                          &response);
    }
    std::ofstream out(svg);
    out << drawing;
    if (!out) return UsageError("cannot write --svg file '" + svg + "'");
  }
  return PrintResponse(ctx, response, PrintCsv, PrintText);
}

}  // namespace

int RunGolf(const Context& ctx, const std::vector<std::string>& args) {
  if (args.empty()) return UsageError("golf needs a subcommand: simulate");
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (args[0] == "simulate") return RunSimulate(ctx, rest);
  return UsageError("unknown golf subcommand '" + args[0] + "' (simulate)");
}

}  // namespace sportsim::cli
