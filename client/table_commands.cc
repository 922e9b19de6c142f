// `sportsim table ...`: authoritative tables (Billiards/CreateTable ... WatchTable).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/flags/declare.h"
#include "absl/flags/flag.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "client/billiards_flags.h"
#include "client/calibration_upload.h"
#include "client/cli.h"
#include "client/game_text.h"
#include "client/table_svg.h"
#include "client/track_json.h"
#include "sim/billiards/model.h"
#include "sim/billiards/track_file.h"
#include "sportsim/v1/billiards.grpc.pb.h"

ABSL_DECLARE_FLAG(std::string, svg);
ABSL_DECLARE_FLAG(double, noise);
ABSL_DECLARE_FLAG(uint64_t, seed);

ABSL_FLAG(int, seats, 0, "table/swing create: number of seats (table default 2, swing 1)");
ABSL_FLAG(std::vector<std::string>, seat_names, {}, "table/swing create: seat names, comma separated");
ABSL_FLAG(double, tick_hz, 0.0, "table/swing create: ticks per second (table default 120, swing 400)");
ABSL_FLAG(std::string, token, "", "The seat's token (table/swing create printed it)");
ABSL_FLAG(std::optional<int>, next_seat, std::nullopt, "table shoot: pass the turn to this seat");
ABSL_FLAG(std::optional<int>, seat, std::nullopt, "table turn: the seat to play next");
ABSL_FLAG(std::optional<int>, frame, std::nullopt,
          "table concede: the frame conceded (default: the table's frame, read first)");
ABSL_FLAG(std::optional<double>, rate, std::nullopt,
          "table/swing watch, swing drive: snapshots per second at most (0, or above the tick "
          "rate: every tick); default 30 for tables, every tick for swings");
ABSL_FLAG(bool, until_rest, false,
          "table watch: exit when the table comes to rest after a shot: at the end of the shot "
          "in progress, or, when the table is at rest, at the end of the next shot");
ABSL_FLAG(std::vector<std::string>, fields, {},
          "table watch: position,velocity,spin,orientation (default all)");
ABSL_FLAG(bool, changed_only, false, "table watch: only the balls that changed");
ABSL_FLAG(std::optional<uint64_t>, from_sequence, std::nullopt,
          "table/swing watch: replay the events after this sequence, then go on");
ABSL_FLAG(int, page_size, 0, "table/swing list: tables or sessions per page (default 100)");
ABSL_FLAG(std::string, page_token, "", "table/swing list: the next_page_token of the previous page");
ABSL_FLAG(bool, geometry, false, "table get: include cushions and pockets");
// Games (ruled tables).
ABSL_FLAG(std::string, game, "",
          "table create: free (default), 8ball, 9ball, 10ball, snooker, three-cushion");
ABSL_FLAG(std::optional<int>, race_to, std::nullopt, "table create: frames to win the match (default 1)");
ABSL_FLAG(std::optional<double>, shot_clock, std::nullopt,
          "table create: seconds of table time per shot (0 = off, the default)");
ABSL_FLAG(std::string, start, "", "table create: break (default) or in-play");
ABSL_FLAG(std::string, aim_lines, "",
          "table create: on (default) or off: whether the seat to play may ask for aim lines "
          "(PreviewShot)");
ABSL_FLAG(std::string, call, "", "table shoot: the called ball and pocket, BALL:POCKET");
ABSL_FLAG(bool, safety, false, "table shoot: declare a safety");
ABSL_FLAG(bool, push_out, false, "table shoot: declare a push-out (9-ball, 10-ball)");
ABSL_FLAG(std::string, nominate, "", "table shoot: the nominated ball (snooker)");
ABSL_FLAG(std::string, choice, "", "table decide: one of the pending decision's choices");
ABSL_FLAG(std::vector<std::string>, fit, {},
          "table calibrate: the parameters to fit, NAME or NAME=LO:HI, comma separated");
ABSL_FLAG(std::vector<std::string>, heldout, {},
          "table calibrate: the shots held out of the fit (0-based, in the files' order), comma "
          "separated");
ABSL_FLAG(std::optional<double>, window, std::nullopt,
          "table calibrate: held-out shots' strikes from their first seconds only");
ABSL_FLAG(std::optional<int>, max_iterations, std::nullopt,
          "table calibrate: Levenberg-Marquardt iterations, [1, 1000] (default 60)");
ABSL_FLAG(std::optional<int64_t>, max_simulations, std::nullopt,
          "table calibrate: simulations in all, [1, 1e9] (default 5000000)");
ABSL_FLAG(std::string, cue_ball, "",
          "table calibrate: the struck ball in every file (default: the first ball to depart "
          "from its spot)");
ABSL_FLAG(bool, fit_elevation, false, "table calibrate: fit the cue's elevation too");
ABSL_FLAG(std::string, predict, "best-fit",
          "table calibrate: held-out shots fitted on a --window: best-fit (the strike that fits "
          "it best) or central (the plausible strikes' central rest)");
ABSL_FLAG(std::string, intent, "none",
          "table calibrate: what the held-out shots were meant to do, a prior for predictions "
          "from a --window: none, three-cushion (the UMB point) or pot (a ball pocketed, "
          "the struck ball kept up)");
ABSL_FLAG(bool, read_cloth, false,
          "table calibrate: read the cloth (rolling resistance, sliding friction) from the "
          "training shots' tracks and start from it");
ABSL_FLAG(std::optional<double>, huber, std::nullopt,
          "table calibrate: Huber's scale in metres, [0, 1], for trackers' false detections "
          "(default: squared distances)");
ABSL_FLAG(std::string, track_origin, "centre",
          "table calibrate: where the files' (0, 0) is: centre (the table frame) or corner (a "
          "corner of the playing area, x along its length)");
ABSL_FLAG(std::optional<double>, track_scale, std::nullopt,
          "table calibrate: metres per unit of the files' coordinates, (0, 1e6] (default 1)");

