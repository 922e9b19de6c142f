// `sportsim round create|list|get|delete|stroke|decide|watch|scorecard|record`: rounds of golf
// on a course (Swing/CreateRound ... WatchRound, GetRoundRecord).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/flags/declare.h"
#include "absl/flags/flag.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "client/cli.h"
#include "client/command_flags.h"
#include "client/swing_flags.h"
#include "sportsim/v1/swing.grpc.pb.h"

// Shared with golf simulate (golf_commands.cc), flight simulate, the table and swing commands.
ABSL_DECLARE_FLAG(std::string, course);
ABSL_DECLARE_FLAG(std::optional<double>, ball_speed);
ABSL_DECLARE_FLAG(std::optional<double>, launch_deg);
ABSL_DECLARE_FLAG(std::optional<double>, spin_rpm);
ABSL_DECLARE_FLAG(double, spin_axis_deg);
ABSL_DECLARE_FLAG(double, launch_direction_deg);
ABSL_DECLARE_FLAG(std::optional<double>, aim_deg);
ABSL_DECLARE_FLAG(std::optional<double>, putt_speed);
ABSL_DECLARE_FLAG(double, putt_direction_deg);
ABSL_DECLARE_FLAG(bool, flagstick);
ABSL_DECLARE_FLAG(std::string, token);
ABSL_DECLARE_FLAG(std::string, choice);
ABSL_DECLARE_FLAG(double, tick_hz);
ABSL_DECLARE_FLAG(std::optional<double>, rate);
ABSL_DECLARE_FLAG(std::optional<uint64_t>, from_sequence);
ABSL_DECLARE_FLAG(bool, until_rest);
ABSL_DECLARE_FLAG(int, page_size);
ABSL_DECLARE_FLAG(std::string, page_token);
ABSL_DECLARE_FLAG(std::string, profile);
ABSL_DECLARE_FLAG(double, noise);
ABSL_DECLARE_FLAG(uint64_t, seed);
ABSL_DECLARE_FLAG(std::optional<double>, shot_clock);
ABSL_DECLARE_FLAG(std::string, club);
ABSL_DECLARE_FLAG(std::optional<double>, dynamic_loft_deg);
ABSL_DECLARE_FLAG(double, face_angle_deg);
ABSL_DECLARE_FLAG(double, club_path_deg);

ABSL_FLAG(std::string, holes, "", "round create: the holes played, A-B (default all)");
ABSL_FLAG(std::vector<std::string>, players, {}, "round create: the players' names, in seat order");
ABSL_FLAG(std::vector<std::string>, tees, {}, "round create: each player's tee, in seat order");
ABSL_FLAG(std::string, play, "stroke", "round create: the form of play (stroke, match, stableford)");
ABSL_FLAG(std::vector<std::string>, handicaps, {},
          "round create: each player's Handicap Index in seat order (+X: a plus handicap; -: none)");
ABSL_FLAG(std::string, device, "", "round monitor: the launch monitor's Open Connect DeviceID");
ABSL_FLAG(bool, fast_forward, false, "round create: each stroke comes to rest at the next tick");
ABSL_FLAG(std::optional<double>, back_m, std::nullopt,
          "round decide: back-on-the-line, metres behind the reference point");

