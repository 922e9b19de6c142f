#include "sim/golf/round.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <tuple>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "sim/golf/ground.h"
#include "sim/swing/realism.h"

namespace sportsim::golf {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr double kDeg = std::numbers::pi / 180.0;

// --- seeded draws -----------------------------------------------------------------------------
// Counter-based: draw n of a stream is a pure function of (seed, stream, n) (SplitMix64's
// finaliser), so the state records only how many draws were made.

uint64_t Mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

enum Stream : uint64_t { kNoiseStream = 1, kDropStream = 2 };

double Uniform(uint64_t seed, Stream stream, uint64_t n) {  // [0, 1)
  return static_cast<double>(Mix(seed ^ Mix(stream * 0x100000001b3ull ^ Mix(n))) >> 11) * 0x1.0p-53;
}

double Normal(uint64_t seed, Stream stream, uint64_t n) {  // Box-Muller on draws 2n, 2n + 1
  const double u1 = Uniform(seed, stream, 2 * n), u2 = Uniform(seed, stream, 2 * n + 1);
  return std::sqrt(-2.0 * std::log1p(-u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

bool Done(const RoundBall& b) { return b.holed || b.picked_up; }

// --- places -----------------------------------------------------------------------------------

Vector2d Pin(const Course& course, int hole) { return *course.Hole(hole)->pin_m; }

double ToPin(const Course& course, int hole, const Vector3d& p) {
  return (p.head<2>() - Pin(course, hole)).norm();
}

Vector3d OnGround(const Course& course, const Vector2d& p) {
  return Vector3d(p.x(), p.y(), course.terrain.HeightAt(p.x(), p.y()));
}

const CourseTee& TeeOf(const CourseHole& hole, const std::string& name) {
  for (const CourseTee& t : hole.tees) {
    if (t.name == name) return t;
  }
  return hole.tees.front();
}

// The area of the course (Rule 2.2) of a ball at `spot`, and its lie (`lie`, when given): one
// LieAt and one SurfaceAt on the index.
CourseAreaKind AreaAt(const CourseIndex& at, int hole, const Vector2d& spot, double r,
                      Terrain* lie_out = nullptr) {
  const Terrain lie = at.LieAt(spot.x(), spot.y(), r);
  if (lie_out != nullptr) *lie_out = lie;
  const Course::Spot under = at.SurfaceAt(spot.x(), spot.y());
  const bool this_hole = under.hole == 0 || under.hole == hole || under.terrain != lie;
  switch (lie) {
    case Terrain::kWaterHazard:
    case Terrain::kLateralWaterHazard: return CourseAreaKind::kPenaltyArea;
    case Terrain::kBunker: return CourseAreaKind::kBunker;
    case Terrain::kGreen: return this_hole ? CourseAreaKind::kGreen : CourseAreaKind::kGeneral;
    case Terrain::kTee: return this_hole ? CourseAreaKind::kTeeing : CourseAreaKind::kGeneral;
    default: return CourseAreaKind::kGeneral;
  }
}

// A relief area (Rule 14.3): within `radius` of the reference point, not nearer the hole than
// it, in bounds, and in the area `where` says.
struct Relief {
  enum class Where { kOutsidePenaltyArea, kInBunker, kOutsideBunker, kSameArea };
  Vector2d reference = Vector2d::Zero();
  double radius_m = kClubLengthM;
  Where where = Where::kOutsidePenaltyArea;
  CourseAreaKind same = CourseAreaKind::kGeneral;  // kSameArea
};

bool InRelief(const CourseIndex& at, int hole, const Relief& relief, const Vector2d& p, double r) {
  if ((p - relief.reference).norm() > relief.radius_m * (1.0 + 1e-12)) return false;
  const Vector2d pin = Pin(at.course(), hole);
  if ((p - pin).norm() < (relief.reference - pin).norm() * (1.0 - 1e-12)) return false;
  if (!at.course().terrain.Covers(p.x(), p.y())) return false;
  Terrain lie = Terrain::kRough;
  const CourseAreaKind a = AreaAt(at, hole, p, r, &lie);
  if (lie == Terrain::kOutOfBounds) return false;
  switch (relief.where) {
    case Relief::Where::kOutsidePenaltyArea: return a != CourseAreaKind::kPenaltyArea;
    case Relief::Where::kInBunker: return a == CourseAreaKind::kBunker;
    case Relief::Where::kOutsideBunker:
      return a != CourseAreaKind::kBunker && a != CourseAreaKind::kPenaltyArea;
    case Relief::Where::kSameArea: return a == relief.same;
  }
  return false;
}

// The share of the relief circle's area a drop may come to rest in, on a 21 x 21 grid over its
// square (at most about one half: "not nearer the hole" takes the other).
double ReliefShare(const CourseIndex& at, int hole, const Relief& relief, double r) {
  constexpr int kN = 21;
  int inside = 0, valid = 0;
  for (int i = 0; i < kN; ++i) {
    for (int j = 0; j < kN; ++j) {
      const Vector2d d(2.0 * i / (kN - 1) - 1.0, 2.0 * j / (kN - 1) - 1.0);
      if (d.squaredNorm() > 1.0) continue;
      ++inside;
      valid += InRelief(at, hole, relief, relief.reference + relief.radius_m * d, r) ? 1 : 0;
    }
  }
  return static_cast<double>(valid) / inside;
}

Relief::Where Constraint(const RoundDecision& d, bool outside_bunker) {
  if (d.area == Terrain::kBunker && d.reason == "unplayable") {
    return outside_bunker ? Relief::Where::kOutsideBunker : Relief::Where::kInBunker;
  }
  return Relief::Where::kOutsidePenaltyArea;
}

// Back on the line: the reference point `back_m` behind the decision's reference on the line
// from the hole through it.
Relief BackOnTheLine(const Course& course, int hole, const RoundDecision& d, double back_m,
                     bool outside_bunker) {
  const Vector2d pin = Pin(course, hole);
  Vector2d u = d.reference_m.head<2>() - pin;
  u = u.norm() > 1e-9 ? Vector2d(u.normalized()) : Vector2d(1.0, 0.0);
  Relief relief;
  relief.reference = d.reference_m.head<2>() + back_m * u;
  relief.radius_m = kClubLengthM;
  relief.where = Constraint(d, outside_bunker);
  return relief;
}

// The reference point itself must be where the relief is taken to (not in the penalty area, in
// or out of the bunker as chosen), in bounds, and the area around it must leave room to drop.
bool UsableBackOnTheLine(const CourseIndex& at, int hole, const Relief& relief, double r) {
  const Vector2d p = relief.reference;
  if (!at.course().terrain.Covers(p.x(), p.y())) return false;
  Terrain lie = Terrain::kRough;
  const CourseAreaKind a = AreaAt(at, hole, p, r, &lie);
  if (lie == Terrain::kOutOfBounds) return false;
  switch (relief.where) {
    case Relief::Where::kInBunker:
      if (a != CourseAreaKind::kBunker) return false;
      break;
    case Relief::Where::kOutsideBunker:
      if (a == CourseAreaKind::kBunker || a == CourseAreaKind::kPenaltyArea) return false;
      break;
    default:
      if (a == CourseAreaKind::kPenaltyArea) return false;
  }
  return ReliefShare(at, hole, relief, r) >= 0.25;
}

constexpr double kBackStepM = 0.5;
constexpr double kBackMaxM = 500.0;

// The nearest usable reference point behind: from 0 behind a penalty area's crossing (the
// crossing itself lies on the edge), from a club-length behind an unplayable ball.
std::optional<double> DefaultBack(const CourseIndex& at, int hole, const RoundDecision& d,
                                  bool outside_bunker, double r) {
  const double from = d.reason == "unplayable" && !outside_bunker && d.area != Terrain::kBunker
                          ? kClubLengthM
                          : 0.0;
  for (double back = from; back <= kBackMaxM; back += kBackStepM) {
    if (UsableBackOnTheLine(at, hole, BackOnTheLine(at.course(), hole, d, back, outside_bunker), r)) {
      return back;
    }
  }
  return std::nullopt;
}

Relief Lateral(const RoundDecision& d) {
  Relief relief;
  relief.reference = d.reference_m.head<2>();
  relief.radius_m = 2.0 * kClubLengthM;
  relief.where = Constraint(d, false);
  return relief;
}

std::vector<std::string> Choices(const CourseIndex& at, int hole, const RoundDecision& d,
                                 double r) {
  std::vector<std::string> out = {"stroke_and_distance"};
  if (DefaultBack(at, hole, d, false, r)) out.push_back("back_on_the_line");
  const bool lateral = d.reason == "unplayable" || d.area == Terrain::kLateralWaterHazard;
  if (lateral && ReliefShare(at, hole, Lateral(d), r) > 0.0) out.push_back("lateral");
  if (d.reason == "unplayable" && d.area == Terrain::kBunker &&
      DefaultBack(at, hole, d, true, r)) {
    out.push_back("back_on_the_line_outside_bunker");
  }
  return out;
}

std::string RuleOf(const RoundDecision& d, std::string_view choice) {
  if (d.reason == "penalty_area") {
    if (choice == "stroke_and_distance") return "17.1d(1)";
    if (choice == "back_on_the_line") return "17.1d(2)";
    return "17.1d(3)";
  }
  if (d.area == Terrain::kBunker) return choice == "back_on_the_line_outside_bunker" ? "19.3b" : "19.3a";
  if (choice == "stroke_and_distance") return "19.2a";
  if (choice == "back_on_the_line") return "19.2b";
  return "19.2c";
}

// --- the referee's steps ----------------------------------------------------------------------

class Referee {
 public:
  Referee(const Course& course, const RoundSettings& settings, const RoundState& state,
          const std::function<bool()>& cancelled)
      : course_(course), at_(course), settings_(settings), cancelled_(cancelled) {
    step_.state = state;
  }

  const CourseIndex& at() const { return at_; }

  RoundState& state() { return step_.state; }
  RoundPlayer& player(int seat) { return step_.state.players[seat]; }
  RoundStep Take() { return std::move(step_); }

  RoundEvent& Emit(RoundEventKind kind, int seat) {
    RoundEvent& e = step_.events.emplace_back();
    e.kind = kind;
    e.seat = seat;
    e.hole = state().hole;
    e.strokes = seat >= 0 ? player(seat).strokes : 0;
    return e;
  }

  void Penalty(int seat, int strokes, std::string reason, std::string rule) {
    player(seat).strokes += strokes;
    player(seat).penalties += strokes;
    RoundEvent& e = Emit(RoundEventKind::kPenalty, seat);
    e.penalty_strokes = strokes;
    e.reason = std::move(reason);
    e.rule = std::move(rule);
    e.position_m = player(seat).ball.position_m;
  }

  void Put(int seat, const Vector3d& p) {
    RoundBall& b = player(seat).ball;
    b.position_m = p;
    b.lie = at_.LieAt(p.x(), p.y(), r());
    b.holed = false;
  }

  // Rule 14.3: dropped from knee height on a drawn point of the relief area; it must come to
  // rest in it. Twice outside: placed where it first touched the ground on the second drop.
  absl::Status Drop(int seat, const Relief& relief) {
    const RoundSettings& s = settings_;
    const int hole = state().hole;
    Hole spec;
    spec.flagstick_diameter_m = kFlagstickDiameter;
    GroundOptions options = CourseGroundOptions();
    options.sample_interval_s = 0.0;
    options.cancelled = cancelled_;
    Vector2d touched = relief.reference;
    for (int attempt = 1; attempt <= 2; ++attempt) {
      touched = DrawPoint(hole, relief);
      GroundStart start;
      start.kind = GroundStartKind::kLanding;
      start.position_m = OnGround(course_, touched);
      start.velocity_mps = Vector3d(0.0, 0.0, -std::sqrt(2.0 * options.gravity_mps2 * kKneeHeightM));
      absl::StatusOr<GroundResult> g =
          SimulateGroundOnCourse(s.ball, course_, hole, spec, start, options);
      if (!g.ok()) return g.status();
      const Vector3d rest = g->rest_m;
      const bool in_area = !g->holed && !g->out_of_bounds && !g->penalty_area &&
                           InRelief(at_, hole, relief, rest.head<2>(), r());
      RoundEvent& e = Emit(RoundEventKind::kDrop, seat);
      e.position_m = start.position_m;
      e.rest_m = rest;
      e.attempt = attempt;
      e.in_area = in_area;
      e.lie = std::string(TerrainTag(at_.LieAt(rest.x(), rest.y(), r())));
      if (in_area) {
        Put(seat, rest);
        return absl::OkStatus();
      }
    }
    Put(seat, OnGround(course_, touched));
    RoundEvent& e = Emit(RoundEventKind::kPlaced, seat);
    e.position_m = player(seat).ball.position_m;
    e.lie = std::string(TerrainTag(player(seat).ball.lie));
    e.rule = "14.3c(2)";
    return absl::OkStatus();
  }

  // Stroke and distance (Rule 14.6): from the teeing area, teed again there; from the putting
  // green, placed on the spot; elsewhere dropped within a club-length of it, not nearer the
  // hole, in the same area of the course.
  absl::Status ReturnToLastSpot(int seat) {
    RoundBall& b = player(seat).ball;
    const Vector3d spot = b.last_spot_m;
    const CourseAreaKind area = AreaAt(at_, state().hole, spot.head<2>(), r());
    if (area == CourseAreaKind::kTeeing || area == CourseAreaKind::kGreen) {
      Put(seat, spot);
      RoundEvent& e = Emit(RoundEventKind::kPlaced, seat);
      e.position_m = spot;
      e.lie = std::string(TerrainTag(b.lie));
      e.rule = "14.6";
      return absl::OkStatus();
    }
    Relief relief;
    relief.reference = spot.head<2>();
    relief.radius_m = kClubLengthM;
    relief.where = Relief::Where::kSameArea;
    relief.same = area;
    return Drop(seat, relief);
  }

  // The ball is out of play for the rest of the hole without being holed.
  void PickUp(int seat, std::string reason) {
    RoundBall& b = player(seat).ball;
    b.picked_up = true;
    b.marked = false;
    if (state().decision && state().decision->seat == seat) state().decision.reset();
    RoundEvent& e = Emit(RoundEventKind::kPickedUp, seat);
    e.reason = std::move(reason);
    e.position_m = b.position_m;
  }

  int Par() const { return course_.Hole(step_.state.hole)->par; }
  int Received(int seat) const {
    const RoundPlayer& p = step_.state.players[seat];
    return p.received[step_.state.hole - settings_.first_hole];
  }

  // The format's own ends of a player's hole: no Stableford point left to score (21.1c), the
  // maximum score reached (21.2c), a match-play hole the player can no longer halve (3.2a).
  void AutoPickUps() {
    RoundState& st = state();
    const int n = static_cast<int>(st.players.size());
    for (int i = 0; i < n; ++i) {
      const RoundPlayer& p = st.players[i];
      if (Done(p.ball)) continue;
      if (settings_.play == PlayFormat::kStableford && p.strokes >= Par() + Received(i) + 1) {
        PickUp(i, "stableford");
      } else if (settings_.play == PlayFormat::kStroke) {
        const int max = MaxScoreOf(settings_.max_score, Par(), Received(i));
        if (max > 0 && p.strokes >= max) PickUp(i, "max_score");
      } else if (settings_.play == PlayFormat::kMatch) {
        const RoundPlayer& o = st.players[1 - i];
        if (o.ball.holed && p.strokes - Received(i) >= o.strokes - Received(1 - i)) {
          PickUp(i, "decided");
        }
      }
    }
  }

  // The hole's scores under the format, and match play's hole result.
  void ScoreHole(int index) {
    RoundState& st = state();
    const int par = Par();
    for (size_t i = 0; i < st.players.size(); ++i) {
      RoundPlayer& p = st.players[i];
      const int recv = p.received[index];
      const int max = settings_.play == PlayFormat::kStroke ? MaxScoreOf(settings_.max_score, par, recv) : 0;
      if (p.ball.holed) {
        p.scores[index] = max > 0 ? std::min(p.strokes, max) : p.strokes;
      } else if (max > 0) {
        p.scores[index] = max;  // picked up at the maximum (21.2c)
      } else {
        p.scores[index] = 0;
        p.no_score[index] = true;
      }
      if (settings_.play == PlayFormat::kStableford) {
        p.points[index] = p.no_score[index] ? 0 : StablefordPoints(p.scores[index], par, recv);
      }
    }
    if (settings_.play == PlayFormat::kMatch && st.hole_winners[index] == -2) {
      // The fewer net strokes wins the hole (3.2a(1)); a ball not holed loses to one holed.
      auto net = [&](int seat) {
        const RoundPlayer& p = st.players[seat];
        return p.no_score[index] ? std::numeric_limits<int>::max() : p.scores[index] - p.received[index];
      };
      const int a = net(0), b = net(1);
      st.hole_winners[index] = a < b ? 0 : (b < a ? 1 : -1);
    }
  }

  void EndRound(std::string result, std::vector<int> winners) {
    RoundState& st = state();
    st.over = true;
    st.result = std::move(result);
    st.winners = std::move(winners);
    Emit(RoundEventKind::kRoundEnd, -1);
  }

  // The round's winners when its last hole is complete: the lowest total (net with handicaps),
  // the most points.
  std::vector<int> Leaders() const {
    const RoundState& st = step_.state;
    const bool net = HasHandicaps(settings_);
    std::vector<int> out;
    int best = 0;
    for (size_t i = 0; i < st.players.size(); ++i) {
      const RoundPlayer& p = st.players[i];
      // Lower is better: strokes, or points negated.
      const int t = settings_.play == PlayFormat::kStableford ? -p.Points()
                                                               : (net ? p.NetTotal() : p.Total());
      if (i == 0 || t < best) {
        best = t;
        out.clear();
      }
      if (t == best) out.push_back(static_cast<int>(i));
    }
    return out;
  }

  // After a ball has moved: the hole's end, the round's, and the marks on the green.
  void Settle() {
    RoundState& st = state();
    AutoPickUps();
    const bool all_done = std::all_of(st.players.begin(), st.players.end(),
                                      [](const RoundPlayer& p) { return Done(p.ball); });
    if (all_done && !st.decision) {
      const int index = st.hole - settings_.first_hole;
      ScoreHole(index);
      Emit(RoundEventKind::kHoleEnd, -1);
      if (settings_.play == PlayFormat::kMatch) {
        // Rule 3.2a(3): won when one side leads by more holes than are left to play.
        const MatchStatus m = MatchStatusOf(settings_, st);
        if (m.leader >= 0 && m.up > m.to_play) {
          EndRound(m.to_play == 0 ? absl::StrCat(m.up, " up") : absl::StrCat(m.up, " and ", m.to_play),
                   {m.leader});
          return;
        }
        if (m.to_play == 0) {
          EndRound("halved", {0, 1});
          return;
        }
      } else if (st.hole == settings_.last_hole) {
        EndRound("finished", Leaders());
        return;
      }
      // Rule 6.4a(2): in match play the winner of a hole has the honour on the next (a halved
      // hole keeps it); in stroke play the lowest score, ties keeping the order they teed off in
      // (a ball without a score goes last).
      if (settings_.play == PlayFormat::kMatch) {
        const int w = st.hole_winners[index];
        if (w >= 0) st.tee_order = {w, 1 - w};
      } else {
        auto key = [&](int seat) {
          const RoundPlayer& p = st.players[seat];
          return p.no_score[index] ? std::numeric_limits<int>::max() : p.scores[index];
        };
        std::stable_sort(st.tee_order.begin(), st.tee_order.end(),
                         [&](int a, int b) { return key(a) < key(b); });
      }
      ++st.hole;
      for (size_t i = 0; i < st.players.size(); ++i) SendToTee(static_cast<int>(i));
    }
    const int next = ToPlay(course_, settings_, st);
    for (size_t i = 0; i < st.players.size(); ++i) {
      RoundBall& b = st.players[i].ball;
      const bool on_green =
          !Done(b) && AreaAt(at_, st.hole, b.position_m.head<2>(), r()) == CourseAreaKind::kGreen;
      const bool mark = on_green && static_cast<int>(i) != next;
      if (mark != b.marked) {
        b.marked = mark;
        Emit(mark ? RoundEventKind::kMarked : RoundEventKind::kReplaced, static_cast<int>(i))
            .position_m = b.position_m;
      }
    }
  }

  void SendToTee(int seat) {
    RoundPlayer& p = player(seat);
    const CourseHole& hole = *course_.Hole(state().hole);
    const Vector2d t = TeeOf(hole, p.tee).position_m;
    p.strokes = 0;
    p.penalties = 0;
    p.ball = RoundBall{};
    p.ball.position_m = OnGround(course_, t);
    p.ball.lie = Terrain::kTee;
    p.ball.last_spot_m = p.ball.position_m;
    p.ball.last_lie = Terrain::kTee;
  }

  void OpenDecision(int seat, std::string reason, Terrain area, const Vector3d& reference) {
    RoundDecision d;
    d.seat = seat;
    d.reason = std::move(reason);
    d.area = area;
    d.reference_m = reference;
    d.choices = Choices(at_, state().hole, d, r());
    RoundEvent& e = Emit(RoundEventKind::kDecision, seat);
    e.reason = d.reason;
    e.rule = d.reason == "penalty_area" ? "17.1d" : (area == Terrain::kBunker ? "19.3" : "19.2");
    e.choices = d.choices;
    e.position_m = reference;
    state().decision = std::move(d);
  }

  double r() const { return settings_.ball.radius_m(); }

 private:
  // A point of the relief area: up to 256 uniform draws in its circle, the first inside; else
  // the first point of the share grid that is (deterministic either way).
  Vector2d DrawPoint(int hole, const Relief& relief) {
    RoundState& st = state();
    for (int k = 0; k < 256; ++k) {
      const double a = 2.0 * std::numbers::pi * Uniform(settings_.seed, kDropStream, st.draws++);
      const double rr = relief.radius_m * std::sqrt(Uniform(settings_.seed, kDropStream, st.draws++));
      const Vector2d p = relief.reference + rr * Vector2d(std::cos(a), std::sin(a));
      if (InRelief(at_, hole, relief, p, r())) return p;
    }
    constexpr int kN = 41;
    for (int i = 0; i < kN; ++i) {
      for (int j = 0; j < kN; ++j) {
        const Vector2d d(2.0 * i / (kN - 1) - 1.0, 2.0 * j / (kN - 1) - 1.0);
        const Vector2d p = relief.reference + relief.radius_m * d;
        if (d.squaredNorm() <= 1.0 && InRelief(at_, hole, relief, p, r())) return p;
      }
    }
    return relief.reference;
  }

  const Course& course_;
  const CourseIndex at_;  // the surface queries of drops and relief areas, sped up
  const RoundSettings& settings_;
  const std::function<bool()>& cancelled_;
  RoundStep step_;
};

absl::Status CheckTurn(const Course& course, const RoundSettings& settings,
                       const RoundState& state, int seat) {
  if (seat < 0 || seat >= static_cast<int>(state.players.size())) {
    return absl::InvalidArgumentError(
        absl::StrFormat("seat: %d is not a seat of the round (0 to %d)", seat, state.players.size() - 1));
  }
  if (state.over) return absl::FailedPreconditionError("the round is over");
  if (state.decision) {
    const RoundDecision& d = *state.decision;
    const std::string rule = d.reason == "penalty_area" ? "Rule 17.1d" : "Rule 19";
    if (d.seat == seat) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "a decision is pending: choose one of %s first (%s)", absl::StrJoin(d.choices, ", "), rule));
    }
    return absl::FailedPreconditionError(absl::StrFormat(
        "a decision is pending: %s (seat %d) chooses their relief first (%s)",
        state.players[d.seat].name, d.seat, rule));
  }
  if (state.players[seat].ball.holed) {
    return absl::FailedPreconditionError(
        absl::StrFormat("%s's ball is holed on hole %d (Rule 13.2c)", state.players[seat].name, state.hole));
  }
  if (state.players[seat].ball.picked_up) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "%s's ball is picked up on hole %d: the hole is over for them", state.players[seat].name, state.hole));
  }
  const std::vector<int> may = MayPlay(course, settings, state);
  if (std::find(may.begin(), may.end(), seat) != may.end()) return absl::OkStatus();
  const int next = ToPlay(course, settings, state);
  const RoundPlayer& n = state.players[next];
  const bool on_tee = n.strokes == 0;
  return absl::FailedPreconditionError(absl::StrFormat(
      "not your turn: %s (seat %d) plays next (Rule 6.4%s)", n.name, next,
      on_tee ? "a: the honour on the tee" : "b: the ball farthest from the hole"));
}

