// `sportsim swing create|list|get|delete|reset|start|watch|drive`: live swing sessions
// (Swing/CreateSession ... WatchSwing, DriveSwing). `swing simulate` is in swing_commands.cc.
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/flags/declare.h"
#include "absl/flags/flag.h"
#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "absl/strings/string_view.h"
#include "client/cli.h"
#include "client/swing_flags.h"
#include "client/swing_svg.h"
#include "sportsim/v1/swing.grpc.pb.h"

// Shared with the table commands (table_commands.cc, shot_commands.cc) and swing simulate.
ABSL_DECLARE_FLAG(int, seats);
ABSL_DECLARE_FLAG(std::vector<std::string>, seat_names);
ABSL_DECLARE_FLAG(double, tick_hz);
ABSL_DECLARE_FLAG(std::string, token);
ABSL_DECLARE_FLAG(std::optional<double>, rate);
ABSL_DECLARE_FLAG(std::optional<uint64_t>, from_sequence);
ABSL_DECLARE_FLAG(int, page_size);
ABSL_DECLARE_FLAG(std::string, page_token);
ABSL_DECLARE_FLAG(std::string, svg);
ABSL_DECLARE_FLAG(std::optional<double>, gamma);
ABSL_DECLARE_FLAG(std::optional<double>, beta0);

ABSL_FLAG(std::string, profile, "",
          "swing create: realistic (human limits) or arcade (none); default realistic");
ABSL_FLAG(bool, until_impact, false,
          "swing watch: exit after the impact (or the end of the swing in progress)");
ABSL_FLAG(bool, apply_late, false,
          "swing drive: a late command applies at the next tick instead of being refused");

namespace sportsim::cli {
namespace {

using Stub = v1::Swing::Stub;

// csv is refused before any call (RunSwingSession), so these print json, jsonl or text.
template <typename Response>
int Print(const Context& ctx, const Response& r, const std::function<void()>& text) {
  return PrintResponse(ctx, r, [](const Response&) {}, [&](const Response&) { text(); });
}

const char* PhaseText(v1::SwingPhase phase) {
  switch (phase) {
    case v1::SWING_PHASE_ADDRESS: return "address";
    case v1::SWING_PHASE_SWINGING: return "swinging";
    case v1::SWING_PHASE_FINISHED: return "finished";
    default: return "unknown";
  }
}

unsigned long long Ull(uint64_t v) { return static_cast<unsigned long long>(v); }
long long Ll(int64_t v) { return static_cast<long long>(v); }

// ---------------------------------------------------------------------------------------------
// Unary calls

int RunCreate(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("swing create takes flags only, got '" + args[0] + "'");
  v1::CreateSessionRequest request;
  if (auto bad = BuildSwingParameters(request.mutable_parameters())) return UsageError(*bad);
  if (auto bad = BuildSwingSolver(request.mutable_solver())) return UsageError(*bad);
  std::vector<v1::SwingEffect> disabled;
  if (auto bad = BuildSwingEffects(&disabled)) return UsageError(*bad);
  for (v1::SwingEffect e : disabled) request.add_disabled_effects(e);
  if (auto bad = CheckSeatFlags()) return UsageError(*bad);
  request.set_seats(static_cast<uint32_t>(absl::GetFlag(FLAGS_seats)));
  for (const std::string& n : absl::GetFlag(FLAGS_seat_names)) request.add_seat_names(n);
  request.set_tick_hz(absl::GetFlag(FLAGS_tick_hz));
  const std::string profile = absl::GetFlag(FLAGS_profile);
  if (profile == "realistic") request.set_profile(v1::REALISM_PROFILE_REALISTIC);
  else if (profile == "arcade") request.set_profile(v1::REALISM_PROFILE_ARCADE);
  else if (!profile.empty()) {
    return UsageError("--profile must be realistic or arcade, got '" + profile + "'");
  }
  // --club: every impact launches this ball and flies it (as swing simulate --club does).
  if (auto bad = BuildBallStrike(request.mutable_ball())) return UsageError(*bad);
  if (request.ball().club().empty()) request.clear_ball();
  v1::CreateSessionResponse r;
  const grpc::Status status = stub.CreateSession(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("session %s: %s, %g Hz, %s profile, tick %lld\n", r.session_id().c_str(),
                r.integrator().c_str(), r.tick_hz(), r.profile().c_str(), Ll(r.tick()));
    for (const v1::Seat& s : r.seats()) {
      std::printf("  seat %u %-10s token %s\n", s.seat(), s.name().c_str(), s.token().c_str());
    }
    if (request.has_ball()) {
      std::printf("  each impact launches a ball (%s) and flies it\n", request.ball().club().c_str());
    }
  });
}

int RunList(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("swing list takes flags only");
  v1::ListSessionsRequest request;
  if (auto bad = CheckPageSize()) return UsageError(*bad);
  request.set_page_size(static_cast<uint32_t>(absl::GetFlag(FLAGS_page_size)));
  request.set_page_token(absl::GetFlag(FLAGS_page_token));
  v1::ListSessionsResponse r;
  const grpc::Status status = stub.ListSessions(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("%u sessions\n", r.total());
    for (const v1::SessionBrief& b : r.sessions()) {
      std::printf("  %-16s %-9s tick %-10lld %g Hz, %llu swings, %u watchers\n",
                  b.session_id().c_str(), PhaseText(b.phase()), Ll(b.tick()), b.tick_hz(),
                  Ull(b.swings()), b.watchers());
    }
    if (!r.next_page_token().empty()) {
      std::printf("more: --page-token %s\n", r.next_page_token().c_str());
    }
  });
}