namespace sportsim::cli {
namespace {

using Stub = v1::Swing::Stub;
constexpr double kMetresPerYard = 0.9144;

template <typename Response>
int Print(const Context& ctx, const Response& r, const std::function<void()>& text) {
  return PrintResponse(ctx, r, [](const Response&) {}, [&](const Response&) { text(); });
}

std::string Lie(const std::string& tag) {
  if (tag == "water_hazard") return "in the water (a yellow penalty area)";
  if (tag == "lateral_water_hazard") return "in the water (a red penalty area)";
  if (tag == "out_of_bounds") return "out of bounds";
  if (tag == "green") return "on the green";
  if (tag == "tee") return "on the tee";
  if (tag == "first_cut") return "in the first cut";
  if (tag == "cartpath") return "on the cart path";
  return "in the " + tag;
}

std::string ToPar(int d) {
  if (d == 0) return "level";
  return absl::StrFormat("%+d", d);
}

// The round in plain words: the hole, whose turn, each ball, the scores.
void PrintRound(const v1::RoundState& r) {
  std::printf("%s, hole %u of %u-%u (par %u)", r.course().c_str(), r.hole(), r.first_hole(),
              r.last_hole(), r.par());
  if (!r.result().empty() && r.play() == "match") {
    std::printf(": the match is over: %s\n", r.match_status().c_str());
  } else if (!r.result().empty()) {
    std::string who;
    for (uint32_t w : r.winners()) {
      if (!who.empty()) who += " and ";
      who += r.players(w).name();
    }
    const v1::RoundPlayerState& best = r.players(r.winners(0));
    const std::string with =
        r.play() == "stableford" ? absl::StrFormat("%u points", best.points_total())
        : r.handicaps()          ? absl::StrFormat("net %d", best.net_total())
                                 : absl::StrFormat("%u", best.total());
    std::printf(": the round is %s; %s %s with %s\n", r.result().c_str(), who.c_str(),
                r.winners_size() > 1 ? "tie" : "wins", with.c_str());
  } else if (r.stroke_in_play()) {
    std::printf(": a ball is moving\n");
  } else if (r.has_decision()) {
    const v1::RoundDecision& d = r.decision();
    std::printf(": %s must decide (%s): %s\n", r.players(d.seat()).name().c_str(),
                d.reason() == "penalty_area" ? "ball in a penalty area, Rule 17.1d"
                                             : "ball declared unplayable, Rule 19",
                absl::StrJoin(d.choices(), ", ").c_str());
  } else if (r.to_play() >= 0) {
    std::printf(": %s to play\n", r.players(r.to_play()).name().c_str());
  } else {
    std::printf("\n");
  }
  if (r.play() == "match" && r.result().empty()) std::printf("  match: %s\n", r.match_status().c_str());
  for (const v1::RoundPlayerState& p : r.players()) {
    const v1::RoundBall& b = p.ball();
    std::string ball;
    if (b.holed()) {
      ball = absl::StrFormat("holed in %u", p.strokes());
    } else if (b.picked_up()) {
      ball = absl::StrFormat("picked up after %u stroke%s", p.strokes(), p.strokes() == 1 ? "" : "s");
    } else {
      ball = absl::StrFormat("%u stroke%s, %.1f m (%.0f yd) from the pin, %s%s", p.strokes(),
                             p.strokes() == 1 ? "" : "s", b.distance_to_pin_m(),
                             b.distance_to_pin_m() / kMetresPerYard, Lie(b.lie()).c_str(),
                             b.marked() ? " (marked)" : "");
    }
    std::printf("  seat %u %-12s %-60s score %u (%s after %d hole%s)\n", p.seat(),
                p.name().c_str(), ball.c_str(), p.score(), ToPar(p.to_par()).c_str(),
                static_cast<int>(std::count_if(p.scores().begin(), p.scores().end(),
                                               [](uint32_t v) { return v > 0; })),
                std::count_if(p.scores().begin(), p.scores().end(),
                              [](uint32_t v) { return v > 0; }) == 1
                    ? ""
                    : "s");
    if (r.handicaps()) {
      std::printf("  %21s playing handicap %d, net %d\n", "", p.playing_handicap(), p.net_total());
    }
    if (r.play() == "stableford") std::printf("  %21s %u Stableford points\n", "", p.points_total());
  }
}

std::optional<std::string> Need(const std::string& token, std::string_view what) {
  if (token.empty()) return std::string(what) + " needs --token";
  return std::nullopt;
}

int RunCreate(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("round create takes flags only, got '" + args[0] + "'");
  v1::CreateRoundRequest request;
  if (FlagGiven("course")) request.set_course(absl::GetFlag(FLAGS_course));
  if (const std::string holes = absl::GetFlag(FLAGS_holes); !holes.empty()) {
    const std::vector<std::string> ab = absl::StrSplit(holes, '-');
    int a = 0, b = 0;
    if (ab.size() > 2 || !absl::SimpleAtoi(ab[0], &a) ||
        !absl::SimpleAtoi(ab.size() == 2 ? ab[1] : ab[0], &b) || a < 1 || b < a) {
      return UsageError("--holes must be A-B (or A), 1 <= A <= B, got '" + holes.substr(0, 20) + "'");
    }
    request.set_first_hole(static_cast<uint32_t>(a));
    request.set_last_hole(static_cast<uint32_t>(b));
  }
  const std::vector<std::string> players = absl::GetFlag(FLAGS_players);
  if (players.empty()) return UsageError("round create needs --players NAME,NAME");
  const std::vector<std::string> tees = absl::GetFlag(FLAGS_tees);
  if (!tees.empty() && tees.size() != players.size()) {
    return UsageError(absl::StrFormat("--tees needs one tee per player (%d), got %d",
                                      players.size(), tees.size()));
  }
  for (size_t i = 0; i < players.size(); ++i) {
    v1::RoundPlayerSpec* p = request.add_players();
    p->set_name(players[i]);
    if (!tees.empty()) p->set_tee(tees[i]);
  }
  const std::string play = absl::GetFlag(FLAGS_play);
  if (play != "stroke" && play != "match" && play != "stableford") {
    return UsageError(InvalidValue("--play must be stroke, match or stableford, got '" +
                                   play.substr(0, 20) + "'"));
  }
  request.set_play(play);
  const std::vector<std::string> handicaps = absl::GetFlag(FLAGS_handicaps);
  if (!handicaps.empty() && handicaps.size() != players.size()) {
    return UsageError(absl::StrFormat("--handicaps needs one Handicap Index per player (%d), got %d",
                                      players.size(), handicaps.size()));
  }
  for (size_t i = 0; i < handicaps.size(); ++i) {
    const std::string& h = handicaps[i];
    if (h == "-" || h == "none") continue;
    double index = 0.0;
    // A plus handicap is written +2.1; the World Handicap System stores it as -2.1.
    const bool plus = !h.empty() && h[0] == '+';
    if (!absl::SimpleAtod(plus ? h.substr(1) : h, &index) || !std::isfinite(index)) {
      return UsageError(InvalidValue("--handicaps: '" + h.substr(0, 20) +
                                     "' is not a Handicap Index (e.g. 12.4, +2.1, or - for none)"));
    }
    request.mutable_players(static_cast<int>(i))->set_handicap_index(plus ? -std::abs(index) : index);
  }
  const std::string profile = absl::GetFlag(FLAGS_profile);
  if (profile == "realistic") request.set_profile(v1::REALISM_PROFILE_REALISTIC);
  else if (profile == "arcade") request.set_profile(v1::REALISM_PROFILE_ARCADE);
  else if (!profile.empty()) return UsageError("--profile must be realistic or arcade, got '" + profile + "'");
  request.set_noise(absl::GetFlag(FLAGS_noise));
  request.set_seed(absl::GetFlag(FLAGS_seed));
  for (const std::string& rule : RepeatedFlagValues("rule")) {
    const size_t eq = rule.find('=');
    if (eq == std::string::npos) return UsageError("--rule must be NAME=VALUE, got '" + rule.substr(0, 40) + "'");
    (*request.mutable_rules())[rule.substr(0, eq)] = rule.substr(eq + 1);
  }
  request.set_tick_hz(FlagGiven("tick_hz") ? absl::GetFlag(FLAGS_tick_hz) : 0.0);
  request.set_fast_forward(absl::GetFlag(FLAGS_fast_forward));
  if (auto c = absl::GetFlag(FLAGS_shot_clock)) request.set_shot_clock_s(*c);
  v1::CreateRoundResponse r;
  const grpc::Status status = stub.CreateRound(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("round %s: %s holes %u-%u, %g Hz%s\n", r.round_id().c_str(),
                r.round().course().c_str(), r.round().first_hole(), r.round().last_hole(),
                r.tick_hz(), request.fast_forward() ? ", fast-forward" : "");
    for (const v1::Seat& s : r.seats()) {
      std::printf("  seat %u %-12s token %s\n", s.seat(), s.name().c_str(), s.token().c_str());
    }
    std::printf("  admin token %s\n", r.admin_token().c_str());
    PrintRound(r.round());
  });
}

int RunGet(const Context& ctx, Stub& stub, const std::vector<std::string>& args, bool scorecard) {
  if (args.size() != 1) return UsageError(scorecard ? "round scorecard ID" : "round get ID");
  v1::GetRoundRequest request;
  request.set_round_id(args[0]);
  v1::RoundInfo r;
  const grpc::Status status = stub.GetRound(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  if (!scorecard) {
    return Print(ctx, r, [&] {
      std::printf("round %s, tick %lld at %g Hz, %u watchers\n", r.round_id().c_str(),
                  static_cast<long long>(r.tick()), r.tick_hz(), r.watchers());
      PrintRound(r.round());
    });
  }
  // The scorecard: per player the holes' scores, the total and against par.
  v1::RoundState card = r.round();
  return Print(ctx, card, [&] {
    std::printf("%-12s", "hole");
    for (uint32_t h = card.first_hole(); h <= card.last_hole(); ++h) std::printf(" %3u", h);
    std::printf("  total  par\n");
    for (const v1::RoundPlayerState& p : card.players()) {
      std::printf("%-12s", p.name().c_str());
      for (int h = 0; h < p.scores_size(); ++h) {
        if (h < p.no_score_size() && p.no_score(h)) std::printf("   x");
        else if (p.scores(h) == 0) std::printf("   -");
        else std::printf(" %3u", p.scores(h));
      }
      std::printf("  %5u  %s\n", p.total(), ToPar(p.to_par()).c_str());
      if (card.handicaps()) {
        std::printf("%-12s", "  received");
        for (int v : p.received()) std::printf(" %3d", v);
        std::printf("  net %d (playing handicap %d)\n", p.net_total(), p.playing_handicap());
      }
      if (card.play() == "stableford") {
        std::printf("%-12s", "  points");
        for (uint32_t v : p.points()) std::printf(" %3u", v);
        std::printf("  %5u\n", p.points_total());
      }
    }
    if (card.play() == "match") {
      std::printf("%-12s", "hole won by");
      for (int w : card.hole_winners()) {
        if (w == -2) std::printf("   -");
        else if (w == -1) std::printf("   =");
        else std::printf(" %3.3s", card.players(w).name().c_str());
      }
      std::printf("\n%s\n", card.match_status().c_str());
    }
  });
}

int RunList(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("round list takes flags only");
  if (auto bad = CheckPageSize()) return UsageError(*bad);
  v1::ListRoundsRequest request;
  request.set_page_size(static_cast<uint32_t>(absl::GetFlag(FLAGS_page_size)));
  request.set_page_token(absl::GetFlag(FLAGS_page_token));
  v1::ListRoundsResponse r;
  const grpc::Status status = stub.ListRounds(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("%u rounds\n", r.total());
    for (const v1::RoundBrief& b : r.rounds()) {
      std::printf("  %-16s %-16s hole %-3u %-10s %s\n", b.round_id().c_str(), b.course().c_str(),
                  b.hole(), b.result().empty() ? "playing" : b.result().c_str(),
                  absl::StrJoin(b.players(), ", ").c_str());
    }
    if (!r.next_page_token().empty()) std::printf("more: --page-token %s\n", r.next_page_token().c_str());
  });
}

int RunDelete(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("round delete ID --token T");
  v1::DeleteRoundRequest request;
  request.set_round_id(args[0]);
  request.set_token(absl::GetFlag(FLAGS_token));
  if (auto bad = Need(request.token(), "round delete (the admin token)")) return UsageError(*bad);
  v1::DeleteRoundResponse r;
  const grpc::Status status = stub.DeleteRound(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] { std::printf("deleted %s\n", args[0].c_str()); });
}