absl::Status Beyond(std::string_view field, double value, double limit, std::string_view unit) {
  return absl::InvalidArgumentError(absl::StrFormat(
      "%s: %g %s is beyond a human golfer (realistic profile: at most %g %s); the arcade profile "
      "lifts the bound",
      field, value, unit, limit, unit));
}

absl::Status CheckRealistic(const RoundStroke& s) {
  const RoundLimits& l = kRoundLimits;
  if (s.kind == RoundStroke::Kind::kPutt) {
    if (s.speed_mps > l.max_putt_speed_mps) return Beyond("speed_mps", s.speed_mps, l.max_putt_speed_mps, "m/s");
    return absl::OkStatus();
  }
  const LaunchConditions& c = s.launch;
  if (c.ball_speed_mps > l.max_ball_speed_mps) {
    return Beyond("launch.ball_speed_mps", c.ball_speed_mps, l.max_ball_speed_mps, "m/s");
  }
  if (c.launch_angle_deg > l.max_launch_angle_deg || c.launch_angle_deg < l.min_launch_angle_deg) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "launch.launch_angle_deg: %g deg is beyond a human golfer (realistic profile: %g to %g "
        "deg); the arcade profile lifts the bound",
        c.launch_angle_deg, l.min_launch_angle_deg, l.max_launch_angle_deg));
  }
  if (std::abs(c.launch_direction_deg) > l.max_launch_direction_deg) {
    return Beyond("launch.launch_direction_deg", std::abs(c.launch_direction_deg),
                  l.max_launch_direction_deg, "deg");
  }
  if (c.spin_rpm > l.max_spin_rpm) return Beyond("launch.spin_rpm", c.spin_rpm, l.max_spin_rpm, "rpm");
  return absl::OkStatus();
}

}  // namespace

