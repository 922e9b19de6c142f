// sportsim: the command-line client. `sportsim --help` for commands; docs/cli.md's command-line
// contract is the reference for flags and JSON keys.
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <iostream>
#include <cctype>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/flags/usage_config.h"
#include "absl/strings/str_cat.h"
#include "client/cli.h"
#include "client/command_flags.h"
#include "client/game_text.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "sportsim/v1/common.grpc.pb.h"

ABSL_FLAG(std::string, server, "127.0.0.1:50051", "Server address host:port");
ABSL_FLAG(std::string, format, "text", "Output: text, json, jsonl or csv");
ABSL_FLAG(absl::Duration, timeout, absl::Seconds(30), "Deadline for each call");

namespace sportsim::cli {
namespace {

constexpr const char* kUsage = R"(sportsim [--server HOST:PORT] [--format text|json|jsonl|csv] [--timeout D] COMMAND ...

Commands:
  info                      server version, build and capabilities
  health                    gRPC health check; exit 0 when SERVING
  swing simulate [flags]    fast-forward one golf swing (Jorgensen's double pendulum):
      --integrator book|euler|semi_implicit_euler|rk4|dp45  --dt S  --tolerance X
      --max-step S  --duration S  --until impact|duration  --qalpha NM  --qbeta NM
      --qbeta-until S  --shoulder-accel MPS2  --gamma DEG  --beta0 DEG
      --disable gravity,shoulder_accel,wrist_torque  --stride N  [golfer/club flags:
      --arm-length M --club-length M --arm-inertia KGM2 --arm-first-moment KGM
      --club-inertia KGM2 --club-mass KG --club-first-moment KGM --gravity MPS2]
  swing create [golfer/club, solver and --disable flags of swing simulate] [--tick-hz HZ]
      [--seats N] [--seat-names A,B] [--profile realistic|arcade] [--club NAME and the ball
      and air flags of swing simulate: a ball at each impact]   a live swing session; prints
      its id and the seat tokens
  swing list [--page-size N --page-token T] | swing get ID
  swing start ID --token T [torque flags of swing simulate: --qalpha --qbeta --qbeta-until
      --until --duration]            a swing with that torque program from the next tick
  swing reset ID --token T [--gamma DEG] [--beta0 DEG] | swing delete ID --token T
  swing watch ID [--rate HZ] [--until-impact] [--from-sequence N] [--svg FILE]
      one sample per state (--format jsonl|csv|text); the impact's line carries "impact"
  swing drive ID --token T [--rate HZ] [--apply-late] [--until impact|duration]
      [--duration S] [--svg FILE]    live torques from stdin, one t_s,qalpha_nm,qbeta_nm a
      line (a first line at t_s 0 gives the starting torques); prints the states as watch
  flight simulate [flags]   fly a golf ball from launch conditions to landing:
      --ball-speed MPS --launch-deg DEG --spin-rpm RPM  [--spin-axis-deg DEG]
      [--launch-direction-deg DEG] [--wind MPS[,TOWARD_DEG[,log]]] [--temperature-c C]
      [--pressure-pa PA] [--humidity F] [--altitude-m M] [--dt S] [--sample-interval S]
      [--disable drag,lift,spin_decay,wind] [--aero ferguson2022|nathan] [--svg FILE]
      (RK4 at --dt: the flight takes no --integrator, --tolerance or --max-step)
  golf simulate [flags]     a golf shot to rest on the ground: [--course practice|range|NAME]
      (practice: [--stimp FT] [--slope-pct P --slope-toward-deg D], hole at the origin;
      range: [--fairway firm|normal|soft]; a course of `course list`: [--hole N] [--tee NAME],
      its terrain, surfaces, pin and air) [--from X,Y] and one of: a launch (--ball-speed
      MPS --launch-deg DEG --spin-rpm RPM [--spin-axis-deg DEG] [--launch-direction-deg DEG]
      [--aim-deg DEG] [air flags of flight simulate]), a putt (--putt-speed MPS
      [--putt-direction-deg DEG]) or a rolling ball (--roll-speed MPS [--roll-direction-deg
      DEG]); [--disable ground_spin,ground_slope] [--sample-interval S] [--svg FILE] (the path
      from above)
  course list               the server's golf courses: holes, pars, lengths
  course show NAME [--hole N] [--svg FILE]   a course's holes (tees, pin, par, stroke index,
      length), its surfaces' constants; --svg draws it from above (surfaces, elevation)
  round create --players NAME,NAME [--course NAME] [--holes A-B] [--tees NAME,NAME]
      [--profile realistic|arcade] [--noise X] [--seed N] [--rule order=honour|ready]
      [--tick-hz HZ] [--fast-forward] [--shot-clock S]   a round of golf (stroke play);
      prints the seat tokens and the admin token
  round list | round get ID | round scorecard ID | round record ID | round delete ID --token T
  round stroke ID --token T (--ball-speed MPS --launch-deg DEG --spin-rpm RPM
      [--spin-axis-deg DEG] [--launch-direction-deg DEG] [--aim-deg DEG] | --putt-speed MPS
      [--putt-direction-deg DEG] | --club NAME [torque and golfer flags of swing simulate]
      [--face-angle-deg DEG] [--club-path-deg DEG] [--dynamic-loft-deg DEG] [--aim-deg DEG])
      [--flagstick=false]   the seat's ball, where it lies
  round decide ID --token T --choice CHOICE [--back-m M]   relief (or unplayable)
  round watch ID [--rate HZ] [--until-rest] [--from-sequence N]   the round's events
  shot simulate [flags]     fast-forward one cue shot until every ball is at rest:
      --table pool-7ft|pool-8ft|pool-9ft|snooker|carom|unbounded  --rack RACK
      [--ball ID@X,Y ...] (--speed V0 | --ball-speed V) [--phi DEG] [--theta DEG] [--a A]
      [--b B] [--engine event|stepped] [--integrator euler|semi_implicit_euler|rk4] [--dt S]
      [--no-ccd] [--disable EFFECT,...] [--enable drag] [--param NAME=VALUE ...]
      (--integrator, --dt, --no-ccd: with --engine stepped only)
      [--cushion-model han|mathavan2010|stronge|mirror] [--ball-ball-model alciatore|mathavan2014]
      [--noise X --seed N] [--jitter M --rack-seed N]
      [--sample-rate HZ] [--max-time S] [--svg FILE]
  shot batch [setup and solver flags of shot simulate] [--samples N] [--noise X] [--seed N]
      [--outcome summary|final|events] [--max-time S] < strikes.jsonl   a batch of candidate
      strikes, one CueStrike as JSON a line ({"ball_speed_mps": 2, "phi_deg": 10, "a": 0.1});
      prints one JSON outcome a line, in input order
  table create [setup and solver flags of shot simulate] [--seats N] [--seat-names A,B]
      [--tick-hz HZ]                       an authoritative table; prints the seat tokens
      [--game free|8ball|9ball|10ball|snooker|three-cushion --race-to N --shot-clock S
      --start break|in-play --rule NAME=VALUE ... --noise X --seed N]   a ruled game (the
      server referees; prints the admin token too)
  table list [--page-size N --page-token T] | table get ID [--geometry]
  table shoot ID --token T [strike flags of shot simulate] [--next-seat N]
      [--call BALL:POCKET | --safety] [--push-out] [--nominate BALL]
  table decide ID --token T --choice CHOICE   answer a pending decision (ruled games)
  table concede ID --token T [--seat N] [--frame N]  concede the frame once (admin: for seat N)
  table record ID                             the match record, one line per action
  table place ID --token T --ball ID@X,Y   ball in hand (the seat to play, balls at rest)
  table turn ID --token T --seat N | table reset ID --token T | table delete ID --token T
  table watch ID [--rate HZ] [--until-rest] [--fields position,velocity,spin,orientation]
      [--changed-only] [--from-sequence N] [--svg FILE]   snapshots as they come; --until-rest
      exits at the end of the shot in progress, or (at rest) of the next shot
Flags may be written --name value or --name=value; dashes and underscores are the same. A
flag the command does not take is a usage error. --format jsonl: streams (the watch commands,
swing drive, shot batch) only; csv: commands with a series (simulate, watch, drive) only.
Errors: the gRPC status code name and message on stderr, exit status = the code number
(64 for usage errors; 65: swing drive, some commands refused).
sportsim COMMAND SUBCOMMAND --help lists a command's flags; --helpfull lists every flag.)";

void Int64FieldNames(const google::protobuf::Descriptor* d, std::set<std::string>* names,
                     std::set<const google::protobuf::Descriptor*>* seen) {
  if (!seen->insert(d).second) return;
  for (int i = 0; i < d->field_count(); ++i) {
    const google::protobuf::FieldDescriptor* f = d->field(i);
    using FD = google::protobuf::FieldDescriptor;
    if (f->cpp_type() == FD::CPPTYPE_INT64 || f->cpp_type() == FD::CPPTYPE_UINT64) {
      names->insert(f->name());
    } else if (f->cpp_type() == FD::CPPTYPE_MESSAGE) {
      Int64FieldNames(f->message_type(), names, seen);
    }
  }
}

// Protobuf's JSON mapping quotes 64-bit integers ("tick": "120"); the command-line contract
// wants numbers, exact in every JSON reader up to 2^53 (a tick count at 1 kHz passes that after
// 285,000 years). A key is unquoted when a field of that name is 64-bit somewhere in the
// message's type tree and its value is a quoted integer. A string field sharing the name of a
// 64-bit field elsewhere would be unquoted too when it holds only digits; no sportsim message
// has such a pair today (keep it so when adding fields).
std::string Int64AsNumbers(const google::protobuf::Descriptor* d, const std::string& json) {
  std::set<std::string> names;
  std::set<const google::protobuf::Descriptor*> seen;
  Int64FieldNames(d, &names, &seen);
  if (names.empty()) return json;
  std::string out;
  out.reserve(json.size());
  size_t i = 0;
  while (i < json.size()) {
    if (json[i] != '"') {
      out += json[i++];
      continue;
    }
    // A string token: copy it, and unquote the value after it when the key is a 64-bit field.
    size_t j = i + 1;
    while (j < json.size() && json[j] != '"') j += json[j] == '\\' ? 2 : 1;
    const std::string token = json.substr(i + 1, j - i - 1);
    out.append(json, i, j - i + 1);
    i = j + 1;
    size_t k = i;
    while (k < json.size() && json[k] == ' ') ++k;
    if (k < json.size() && json[k] == ':' && names.count(token) > 0) {
      size_t v = k + 1;
      while (v < json.size() && json[v] == ' ') ++v;
      if (v < json.size() && json[v] == '"') {
        size_t e = v + 1;
        if (e < json.size() && json[e] == '-') ++e;
        const size_t digits = e;
        while (e < json.size() && std::isdigit(static_cast<unsigned char>(json[e]))) ++e;
        if (e > digits && e < json.size() && json[e] == '"') {
          out.append(json, i, v - i);
          out.append(json, v + 1, e - v - 1);
          i = e + 1;
        }
      }
    }
  }
  return out;
}

// A game's state leaves unset what does not apply to the game; its JSON says so by leaving the
// key out. Protobuf's printer (always_print_primitive_fields) already leaves out unset optional
// fields and unset messages, but prints an empty repeated field as [] and an empty map as {}:
// this pass drops those inside every GameState object, walking the JSON text along the message
// type and keeping the printer's layout (indentation, key order) for everything else. It also
// drops what means nothing where it is printed: a seat's empty token (only the create calls
// return tokens), and on a physics or table event (not a game event) the game keys reason,
// points and choices when empty or zero.
constexpr std::string_view kGameStateType = "sportsim.v1.GameState";
constexpr std::string_view kSeatType = "sportsim.v1.Seat";
constexpr std::string_view kTableEventType = "sportsim.v1.TableEvent";

bool HasPrunedType(const google::protobuf::Descriptor* d,
                   std::set<const google::protobuf::Descriptor*>* seen) {
  if (d->full_name() == kGameStateType || d->full_name() == kSeatType ||
      d->full_name() == kTableEventType) {
    return true;
  }
  if (!seen->insert(d).second) return false;
  for (int i = 0; i < d->field_count(); ++i) {
    const google::protobuf::Descriptor* m = d->field(i)->message_type();
    if (m != nullptr && HasPrunedType(m, seen)) return true;
  }
  return false;
}

// The kinds of game events (EventKind foul ... match_end), as the JSON prints them.
bool IsGameEventKind(std::string_view quoted_kind) {
  static constexpr std::string_view kGameKinds[] = {
      "\"foul\"", "\"score\"", "\"respot\"", "\"decision\"", "\"warning\"",
      "\"frame_end\"", "\"match_end\""};
  for (std::string_view k : kGameKinds) {
    if (k == quoted_kind) return true;
  }
  return false;
}

class JsonPruner {
 public:
  explicit JsonPruner(std::string_view json) : s_(json) {}

