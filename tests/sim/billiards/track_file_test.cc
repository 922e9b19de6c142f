// Track files (track_file.h): recorded shots as CSV.
#include "sim/billiards/track_file.h"

#include <cstdio>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "sim/billiards/calibrate.h"
#include "sim/billiards/model.h"

namespace sportsim::billiards {
namespace {

using ::testing::HasSubstr;

// `shot simulate --format csv`'s form: the state column ignored, t = 0 rows the spots, the
// struck ball the first to leave its spot, points in time order whatever the file's order.
TEST(TrackFileTest, ReadsTheShotCommandsCsv) {
  const std::string text =
      "t_s,id,x_m,y_m,state\r\n"
      "0,white,-0.5,0.1,stationary\r\n"
      "0,red,0.5,0,stationary\r\n"
      "# a comment\n"
      "\n"
      "0.04,white,-0.42,0.1,sliding\n"
      "0.04,red,0.5,0,stationary\n"
      "0.02,white,-0.46,0.1,sliding\n"
      "0.02,red,0.5,0.0,stationary\n"
      "0.02,yellow,1.0,-0.3,stationary\n";
  absl::StatusOr<TrackFile> f = ParseTrackCsv(text);
  ASSERT_TRUE(f.ok()) << f.status();
  EXPECT_THAT(f->balls, ::testing::ElementsAre("white", "red", "yellow"));
  EXPECT_EQ(f->spots[0], Eigen::Vector2d(-0.5, 0.1));
  EXPECT_EQ(f->spots[2], Eigen::Vector2d(1.0, -0.3));  // first tracked: no t <= 0 row
  EXPECT_EQ(f->cue, 0);
  ASSERT_EQ(f->points.size(), 5u);
  EXPECT_EQ(f->points[0].t_s, 0.02);
  EXPECT_EQ(f->points[0].ball, 0);  // ties keep the file's order
  EXPECT_EQ(f->points[4].t_s, 0.04);
  EXPECT_EQ(f->points[4].ball, 1);
}

TEST(TrackFileTest, HeaderColumnsInAnyOrderAndCase) {
  absl::StatusOr<TrackFile> f = ParseTrackCsv("frame,Y,X,Ball,T\n1,0.2,0.1,a,0\n2,0.2,0.15,a,0.5\n");
  ASSERT_TRUE(f.ok()) << f.status();
  EXPECT_EQ(f->spots[0], Eigen::Vector2d(0.1, 0.2));
  ASSERT_EQ(f->points.size(), 1u);
  EXPECT_EQ(f->points[0].xy, Eigen::Vector2d(0.15, 0.2));
  EXPECT_EQ(f->cue, 0);
}

// A ball seen off its spot in a single frame is a tracker's false detection: the struck ball
// is the first to depart (a point away, then one farther along the same line); a ball seen
// away only once is the struck one when no ball departs.
TEST(TrackFileTest, TheStruckBallIsTheFirstToDepart) {
  absl::StatusOr<TrackFile> f = ParseTrackCsv(
      "t,ball,x,y\n0,white,-0.5,0.1\n0,red,0.5,0\n"
      "0.02,white,-0.5,0.1\n0.02,red,0.9,0.3\n"   // red's false detection
      "0.04,white,-0.5,0.1\n0.04,red,0.5,0\n"
      "0.06,white,-0.46,0.1\n0.06,red,0.5,0\n"
      "0.08,white,-0.42,0.1\n0.08,red,0.5,0\n");
  ASSERT_TRUE(f.ok()) << f.status();
  EXPECT_EQ(f->cue, 0);
  f = ParseTrackCsv("t,ball,x,y\n0,white,-0.5,0.1\n0,red,0.5,0\n0.02,red,0.9,0.3\n0.04,white,-0.5,0.1\n");
  ASSERT_TRUE(f.ok()) << f.status();
  EXPECT_EQ(f->cue, 1);
}

TEST(TrackFileTest, RefusesMalformedFilesNamingTheLine) {
  auto message = [](const std::string& text) {
    absl::StatusOr<TrackFile> f = ParseTrackCsv(text);
    EXPECT_EQ(f.status().code(), absl::StatusCode::kInvalidArgument);
    return std::string(f.status().message());
  };
  EXPECT_THAT(message(""), HasSubstr("no header"));
  EXPECT_THAT(message("t,ball,x\n"), HasSubstr("line 1: the header must name"));
  EXPECT_THAT(message("t,ball,x,y\n"), HasSubstr("no rows"));
  EXPECT_THAT(message("t,ball,x,y\n0,a,1,2\n0.1,a,one,2\n"), HasSubstr("line 3: x must be a finite number"));
  EXPECT_THAT(message("t,ball,x,y\n0,a,1,nan\n"), HasSubstr("line 2: y must be"));
  EXPECT_THAT(message("t,ball,x,y\n0,a,1\n"), HasSubstr("line 2: 3 cells"));
  EXPECT_THAT(message("t,ball,x,y\n0,,1,2\n"), HasSubstr("line 2: the ball's id is empty"));
  EXPECT_THAT(message("t,ball,x,y\n0,a,1,2\n0.1,a,1,1e9\n"), HasSubstr("within 1e6"));
}

// A synthetic recording written as a file and read back is the same recording.
TEST(TrackFileTest, ASyntheticRecordingRoundTrips) {
  const TableModel model = *TableModel::Create(*MakeTablePreset("carom"));
  TableState s;
  s.balls = {Ball{.id = "white", .r = {-0.6, 0.1, model.radius()}},
             Ball{.id = "yellow", .r = {0.3, -0.2, model.radius()}},
             Ball{.id = "red", .r = {0.7, 0.3, model.radius()}}};
  CueStrike strike;
  strike.ball_speed = true;
  strike.speed_mps = 2.5;
  strike.phi_rad = -0.25;
  absl::StatusOr<Recording> rec = SyntheticRecording(model, SolverOptions{}, s, 0, strike);
  ASSERT_TRUE(rec.ok()) << rec.status();
  std::string text = "t_s,id,x_m,y_m\n";
  char buf[128];
  for (const Ball& b : s.balls) {
    std::snprintf(buf, sizeof buf, "0,%s,%.17g,%.17g\n", b.id.c_str(), b.r.x(), b.r.y());
    text += buf;
  }
  for (const TrackPoint& p : rec->track) {
    std::snprintf(buf, sizeof buf, "%.17g,%s,%.17g,%.17g\n", p.t_s, s.balls[static_cast<size_t>(p.ball)].id.c_str(),
                  p.xy.x(), p.xy.y());
    text += buf;
  }
  absl::StatusOr<TrackFile> f = ParseTrackCsv(text);
  ASSERT_TRUE(f.ok()) << f.status();
  EXPECT_EQ(f->cue, 0);
  ASSERT_EQ(f->points.size(), rec->track.size());
  for (size_t i = 0; i < f->points.size(); ++i) {
    EXPECT_EQ(f->points[i].t_s, rec->track[i].t_s);
    EXPECT_EQ(f->points[i].ball, rec->track[i].ball);
    EXPECT_EQ(f->points[i].xy, rec->track[i].xy);
  }
}

}  // namespace
}  // namespace sportsim::billiards
