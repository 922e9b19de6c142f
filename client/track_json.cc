#include "client/track_json.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "sim/core/quote.h"

namespace sportsim::cli {
namespace {

// The first of a key's names that the object has, or null.
const google::protobuf::Value* Field(const google::protobuf::Struct& o, const char* a,
                                     const char* b = nullptr) {
  if (auto it = o.fields().find(a); it != o.fields().end()) return &it->second;
  if (b == nullptr) return nullptr;
  if (auto it = o.fields().find(b); it != o.fields().end()) return &it->second;
  return nullptr;
}

// A ball's or a shot's id: a string, or a whole number written without its fraction.
std::optional<std::string> IdOf(const google::protobuf::Value& v) {
  if (v.has_string_value()) return v.string_value();
  if (v.has_number_value() && v.number_value() == std::floor(v.number_value()) &&
      std::abs(v.number_value()) < 1e15) {
    return absl::StrFormat("%.0f", v.number_value());
  }
  return std::nullopt;
}

}  // namespace

absl::StatusOr<billiards::TrackFile> ParseTrackJsonLines(std::string_view text,
                                                         const billiards::TrackFrame& frame) {
  if (absl::Status s = billiards::ValidateTrackFrame(frame); !s.ok()) return s;
  billiards::TrackBuilder rows(frame);
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
    const std::optional<std::string> id = IdOf(*v[1]);
    if (!id) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "line %d: ball must be a string or a whole number", line_no));
    }
    if (absl::Status s = rows.Add(line_no, v[0]->number_value(), *id, v[2]->number_value(),
                                  v[3]->number_value());
        !s.ok()) {
      return s;
    }
  }
  return std::move(rows).Finish();
}

absl::StatusOr<billiards::TrackFile> ParseTrackText(std::string_view text,
                                                    const billiards::TrackFrame& frame) {
  for (size_t pos = 0; pos < text.size();) {
    const char c = text[pos];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') {
      ++pos;
    } else if (c == '#') {
      const size_t nl = text.find('\n', pos);
      pos = nl == std::string_view::npos ? text.size() : nl + 1;
    } else {
      return c == '{' ? ParseTrackJsonLines(text, frame) : billiards::ParseTrackCsv(text, frame);
    }
  }
  return billiards::ParseTrackCsv(text, frame);
}