int RunStroke(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("round stroke ID --token T (a launch or --putt-speed)");
  v1::PlayStrokeRequest request;
  request.set_round_id(args[0]);
  request.set_token(absl::GetFlag(FLAGS_token));
  if (auto bad = Need(request.token(), "round stroke (the seat's token)")) return UsageError(*bad);
  const auto speed = absl::GetFlag(FLAGS_ball_speed);
  const auto putt = absl::GetFlag(FLAGS_putt_speed);
  const std::string club = absl::GetFlag(FLAGS_club);
  if ((speed ? 1 : 0) + (putt ? 1 : 0) + (club.empty() ? 0 : 1) != 1) {
    return UsageError("round stroke needs one stroke: a launch (--ball-speed --launch-deg "
                      "--spin-rpm), a putt (--putt-speed) or a swing (--club NAME)");
  }
  if (club.empty()) {
    for (const char* f : {"qalpha", "qbeta", "qbeta_until", "dynamic_loft_deg", "face_angle_deg",
                          "club_path_deg", "gamma", "beta0", "arm_length", "club_length",
                          "arm_inertia", "arm_first_moment", "club_inertia", "club_mass",
                          "club_first_moment", "gravity", "shoulder_accel"}) {
      if (FlagGiven(f)) return UsageError(Dashed(f) + " describes a swing: give --club too");
    }
  }
  if (!club.empty()) {
    v1::RoundSwing* w = request.mutable_swing();
    w->set_club(club);
    if (auto v = absl::GetFlag(FLAGS_dynamic_loft_deg)) w->set_dynamic_loft_deg(*v);
    w->set_face_angle_deg(absl::GetFlag(FLAGS_face_angle_deg));
    w->set_club_path_deg(absl::GetFlag(FLAGS_club_path_deg));
    v1::TorqueProgram torques;
    if (auto bad = BuildTorqueProgram(&torques)) return UsageError(*bad);
    if (torques.has_qalpha() || torques.has_qbeta()) *w->mutable_torques() = torques;
    if (auto bad = BuildSwingParameters(w->mutable_parameters())) return UsageError(*bad);
    if (FlagGiven("putt_direction_deg")) return UsageError("--putt-direction-deg is a putt's; a swing takes --aim-deg");
    if (auto a = absl::GetFlag(FLAGS_aim_deg)) request.set_aim_deg(*a);
  } else if (speed) {
    const auto launch = absl::GetFlag(FLAGS_launch_deg);
    const auto spin = absl::GetFlag(FLAGS_spin_rpm);
    if (!launch || !spin) return UsageError("a launch needs --ball-speed, --launch-deg and --spin-rpm");
    v1::LaunchConditions* l = request.mutable_launch();
    l->set_ball_speed_mps(*speed);
    l->set_launch_angle_deg(*launch);
    l->set_spin_rpm(*spin);
    l->set_spin_axis_deg(absl::GetFlag(FLAGS_spin_axis_deg));
    l->set_launch_direction_deg(absl::GetFlag(FLAGS_launch_direction_deg));
    if (FlagGiven("putt_direction_deg")) return UsageError("--putt-direction-deg is a putt's; a launch takes --aim-deg");
    if (auto a = absl::GetFlag(FLAGS_aim_deg)) request.set_aim_deg(*a);
  } else {
    request.set_putt_speed_mps(*putt);
    if (FlagGiven("aim_deg")) return UsageError("a putt's heading is --putt-direction-deg (default toward the pin)");
    if (FlagGiven("putt_direction_deg")) request.set_aim_deg(absl::GetFlag(FLAGS_putt_direction_deg));
  }
  // The flagstick stays in unless --flagstick=false.
  request.set_flagstick_out(FlagGiven("flagstick") && !absl::GetFlag(FLAGS_flagstick));
  v1::PlayStrokeResponse r;
  const grpc::Status status = stub.PlayStroke(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("stroke %llu struck at tick %lld; the ball comes to rest at tick %lld\n",
                static_cast<unsigned long long>(r.stroke()), static_cast<long long>(r.start_tick()),
                static_cast<long long>(r.rest_tick()));
  });
}