int RunGet(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("swing get ID");
  v1::GetSessionRequest request;
  request.set_session_id(args[0]);
  v1::SessionInfo r;
  const grpc::Status status = stub.GetSession(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("session %s: %s, tick %lld at %g Hz, %s%s, %s profile, %llu swings, %u "
                "watchers, sequence %llu\n",
                r.session_id().c_str(), PhaseText(r.phase()), Ll(r.tick()), r.tick_hz(),
                r.integrator().c_str(),
                r.dt_s() > 0 ? absl::StrFormat(" (dt %g s)", r.dt_s()).c_str() : "",
                r.profile().c_str(), Ull(r.swings()), r.watchers(), Ull(r.sequence()));
    std::printf("  address: gamma %g deg, beta0 %g deg\n", r.gamma_deg(), r.beta0_deg());
    if (r.has_state()) {
      const v1::SwingSample& s = r.state();
      std::printf("  state (swing %llu): t %.4f s  theta %.3f  alpha %.3f  beta %.3f  phi %.3f "
                  "deg  clubhead %.3f m/s\n",
                  Ull(r.swing_id()), s.t_s(), s.theta_deg(), s.alpha_deg(), s.beta_deg(),
                  s.phi_deg(), s.clubhead_speed_mps());
    }
    if (r.has_last_impact()) {
      std::printf("  last impact: t = %.9f s, clubhead %.4f m/s (%.4f m/s over the ground)\n",
                  r.last_impact().t_s(), r.last_impact().clubhead_speed_mps(),
                  r.last_impact().clubhead_speed_ground_mps());
    }
    if (!r.last_end_reason().empty()) {
      std::printf("  last swing ended: %s\n", r.last_end_reason().c_str());
    }
  });
}

int RunDelete(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("swing delete ID --token T");
  v1::DeleteSessionRequest request;
  request.set_session_id(args[0]);
  request.set_token(absl::GetFlag(FLAGS_token));
  if (request.token().empty()) return UsageError("swing delete needs --token (a seat's token)");
  v1::DeleteSessionResponse r;
  const grpc::Status status = stub.DeleteSession(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] { std::printf("deleted %s\n", args[0].c_str()); });
}

int RunReset(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("swing reset ID --token T [--gamma DEG] [--beta0 DEG]");
  v1::ResetSwingRequest request;
  request.set_session_id(args[0]);
  request.set_token(absl::GetFlag(FLAGS_token));
  if (request.token().empty()) return UsageError("swing reset needs --token (a seat's token)");
  if (const auto v = absl::GetFlag(FLAGS_gamma)) request.set_gamma_deg(*v);
  if (const auto v = absl::GetFlag(FLAGS_beta0)) request.set_beta0_deg(*v);
  v1::ResetSwingResponse r;
  const grpc::Status status = stub.ResetSwing(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("back at the address position at tick %lld (sequence %llu)\n", Ll(r.tick()),
                Ull(r.sequence()));
  });
}

