// Plain words for ruled games: see game_text.h.
#include "client/game_text.h"

#include <cstdio>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/match.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "client/cli.h"

namespace sportsim::cli {
namespace {

// Per-seat numbers as "3-1".
template <typename List>
std::string PerSeat(const List& values) {
  return absl::StrJoin(values, "-");
}

std::string BallInHandWords(const std::string& b) {
  if (b.empty() || b == "none") return "no ball in hand";
  if (b == "anywhere") return "ball in hand anywhere";
  if (b == "kitchen") return "ball in hand in the kitchen (behind the head string)";
  if (b == "d") return "ball in hand in the D";
  return "ball in hand: " + b;
}

std::string Plural(int n, const char* one, const char* many) {
  return absl::StrFormat("%d %s", n, n == 1 || n == -1 ? one : many);
}

std::string OrList(const google::protobuf::RepeatedPtrField<std::string>& choices) {
  if (choices.empty()) return "(no choices listed)";
  if (choices.size() == 1) return choices[0];
  std::vector<std::string> head(choices.begin(), choices.end() - 1);
  return absl::StrCat(absl::StrJoin(head, ", "), " or ", choices[choices.size() - 1]);
}

}  // namespace

std::string VerdictText(const v1::Verdict& v, uint32_t seat) {
  std::string s;
  if (v.foul()) {
    s = absl::StrFormat("foul by seat %u (%s)", seat, v.reason().empty() ? "foul" : v.reason());
    if (v.points() != 0) absl::StrAppend(&s, ", ", Plural(v.points(), "point", "points"), " to the opponent");
  } else {
    s = absl::StrFormat("legal shot by seat %u", seat);
    if (!v.reason().empty()) absl::StrAppend(&s, " (", v.reason(), ")");
    if (v.points() != 0) absl::StrAppend(&s, ", ", Plural(v.points(), "point", "points"));
  }
  if (!v.respotted().empty()) absl::StrAppend(&s, ", respotted ", absl::StrJoin(v.respotted(), ", "));
  if (v.frame_over()) {
    absl::StrAppend(&s, ", frame over");
  } else if (v.turn_passes()) {
    absl::StrAppend(&s, ", turn passes");
  } else {
    absl::StrAppend(&s, absl::StrFormat(", seat %u plays on", seat));
  }
  return s;
}

std::string RulingText(const v1::Verdict& v, std::string_view said) {
  std::string s = v.foul() ? absl::StrCat("foul (", v.reason().empty() ? "foul" : v.reason(), ")")
                           : (v.reason().empty() ? "no foul" : v.reason());
  if (!v.foul() && !said.empty() && v.reason() == said) s.clear();
  if (v.points() != 0) absl::StrAppend(&s, ", ", Plural(v.points(), "point", "points"));
  if (!v.respotted().empty()) absl::StrAppend(&s, ", respotted ", absl::StrJoin(v.respotted(), ", "));
  if (v.frame_over()) absl::StrAppend(&s, ", frame over");
  else if (v.turn_passes()) absl::StrAppend(&s, ", turn passes");
  return absl::StartsWith(s, ", ") ? s.substr(2) : s;
}

std::string CallText(const v1::ShotCall& c) {
  std::vector<std::string> parts;
  if (!c.ball().empty() || !c.pocket().empty()) {
    parts.push_back(absl::StrCat("called ", c.ball().empty() ? "?" : c.ball(), " in ",
                                 c.pocket().empty() ? "?" : c.pocket()));
  }
  if (c.safety()) parts.push_back("safety");
  if (c.push_out()) parts.push_back("push-out");
  if (!c.nominate().empty()) parts.push_back("nominated " + c.nominate());
  return absl::StrJoin(parts, ", ");
}

std::string StrikeText(const v1::CueStrike& s) {
  std::string speed;
  if (s.speed_case() == v1::CueStrike::kSpeedMps) {
    speed = absl::StrFormat("cue speed %s m/s", Num(s.speed_mps()));
  } else {
    speed = absl::StrFormat("ball speed %s m/s", Num(s.ball_speed_mps()));
  }
  std::string text = absl::StrFormat("%s struck, %s, phi %s deg, theta %s deg, a %s, b %s",
                                     s.ball().empty() ? "cue" : s.ball(), speed, Num(s.phi_deg()),
                                     Num(s.theta_deg()), Num(s.a()), Num(s.b()));
  if (s.noise() != 0) absl::StrAppend(&text, ", noise ", Num(s.noise()));
  return text;
}

std::vector<std::string> GameLines(const v1::GameState& g, const v1::ShotSummary* last) {
  std::vector<std::string> lines;
  // The match and the frame.
  std::string score = absl::StrFormat("game %s, frame %u, race to %u", g.name(), g.frame(),
                                      g.race_to());
  if (!g.frames_won().empty()) absl::StrAppend(&score, ": frames ", PerSeat(g.frames_won()));
  if (!g.scores().empty()) absl::StrAppend(&score, ", points ", PerSeat(g.scores()));
  if (!g.innings().empty()) absl::StrAppend(&score, ", innings ", PerSeat(g.innings()));
  if (!g.phase().empty()) absl::StrAppend(&score, ", phase ", g.phase());
  if (!g.groups().empty()) {
    std::vector<std::string> groups;
    for (const char* seat : {"0", "1"}) {
      auto it = g.groups().find(seat);
      if (it != g.groups().end()) groups.push_back(absl::StrCat("seat ", seat, " ", it->second));
    }
    absl::StrAppend(&score, ", ", absl::StrJoin(groups, ", "));
  } else if (g.name() == "8ball") {
    absl::StrAppend(&score, ", open table");
  }
  lines.push_back(score);

  // Whose turn it is, or the result.
  std::string turn;
  if (!g.result().empty()) {
    if (g.has_winner()) {
      turn = absl::StrFormat("match over: seat %u won (%s)", g.winner(), g.result());
    } else {
      turn = absl::StrFormat("match over: no winner (%s)", g.result());
    }
  } else if (g.has_decision()) {
    turn = absl::StrFormat("seat %u to decide: %s", g.decision().seat(),
                           OrList(g.decision().choices()));
  } else {
    turn = absl::StrFormat("seat %u to play", g.to_play());
    if (g.is_break()) absl::StrAppend(&turn, " the break");
    absl::StrAppend(&turn, ", ", BallInHandWords(g.ball_in_hand()));
    if (g.on().size() > 6) {
      absl::StrAppend(&turn, absl::StrFormat(", any of %d balls on (%s to %s)", g.on().size(),
                                             g.on(0), g.on(g.on().size() - 1)));
    } else if (!g.on().empty()) {
      absl::StrAppend(&turn, g.on().size() == 1 ? ", ball on " : ", balls on ",
                      absl::StrJoin(g.on(), " "));
    }
    if (g.free_ball()) absl::StrAppend(&turn, ", free ball");
    if (g.call_required()) absl::StrAppend(&turn, ", call required");
    if (g.push_out_available()) absl::StrAppend(&turn, ", push-out available");
    if (g.has_shot_clock_deadline_s()) {
      absl::StrAppend(&turn, absl::StrFormat(", shot clock runs out at %.3f s",
                                             g.shot_clock_deadline_s()));
    }
  }
  if (last != nullptr && last->has_verdict()) {
    absl::StrAppend(&turn, "; last shot: ", VerdictText(last->verdict(), last->seat()));
  }
  lines.push_back(turn);

  bool any_fouls = false;
  for (uint32_t f : g.fouls_in_row()) any_fouls |= f > 0;
  if (any_fouls) {
    std::string fouls = "fouls in a row " + PerSeat(g.fouls_in_row());
    for (int i = 0; i < g.warned_size(); ++i) {
      if (g.warned(i)) absl::StrAppend(&fouls, absl::StrFormat(" (seat %d warned)", i));
    }
    lines.push_back(fouls);
  }
  return lines;
}

std::string GameEventNote(const v1::TableEvent& e) {
  const std::string seat = e.has_seat() ? absl::StrFormat("seat %u", e.seat()) : "a seat";
  const std::string why = e.reason().empty() ? "" : " (" + e.reason() + ")";
  switch (e.kind()) {
    case v1::foul:
      return absl::StrCat("foul by ", seat, why,
                          e.points() != 0 ? ", " + Plural(e.points(), "point", "points") +
                                                " to the opponent"
                                          : "");
    case v1::score:
      return absl::StrCat(seat, " scores ", Plural(e.points(), "point", "points"), why);
    case v1::respot:
      return absl::StrCat(absl::StrJoin(e.balls(), ", "), " respotted");
    case v1::decision:
      return absl::StrCat(seat, " to decide: ", OrList(e.choices()), why);
    case v1::warning:
      return absl::StrCat(seat, " warned: two fouls in a row", why);
    case v1::frame_end:
      return e.has_winner() ? absl::StrFormat("frame won by seat %u%s", e.winner(), why)
                            : absl::StrCat("frame ended", why);
    case v1::match_end:
      return e.has_winner() ? absl::StrFormat("match won by seat %u%s", e.winner(), why)
                            : absl::StrCat("match ended without a winner", why);
    default: return "";
  }
}

void PrintGames(const v1::Capabilities& c) {
  if (c.games().empty()) {
    std::printf("  games:                 (none: free play only)\n");
    return;
  }
  std::printf("  games (table create --game NAME, variants with --rule NAME=VALUE):\n");
  for (const v1::GameInfo& g : c.games()) {
    std::printf("    %-14s rack %s%s\n", g.name().c_str(),
                g.default_rack().empty() ? "(any)" : g.default_rack().c_str(),
                g.variants().empty() ? ", no variants" : "");
    for (const v1::GameVariant& v : g.variants()) {
      const std::string allowed =
          v.values().empty() ? absl::StrFormat("[%d, %d]", v.min(), v.max())
                             : absl::StrJoin(v.values(), "|");
      std::printf("      %-24s default %-10s %s  %s\n", v.name().c_str(),
                  v.default_value().c_str(), allowed.c_str(), v.description().c_str());
    }
  }
}

}  // namespace sportsim::cli