namespace sportsim::cli {
namespace {

using Stub = v1::Billiards::Stub;

// csv is refused before any call (RunTable), so these print json, jsonl or text.
template <typename Response>
int Print(const Context& ctx, const Response& r, const std::function<void()>& text) {
  return PrintResponse(ctx, r, [](const Response&) {}, [&](const Response&) { text(); });
}

std::string BallLine(const v1::BallState& b) {
  return absl::StrFormat("%-8s %9.4f %9.4f  %s%s%s", b.id(), b.x_m(), b.y_m(),
                         v1::MotionState_Name(b.state()), b.pocket().empty() ? "" : " in ",
                         b.pocket());
}

std::string SummaryLine(const v1::ShotSummary& s) {
  std::string line = absl::StrFormat(
      "shot %d by seat %d (%s): first hit %s, %d rails (%d after contact), pocketed [%s]%s, "
      "%.2f s, ticks %d-%d",
      s.shot_id(), s.seat(), s.struck_ball(),
      s.first_ball_hit().empty() ? "none" : s.first_ball_hit(), s.rails(),
      s.rails_after_contact(), absl::StrJoin(s.pocketed(), ", "),
      s.struck_ball_pocketed() ? ", struck ball pocketed" : "", s.duration_s(), s.start_tick(),
      s.end_tick());
  if (!s.error().empty()) line += " (stopped: " + s.error() + ")";
  if (s.has_call()) {
    const std::string call = CallText(s.call());
    if (!call.empty()) line += "; " + call;
  }
  if (s.has_verdict()) line += "; " + VerdictText(s.verdict(), s.seat());
  return line;
}

bool Given(std::string_view flag) { return FlagGiven(flag); }

// --game --race-to --shot-clock --start --rule ... --noise --seed: CreateTableRequest.game, set
// when any of them is given (unset: free play, as before games).
std::optional<std::string> BuildGame(v1::CreateTableRequest* request) {
  const std::vector<std::string>& rules = RepeatedFlagValues("rule");
  if (!Given("game") && !Given("race_to") && !Given("shot_clock") && !Given("start") &&
      rules.empty() && !Given("noise") && !Given("seed")) {
    return std::nullopt;
  }
  v1::GameConfig* g = request->mutable_game();
  g->set_name(absl::GetFlag(FLAGS_game));
  if (const auto race = absl::GetFlag(FLAGS_race_to)) {
    if (*race < 1) return InvalidValue("--race-to must be a number of frames, at least 1");
    g->set_race_to(static_cast<uint32_t>(*race));
  }
  if (const auto clock = absl::GetFlag(FLAGS_shot_clock)) {
    if (!(*clock >= 0)) return InvalidValue("--shot-clock must be seconds, 0 (off) or more");
    g->set_shot_clock_s(*clock);
  }
  const std::string start = absl::GetFlag(FLAGS_start);
  if (!start.empty() && start != "break" && start != "in-play") {
    return "--start must be break or in-play, got '" + start + "'";
  }
  g->set_start(start);
  for (const std::string& spec : rules) {
    const size_t eq = spec.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == spec.size()) {
      return "--rule must be NAME=VALUE, got '" + spec + "'";
    }
    const std::string name = spec.substr(0, eq);
    if (g->rules().contains(name)) return "--rule " + name + " given twice";
    (*g->mutable_rules())[name] = spec.substr(eq + 1);
  }
  g->set_noise(absl::GetFlag(FLAGS_noise));
  if (Given("seed")) g->set_seed(absl::GetFlag(FLAGS_seed));
  return std::nullopt;
}

int RunCreate(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("table create takes flags only, got '" + args[0] + "'");
  v1::CreateTableRequest request;
  if (auto bad = BuildSetup(request.mutable_table())) return UsageError(*bad);
  if (auto bad = BuildSolver(request.mutable_solver())) return UsageError(*bad);
  if (auto bad = CheckSeatFlags()) return UsageError(*bad);
  request.set_seats(static_cast<uint32_t>(absl::GetFlag(FLAGS_seats)));
  for (const std::string& n : absl::GetFlag(FLAGS_seat_names)) request.add_seat_names(n);
  request.set_tick_hz(absl::GetFlag(FLAGS_tick_hz));
  if (auto bad = BuildGame(&request)) return UsageError(*bad);
  if (Given("aim_lines")) {
    const std::string aim = absl::GetFlag(FLAGS_aim_lines);
    if (aim != "on" && aim != "off") return UsageError("--aim-lines must be on or off, got '" + aim + "'");
    request.set_aim_lines(aim == "on");
  }
  // A ruled game is played on its own table unless --table names one.
  if (request.has_game() && !Given("table")) request.mutable_table()->clear_preset();
  v1::CreateTableResponse r;
  const grpc::Status status = stub.CreateTable(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("table %s: %s engine%s, %g Hz\n", r.table_id().c_str(), r.engine().c_str(),
                r.dt_s() > 0 ? absl::StrFormat(" (dt %g s)", r.dt_s()).c_str() : "",
                r.tick_hz());
    for (const v1::Seat& s : r.seats()) {
      std::printf("  seat %u %-10s token %s\n", s.seat(), s.name().c_str(), s.token().c_str());
    }
    if (!r.admin_token().empty()) {
      std::printf("  admin         token %s\n", r.admin_token().c_str());
    }
    if (r.has_game()) {
      for (const std::string& line : GameLines(r.game(), nullptr)) {
        std::printf("  %s\n", line.c_str());
      }
    }
  });
}

int RunList(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("table list takes flags only");
  v1::ListTablesRequest request;
  if (auto bad = CheckPageSize()) return UsageError(*bad);
  request.set_page_size(static_cast<uint32_t>(absl::GetFlag(FLAGS_page_size)));
  request.set_page_token(absl::GetFlag(FLAGS_page_token));
  v1::ListTablesResponse r;
  const grpc::Status status = stub.ListTables(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("%d tables\n", r.total());
    for (const v1::TableBrief& t : r.tables()) {
      std::printf("  %-16s %-10s %-8s tick %-10lld %2u balls on, %u seats, %u watchers, %llu shots\n",
                  t.table_id().c_str(), t.preset().c_str(), t.at_rest() ? "at rest" : "moving",
                  static_cast<long long>(t.tick()), t.balls_on_table(), t.seats(), t.watchers(),
                  static_cast<unsigned long long>(t.shots()));
    }
    if (!r.next_page_token().empty()) {
      std::printf("more: --page-token %s\n", r.next_page_token().c_str());
    }
  });
}

