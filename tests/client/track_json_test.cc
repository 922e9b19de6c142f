// Track files as JSON lines (client/track_json.h): the same shot as CSV gives the same file.
#include "client/track_json.h"

#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace sportsim::cli {
namespace {

using ::testing::HasSubstr;

void ExpectSame(const billiards::TrackFile& a, const billiards::TrackFile& b) {
  EXPECT_EQ(a.balls, b.balls);
  ASSERT_EQ(a.spots.size(), b.spots.size());
  for (size_t i = 0; i < a.spots.size(); ++i) EXPECT_EQ(a.spots[i], b.spots[i]);
  EXPECT_EQ(a.cue, b.cue);
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i].t_s, b.points[i].t_s);
    EXPECT_EQ(a.points[i].ball, b.points[i].ball);
    EXPECT_EQ(a.points[i].xy, b.points[i].xy);
  }
}

// The same rows as CSV and as JSON lines (keys in any order, either names, extra keys, numeric
// ids, comments and blank lines) read to the same file, and ParseTrackText tells them apart.
TEST(TrackJsonTest, JsonLinesReadAsTheirCsv) {
  const std::string csv =
      "t,ball,x,y\n"
      "0,white,-0.5,0.1\n"
      "0,7,0.5,0\n"
      "0.04,white,-0.42,0.1\n"
      "0.02,white,-0.46,0.1\n"
      "0.02,7,0.5,0.0\n";
  const std::string jsonl =
      "# tracker export\n"
      "{\"t\": 0, \"ball\": \"white\", \"x\": -0.5, \"y\": 0.1}\n"
      "{\"y_m\": 0, \"x_m\": 0.5, \"id\": 7, \"t_s\": 0, \"frame\": 0}\r\n"
      "\n"
      "  {\"t\": 0.04, \"ball\": \"white\", \"x\": -0.42, \"y\": 0.1, \"conf\": [0.9]}\n"
      "{\"t\": 0.02, \"ball\": \"white\", \"x\": -0.46, \"y\": 0.1}\n"
      "{\"t\": 0.02, \"ball\": \"7\", \"x\": 0.5, \"y\": 0.0}\n";
  absl::StatusOr<billiards::TrackFile> a = billiards::ParseTrackCsv(csv);
  absl::StatusOr<billiards::TrackFile> b = ParseTrackJsonLines(jsonl);
  ASSERT_TRUE(a.ok()) << a.status();
  ASSERT_TRUE(b.ok()) << b.status();
  ExpectSame(*a, *b);
  EXPECT_EQ(b->cue, 0);
  absl::StatusOr<billiards::TrackFile> c = ParseTrackText(jsonl);
  ASSERT_TRUE(c.ok()) << c.status();
  ExpectSame(*a, *c);
  absl::StatusOr<billiards::TrackFile> d = ParseTrackText("# csv\n" + csv);
  ASSERT_TRUE(d.ok()) << d.status();
  ExpectSame(*a, *d);
}

TEST(TrackJsonTest, RefusesMalformedLinesNamingTheLine) {
  auto message = [](const std::string& text) {
    absl::StatusOr<billiards::TrackFile> f = ParseTrackJsonLines(text);
    EXPECT_EQ(f.status().code(), absl::StatusCode::kInvalidArgument) << text;
    return std::string(f.status().message());
  };
  const std::string ok = "{\"t\": 0, \"ball\": \"a\", \"x\": 0, \"y\": 0}\n";
  EXPECT_THAT(message(""), HasSubstr("no rows"));
  EXPECT_THAT(message(ok + "[1, 2]\n"), HasSubstr("line 2: not a JSON object"));
  EXPECT_THAT(message(ok + "{\"t\": 0.1, \"ball\": \"a\", \"x\": 0\n"),
              HasSubstr("line 2: not a JSON object"));
  EXPECT_THAT(message(ok + "{\"t\": 0.1, \"ball\": \"a\", \"x\": 0}\n"),
              HasSubstr("line 2: no y (or y_m) key"));
  EXPECT_THAT(message(ok + "{\"t\": \"0.1\", \"ball\": \"a\", \"x\": 0, \"y\": 0}\n"),
              HasSubstr("line 2: t must be a number"));
  EXPECT_THAT(message(ok + "{\"t\": 0.1, \"ball\": 1.5, \"x\": 0, \"y\": 0}\n"),
              HasSubstr("line 2: ball must be a string or a whole number"));
  EXPECT_THAT(message(ok + "{\"t\": 0.1, \"ball\": \"\", \"x\": 0, \"y\": 0}\n"),
              HasSubstr("line 2: the ball's id is empty"));
  EXPECT_THAT(message(ok + "{\"t\": 0.1, \"ball\": \"a\", \"x\": 2e6, \"y\": 0}\n"),
              HasSubstr("line 2: x must be a finite number within 1e6"));
}

}  // namespace
}  // namespace sportsim::cli
