// Shared pieces of the `sportsim` command-line tool.
#ifndef SPORTSIM_CLIENT_CLI_H_
#define SPORTSIM_CLIENT_CLI_H_

#include <cstdint>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <google/protobuf/message.h>
#include <grpcpp/channel.h>
#include <grpcpp/client_context.h>
#include <grpcpp/support/status.h>

#include "absl/time/time.h"

namespace sportsim::cli {

enum class Format { kText, kJson, kJsonl, kCsv };

struct Context {
  std::string server;
  Format format = Format::kText;
  absl::Duration timeout;
  std::shared_ptr<grpc::Channel> channel;
  /// A client context with the deadline set.
  std::unique_ptr<grpc::ClientContext> NewCall() const;
};

/// Exit status for usage errors (bad flags or arguments): sysexits' EX_USAGE, distinct from
/// every gRPC code number.
inline constexpr int kUsageExit = 64;

/// The name of a gRPC status code number ("NOT_FOUND"); "UNKNOWN" outside 0..16.
const char* CodeName(int code);
/// Prints "sportsim: CODE_NAME: message" to stderr; returns the exit status (the code number).
int ReportRpcError(const grpc::Status& status);
/// A value the CLI checks itself (a number out of its range, a rack without the ball to strike)
/// is reported as the server would report it: marked by this prefix, UsageError prints
/// "sportsim: INVALID_ARGUMENT: message" and returns that code's number. Flags it does not
/// know and malformed arguments stay usage errors.
inline constexpr std::string_view kInvalidValue = "INVALID_ARGUMENT: ";
inline std::string InvalidValue(std::string_view message) {
  return std::string(kInvalidValue) + std::string(message);
}
/// Prints "sportsim: usage: message" to stderr and returns kUsageExit, or, for a message made
/// by InvalidValue, "sportsim: INVALID_ARGUMENT: message" and returns 3.
int UsageError(std::string_view message);

/// One JSON document (or one line, for jsonl) from a message, with proto field names and every
/// field present. Protobuf's own JSON printer, not a hand-written one.
std::string ToJson(const google::protobuf::Message& message, bool one_line);

/// `--format json` on a stream (table watch, swing watch, swing drive): one JSON document, an
/// array of the items, each written (and flushed) as it comes; the array is closed when the
/// writer goes (the command ends, by its condition, the stream's end or an error), so the output
/// of a command that ends is one valid document. Does nothing unless `on`.
class JsonArrayStream {
 public:
  explicit JsonArrayStream(bool on) : on_(on) {}
  JsonArrayStream(const JsonArrayStream&) = delete;
  JsonArrayStream& operator=(const JsonArrayStream&) = delete;
  ~JsonArrayStream() { Close(); }
  /// One item, a JSON value on one line, complete as soon as it is written: "[" alone on the
  /// first line, then the items one a line, every one but the first led by its comma.
  void Add(const std::string& json) {
    std::cout << (items_++ == 0 ? "[\n" : ",") << json << "\n" << std::flush;
  }
  void Close() {
    if (!on_ || closed_) return;
    closed_ = true;
    std::cout << (items_ == 0 ? "[]\n" : "]\n") << std::flush;
  }

 private:
  bool on_;
  bool closed_ = false;
  int64_t items_ = 0;
};

/// Shortest decimal text that reads back as the same double.
std::string Num(double v);

/// Prints a simulate response in the context's format: protobuf's JSON for json/jsonl, the
/// command's own CSV and text writers otherwise. Returns the exit status (0).
template <typename Response, typename CsvFn, typename TextFn>
int PrintResponse(const Context& ctx, const Response& response, CsvFn csv, TextFn text) {
  switch (ctx.format) {
    case Format::kJson: std::cout << ToJson(response, false) << "\n"; break;
    case Format::kJsonl: std::cout << ToJson(response, true) << "\n"; break;
    case Format::kCsv: csv(response); break;
    case Format::kText: text(response); break;
  }
  return 0;
}

int RunInfo(const Context& ctx, const std::vector<std::string>& args);
int RunHealth(const Context& ctx, const std::vector<std::string>& args);
int RunSwing(const Context& ctx, const std::vector<std::string>& args);
int RunFlight(const Context& ctx, const std::vector<std::string>& args);
int RunGolf(const Context& ctx, const std::vector<std::string>& args);
int RunCourse(const Context& ctx, const std::vector<std::string>& args);
int RunShot(const Context& ctx, const std::vector<std::string>& args);
int RunTable(const Context& ctx, const std::vector<std::string>& args);
int RunRound(const Context& ctx, const std::vector<std::string>& args);

/// A usage error's message when a games flag (--game, --race-to, --shot-clock, --start, --rule,
/// --call, --safety, --push-out, --nominate, --choice) is given to a command that does not take
/// it; nullopt when every one given applies.
std::optional<std::string> CheckGameFlags(std::string_view command, std::string_view sub);

/// --seats in [1, 16] and --tick-hz in [1, 1000] when given, --seat-names each once: table
/// and swing create (defined in table_commands.cc).
std::optional<std::string> CheckSeatFlags();
/// --page-size in [0, 1000]: table and swing list.
std::optional<std::string> CheckPageSize();

/// Exit status of `swing drive` when the server refused any of stdin's commands (sysexits'
/// EX_DATAERR): the swing ran, but not as the input asked.
inline constexpr int kRefusedCommandsExit = 65;

/// Whether a flag (absl name, with underscores: "race_to") was written on the command line.
bool FlagGiven(std::string_view name);

/// Values of a repeatable flag (--ball, --param), in command-line order. absl flags keep only
/// the last value, so main() takes these out of argv before parsing.
const std::vector<std::string>& RepeatedFlagValues(std::string_view name);

}  // namespace sportsim::cli

#endif  // SPORTSIM_CLIENT_CLI_H_