int RunGet(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("table get ID");
  v1::GetTableRequest request;
  request.set_table_id(args[0]);
  request.set_include_geometry(absl::GetFlag(FLAGS_geometry));
  v1::TableInfo r;
  const grpc::Status status = stub.GetTable(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("table %s: %s, rack %s, %s engine, %g Hz, tick %lld (%.3f s), %s, seat %u to "
                "play, %llu shots, %u watchers\n",
                r.table_id().c_str(), r.preset().c_str(), r.rack().c_str(), r.engine().c_str(),
                r.tick_hz(), static_cast<long long>(r.tick()), r.t_s(),
                r.at_rest() ? "at rest" : "moving", r.turn(),
                static_cast<unsigned long long>(r.shots()), r.watchers());
    if (r.has_game()) {
      for (const std::string& line : GameLines(r.game(), r.has_last_shot() ? &r.last_shot() : nullptr)) {
        std::printf("%s\n", line.c_str());
      }
    }
    if (r.has_last_shot()) std::printf("last %s\n", SummaryLine(r.last_shot()).c_str());
    std::printf("%-8s %9s %9s  %s\n", "ball", "x_m", "y_m", "state");
    for (const v1::BallState& b : r.balls()) std::printf("%s\n", BallLine(b).c_str());
  });
}

int RunSimple(const Context& ctx, Stub& stub, const std::string& verb,
              const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("table " + verb + " ID --token T");
  const std::string token = absl::GetFlag(FLAGS_token);
  if (token.empty()) return UsageError("table " + verb + " needs --token (a seat's or the admin token)");
  grpc::Status status;
  std::string text;
  if (verb == "delete") {
    v1::DeleteTableRequest request;
    request.set_table_id(args[0]);
    request.set_token(token);
    v1::DeleteTableResponse r;
    status = stub.DeleteTable(ctx.NewCall().get(), request, &r);
    if (!status.ok()) return ReportRpcError(status);
    return Print(ctx, r, [&] { std::printf("deleted %s\n", args[0].c_str()); });
  }
  if (verb == "reset") {
    v1::ResetTableRequest request;
    request.set_table_id(args[0]);
    request.set_token(token);
    v1::ResetTableResponse r;
    status = stub.ResetTable(ctx.NewCall().get(), request, &r);
    if (!status.ok()) return ReportRpcError(status);
    return Print(ctx, r, [&] {
      std::printf("re-racked at tick %lld (sequence %llu)\n", static_cast<long long>(r.tick()),
                  static_cast<unsigned long long>(r.sequence()));
    });
  }
  if (verb == "place") {
    const std::vector<std::string>& balls = RepeatedFlagValues("ball");
    if (balls.size() != 1) return UsageError("table place ID --token T --ball ID@X,Y (one ball)");
    v1::TableSetup parsed;
    if (auto bad = BuildSetup(&parsed)) return UsageError(*bad);
    v1::PlaceBallRequest request;
    request.set_table_id(args[0]);
    request.set_token(token);
    *request.mutable_ball() = parsed.balls(0);
    v1::PlaceBallResponse r;
    status = stub.PlaceBall(ctx.NewCall().get(), request, &r);
    if (!status.ok()) return ReportRpcError(status);
    return Print(ctx, r, [&] {
      std::printf("placed %s at (%g, %g) m, tick %lld\n", request.ball().id().c_str(),
                  request.ball().x_m(), request.ball().y_m(), static_cast<long long>(r.tick()));
    });
  }
  // turn
  const auto seat = absl::GetFlag(FLAGS_seat);
  if (!seat || *seat < 0) return UsageError("table turn ID --token T --seat N");
  v1::SetTurnRequest request;
  request.set_table_id(args[0]);
  request.set_token(token);
  request.set_seat(static_cast<uint32_t>(*seat));
  v1::SetTurnResponse r;
  status = stub.SetTurn(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] { std::printf("seat %d to play\n", *seat); });
}

// --call BALL:POCKET | --safety, --push-out, --nominate BALL: ShootRequest.call, set when any
// of them is given.
std::optional<std::string> BuildCall(v1::ShootRequest* request) {
  const std::string call = absl::GetFlag(FLAGS_call);
  const bool safety = absl::GetFlag(FLAGS_safety);
  const bool push_out = absl::GetFlag(FLAGS_push_out);
  const std::string nominate = absl::GetFlag(FLAGS_nominate);
  if (Given("call") && safety) return "give --call BALL:POCKET or --safety, not both";
  if (!Given("call") && !safety && !push_out && !Given("nominate")) return std::nullopt;
  v1::ShotCall* c = request->mutable_call();
  if (Given("call")) {
    const size_t colon = call.find(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == call.size() ||
        call.find(':', colon + 1) != std::string::npos) {
      return "--call must be BALL:POCKET (e.g. 9:top_left), got '" + call + "'";
    }
    c->set_ball(call.substr(0, colon));
    c->set_pocket(call.substr(colon + 1));
  }
  if (Given("nominate") && nominate.empty()) return "--nominate needs a ball";
  c->set_safety(safety);
  c->set_push_out(push_out);
  c->set_nominate(nominate);
  return std::nullopt;
}

int RunShoot(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("table shoot ID --token T (strike flags)");
  v1::ShootRequest request;
  request.set_table_id(args[0]);
  request.set_token(absl::GetFlag(FLAGS_token));
  if (request.token().empty()) return UsageError("table shoot needs --token (the seat's token)");
  if (auto bad = BuildStrike(request.mutable_strike())) return UsageError(*bad);
  // Unnamed, the struck ball is the server's to choose: the cue ball, or in a ruled game the
  // striker's own (three-cushion: yellow for seat 1).
  if (!Given("strike_ball")) request.mutable_strike()->clear_ball();
  if (auto bad = BuildCall(&request)) return UsageError(*bad);
  if (const auto next = absl::GetFlag(FLAGS_next_seat)) {
    if (*next < 0) return UsageError(InvalidValue("--next-seat must be a seat number"));
    request.set_next_seat(static_cast<uint32_t>(*next));
  }
  v1::ShootResponse r;
  const grpc::Status status = stub.Shoot(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    const std::string call = request.has_call() ? CallText(request.call()) : "";
    std::printf("shot %llu starts at tick %lld: ball %.3f m/s, phi %.2f deg%s%s\n",
                static_cast<unsigned long long>(r.shot_id()),
                static_cast<long long>(r.start_tick()), r.strike().ball_speed_mps(),
                r.strike().phi_deg(), call.empty() ? "" : "; ", call.c_str());
  });
}