int RunDecide(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("round decide ID --token T --choice CHOICE");
  v1::DecideRoundRequest request;
  request.set_round_id(args[0]);
  request.set_token(absl::GetFlag(FLAGS_token));
  if (auto bad = Need(request.token(), "round decide (the seat's token)")) return UsageError(*bad);
  request.set_choice(absl::GetFlag(FLAGS_choice));
  if (request.choice().empty()) {
    return UsageError("round decide needs --choice: one of the decision's choices, or unplayable");
  }
  if (auto b = absl::GetFlag(FLAGS_back_m)) request.set_back_m(*b);
  v1::DecideRoundResponse r;
  const grpc::Status status = stub.DecideRound(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] { PrintRound(r.round()); });
}

// `round concede` (match play) and `round pickup`: the DecideRound choices that are not relief.
int RunConcede(const Context& ctx, Stub& stub, const std::vector<std::string>& args, bool pickup) {
  if (args.size() != 1) {
    return UsageError(pickup ? "round pickup ID --token T"
                             : "round concede ID --token T [--stroke | --hole | --match]");
  }
  v1::DecideRoundRequest request;
  request.set_round_id(args[0]);
  request.set_token(absl::GetFlag(FLAGS_token));
  if (auto bad = Need(request.token(), pickup ? "round pickup (the seat's token)"
                                              : "round concede (the conceding seat's token)")) {
    return UsageError(*bad);
  }
  const std::vector<std::string>& words = WordFlags();
  if (words.size() > 1) return UsageError("round concede takes one of --stroke, --hole, --match");
  request.set_choice(pickup ? "pick_up" : "concede_" + (words.empty() ? std::string("stroke") : words[0]));
  v1::DecideRoundResponse r;
  const grpc::Status status = stub.DecideRound(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] { PrintRound(r.round()); });
}

