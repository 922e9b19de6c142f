// `sportsim flight ...`
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
#include "client/swing_flags.h"
#include "client/table_svg.h"
#include "sportsim/v1/swing.grpc.pb.h"

// Shared with `swing simulate` (defined in swing_commands.cc).
ABSL_DECLARE_FLAG(std::optional<double>, dt);
ABSL_DECLARE_FLAG(std::vector<std::string>, disable);
ABSL_DECLARE_FLAG(std::string, svg);
ABSL_DECLARE_FLAG(std::string, fairway);  // golf_commands.cc

ABSL_FLAG(std::optional<double>, ball_speed, std::nullopt, "Ball speed at launch (m/s)");
ABSL_FLAG(std::optional<double>, launch_deg, std::nullopt, "Launch angle above the horizontal (deg)");
ABSL_FLAG(std::optional<double>, spin_rpm, std::nullopt, "Total spin (rpm)");
ABSL_FLAG(double, spin_axis_deg, 0.0, "Spin-axis tilt (deg), + curves right");
ABSL_FLAG(double, launch_direction_deg, 0.0, "Launch direction (deg), + right of the target line");
ABSL_FLAG(std::string, wind, "", "Wind SPEED_MPS[,TOWARD_DEG[,log]]: toward 0 = tailwind, 180 = headwind, 90 = left to right");
ABSL_FLAG(std::optional<double>, temperature_c, std::nullopt, "Air temperature (deg C); default 15");
ABSL_FLAG(std::optional<double>, pressure_pa, std::nullopt, "Sea-level pressure (Pa); default 101325");
ABSL_FLAG(std::optional<double>, humidity, std::nullopt, "Relative humidity, 0 to 1; default 0");
ABSL_FLAG(std::optional<double>, altitude_m, std::nullopt, "Course elevation (m); default 0");
ABSL_FLAG(std::string, aero, "ferguson2022",
          "Aerodynamic fit: ferguson2022 (Ferguson, McNally & McPhee 2022) or nathan (Nathan's "
          "golf trajectory calculator)");
ABSL_FLAG(std::optional<double>, sample_interval, std::nullopt, "Sample spacing (s); default 0.01");