void PrintGameLines(const v1::GameState& g) {
  for (const std::string& line : GameLines(g, nullptr)) std::printf("%s\n", line.c_str());
}

int RunDecide(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("table decide ID --token T --choice CHOICE");
  v1::DecideRequest request;
  request.set_table_id(args[0]);
  request.set_token(absl::GetFlag(FLAGS_token));
  request.set_choice(absl::GetFlag(FLAGS_choice));
  if (request.token().empty()) return UsageError("table decide needs --token (the deciding seat's token)");
  if (request.choice().empty()) {
    return UsageError("table decide needs --choice (one of the choices the decision lists)");
  }
  v1::DecideResponse r;
  const grpc::Status status = stub.Decide(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("decided %s (sequence %llu)\n", request.choice().c_str(),
                static_cast<unsigned long long>(r.sequence()));
    if (r.has_game()) PrintGameLines(r.game());
  });
}

int RunConcede(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("table concede ID --token T [--seat N] [--frame N]");
  v1::ConcedeRequest request;
  request.set_table_id(args[0]);
  request.set_token(absl::GetFlag(FLAGS_token));
  if (request.token().empty()) {
    return UsageError("table concede needs --token (a seat's, or the admin token with --seat)");
  }
  if (const auto seat = absl::GetFlag(FLAGS_seat)) {
    if (*seat < 0) return UsageError(InvalidValue("--seat must be a seat number"));
    request.set_seat(static_cast<uint32_t>(*seat));
  }
  // The concession names its frame, so that repeating the command (or running it twice at
  // once) concedes that frame once, never the next one too.
  if (const auto frame = absl::GetFlag(FLAGS_frame)) {
    if (*frame < 1) return UsageError(InvalidValue("--frame must be a frame number, from 1"));
    request.set_frame(static_cast<uint32_t>(*frame));
  } else {
    v1::GetTableRequest get;
    get.set_table_id(args[0]);
    v1::TableInfo info;
    const grpc::Status got = stub.GetTable(ctx.NewCall().get(), get, &info);
    if (!got.ok()) return ReportRpcError(got);
    if (info.has_game()) request.set_frame(info.game().frame());
  }
  v1::ConcedeResponse r;
  const grpc::Status status = stub.Concede(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("conceded (sequence %llu)\n", static_cast<unsigned long long>(r.sequence()));
    if (r.has_game()) PrintGameLines(r.game());
  });
}

std::string ActionLine(const v1::MatchAction& a) {
  std::string line = absl::StrFormat("tick %-8lld seat %u  ", static_cast<long long>(a.tick()),
                                     a.seat());
  switch (a.kind()) {
    case v1::MatchAction::SHOOT: {
      absl::StrAppend(&line, absl::StrFormat("shot %llu: %s",
                                             static_cast<unsigned long long>(a.shot_id()),
                                             StrikeText(a.strike())));
      if (a.has_call()) {
        const std::string call = CallText(a.call());
        if (!call.empty()) absl::StrAppend(&line, "; ", call);
      }
      if (a.has_seed()) absl::StrAppend(&line, "; seed ", a.seed());
      if (a.has_applied()) {
        const v1::StrikeReport& s = a.applied();
        absl::StrAppend(&line, absl::StrFormat(
                                   "; applied: ball speed %s m/s, phi %s deg, theta %s deg, a %s, b %s",
                                   Num(s.ball_speed_mps()), Num(s.phi_deg()),
                                   Num(s.theta_deg()), Num(s.a()), Num(s.b())));
      }
      break;
    }
    case v1::MatchAction::PLACE:
      absl::StrAppend(&line, absl::StrFormat("placed %s at (%s, %s) m", a.place().id(),
                                             Num(a.place().x_m()), Num(a.place().y_m())));
      break;
    case v1::MatchAction::DECIDE: absl::StrAppend(&line, "decided ", a.choice()); break;
    case v1::MatchAction::CONCEDE: absl::StrAppend(&line, "conceded"); break;
    case v1::MatchAction::SHOT_CLOCK: absl::StrAppend(&line, "shot clock ran out"); break;
    case v1::MatchAction::RESET: absl::StrAppend(&line, "re-racked (the match starts again)"); break;
    default: absl::StrAppend(&line, "action ", static_cast<int>(a.kind())); break;
  }
  if (a.has_verdict()) {
    absl::StrAppend(&line, "; ", a.kind() == v1::MatchAction::SHOOT
                                     ? VerdictText(a.verdict(), a.seat())
                                     : RulingText(a.verdict(), a.kind() == v1::MatchAction::CONCEDE
                                                                   ? "conceded" : ""));
  }
  return line;
}

int RunRecord(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("table record ID");
  v1::GetMatchRecordRequest request;
  request.set_table_id(args[0]);
  v1::MatchRecord r;
  const grpc::Status status = stub.GetMatchRecord(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    const v1::GameConfig& g = r.create().game();
    std::printf("match on table %s: %s, %d actions, %s", r.table_id().c_str(),
                g.name().empty() ? "free" : g.name().c_str(), r.actions_size(),
                r.ended() ? "ended" : "in progress");
    if (g.has_seed()) std::printf(", noise %s with seed %llu", Num(g.noise()).c_str(),
                                  static_cast<unsigned long long>(g.seed()));
    std::printf("\n");
    for (const v1::MatchAction& a : r.actions()) std::printf("%s\n", ActionLine(a).c_str());
    if (r.has_game()) PrintGameLines(r.game());
  });
}