// --- names ------------------------------------------------------------------------------------

std::string_view OrderOfPlayName(OrderOfPlay o) { return o == OrderOfPlay::kReady ? "ready" : "honour"; }

std::string_view PlayFormatName(PlayFormat p) {
  switch (p) {
    case PlayFormat::kMatch: return "match";
    case PlayFormat::kStableford: return "stableford";
    case PlayFormat::kStroke: break;
  }
  return "stroke";
}

absl::StatusOr<PlayFormat> PlayFormatFromName(std::string_view name) {
  if (name == "stroke" || name.empty()) return PlayFormat::kStroke;
  if (name == "match") return PlayFormat::kMatch;
  if (name == "stableford") return PlayFormat::kStableford;
  return absl::InvalidArgumentError(absl::StrFormat(
      "play: \"%s\" is not a form of play (stroke, match, stableford)", name.substr(0, 24)));
}

std::string_view RealismName(Realism r) { return r == Realism::kArcade ? "arcade" : "realistic"; }

absl::StatusOr<Realism> RealismFromName(std::string_view name) {
  if (name == "realistic") return Realism::kRealistic;
  if (name == "arcade") return Realism::kArcade;
  return absl::InvalidArgumentError(absl::StrFormat(
      "realism: must be realistic or arcade; got \"%s\"", name.substr(0, 24)));
}

