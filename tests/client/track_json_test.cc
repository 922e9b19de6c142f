// Track files as JSON lines and shot sets (client/track_json.h): the same shot as CSV gives
// the same file, in the table's frame or a tracker's.
#include "client/track_json.h"

#include <string>
#include <vector>

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

// The same file up to rounding (a frame's map is arithmetic).
void ExpectNear(const billiards::TrackFile& a, const billiards::TrackFile& b) {
  EXPECT_EQ(a.balls, b.balls);
  ASSERT_EQ(a.spots.size(), b.spots.size());
  for (size_t i = 0; i < a.spots.size(); ++i) EXPECT_LT((a.spots[i] - b.spots[i]).norm(), 1e-12);
  EXPECT_EQ(a.cue, b.cue);
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i].t_s, b.points[i].t_s);
    EXPECT_EQ(a.points[i].ball, b.points[i].ball);
    EXPECT_LT((a.points[i].xy - b.points[i].xy).norm(), 1e-12) << i;
  }
}

// A shot set's shots read as their CSV files: named by id (a number or a string) or index,
// balls in the order of their ids whatever the document's order, extra keys ignored.
TEST(ShotSetTest, ShotsReadAsTheirCsvFiles) {
  const std::string csv0 =
      "t,ball,x,y\n"
      "0,1,-0.5,0.1\n0.02,1,-0.46,0.1\n0.04,1,-0.42,0.1\n"
      "0,2,0.5,0\n0.02,2,0.5,0\n0.04,2,0.5,0\n";
  const std::string csv1 =
      "t,ball,x,y\n"
      "0,red,0.3,-0.2\n0.02,red,0.3,-0.2\n"
      "0,white,0,0\n0.02,white,0,0.05\n";
  const std::string set =
      "[\n"
      " {\"id\": 17, \"player\": \"A\", \"balls\": {\n"
      "   \"2\": {\"t\": [0, 0.02, 0.04], \"x\": [0.5, 0.5, 0.5], \"y\": [0, 0, 0]},\n"
      "   \"1\": {\"t_s\": [0, 0.02, 0.04], \"x_m\": [-0.5, -0.46, -0.42], "
      "\"y_m\": [0.1, 0.1, 0.1], \"v\": [1]}}},\n"
      " {\"balls\": {\"white\": {\"t\": [0, 0.02], \"x\": [0, 0], \"y\": [0, 0.05]},\n"
      "              \"red\": {\"t\": [0, 0.02], \"x\": [0.3, 0.3], \"y\": [-0.2, -0.2]}}},\n"
      " {\"name\": \"break\", \"balls\": {\"a\": {\"t\": [0], \"x\": [0], \"y\": [0]}}}\n"
      "]\n";
  absl::StatusOr<std::vector<NamedTrack>> shots = ParseTracks(set);
  ASSERT_TRUE(shots.ok()) << shots.status();
  ASSERT_EQ(shots->size(), 3u);
  EXPECT_EQ((*shots)[0].name, "17");
  EXPECT_EQ((*shots)[1].name, "1");
  EXPECT_EQ((*shots)[2].name, "break");
  ExpectSame((*shots)[0].file, *billiards::ParseTrackCsv(csv0));
  EXPECT_EQ((*shots)[0].file.cue, 0);  // ball "1" moves
  // Balls go by id ("red" before "white"), so the CSV lists red first too.
  ExpectSame((*shots)[1].file, *billiards::ParseTrackCsv(csv1));
  EXPECT_EQ((*shots)[1].file.cue, 1);  // white moves 5 cm
  EXPECT_EQ((*shots)[2].file.cue, -1);
  // One file of any other form is one unnamed shot.
  absl::StatusOr<std::vector<NamedTrack>> one = ParseTracks("# a shot\n" + csv0);
  ASSERT_TRUE(one.ok()) << one.status();
  ASSERT_EQ(one->size(), 1u);
  EXPECT_EQ((*one)[0].name, "");
  ExpectSame((*one)[0].file, (*shots)[0].file);
}

