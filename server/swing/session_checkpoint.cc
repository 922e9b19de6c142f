#include "server/swing/session_checkpoint.h"

#include <optional>
#include <utility>

#include "absl/strings/str_format.h"
#include "server/world/checkpoint_codec.h"
#include "sportsim/store/v1/session_state.pb.h"

namespace sportsim::server {

namespace sw = ::sportsim::swing;
namespace st = ::sportsim::store::v1;

namespace {

using checkpoint::Differ;
using checkpoint::Member;

// Every error message starts with this and names the field by its path in SessionRestState.
constexpr std::string_view kWhat = "session checkpoint: ";

absl::Status Corrupt(std::string_view path, std::string_view what) {
  return checkpoint::Corrupt(kWhat, path, what);
}

// The stored numbers are session_state.proto's, mapped value by value (no default case, so that
// -Wswitch names a value added to SessionPhase and not mapped here). A value outside the enum
// is written as -1, which no reader accepts.
st::SessionRestState::Phase PhaseToProto(SessionPhase p) {
  switch (p) {
    case SessionPhase::kAddress: return st::SessionRestState::PHASE_ADDRESS;
    case SessionPhase::kSwinging: return st::SessionRestState::PHASE_SWINGING;
    case SessionPhase::kFinished: return st::SessionRestState::PHASE_FINISHED;
  }
  return static_cast<st::SessionRestState::Phase>(-1);
}

absl::StatusOr<SessionPhase> PhaseFromProto(int v) {
  switch (v) {
    case st::SessionRestState::PHASE_ADDRESS: return SessionPhase::kAddress;
    case st::SessionRestState::PHASE_SWINGING: return SessionPhase::kSwinging;
    case st::SessionRestState::PHASE_FINISHED: return SessionPhase::kFinished;
    default: return Corrupt("phase", absl::StrFormat("unknown phase %d", v));
  }
}

void SampleToStore(const sw::SwingSample& s, st::SwingSample* out) {
  out->set_t_s(s.t_s);
  out->set_alpha(s.alpha);
  out->set_beta(s.beta);
  out->set_theta(s.theta);
  out->set_phi(s.phi);
  out->set_alpha_dot(s.alpha_dot);
  out->set_beta_dot(s.beta_dot);
  out->set_clubhead_speed_mps(s.clubhead_speed_mps);
  out->set_clubhead_speed_ground_mps(s.clubhead_speed_ground_mps);
  out->set_clubhead_x_m(s.clubhead_x_m);
  out->set_clubhead_y_m(s.clubhead_y_m);
  out->set_clubhead_vx_mps(s.clubhead_vx_mps);
  out->set_clubhead_vy_mps(s.clubhead_vy_mps);
  out->set_clubhead_vx_ground_mps(s.clubhead_vx_ground_mps);
  out->set_clubhead_vy_ground_mps(s.clubhead_vy_ground_mps);
}

sw::SwingSample SampleFromStore(const st::SwingSample& in) {
  return sw::SwingSample{.t_s = in.t_s(),
                         .alpha = in.alpha(),
                         .beta = in.beta(),
                         .theta = in.theta(),
                         .phi = in.phi(),
                         .alpha_dot = in.alpha_dot(),
                         .beta_dot = in.beta_dot(),
                         .clubhead_speed_mps = in.clubhead_speed_mps(),
                         .clubhead_speed_ground_mps = in.clubhead_speed_ground_mps(),
                         .clubhead_x_m = in.clubhead_x_m(),
                         .clubhead_y_m = in.clubhead_y_m(),
                         .clubhead_vx_mps = in.clubhead_vx_mps(),
                         .clubhead_vy_mps = in.clubhead_vy_mps(),
                         .clubhead_vx_ground_mps = in.clubhead_vx_ground_mps(),
                         .clubhead_vy_ground_mps = in.clubhead_vy_ground_mps()};
}

void DiffSample(Differ& d, const std::string& p, const sw::SwingSample& a,
                const sw::SwingSample& b) {
  d.Bits(Member(p, "t_s"), a.t_s, b.t_s);
  d.Bits(Member(p, "alpha"), a.alpha, b.alpha);
  d.Bits(Member(p, "beta"), a.beta, b.beta);
  d.Bits(Member(p, "theta"), a.theta, b.theta);
  d.Bits(Member(p, "phi"), a.phi, b.phi);
  d.Bits(Member(p, "alpha_dot"), a.alpha_dot, b.alpha_dot);
  d.Bits(Member(p, "beta_dot"), a.beta_dot, b.beta_dot);
  d.Bits(Member(p, "clubhead_speed_mps"), a.clubhead_speed_mps, b.clubhead_speed_mps);
  d.Bits(Member(p, "clubhead_speed_ground_mps"), a.clubhead_speed_ground_mps,
         b.clubhead_speed_ground_mps);
  d.Bits(Member(p, "clubhead_x_m"), a.clubhead_x_m, b.clubhead_x_m);
  d.Bits(Member(p, "clubhead_y_m"), a.clubhead_y_m, b.clubhead_y_m);
  d.Bits(Member(p, "clubhead_vx_mps"), a.clubhead_vx_mps, b.clubhead_vx_mps);
  d.Bits(Member(p, "clubhead_vy_mps"), a.clubhead_vy_mps, b.clubhead_vy_mps);
  d.Bits(Member(p, "clubhead_vx_ground_mps"), a.clubhead_vx_ground_mps, b.clubhead_vx_ground_mps);
  d.Bits(Member(p, "clubhead_vy_ground_mps"), a.clubhead_vy_ground_mps, b.clubhead_vy_ground_mps);
}

}  // namespace

std::string EncodeSessionRestState(const SessionRestState& state) {
  st::SessionRestState out;
  out.set_version(kSessionCheckpointVersion);
  out.set_tick(state.tick);
  out.set_sequence(state.sequence);
  out.set_params(state.params.SerializeAsString());
  out.set_phase(PhaseToProto(state.phase));
  out.set_swings(state.swings);
  out.set_start_tick(state.start_tick);
  out.set_seat(state.seat);
  SampleToStore(state.state, out.mutable_state());
  out.set_qalpha_nm(state.qalpha);
  out.set_qbeta_nm(state.qbeta);
  if (state.last_impact.has_value()) SampleToStore(*state.last_impact, out.mutable_last_impact());
  out.set_last_end_reason(state.last_end_reason);
  return checkpoint::Seal(out);
}

absl::StatusOr<SessionRestState> DecodeSessionRestState(std::string_view bytes) {
  st::SessionRestState in;
  if (absl::Status s = checkpoint::Open(bytes, kWhat, kSessionCheckpointVersion, &in); !s.ok()) {
    return s;
  }
  SessionRestState out;
  out.tick = in.tick();
  out.sequence = in.sequence();
  if (!out.params.ParseFromString(in.params())) {
    return Corrupt("params", "not a sportsim.v1.SwingParameters message");
  }
  if (absl::Status s = checkpoint::CheckNoUnknownFields(out.params, kWhat, "params"); !s.ok()) {
    return s;
  }
  absl::StatusOr<SessionPhase> phase = PhaseFromProto(in.phase());
  if (!phase.ok()) return phase.status();
  out.phase = *phase;
  out.swings = in.swings();
  out.start_tick = in.start_tick();
  out.seat = in.seat();
  if (!in.has_state()) return Corrupt("state", "missing");
  out.state = SampleFromStore(in.state());
  out.qalpha = in.qalpha_nm();
  out.qbeta = in.qbeta_nm();
  if (in.has_last_impact()) out.last_impact = SampleFromStore(in.last_impact());
  out.last_end_reason = in.last_end_reason();
  return out;
}

std::string SessionRestStateDifference(const SessionRestState& a, const SessionRestState& b) {
  Differ d;
  d.Same("tick", a.tick, b.tick);
  d.Same("sequence", a.sequence, b.sequence);
  d.Same("params", a.params, b.params);
  d.Same("phase", a.phase, b.phase);
  d.Same("swings", a.swings, b.swings);
  d.Same("start_tick", a.start_tick, b.start_tick);
  d.Same("seat", a.seat, b.seat);
  DiffSample(d, "state", a.state, b.state);
  d.Bits("qalpha", a.qalpha, b.qalpha);
  d.Bits("qbeta", a.qbeta, b.qbeta);
  if (d.Presence("last_impact", a.last_impact, b.last_impact)) {
    DiffSample(d, "last_impact", *a.last_impact, *b.last_impact);
  }
  d.Same("last_end_reason", a.last_end_reason, b.last_end_reason);
  return d.first();
}

bool SameSessionRestState(const SessionRestState& a, const SessionRestState& b) {
  return SessionRestStateDifference(a, b).empty();
}

}  // namespace sportsim::server
