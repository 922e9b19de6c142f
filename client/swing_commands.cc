// `sportsim swing ...`
#include <cstdio>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/flags/declare.h"
#include "absl/flags/flag.h"
#include "absl/strings/str_split.h"
#include "client/cli.h"
#include "client/command_flags.h"
#include "client/swing_flags.h"
#include "sportsim/v1/swing.grpc.pb.h"

ABSL_DECLARE_FLAG(std::string, fairway);  // golf_commands.cc
ABSL_FLAG(std::string, integrator, "rk4", "Swing integrator: book|euler|semi_implicit_euler|rk4|dp45");
ABSL_FLAG(std::optional<double>, dt, std::nullopt, "Fixed step (s); default 0.0025");
ABSL_FLAG(std::optional<double>, tolerance, std::nullopt, "dp45 tolerance; default 1e-8");
ABSL_FLAG(std::optional<double>, max_step, std::nullopt, "dp45 largest step (s); default 0.01");
ABSL_FLAG(std::optional<double>, duration, std::nullopt,
          "Run length (s) for --until duration (default 0.5), cap for --until impact (default 2)");
ABSL_FLAG(std::string, until, "impact", "Stop at: impact or duration");
ABSL_FLAG(std::optional<double>, qalpha, std::nullopt, "Shoulder torque (N m), constant; default 100");
ABSL_FLAG(std::optional<double>, qbeta, std::nullopt, "Wrist torque (N m) until --qbeta-until, then 0; default -10");
ABSL_FLAG(std::optional<double>, qbeta_until, std::nullopt, "When the wrist torque stops (s); default 0.1");
ABSL_FLAG(std::optional<double>, shoulder_accel, std::nullopt, "Shoulder acceleration toward the target (m/s^2); default 0.98");
ABSL_FLAG(std::optional<double>, gamma, std::nullopt, "Arm angle at the top of the backswing (deg); default 135");
ABSL_FLAG(std::optional<double>, beta0, std::nullopt, "Initial wrist cock (deg); default 120");
ABSL_FLAG(std::optional<double>, arm_length, std::nullopt, "Arm length R, shoulder to wrists (m); default 0.62");
ABSL_FLAG(std::optional<double>, club_length, std::nullopt, "Club length L, wrists to clubhead (m); default 1.1");
ABSL_FLAG(std::optional<double>, arm_inertia, std::nullopt, "Arm moment of inertia about the shoulder (kg m^2); default 1.15");
ABSL_FLAG(std::optional<double>, arm_first_moment, std::nullopt, "Arm first moment about the shoulder (kg m); default 2.263");
ABSL_FLAG(std::optional<double>, club_inertia, std::nullopt, "Club moment of inertia about the wrists (kg m^2); default 0.08");
ABSL_FLAG(std::optional<double>, club_mass, std::nullopt, "Club mass (kg); default 0.4");
ABSL_FLAG(std::optional<double>, club_first_moment, std::nullopt, "Club first moment about the wrists (kg m); default 0.33");
ABSL_FLAG(std::optional<double>, gravity, std::nullopt, "Gravity (m/s^2); default 9.8");
ABSL_FLAG(std::vector<std::string>, disable, {}, "Effects to switch off (swing: gravity,shoulder_accel,wrist_torque; shot: see info)");
ABSL_FLAG(std::string, club, "",
          "swing simulate, swing create: launch a ball at the impact with this club (driver, 3-wood, 3-iron, "
          "5-iron, 7-iron, 9-iron, pitching-wedge, sand-wedge) and fly it (flight's air flags)");
ABSL_FLAG(std::optional<double>, dynamic_loft_deg, std::nullopt,
          "With --club: face loft at impact (deg); default the club's static loft");
ABSL_FLAG(double, face_angle_deg, 0.0, "With --club: face angle (deg), + open (right)");
ABSL_FLAG(double, club_path_deg, 0.0, "With --club: club path (deg), + in-to-out (right)");
ABSL_FLAG(std::optional<double>, cor, std::nullopt,
          "With --club: coefficient of restitution; default the club's (0.83)");