// A tracker's frame (origin at a corner, its own unit) maps onto the table's in every form,
// and the struck ball is the first to move a centimetre of the table, not of the file.
TEST(ShotSetTest, FrameMapsEveryFormOntoTheTable) {
  // Millimetres from the corner of a 2.84 x 1.42 m playing area.
  const billiards::TrackFrame mm{.scale = 1e-3, .origin = Eigen::Vector2d(-1.42, -0.71)};
  const std::string table =
      "t,ball,x,y\n0,a,-1.0,0.2\n0.02,a,-0.995,0.2\n0.04,a,-0.985,0.2\n0,b,0.4,-0.3\n";
  const std::string file =
      "t,ball,x,y\n0,a,420,910\n0.02,a,425,910\n0.04,a,435,910\n0,b,1820,410\n";
  const std::string jsonl =
      "{\"t\": 0, \"ball\": \"a\", \"x\": 420, \"y\": 910}\n"
      "{\"t\": 0.02, \"ball\": \"a\", \"x\": 425, \"y\": 910}\n"
      "{\"t\": 0.04, \"ball\": \"a\", \"x\": 435, \"y\": 910}\n"
      "{\"t\": 0, \"ball\": \"b\", \"x\": 1820, \"y\": 410}\n";
  const std::string set =
      "[{\"balls\": {\"a\": {\"t\": [0, 0.02, 0.04], \"x\": [420, 425, 435], \"y\": [910, 910, "
      "910]}, \"b\": {\"t\": [0], \"x\": [1820], \"y\": [410]}}}]";
  absl::StatusOr<billiards::TrackFile> want = billiards::ParseTrackCsv(table);
  ASSERT_TRUE(want.ok()) << want.status();
  EXPECT_EQ(want->cue, 0);  // 15 mm by the last frame (5 mm, the first, is not enough)
  absl::StatusOr<billiards::TrackFile> a = billiards::ParseTrackCsv(file, mm);
  absl::StatusOr<billiards::TrackFile> b = ParseTrackText(jsonl, mm);
  absl::StatusOr<std::vector<NamedTrack>> c = ParseTracks(set, mm);
  ASSERT_TRUE(a.ok()) << a.status();
  ASSERT_TRUE(b.ok()) << b.status();
  ASSERT_TRUE(c.ok()) << c.status();
  ExpectNear(*want, *a);
  ExpectNear(*want, *b);
  ExpectNear(*want, (*c)[0].file);
  // Without its frame the file stays in its own units.
  absl::StatusOr<billiards::TrackFile> metres = billiards::ParseTrackCsv(file);
  ASSERT_TRUE(metres.ok());
  EXPECT_EQ(metres->spots[0], Eigen::Vector2d(420, 910));
  // A frame that maps nothing is refused, naming the field.
  for (const billiards::TrackFrame& bad :
       {billiards::TrackFrame{.scale = 0}, billiards::TrackFrame{.scale = -1},
        billiards::TrackFrame{.scale = std::nan("")},
        billiards::TrackFrame{.origin = Eigen::Vector2d(std::nan(""), 0)},
        billiards::TrackFrame{.table_m = Eigen::Vector2d(-2.84, 1.42)}}) {
    absl::StatusOr<std::vector<NamedTrack>> r = ParseTracks(set, bad);
    EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(r.status().message(), HasSubstr("frame."));
    EXPECT_EQ(ParseTrackText(table, bad).status().code(), absl::StatusCode::kInvalidArgument);
  }
}