  // One JSON value; `type` is its message type when it is a message (or, for an array, the
  // type of its elements), else null. `map_values` makes an object a map with values of `type`.
  std::string Value(const google::protobuf::Descriptor* type, bool map_values = false) {
    if (Peek() == '{') return Object(type, map_values);
    if (Peek() == '[') return Array(type);
    const size_t start = pos_;
    if (Peek() == '"') {
      SkipString();
    } else {
      while (pos_ < s_.size() && s_[pos_] != ',' && s_[pos_] != '}' && s_[pos_] != ']' &&
             !std::isspace(static_cast<unsigned char>(s_[pos_]))) {
        ++pos_;
      }
    }
    return std::string(s_.substr(start, pos_ - start));
  }

  bool Done() const { return pos_ >= s_.size(); }
  std::string Rest() { return std::string(s_.substr(pos_)); }

 private:
  char Peek() const { return pos_ < s_.size() ? s_[pos_] : '\0'; }
  std::string Space() {
    const size_t start = pos_;
    while (pos_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[pos_]))) ++pos_;
    return std::string(s_.substr(start, pos_ - start));
  }
  void SkipString() {
    ++pos_;  // the opening quote
    while (pos_ < s_.size() && s_[pos_] != '"') pos_ += s_[pos_] == '\\' ? 2 : 1;
    ++pos_;
  }
  static bool Empty(std::string_view v) {
    size_t n = 0;
    for (char c : v) n += !std::isspace(static_cast<unsigned char>(c));
    return n == 2 && (v.front() == '[' || v.front() == '{');
  }
  // Items of an object or array: the space before each, its text, and the space before the
  // closing bracket. Joined back with commas as they were.
  static std::string Join(char open, const std::vector<std::string>& items,
                          const std::string& tail, char close) {
    std::string out(1, open);
    for (size_t i = 0; i < items.size(); ++i) {
      if (i > 0) out += ',';
      out += items[i];
    }
    out += tail;
    out += close;
    return out;
  }