// The readable form of a stream: one line when something happens, at most a few per second
// while balls just roll.
class WatchText {
 public:
  void Add(const v1::TableSnapshot& s) {
    if (s.heartbeat()) return;
    for (const v1::BallState& b : s.balls()) state_[b.id()] = b.state();
    std::vector<std::string> notes;
    for (const v1::TableEvent& e : s.events()) {
      ++counts_[v1::EventKind_Name(e.kind())];
      switch (e.kind()) {
        case v1::ball_pocket: notes.push_back(e.balls(0) + " pocketed in " + e.pocket()); break;
        case v1::shot:
          notes.push_back(absl::StrFormat("shot %d by seat %d", e.shot_id(), e.seat()));
          break;
        case v1::ball_placed:
          notes.push_back(absl::StrFormat("seat %d placed %s", e.seat(), e.balls(0)));
          break;
        case v1::table_reset: notes.push_back("re-racked"); break;
        case v1::turn: notes.push_back(absl::StrFormat("seat %d to play", e.seat())); break;
        case v1::shot_end:
          notes.push_back(SummaryLine(e.summary()));
          last_shot_ = e.summary();
          break;
        default:
          if (std::string note = GameEventNote(e); !note.empty()) notes.push_back(note);
          break;
      }
    }
    // The game in words whenever it changed (and on the first snapshot that carries it).
    std::vector<std::string> game_lines;
    if (s.has_game()) {
      game_lines = GameLines(s.game(), last_shot_.has_verdict() ? &last_shot_ : nullptr);
      if (game_lines == last_game_lines_) game_lines.clear();
      else last_game_lines_ = game_lines;
    }
    const bool interesting = !notes.empty() || !game_lines.empty() ||
                             s.at_rest() != last_at_rest_ || s.resync();
    if (!interesting && s.t_s() < next_line_t_) return;
    next_line_t_ = s.t_s() + 0.25;
    last_at_rest_ = s.at_rest();
    int moving = 0, on = 0;
    for (const auto& [id, st] : state_) {
      moving += st == v1::sliding || st == v1::rolling || st == v1::spinning;
      on += st != v1::pocketed;
    }
    std::string ev;
    for (const auto& [kind, n] : counts_) {
      if (kind != "transition") ev += absl::StrFormat(" +%d %s", n, kind);
    }
    counts_.clear();
    std::printf("tick %-8lld %9.3f s  seq %-6llu %s  %2d moving, %2d on the table%s%s\n",
                static_cast<long long>(s.tick()), s.t_s(),
                static_cast<unsigned long long>(s.sequence()),
                s.at_rest() ? "at rest" : "moving ", moving, on, ev.c_str(),
                s.resync() ? "  (resync: events lost)" : "");
    for (const std::string& n : notes) std::printf("    %s\n", n.c_str());
    for (const std::string& n : game_lines) std::printf("    %s\n", n.c_str());
    std::fflush(stdout);
  }

 private:
  v1::ShotSummary last_shot_;
  std::vector<std::string> last_game_lines_;
  std::map<std::string, v1::MotionState> state_;
  std::map<std::string, int> counts_;  // events since the last line
  double next_line_t_ = -1.0;
  bool last_at_rest_ = true;
};

int RunWatch(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("table watch ID [--rate HZ] [--until-rest]");
  v1::WatchTableRequest request;
  request.set_table_id(args[0]);
  request.set_rate_hz(absl::GetFlag(FLAGS_rate).value_or(30.0));
  request.set_changed_only(absl::GetFlag(FLAGS_changed_only));
  if (const auto from = absl::GetFlag(FLAGS_from_sequence)) request.set_from_sequence(*from);
  for (const std::string& f : absl::GetFlag(FLAGS_fields)) {
    if (f == "position") request.add_fields(v1::SNAPSHOT_FIELD_POSITION);
    else if (f == "velocity") request.add_fields(v1::SNAPSHOT_FIELD_VELOCITY);
    else if (f == "spin") request.add_fields(v1::SNAPSHOT_FIELD_SPIN);
    else if (f == "orientation") request.add_fields(v1::SNAPSHOT_FIELD_ORIENTATION);
    else return UsageError("--fields takes position,velocity,spin,orientation, got '" + f + "'");
  }
  const bool until_rest = absl::GetFlag(FLAGS_until_rest);
  const std::string svg = absl::GetFlag(FLAGS_svg);

  TableDrawing drawing;
  std::map<std::string, size_t> path_of;
  if (!svg.empty()) {
    v1::GetTableRequest get;
    get.set_table_id(args[0]);
    get.set_include_geometry(true);
    v1::TableInfo info;
    const grpc::Status status = stub.GetTable(ctx.NewCall().get(), get, &info);
    if (!status.ok()) return ReportRpcError(status);
    drawing.geometry = info.geometry();
  }

  grpc::ClientContext call;  // no deadline: a stream lives as long as the table
  std::unique_ptr<grpc::ClientReader<v1::TableSnapshot>> reader =
      stub.WatchTable(&call, request);
  v1::TableSnapshot s;
  JsonArrayStream document(ctx.format == Format::kJson);
  WatchText text;
  bool saw_shot_end = false;
  bool saw_moving = false;
  bool done = false;
  int64_t snapshots = 0;
  while (!done && reader->Read(&s)) {
    ++snapshots;
    for (const v1::TableEvent& e : s.events()) saw_shot_end |= e.kind() == v1::shot_end;
    // A reader resynced after falling behind may have lost the shot_end event itself.
    saw_moving |= !s.at_rest() || s.resync();
    switch (ctx.format) {
      case Format::kJson: document.Add(ToJson(s, true)); break;
      case Format::kJsonl: std::cout << ToJson(s, true) << std::endl; break;
      case Format::kCsv:
        if (snapshots == 1) std::cout << "sequence,tick,t_s,id,x_m,y_m,state\n";
        for (const v1::BallState& b : s.balls()) {
          std::cout << s.sequence() << ',' << s.tick() << ',' << Num(s.t_s()) << ',' << b.id()
                    << ',' << Num(b.x_m()) << ',' << Num(b.y_m()) << ','
                    << v1::MotionState_Name(b.state()) << '\n';
        }
        std::cout.flush();
        break;
      case Format::kText: text.Add(s); break;
    }
    if (!svg.empty() && !s.heartbeat()) {
      for (const v1::BallState& b : s.balls()) {
        auto [it, fresh] = path_of.try_emplace(b.id(), drawing.paths.size());
        if (fresh) drawing.paths.push_back(BallPath{.id = b.id()});
        BallPath& p = drawing.paths[it->second];
        if (p.pocketed) continue;
        p.t_s.push_back(s.t_s());
        p.x_m.push_back(b.x_m());
        p.y_m.push_back(b.y_m());
        p.pocketed = b.state() == v1::pocketed;
      }
      for (const v1::TableEvent& e : s.events()) drawing.events.push_back(e);
    }
    if (until_rest && (saw_shot_end || saw_moving) && s.at_rest() && !s.heartbeat()) done = true;
  }
  grpc::Status status;
  if (done) {
    call.TryCancel();
    (void)reader->Finish();
  } else {
    status = reader->Finish();
  }
  if (!svg.empty()) {
    drawing.title = absl::StrFormat("table %s: %d snapshots seen", args[0], snapshots);
    std::ofstream out(svg);
    out << TableSvg(drawing);
    if (!out) return UsageError("cannot write --svg file '" + svg + "'");
  }
  if (!status.ok()) return ReportRpcError(status);
  return 0;
}

}  // namespace