// `round monitor`: binds a launch monitor's Open Connect DeviceID to the seat.
int RunMonitor(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("round monitor ID --token T --device DEVICE_ID");
  v1::BindMonitorRequest request;
  request.set_round_id(args[0]);
  request.set_token(absl::GetFlag(FLAGS_token));
  if (auto bad = Need(request.token(), "round monitor (the seat's token)")) return UsageError(*bad);
  request.set_device_id(absl::GetFlag(FLAGS_device));
  if (request.device_id().empty()) {
    return UsageError("round monitor needs --device: the DeviceID the monitor's connector sends");
  }
  v1::BindMonitorResponse r;
  const grpc::Status status = stub.BindMonitor(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("device %s plays seat %u: point its Open Connect connector at %s\n",
                request.device_id().c_str(), r.seat(), r.listen().c_str());
  });
}

int RunRecord(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("round record ID");
  v1::GetRoundRecordRequest request;
  request.set_round_id(args[0]);
  v1::RoundRecord r;
  const grpc::Status status = stub.GetRoundRecord(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("round %s on %s: %d commands\n", r.round_id().c_str(), r.round().course().c_str(),
                r.commands_size());
    for (const v1::RoundCommand& c : r.commands()) {
      const std::string who = c.seat() >= 0 && c.seat() < r.round().players_size()
                                  ? r.round().players(c.seat()).name()
                                  : "admin";
      if (c.has_stroke()) {
        const v1::PlayStrokeRequest& s = c.stroke();
        if (s.has_launch()) {
          std::printf("  tick %-8lld %-12s launch %.2f m/s, %.1f deg up, %.0f rpm%s\n",
                      static_cast<long long>(c.tick()), who.c_str(), s.launch().ball_speed_mps(),
                      s.launch().launch_angle_deg(), s.launch().spin_rpm(),
                      s.has_aim_deg() ? absl::StrFormat(", aim %.2f deg", s.aim_deg()).c_str() : "");
        } else {
          std::printf("  tick %-8lld %-12s putt %.3f m/s%s\n", static_cast<long long>(c.tick()),
                      who.c_str(), s.putt_speed_mps(),
                      s.has_aim_deg() ? absl::StrFormat(", heading %.2f deg", s.aim_deg()).c_str() : "");
        }
      } else if (c.has_decide()) {
        std::printf("  tick %-8lld %-12s decides %s\n", static_cast<long long>(c.tick()), who.c_str(),
                    c.decide().choice().c_str());
      } else if (c.shot_clock()) {
        std::printf("  tick %-8lld %-12s the shot clock ran out: a penalty stroke\n",
                    static_cast<long long>(c.tick()), who.c_str());
      }
    }
    PrintRound(r.round());
  });
}