  std::string Object(const google::protobuf::Descriptor* type, bool map_values) {
    ++pos_;  // {
    const std::string_view type_name =
        type != nullptr && !map_values ? std::string_view(type->full_name()) : "";
    struct Member {
      std::string key;
      std::string value;
      std::string item;
      const google::protobuf::FieldDescriptor* field;
    };
    std::vector<Member> members;
    std::string tail = Space();
    while (pos_ < s_.size() && Peek() != '}') {
      std::string item = tail;
      const size_t key_start = pos_;
      SkipString();
      const std::string key(s_.substr(key_start + 1, pos_ - key_start - 2));
      item += s_.substr(key_start, pos_ - key_start);
      item += Space();
      if (Peek() == ':') {
        ++pos_;
        item += ':';
      }
      item += Space();
      const google::protobuf::FieldDescriptor* f =
          map_values || type == nullptr ? nullptr : type->FindFieldByName(key);
      std::string value;
      if (map_values) {
        value = Value(type);
      } else if (f != nullptr && f->is_map()) {
        value = Value(f->message_type()->map_value()->message_type(), true);
      } else {
        value = Value(f != nullptr ? f->message_type() : nullptr);
      }
      item += value;
      tail = Space();
      if (Peek() == ',') {
        ++pos_;
        item += tail;
        tail = Space();
      }
      members.push_back({key, std::move(value), std::move(item), f});
    }
    ++pos_;  // }
    bool game_event = true;
    if (type_name == kTableEventType) {
      game_event = false;
      for (const Member& m : members) {
        if (m.key == "kind") game_event = IsGameEventKind(m.value);
      }
    }
    std::vector<std::string> items;
    for (Member& m : members) {
      bool drop = false;
      if (type_name == kGameStateType) {
        drop = m.field != nullptr && m.field->is_repeated() && Empty(m.value);
      } else if (type_name == kSeatType) {
        drop = m.key == "token" && m.value == "\"\"";
      } else if (type_name == kTableEventType && !game_event) {
        drop = (m.key == "reason" && m.value == "\"\"") || (m.key == "points" && m.value == "0") ||
               (m.key == "choices" && Empty(m.value));
      }
      if (!drop) items.push_back(std::move(m.item));
    }
    return Join('{', items, tail, '}');
  }