std::optional<std::string> CheckSeatFlags() {
  const int seats = absl::GetFlag(FLAGS_seats);
  if (Given("seats") && (seats < 1 || seats > 16)) {
    return InvalidValue(absl::StrCat("--seats: must be in [1, 16], got ", seats));
  }
  const double tick_hz = absl::GetFlag(FLAGS_tick_hz);
  if (Given("tick_hz") && !(tick_hz >= 1 && tick_hz <= 1000)) {
    return InvalidValue("--tick-hz: must be in [1, 1000], got " + Num(tick_hz));
  }
  const std::vector<std::string> names = absl::GetFlag(FLAGS_seat_names);
  for (size_t i = 0; i < names.size(); ++i) {
    for (size_t j = 0; j < i; ++j) {
      if (names[i] == names[j]) return "--seat-names: '" + names[i] + "' given twice";
    }
  }
  return std::nullopt;
}

std::optional<std::string> CheckPageSize() {
  const int n = absl::GetFlag(FLAGS_page_size);
  if (n < 0 || n > 1000) {
    return InvalidValue(
        absl::StrCat("--page-size: must be in [0, 1000] (0: the default, 100), got ", n));
  }
  return std::nullopt;
}

std::optional<std::string> CheckGameFlags(std::string_view command, std::string_view sub) {
  struct Use {
    const char* flag;   // absl name
    const char* shown;  // as written on the command line
    const char* verb;   // the only `table` subcommand that takes it
  };
  static constexpr Use kUses[] = {
      {"game", "--game", "create"},          {"race_to", "--race-to", "create"},
      {"shot_clock", "--shot-clock", "create"}, {"start", "--start", "create"},
      {"call", "--call", "shoot"},           {"safety", "--safety", "shoot"},
      {"push_out", "--push-out", "shoot"},   {"nominate", "--nominate", "shoot"},
      {"choice", "--choice", "decide"},      {"aim_lines", "--aim-lines", "create"},
  };
  const bool table = command == "table";
  const bool round = command == "round";
  for (const Use& u : kUses) {
    if (round && std::string_view(u.flag) == "choice" && sub == "decide") continue;
    if (round && std::string_view(u.flag) == "shot_clock" && sub == "create") continue;
    if (Given(u.flag) && !(table && sub == u.verb)) {
      return absl::StrCat(u.shown, " applies to table ", u.verb, " only");
    }
  }
  if (!RepeatedFlagValues("rule").empty() && !((table || round) && sub == "create")) {
    return "--rule applies to table create and round create only";
  }
  return std::nullopt;
}

