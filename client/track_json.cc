#include "client/track_json.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>

#include <cmath>
#include <string>

#include "absl/strings/str_format.h"
#include "sim/core/quote.h"

namespace sportsim::cli {
namespace {

// The first of a key's names that the object has, or null.
const google::protobuf::Value* Field(const google::protobuf::Struct& o, const char* a,
                                     const char* b) {
  if (auto it = o.fields().find(a); it != o.fields().end()) return &it->second;
  if (auto it = o.fields().find(b); it != o.fields().end()) return &it->second;
  return nullptr;
}

}  // namespace

absl::StatusOr<billiards::TrackFile> ParseTrackJsonLines(std::string_view text) {
  billiards::TrackBuilder rows;
  size_t pos = 0;
  for (int line_no = 1; pos <= text.size(); ++line_no) {
    const size_t nl = text.find('\n', pos);
    std::string_view line =
        text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    pos = nl == std::string_view::npos ? text.size() + 1 : nl + 1;
    while (!line.empty() && (line.front() == ' ' || line.front() == '\t')) line.remove_prefix(1);
    while (!line.empty() && (line.back() == ' ' || line.back() == '\t' || line.back() == '\r')) {
      line.remove_suffix(1);
    }
    if (line.empty() || line.front() == '#') continue;
    google::protobuf::Struct o;
    const auto parsed = google::protobuf::util::JsonStringToMessage(std::string(line), &o);
    if (!parsed.ok()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "line %d: not a JSON object: %s", line_no, QuoteInput(std::string(parsed.message()), 80)));
    }
    static constexpr const char* kNames[4][2] = {{"t", "t_s"}, {"ball", "id"}, {"x", "x_m"},
                                                 {"y", "y_m"}};
    const google::protobuf::Value* v[4];
    for (int k = 0; k < 4; ++k) {
      v[k] = Field(o, kNames[k][0], kNames[k][1]);
      if (v[k] == nullptr) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "line %d: no %s (or %s) key", line_no, kNames[k][0], kNames[k][1]));
      }
      if (k != 1 && !v[k]->has_number_value()) {
        return absl::InvalidArgumentError(
            absl::StrFormat("line %d: %s must be a number", line_no, kNames[k][0]));
      }
    }
    std::string id;
    if (v[1]->has_string_value()) {
      id = v[1]->string_value();
    } else if (v[1]->has_number_value() && v[1]->number_value() == std::floor(v[1]->number_value()) &&
               std::abs(v[1]->number_value()) < 1e15) {
      id = absl::StrFormat("%.0f", v[1]->number_value());
    } else {
      return absl::InvalidArgumentError(absl::StrFormat(
          "line %d: ball must be a string or a whole number", line_no));
    }
    if (absl::Status s = rows.Add(line_no, v[0]->number_value(), id, v[2]->number_value(),
                                  v[3]->number_value());
        !s.ok()) {
      return s;
    }
  }
  return std::move(rows).Finish();
}

absl::StatusOr<billiards::TrackFile> ParseTrackText(std::string_view text) {
  for (size_t pos = 0; pos < text.size();) {
    const char c = text[pos];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
      ++pos;
    } else if (c == '#') {
      const size_t nl = text.find('\n', pos);
      pos = nl == std::string_view::npos ? text.size() : nl + 1;
    } else {
      return c == '{' ? ParseTrackJsonLines(text) : billiards::ParseTrackCsv(text);
    }
  }
  return billiards::ParseTrackCsv(text);
}

}  // namespace sportsim::cli