int RunStart(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) return UsageError("swing start ID --token T (torque flags)");
  v1::StartSwingRequest request;
  request.set_session_id(args[0]);
  request.set_token(absl::GetFlag(FLAGS_token));
  if (request.token().empty()) return UsageError("swing start needs --token (a seat's token)");
  v1::TorqueProgram torques;
  if (auto bad = BuildTorqueProgram(&torques)) return UsageError(*bad);
  if (torques.has_qalpha() || torques.has_qbeta()) *request.mutable_torques() = torques;
  v1::SwingStop stop = v1::SWING_STOP_UNSPECIFIED;
  std::optional<double> duration;
  if (auto bad = BuildSwingStop(&stop, &duration)) return UsageError(*bad);
  request.set_stop(stop);
  if (duration) request.set_duration_s(*duration);
  v1::StartSwingResponse r;
  const grpc::Status status = stub.StartSwing(ctx.NewCall().get(), request, &r);
  if (!status.ok()) return ReportRpcError(status);
  return Print(ctx, r, [&] {
    std::printf("swing %llu starts at tick %lld (sequence %llu)\n", Ull(r.swing_id()),
                Ll(r.start_tick()), Ull(r.sequence()));
  });
}

// ---------------------------------------------------------------------------------------------
// Streams (watch, drive): one line per snapshot with a state

// The impact a snapshot carries, if any.
const v1::SwingImpact* ImpactOf(const v1::SwingSnapshot& s) {
  for (const v1::SwingEvent& e : s.events()) {
    if (e.kind() == v1::SWING_EVENT_IMPACT && e.has_impact()) return &e.impact();
  }
  return nullptr;
}

// One JSON line: the sample's keys (protobuf's JSON of SwingSample, as in `swing simulate`'s
// samples), then the snapshot's sequence, tick, swing, phase and torques, the impact (the keys of
// `swing simulate`'s impact) when the snapshot carries it, and its events when it has any.
std::string JsonLine(const v1::SwingSnapshot& s, const v1::SwingImpact* impact) {
  std::vector<std::string> members;
  if (s.has_state()) {
    // Protobuf's one-line object, {"t_s":...}: its members spliced in.
    const std::string sample = ToJson(s.state(), true);
    if (sample.size() > 2) members.push_back(sample.substr(1, sample.size() - 2));
  }
  members.push_back(absl::StrCat("\"sequence\":", s.sequence(), ",\"tick\":", s.tick(),
                                 ",\"swing_id\":", s.swing_id(), ",\"phase\":\"",
                                 v1::SwingPhase_Name(s.phase()), "\",\"qalpha_nm\":",
                                 Num(s.qalpha_nm()), ",\"qbeta_nm\":", Num(s.qbeta_nm())));
  if (impact != nullptr) members.push_back("\"impact\":" + ToJson(*impact, true));
  if (s.events_size() > 0) {
    std::string events = "\"events\":[";
    for (int i = 0; i < s.events_size(); ++i) {
      if (i > 0) events += ',';
      events += ToJson(s.events(i), true);
    }
    members.push_back(events + "]");
  }
  if (s.resync()) {
    members.push_back(absl::StrCat("\"resync\":true,\"events_lost\":", s.events_lost()));
  }
  std::string line = "{";
  for (size_t i = 0; i < members.size(); ++i) {
    if (i > 0) line += ',';
    line += members[i];
  }
  return line + "}";
}