namespace {

// The frame of the calibration's track files (--track-origin, --track-scale) on `preset`'s
// table; an error message for a bad flag.
absl::StatusOr<billiards::TrackFrame> TrackFrameFromFlags(const std::string& preset) {
  const std::string origin = absl::GetFlag(FLAGS_track_origin);
  if (origin != "centre" && origin != "corner") {
    return absl::InvalidArgumentError("--track-origin: centre or corner, got '" + origin + "'");
  }
  billiards::TrackFrame frame{.scale = absl::GetFlag(FLAGS_track_scale).value_or(1.0)};
  // On the preset's playing area, for a corner origin and for files measuring in fractions
  // of it (an unknown preset is left to the server to refuse, unless the corner needs it).
  absl::StatusOr<billiards::TableSpec> spec =
      billiards::MakeTablePreset(preset.empty() ? "pool-9ft" : preset);
  if (spec.ok()) {
    frame = billiards::TrackFrameOn(*spec, origin == "corner", frame.scale);
  } else if (origin == "corner") {
    return absl::InvalidArgumentError("--table: " + std::string(spec.status().message()));
  }
  if (absl::Status s = billiards::ValidateTrackFrame(frame); !s.ok()) {
    return absl::InvalidArgumentError("--track-scale: " + std::string(s.message()));
  }
  return frame;
}

// table calibrate FILE...: the files' recorded shots, the fit's progress on stderr, the report.
int RunCalibrate(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.empty()) {
    return UsageError("table calibrate needs one or more track files (CSV, JSON lines or a shot set)");
  }
  v1::CalibrateTableRequest request;
  if (auto bad = BuildSetup(request.mutable_table())) return UsageError(*bad);
  absl::StatusOr<billiards::TrackFrame> frame = TrackFrameFromFlags(request.table().preset());
  if (!frame.ok()) return UsageError(std::string(frame.status().message()));
  request.mutable_table()->clear_rack();
  request.mutable_table()->clear_balls();
  if (auto bad = BuildSolver(request.mutable_solver())) return UsageError(*bad);
  for (const std::string& f : absl::GetFlag(FLAGS_fit)) {
    v1::FitParameter* p = request.add_fit();
    const size_t eq = f.find('=');
    p->set_name(f.substr(0, eq));
    if (eq == std::string::npos) continue;
    const std::vector<std::string> range = absl::StrSplit(f.substr(eq + 1), ':');
    double lo = 0, hi = 0;
    if (range.size() != 2 || !absl::SimpleAtod(range[0], &lo) || !absl::SimpleAtod(range[1], &hi)) {
      return UsageError("--fit: NAME or NAME=LO:HI, got '" + f + "'");
    }
    p->set_lo(lo);
    p->set_hi(hi);
  }
  for (const std::string& h : absl::GetFlag(FLAGS_heldout)) {
    uint32_t i = 0;
    if (!absl::SimpleAtoi(h, &i)) return UsageError("--heldout: shot indices, got '" + h + "'");
    request.add_heldout(i);
  }
  if (const auto w = absl::GetFlag(FLAGS_window)) request.set_strike_window_s(*w);
  if (const auto n = absl::GetFlag(FLAGS_max_iterations)) request.set_max_iterations(*n);
  if (const auto n = absl::GetFlag(FLAGS_max_simulations)) request.set_max_simulations(*n);
  request.set_fit_elevation(absl::GetFlag(FLAGS_fit_elevation));
  if (const std::string w = absl::GetFlag(FLAGS_predict); w == "central") {
    request.set_prediction(v1::STRIKE_PREDICTION_CENTRAL_REST);
  } else if (w == "best-fit") {
    request.set_prediction(v1::STRIKE_PREDICTION_BEST_FIT);
  } else {
    return UsageError("--predict: best-fit or central, got '" + w + "'");
  }
  if (const std::string i = absl::GetFlag(FLAGS_intent); i == "three-cushion") {
    request.set_intent(v1::SHOT_INTENT_THREE_CUSHION_POINT);
  } else if (i == "pot") {
    request.set_intent(v1::SHOT_INTENT_POT);
  } else if (i != "none") {
    return UsageError("--intent: none, three-cushion or pot, got '" + i + "'");
  }
  request.set_read_cloth(absl::GetFlag(FLAGS_read_cloth));
  if (const auto h = absl::GetFlag(FLAGS_huber)) request.set_huber_m(*h);
  const std::string cue = absl::GetFlag(FLAGS_cue_ball);
  for (const std::string& path : args) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return UsageError("table calibrate: cannot read '" + path + "'");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    absl::StatusOr<std::vector<NamedTrack>> tracks = ParseTracks(text, *frame);
    if (!tracks.ok()) return UsageError(InvalidValue(path + ": " + std::string(tracks.status().message())));
    const std::string base = std::filesystem::path(path).filename().string();
    for (const NamedTrack& track : *tracks) {
      const billiards::TrackFile* file = &track.file;
      v1::RecordedShot* shot = request.add_shots();
      // A shot of a set is named by its file and its own name: "match.json#17" (the file's
      // name cut to fit 64 bytes in all).
      const std::string own = track.name.empty() ? "" : "#" + track.name.substr(0, 24);
      const std::string name = base.substr(0, 64 - own.size()) + own;
      shot->set_name(name);
      for (size_t b = 0; b < file->balls.size(); ++b) {
        v1::BallPlacement* p = shot->add_balls();
        p->set_id(file->balls[b]);
        p->set_x_m(file->spots[b].x());
        p->set_y_m(file->spots[b].y());
      }
      if (!cue.empty()) {
        shot->set_cue_ball(cue);
      } else if (file->cue >= 0) {
        shot->set_cue_ball(file->balls[static_cast<size_t>(file->cue)]);
      } else {
        return UsageError(InvalidValue(name + ": no ball leaves its spot by a centimetre; name "
                                              "the struck ball with --cue-ball"));
      }
      for (const billiards::TrackPoint& t : file->points) {
        v1::TrackedPoint* q = shot->add_points();
        q->set_t_s(t.t_s);
        q->set_ball(static_cast<uint32_t>(t.ball));
        q->set_x_m(t.xy.x());
        q->set_y_m(t.xy.y());
      }
    }
  }
  v1::CalibrateTableResponse r, last;
  bool have_report = false;
  int shown = -1;
  auto progress = [&] {
    if (r.has_report()) {  // the last message (the server keeps only the latest progress)
      last = r;
      have_report = true;
      std::cerr << "calibrate: 100% (done)\n";
      return;
    }
    const int pct = static_cast<int>(r.fraction() * 100);
    if (pct / 10 != shown / 10) {  // every tenth of the way
      std::cerr << "calibrate: " << pct << "% (" << r.stage() << ")\n";
      shown = pct;
    }
  };
  // Uploaded in parts, each within the server's request limit however many shots there are.
  grpc::Status status;
  {
    std::unique_ptr<grpc::ClientContext> call = ctx.NewCall();
    std::unique_ptr<grpc::ClientReaderWriter<v1::CalibrationUpload, v1::CalibrateTableResponse>>
        stream = stub.UploadCalibration(call.get());
    for (const v1::CalibrationUpload& part : CalibrationUploadParts(request)) {
      if (!stream->Write(part)) break;  // the server ended the call: Finish says why
    }
    stream->WritesDone();
    while (stream->Read(&r)) progress();
    status = stream->Finish();
  }
  if (status.error_code() == grpc::StatusCode::UNIMPLEMENTED && shown < 0 && !have_report) {
    // A server from before UploadCalibration: the whole request in one message.
    std::unique_ptr<grpc::ClientContext> call = ctx.NewCall();
    std::unique_ptr<grpc::ClientReader<v1::CalibrateTableResponse>> reader =
        stub.CalibrateTable(call.get(), request);
    while (reader->Read(&r)) progress();
    status = reader->Finish();
    if (status.error_code() == grpc::StatusCode::RESOURCE_EXHAUSTED &&
        absl::StrContains(status.error_message(), "larger than max")) {
      return ReportRpcError(grpc::Status(
          status.error_code(),
          absl::StrFormat("%s: the recorded shots make a %d-byte request, and this server "
                          "takes them in one message up to its --max_request_bytes: raise "
                          "it, or give fewer shots",
                          status.error_message(), request.ByteSizeLong())));
    }
  }
  if (!status.ok()) return ReportRpcError(status);
  if (!have_report) return ReportRpcError(grpc::Status(grpc::StatusCode::INTERNAL, "no report"));
  const v1::CalibrationReport& rep = last.report();
  return Print(ctx, rep, [&] {
    if (rep.has_cloth()) {
      // What the tracks say of the cloth, and what the calibration started from.
      const v1::ClothReading& c = rep.cloth();
      std::cout << absl::StrFormat("%-22s %12s %12s %9s   %s\n", "cloth read", "table", "read",
                                   "stretches", "(median, quartiles)");
      const auto line = [](std::string_view name, double before, double read, double q1,
                           double q3, uint32_t n, bool taken, double start) {
        std::string note = taken ? absl::StrFormat("%.4g-%.4g", q1, q3)
                                 : std::string("too few stretches: not taken");
        // A fitted constant starts within its bounds: say where, when that is not the reading.
        if (taken && start != read) note += absl::StrFormat("; started at %.6g, a bound", start);
        std::cout << absl::StrFormat("%-22s %12.6g %12s %9d   %s\n", name, before,
                                     n == 0 ? std::string("-") : absl::StrFormat("%.6g", read), n,
                                     note);
      };
      line("mu_roll", c.mu_roll_before(), c.mu_roll(), c.mu_roll_q1(), c.mu_roll_q3(),
           c.rolling_stretches(), c.mu_roll_taken(), c.mu_roll_start());
      line("mu_slide", c.mu_slide_before(), c.mu_slide(), c.mu_slide_q1(), c.mu_slide_q3(),
           c.sliding_stretches(), c.mu_slide_taken(), c.mu_slide_start());
    }
    std::cout << absl::StrFormat("%-22s %12s %12s %12s   bounds\n", "parameter", "before", "after",
                                 "std error");
    for (const v1::FittedParameter& p : rep.fitted()) {
      // At a bound the error, of the bounded coordinate, says nothing: the bound is the news.
      const std::string error = p.at_bound()                     ? std::string("at a bound")
                                : std::isfinite(p.standard_error()) ? absl::StrFormat("%.2g", p.standard_error())
                                                                    : std::string("unidentified");
      std::cout << absl::StrFormat("%-22s %12.6g %12.6g %12s   [%g, %g]\n", p.name(), p.before(),
                                   p.after(), error, p.lo(), p.hi());
    }
    std::cout << absl::StrFormat("%-22s %9s %9s %9s  %s\n", "shot", "before", "after", "strike s",
                                 "(mean distance, mm; strike time on the file's clock)");
    for (const v1::ShotCalibration& c : rep.shots()) {
      std::string note = c.heldout() ? "held out" : "";
      if (c.plausible() > 0) {
        absl::StrAppend(&note,
                        absl::StrFormat(", predicted from %d plausible strike%s", c.plausible(),
                                        c.plausible() == 1 ? "" : "s"));
        if (c.intent_met()) absl::StrAppend(&note, ", as intended");
      }
      std::cout << absl::StrFormat("%-22s %9.1f %9.1f %9.4f  %s\n", c.name(), 1e3 * c.before().mean_m(),
                                   1e3 * c.after().mean_m(), c.strike_time_after_s(), note);
    }
    std::cout << absl::StrFormat("median: training %.1f -> %.1f mm", 1e3 * rep.train_before_m(),
                                 1e3 * rep.train_after_m());
    if (rep.heldout_before_m() > 0 || rep.heldout_after_m() > 0) {
      std::cout << absl::StrFormat(", held out %.1f -> %.1f mm", 1e3 * rep.heldout_before_m(),
                                   1e3 * rep.heldout_after_m());
    }
    std::cout << absl::StrFormat("; %d iterations, %d simulations, %.2f s CPU", rep.iterations(),
                                 rep.simulations(), rep.cpu_s());
    if (rep.start_rms_m_size() > 1) {
      std::cout << absl::StrFormat("; start %d of %d kept (%.1f / %.1f mm)", rep.start_kept(),
                                   rep.start_rms_m_size(), 1e3 * rep.start_rms_m(0), 1e3 * rep.start_rms_m(1));
    }
    std::cout << "\n";
    // Every parameter the report's table has moved (params: the fitted ones and the cloth
    // read), in name order.
    std::string flags;
    for (const auto& [name, value] : std::map<std::string, double>(rep.params().begin(),
                                                                   rep.params().end())) {
      flags += absl::StrFormat(" --param %s=%.6g", name, value);
    }
    if (!flags.empty()) std::cout << "use:" << flags << "\n";
  });
}

}  // namespace

