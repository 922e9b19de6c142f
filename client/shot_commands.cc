// `sportsim shot ...`: fast-forward a cue shot (Billiards/SimulateShot), or a batch of
// candidate strikes (Billiards/SimulateShots).
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <grpcpp/grpcpp.h>

#include "absl/flags/declare.h"
#include "absl/flags/flag.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_format.h"
#include "absl/strings/ascii.h"
#include "absl/strings/str_split.h"
#include "client/billiards_flags.h"
#include "client/cli.h"
#include "client/command_flags.h"
#include "client/table_svg.h"
#include "sportsim/v1/billiards.grpc.pb.h"

// Shared with the swing and flight commands.
ABSL_DECLARE_FLAG(std::string, integrator);
ABSL_DECLARE_FLAG(std::optional<double>, dt);
ABSL_DECLARE_FLAG(std::vector<std::string>, disable);
ABSL_DECLARE_FLAG(std::optional<double>, ball_speed);

ABSL_FLAG(std::string, table, "pool-9ft", "Table preset: pool-7ft|pool-8ft|pool-9ft|snooker|carom|unbounded");
ABSL_FLAG(std::string, rack, "", "Rack: empty|8ball|9ball|snooker|three-cushion|chapter19 (default: the preset's game)");
ABSL_FLAG(double, jitter, 0.0, "Seeded random gaps between racked balls, up to this (m)");
ABSL_FLAG(uint64_t, rack_seed, 0, "Seed of the rack jitter");
ABSL_FLAG(std::optional<double>, speed, std::nullopt, "Cue speed V0 (m/s)");
ABSL_FLAG(double, phi, 0.0, "Heading (deg), counter-clockwise from +x");
ABSL_FLAG(double, theta, 0.0, "Cue elevation (deg)");
ABSL_FLAG(double, a, 0.0, "Side offset of the tip, fraction of R (> 0: right of centre)");
ABSL_FLAG(double, b, 0.0, "Vertical offset of the tip, fraction of R (> 0: above centre)");
ABSL_FLAG(double, noise, 0.0, "Strike noise (1 = FastFiz's sigmas)");
ABSL_FLAG(uint64_t, seed, 0, "Seed of the strike noise");
ABSL_FLAG(std::string, strike_ball, "cue", "Ball the cue strikes");
ABSL_FLAG(std::string, engine, "", "Billiards engine: event|stepped (default: the server's)");
ABSL_FLAG(bool, no_ccd, false, "Stepped engine without continuous collision detection");
ABSL_FLAG(std::vector<std::string>, enable, {}, "Effects off by default to switch on: drag");
ABSL_FLAG(std::string, cushion_model, "", "Cushion model: han|mathavan2010|stronge|mirror");
ABSL_FLAG(std::string, ball_ball_model, "", "Ball-ball model: alciatore|mathavan2014");
ABSL_FLAG(std::string, param_file, "",
          "Model parameters from a JSON file: an object of NAME: VALUE, or a `table calibrate "
          "--format json` report (its params); --param flags override it");
ABSL_FLAG(std::optional<double>, sample_rate, std::nullopt, "Trajectory samples per second");
ABSL_FLAG(std::optional<double>, max_time, std::nullopt, "Stop after this much simulated time (s)");
ABSL_FLAG(int, samples, 1, "shot batch: noise samples of each strike, [1, 1000]");
ABSL_FLAG(std::string, outcome, "summary", "shot batch: what each outcome carries: summary|final|events");
ABSL_FLAG(std::string, svg, "", "Write a picture to this SVG file (shots, tables: top view; swings: stroboscopic side view)");