TEST(ShotSetTest, RefusesMalformedSetsNamingTheShotAndBall) {
  auto message = [](const std::string& text) {
    absl::StatusOr<std::vector<NamedTrack>> f = ParseShotSet(text);
    EXPECT_EQ(f.status().code(), absl::StatusCode::kInvalidArgument) << text;
    return std::string(f.status().message());
  };
  const std::string ok = R"({"balls": {"a": {"t": [0, 0.1], "x": [0, 0.1], "y": [0, 0]}}})";
  EXPECT_THAT(message("[" + ok + ","), HasSubstr("not a JSON document"));
  EXPECT_THAT(message("{\"shots\": []}"), HasSubstr("must be a JSON array of shots"));
  EXPECT_THAT(message("[]"), HasSubstr("no shots"));
  EXPECT_THAT(message("[" + ok + ", 3]"), HasSubstr("shot 1: must be a JSON object"));
  EXPECT_THAT(message("[" + ok + ", {\"id\": 1}]"), HasSubstr("shot 1: no balls"));
  EXPECT_THAT(message("[" + ok + ", {\"balls\": {}}]"), HasSubstr("shot 1: no balls"));
  EXPECT_THAT(message(R"([{"id": 1.5, "balls": {"a": {"t": [], "x": [], "y": []}}}])"),
              HasSubstr("shot 0: id must be a string or a whole number"));
  EXPECT_THAT(message(R"([{"balls": {"a": [0, 1]}}])"),
              HasSubstr("shot 0: ball \"a\": must be an object of t, x and y arrays"));
  EXPECT_THAT(message(R"([{"balls": {"a": {"t": [0], "x": [0]}}}])"),
              HasSubstr("shot 0: ball \"a\": no y (or y_m) array"));
  EXPECT_THAT(message(R"([{"balls": {"a": {"t": [0, 1], "x": [0], "y": [0, 1]}}}])"),
              HasSubstr("shot 0: ball \"a\": t, x and y must have the same length, got 2, 1 and 2"));
  EXPECT_THAT(message(R"([{"balls": {"a": {"t": [0, 1], "x": [0, "1"], "y": [0, 1]}}}])"),
              HasSubstr("shot 0: ball \"a\": x[1] must be a finite number within 1e6"));
  EXPECT_THAT(message(R"([{"balls": {"a": {"t": [0, 1], "x": [0, 1], "y": [0, 2e6]}}}])"),
              HasSubstr("shot 0: ball \"a\": y[1] must be a finite number within 1e6"));
  EXPECT_THAT(message(R"([{"balls": {"": {"t": [0], "x": [0], "y": [0]}}}])"),
              HasSubstr("shot 0: a ball's id is empty"));
  EXPECT_THAT(message(R"([{"balls": {"a": {"t": [], "x": [], "y": []}}}])"),
              HasSubstr("shot 0: the file has no rows"));
  // More shots than a set may hold.
  std::string many = "[";
  for (int i = 0; i <= kMaxShotsPerSet; ++i) many += (i ? "," : "") + ok;
  EXPECT_THAT(message(many + "]"), HasSubstr("at most 10000 shots"));
}