// A readable note for an event (nothing for COMMAND_REFUSED: the driver reports those on
// stderr).
std::string EventNote(const v1::SwingEvent& e) {
  switch (e.kind()) {
    case v1::SWING_EVENT_STARTED:
      return absl::StrFormat("swing %d started by seat %d (%s)", e.swing_id(), e.seat(),
                             e.driven() ? "driven" : "torque schedule");
    case v1::SWING_EVENT_TORQUE:
      return absl::StrFormat("torques %g, %g N m from t = %.4f s (command %d, for t = %.4f s)",
                             e.qalpha_nm(), e.qbeta_nm(), e.t_s(), e.command(), e.command_t_s());
    case v1::SWING_EVENT_IMPACT:
      return absl::StrFormat("impact at t = %.9f s: clubhead %.4f m/s (%.4f m/s over the ground)",
                             e.impact().t_s(), e.impact().clubhead_speed_mps(),
                             e.impact().clubhead_speed_ground_mps());
    case v1::SWING_EVENT_ENDED:
      return absl::StrFormat("swing %d ended at t = %.4f s: %s", e.swing_id(), e.t_s(),
                             e.reason());
    case v1::SWING_EVENT_RESET: return "back at the address position";
    case v1::SWING_EVENT_BEYOND_HUMAN:
      return absl::StrFormat("beyond human at t = %.4f s: %s", e.t_s(), e.reason());
    case v1::SWING_EVENT_BALL_LAUNCH:
      return absl::StrFormat("ball launched at %.2f m/s, %.2f deg up, %.0f rpm backspin",
                             e.ball().launch().ball_speed_mps(),
                             e.ball().launch().launch_angle_deg(), e.ball().backspin_rpm());
    case v1::SWING_EVENT_LANDING:
      return absl::StrFormat("ball lands at t = %.4f s: carry %.2f m, %.2f m %s of the line",
                             e.t_s(), e.ball().flight().carry_m(),
                             std::abs(e.ball().flight().lateral_m()),
                             e.ball().flight().lateral_m() >= 0 ? "right" : "left");
    default: return "";
  }
}

// Prints a stream's snapshots in the context's format: a line per snapshot with a state (json
// and jsonl alike), csv rows under one header, or a readable table with event notes.
// Heartbeats print nothing.
class StreamPrinter {
 public:
  explicit StreamPrinter(Format format) : format_(format), document_(format == Format::kJson) {}

  void Add(const v1::SwingSnapshot& s) {
    if (s.heartbeat()) return;
    const v1::SwingImpact* impact = ImpactOf(s);
    switch (format_) {
      case Format::kJson:
        if (s.has_state() || impact != nullptr) document_.Add(JsonLine(s, impact));
        break;
      case Format::kJsonl:
        if (s.has_state() || impact != nullptr) std::cout << JsonLine(s, impact) << std::endl;
        break;
      case Format::kCsv:
        if (!s.has_state()) break;
        if (!header_done_) std::cout << SwingCsvHeader();
        header_done_ = true;
        std::cout << SwingCsvRow(s.state()) << std::flush;
        break;
      case Format::kText: Text(s); break;
    }
  }

 private:
  void Text(const v1::SwingSnapshot& s) {
    if (!header_done_) {
      std::printf("%10s %9s %9s %9s %9s %10s  %s\n", "t_s", "theta_deg", "alpha_deg",
                  "beta_deg", "phi_deg", "speed_mps", "phase");
      header_done_ = true;
    }
    if (s.has_state()) {
      const v1::SwingSample& x = s.state();
      std::printf("%10.4f %9.3f %9.3f %9.3f %9.3f %10.4f  %s\n", x.t_s(), x.theta_deg(),
                  x.alpha_deg(), x.beta_deg(), x.phi_deg(), x.clubhead_speed_mps(),
                  PhaseText(s.phase()));
    }
    for (const v1::SwingEvent& e : s.events()) {
      const std::string note = EventNote(e);
      if (!note.empty()) std::printf("    %s\n", note.c_str());
    }
    if (s.resync()) std::printf("    (resync: %llu events lost)\n", Ull(s.events_lost()));
    std::fflush(stdout);
  }

  Format format_;
  JsonArrayStream document_;  // --format json: the snapshots as one array
  bool header_done_ = false;
};

// Whether a swing ended with this snapshot: its ENDED event (or its impact, when asked), or, if
// events were lost, a phase other than swinging after the swing was seen.
class SwingEnd {
 public:
  explicit SwingEnd(bool at_impact) : at_impact_(at_impact) {}