  std::string Array(const google::protobuf::Descriptor* type) {
    ++pos_;  // [
    std::vector<std::string> items;
    std::string tail = Space();
    while (pos_ < s_.size() && Peek() != ']') {
      std::string item = tail + Value(type);
      tail = Space();
      if (Peek() == ',') {
        ++pos_;
        item += tail;
        tail = Space();
      }
      items.push_back(std::move(item));
    }
    ++pos_;  // ]
    return Join('[', items, tail, ']');
  }

  std::string_view s_;
  size_t pos_ = 0;
};

// Protobuf prints a negative zero as -0; the contract prints 0 (a value that is zero either way
// reads the same, and `-0` surprises readers and some parsers). Outside strings only.
std::string NoNegativeZero(const std::string& json) {
  std::string out;
  out.reserve(json.size());
  for (size_t i = 0; i < json.size(); ++i) {
    const char c = json[i];
    if (c == '"') {
      const size_t start = i++;
      while (i < json.size() && json[i] != '"') i += json[i] == '\\' ? 2 : 1;
      out.append(json, start, i - start + 1);
      continue;
    }
    if (c == '-' && i + 1 < json.size() && json[i + 1] == '0') {
      const char next = i + 2 < json.size() ? json[i + 2] : ' ';
      if (next != '.' && next != 'e' && next != 'E' &&
          !std::isdigit(static_cast<unsigned char>(next))) {
        continue;  // drop the sign of "-0"
      }
    }
    out += c;
  }
  return out;
}