std::string_view CourseAreaName(CourseAreaKind a) {
  switch (a) {
    case CourseAreaKind::kGeneral: return "general";
    case CourseAreaKind::kTeeing: return "teeing";
    case CourseAreaKind::kPenaltyArea: return "penalty_area";
    case CourseAreaKind::kBunker: return "bunker";
    case CourseAreaKind::kGreen: return "green";
  }
  return "general";
}

std::string_view RoundEventName(RoundEventKind kind) {
  switch (kind) {
    case RoundEventKind::kStroke: return "stroke";
    case RoundEventKind::kHoled: return "holed";
    case RoundEventKind::kRest: return "rest";
    case RoundEventKind::kPenalty: return "penalty";
    case RoundEventKind::kDecision: return "decision";
    case RoundEventKind::kChoice: return "choice";
    case RoundEventKind::kDrop: return "drop";
    case RoundEventKind::kPlaced: return "placed";
    case RoundEventKind::kMarked: return "marked";
    case RoundEventKind::kReplaced: return "replaced";
    case RoundEventKind::kConceded: return "conceded";
    case RoundEventKind::kPickedUp: return "picked_up";
    case RoundEventKind::kHoleEnd: return "hole_end";
    case RoundEventKind::kRoundEnd: return "round_end";
  }
  return "stroke";
}