  bool Add(const v1::SwingSnapshot& s) {
    for (const v1::SwingEvent& e : s.events()) {
      if (e.kind() == v1::SWING_EVENT_ENDED) return true;
      if (at_impact_ && e.kind() == v1::SWING_EVENT_IMPACT) return true;
    }
    if (s.phase() == v1::SWING_PHASE_SWINGING) {
      saw_swinging_ = true;
    } else if (saw_swinging_ && s.phase() != v1::SWING_PHASE_UNSPECIFIED) {
      return true;
    }
    return false;
  }

 private:
  bool at_impact_;
  bool saw_swinging_ = false;
};

void StartDrawing(SwingDrawing* drawing) {
  drawing->arm_length_m = ArmLengthFlag();
  drawing->club_length_m = ClubLengthFlag();
}

int WriteDrawing(const std::string& path, SwingDrawing* drawing, const std::string& session) {
  drawing->title = drawing->swing_id > 0
                       ? absl::StrFormat("swing session %s, swing %d", session, drawing->swing_id)
                       : absl::StrFormat("swing session %s: no swing seen", session);
  std::ofstream out(path);
  out << SwingSvg(*drawing);
  if (!out) return UsageError("cannot write --svg file '" + path + "'");
  return 0;
}

int RunWatch(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) {
    return UsageError("swing watch ID [--rate HZ] [--until-impact] [--from-sequence N] "
                      "[--svg FILE]");
  }
  v1::WatchSwingRequest request;
  request.set_session_id(args[0]);
  request.set_rate_hz(absl::GetFlag(FLAGS_rate).value_or(0.0));
  if (const auto from = absl::GetFlag(FLAGS_from_sequence)) request.set_from_sequence(*from);
  const bool until_impact = absl::GetFlag(FLAGS_until_impact);
  const std::string svg = absl::GetFlag(FLAGS_svg);
  SwingDrawing drawing;
  StartDrawing(&drawing);

  grpc::ClientContext call;  // no deadline: a stream lives as long as the session
  std::unique_ptr<grpc::ClientReader<v1::SwingSnapshot>> reader = stub.WatchSwing(&call, request);
  StreamPrinter printer(ctx.format);
  SwingEnd end(/*at_impact=*/true);
  v1::SwingSnapshot s;
  bool done = false;
  while (!done && reader->Read(&s)) {
    printer.Add(s);
    if (!svg.empty()) AddSnapshot(s, &drawing);
    if (until_impact && end.Add(s)) done = true;
  }
  grpc::Status status;
  if (done) {
    call.TryCancel();
    (void)reader->Finish();
  } else {
    status = reader->Finish();
  }
  if (!svg.empty()) {
    if (const int code = WriteDrawing(svg, &drawing, args[0]); code != 0) return code;
  }
  if (!status.ok()) return ReportRpcError(status);
  return 0;
}

// Lines of stdin, read with poll() so that a stop request ends the wait (a blocked
// std::getline cannot be interrupted).
class StdinLines {
 public:
  enum class Result { kLine, kEof, kStopped };

  /// Waits for the next line (without its newline); with `stop`, checks it every 100 ms.
  Result Next(std::string* line, const std::atomic<bool>* stop) {
    while (true) {
      const size_t nl = buffer_.find('\n');
      if (nl != std::string::npos) {
        *line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        return Result::kLine;
      }
      if (eof_) {
        if (buffer_.empty()) return Result::kEof;
        *line = buffer_;
        buffer_.clear();
        return Result::kLine;
      }
      if (stop != nullptr && stop->load()) return Result::kStopped;
      pollfd fd{};
      fd.fd = STDIN_FILENO;
      fd.events = POLLIN;
      const int ready = poll(&fd, 1, stop != nullptr ? 100 : -1);
      if (ready < 0 && errno != EINTR) eof_ = true;
      if (ready <= 0) continue;
      char chunk[4096];
      const ssize_t n = read(STDIN_FILENO, chunk, sizeof(chunk));
      if (n > 0) {
        buffer_.append(chunk, static_cast<size_t>(n));
      } else if (n == 0 || (errno != EINTR && errno != EAGAIN)) {
        eof_ = true;
      }
    }
  }