std::string PruneGameJson(const google::protobuf::Descriptor* d, const std::string& json) {
  std::set<const google::protobuf::Descriptor*> seen;
  if (!HasPrunedType(d, &seen)) return json;
  JsonPruner pruner(json);
  std::string out = pruner.Value(d);
  return out + pruner.Rest();
}

}  // namespace

std::unique_ptr<grpc::ClientContext> Context::NewCall() const {
  auto c = std::make_unique<grpc::ClientContext>();
  c->set_deadline(absl::ToChronoTime(absl::Now() + timeout));
  return c;
}

const char* CodeName(int code) {
  static constexpr const char* kNames[] = {
      "OK",        "CANCELLED",          "UNKNOWN",        "INVALID_ARGUMENT",
      "DEADLINE_EXCEEDED", "NOT_FOUND",  "ALREADY_EXISTS", "PERMISSION_DENIED",
      "RESOURCE_EXHAUSTED", "FAILED_PRECONDITION", "ABORTED", "OUT_OF_RANGE",
      "UNIMPLEMENTED", "INTERNAL",       "UNAVAILABLE",    "DATA_LOSS",
      "UNAUTHENTICATED"};
  return code >= 0 && code <= 16 ? kNames[code] : "UNKNOWN";
}

namespace {

// The request fields the server's messages name, and the flags that set them. A message that
// names one gets the flag appended (WithFlagNames), so that "place it with table.balls" points
// at --ball.
struct FieldFlag {
  std::string_view field;
  std::string_view flag;
};
constexpr FieldFlag kFieldFlags[] = {
    {"table.balls", "--ball"},          {"table.preset", "--table"},
    {"table.rack_jitter_m", "--jitter"}, {"table.rack", "--rack"},
    {"table.params", "--param"},        {"table.cushion_model", "--cushion-model"},
    {"table.ball_ball_model", "--ball-ball-model"},
    {"strike.ball_speed_mps", "--ball-speed"}, {"strike.speed_mps", "--speed"},
    {"strike.ball", "--strike-ball"},   {"strike.phi_deg", "--phi"},
    {"strike.theta_deg", "--theta"},    {"strike.a", "--a"},
    {"strike.b", "--b"},                {"strike.noise", "--noise"},
    {"solver.dt_s", "--dt"},            {"solver.tolerance", "--tolerance"},
    {"solver.max_step_s", "--max-step"}, {"solver.integrator", "--integrator"},
    {"solver.engine", "--engine"},      {"solver.disable", "--disable"},
    {"solver.enable", "--enable"},      {"max_time_s", "--max-time"},
    {"sample_rate_hz", "--sample-rate"}, {"tick_hz", "--tick-hz"},
    {"seat_names", "--seat-names"},     {"launch.ball_speed_mps", "--ball-speed"},
    {"launch.launch_angle_deg", "--launch-deg"}, {"launch.spin_rpm", "--spin-rpm"},
    {"launch.spin_axis_deg", "--spin-axis-deg"},
    {"launch.launch_direction_deg", "--launch-direction-deg"},
    {"sample_interval_s", "--sample-interval"}, {"duration_s", "--duration"},
    {"game.race_to", "--race-to"},      {"game.shot_clock_s", "--shot-clock"},
    {"game.rules", "--rule"},           {"game.noise", "--noise"},
    {"ball.club", "--club"},            {"ball.dynamic_loft_deg", "--dynamic-loft-deg"},
    {"ball.face_angle_deg", "--face-angle-deg"}, {"ball.club_path_deg", "--club-path-deg"},
    {"ball.cor", "--cor"},
};

bool FieldChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
}