namespace {

// Samples in all of a set's shots, against kMaxShotSetSamples.
struct SampleCount {
  int64_t set = 0;
  absl::Status Add(int64_t shot_samples, int64_t n) {
    set += n;
    if (set > kMaxShotSetSamples) {
      return absl::InvalidArgumentError(absl::StrFormat("at most %d samples in a set", kMaxShotSetSamples));
    }
    if (shot_samples > billiards::kMaxTrackRows) {
      return absl::InvalidArgumentError(
          absl::StrFormat("at most %d samples in a shot", billiards::kMaxTrackRows));
    }
    return absl::OkStatus();
  }
};

// A finite number within 1e6, or nullopt.
std::optional<double> SampleOf(const google::protobuf::Value& e) {
  if (!e.has_number_value() || !std::isfinite(e.number_value()) || std::abs(e.number_value()) > 1e6) {
    return std::nullopt;
  }
  return e.number_value();
}

// An array of shots, each {"id": ..., "balls": {ID: {"t": [...], "x": [...], "y": [...]}}}.
absl::StatusOr<std::vector<NamedTrack>> FromShotArray(const google::protobuf::ListValue& list,
                                                      const billiards::TrackFrame& frame) {
  const auto& shots = list.values();
  if (shots.empty()) return absl::InvalidArgumentError("the shot set has no shots");
  if (shots.size() > kMaxShotsPerSet) {
    return absl::InvalidArgumentError(
        absl::StrFormat("at most %d shots in a set, got %d", kMaxShotsPerSet, shots.size()));
  }
  std::vector<NamedTrack> out;
  SampleCount count;
  for (int i = 0; i < shots.size(); ++i) {
    const auto fail = [&](const std::string& what) {
      return absl::InvalidArgumentError(absl::StrFormat("shot %d: %s", i, what));
    };
    if (!shots[i].has_struct_value()) return fail("must be a JSON object");
    const google::protobuf::Struct& shot = shots[i].struct_value();
    NamedTrack track;
    const google::protobuf::Value* id = Field(shot, "id", "name");
    if (id == nullptr) id = Field(shot, "shotID", "shot_id");
    if (id != nullptr) {
      const std::optional<std::string> name = IdOf(*id);
      if (!name) return fail("id must be a string or a whole number");
      track.name = *name;
    } else {
      track.name = std::to_string(i);
    }
    const google::protobuf::Value* balls = Field(shot, "balls");
    if (balls == nullptr || !balls->has_struct_value() || balls->struct_value().fields().empty()) {
      return fail("no balls (an object of ball ids to their samples)");
    }
    // A map has no order: the balls go in the order of their ids, so the file is the same
    // however the document was read.
    std::vector<std::pair<std::string, const google::protobuf::Value*>> by_id;
    for (const auto& [ball_id, v] : balls->struct_value().fields()) by_id.emplace_back(ball_id, &v);
    std::sort(by_id.begin(), by_id.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    billiards::TrackBuilder rows(frame);
    int64_t shot_samples = 0;
    for (const auto& [ball_id, v] : by_id) {
      const std::string ball = "ball " + QuoteInput(ball_id);
      if (ball_id.empty()) return fail("a ball's id is empty");
      if (!v->has_struct_value()) return fail(ball + ": must be an object of t, x and y arrays");
      static constexpr const char* kNames[3][2] = {{"t", "t_s"}, {"x", "x_m"}, {"y", "y_m"}};
      const google::protobuf::ListValue* col[3];
      for (int k = 0; k < 3; ++k) {
        const google::protobuf::Value* c = Field(v->struct_value(), kNames[k][0], kNames[k][1]);
        if (c == nullptr || !c->has_list_value()) {
          return fail(absl::StrFormat("%s: no %s (or %s) array", ball, kNames[k][0], kNames[k][1]));
        }
        col[k] = &c->list_value();
      }
      const int n = col[0]->values_size();
      if (col[1]->values_size() != n || col[2]->values_size() != n) {
        return fail(absl::StrFormat("%s: t, x and y must have the same length, got %d, %d and %d",
                                    ball, n, col[1]->values_size(), col[2]->values_size()));
      }
      shot_samples += n;
      if (absl::Status s = count.Add(shot_samples, n); !s.ok()) return fail(std::string(s.message()));
      for (int j = 0; j < n; ++j) {
        double v3[3];
        for (int k = 0; k < 3; ++k) {
          const std::optional<double> e = SampleOf(col[k]->values(j));
          if (!e) {
            return fail(absl::StrFormat("%s: %s[%d] must be a finite number within 1e6", ball,
                                        kNames[k][0], j));
          }
          v3[k] = *e;
        }
        // The checks above leave Add nothing to refuse.
        if (absl::Status s = rows.Add(j + 1, v3[0], ball_id, v3[1], v3[2]); !s.ok()) {
          return fail(ball + ": " + std::string(s.message()));
        }
      }
    }
    absl::StatusOr<billiards::TrackFile> file = std::move(rows).Finish();
    if (!file.ok()) return fail(std::string(file.status().message()));
    track.file = *std::move(file);
    out.push_back(std::move(track));
  }
  return out;
}

// A match tracker's frame: fractions of the playing area from a corner, which needs the
// table's size and takes no origin or scale.
absl::StatusOr<billiards::TrackFrame> TrackerCorner(const billiards::TrackFrame& frame) {
  if (!(frame.table_m.x() > 0 && frame.table_m.y() > 0)) {
    return absl::InvalidArgumentError(
        "a match tracker's export measures in fractions of the playing area: give the table");
  }
  if (frame.scale != 1.0 || !frame.origin.isZero()) {
    return absl::InvalidArgumentError(
        "a match tracker's export sets its own frame (fractions of the playing area from a "
        "corner): give no origin or scale");
  }
  return billiards::TrackFrame{.origin = -frame.table_m / 2};
}

// One tracked entry of a match tracker's export (`path` names it in errors): its
// PathTracking's data sets, each a ball and its coordinates; nullopt for an entry without
// tracking data, which is not a shot.
absl::StatusOr<std::optional<NamedTrack>> EntryTrack(const google::protobuf::Struct& entry,
                                                     const std::string& path,
                                                     const billiards::TrackFrame& frame,
                                                     const billiards::TrackFrame& corner,
                                                     SampleCount& count) {
  const google::protobuf::Value* tracking = Field(entry, "PathTracking");
  if (tracking == nullptr || !tracking->has_struct_value()) return std::nullopt;  // not tracked
  const google::protobuf::Value* data = Field(tracking->struct_value(), "DataSets");
  if (data == nullptr || !data->has_list_value() || data->list_value().values_size() == 0) {
    return std::nullopt;
  }
  NamedTrack track;
  if (const google::protobuf::Value* id = Field(entry, "PathTrackingId")) {
    const std::optional<std::string> name = IdOf(*id);
    if (!name) {
      return absl::InvalidArgumentError(path + ".PathTrackingId: must be a string or a whole number");
    }
    track.name = *name;
  }
  billiards::TrackBuilder rows(corner);
  int64_t shot_samples = 0;
  std::vector<std::string> seen;
  for (int d = 0; d < data->list_value().values_size(); ++d) {
    const google::protobuf::Value& ds = data->list_value().values(d);
    const std::string ds_path = absl::StrFormat("%sPathTracking.DataSets[%d]",
                                                path.empty() ? "" : path + ".", d);
    const auto fail = [&](const std::string& what) {
      return absl::InvalidArgumentError(ds_path + what);
    };
    if (!ds.has_struct_value()) return fail(": must be an object");
    const google::protobuf::Value* color = Field(ds.struct_value(), "BallColor");
    const std::optional<std::string> ball =
        color != nullptr && color->has_number_value() ? IdOf(*color) : std::nullopt;
    if (!ball) return fail(".BallColor: must be a whole number");
    if (std::find(seen.begin(), seen.end(), *ball) != seen.end()) {
      return fail(".BallColor: ball " + *ball + " is tracked twice in the shot");
    }
    seen.push_back(*ball);
    const google::protobuf::Value* coords = Field(ds.struct_value(), "Coords");
    if (coords == nullptr || !coords->has_list_value()) return fail(".Coords: must be an array");
    const int n = coords->list_value().values_size();
    shot_samples += n;
    if (absl::Status st = count.Add(shot_samples, n); !st.ok()) {
      return absl::InvalidArgumentError((path.empty() ? "" : path + ": ") + std::string(st.message()));
    }
    for (int j = 0; j < n; ++j) {
      const google::protobuf::Value& c = coords->list_value().values(j);
      static constexpr const char* kKeys[3] = {"DeltaT_500us", "X", "Y"};
      double v3[3];
      for (int k = 0; k < 3; ++k) {
        const google::protobuf::Value* f =
            c.has_struct_value() ? Field(c.struct_value(), kKeys[k], kKeys[k]) : nullptr;
        const std::optional<double> x = f != nullptr ? SampleOf(*f) : std::nullopt;
        if (!x) {
          return fail(absl::StrFormat(".Coords[%d].%s: must be a finite number within 1e6", j,
                                      kKeys[k]));
        }
        v3[k] = *x;
      }
      // Ticks of 500 us; fractions of the length and the width from the corner.
      if (absl::Status st = rows.Add(j + 1, 5e-4 * v3[0], *ball, v3[1] * frame.table_m.x(),
                                     v3[2] * frame.table_m.y());
          !st.ok()) {
        return fail(absl::StrFormat(".Coords[%d]: %s", j, st.message()));
      }
    }
  }
  absl::StatusOr<billiards::TrackFile> file = std::move(rows).Finish();
  if (!file.ok()) {
    return absl::InvalidArgumentError((path.empty() ? "" : path + ": ") +
                                      std::string(file.status().message()));
  }
  track.file = *std::move(file);
  return track;
}

// A match-tracking document: {"Match": {"Sets": [{"Entries": [{"PathTrackingId": ...,
// "PathTracking": {"DataSets": [{"BallColor": 1, "Coords": [{"DeltaT_500us": 0, "X": 0.2,
// "Y": 0.6}, ...]}]}}]}]}}, positions as fractions of the playing area's length and width from
// a corner, times in units of 500 us. Entries without tracking data are not shots.
absl::StatusOr<std::vector<NamedTrack>> FromMatchTracking(const google::protobuf::Struct& doc,
                                                          const billiards::TrackFrame& frame) {
  absl::StatusOr<billiards::TrackFrame> corner = TrackerCorner(frame);
  if (!corner.ok()) return corner.status();
  const google::protobuf::Value* match = Field(doc, "Match");
  const google::protobuf::Value* sets =
      match != nullptr && match->has_struct_value() ? Field(match->struct_value(), "Sets")
                                                    : nullptr;
  if (sets == nullptr || !sets->has_list_value()) {
    return absl::InvalidArgumentError("Match.Sets: must be an array of sets");
  }
  std::vector<NamedTrack> out;
  SampleCount count;
  for (int s = 0; s < sets->list_value().values_size(); ++s) {
    const google::protobuf::Value& set = sets->list_value().values(s);
    const std::string set_path = absl::StrFormat("Match.Sets[%d]", s);
    const google::protobuf::Value* entries =
        set.has_struct_value() ? Field(set.struct_value(), "Entries") : nullptr;
    if (entries == nullptr) continue;  // a set without shots
    if (!entries->has_list_value()) {
      return absl::InvalidArgumentError(set_path + ".Entries: must be an array");
    }
    for (int e = 0; e < entries->list_value().values_size(); ++e) {
      const google::protobuf::Value& entry = entries->list_value().values(e);
      const std::string path = absl::StrFormat("%s.Entries[%d]", set_path, e);
      if (!entry.has_struct_value()) return absl::InvalidArgumentError(path + ": must be an object");
      absl::StatusOr<std::optional<NamedTrack>> track =
          EntryTrack(entry.struct_value(), path, frame, *corner, count);
      if (!track.ok()) return track.status();
      if (!track->has_value()) continue;
      if (static_cast<int>(out.size()) == kMaxShotsPerSet) {
        return absl::InvalidArgumentError(absl::StrFormat("at most %d shots in a set", kMaxShotsPerSet));
      }
      if ((*track)->name.empty()) (*track)->name = absl::StrFormat("%d.%d", s, e);
      out.push_back(**std::move(track));
    }
  }
  if (out.empty()) return absl::InvalidArgumentError("Match: no entry has tracking data");
  return out;
}

// A tracker's export of one entry, a shot on its own: {"PathTracking": {"DataSets": [...]},
// ...}, as in a match-tracking document; named by its PathTrackingId when it has one.
absl::StatusOr<std::vector<NamedTrack>> FromTrackerEntry(const google::protobuf::Struct& doc,
                                                         const billiards::TrackFrame& frame) {
  absl::StatusOr<billiards::TrackFrame> corner = TrackerCorner(frame);
  if (!corner.ok()) return corner.status();
  SampleCount count;
  absl::StatusOr<std::optional<NamedTrack>> track = EntryTrack(doc, "", frame, *corner, count);
  if (!track.ok()) return track.status();
  if (!track->has_value()) {
    return absl::InvalidArgumentError("PathTracking.DataSets: must be a non-empty array of balls");
  }
  return std::vector<NamedTrack>{**std::move(track)};
}

// A document's shots, whichever of the two layouts it has.
absl::StatusOr<std::vector<NamedTrack>> FromDocument(const google::protobuf::Value& doc,
                                                     const billiards::TrackFrame& frame) {
  if (doc.has_list_value()) return FromShotArray(doc.list_value(), frame);
  if (doc.has_struct_value() && Field(doc.struct_value(), "Match") != nullptr) {
    return FromMatchTracking(doc.struct_value(), frame);
  }
  if (doc.has_struct_value() && Field(doc.struct_value(), "PathTracking") != nullptr) {
    return FromTrackerEntry(doc.struct_value(), frame);
  }
  return absl::InvalidArgumentError(
      "a shot set must be a JSON array of shots, a match-tracking document (\"Match\") or a "
      "tracker's entry (\"PathTracking\")");
}

}  // namespace

absl::StatusOr<std::vector<NamedTrack>> ParseShotSet(std::string_view text,
                                                     const billiards::TrackFrame& frame) {
  if (absl::Status s = billiards::ValidateTrackFrame(frame); !s.ok()) return s;
  google::protobuf::Value doc;
  if (const auto parsed = google::protobuf::util::JsonStringToMessage(std::string(text), &doc);
      !parsed.ok()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "not a JSON document: %s", QuoteInput(std::string(parsed.message()), 80)));
  }
  return FromDocument(doc, frame);
}

absl::StatusOr<std::vector<NamedTrack>> ParseTracks(std::string_view text,
                                                    const billiards::TrackFrame& frame) {
  const size_t first = text.find_first_not_of(" \t\r\n");
  if (first != std::string_view::npos && text[first] == '[') return ParseShotSet(text, frame);
  if (first != std::string_view::npos && text[first] == '{') {
    // One JSON object holding "Match" is a match-tracking document, one holding "PathTracking"
    // a tracker's entry; anything else that starts with '{' is JSON lines (a one-line file of
    // them is a JSON object too).
    google::protobuf::Value doc;
    if (google::protobuf::util::JsonStringToMessage(std::string(text), &doc).ok() &&
        doc.has_struct_value() && (Field(doc.struct_value(), "Match") != nullptr ||
                                   Field(doc.struct_value(), "PathTracking") != nullptr)) {
      if (absl::Status s = billiards::ValidateTrackFrame(frame); !s.ok()) return s;
      return FromDocument(doc, frame);
    }
  }
  absl::StatusOr<billiards::TrackFile> file = ParseTrackText(text, frame);
  if (!file.ok()) return file.status();
  std::vector<NamedTrack> out(1);
  out[0].file = *std::move(file);
  return out;
}
}  // namespace sportsim::cli