// One line per snapshot with events or a state change; the ball's position while it moves.
int RunWatch(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("round watch ID [--rate HZ] [--until-rest] [--from-sequence N]");
  v1::WatchRoundRequest request;
  request.set_round_id(args[0]);
  if (auto v = absl::GetFlag(FLAGS_rate)) request.set_rate_hz(*v);
  if (auto v = absl::GetFlag(FLAGS_from_sequence)) request.set_from_sequence(*v);
  const bool until_rest = absl::GetFlag(FLAGS_until_rest);
  auto call = ctx.NewCall();
  std::unique_ptr<grpc::ClientReader<v1::RoundSnapshot>> reader = stub.WatchRound(call.get(), request);
  JsonArrayStream array(ctx.format == Format::kJson);
  v1::RoundSnapshot s;
  bool moving_seen = false;
  while (reader->Read(&s)) {
    if (ctx.format == Format::kJson) {
      array.Add(ToJson(s, true));
    } else if (ctx.format == Format::kJsonl) {
      std::cout << ToJson(s, true) << "\n" << std::flush;
    } else {
      for (const v1::RoundEvent& e : s.events()) {
        std::string who = e.seat() >= 0 && s.has_round() && e.seat() < s.round().players_size()
                              ? s.round().players(e.seat()).name() + ": "
                              : "";
        std::printf("tick %-8lld %s%s at (%.2f, %.2f)%s%s%s\n", static_cast<long long>(e.tick()),
                    who.c_str(), e.kind().c_str(), e.x_m(), e.y_m(),
                    e.lie().empty() ? "" : (" " + e.lie()).c_str(),
                    e.rule().empty() ? "" : (" (Rule " + e.rule() + ")").c_str(),
                    e.choices().empty() ? "" : (": " + absl::StrJoin(e.choices(), ", ")).c_str());
      }
      std::fflush(stdout);
    }
    if (s.has_ball()) moving_seen = true;
    if (until_rest && moving_seen && s.has_round() && !s.round().stroke_in_play()) break;
  }
  if (until_rest && moving_seen) {
    call->TryCancel();
    return 0;
  }
  const grpc::Status status = reader->Finish();
  if (!status.ok()) return ReportRpcError(status);
  return 0;
}

}  // namespace