int RoundPlayer::Total() const {
  int t = 0;
  for (int s : scores) t += s;
  return t;
}

int RoundPlayer::NetTotal() const {
  int t = 0;
  for (size_t h = 0; h < scores.size(); ++h) {
    if (scores[h] > 0) t += scores[h] - received[h];
  }
  return t;
}

int RoundPlayer::Points() const {
  int t = 0;
  for (int p : points) t += p;
  return t;
}

// --- handicaps and scores ---------------------------------------------------------------------

bool HasHandicaps(const RoundSettings& settings) {
  return std::any_of(settings.players.begin(), settings.players.end(),
                     [](const RoundPlayerSpec& p) { return p.handicap_index.has_value(); });
}

RoundStroke ReferenceStroke(double d, bool on_green, int strokes_over_par) {
  RoundStroke k;
  if (on_green || d < 20) {
    k.kind = RoundStroke::Kind::kPutt;
    // Struck, a putt rolls at 5/7 of its speed; a stimp-10 green takes about 0.6 m/s^2.
    k.speed_mps = std::min(12.0, 1.4 * std::sqrt(1.2 * (d + 0.3)));
    return k;
  }
  const double f = std::pow(0.9, std::max(0, strokes_over_par));
  const bool pitch = d < 60;
  k.launch = LaunchConditions{.ball_speed_mps = pitch ? 3.6 * std::sqrt(d) * f
                                                      : std::min(70.0, 4.5 * std::sqrt(d)) * f,
                              .launch_angle_deg = pitch ? 40.0 : 20.0,
                              .launch_direction_deg = 0,
                              .spin_rpm = pitch ? 6000.0 : 5000.0,
                              .spin_axis_deg = 0};
  return k;
}

double CourseHandicap(const Course& course, std::string_view tee, double handicap_index) {
  const CourseRating r = course.RatingOf(tee);
  const double scale = static_cast<double>(course.holes.size()) / 18.0;
  return handicap_index * scale * r.slope / 113.0 + (r.course_rating - course.Par());
}

int StrokesReceived(int playing_handicap, int stroke_index, int holes) {
  if (holes <= 0) return 0;
  if (playing_handicap >= 0) {
    return playing_handicap / holes + (stroke_index <= playing_handicap % holes ? 1 : 0);
  }
  const int back = -playing_handicap;
  return -(back / holes + (stroke_index > holes - back % holes ? 1 : 0));
}

int StablefordPoints(int gross, int par, int received) {
  return std::max(0, 2 + par + received - gross);
}

int MaxScoreOf(const MaxScore& max, int par, int received) {
  switch (max.kind) {
    case MaxScore::Kind::kFixed: return max.n;
    case MaxScore::Kind::kParPlus: return par + max.n;
    case MaxScore::Kind::kNetDoubleBogey: return par + 2 + received;
    case MaxScore::Kind::kNone: break;
  }
  return 0;
}

MatchStatus MatchStatusOf(const RoundSettings& settings, const RoundState& state) {
  MatchStatus m;
  if (settings.play != PlayFormat::kMatch) return m;
  int won[2] = {0, 0};
  for (int w : state.hole_winners) {
    if (w >= 0) ++won[w];
    if (w == -2) ++m.to_play;
  }
  if (won[0] != won[1]) {
    m.leader = won[0] > won[1] ? 0 : 1;
    m.up = std::abs(won[0] - won[1]);
  }
  m.dormie = !state.over && m.up > 0 && m.up == m.to_play;
  return m;
}

std::string MatchStatusText(const RoundSettings& settings, const RoundState& state) {
  if (settings.play != PlayFormat::kMatch || state.players.size() != 2) return "";
  const MatchStatus m = MatchStatusOf(settings, state);
  if (state.over) {
    if (state.winners.size() != 1) return "halved";
    const std::string& who = state.players[state.winners.front()].name;
    if (state.result == "conceded") return absl::StrCat(who, " won (the match was conceded)");
    return absl::StrCat(who, " won ", state.result);
  }
  if (m.leader < 0) return absl::StrCat("all square with ", m.to_play, " to play");
  return absl::StrCat(state.players[m.leader].name, " ", m.up, " up with ", m.to_play, " to play",
                      m.dormie ? " (dormie)" : "");
}

// --- settings ---------------------------------------------------------------------------------

absl::Status ValidateRoundSettings(const Course& course, const RoundSettings& s) {
  const int n = static_cast<int>(course.holes.size());
  if (s.first_hole < 1 || s.first_hole > n) {
    return absl::InvalidArgumentError(
        absl::StrFormat("holes: %d is not a hole of %s (1 to %d)", s.first_hole, course.name, n));
  }
  if (s.last_hole < s.first_hole || s.last_hole > n) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "holes: the last hole %d must be from %d to %d", s.last_hole, s.first_hole, n));
  }
  if (s.players.empty() || s.players.size() > 8) {
    return absl::InvalidArgumentError(
        absl::StrFormat("players: a round has 1 to 8 players; got %d", s.players.size()));
  }
  for (size_t i = 0; i < s.players.size(); ++i) {
    const RoundPlayerSpec& p = s.players[i];
    const bool printable = std::all_of(p.name.begin(), p.name.end(), [](char c) {
      return static_cast<unsigned char>(c) >= 0x20 && c != 0x7f;
    });
    if (p.name.empty() || p.name.size() > 40 || !printable) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "players[%d].name: must be 1 to 40 printable characters", i));
    }
    if (p.tee.empty()) continue;
    bool found = false;
    for (int h = s.first_hole; h <= s.last_hole && !found; ++h) {
      for (const CourseTee& t : course.Hole(h)->tees) found = found || t.name == p.tee;
    }
    if (!found) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "players[%d].tee: \"%s\" is not a tee of holes %d-%d", i, p.tee.substr(0, 24),
          s.first_hole, s.last_hole));
    }
  }
  for (size_t i = 0; i < s.players.size(); ++i) {
    const std::optional<double>& h = s.players[i].handicap_index;
    if (h && !(*h >= -10.0 && *h <= 54.0)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "players[%d].handicap_index: a Handicap Index is from +10 (-10) to 54; got %g", i, *h));
    }
  }
  if (s.play == PlayFormat::kMatch && s.players.size() != 2) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "players: match play is between two players (Rule 3.2); got %d", s.players.size()));
  }
  if (s.max_score.kind != MaxScore::Kind::kNone && s.play != PlayFormat::kStroke) {
    return absl::InvalidArgumentError(
        "rules: max_score is a form of stroke play (Rule 21.2); Stableford and match play end a "
        "hole their own way");
  }
  if (s.allowance_pct && !(*s.allowance_pct >= 0.0 && *s.allowance_pct <= 100.0)) {
    return absl::InvalidArgumentError(
        absl::StrFormat("rules: allowance must be in [0, 100] %%; got %g", *s.allowance_pct));
  }
  if (!std::isfinite(s.noise) || s.noise < 0.0 || s.noise > 5.0) {
    return absl::InvalidArgumentError(absl::StrFormat("noise: must be in [0, 5]; got %g", s.noise));
  }
  return ValidateBallSpec(s.ball);
}

