// The golf round's referee (sim/golf/round.h) on random rounds: sportsim_links with 1 to 4
// players on random holes, order, profile, noise, seed, form of play (stroke with or without a
// maximum score, match, Stableford) and handicaps, then a sequence of random actions: strokes
// by any seat (launches, putts, swings of any strength and direction: refused or played),
// relief choices (offered, unknown, with any back_m), "unplayable", picking up, concessions
// and shot-clock expiries. Invariants after every accepted action: strokes and penalties consistent; every
// ball not holed at rest on the map, on the terrain, never out of bounds, in a penalty area
// only with its own decision pending; the decision's seat and choices valid; ToPlay in range
// (-1 only once over); Stableford points the table's, scores within a maximum; a finished
// round's winners the lowest totals (net), the most points, or the match's tally; and Decide a pure function
// (the same call twice gives the same state).
#include <fuzzer/FuzzedDataProvider.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/golf/course.h"
#include "sim/golf/round.h"
#include "tests/fuzz/fuzz_util.h"

namespace golf = sportsim::golf;

namespace {

bool SameBalls(const golf::RoundState& a, const golf::RoundState& b) {
  if (a.players.size() != b.players.size() || a.hole != b.hole || a.draws != b.draws) return false;
  for (size_t i = 0; i < a.players.size(); ++i) {
    const golf::RoundPlayer& p = a.players[i];
    const golf::RoundPlayer& q = b.players[i];
    if (p.strokes != q.strokes || p.penalties != q.penalties || p.ball.holed != q.ball.holed ||
        p.ball.position_m != q.ball.position_m || p.ball.lie != q.ball.lie) {
      return false;
    }
  }
  return true;
}

void Check(const golf::Course& c, const golf::RoundSettings& s, const golf::RoundState& st,
           const char* after) {
  const int n = static_cast<int>(st.players.size());
  FUZZ_CHECK(st.hole >= s.first_hole && st.hole <= s.last_hole, "after %s: hole %d", after, st.hole);
  for (int i = 0; i < n; ++i) {
    const golf::RoundPlayer& p = st.players[i];
    FUZZ_CHECK(p.strokes >= 0 && p.penalties >= 0 && p.penalties <= p.strokes,
               "after %s: seat %d strokes %d penalties %d", after, i, p.strokes, p.penalties);
    for (int score : p.scores) FUZZ_CHECK(score >= 0, "after %s: a score %d", after, score);
    for (size_t h = 0; h < p.scores.size(); ++h) {
      const golf::CourseHole& hole = *c.Hole(s.first_hole + static_cast<int>(h));
      if (s.play == golf::PlayFormat::kStableford && p.scores[h] > 0) {
        FUZZ_CHECK(p.points[h] == golf::StablefordPoints(p.scores[h], hole.par, p.received[h]),
                   "after %s: seat %d hole %d points %d", after, i, hole.number, p.points[h]);
      }
      const int max = golf::MaxScoreOf(s.max_score, hole.par, p.received[h]);
      FUZZ_CHECK(max == 0 || p.scores[h] <= max, "after %s: seat %d score %d over the maximum %d",
                 after, i, p.scores[h], max);
      FUZZ_CHECK(!p.no_score[h] || p.scores[h] == 0, "after %s: a score with no_score", after);
    }
    FUZZ_CHECK(!(p.ball.holed && p.ball.picked_up), "after %s: seat %d holed and picked up", after, i);
    if (p.ball.holed || p.ball.picked_up || st.over) continue;
    const Eigen::Vector3d& b = p.ball.position_m;
    FUZZ_CHECK(b.allFinite(), "after %s: seat %d ball not finite", after, i);
    FUZZ_CHECK(c.terrain.Covers(b.x(), b.y()), "after %s: seat %d ball off the map (%g, %g)",
               after, i, b.x(), b.y());
    FUZZ_CHECK(std::abs(b.z() - c.terrain.HeightAt(b.x(), b.y())) < 1e-3,
               "after %s: seat %d ball %g m off the terrain", after, i,
               b.z() - c.terrain.HeightAt(b.x(), b.y()));
    FUZZ_CHECK(p.ball.lie != golf::Terrain::kOutOfBounds, "after %s: seat %d at rest out of bounds",
               after, i);
    if (golf::IsPenaltyArea(p.ball.lie)) {
      FUZZ_CHECK(st.decision && st.decision->seat == i && st.decision->reason == "penalty_area",
                 "after %s: seat %d in a penalty area without its decision", after, i);
    }
  }
  if (st.decision) {
    FUZZ_CHECK(st.decision->seat >= 0 && st.decision->seat < n, "after %s: decision seat %d",
               after, st.decision->seat);
    FUZZ_CHECK(!st.decision->choices.empty() && st.decision->choices.front() == "stroke_and_distance",
               "after %s: decision choices", after);
  }
  const int next = golf::ToPlay(c, s, st);
  FUZZ_CHECK(st.over ? next == -1 : next >= 0 && next < n, "after %s: to play %d (over %d)",
             after, next, st.over);
  if (st.over && s.play == golf::PlayFormat::kMatch) {
    const golf::MatchStatus m = golf::MatchStatusOf(s, st);
    if (st.result == "conceded") {
      FUZZ_CHECK(st.winners.size() == 1, "after %s: a conceded match's winners", after);
    } else if (st.result == "halved") {
      FUZZ_CHECK(m.leader == -1 && m.to_play == 0 && st.winners.size() == 2, "after %s: halved", after);
    } else {
      FUZZ_CHECK(m.leader >= 0 && m.up > m.to_play && st.winners == std::vector<int>{m.leader},
                 "after %s: match result %s, leader %d up %d to play %d", after, st.result.c_str(),
                 m.leader, m.up, m.to_play);
    }
  } else if (st.over) {
    FUZZ_CHECK(st.result == "finished" && !st.winners.empty(), "after %s: a round over without "
               "winners", after);
    const bool net = golf::HasHandicaps(s);
    auto key = [&](const golf::RoundPlayer& p) {
      return s.play == golf::PlayFormat::kStableford ? -p.Points() : (net ? p.NetTotal() : p.Total());
    };
    int best = 1 << 30;
    for (const golf::RoundPlayer& p : st.players) best = std::min(best, key(p));
    for (int w : st.winners) {
      FUZZ_CHECK(key(st.players[w]) == best, "after %s: winner %d has %d, best %d", after, w,
                 key(st.players[w]), best);
    }
  }
}

golf::RoundStroke RandomStroke(FuzzedDataProvider& in) {
  golf::RoundStroke k;
  const int kind = in.ConsumeIntegralInRange(0, 2);
  if (in.ConsumeBool()) k.aim_deg = in.ConsumeFloatingPointInRange(-720.0, 720.0);
  k.flagstick_in = in.ConsumeBool();
  if (kind == 0) {
    k.launch = golf::LaunchConditions{.ball_speed_mps = in.ConsumeFloatingPointInRange(0.0, 125.0),
                                      .launch_angle_deg = in.ConsumeFloatingPointInRange(-90.0, 90.0),
                                      .launch_direction_deg = in.ConsumeFloatingPointInRange(-90.0, 90.0),
                                      .spin_rpm = in.ConsumeFloatingPointInRange(0.0, 31000.0),
                                      .spin_axis_deg = in.ConsumeFloatingPointInRange(-180.0, 180.0)};
  } else if (kind == 1) {
    k.kind = golf::RoundStroke::Kind::kPutt;
    k.speed_mps = in.ConsumeFloatingPointInRange(-1.0, 16.0);
  } else {
    k.kind = golf::RoundStroke::Kind::kSwing;
    golf::SwingStroke sw;
    sw.model = std::make_shared<const sportsim::swing::SwingModel>(
        *sportsim::swing::SwingModel::Create(sportsim::swing::SwingParams{}));
    sw.program = sportsim::swing::TorqueProgram::Constant(in.ConsumeFloatingPointInRange(-400.0, 400.0),
                                                          in.ConsumeFloatingPointInRange(-40.0, 40.0));
    const auto names = golf::kClubPresetNames;
    sw.club = *golf::ClubPreset(names[in.ConsumeIntegralInRange<size_t>(0, names.size() - 1)]);
    sw.delivery.face_angle_deg = in.ConsumeFloatingPointInRange(-50.0, 50.0);
    sw.delivery.club_path_deg = in.ConsumeFloatingPointInRange(-50.0, 50.0);
    k.swing = sw;
  }
  return k;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  const golf::Course& c = **golf::BuiltinCourse("sportsim_links");
  golf::RoundSettings s;
  s.first_hole = in.ConsumeIntegralInRange(1, 3);
  s.last_hole = in.ConsumeIntegralInRange(s.first_hole, 3);
  const int players = in.ConsumeIntegralInRange(1, 4);
  const char* tees[] = {"", "white", "red"};
  for (int i = 0; i < players; ++i) {
    s.players.push_back({std::string(1, static_cast<char>('A' + i)), tees[in.ConsumeIntegralInRange(0, 2)]});
  }
  s.order = in.ConsumeBool() ? golf::OrderOfPlay::kReady : golf::OrderOfPlay::kHonour;
  s.realism = in.ConsumeBool() ? golf::Realism::kArcade : golf::Realism::kRealistic;
  s.noise = in.ConsumeFloatingPointInRange(0.0, 5.0);
  s.seed = in.ConsumeIntegral<uint64_t>();
  // The forms of play: match play needs two players; handicaps and a maximum score at random.
  s.play = static_cast<golf::PlayFormat>(in.ConsumeIntegralInRange(0, 2));
  if (s.play == golf::PlayFormat::kMatch && players != 2) s.play = golf::PlayFormat::kStroke;
  for (golf::RoundPlayerSpec& p : s.players) {
    if (in.ConsumeBool()) p.handicap_index = in.ConsumeFloatingPointInRange(-10.0, 54.0);
  }
  if (s.play == golf::PlayFormat::kStroke) {
    static const char* kMax[] = {"none", "net_double_bogey", "par+2", "8"};
    (void)golf::SetRoundVariant("max_score", kMax[in.ConsumeIntegralInRange(0, 3)], &s);
  }
  absl::StatusOr<golf::RoundState> started = golf::StartRound(c, s);
  if (!started.ok()) return 0;  // a tee some hole lacks
  golf::RoundState st = *started;
  Check(c, s, st, "start");
  static const char* kChoices[] = {"stroke_and_distance", "back_on_the_line", "lateral",
                                   "back_on_the_line_outside_bunker", "unplayable", "drop",
                                   "pick_up", "concede_stroke", "concede_hole", "concede_match"};
  for (int step = 0; step < 10 && in.remaining_bytes() > 0 && !st.over; ++step) {
    const int action = in.ConsumeIntegralInRange(0, 9);
    const int seat = in.ConsumeIntegralInRange(-1, players);
    if (action <= 5) {
      const golf::RoundStroke k = RandomStroke(in);
      absl::StatusOr<golf::RoundStep> r = golf::PlayStroke(c, s, st, seat, k);
      if (r.ok()) {
        st = r->state;
        Check(c, s, st, "a stroke");
      }
    } else if (action <= 8) {
      golf::RoundChoice choice{kChoices[in.ConsumeIntegralInRange(0, 9)], std::nullopt};
      if (in.ConsumeBool()) choice.back_m = in.ConsumeFloatingPointInRange(-10.0, 600.0);
      absl::StatusOr<golf::RoundStep> r = golf::Decide(c, s, st, seat, choice);
      absl::StatusOr<golf::RoundStep> again = golf::Decide(c, s, st, seat, choice);
      FUZZ_CHECK(r.ok() == again.ok(), "Decide(%s) gave %d then %d", choice.choice.c_str(), r.ok(),
                 again.ok());
      if (r.ok()) {
        FUZZ_CHECK(SameBalls(r->state, again->state), "Decide(%s) is not a pure function",
                   choice.choice.c_str());
        st = r->state;
        Check(c, s, st, "a decision");
      }
    } else {
      absl::StatusOr<golf::RoundStep> r = golf::ShotClockExpired(c, s, st);
      if (r.ok()) {
        st = r->state;
        Check(c, s, st, "the shot clock");
      }
    }
  }
  return 0;
}