// A match tracker's export: each tracked entry a shot named by its id, fractions of the
// playing area from a corner and ticks of 500 us mapped onto the table; untracked entries are
// not shots.
TEST(ShotSetTest, MatchTrackingDocumentsReadAsTheirCsv) {
  const std::string doc = R"({
  "Match": {"Player1": "A", "Sets": [
    {"Entries": [
      {"Scoring": {"Points": 1}},
      {"PathTrackingId": 392699, "PathTracking": {"DataSets": [
        {"BallColor": 2, "Coords": [{"DeltaT_500us": 0, "X": 0.75, "Y": 0.25}]},
        {"BallColor": 1, "Coords": [{"DeltaT_500us": 0, "X": 0.25, "Y": 0.5},
                                    {"DeltaT_500us": 40, "X": 0.26, "Y": 0.5, "Z": 0}]}]}}]},
    {"Entries": [
      {"PathTracking": {"DataSets": []}},
      {"PathTracking": {"DataSets": [
        {"BallColor": 3, "Coords": [{"DeltaT_500us": 0, "X": 0.5, "Y": 0.5},
                                    {"DeltaT_500us": 1000, "X": 0.5, "Y": 0.5}]}]}}]}]}})";
  const billiards::TrackFrame carom{.table_m = Eigen::Vector2d(2.84, 1.42)};
  absl::StatusOr<std::vector<NamedTrack>> shots = ParseTracks(doc, carom);
  ASSERT_TRUE(shots.ok()) << shots.status();
  ASSERT_EQ(shots->size(), 2u);
  EXPECT_EQ((*shots)[0].name, "392699");
  EXPECT_EQ((*shots)[1].name, "1.1");
  // 0.25 of 2.84 m from the corner is -0.71 from the centre; 40 ticks are 0.02 s.
  ExpectNear((*shots)[0].file, *billiards::ParseTrackCsv(
                                   "t,ball,x,y\n0,2,0.71,-0.355\n0,1,-0.71,0\n0.02,1,-0.6816,0\n"));
  EXPECT_EQ((*shots)[0].file.cue, 1);  // ball 1 moves 2.84 cm
  ExpectNear((*shots)[1].file, *billiards::ParseTrackCsv("t,ball,x,y\n0,3,0,0\n0.5,3,0,0\n"));
  EXPECT_EQ(ParseShotSet(doc, carom).status(), shots.status());

  auto message = [&](const std::string& text, const billiards::TrackFrame& frame) {
    absl::StatusOr<std::vector<NamedTrack>> f = ParseTracks(text, frame);
    EXPECT_EQ(f.status().code(), absl::StatusCode::kInvalidArgument) << text;
    return std::string(f.status().message());
  };
  EXPECT_THAT(message(doc, {}), HasSubstr("fractions of the playing area: give the table"));
  EXPECT_THAT(message(doc, {.scale = 2, .table_m = Eigen::Vector2d(2.84, 1.42)}),
              HasSubstr("sets its own frame"));
  const auto one = [](const std::string& dataset) {
    return R"({"Match": {"Sets": [{"Entries": [{"PathTracking": {"DataSets": [)" + dataset +
           "]}}]}]}}";
  };
  EXPECT_THAT(message(R"({"Match": {"Sets": 3}})", carom), HasSubstr("Match.Sets: must be an array"));
  EXPECT_THAT(message(R"({"Match": {"Sets": [{"Entries": []}]}})", carom),
              HasSubstr("no entry has tracking data"));
  EXPECT_THAT(message(one(R"({"BallColor": "white", "Coords": []})"), carom),
              HasSubstr("Match.Sets[0].Entries[0].PathTracking.DataSets[0].BallColor: must be a "
                        "whole number"));
  EXPECT_THAT(message(one(R"({"BallColor": 1, "Coords": [{"DeltaT_500us": 0, "X": 0.5, "Y": 0.5}]},
                            {"BallColor": 1, "Coords": []})"),
                      carom),
              HasSubstr("DataSets[1].BallColor: ball 1 is tracked twice"));
  EXPECT_THAT(message(one(R"({"BallColor": 1, "Coords": [{"DeltaT_500us": 0, "X": 0.5, "Y": 0.5},
                                                         {"DeltaT_500us": 40, "Y": 0.5}]})"),
                      carom),
              HasSubstr("DataSets[0].Coords[1].X: must be a finite number within 1e6"));
  EXPECT_THAT(message(one(R"({"BallColor": 1})"), carom), HasSubstr("DataSets[0].Coords: must be an array"));
  // A tracker's export of one entry, a shot on its own (a file of its own): read as the same
  // entry in a match, named by its id when it has one.
  const std::string entry = R"({"Path": null, "PathTrackingId": 7, "PathTracking": {"DataSets": [
        {"BallColor": 2, "Coords": [{"DeltaT_500us": 0, "X": 0.75, "Y": 0.25}]},
        {"BallColor": 1, "Coords": [{"DeltaT_500us": 0, "X": 0.25, "Y": 0.5},
                                    {"DeltaT_500us": 40, "X": 0.26, "Y": 0.5}]}],
        "TableWidth": 2840, "TableHeight": 1420}, "White": {"relX": 0.25, "relY": 0.5}})";
  absl::StatusOr<std::vector<NamedTrack>> single = ParseTracks(entry, carom);
  ASSERT_TRUE(single.ok()) << single.status();
  ASSERT_EQ(single->size(), 1u);
  EXPECT_EQ((*single)[0].name, "7");
  ExpectNear((*single)[0].file, (*shots)[0].file);
  EXPECT_EQ(ParseShotSet(entry, carom).status(), single.status());
  EXPECT_THAT(message(entry, {}), HasSubstr("give the table"));
  EXPECT_THAT(message(R"({"PathTracking": {"DataSets": []}})", carom),
              HasSubstr("PathTracking.DataSets: must be a non-empty array of balls"));
  EXPECT_THAT(message(R"({"PathTracking": {"DataSets": [{"BallColor": 1}]}})", carom),
              HasSubstr("PathTracking.DataSets[0].Coords: must be an array"));
  // One line of JSON lines is a JSON object too: without "Match" it stays a track file.
  absl::StatusOr<std::vector<NamedTrack>> line =
      ParseTracks("{\"t\": 0, \"ball\": \"a\", \"x\": 0.1, \"y\": 0.2}\n", carom);
  ASSERT_TRUE(line.ok()) << line.status();
  EXPECT_EQ((*line)[0].file.spots[0], Eigen::Vector2d(0.1, 0.2));
}

}  // namespace
}  // namespace sportsim::cli