absl::Status SetRoundVariant(std::string_view name, std::string_view value, RoundSettings* settings) {
  if (name == "order") {
    if (value == "honour") {
      settings->order = OrderOfPlay::kHonour;
    } else if (value == "ready") {
      settings->order = OrderOfPlay::kReady;
    } else {
      return absl::InvalidArgumentError(absl::StrFormat(
          "rule order must be one of honour, ready; got \"%s\"", value.substr(0, 24)));
    }
    return absl::OkStatus();
  }
  if (name == "max_score") {
    MaxScore m;
    int n = 0;
    if (value == "none") {
      m.kind = MaxScore::Kind::kNone;
    } else if (value == "net_double_bogey") {
      m.kind = MaxScore::Kind::kNetDoubleBogey;
    } else if (value.starts_with("par+") && absl::SimpleAtoi(std::string(value.substr(4)), &n) &&
               n >= 1 && n <= 10) {
      m = {MaxScore::Kind::kParPlus, n};
    } else if (absl::SimpleAtoi(std::string(value), &n) && n >= 3 && n <= 20) {
      m = {MaxScore::Kind::kFixed, n};
    } else {
      return absl::InvalidArgumentError(absl::StrFormat(
          "rule max_score must be a number of strokes (3-20), par+N (1-10), net_double_bogey or "
          "none; got \"%s\"", value.substr(0, 24)));
    }
    settings->max_score = m;
    return absl::OkStatus();
  }
  if (name == "allowance") {
    double pct = 0.0;
    if (!absl::SimpleAtod(std::string(value), &pct) || !(pct >= 0.0 && pct <= 100.0)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "rule allowance must be a percentage in [0, 100]; got \"%s\"", value.substr(0, 24)));
    }
    settings->allowance_pct = pct;
    return absl::OkStatus();
  }
  return absl::InvalidArgumentError(absl::StrFormat(
      "rule \"%s\" is not a rule of a round (order, max_score, allowance)", name.substr(0, 24)));
}

// --- areas ------------------------------------------------------------------------------------

CourseAreaKind AreaOfCourse(const Course& course, int hole, const Vector2d& spot, double r) {
  return AreaAt(CourseIndex(course), hole, spot, r);
}

// --- the round --------------------------------------------------------------------------------

absl::StatusOr<RoundState> StartRound(const Course& course, const RoundSettings& settings) {
  if (absl::Status s = ValidateRoundSettings(course, settings); !s.ok()) return s;
  RoundState st;
  st.hole = settings.first_hole;
  const int holes = settings.last_hole - settings.first_hole + 1;
  for (size_t i = 0; i < settings.players.size(); ++i) {
    RoundPlayer& p = st.players.emplace_back();
    p.name = settings.players[i].name;
    p.tee = settings.players[i].tee;
    p.scores.assign(holes, 0);
    p.no_score.assign(holes, false);
    p.points.assign(holes, 0);
    st.tee_order.push_back(static_cast<int>(i));
  }
  // Playing handicaps (Rules of Handicapping 6.2): the unrounded course handicap times the
  // allowance, rounded (.5 up); in match play the lower plays off scratch and the other
  // receives the difference (Appendix C).
  const double allowance =
      settings.allowance_pct ? *settings.allowance_pct / 100.0
                             : (settings.play == PlayFormat::kMatch ? 1.0 : 0.95);
  for (size_t i = 0; i < settings.players.size(); ++i) {
    const RoundPlayerSpec& spec = settings.players[i];
    if (!spec.handicap_index) continue;
    st.players[i].playing_handicap = static_cast<int>(
        std::floor(CourseHandicap(course, spec.tee, *spec.handicap_index) * allowance + 0.5));
  }
  if (settings.play == PlayFormat::kMatch) {
    const int low = std::min(st.players[0].playing_handicap, st.players[1].playing_handicap);
    for (RoundPlayer& p : st.players) p.playing_handicap -= low;
    st.hole_winners.assign(holes, -2);
  }
  const int course_holes = static_cast<int>(course.holes.size());
  for (RoundPlayer& p : st.players) {
    for (int h = settings.first_hole; h <= settings.last_hole; ++h) {
      p.received.push_back(StrokesReceived(p.playing_handicap, course.Hole(h)->stroke_index, course_holes));
    }
  }
  static const std::function<bool()> kNever;
  Referee ref(course, settings, st, kNever);
  for (size_t i = 0; i < settings.players.size(); ++i) ref.SendToTee(static_cast<int>(i));
  return ref.Take().state;
}

int ToPlay(const Course& course, const RoundSettings& settings, const RoundState& state) {
  (void)settings;
  if (state.over) return -1;
  if (state.decision) return state.decision->seat;
  for (int seat : state.tee_order) {
    const RoundPlayer& p = state.players[seat];
    if (!Done(p.ball) && p.strokes == 0) return seat;
  }
  int best = -1;
  double far = -1.0;
  for (size_t i = 0; i < state.players.size(); ++i) {
    const RoundPlayer& p = state.players[i];
    if (Done(p.ball)) continue;
    const double d = ToPin(course, state.hole, p.ball.position_m);
    if (d > far) {
      far = d;
      best = static_cast<int>(i);
    }
  }
  return best;
}

std::vector<int> MayPlay(const Course& course, const RoundSettings& settings,
                         const RoundState& state) {
  if (state.over || state.decision) return {};
  if (settings.order == OrderOfPlay::kHonour) {
    const int next = ToPlay(course, settings, state);
    return next >= 0 ? std::vector<int>{next} : std::vector<int>{};
  }
  std::vector<int> out;
  for (size_t i = 0; i < state.players.size(); ++i) {
    if (!Done(state.players[i].ball)) out.push_back(static_cast<int>(i));
  }
  return out;
}

absl::Status CheckStroke(const Course& course, const RoundSettings& settings,
                         const RoundState& state, int seat, const RoundStroke& stroke) {
  if (absl::Status s = CheckTurn(course, settings, state, seat); !s.ok()) return s;
  if (stroke.aim_deg && !(std::abs(*stroke.aim_deg) <= 1e4)) {
    return absl::InvalidArgumentError("aim_deg: must be a finite heading (deg)");
  }
  if (stroke.kind == RoundStroke::Kind::kSwing) {
    if (!stroke.swing || stroke.swing->model == nullptr) {
      return absl::InvalidArgumentError("swing: a swing stroke needs its golfer, torques and club");
    }
    if (settings.realism == Realism::kRealistic) {
      const swing::TorqueProgram& p = stroke.swing->program;
      for (const auto& [name, schedule, limit] :
           {std::tuple{"qalpha", &p.q_alpha(), swing::kHumanLimits.max_shoulder_torque_nm},
            std::tuple{"qbeta", &p.q_beta(), swing::kHumanLimits.max_wrist_torque_nm}}) {
        for (size_t i = 0; i < schedule->knots.size(); ++i) {
          if (absl::Status s = swing::CheckHumanTorque(
                  absl::StrFormat("swing.torques.%s.knots[%d].torque_nm", name, i),
                  schedule->knots[i].torque_nm, limit);
              !s.ok()) {
            return s;
          }
        }
      }
    }
    return absl::OkStatus();
  }
  if (stroke.kind == RoundStroke::Kind::kPutt) {
    if (!(stroke.speed_mps > 0.0 && stroke.speed_mps <= 15.0)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("speed_mps: a putt's speed must be in (0, 15] m/s; got %g", stroke.speed_mps));
    }
  } else if (absl::Status s = ValidateLaunchConditions(stroke.launch); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("launch.", s.message()));
  }
  if (settings.realism == Realism::kRealistic) return CheckRealistic(stroke);
  return absl::OkStatus();
}