int RunRound(const Context& ctx, const std::vector<std::string>& args) {
  static constexpr const char* kVerbs =
      "create, list, get, delete, stroke, decide, concede, pickup, monitor, watch, scorecard, record";
  if (args.empty()) return UsageError(std::string("round needs a subcommand: ") + kVerbs);
  const std::string& verb = args[0];
  if (ctx.format == Format::kCsv) return UsageError("round " + verb + " has no csv form (json or text)");
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  std::unique_ptr<Stub> stub = v1::Swing::NewStub(ctx.channel);
  if (verb == "create") return RunCreate(ctx, *stub, rest);
  if (verb == "list") return RunList(ctx, *stub, rest);
  if (verb == "get") return RunGet(ctx, *stub, rest, false);
  if (verb == "scorecard") return RunGet(ctx, *stub, rest, true);
  if (verb == "delete") return RunDelete(ctx, *stub, rest);
  if (verb == "stroke") return RunStroke(ctx, *stub, rest);
  if (verb == "decide") return RunDecide(ctx, *stub, rest);
  if (verb == "concede") return RunConcede(ctx, *stub, rest, false);
  if (verb == "pickup") return RunConcede(ctx, *stub, rest, true);
  if (verb == "monitor") return RunMonitor(ctx, *stub, rest);
  if (verb == "watch") return RunWatch(ctx, *stub, rest);
  if (verb == "record") return RunRecord(ctx, *stub, rest);
  return UsageError("unknown round subcommand '" + verb + "' (" + kVerbs + ")");
}

}  // namespace sportsim::cli
