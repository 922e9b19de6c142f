// `sportsim flight ...`
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/flags/declare.h"
#include "absl/flags/flag.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "client/cli.h"
#include "client/swing_flags.h"
#include "sportsim/v1/swing.grpc.pb.h"

// Shared with `swing simulate` (defined in swing_commands.cc).
ABSL_DECLARE_FLAG(std::optional<double>, dt);
ABSL_DECLARE_FLAG(std::vector<std::string>, disable);

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

int RunSimulate(const Context& ctx, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("flight simulate takes flags only, got '" + args[0] + "'");
  v1::SimulateFlightRequest request;
  if (auto bad = BuildRequest(&request)) return UsageError(*bad);
  auto stub = v1::Swing::NewStub(ctx.channel);
  v1::SimulateFlightResponse response;
  const grpc::Status status = stub->SimulateFlight(ctx.NewCall().get(), request, &response);
  if (!status.ok()) return ReportRpcError(status);
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