absl::StatusOr<CourseShot> StrokeShot(const Course& course, const RoundSettings& settings,
                                      const RoundState& state, int seat,
                                      const RoundStroke& stroke,
                                      const std::function<bool()>& cancelled) {
  if (seat < 0 || seat >= static_cast<int>(state.players.size())) {
    return absl::InvalidArgumentError(absl::StrFormat("seat: %d is not a seat of the round", seat));
  }
  const RoundBall& b = state.players[seat].ball;
  CourseShot shot;
  shot.hole = state.hole;
  shot.from_m = b.position_m.head<2>();
  const Vector2d to_pin = Pin(course, state.hole) - shot.from_m;
  shot.aim_deg = stroke.aim_deg ? *stroke.aim_deg : std::atan2(to_pin.y(), to_pin.x()) / kDeg;
  shot.ball = settings.ball;
  shot.hole_spec.flagstick_diameter_m = stroke.flagstick_in ? kFlagstickDiameter : 0.0;
  // The round's noise: the stroke's draws are its number's (8 per stroke).
  const double k = settings.noise;
  const uint64_t n0 = static_cast<uint64_t>(state.strokes) * 8;
  auto normal = [&](int i) { return k > 0.0 ? Normal(settings.seed, kNoiseStream, n0 + i) : 0.0; };
  if (stroke.kind == RoundStroke::Kind::kPutt) {
    shot.kind = CourseShot::Kind::kPutt;
    shot.speed_mps = std::clamp(stroke.speed_mps * (1.0 + 0.03 * k * normal(0)), 1e-3, 15.0);
    shot.aim_deg += 0.5 * k * normal(1);
  } else {
    shot.kind = CourseShot::Kind::kLaunch;
    LaunchConditions c = stroke.launch;
    if (stroke.kind == RoundStroke::Kind::kSwing) {
      if (!stroke.swing || stroke.swing->model == nullptr) {
        return absl::InvalidArgumentError("swing: a swing stroke needs its golfer, torques and club");
      }
      absl::StatusOr<SwingLaunch> swung = LaunchFromSwing(*stroke.swing, settings.ball, cancelled);
      if (!swung.ok()) return swung.status();
      if (settings.realism == Realism::kRealistic &&
          swung->clubhead_speed_mps > swing::kHumanLimits.max_clubhead_speed_mps) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "torques: this swing brings the clubhead to %.1f m/s at impact, beyond what a human "
            "golfer reaches (realistic profile: %g m/s); the arcade profile lifts the bound",
            swung->clubhead_speed_mps, swing::kHumanLimits.max_clubhead_speed_mps));
      }
      c = swung->launch;
    }
    c.ball_speed_mps = std::clamp(c.ball_speed_mps * (1.0 + 0.015 * k * normal(0)), 0.1, 120.0);
    c.launch_angle_deg = std::clamp(c.launch_angle_deg + 1.0 * k * normal(1), -90.0, 90.0);
    c.launch_direction_deg = std::clamp(c.launch_direction_deg + 1.5 * k * normal(2), -90.0, 90.0);
    c.spin_rpm = std::clamp(c.spin_rpm * (1.0 + 0.05 * k * normal(3)), 0.0, 30000.0);
    c.spin_axis_deg = std::clamp(c.spin_axis_deg + 2.0 * k * normal(4), -180.0, 180.0);
    shot.launch = c;
  }
  return shot;
}

absl::StatusOr<RoundStep> JudgeStroke(const Course& course, const RoundSettings& settings,
                                      const RoundState& state, int seat,
                                      const CourseShotResult& shot,
                                      const std::function<bool()>& cancelled) {
  if (absl::Status s = CheckTurn(course, settings, state, seat); !s.ok()) return s;
  Referee ref(course, settings, state, cancelled);
  RoundPlayer& p = ref.player(seat);
  RoundBall& b = p.ball;
  ++p.strokes;
  ++ref.state().strokes;
  b.last_spot_m = b.position_m;
  b.last_lie = b.lie;
  b.marked = false;
  ref.Emit(RoundEventKind::kStroke, seat).position_m = b.position_m;
  const GroundResult& g = shot.ground;
  if (g.holed) {
    b.position_m = g.rest_m;
    b.lie = Terrain::kGreen;
    b.holed = true;
    ref.Emit(RoundEventKind::kHoled, seat).position_m = g.rest_m;
  } else {
    b.position_m = g.rest_m;
    b.lie = shot.lie;
    RoundEvent& rest = ref.Emit(RoundEventKind::kRest, seat);
    rest.position_m = g.rest_m;
    rest.lie = std::string(TerrainTag(shot.lie));
    if (g.out_of_bounds || shot.lie == Terrain::kOutOfBounds) {
      ref.Penalty(seat, 1, "out_of_bounds", "18.2b");
      if (absl::Status s = ref.ReturnToLastSpot(seat); !s.ok()) return s;
    } else if (IsPenaltyArea(shot.lie)) {
      // Where the ball last crossed the penalty area's edge: the last point of its path
      // outside, then bisection toward the next (the path's points are its lowest point's).
      const double r = ref.r();
      auto inside = [&](const Vector2d& q) {
        return !course.terrain.Covers(q.x(), q.y()) || IsPenaltyArea(ref.at().LieAt(q.x(), q.y(), r));
      };
      std::vector<Vector2d> pts;
      pts.push_back(shot.start_m.head<2>());
      for (const GroundSample& s : shot.path) pts.push_back(s.position_m.head<2>());
      pts.push_back(g.rest_m.head<2>());
      Vector2d crossing = shot.start_m.head<2>();
      for (size_t i = pts.size() - 1; i-- > 0;) {
        if (inside(pts[i])) continue;
        Vector2d out = pts[i], in = pts[i + 1];
        for (int k = 0; k < 50; ++k) {
          const Vector2d mid = 0.5 * (out + in);
          (inside(mid) ? in : out) = mid;
        }
        crossing = out;
        break;
      }
      ref.OpenDecision(seat, "penalty_area", shot.lie, OnGround(course, crossing));
    }
  }
  ref.Settle();
  return ref.Take();
}

absl::StatusOr<RoundStep> ShotClockExpired(const Course& course, const RoundSettings& settings,
                                           const RoundState& state) {
  const int seat = ToPlay(course, settings, state);
  if (seat < 0) return absl::FailedPreconditionError("the round is over");
  static const std::function<bool()> kNever;
  Referee ref(course, settings, state, kNever);
  ref.Penalty(seat, 1, "shot_clock", "5.6b");
  ref.Settle();  // the penalty may reach a format's end of the hole (a maximum score)
  return ref.Take();
}

absl::StatusOr<RoundStep> PlayStroke(const Course& course, const RoundSettings& settings,
                                     const RoundState& state, int seat, const RoundStroke& stroke,
                                     CourseShotResult* shot_out,
                                     const std::function<bool()>& cancelled) {
  if (absl::Status s = CheckStroke(course, settings, state, seat, stroke); !s.ok()) return s;
  absl::StatusOr<CourseShot> shot = StrokeShot(course, settings, state, seat, stroke, cancelled);
  if (!shot.ok()) return shot.status();
  shot->flight.cancelled = cancelled;
  shot->ground.cancelled = cancelled;
  absl::StatusOr<CourseShotResult> result = PlayCourseShot(course, *shot);
  if (!result.ok()) return result.status();
  absl::StatusOr<RoundStep> step = JudgeStroke(course, settings, state, seat, *result, cancelled);
  if (step.ok() && shot_out != nullptr) *shot_out = *std::move(result);
  return step;
}