namespace sportsim::cli {
namespace {

constexpr double kMetresPerYard = 0.9144;

std::optional<std::string> BuildRequest(v1::SimulateFlightRequest* r) {
  const auto speed = absl::GetFlag(FLAGS_ball_speed);
  const auto launch = absl::GetFlag(FLAGS_launch_deg);
  const auto spin = absl::GetFlag(FLAGS_spin_rpm);
  if (!speed || !launch || !spin) return "flight simulate needs --ball-speed, --launch-deg and --spin-rpm";
  v1::LaunchConditions* l = r->mutable_launch();
  l->set_ball_speed_mps(*speed);
  l->set_launch_angle_deg(*launch);
  l->set_spin_rpm(*spin);
  l->set_spin_axis_deg(absl::GetFlag(FLAGS_spin_axis_deg));
  l->set_launch_direction_deg(absl::GetFlag(FLAGS_launch_direction_deg));
  if (auto bad = BuildFlightAir(r)) return bad;
  r->set_fairway(absl::GetFlag(FLAGS_fairway));
  if (auto v = absl::GetFlag(FLAGS_dt)) r->set_dt_s(*v);
  for (const std::string& e : absl::GetFlag(FLAGS_disable)) {
    if (e == "drag") r->add_disabled_effects(v1::FLIGHT_EFFECT_DRAG);
    else if (e == "lift") r->add_disabled_effects(v1::FLIGHT_EFFECT_LIFT);
    else if (e == "spin_decay") r->add_disabled_effects(v1::FLIGHT_EFFECT_SPIN_DECAY);
    else if (e == "wind") r->add_disabled_effects(v1::FLIGHT_EFFECT_WIND);
    else return "--disable for flight takes drag, lift, spin_decay, wind; got '" + e + "'";
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> BuildFlightAir(v1::SimulateFlightRequest* r) {
  if (const std::string w = absl::GetFlag(FLAGS_wind); !w.empty()) {
    const std::vector<std::string> parts = absl::StrSplit(w, ',');
    double v = 0;
    if (parts.size() > 3 || !absl::SimpleAtod(parts[0], &v)) {
      return "--wind must be SPEED_MPS[,TOWARD_DEG[,log]], got '" + w + "'";
    }
    r->mutable_wind()->set_speed_mps(v);
    if (parts.size() > 1) {
      if (!absl::SimpleAtod(parts[1], &v)) return "--wind direction must be a number, got '" + parts[1] + "'";
      r->mutable_wind()->set_toward_deg(v);
    }
    if (parts.size() > 2) {
      if (parts[2] != "log") return "--wind profile must be 'log', got '" + parts[2] + "'";
      r->mutable_wind()->set_logarithmic_profile(true);
    }
  }
  v1::Atmosphere* a = r->mutable_atmosphere();
  if (auto v = absl::GetFlag(FLAGS_temperature_c)) a->set_temperature_c(*v);
  if (auto v = absl::GetFlag(FLAGS_pressure_pa)) a->set_sea_level_pressure_pa(*v);
  if (auto v = absl::GetFlag(FLAGS_humidity)) a->set_relative_humidity(*v);
  if (auto v = absl::GetFlag(FLAGS_altitude_m)) a->set_altitude_m(*v);
  if (auto v = absl::GetFlag(FLAGS_sample_interval)) r->set_sample_interval_s(*v);
  if (const std::string fit = absl::GetFlag(FLAGS_aero); fit == "ferguson2022") {
    r->set_aero_fit(v1::AERO_FIT_FERGUSON_2022);
  } else if (fit == "nathan") {
    r->set_aero_fit(v1::AERO_FIT_NATHAN);
  } else {
    return "--aero takes ferguson2022 or nathan; got '" + fit + "'";
  }
  return std::nullopt;
}

void PrintFlightText(const v1::SimulateFlightResponse& f) {
  std::printf(
      "carry %.2f m (%.1f yd), %.2f m along the target line, %.2f m %s\n"
      "apex %.2f m (%.1f yd) at %.3f s; flight %.3f s\n"
      "landing at %.2f deg, %.2f m/s; air density %.4f kg/m^3; %u steps, %.3f ms CPU\n",
      f.carry_m(), f.carry_m() / kMetresPerYard, f.carry_downrange_m(), std::abs(f.lateral_m()),
      f.lateral_m() >= 0 ? "right" : "left", f.apex_m(), f.apex_m() / kMetresPerYard,
      f.apex_time_s(), f.flight_time_s(), f.landing_angle_deg(), f.landing_speed_mps(),
      f.air_density_kgpm3(), f.steps(), f.cpu_s() * 1e3);
  if (f.has_total_m()) {
    std::printf("rolled out on the %s: total %.2f m (%.1f yd), %.2f m %s, at rest after %.2f s "
                "(%d events on the ground)\n",
                f.rest().surface().c_str(), f.total_m(), f.total_m() / kMetresPerYard,
                std::abs(f.total_lateral_m()), f.total_lateral_m() >= 0 ? "right" : "left",
                f.ground_events_size() > 0 ? f.ground_events(f.ground_events_size() - 1).t_s() : 0.0,
                f.ground_events_size());
  }
}

namespace {

void PrintCsv(const v1::SimulateFlightResponse& f) {
  std::cout << "t_s,x_m,y_m,z_m,vx_mps,vy_mps,vz_mps,speed_mps,spin_rpm\n";
  for (const v1::FlightSample& s : f.samples()) {
    std::cout << Num(s.t_s()) << ',' << Num(s.x_m()) << ',' << Num(s.y_m()) << ','
              << Num(s.z_m()) << ',' << Num(s.vx_mps()) << ',' << Num(s.vy_mps()) << ','
              << Num(s.vz_mps()) << ',' << Num(s.speed_mps()) << ',' << Num(s.spin_rpm()) << '\n';
  }
}

// A round tick step for a span: 1, 2 or 5 times a power of ten, about `ticks` to the span.
double NiceStep(double span, int ticks) {
  const double raw = std::max(span, 1e-9) / ticks;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0}) {
    if (m * p >= raw) return m * p;
  }
  return 10 * p;
}

// The trajectory as two views sharing the downrange axis: the side view (height over
// downrange) at one scale for both axes, so the flight's shape is true, with a downrange axis
// in metres and yards and a height axis in metres; under it the top view (lateral over
// downrange, + right drawn downward as on a map seen from behind the golfer), whose lateral
// scale is its own (a 5 m curve over 250 m would not show) and is marked on its axis. The
// carry, apex and landing are written under them.
std::string FlightSvg(const v1::SimulateFlightResponse& f, const std::string& title) {
  constexpr double kWidth = 900, kLeft = 70, kRight = 30, kSideTop = 60, kMaxSideH = 360;
  constexpr double kTopH = 160;
  constexpr double kPlotW = kWidth - kLeft - kRight;
  double x_max = 1, z_max = 1, y_max = 1;
  for (const v1::FlightSample& s : f.samples()) {
    x_max = std::max(x_max, s.x_m());
    z_max = std::max(z_max, s.z_m());
    y_max = std::max(y_max, std::abs(s.y_m()));
  }
  // One scale (px per metre) for downrange and height.
  const double scale = std::min(kPlotW / x_max, kMaxSideH / z_max);
  const double side_h = z_max * scale;
  const double ground = kSideTop + side_h;
  const auto px = [&](double x) { return kLeft + x * scale; };
  const auto side_y = [&](double z) { return ground - z * scale; };
  const double axis_end = px(x_max);
  const double yard_axis = ground + 34;
  const double top_top = yard_axis + 70;
  // Left of the target line (y > 0) is drawn up, right (y < 0) down.
  const auto top_y = [&](double y) { return top_top + kTopH / 2 - y * (kTopH / 2) / y_max; };
  const double height = top_top + kTopH + 50;
  std::string side, top;
  for (const v1::FlightSample& s : f.samples()) {
    side += absl::StrFormat("%.1f,%.1f ", px(s.x_m()), side_y(s.z_m()));
    top += absl::StrFormat("%.1f,%.1f ", px(s.x_m()), top_y(s.y_m()));
  }
  std::string out = absl::StrFormat(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
      "font-family=\"sans-serif\" font-size=\"13\">\n"
      "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n"
      "<text x=\"%.0f\" y=\"25\">%s</text>\n",
      kWidth, height, kLeft, SvgEscape(title));
  out += absl::StrFormat(
      "<text x=\"%.0f\" y=\"%.0f\">side view, same scale across and up (%.1f px/m); apex "
      "%.1f m</text>\n",
      kLeft, kSideTop - 12, scale, f.apex_m());
  // Downrange axis in metres (the ground line) and in yards under it.
  out += absl::StrFormat(
      "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#6a6\"/>\n"
      "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#999\"/>\n",
      px(0), ground, axis_end, ground, px(0), yard_axis, axis_end, yard_axis);
  const double m_step = NiceStep(x_max, 8);
  for (double x = 0; x <= x_max + 1e-9; x += m_step) {
    out += absl::StrFormat(
        "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#6a6\"/>\n"
        "<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" text-anchor=\"middle\">%g</text>\n",
        px(x), ground, px(x), ground + 5, px(x), ground + 17, x);
  }
  const double yd_max = x_max / kMetresPerYard;
  const double yd_step = NiceStep(yd_max, 8);
  for (double yd = 0; yd <= yd_max + 1e-9; yd += yd_step) {
    const double x = px(yd * kMetresPerYard);
    out += absl::StrFormat(
        "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#999\"/>\n"
        "<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" text-anchor=\"middle\">%g</text>\n",
        x, yard_axis, x, yard_axis + 5, x, yard_axis + 17, yd);
  }
  out += absl::StrFormat(
      "<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" text-anchor=\"end\">m</text>\n"
      "<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" text-anchor=\"end\">yd</text>\n",
      kLeft - 8, ground + 17, kLeft - 8, yard_axis + 17);
  // Height axis, metres.
  out += absl::StrFormat(
      "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#999\"/>\n", px(0),
      ground, px(0), side_y(z_max));
  const double z_step = NiceStep(z_max, 4);
  for (double z = z_step; z <= z_max + 1e-9; z += z_step) {
    out += absl::StrFormat(
        "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#999\"/>\n"
        "<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" text-anchor=\"end\">%g m</text>\n",
        px(0) - 5, side_y(z), px(0), side_y(z), px(0) - 8, side_y(z) + 4, z);
  }
  out += absl::StrFormat(
      "<polyline points=\"%s\" fill=\"none\" stroke=\"#1f5fbf\" stroke-width=\"2\"/>\n", side);
  // Top view: the target line, the lateral scale, the trajectory.
  out += absl::StrFormat(
      "<text x=\"%.0f\" y=\"%.0f\">top view (lateral scale stretched: %.1f m to the edge; "
      "right of the target line drawn down)</text>\n"
      "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#999\" "
      "stroke-dasharray=\"6 4\"/>\n"
      "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#999\"/>\n",
      kLeft, top_top - 12, y_max, px(0), top_y(0), axis_end, top_y(0), px(0), top_y(y_max),
      px(0), top_y(-y_max));
  for (double y : {y_max, -y_max}) {
    out += absl::StrFormat(
        "<text x=\"%.1f\" y=\"%.1f\" font-size=\"11\" text-anchor=\"end\">%.1f m %s</text>\n",
        px(0) - 8, top_y(y) + 4, std::abs(y), y > 0 ? "L" : "R");
  }
  out += absl::StrFormat(
      "<polyline points=\"%s\" fill=\"none\" stroke=\"#1f5fbf\" stroke-width=\"2\"/>\n", top);
  out += absl::StrFormat(
      "<text x=\"%.0f\" y=\"%.0f\">carry %.1f m (%.1f yd), apex %.1f m, flight %.2f s, "
      "landing %.1f deg at %.1f m/s, %.1f m %s</text>\n</svg>\n",
      kLeft, height - 15, f.carry_m(), f.carry_m() / kMetresPerYard, f.apex_m(),
      f.flight_time_s(), f.landing_angle_deg(), f.landing_speed_mps(), std::abs(f.lateral_m()),
      f.lateral_m() >= 0 ? "right" : "left");
  return out;
}

int RunSimulate(const Context& ctx, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("flight simulate takes flags only, got '" + args[0] + "'");
  v1::SimulateFlightRequest request;
  if (auto bad = BuildRequest(&request)) return UsageError(*bad);
  auto stub = v1::Swing::NewStub(ctx.channel);
  v1::SimulateFlightResponse response;
  const grpc::Status status = stub->SimulateFlight(ctx.NewCall().get(), request, &response);
  if (!status.ok()) return ReportRpcError(status);
  // The ball starts on the landing plane (z = 0): launched level or downward without the lift
  // to climb, it lands at once. Say so rather than print a bare carry of 0.
  if (response.flight_time_s() <= 0) {
    std::cerr << "sportsim: note: the ball landed at launch (flight 0 s, carry 0 m): it starts "
                 "on the ground (z = 0), and a launch angle of "
              << Num(request.launch().launch_angle_deg())
              << " deg does not take it up; give --launch-deg above 0\n";
  }
  if (const std::string svg = absl::GetFlag(FLAGS_svg); !svg.empty()) {
    const v1::LaunchConditions& l = request.launch();
    std::ofstream out(svg);
    out << FlightSvg(response, absl::StrFormat("%.1f m/s, launch %.1f deg, %.0f rpm, axis %.1f deg",
                                               l.ball_speed_mps(), l.launch_angle_deg(),
                                               l.spin_rpm(), l.spin_axis_deg()));
    if (!out) return UsageError("cannot write --svg file '" + svg + "'");
  }
  return PrintResponse(ctx, response, PrintCsv, PrintFlightText);
}

}  // namespace

int RunFlight(const Context& ctx, const std::vector<std::string>& args) {
  if (args.empty()) return UsageError("flight needs a subcommand: simulate");
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (args[0] == "simulate") return RunSimulate(ctx, rest);
  return UsageError("unknown flight subcommand '" + args[0] + "' (simulate)");
}

}  // namespace sportsim::cli