 private:
  std::string buffer_;
  bool eof_ = false;
};

struct DriveCommand {
  double t_s = 0;
  double qalpha_nm = 0;
  double qbeta_nm = 0;
};

// Torque commands from stdin, one "t_s,qalpha_nm,qbeta_nm" a line; blank lines and lines
// starting with '#' skipped.
class CommandInput {
 public:
  enum class Result { kCommand, kEof, kStopped, kBad };

  /// The next command; kBad sets `error` to a usage message naming the line.
  Result Next(DriveCommand* command, const std::atomic<bool>* stop, std::string* error) {
    std::string line;
    while (true) {
      switch (lines_.Next(&line, stop)) {
        case StdinLines::Result::kEof: return Result::kEof;
        case StdinLines::Result::kStopped: return Result::kStopped;
        case StdinLines::Result::kLine: break;
      }
      ++line_number_;
      const absl::string_view text = absl::StripAsciiWhitespace(line);
      if (text.empty() || text[0] == '#') continue;
      const std::vector<absl::string_view> parts = absl::StrSplit(text, ',');
      double v[3] = {0, 0, 0};
      bool ok = parts.size() == 3;
      for (size_t i = 0; ok && i < 3; ++i) {
        ok = absl::SimpleAtod(absl::StripAsciiWhitespace(parts[i]), &v[i]);
      }
      if (!ok) {
        *error = absl::StrFormat(
            "stdin line %d must be t_s,qalpha_nm,qbeta_nm (numbers), got '%s'", line_number_,
            text);
        return Result::kBad;
      }
      *command = DriveCommand{.t_s = v[0], .qalpha_nm = v[1], .qbeta_nm = v[2]};
      ++commands_;
      return Result::kCommand;
    }
  }

  /// The commands read so far.
  int commands() const { return commands_; }

 private:
  int commands_ = 0;
  StdinLines lines_;
  int line_number_ = 0;
};

void ReportRefused(const v1::SwingEvent& e) {
  std::cerr << absl::StrFormat(
      "sportsim: command %d (t_s %s, qalpha %s N m, qbeta %s N m) refused: %s: %s\n",
      e.command(), Num(e.command_t_s()), Num(e.qalpha_nm()), Num(e.qbeta_nm()),
      CodeName(e.code()), e.reason());
}