// The flags behind the request fields a server message names, appended after the message,
// which is left verbatim: "strike.ball: no ball "x" (place it with table.balls)" gets
// " [flags: --strike-ball, --ball]". Each flag is named once, in the order of the fields'
// first mentions; whole field names only.
std::string WithFlagNames(const std::string& message) {
  std::vector<std::string_view> flags;
  for (size_t i = 0; i < message.size(); ++i) {
    if (i > 0 && (FieldChar(message[i - 1]) || message[i - 1] == '.')) continue;
    const FieldFlag* best = nullptr;
    for (const FieldFlag& f : kFieldFlags) {
      if (message.compare(i, f.field.size(), f.field) != 0) continue;
      const size_t end = i + f.field.size();
      if (end < message.size() && (FieldChar(message[end]) || message[end] == '.')) continue;
      if (best == nullptr || f.field.size() > best->field.size()) best = &f;
    }
    if (best == nullptr) continue;
    if (std::find(flags.begin(), flags.end(), best->flag) == flags.end()) {
      flags.push_back(best->flag);
    }
    i += best->field.size() - 1;
  }
  if (flags.empty()) return message;
  std::string out = message + (flags.size() == 1 ? " [flag: " : " [flags: ");
  for (size_t k = 0; k < flags.size(); ++k) {
    if (k > 0) out += ", ";
    out += flags[k];
  }
  return out + "]";
}

}  // namespace

int ReportRpcError(const grpc::Status& status) {
  const int code = static_cast<int>(status.error_code());
  std::cerr << "sportsim: " << CodeName(code) << ": " << WithFlagNames(status.error_message())
            << "\n";
  return code == 0 ? 1 : code;
}

int UsageError(std::string_view message) {
  if (message.substr(0, kInvalidValue.size()) == kInvalidValue) {
    std::cerr << "sportsim: INVALID_ARGUMENT: " << message.substr(kInvalidValue.size()) << "\n";
    return static_cast<int>(grpc::StatusCode::INVALID_ARGUMENT);
  }
  std::cerr << "sportsim: usage: " << message << "\n";
  return kUsageExit;
}