ABSL_FLAG(int, stride, 0, "Keep every n-th step as a sample (0: automatic)");

namespace sportsim::cli {
namespace {

std::optional<v1::SwingIntegrator> IntegratorFromName(const std::string& name) {
  if (name == "book") return v1::SWING_INTEGRATOR_BOOK;
  if (name == "euler") return v1::SWING_INTEGRATOR_EULER;
  if (name == "semi_implicit_euler") return v1::SWING_INTEGRATOR_SEMI_IMPLICIT_EULER;
  if (name == "rk4") return v1::SWING_INTEGRATOR_RK4;
  if (name == "dp45") return v1::SWING_INTEGRATOR_DP45;
  return std::nullopt;
}

}  // namespace

std::optional<std::string> BuildSwingSolver(v1::SwingSolver* solver) {
  const std::optional<v1::SwingIntegrator> integrator =
      IntegratorFromName(absl::GetFlag(FLAGS_integrator));
  if (!integrator) {
    return "--integrator must be book, euler, semi_implicit_euler, rk4 or dp45, got '" +
           absl::GetFlag(FLAGS_integrator) + "'";
  }
  solver->set_integrator(*integrator);
  if (auto v = absl::GetFlag(FLAGS_dt)) solver->set_dt_s(*v);
  if (auto v = absl::GetFlag(FLAGS_tolerance)) solver->set_tolerance(*v);
  if (auto v = absl::GetFlag(FLAGS_max_step)) solver->set_max_step_s(*v);
  return std::nullopt;
}

std::optional<std::string> BuildSwingStop(v1::SwingStop* stop, std::optional<double>* duration_s) {
  const std::string until = absl::GetFlag(FLAGS_until);
  if (until == "impact") *stop = v1::SWING_STOP_IMPACT;
  else if (until == "duration") *stop = v1::SWING_STOP_DURATION;
  else return "--until must be impact or duration, got '" + until + "'";
  *duration_s = absl::GetFlag(FLAGS_duration);
  return std::nullopt;
}

std::optional<std::string> BuildSwingParameters(v1::SwingParameters* p) {
  if (auto v = absl::GetFlag(FLAGS_shoulder_accel)) p->set_shoulder_accel_mps2(*v);
  if (auto v = absl::GetFlag(FLAGS_gamma)) p->set_gamma_deg(*v);
  if (auto v = absl::GetFlag(FLAGS_beta0)) p->set_beta0_deg(*v);
  if (auto v = absl::GetFlag(FLAGS_arm_length)) p->set_arm_length_m(*v);
  if (auto v = absl::GetFlag(FLAGS_club_length)) p->set_club_length_m(*v);
  if (auto v = absl::GetFlag(FLAGS_arm_inertia)) p->set_arm_inertia_kgm2(*v);
  if (auto v = absl::GetFlag(FLAGS_arm_first_moment)) p->set_arm_first_moment_kgm(*v);
  if (auto v = absl::GetFlag(FLAGS_club_inertia)) p->set_club_inertia_kgm2(*v);
  if (auto v = absl::GetFlag(FLAGS_club_mass)) p->set_club_mass_kg(*v);
  if (auto v = absl::GetFlag(FLAGS_club_first_moment)) p->set_club_first_moment_kgm(*v);
  if (auto v = absl::GetFlag(FLAGS_gravity)) p->set_gravity_mps2(*v);
  return std::nullopt;
}

std::optional<std::string> BuildTorqueProgram(v1::TorqueProgram* torques) {
  const auto qa = absl::GetFlag(FLAGS_qalpha);
  const auto qb = absl::GetFlag(FLAGS_qbeta);
  const auto qb_until = absl::GetFlag(FLAGS_qbeta_until);
  if (qb_until && !(*qb_until > 0)) return InvalidValue("--qbeta-until must be a time after 0 s");
  if (!qa && !qb && !qb_until) return std::nullopt;
  v1::TorqueKnot* k = torques->mutable_qalpha()->add_knots();
  k->set_t_s(0);
  k->set_torque_nm(qa.value_or(100.0));
  v1::TorqueSchedule* b = torques->mutable_qbeta();
  b->add_knots()->set_torque_nm(qb.value_or(-10.0));
  v1::TorqueKnot* off = b->add_knots();
  off->set_t_s(qb_until.value_or(0.1));
  off->set_torque_nm(0.0);
  return std::nullopt;
}

std::optional<std::string> BuildSwingEffects(std::vector<v1::SwingEffect>* disabled) {
  for (const std::string& e : absl::GetFlag(FLAGS_disable)) {
    if (e == "gravity") disabled->push_back(v1::SWING_EFFECT_GRAVITY);
    else if (e == "shoulder_accel") disabled->push_back(v1::SWING_EFFECT_SHOULDER_ACCEL);
    else if (e == "wrist_torque") disabled->push_back(v1::SWING_EFFECT_WRIST_TORQUE);
    else return "--disable takes gravity, shoulder_accel, wrist_torque; got '" + e + "'";
  }
  return std::nullopt;
}

std::optional<std::string> BuildBallStrike(v1::BallStrike* b) {
  const std::string club = absl::GetFlag(FLAGS_club);
  if (club.empty()) {
    if (FlagGiven("club")) return "--club: needs a club preset (driver, 7-iron, ...)";
    // The ball's own flags and the air it flies through mean nothing without a ball.
    for (const char* flag : {"dynamic_loft_deg", "face_angle_deg", "club_path_deg", "cor",
                             "wind", "temperature_c", "pressure_pa", "humidity", "altitude_m",
                             "aero", "sample_interval", "fairway"}) {
      if (FlagGiven(flag)) return Dashed(flag) + ": describes the ball: give --club too";
    }
    return std::nullopt;
  }
  b->set_club(club);
  if (auto v = absl::GetFlag(FLAGS_dynamic_loft_deg)) b->set_dynamic_loft_deg(*v);
  b->set_face_angle_deg(absl::GetFlag(FLAGS_face_angle_deg));
  b->set_club_path_deg(absl::GetFlag(FLAGS_club_path_deg));
  if (auto v = absl::GetFlag(FLAGS_cor)) b->set_cor(*v);
  v1::SimulateFlightRequest air;
  if (auto bad = BuildFlightAir(&air)) return bad;
  *b->mutable_atmosphere() = air.atmosphere();
  *b->mutable_wind() = air.wind();
  b->set_aero_fit(air.aero_fit());
  if (air.has_sample_interval_s()) b->set_sample_interval_s(air.sample_interval_s());
  b->set_fairway(absl::GetFlag(FLAGS_fairway));
  return std::nullopt;
}

std::optional<double> ArmLengthFlag() { return absl::GetFlag(FLAGS_arm_length); }
std::optional<double> ClubLengthFlag() { return absl::GetFlag(FLAGS_club_length); }

std::string SwingCsvHeader() {
  return "t_s,theta_deg,alpha_deg,beta_deg,phi_deg,clubhead_speed_mps\n";
}

std::string SwingCsvRow(const v1::SwingSample& s) {
  return Num(s.t_s()) + ',' + Num(s.theta_deg()) + ',' + Num(s.alpha_deg()) + ',' +
         Num(s.beta_deg()) + ',' + Num(s.phi_deg()) + ',' + Num(s.clubhead_speed_mps()) + '\n';
}

namespace {

// Builds the request from the flags; returns a usage message on bad flags.
std::optional<std::string> BuildRequest(v1::SimulateSwingRequest* r) {
  if (auto bad = BuildSwingSolver(r->mutable_solver())) return bad;
  v1::SwingStop stop = v1::SWING_STOP_UNSPECIFIED;
  std::optional<double> duration;
  if (auto bad = BuildSwingStop(&stop, &duration)) return bad;
  r->set_stop(stop);
  if (duration) r->set_duration_s(*duration);
  if (auto bad = BuildSwingParameters(r->mutable_parameters())) return bad;
  v1::TorqueProgram torques;
  if (auto bad = BuildTorqueProgram(&torques)) return bad;
  if (torques.has_qalpha() || torques.has_qbeta()) *r->mutable_torques() = torques;
  std::vector<v1::SwingEffect> disabled;
  if (auto bad = BuildSwingEffects(&disabled)) return bad;
  for (v1::SwingEffect e : disabled) r->add_disabled_effects(e);
  const int stride = absl::GetFlag(FLAGS_stride);
  if (stride < 0) return InvalidValue("--stride must be >= 0");
  r->set_sample_stride(static_cast<uint32_t>(stride));
  if (auto bad = BuildBallStrike(r->mutable_ball())) return bad;
  if (r->ball().club().empty()) r->clear_ball();
  return std::nullopt;
}

void PrintText(const v1::SimulateSwingResponse& r) {
  if (r.has_impact()) {
    const v1::SwingImpact& i = r.impact();
    std::printf(
        "impact at t = %.9f s\n"
        "  clubhead speed  %.4f m/s relative to the shoulder, %.4f m/s over the ground\n"
        "  alpha %.4f deg  beta %.4f deg  theta %.4f deg\n"
        "  alpha_dot %.4f rad/s  beta_dot %.4f rad/s  direction %.2f deg above horizontal\n",
        i.t_s(), i.clubhead_speed_mps(), i.clubhead_speed_ground_mps(), i.alpha_deg(),
        i.beta_deg(), i.theta_deg(), i.alpha_dot_rps(), i.beta_dot_rps(),
        i.clubhead_direction_deg());
  } else {
    std::printf("no impact before t = %.6f s\n", r.end_t_s());
  }
  std::printf("%u steps (%u rejected), %u force evaluations, %d samples, %.3f ms CPU\n",
              r.steps(), r.rejected_steps(), r.rhs_evaluations(), r.samples_size(),
              r.cpu_s() * 1e3);
  if (r.has_ball()) {
    const v1::BallLaunch& b = r.ball();
    if (!b.error().empty()) {
      std::printf("ball (%s): not launched: %s\n", b.club().c_str(), b.error().c_str());
      return;
    }
    const v1::LaunchConditions& l = b.launch();
    std::printf(
        "ball (%s): %.2f m/s (smash %.3f), launch %.2f deg, direction %.2f deg, spin %.0f rpm "
        "(backspin %.0f, sidespin %.0f), spin loft %.2f deg, attack %.2f deg\n",
        b.club().c_str(), l.ball_speed_mps(), b.smash_factor(), l.launch_angle_deg(),
        l.launch_direction_deg(), l.spin_rpm(), b.backspin_rpm(), b.sidespin_rpm(),
        b.spin_loft_deg(), b.attack_angle_deg());
    PrintFlightText(b.flight());
  }
}

void PrintCsv(const v1::SimulateSwingResponse& r) {
  std::cout << SwingCsvHeader();
  for (const v1::SwingSample& s : r.samples()) std::cout << SwingCsvRow(s);
}

int RunSimulate(const Context& ctx, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("swing simulate takes flags only, got '" + args[0] + "'");
  v1::SimulateSwingRequest request;
  if (auto bad = BuildRequest(&request)) return UsageError(*bad);
  auto stub = v1::Swing::NewStub(ctx.channel);
  v1::SimulateSwingResponse response;
  const grpc::Status status = stub->SimulateSwing(ctx.NewCall().get(), request, &response);
  if (!status.ok()) return ReportRpcError(status);
  return PrintResponse(ctx, response, PrintCsv, PrintText);
}

}  // namespace

int RunSwing(const Context& ctx, const std::vector<std::string>& args) {
  static constexpr const char* kVerbs =
      "simulate, create, list, get, delete, reset, start, watch, drive";
  if (args.empty()) return UsageError(std::string("swing needs a subcommand: ") + kVerbs);
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  const std::string& verb = args[0];
  if (verb == "simulate") return RunSimulate(ctx, rest);
  if (verb == "create" || verb == "list" || verb == "get" || verb == "delete" ||
      verb == "reset" || verb == "start" || verb == "watch" || verb == "drive") {
    return RunSwingSession(ctx, verb, rest);
  }
  return UsageError("unknown swing subcommand '" + verb + "' (" + kVerbs + ")");
}

}  // namespace sportsim::cli