int RunDrive(const Context& ctx, Stub& stub, const std::vector<std::string>& args) {
  if (args.size() != 1) {
    return UsageError("swing drive ID --token T [--rate HZ] [--apply-late] [--until "
                      "impact|duration] [--duration S] [--svg FILE], torques "
                      "t_s,qalpha_nm,qbeta_nm on stdin");
  }
  v1::DriveStart start;
  start.set_session_id(args[0]);
  start.set_token(absl::GetFlag(FLAGS_token));
  if (start.token().empty()) return UsageError("swing drive needs --token (a seat's token)");
  start.set_rate_hz(absl::GetFlag(FLAGS_rate).value_or(0.0));
  v1::SwingStop stop = v1::SWING_STOP_UNSPECIFIED;
  std::optional<double> duration;
  if (auto bad = BuildSwingStop(&stop, &duration)) return UsageError(*bad);
  start.set_stop(stop);
  if (duration) start.set_duration_s(*duration);
  start.set_apply_late(absl::GetFlag(FLAGS_apply_late));
  const std::string svg = absl::GetFlag(FLAGS_svg);
  SwingDrawing drawing;
  StartDrawing(&drawing);

  // The first command: at t = 0 its torques are the start's (until the next command); any
  // other time is sent as a command, the torques being 0 until then.
  CommandInput input;
  bool first_in_start = false;  // the first line gave the start's torques (not a command)
  std::optional<DriveCommand> pending;
  std::string input_error;
  {
    DriveCommand first;
    switch (input.Next(&first, nullptr, &input_error)) {
      case CommandInput::Result::kBad: return UsageError(input_error);
      case CommandInput::Result::kCommand:
        if (first.t_s == 0) {
          first_in_start = true;
          start.set_qalpha_nm(first.qalpha_nm);
          start.set_qbeta_nm(first.qbeta_nm);
        } else {
          pending = first;
        }
        break;
      default: break;
    }
  }

  grpc::ClientContext call;  // no deadline: the stream lives as long as the swing
  std::unique_ptr<grpc::ClientReaderWriter<v1::DriveSwingRequest, v1::SwingSnapshot>> stream =
      stub.DriveSwing(&call);
  v1::DriveSwingRequest opening;
  *opening.mutable_start() = start;

  // Commands go out from a thread of their own as stdin's lines arrive, while this thread reads
  // the states. Writes hold write_mu; writes_open turns false at the half-close.
  std::mutex write_mu;
  bool writes_open = true;
  std::atomic<bool> stop_input{false};
  std::thread writer;
  if (stream->Write(opening)) {
    writer = std::thread([&] {
      std::optional<DriveCommand> next = pending;
      while (true) {
        DriveCommand command;
        if (next) {
          command = *next;
          next.reset();
        } else {
          const CommandInput::Result got = input.Next(&command, &stop_input, &input_error);
          if (got == CommandInput::Result::kBad) call.TryCancel();
          if (got != CommandInput::Result::kCommand) return;
        }
        v1::DriveSwingRequest message;
        message.mutable_torque()->set_t_s(command.t_s);
        message.mutable_torque()->set_qalpha_nm(command.qalpha_nm);
        message.mutable_torque()->set_qbeta_nm(command.qbeta_nm);
        const std::lock_guard<std::mutex> lock(write_mu);
        if (!writes_open || !stream->Write(message)) return;
      }
    });
  }
  // The end of stdin means no more commands, not the end of the swing: the stream stays open
  // until the swing ends (the server then ends it), and is half-closed at that point.
  const auto close_writes = [&] {
    stop_input = true;
    if (writer.joinable()) writer.join();
    const std::lock_guard<std::mutex> lock(write_mu);
    if (writes_open) {
      writes_open = false;
      (void)stream->WritesDone();
    }
  };

  StreamPrinter printer(ctx.format);
  SwingEnd end(/*at_impact=*/false);
  bool ended = false;
  int refused = 0;
  v1::SwingSnapshot s;
  while (stream->Read(&s)) {
    for (const v1::SwingEvent& e : s.events()) {
      if (e.kind() == v1::SWING_EVENT_COMMAND_REFUSED) {
        ReportRefused(e);
        ++refused;
      }
    }
    printer.Add(s);
    if (!svg.empty()) AddSnapshot(s, &drawing);
    if (!ended && end.Add(s)) {
      ended = true;
      close_writes();
    }
  }
  close_writes();
  const grpc::Status status = stream->Finish();
  if (!svg.empty()) {
    if (const int code = WriteDrawing(svg, &drawing, args[0]); code != 0) return code;
  }
  if (!input_error.empty()) return UsageError(input_error);
  if (!status.ok()) return ReportRpcError(status);
  if (refused > 0) {
    std::cerr << absl::StrFormat("sportsim: %d of %d commands refused\n", refused,
                                 std::max(refused, input.commands() - (first_in_start ? 1 : 0)));
    return kRefusedCommandsExit;
  }
  return 0;
}

}  // namespace

int RunSwingSession(const Context& ctx, const std::string& verb,
                    const std::vector<std::string>& args) {
  if (ctx.format == Format::kCsv && verb != "watch" && verb != "drive") {
    return UsageError("swing " + verb + " has no csv form (json, jsonl or text)");
  }
  std::unique_ptr<Stub> stub = v1::Swing::NewStub(ctx.channel);
  if (verb == "create") return RunCreate(ctx, *stub, args);
  if (verb == "list") return RunList(ctx, *stub, args);
  if (verb == "get") return RunGet(ctx, *stub, args);
  if (verb == "delete") return RunDelete(ctx, *stub, args);
  if (verb == "reset") return RunReset(ctx, *stub, args);
  if (verb == "start") return RunStart(ctx, *stub, args);
  if (verb == "watch") return RunWatch(ctx, *stub, args);
  if (verb == "drive") return RunDrive(ctx, *stub, args);
  return UsageError("unknown swing subcommand '" + verb + "'");
}

}  // namespace sportsim::cli