std::string ToJson(const google::protobuf::Message& message, bool one_line) {
  google::protobuf::util::JsonPrintOptions options;
  options.preserve_proto_field_names = true;
  options.always_print_primitive_fields = true;
  options.add_whitespace = !one_line;
  std::string out;
  (void)google::protobuf::util::MessageToJsonString(message, &out, options);
  return NoNegativeZero(
      Int64AsNumbers(message.GetDescriptor(), PruneGameJson(message.GetDescriptor(), out)));
}

std::string Num(double v) {
  if (v == 0) return "0";  // and not "-0"
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

int RunInfo(const Context& ctx, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("info takes no arguments");
  auto stub = v1::Server::NewStub(ctx.channel);
  v1::GetInfoResponse info;
  const grpc::Status status = stub->GetInfo(ctx.NewCall().get(), v1::GetInfoRequest(), &info);
  if (!status.ok()) return ReportRpcError(status);
  if (ctx.format == Format::kJson || ctx.format == Format::kJsonl) {
    std::cout << ToJson(info, ctx.format == Format::kJsonl) << "\n";
    return 0;
  }
  if (ctx.format == Format::kCsv) return UsageError("info has no csv form");
  const v1::Capabilities& c = info.capabilities();
  const auto list = [](const auto& items) {
    std::string s;
    for (const auto& i : items) absl::StrAppend(&s, s.empty() ? "" : ", ", i);
    return s.empty() ? std::string("(none yet)") : s;
  };
  std::cout << "sportsim " << info.version() << " (" << info.build_type() << ", "
            << info.compiler() << ", gRPC " << info.grpc_version() << ", protobuf "
            << info.protobuf_version() << ") at " << ctx.server << "\n"
            << "  billiards engines:     " << list(c.engines()) << "\n"
            << "  billiards integrators: " << list(c.integrators()) << "\n"
            << "  table presets:         " << list(c.table_presets()) << "\n"
            << "  racks:                 " << list(c.racks()) << "\n"
            << "  billiards effects:     " << list(c.effects()) << "\n"
            << "  swing integrators:     " << list(c.swing_integrators()) << "\n"
            << "  swing effects:         " << list(c.swing_effects()) << "\n"
            << "  services:              " << list(c.services()) << "\n"
            << "  golf courses:          " << list(c.golf_courses()) << "\n"
            << "  golf surfaces:         " << list(c.golf_surfaces()) << "\n"
            << "  billiards parameters (pool-9ft defaults):\n";
  const auto print_params = [](const auto& params) {
    for (const v1::ParameterInfo& p : params) {
      std::printf("    %-24s default %-10.6g range [%g, %g] %s  %s\n", p.name().c_str(),
                  p.default_value(), p.min_value(), p.max_value(), p.unit().c_str(),
                  p.description().c_str());
    }
  };
  print_params(c.parameters());
  std::cout << "  swing parameters:\n";
  print_params(c.swing_parameters());
  PrintGames(c);
  return 0;
}

int RunHealth(const Context& ctx, const std::vector<std::string>& args) {
  if (args.size() > 1) return UsageError("health takes at most one argument: a service name");
  auto stub = grpc::health::v1::Health::NewStub(ctx.channel);
  grpc::health::v1::HealthCheckRequest request;
  if (!args.empty()) request.set_service(args[0]);
  grpc::health::v1::HealthCheckResponse response;
  const grpc::Status status = stub->Check(ctx.NewCall().get(), request, &response);
  if (!status.ok()) return ReportRpcError(status);
  const std::string name = grpc::health::v1::HealthCheckResponse::ServingStatus_Name(response.status());
  if (ctx.format == Format::kJson || ctx.format == Format::kJsonl) {
    std::cout << ToJson(response, ctx.format == Format::kJsonl) << "\n";
  } else {
    std::cout << name << "\n";
  }
  return response.status() == grpc::health::v1::HealthCheckResponse::SERVING ? 0 : 1;
}

}  // namespace sportsim::cli

