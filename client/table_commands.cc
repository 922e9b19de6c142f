// `sportsim table ...`: authoritative tables (Billiards/CreateTable ... WatchTable).
#include <cstdio>
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
#include "absl/strings/numbers.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "client/billiards_flags.h"
#include "client/cli.h"
#include "client/table_svg.h"
#include "sportsim/v1/billiards.grpc.pb.h"

ABSL_DECLARE_FLAG(std::string, svg);

ABSL_FLAG(int, seats, 0, "table/swing create: number of seats (table default 2, swing 1)");
ABSL_FLAG(std::vector<std::string>, seat_names, {}, "table/swing create: seat names, comma separated");
ABSL_FLAG(double, tick_hz, 0.0, "table/swing create: ticks per second (table default 120, swing 400)");
ABSL_FLAG(std::string, token, "", "The seat's token (table/swing create printed it)");
ABSL_FLAG(std::optional<int>, next_seat, std::nullopt, "table shoot: pass the turn to this seat");
ABSL_FLAG(std::optional<int>, seat, std::nullopt, "table turn: the seat to play next");
ABSL_FLAG(std::optional<double>, rate, std::nullopt,
          "table/swing watch, swing drive: snapshots per second at most (0, or above the tick "
          "rate: every tick); default 30 for tables, every tick for swings");
ABSL_FLAG(bool, until_rest, false,
          "table watch: exit after the first at-rest snapshot that follows a shot");
ABSL_FLAG(std::vector<std::string>, fields, {},
          "table watch: position,velocity,spin,orientation (default all)");
ABSL_FLAG(bool, changed_only, false, "table watch: only the balls that changed");
ABSL_FLAG(std::optional<uint64_t>, from_sequence, std::nullopt,
          "table/swing watch: replay the events after this sequence, then go on");
ABSL_FLAG(int, page_size, 0, "table/swing list: tables or sessions per page (default 100)");
ABSL_FLAG(std::string, page_token, "", "table/swing list: the next_page_token of the previous page");
ABSL_FLAG(bool, geometry, false, "table get: include cushions and pockets");

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
  return line;
}

int RunCreate(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("table create takes flags only, got '" + args[0] + "'");
  v1::CreateTableRequest request;
  if (auto bad = BuildSetup(request.mutable_table())) return UsageError(*bad);
  if (auto bad = BuildSolver(request.mutable_solver())) return UsageError(*bad);
  const int seats = absl::GetFlag(FLAGS_seats);
  if (seats < 0) return UsageError("--seats must be positive");
  request.set_seats(static_cast<uint32_t>(seats));
  for (const std::string& n : absl::GetFlag(FLAGS_seat_names)) request.add_seat_names(n);
  request.set_tick_hz(absl::GetFlag(FLAGS_tick_hz));
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
  });
}

int RunList(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("table list takes flags only");
  v1::ListTablesRequest request;
  request.set_page_size(static_cast<uint32_t>(std::max(0, absl::GetFlag(FLAGS_page_size))));
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
    if (r.has_last_shot()) std::printf("last %s\n", SummaryLine(r.last_shot()).c_str());
    std::printf("%-8s %9s %9s  %s\n", "ball", "x_m", "y_m", "state");
    for (const v1::BallState& b : r.balls()) std::printf("%s\n", BallLine(b).c_str());
  });
}

int RunSimple(const Context& ctx, Stub& stub, const std::string& verb,
              const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("table " + verb + " ID --token T");
  const std::string token = absl::GetFlag(FLAGS_token);
  if (token.empty()) return UsageError("table " + verb + " needs --token (a seat's token)");
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

int RunShoot(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("table shoot ID --token T (strike flags)");
  v1::ShootRequest request;
  request.set_table_id(args[0]);
  request.set_token(absl::GetFlag(FLAGS_token));
  if (request.token().empty()) return UsageError("table shoot needs --token (the seat's token)");
  if (auto bad = BuildStrike(request.mutable_strike())) return UsageError(*bad);
  if (const auto next = absl::GetFlag(FLAGS_next_seat)) {
    if (*next < 0) return UsageError("--next-seat must be a seat number");
    request.set_next_seat(static_cast<uint32_t>(*next));
  }
  v1::ShootResponse r;
  const grpc::Status status = stub.Shoot(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("shot %llu starts at tick %lld: ball %.3f m/s, phi %.2f deg\n",
                static_cast<unsigned long long>(r.shot_id()),
                static_cast<long long>(r.start_tick()), r.strike().ball_speed_mps(),
                r.strike().phi_deg());
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
        case v1::shot_end: notes.push_back(SummaryLine(e.summary())); break;
        default: break;
      }
    }
    const bool interesting = !notes.empty() || s.at_rest() != last_at_rest_ || s.resync();
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
    std::fflush(stdout);
  }

 private:
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
      case Format::kJson:
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

int RunTable(const Context& ctx, const std::vector<std::string>& args) {
  static constexpr const char* kVerbs =
      "create, list, get, delete, reset, place, shoot, turn, watch";
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
  return UsageError("unknown table subcommand '" + verb + "' (" + kVerbs + ")");
}

}  // namespace sportsim::cli