absl::StatusOr<RoundStep> Decide(const Course& course, const RoundSettings& settings,
                                 const RoundState& state, int seat, const RoundChoice& choice,
                                 const std::function<bool()>& cancelled) {
  if (seat < 0 || seat >= static_cast<int>(state.players.size())) {
    return absl::InvalidArgumentError(
        absl::StrFormat("seat: %d is not a seat of the round (0 to %d)", seat, state.players.size() - 1));
  }
  if (state.over) return absl::FailedPreconditionError("the round is over");
  Referee ref(course, settings, state, cancelled);
  const double r = ref.r();
  if (choice.choice == "pick_up") {
    if (settings.play == PlayFormat::kMatch) {
      return absl::FailedPreconditionError(
          "in match play a player who picks up concedes the hole: concede_hole (Rule 3.2b)");
    }
    if (settings.play == PlayFormat::kStroke && settings.max_score.kind == MaxScore::Kind::kNone) {
      return absl::FailedPreconditionError(
          "in stroke play every hole is holed out (Rule 3.3c); picking up is for Stableford "
          "(21.1c) or a maximum score (21.2c, rule max_score)");
    }
    // At any time while the seat's ball is in play (not only on its turn: lifting it affects
    // no one's play), a pending relief decision of its own included.
    const RoundBall& ball = state.players[seat].ball;
    if (Done(ball)) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "%s's hole is over: the ball is %s", state.players[seat].name, ball.holed ? "holed" : "picked up"));
    }
    if (state.players[seat].strokes == 0) {
      return absl::FailedPreconditionError(
          "no ball in play: a ball is in play once it has been struck from the teeing area (Rule 6.2)");
    }
    ref.PickUp(seat, "pick_up");
    ref.Settle();
    return ref.Take();
  }
  if (absl::StartsWith(choice.choice, "concede_")) {
    if (settings.play != PlayFormat::kMatch) {
      return absl::FailedPreconditionError("concessions are match play's (Rule 3.2b)");
    }
    const std::string& what = choice.choice;
    if (what != "concede_stroke" && what != "concede_hole" && what != "concede_match") {
      return absl::InvalidArgumentError(absl::StrFormat(
          "choice: \"%s\" is not a concession (concede_stroke, concede_hole, concede_match)",
          what.substr(0, 24)));
    }
    const int opp = 1 - seat;
    const RoundPlayer& o = state.players[opp];
    if (what == "concede_stroke") {
      if (Done(o.ball)) {
        return absl::FailedPreconditionError(absl::StrFormat(
            "%s's hole is over: there is no next stroke to concede", o.name));
      }
      if (state.decision && state.decision->seat == opp) {
        return absl::FailedPreconditionError(absl::StrFormat(
            "%s has a relief decision pending: their next stroke comes after it (concede the hole "
            "instead)", o.name));
      }
    }
    RoundEvent& e = ref.Emit(RoundEventKind::kConceded, seat);
    e.choice = what;
    e.rule = "3.2b";
    if (what == "concede_match") {
      ref.EndRound("conceded", {opp});
      return ref.Take();
    }
    if (what == "concede_stroke") {
      // The opponent's ball is holed with their next stroke (3.2b(1)).
      RoundPlayer& op = ref.player(opp);
      ++op.strokes;
      op.ball.holed = true;
      op.ball.marked = false;
      op.ball.position_m = OnGround(course, Pin(course, state.hole));
      ref.Emit(RoundEventKind::kHoled, opp).position_m = op.ball.position_m;
    } else {
      ref.state().hole_winners[state.hole - settings.first_hole] = opp;
      for (int i : {seat, opp}) {
        if (!Done(ref.player(i).ball)) ref.PickUp(i, "conceded");
      }
      ref.state().decision.reset();
    }
    ref.Settle();
    return ref.Take();
  }
  if (choice.choice == "unplayable") {
    if (absl::Status s = CheckTurn(course, settings, state, seat); !s.ok()) return s;
    const RoundPlayer& p = state.players[seat];
    if (p.strokes == 0) {
      return absl::FailedPreconditionError(
          "no ball in play: a ball is in play once it has been struck from the teeing area (Rule 6.2)");
    }
    if (IsPenaltyArea(p.ball.lie)) {
      return absl::FailedPreconditionError(
          "a ball in a penalty area cannot be declared unplayable (Rule 19.1); the penalty area's "
          "relief is Rule 17");
    }
    ref.OpenDecision(seat, "unplayable", p.ball.lie, p.ball.position_m);
    return ref.Take();
  }
  if (!state.decision) {
    return absl::FailedPreconditionError(
        "no decision is pending (a choice answers a ball in a penalty area, Rule 17.1d, or one "
        "declared unplayable, Rule 19: --choice unplayable)");
  }
  const RoundDecision d = *state.decision;
  if (d.seat != seat) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "the decision is %s's (seat %d)", state.players[d.seat].name, d.seat));
  }
  if (std::find(d.choices.begin(), d.choices.end(), choice.choice) == d.choices.end()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "choice: \"%s\" is not one of %s", choice.choice.substr(0, 24), absl::StrJoin(d.choices, ", ")));
  }
  const bool back = choice.choice == "back_on_the_line" ||
                    choice.choice == "back_on_the_line_outside_bunker";
  const bool outside_bunker = choice.choice == "back_on_the_line_outside_bunker";
  if (choice.back_m && !back) {
    return absl::InvalidArgumentError("back_m: only a back-on-the-line choice takes a distance");
  }
  Relief relief;
  if (back) {
    double distance = 0.0;
    if (choice.back_m) {
      if (!(*choice.back_m >= 0.0 && *choice.back_m <= kBackMaxM)) {
        return absl::InvalidArgumentError(
            absl::StrFormat("back_m: must be in [0, %g] m; got %g", kBackMaxM, *choice.back_m));
      }
      distance = *choice.back_m;
      if (!UsableBackOnTheLine(ref.at(), state.hole,
                               BackOnTheLine(course, state.hole, d, distance, outside_bunker), r)) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "back_m: the point %g m back on the line is out of bounds, in the area the relief is "
            "from, or leaves no room to drop",
            distance));
      }
    } else {
      distance = *DefaultBack(ref.at(), state.hole, d, outside_bunker, r);  // offered: it exists
    }
    relief = BackOnTheLine(course, state.hole, d, distance, outside_bunker);
  } else if (choice.choice == "lateral") {
    relief = Lateral(d);
  }
  ref.state().decision.reset();
  RoundEvent& e = ref.Emit(RoundEventKind::kChoice, seat);
  e.choice = choice.choice;
  e.reason = d.reason;
  e.rule = RuleOf(d, choice.choice);
  ref.Penalty(seat, outside_bunker ? 2 : 1, d.reason, RuleOf(d, choice.choice));
  RoundBall& b = ref.player(seat).ball;
  b.marked = false;
  absl::Status s = choice.choice == "stroke_and_distance" ? ref.ReturnToLastSpot(seat)
                                                          : ref.Drop(seat, relief);
  if (!s.ok()) return s;
  ref.Settle();
  return ref.Take();
}

}  // namespace sportsim::golf