int main(int argc, char** argv) {
  using namespace sportsim::cli;
  // The flag library's own help (--helpfull, which this parser does not hand it) would name
  // source files by their build path: shorten them anyway, and keep the usage text ours.
  absl::FlagsUsageConfig usage_config;
  usage_config.normalize_filename = [](absl::string_view f) {
    const size_t slash = f.rfind('/');
    return std::string(slash == absl::string_view::npos ? f : f.substr(slash + 1));
  };
  absl::SetFlagsUsageConfig(usage_config);
  absl::SetProgramUsageMessage(kUsage);

  std::vector<std::string> positional;
  HelpRequest help = HelpRequest::kNone;
  if (auto bad = ParseArgs(argc, argv, &positional, &help)) return UsageError(*bad);
  if (help == HelpRequest::kHelpFull) {
    std::cout << FullHelp(kUsage);
    return 0;
  }
  if (help == HelpRequest::kHelp) {
    if (positional.empty()) {
      std::cout << kUsage << "\n";
      return 0;
    }
    const auto text = CommandHelp(positional[0], positional.size() > 1 ? positional[1] : "");
    if (!text) {
      return UsageError("no help for '" + positional[0] +
                        (positional.size() > 1 ? " " + positional[1] : std::string()) +
                        "' (commands: info, health, swing, flight, golf, course, shot, table)");
    }
    std::cout << *text;
    return 0;
  }

  Context ctx;
  ctx.server = absl::GetFlag(FLAGS_server);
  ctx.timeout = absl::GetFlag(FLAGS_timeout);
  if (!(ctx.timeout > absl::ZeroDuration()) || ctx.timeout == absl::InfiniteDuration()) {
    return UsageError("--timeout: must be a finite duration more than 0 (e.g. 500ms, 30s), got " +
                      absl::FormatDuration(ctx.timeout));
  }
  const std::string format = absl::GetFlag(FLAGS_format);
  if (format == "text") ctx.format = Format::kText;
  else if (format == "json") ctx.format = Format::kJson;
  else if (format == "jsonl") ctx.format = Format::kJsonl;
  else if (format == "csv") ctx.format = Format::kCsv;
  else return UsageError("--format: must be text, json, jsonl or csv, got '" + format + "'");

  if (positional.empty()) {
    return UsageError("give a command: info, health, swing, flight, golf, course, shot or table (sportsim "
                      "--help lists them)");
  }
  const std::string command = positional[0];
  std::vector<std::string> rest(positional.begin() + 1, positional.end());
  // Sampled trajectories can be large: accept what the server may send (64 MiB).
  grpc::ChannelArguments channel_args;
  channel_args.SetMaxReceiveMessageSize(64 << 20);
  ctx.channel = grpc::CreateCustomChannel(ctx.server, grpc::InsecureChannelCredentials(),
                                          channel_args);
  if (auto bad = CheckGameFlags(command, rest.empty() ? "" : rest[0])) return UsageError(*bad);
  const bool has_sub = command != "info" && command != "health";
  if (const CommandSpec* spec =
          FindCommand(command, has_sub ? (rest.empty() ? "" : rest[0]) : "")) {
    if (auto bad = CheckFlagsApply(*spec)) return UsageError(*bad);
    const std::string name = has_sub ? command + " " + rest[0] : command;
    if (ctx.format == Format::kCsv && !spec->series && command != "health") {
      return UsageError("--format csv: " + name + " has no csv form (json or text)");
    }
    if (ctx.format == Format::kJsonl && !spec->stream) {
      return UsageError("--format jsonl: " + name + " prints one document, not a stream "
                        "(jsonl is for table watch, swing watch, swing drive and shot batch; use "
                        "json)");
    }
  }
  if (command == "info") return RunInfo(ctx, rest);
  if (command == "health") return RunHealth(ctx, rest);
  if (command == "swing") return RunSwing(ctx, rest);
  if (command == "flight") return RunFlight(ctx, rest);
  if (command == "golf") return RunGolf(ctx, rest);
  if (command == "course") return RunCourse(ctx, rest);
  if (command == "shot") return RunShot(ctx, rest);
  if (command == "table") return RunTable(ctx, rest);
  if (command == "round") return RunRound(ctx, rest);
  return UsageError("unknown command '" + command +
                    "' (info, health, swing, flight, golf, course, shot, table, round)");
}