int RunTable(const Context& ctx, const std::vector<std::string>& args) {
  static constexpr const char* kVerbs =
      "create, list, get, delete, reset, place, shoot, turn, watch, decide, concede, record, "
      "calibrate";
  if (args.empty()) return UsageError(std::string("table needs a subcommand: ") + kVerbs);
  if (ctx.format == Format::kCsv && args[0] != "watch") {
    return UsageError("table " + args[0] + " has no csv form (json, jsonl or text)");
  }
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  std::unique_ptr<Stub> stub = v1::Billiards::NewStub(ctx.channel);
  const std::string& verb = args[0];
  if (verb == "create") return RunCreate(ctx, *stub, rest);
  if (verb == "list") return RunList(ctx, *stub, rest);
  if (verb == "get") return RunGet(ctx, *stub, rest);
  if (verb == "delete" || verb == "reset" || verb == "place" || verb == "turn") {
    return RunSimple(ctx, *stub, verb, rest);
  }
  if (verb == "shoot") return RunShoot(ctx, *stub, rest);
  if (verb == "watch") return RunWatch(ctx, *stub, rest);
  if (verb == "decide") return RunDecide(ctx, *stub, rest);
  if (verb == "concede") return RunConcede(ctx, *stub, rest);
  if (verb == "record") return RunRecord(ctx, *stub, rest);
  if (verb == "calibrate") return RunCalibrate(ctx, *stub, rest);
  return UsageError("unknown table subcommand '" + verb + "' (" + kVerbs + ")");
}

}  // namespace sportsim::cli