namespace sportsim::cli {
namespace {

// --param-file FILE: a JSON object of parameters (NAME: number), or a calibration report
// (`table calibrate --format json`) whose "params" object holds them.
std::optional<std::string> ParamsFromFile(const std::string& path,
                                          google::protobuf::Map<std::string, double>* out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "--param-file: cannot read '" + path + "'";
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  google::protobuf::Struct doc;
  if (!google::protobuf::util::JsonStringToMessage(text, &doc).ok()) {
    return "--param-file: " + path + ": not a JSON object";
  }
  const google::protobuf::Struct* params = &doc;
  const google::protobuf::Struct none;
  const bool report = doc.fields().contains("params") || doc.fields().contains("shots");
  if (const auto it = doc.fields().find("params"); it != doc.fields().end()) {
    if (!it->second.has_struct_value()) {
      return "--param-file: " + path + ": \"params\" must be an object of NAME: VALUE";
    }
    params = &it->second.struct_value();
  } else if (report) {
    params = &none;  // a report printed without its empty params
  }
  // In name order, so that the first bad one named is the same every time.
  const std::map<std::string, google::protobuf::Value> sorted(params->fields().begin(),
                                                               params->fields().end());
  if (sorted.empty()) {
    return "--param-file: " + path +
           (report ? ": a calibration report that moved no parameters" : ": no parameters");
  }
  for (const auto& [name, value] : sorted) {
    if (!value.has_number_value()) {
      return "--param-file: " + path + ": \"" + name.substr(0, 32) + "\" must be a number";
    }
    (*out)[name] = value.number_value();
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> BuildSetup(v1::TableSetup* t) {
  if (FlagGiven("table") && absl::GetFlag(FLAGS_table).empty()) {
    return "--table: needs a preset: pool-7ft, pool-8ft, pool-9ft, snooker, carom or unbounded";
  }
  if (FlagGiven("rack") && absl::GetFlag(FLAGS_rack).empty()) {
    return "--rack: needs a rack: empty, 8ball, 9ball, 10ball, snooker, three-cushion or chapter19";
  }
  t->set_preset(absl::GetFlag(FLAGS_table));
  t->set_rack(absl::GetFlag(FLAGS_rack));
  t->set_rack_jitter_m(absl::GetFlag(FLAGS_jitter));
  t->set_rack_seed(absl::GetFlag(FLAGS_rack_seed));
  for (const std::string& spec : RepeatedFlagValues("ball")) {
    // ID@X,Y
    const size_t at = spec.find('@');
    std::vector<std::string> xy;
    if (at != std::string::npos) xy = absl::StrSplit(spec.substr(at + 1), ',');
    double x = 0, y = 0;
    if (at == std::string::npos || at == 0 || xy.size() != 2 || !absl::SimpleAtod(xy[0], &x) ||
        !absl::SimpleAtod(xy[1], &y)) {
      return "--ball must be ID@X,Y (metres), got '" + spec + "'";
    }
    const std::string id = spec.substr(0, at);
    for (const v1::BallPlacement& earlier : t->balls()) {
      if (earlier.id() == id) return "--ball: " + id + " given twice";
    }
    v1::BallPlacement* b = t->add_balls();
    b->set_id(spec.substr(0, at));
    b->set_x_m(x);
    b->set_y_m(y);
  }
  if (const std::string path = absl::GetFlag(FLAGS_param_file); !path.empty()) {
    if (auto bad = ParamsFromFile(path, t->mutable_params())) return *bad;
  }
  for (const std::string& spec : RepeatedFlagValues("param")) {
    const size_t eq = spec.find('=');
    double v = 0;
    if (eq == std::string::npos || eq == 0 || !absl::SimpleAtod(spec.substr(eq + 1), &v)) {
      return "--param must be NAME=VALUE, got '" + spec + "'";
    }
    (*t->mutable_params())[spec.substr(0, eq)] = v;
  }
  const std::string cm = absl::GetFlag(FLAGS_cushion_model);
  if (cm == "mirror") t->set_cushion_model(v1::CUSHION_MODEL_MIRROR);
  else if (cm == "han") t->set_cushion_model(v1::CUSHION_MODEL_HAN);
  else if (cm == "mathavan2010") t->set_cushion_model(v1::CUSHION_MODEL_MATHAVAN_2010);
  else if (cm == "stronge") t->set_cushion_model(v1::CUSHION_MODEL_STRONGE_COMPLIANT);
  else if (!cm.empty()) {
    return "--cushion-model must be han, mathavan2010, stronge or mirror, got '" + cm + "'";
  }
  const std::string bm = absl::GetFlag(FLAGS_ball_ball_model);
  if (bm == "alciatore") t->set_ball_ball_model(v1::BALL_BALL_MODEL_ALCIATORE);
  else if (bm == "mathavan2014") t->set_ball_ball_model(v1::BALL_BALL_MODEL_MATHAVAN_2014);
  else if (!bm.empty()) {
    return "--ball-ball-model must be alciatore or mathavan2014, got '" + bm + "'";
  }
  return std::nullopt;
}

std::optional<std::string> BuildSolver(v1::SolverConfig* s) {
  const std::string engine = absl::GetFlag(FLAGS_engine);
  if (engine == "stepped") s->set_engine(v1::ENGINE_STEPPED);
  else if (engine == "event") s->set_engine(v1::ENGINE_EVENT);
  else if (!engine.empty()) return "--engine must be event or stepped, got '" + engine + "'";
  // The step settings mean something to the stepped engine only: asked or chosen by the
  // server because drag is on (the event engine has no closed form with drag).
  const std::vector<std::string> enabled = absl::GetFlag(FLAGS_enable);
  const bool drag = std::find(enabled.begin(), enabled.end(), "drag") != enabled.end();
  // Without --engine, a step setting asks for the stepped engine: it is the only one they
  // mean something to. With --engine event they contradict it.
  bool step_settings = false;
  for (const char* flag : {"integrator", "dt", "no_ccd"}) step_settings |= FlagGiven(flag);
  if (engine.empty() && step_settings) s->set_engine(v1::ENGINE_STEPPED);
  const bool stepped = engine == "stepped" || (engine.empty() && (drag || step_settings));
  for (const char* flag : {"integrator", "dt", "no_ccd"}) {
    if (FlagGiven(flag) && !stepped) {
      return Dashed(flag) + ": applies to the stepped engine only (--engine " + engine +
             "; leave --engine out or give --engine stepped)";
    }
  }
  const std::string integ = absl::GetFlag(FLAGS_integrator);
  if (integ == "rk4") s->set_integrator(v1::BILLIARDS_INTEGRATOR_RK4);
  else if (integ == "euler") s->set_integrator(v1::BILLIARDS_INTEGRATOR_EULER);
  else if (integ == "semi_implicit_euler") s->set_integrator(v1::BILLIARDS_INTEGRATOR_SEMI_IMPLICIT_EULER);
  else return "--integrator for billiards must be euler, semi_implicit_euler or rk4, got '" + integ + "'";
  if (auto dt = absl::GetFlag(FLAGS_dt)) s->set_dt_s(*dt);
  s->set_no_ccd(absl::GetFlag(FLAGS_no_ccd));
  for (const std::string& e : absl::GetFlag(FLAGS_disable)) s->add_disable(e);
  for (const std::string& e : absl::GetFlag(FLAGS_enable)) s->add_enable(e);
  return std::nullopt;
}

std::optional<std::string> BuildStrike(v1::CueStrike* c) {
  const auto speed = absl::GetFlag(FLAGS_speed);
  const auto ball_speed = absl::GetFlag(FLAGS_ball_speed);
  if (speed.has_value() == ball_speed.has_value()) {
    return "give exactly one of --speed (cue speed, m/s) and --ball-speed (m/s)";
  }
  if (speed) c->set_speed_mps(*speed);
  if (ball_speed) c->set_ball_speed_mps(*ball_speed);
  c->set_ball(absl::GetFlag(FLAGS_strike_ball));
  c->set_phi_deg(absl::GetFlag(FLAGS_phi));
  c->set_theta_deg(absl::GetFlag(FLAGS_theta));
  c->set_a(absl::GetFlag(FLAGS_a));
  c->set_b(absl::GetFlag(FLAGS_b));
  c->set_noise(absl::GetFlag(FLAGS_noise));
  c->set_seed(absl::GetFlag(FLAGS_seed));
  return std::nullopt;
}

namespace {

int CountKind(const v1::SimulateShotResponse& r, v1::EventKind k) {
  int n = 0;
  for (const v1::TableEvent& e : r.events()) n += e.kind() == k;
  return n;
}

void PrintText(const v1::SimulateShotResponse& r) {
  const std::string scheme =
      r.integrator().empty() ? "" : absl::StrFormat(", %s, dt %g s", r.integrator(), r.dt_s());
  std::printf("%s after %.3f s; %d ball-ball, %d cushion, %d pocket events (%d in all); "
              "%s engine%s; %.3f ms CPU\n",
              r.at_rest() ? "at rest" : "still moving", r.t_rest_s(),
              CountKind(r, v1::ball_ball), CountKind(r, v1::ball_cushion),
              CountKind(r, v1::ball_pocket), r.events_size(), r.engine().c_str(), scheme.c_str(),
              r.cpu_s() * 1e3);
  if (r.has_strike()) {
    std::printf("strike: cue %.3f m/s -> ball %.3f m/s, phi %.2f deg, theta %.2f deg, a %.3f, "
                "b %.3f, squirt %.2f deg\n",
                r.strike().cue_speed_mps(), r.strike().ball_speed_mps(), r.strike().phi_deg(),
                r.strike().theta_deg(), r.strike().a(), r.strike().b(), r.strike().squirt_deg());
  }
  std::printf("%-8s %9s %9s  %s\n", "ball", "x_m", "y_m", "state");
  for (const v1::BallState& b : r.balls()) {
    std::printf("%-8s %9.4f %9.4f  %s%s%s\n", b.id().c_str(), b.x_m(), b.y_m(),
                v1::MotionState_Name(b.state()).c_str(), b.pocket().empty() ? "" : " in ",
                b.pocket().c_str());
  }
  int shown = 0;
  for (const v1::TableEvent& e : r.events()) {
    if (e.kind() == v1::transition) continue;
    if (++shown > 40) {
      std::printf("... (--format json lists every event)\n");
      break;
    }
    std::string who;
    for (const std::string& id : e.balls()) who += (who.empty() ? "" : "-") + id;
    std::printf("%10.6f s  %-12s %-10s %s\n", e.t_s(), v1::EventKind_Name(e.kind()).c_str(),
                who.c_str(), e.has_cushion() ? e.cushion().c_str() : e.pocket().c_str());
  }
}

void PrintCsv(const v1::SimulateShotResponse& r) {
  std::cout << "t_s,id,x_m,y_m,state\n";
  for (const v1::ShotSample& s : r.samples()) {
    for (int i = 0; i < s.x_m_size(); ++i) {
      std::cout << Num(s.t_s()) << ',' << r.balls(i).id() << ',' << Num(s.x_m(i)) << ','
                << Num(s.y_m(i)) << ',' << v1::MotionState_Name(s.state(i)) << '\n';
    }
  }
}

int RunSimulate(const Context& ctx, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("shot simulate takes flags only, got '" + args[0] + "'");
  v1::SimulateShotRequest request;
  if (auto bad = BuildSetup(request.mutable_table())) return UsageError(*bad);
  if (auto bad = BuildSolver(request.mutable_solver())) return UsageError(*bad);
  if (auto bad = BuildStrike(request.mutable_strike())) return UsageError(*bad);
  // An empty rack holds only the balls --ball puts there: without the struck one there is
  // nothing to strike (the server would say so in its own field names).
  if (request.table().rack() == "empty") {
    const std::string& struck = request.strike().ball();
    bool placed = false;
    for (const v1::BallPlacement& b : request.table().balls()) placed |= b.id() == struck;
    if (!placed) {
      return UsageError(InvalidValue("--rack empty: no " + struck +
                                      " ball to strike: place it with --ball " + struck + "@X,Y"));
    }
  }
  const std::string svg = absl::GetFlag(FLAGS_svg);
  // Drawings and CSV need a trajectory: 240 samples/s unless told otherwise.
  const bool want_samples = !svg.empty() || ctx.format == Format::kCsv;
  if (auto rate = absl::GetFlag(FLAGS_sample_rate)) request.set_sample_rate_hz(*rate);
  else if (want_samples) request.set_sample_rate_hz(240);
  if (auto t = absl::GetFlag(FLAGS_max_time)) {
    if (!(*t > 0 && *t <= 3600)) return UsageError(InvalidValue("--max-time: must be in (0, 3600] s, got " + Num(*t)));
    request.set_max_time_s(*t);
  }
  request.set_include_geometry(!svg.empty());

  auto stub = v1::Billiards::NewStub(ctx.channel);
  v1::SimulateShotResponse response;
  const grpc::Status status = stub->SimulateShot(ctx.NewCall().get(), request, &response);
  if (!status.ok()) return ReportRpcError(status);
  if (!svg.empty()) {
    TableDrawing drawing{.geometry = response.geometry(), .paths = PathsFromShot(response)};
    drawing.events.assign(response.events().begin(), response.events().end());
    drawing.title = absl::StrFormat(
        "%s, %s: %s after %.2f s (%d ball-ball, %d cushion, %d pocketed)",
        absl::GetFlag(FLAGS_table), request.table().rack().empty() ? "default rack" : request.table().rack(),
        response.at_rest() ? "at rest" : "still moving", response.t_rest_s(),
        CountKind(response, v1::ball_ball), CountKind(response, v1::ball_cushion),
        CountKind(response, v1::ball_pocket));
    std::ofstream out(svg);
    out << TableSvg(drawing);
    if (!out) return UsageError("cannot write --svg file '" + svg + "'");
  }
  return PrintResponse(ctx, response, PrintCsv, PrintText);
}


// `shot batch`: candidate strikes from stdin, one CueStrike as JSON a line (protobuf's JSON
// mapping of CueStrike: ball, speed_mps | ball_speed_mps, phi_deg, theta_deg, a, b; the
// lowerCamel spellings too); blank lines and lines starting with '#' skipped. A line that does
// not parse is a usage error naming it.
constexpr int kMaxStdinStrikes = 1'000'000;
std::optional<std::string> ReadStrikes(std::istream& in, std::vector<v1::CueStrike>* strikes) {
  std::string line;
  int line_number = 0;
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  while (std::getline(in, line)) {
    ++line_number;
    const absl::string_view text = absl::StripAsciiWhitespace(line);
    if (text.empty() || text[0] == '#') continue;
    if (strikes->size() >= kMaxStdinStrikes) {
      return absl::StrFormat("stdin: at most %d strikes (line %d is one more)", kMaxStdinStrikes,
                             line_number);
    }
    v1::CueStrike strike;
    const auto parsed =
        google::protobuf::util::JsonStringToMessage(std::string(text), &strike, options);
    if (!parsed.ok() || text[0] != '{') {
      return absl::StrFormat(
          "stdin line %d must be a CueStrike as JSON, e.g. {\"ball_speed_mps\": 2, "
          "\"phi_deg\": 10} (keys ball, speed_mps or ball_speed_mps, phi_deg, theta_deg, a, b): "
          "%s",
          line_number, parsed.ok() ? "not an object" : std::string(parsed.message()));
    }
    if (strike.speed_case() == v1::CueStrike::SPEED_NOT_SET) {
      return absl::StrFormat("stdin line %d: give speed_mps (cue speed) or ball_speed_mps",
                             line_number);
    }
    if (strike.noise() != 0 || strike.seed() != 0) {
      return absl::StrFormat(
          "stdin line %d: noise and seed are the batch's (--noise, --seed), not a strike's",
          line_number);
    }
    strikes->push_back(std::move(strike));
  }
  if (strikes->empty()) {
    return "shot batch reads its strikes from stdin, one JSON object a line (none given)";
  }
  return std::nullopt;
}

// One request carries at most this many bytes of strikes (the server's --max_request_bytes is
// 64 KiB by default, and the table's setup rides along), this many strikes, and this many
// outcomes (the server's per-request limits): a longer batch goes as consecutive requests
// numbered by first_index, which give the outcomes, indices and noise seeds one request would.
constexpr size_t kChunkStrikeBytes = 32 * 1024;
constexpr int kChunkStrikes = 10000;
constexpr int64_t kChunkOutcomes = 100000;

int RunBatch(const Context& ctx, const std::vector<std::string>& args) {
  if (!args.empty()) return UsageError("shot batch takes flags only (strikes on stdin), got '" + args[0] + "'");
  v1::SimulateShotsRequest request;
  if (auto bad = BuildSetup(request.mutable_table())) return UsageError(*bad);
  if (auto bad = BuildSolver(request.mutable_solver())) return UsageError(*bad);
  const int samples = absl::GetFlag(FLAGS_samples);
  if (samples < 1 || samples > 1000) {
    return UsageError(InvalidValue(absl::StrFormat("--samples: must be in [1, 1000], got %d", samples)));
  }
  request.set_samples_per_strike(static_cast<uint32_t>(samples));
  const double noise = absl::GetFlag(FLAGS_noise);
  if (!(noise >= 0 && noise <= 100)) return UsageError(InvalidValue("--noise: must be in [0, 100], got " + Num(noise)));
  request.set_noise(noise);
  request.set_seed(absl::GetFlag(FLAGS_seed));
  const std::string outcome = absl::GetFlag(FLAGS_outcome);
  if (outcome == "summary") request.set_outcome(v1::SHOT_OUTCOME_SUMMARY);
  else if (outcome == "final") request.set_outcome(v1::SHOT_OUTCOME_FINAL);
  else if (outcome == "events") request.set_outcome(v1::SHOT_OUTCOME_EVENTS);
  else return UsageError("--outcome must be summary, final or events, got '" + outcome + "'");
  if (auto t = absl::GetFlag(FLAGS_max_time)) {
    if (!(*t > 0 && *t <= 3600)) return UsageError(InvalidValue("--max-time: must be in (0, 3600] s, got " + Num(*t)));
    request.set_max_time_s(*t);
  }
  std::vector<v1::CueStrike> strikes;
  if (auto bad = ReadStrikes(std::cin, &strikes)) return UsageError(*bad);

  auto stub = v1::Billiards::NewStub(ctx.channel);
  // jsonl (and the default): one outcome a line as they come; json: one document at the end.
  const bool document = ctx.format == Format::kJson;
  v1::SimulateShotsResponse all;
  v1::SimulateShotsResponse response;
  const int64_t per_chunk = std::min<int64_t>(kChunkStrikes, kChunkOutcomes / samples);
  for (size_t first = 0; first < strikes.size();) {
    request.clear_strikes();
    request.set_first_index(static_cast<uint32_t>(first));
    size_t bytes = 0;
    size_t next = first;
    while (next < strikes.size() && request.strikes_size() < per_chunk) {
      const size_t size = strikes[next].ByteSizeLong() + 4;  // + the field's tag and length
      if (request.strikes_size() > 0 && bytes + size > kChunkStrikeBytes) break;
      bytes += size;
      *request.add_strikes() = std::move(strikes[next++]);  // each strike is sent once
    }
    std::unique_ptr<grpc::ClientContext> call = ctx.NewCall();
    std::unique_ptr<grpc::ClientReader<v1::SimulateShotsResponse>> reader =
        stub->SimulateShots(call.get(), request);
    while (reader->Read(&response)) {
      for (v1::ShotOutcome& o : *response.mutable_outcomes()) {
        if (document) {
          *all.add_outcomes() = std::move(o);
        } else {
          std::cout << ToJson(o, true) << "\n";
        }
      }
      if (!document) std::cout.flush();
    }
    const grpc::Status status = reader->Finish();
    if (!status.ok()) return ReportRpcError(status);
    first = next;
  }
  if (document) std::cout << ToJson(all, false) << "\n";
  return 0;
}

}  // namespace

int RunShot(const Context& ctx, const std::vector<std::string>& args) {
  if (args.empty()) return UsageError("shot needs a subcommand: simulate or batch");
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (args[0] == "simulate") return RunSimulate(ctx, rest);
  if (args[0] == "batch") return RunBatch(ctx, rest);
  return UsageError("unknown shot subcommand '" + args[0] + "' (simulate, batch)");
}

}  // namespace sportsim::cli
