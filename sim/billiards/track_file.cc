#include "sim/billiards/track_file.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <optional>

#include "absl/strings/str_format.h"
#include "sim/core/quote.h"

namespace sportsim::billiards {
namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  if (s.size() >= 2 && s.front() == '"' && s.back() == '"') s = s.substr(1, s.size() - 2);
  return s;
}

std::vector<std::string_view> Cells(std::string_view line) {
  std::vector<std::string_view> out;
  size_t start = 0;
  for (;;) {
    const size_t comma = line.find(',', start);
    out.push_back(Trim(line.substr(start, comma == std::string_view::npos ? comma : comma - start)));
    if (comma == std::string_view::npos) return out;
    start = comma + 1;
  }
}

std::optional<double> Number(std::string_view s) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

}  // namespace

TrackFrame TrackFrameOn(const TableSpec& spec, bool from_corner, double scale) {
  TrackFrame frame{.scale = scale, .table_m = Eigen::Vector2d(spec.length_m, spec.width_m)};
  if (from_corner) frame.origin = -frame.table_m / 2;
  return frame;
}

absl::Status ValidateTrackFrame(const TrackFrame& frame) {
  if (!std::isfinite(frame.scale) || frame.scale <= 0.0 || frame.scale > 1e6) {
    return absl::InvalidArgumentError(
        absl::StrFormat("frame.scale: must be a finite number in (0, 1e6], got %g", frame.scale));
  }
  if (!frame.origin.allFinite() || frame.origin.cwiseAbs().maxCoeff() > 1e6) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "frame.origin: must be finite and within 1e6 m, got (%g, %g)", frame.origin.x(),
        frame.origin.y()));
  }
  if (!frame.table_m.allFinite() || frame.table_m.minCoeff() < 0.0 || frame.table_m.maxCoeff() > 1e3) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "frame.table_m: must be finite and within [0, 1e3] m, got (%g, %g)", frame.table_m.x(),
        frame.table_m.y()));
  }
  return absl::OkStatus();
}

absl::Status TrackBuilder::Add(int line, double t, std::string_view id, double x, double y) {
  if (++rows_ > kMaxTrackRows) {
    return absl::InvalidArgumentError(
        absl::StrFormat("line %d: at most %d rows", line, kMaxTrackRows));
  }
  const double v[3] = {t, x, y};
  static constexpr const char* kWhat[3] = {"t", "x", "y"};
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(v[k]) || std::abs(v[k]) > 1e6) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "line %d: %s must be a finite number within 1e6, got %g", line, kWhat[k], v[k]));
    }
  }
  if (id.empty()) {
    return absl::InvalidArgumentError(absl::StrFormat("line %d: the ball's id is empty", line));
  }
  auto it = index_.find(id);
  if (it == index_.end()) {
    it = index_.emplace(std::string(id), static_cast<int>(out_.balls.size())).first;
    out_.balls.emplace_back(id);
    before_.emplace_back();
    first_.emplace_back();
  }
  const int b = it->second;
  const Eigen::Vector2d xy = frame_.origin + frame_.scale * Eigen::Vector2d(x, y);
  if (t <= 0.0) {
    before_[static_cast<size_t>(b)] = xy;
  } else {
    out_.points.push_back(TrackPoint{.t_s = t, .ball = b, .xy = xy});
    auto& f = first_[static_cast<size_t>(b)];
    if (!f || t < f->first) f = std::make_pair(t, xy);
  }
  return absl::OkStatus();
}

absl::StatusOr<TrackFile> TrackBuilder::Finish() && {
  if (out_.balls.empty()) return absl::InvalidArgumentError("the file has no rows");
  std::stable_sort(out_.points.begin(), out_.points.end(),
                   [](const TrackPoint& a, const TrackPoint& b) { return a.t_s < b.t_s; });
  for (size_t b = 0; b < out_.balls.size(); ++b) {
    out_.spots.push_back(before_[b] ? *before_[b] : first_[b]->second);
  }
  // The struck ball: the first to depart from its spot (Departs: a point away and the next
  // farther along the same line; a single point away is a tracker's false detection), else the
  // first seen away at all.
  std::vector<const TrackPoint*> last(out_.balls.size(), nullptr);
  std::optional<int> once;
  for (const TrackPoint& p : out_.points) {
    const size_t b = static_cast<size_t>(p.ball);
    if (last[b] != nullptr && Departs(out_.spots[b], *last[b], p)) {
      out_.cue = p.ball;
      break;
    }
    last[b] = &p;
    if (!once && (p.xy - out_.spots[b]).norm() >= kStruckDistance) once = p.ball;
  }
  if (out_.cue < 0 && once) out_.cue = *once;
  return std::move(out_);
}

absl::StatusOr<TrackFile> ParseTrackCsv(std::string_view text, const TrackFrame& frame) {
  if (absl::Status s = ValidateTrackFrame(frame); !s.ok()) return s;
  TrackBuilder rows(frame);
  // Column indices of t, ball, x, y once the header is read.
  int col[4] = {-1, -1, -1, -1};
  bool header = false;
  size_t pos = 0;
  for (int line_no = 1; pos <= text.size(); ++line_no) {
    const size_t nl = text.find('\n', pos);
    const std::string_view line =
        text.substr(pos, nl == std::string_view::npos ? std::string_view::npos : nl - pos);
    pos = nl == std::string_view::npos ? text.size() + 1 : nl + 1;
    const std::string_view trimmed = Trim(line);
    if (trimmed.empty() || trimmed.front() == '#') continue;
    const std::vector<std::string_view> cells = Cells(line);
    if (!header) {
      static constexpr std::string_view kNames[4][2] = {
          {"t", "t_s"}, {"ball", "id"}, {"x", "x_m"}, {"y", "y_m"}};
      for (int c = 0; c < static_cast<int>(cells.size()); ++c) {
        std::string name(cells[static_cast<size_t>(c)]);
        std::transform(name.begin(), name.end(), name.begin(),
                       [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
        for (int k = 0; k < 4; ++k) {
          if ((name == kNames[k][0] || name == kNames[k][1]) && col[k] < 0) col[k] = c;
        }
      }
      for (int k = 0; k < 4; ++k) {
        if (col[k] < 0) {
          return absl::InvalidArgumentError(absl::StrFormat(
              "line %d: the header must name the columns t, ball, x and y (or t_s, id, x_m, "
              "y_m); no %s column",
              line_no, kNames[k][0]));
        }
      }
      header = true;
      continue;
    }
    const int need = *std::max_element(col, col + 4) + 1;
    if (static_cast<int>(cells.size()) < need) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "line %d: %d cells, the header's columns need %d", line_no, cells.size(), need));
    }
    double v[3];
    static constexpr const char* kWhat[3] = {"t", "x", "y"};
    static constexpr int kCol[3] = {0, 2, 3};
    for (int k = 0; k < 3; ++k) {
      const std::string_view cell = cells[static_cast<size_t>(col[kCol[k]])];
      const std::optional<double> n = Number(cell);
      if (!n || std::abs(*n) > 1e6) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "line %d: %s must be a finite number within 1e6, got %s", line_no, kWhat[k], QuoteInput(cell)));
      }
      v[k] = *n;
    }
    if (absl::Status s = rows.Add(line_no, v[0], cells[static_cast<size_t>(col[1])], v[1], v[2]);
        !s.ok()) {
      return s;
    }
  }
  if (!header) return absl::InvalidArgumentError("the file has no header row (t, ball, x, y)");
  return std::move(rows).Finish();
}

}  // namespace sportsim::billiards
