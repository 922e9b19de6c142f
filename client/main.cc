// sportsim: the command-line client. `sportsim --help` for commands; DESIGN.md's command-line
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
#include "absl/strings/str_cat.h"
#include "client/cli.h"
#include "client/game_text.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "sportsim/v1/common.grpc.pb.h"

ABSL_FLAG(std::string, server, "127.0.0.1:50051", "Server address host:port");
ABSL_FLAG(std::string, format, "text", "Output: text, json, jsonl or csv");
ABSL_FLAG(absl::Duration, timeout, absl::Seconds(30), "Deadline for each call");

namespace sportsim::cli {
namespace {

constexpr const char* kUsage = R"(sportsim [--server HOST:PORT] [--format text|json|jsonl|csv] COMMAND ...

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
      [--seats N] [--seat-names A,B] [--profile realistic|arcade]   a live swing session;
      prints its id and seat 0's token
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
  shot simulate [flags]     fast-forward one cue shot until every ball is at rest:
      --table pool-7ft|pool-8ft|pool-9ft|snooker|carom|unbounded  --rack RACK
      [--ball ID@X,Y ...] (--speed V0 | --ball-speed V) [--phi DEG] [--theta DEG] [--a A]
      [--b B] [--engine event|stepped] [--integrator euler|semi_implicit_euler|rk4] [--dt S]
      [--no-ccd] [--disable EFFECT,...] [--enable drag] [--param NAME=VALUE ...]
      [--cushion-model han|mirror] [--noise X --seed N] [--jitter M --rack-seed N]
      [--sample-rate HZ] [--max-time S] [--svg FILE]
  table create [setup and solver flags of shot simulate] [--seats N] [--seat-names A,B]
      [--tick-hz HZ]                       an authoritative table; prints the seat tokens
      [--game free|8ball|9ball|10ball|snooker|three-cushion --race-to N --shot-clock S
      --start break|in-play --rule NAME=VALUE ... --noise X --seed N]   a ruled game (the
      server referees; prints the admin token too)
  table list [--page-size N --page-token T] | table get ID [--geometry]
  table shoot ID --token T [strike flags of shot simulate] [--next-seat N]
      [--call BALL:POCKET | --safety] [--push-out] [--nominate BALL]
  table decide ID --token T --choice CHOICE   answer a pending decision (ruled games)
  table concede ID --token T [--seat N]       concede the frame (admin token: for seat N)
  table record ID                             the match record, one line per action
  table place ID --token T --ball ID@X,Y   ball in hand (the seat to play, balls at rest)
  table turn ID --token T --seat N | table reset ID --token T | table delete ID --token T
  table watch ID [--rate HZ] [--until-rest] [--fields position,velocity,spin,orientation]
      [--changed-only] [--from-sequence N] [--svg FILE]   snapshots as they come
Flags may be written --name value or --name=value; dashes and underscores are the same.
Errors: the gRPC status code name and message on stderr, exit status = the code number
(64 for usage errors). --helpfull lists every flag.)";

constexpr std::string_view kRepeatable[] = {"ball", "param", "rule"};

std::map<std::string, std::vector<std::string>, std::less<>>& Repeated() {
  static auto* values = new std::map<std::string, std::vector<std::string>, std::less<>>();
  return *values;
}

// Names (with underscores) of the flags written on the command line.
std::set<std::string, std::less<>>& Given() {
  static auto* names = new std::set<std::string, std::less<>>();
  return *names;
}

// absl flag names cannot contain '-': accept --qbeta-until for --qbeta_until. Repeatable flags
// (--ball ID@X,Y, --param NAME=VALUE, --rule NAME=VALUE) are taken out here, since absl keeps only a flag's last
// value and splits vectors at commas.
std::vector<std::string> NormalizeFlagNames(int argc, char** argv) {
  std::vector<std::string> out;
  bool flags_done = false;
  for (int i = 0; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--") flags_done = true;
    if (!flags_done && a.size() > 2 && a[0] == '-' && a[1] == '-') {
      const size_t eq = a.find('=');
      const std::string name = a.substr(2, eq == std::string::npos ? std::string::npos : eq - 2);
      bool repeatable = false;
      for (std::string_view r : kRepeatable) repeatable |= name == r;
      if (repeatable) {
        if (eq != std::string::npos) {
          Repeated()[name].push_back(a.substr(eq + 1));
        } else if (i + 1 < argc) {
          Repeated()[name].push_back(argv[++i]);
        } else {
          Repeated()[name].push_back("");
        }
        continue;
      }
    }
    if (!flags_done && i > 0 && a.size() > 2 && a[0] == '-' && a[1] == '-') {
      const size_t end = a.find('=');
      for (size_t j = 2; j < std::min(end, a.size()); ++j) {
        if (a[j] == '-') a[j] = '_';
      }
      Given().insert(a.substr(2, end == std::string::npos ? std::string::npos : end - 2));
    }
    out.push_back(std::move(a));
  }
  return out;
}

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
// type and keeping the printer's layout (indentation, key order) for everything else.
constexpr std::string_view kPrunedType = "sportsim.v1.GameState";

bool HasPrunedType(const google::protobuf::Descriptor* d,
                   std::set<const google::protobuf::Descriptor*>* seen) {
  if (d->full_name() == kPrunedType) return true;
  if (!seen->insert(d).second) return false;
  for (int i = 0; i < d->field_count(); ++i) {
    const google::protobuf::Descriptor* m = d->field(i)->message_type();
    if (m != nullptr && HasPrunedType(m, seen)) return true;
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
    const bool prune = type != nullptr && !map_values && type->full_name() == kPrunedType;
    std::vector<std::string> items;
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
      const bool drop = prune && f != nullptr && f->is_repeated() && Empty(value);
      if (Peek() == ',') {
        ++pos_;
        item += tail;
        tail = Space();
      }
      if (!drop) items.push_back(std::move(item));
    }
    ++pos_;  // }
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

int ReportRpcError(const grpc::Status& status) {
  const int code = static_cast<int>(status.error_code());
  std::cerr << "sportsim: " << CodeName(code) << ": " << status.error_message() << "\n";
  return code == 0 ? 1 : code;
}

int UsageError(std::string_view message) {
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
  return Int64AsNumbers(message.GetDescriptor(), PruneGameJson(message.GetDescriptor(), out));
}

bool FlagGiven(std::string_view name) { return Given().contains(name); }

const std::vector<std::string>& RepeatedFlagValues(std::string_view name) {
  static const std::vector<std::string> kNone;
  auto it = Repeated().find(name);
  return it == Repeated().end() ? kNone : it->second;
}

std::string Num(double v) {
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
  absl::SetProgramUsageMessage(kUsage);
  std::vector<std::string> normalized = NormalizeFlagNames(argc, argv);
  std::vector<char*> args_c;
  for (std::string& s : normalized) args_c.push_back(s.data());
  std::vector<char*> positional =
      absl::ParseCommandLine(static_cast<int>(args_c.size()), args_c.data());

  Context ctx;
  ctx.server = absl::GetFlag(FLAGS_server);
  ctx.timeout = absl::GetFlag(FLAGS_timeout);
  const std::string format = absl::GetFlag(FLAGS_format);
  if (format == "text") ctx.format = Format::kText;
  else if (format == "json") ctx.format = Format::kJson;
  else if (format == "jsonl") ctx.format = Format::kJsonl;
  else if (format == "csv") ctx.format = Format::kCsv;
  else return UsageError("--format must be text, json, jsonl or csv, got '" + format + "'");

  if (positional.size() < 2) {
    std::cerr << kUsage << "\n";
    return kUsageExit;
  }
  const std::string command = positional[1];
  std::vector<std::string> rest(positional.begin() + 2, positional.end());
  // Sampled trajectories can be large: accept what the server may send (64 MiB).
  grpc::ChannelArguments channel_args;
  channel_args.SetMaxReceiveMessageSize(64 << 20);
  ctx.channel = grpc::CreateCustomChannel(ctx.server, grpc::InsecureChannelCredentials(),
                                          channel_args);
  if (auto bad = CheckGameFlags(command, rest.empty() ? "" : rest[0])) return UsageError(*bad);
  if (command == "info") return RunInfo(ctx, rest);
  if (command == "health") return RunHealth(ctx, rest);
  if (command == "swing") return RunSwing(ctx, rest);
  if (command == "flight") return RunFlight(ctx, rest);
  if (command == "shot") return RunShot(ctx, rest);
  if (command == "table") return RunTable(ctx, rest);
  return UsageError("unknown command '" + command + "' (info, health, swing, flight, shot, table)");
}
