// The session checkpoint (server/swing/session_checkpoint.h): a swing session at rest encoded
// and decoded bit for bit, and restores that start from it.
//
// 1. Real states: the checkpoints a live session writes to its journal after real swings
//    (scheduled and driven, a ball launched at each impact, a reset that changed the golfer)
//    decode to what the session reported at that swing's end and encode back to the same bytes.
// 2. Adversarial values: -0.0, denormals, NaNs with payloads, infinities, extreme integers, long
//    and binary strings, every phase, optionals and the parameters' fields present and absent.
// 3. Damaged bytes: every prefix, every flipped bit, other versions, unknown fields and enum
//    values, a missing state, parameters that do not parse: an error naming what is wrong, and a
//    restore from such a checkpoint fails with DATA_LOSS.
// 4. Restores: a session restored from its latest checkpoint and the entries after it, and one
//    restored from its whole journal, end the next swing bit-identical to the session that ran
//    uninterrupted (state, sequence numbers, events), and write the same checkpoint after it.
//
// The field counts of the stored types and of a live session's members are checked at compile
// time: a member added to one of them fails this test's build until the checkpoint stores it
// (or session_checkpoint.h says why it need not).
#include "server/swing/session_checkpoint.h"

#include <google/protobuf/util/message_differencer.h>

#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "server/swing/convert.h"
#include "server/world/checkpoint_codec.h"
#include "server/world/journal.h"
#include "sportsim/store/v1/session_state.pb.h"
#include "tests/server/fake_sink.h"
#include "tests/server/checkpoint_testing.h"

namespace sportsim::server {
namespace {

namespace sw = ::sportsim::swing;
namespace st = ::sportsim::store::v1;
using ::google::protobuf::util::MessageDifferencer;
using ::testing::HasSubstr;

using FakeSink = FakeSinkFor<SwingWatcher>;

static_assert(CountFields<sw::SwingSample>() == 15, "SwingSample changed: update the checkpoint");
static_assert(CountFields<SessionRestState>() == 12,
              "SessionRestState changed: update the checkpoint");
// Every member of a live session, stored or derived (session_checkpoint.h).
static_assert(CountFields<SessionKind::Data>() == 18,
              "SessionKind::Data changed: store the new member in the checkpoint, or say in "
              "session_checkpoint.h why it need not be");

// ---------------------------------------------------------------------------------------------
// Helpers.

/// Encodes, decodes and compares bit for bit; the decoded state encodes to the same bytes.
void ExpectRoundTrip(const SessionRestState& s, const std::string& what) {
  const std::string bytes = EncodeSessionRestState(s);
  absl::StatusOr<SessionRestState> back = DecodeSessionRestState(bytes);
  ASSERT_TRUE(back.ok()) << what << ": " << back.status();
  EXPECT_TRUE(SameSessionRestState(s, *back)) << what << ": "
                                              << SessionRestStateDifference(s, *back);
  EXPECT_EQ(EncodeSessionRestState(*back), bytes) << what;
}

/// A store's journal, in memory: every entry, and every checkpoint in the order written.
class MemoryJournal final : public Journal {
 public:
  struct Written {
    uint64_t index = 0;
    int64_t tick = 0;
    std::string state;
  };

  absl::Status Append(JournalEntry entry) override {
    absl::MutexLock lock(&mu_);
    entries_.push_back(std::move(entry));
    return absl::OkStatus();
  }
  absl::Status Remove(JournalEntry deletion) override { return Append(std::move(deletion)); }
  void Checkpoint(const std::string& world_id, uint64_t index, int64_t tick,
                  std::string state) override {
    absl::MutexLock lock(&mu_);
    checkpoints_[world_id].push_back(
        Written{.index = index, .tick = tick, .state = std::move(state)});
  }
  void Anchor(const std::string&, int64_t, double) override {}
  double NodeSeconds() const override { return 0.0; }
  absl::Status Healthy() const override { return absl::OkStatus(); }

  std::vector<Written> checkpoints(const std::string& id) const {
    absl::MutexLock lock(&mu_);
    auto it = checkpoints_.find(id);
    return it == checkpoints_.end() ? std::vector<Written>() : it->second;
  }
  std::vector<JournalEntry> entries(const std::string& id) const {
    absl::MutexLock lock(&mu_);
    std::vector<JournalEntry> out;
    for (const JournalEntry& e : entries_) {
      if (e.world_id == id) out.push_back(e);
    }
    return out;
  }
  /// The world as a store hands it to a restore: from `checkpoint` (null: none) with the
  /// entries after it and the creation, else every entry; stopped at tick `reached` (the node
  /// clock stands still: anchor_s = clock_s = 0).
  StoredWorld Stored(const std::string& id, const Written* checkpoint, int64_t reached) const {
    StoredWorld w{.world_id = id, .kind = "session"};
    if (checkpoint != nullptr) {
      w.checkpoint_index = checkpoint->index;
      w.checkpoint_tick = checkpoint->tick;
      w.checkpoint = checkpoint->state;
    }
    for (JournalEntry& e : entries(id)) {
      if (e.index == 1 || e.index > w.checkpoint_index) w.entries.push_back(std::move(e));
    }
    w.anchor_tick = reached;
    return w;
  }

 private:
  mutable absl::Mutex mu_;
  std::vector<JournalEntry> entries_ ABSL_GUARDED_BY(mu_);
  std::map<std::string, std::vector<Written>> checkpoints_ ABSL_GUARDED_BY(mu_);
};

SteadyClock::duration Seconds(double s) {
  return std::chrono::duration_cast<SteadyClock::duration>(std::chrono::duration<double>(s));
}

// A session's GetSession and first watch snapshot, compared bit for bit (MessageDifferencer
// compares doubles exactly) except for what is a reading of the wall clock or of the process:
// the tick now (a clock reading at rest) and a launched ball's flight CPU time.
bool SameBut(const google::protobuf::Message& a, const google::protobuf::Message& b,
             std::string* report) {
  MessageDifferencer d;
  d.ReportDifferencesToString(report);
  // The top-level tick only: every event's tick is compared.
  if (const auto* tick = a.GetDescriptor()->FindFieldByName("tick"); tick != nullptr) {
    d.IgnoreField(tick);
  }
  d.IgnoreField(
      v1::BallLaunch::descriptor()->FindFieldByName("flight")->message_type()->FindFieldByName(
          "cpu_s"));
  return d.Compare(a, b);
}

// ---------------------------------------------------------------------------------------------
// A session with a history: scheduled and driven swings, a ball launched at each impact, a
// reset that changes the golfer, a swing stopped by its duration.

constexpr uint64_t kEvery = 3;  // swings between checkpoints in these tests

SessionLimits Limits() {
  SessionLimits limits;
  limits.world.clock_rate = 10;  // swings take a tenth of their time
  limits.world.checkpoint_every_runs = kEvery;
  return limits;
}

v1::CreateSessionRequest CreateReq() {
  v1::CreateSessionRequest r;
  r.mutable_parameters()->set_club_length_m(1.05);
  r.mutable_ball()->set_club("7-iron");
  r.mutable_ball()->set_face_angle_deg(1.5);
  return r;
}

class SessionCheckpointTest : public ::testing::Test {
 protected:
  // Declared before the registries so that they outlive them (their streams may write).
  std::deque<std::unique_ptr<FakeSink>> sinks_;
  MemoryJournal journal_;  // the uninterrupted session's

  FakeSink& NewSink() {
    sinks_.push_back(std::make_unique<FakeSink>());
    return *sinks_.back();
  }

  static v1::SessionInfo Info(SessionRegistry& reg, const std::string& id) {
    v1::GetSessionRequest r;
    r.set_session_id(id);
    absl::StatusOr<v1::SessionInfo> info = reg.Get(r);
    EXPECT_TRUE(info.ok()) << info.status();
    return info.ok() ? *info : v1::SessionInfo();
  }

  // Polls until swing `swing` of the session has finished; its GetSession then.
  static v1::SessionInfo WaitFinished(SessionRegistry& reg, const std::string& id,
                                      uint64_t swing) {
    const SteadyClock::time_point until = SteadyClock::now() + Seconds(10);
    for (;;) {
      const v1::SessionInfo info = Info(reg, id);
      if (info.swings() == swing && info.phase() == v1::SWING_PHASE_FINISHED) return info;
      if (SteadyClock::now() > until) {
        ADD_FAILURE() << "swing " << swing << " did not finish: " << info.ShortDebugString();
        return info;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }

  // Swing `k` of the history, on `reg`, to its end (at rest after it).
  void Swing(SessionRegistry& reg, const v1::CreateSessionResponse& s, uint64_t k) {
    const std::string& id = s.session_id();
    if (k == 2) {
      // A new address position: the checkpoints after it hold parameters the creation had not.
      v1::ResetSwingRequest reset;
      reset.set_session_id(id);
      reset.set_token(s.token());
      reset.set_gamma_deg(130);
      ASSERT_TRUE(reg.Reset(reset).ok());
    }
    if (k % kEvery == 1 && k > 1) {
      // Driven: one command for later in the swing (applied at the next tick should it come
      // late), then the driver half-closes; the swing goes on with its queued command to the
      // end of its duration (a tenth of a second of wall time, for the calls to land in it).
      v1::DriveStart start;
      start.set_session_id(id);
      start.set_token(s.token());
      start.set_qalpha_nm(100);
      start.set_qbeta_nm(-10);
      start.set_apply_late(true);
      start.set_stop(v1::SWING_STOP_DURATION);
      start.set_duration_s(1.0);
      FakeSink& sink = NewSink();
      absl::StatusOr<std::shared_ptr<Drive>> drive = reg.StartDrive(start, &sink);
      ASSERT_TRUE(drive.ok()) << drive.status();
      sink.Bind((*drive)->watcher);
      v1::TorqueCommand c;
      c.set_t_s(0.1);
      c.set_qalpha_nm(100);
      c.set_qbeta_nm(static_cast<double>(k) - 5.0);
      reg.Command(**drive, c);
      reg.EndDrive(**drive, /*half_closed=*/true);
    } else {
      v1::StartSwingRequest r;  // the chapter's torques
      r.set_session_id(id);
      r.set_token(s.token());
      if (k == 8) {
        r.set_stop(v1::SWING_STOP_DURATION);
        r.set_duration_s(0.4);
      }
      absl::StatusOr<v1::StartSwingResponse> started = reg.Start(r);
      ASSERT_TRUE(started.ok()) << started.status();
      EXPECT_EQ(started->swing_id(), k);
    }
    WaitFinished(reg, id, k);
  }

  // Creates the session on `reg` (journaled in journal_) and plays swings 1 to n; the
  // GetSession after each swing, by swing (0: before the first).
  std::vector<v1::SessionInfo> Play(SessionRegistry& reg, v1::CreateSessionResponse* s,
                                    uint64_t n) {
    absl::StatusOr<v1::CreateSessionResponse> created = reg.Create(CreateReq());
    EXPECT_TRUE(created.ok()) << created.status();
    if (!created.ok()) return {};
    *s = *created;
    std::vector<v1::SessionInfo> infos = {Info(reg, s->session_id())};
    for (uint64_t k = 1; k <= n && !HasFailure(); ++k) {
      Swing(reg, *s, k);
      infos.push_back(Info(reg, s->session_id()));
    }
    return infos;
  }

  // The first snapshot of a watcher resuming after `from` (its events: every one since).
  v1::SwingSnapshot Resume(SessionRegistry& reg, const std::string& id, uint64_t from) {
    v1::WatchSwingRequest w;
    w.set_session_id(id);
    w.set_from_sequence(from);
    FakeSink& sink = NewSink();
    absl::StatusOr<std::shared_ptr<SwingWatcher>> watcher = reg.Watch(w, &sink);
    EXPECT_TRUE(watcher.ok()) << watcher.status();
    if (!watcher.ok()) return v1::SwingSnapshot();
    sink.Bind(*watcher);  // never completes a write: the first one is all it gets
    (*watcher)->Pump();
    const std::vector<v1::SwingSnapshot> got = sink.got();
    EXPECT_EQ(got.size(), 1u);
    return got.empty() ? v1::SwingSnapshot() : got[0];
  }
};

SessionRestState Decoded(const MemoryJournal::Written& w) {
  absl::StatusOr<SessionRestState> s = DecodeSessionRestState(w.state);
  EXPECT_TRUE(s.ok()) << s.status();
  return s.ok() ? *s : SessionRestState();
}

// ---------------------------------------------------------------------------------------------
// 1. Real states.

// A live session writes a checkpoint at the end of every kEvery-th swing, covering its journal
// so far, and it holds what GetSession reported then, bit for bit (GetSession turns radians into
// degrees; the checkpoint keeps the radians, which give the same degrees).
TEST_F(SessionCheckpointTest, RealCheckpointsHoldTheSessionAtEachCheckpointedSwingsEnd) {
  SessionRegistry reg(Limits(), nullptr, /*workers=*/1);
  reg.SetJournal(&journal_);
  v1::CreateSessionResponse s;
  const std::vector<v1::SessionInfo> infos = Play(reg, &s, 7);
  ASSERT_EQ(infos.size(), 8u);
  const std::vector<MemoryJournal::Written> written = journal_.checkpoints(s.session_id());
  ASSERT_EQ(written.size(), 2u) << "a checkpoint at swings 3 and 6 only";
  const std::vector<JournalEntry> entries = journal_.entries(s.session_id());
  for (size_t c = 0; c < written.size(); ++c) {
    const uint64_t swing = (c + 1) * kEvery;
    const v1::SessionInfo& info = infos[swing];
    SCOPED_TRACE(absl::StrFormat("checkpoint after swing %d", swing));
    const SessionRestState state = Decoded(written[c]);
    ExpectRoundTrip(state, "real");
    std::cout << "checkpoint after swing " << swing << ": " << written[c].state.size()
              << " bytes\n";
    EXPECT_EQ(state.swings, swing);
    EXPECT_EQ(state.phase, SessionPhase::kFinished);
    EXPECT_EQ(state.sequence, info.sequence());
    EXPECT_EQ(state.tick, written[c].tick);
    EXPECT_LE(state.tick, info.tick());  // GetSession's is the clock's, at or after the end
    EXPECT_LT(state.start_tick, state.tick);
    EXPECT_EQ(state.seat, 0u);
    EXPECT_EQ(state.last_end_reason, info.last_end_reason());
    v1::SwingSample sample;
    SampleToProto(state.state, &sample);
    EXPECT_TRUE(MessageDifferencer::Equals(sample, info.state()))
        << sample.ShortDebugString() << "\nvs " << info.state().ShortDebugString();
    ASSERT_TRUE(state.last_impact.has_value());
    v1::SwingImpact impact;
    ImpactToProto(*state.last_impact, &impact);
    EXPECT_TRUE(MessageDifferencer::Equals(impact, info.last_impact()));
    // The creation's parameters and the reset's, with their presence.
    EXPECT_TRUE(state.params.has_club_length_m());
    EXPECT_EQ(state.params.club_length_m(), 1.05);
    EXPECT_TRUE(state.params.has_gamma_deg());
    EXPECT_EQ(state.params.gamma_deg(), 130.0);
    EXPECT_FALSE(state.params.has_beta0_deg());
    EXPECT_EQ(info.gamma_deg(), 130.0);
    // It covers the journal up to the swing's end: the next entry starts the next swing.
    ASSERT_LT(written[c].index, entries.size());
    const JournalEntry& next = entries[written[c].index];  // entries are numbered from 1
    ASSERT_EQ(next.index, written[c].index + 1);
    EXPECT_THAT(static_cast<SessionCommand>(next.type),
                ::testing::AnyOf(SessionCommand::kStart, SessionCommand::kDriveStart));
    EXPECT_GE(next.tick, state.tick);
  }
  // Swing 6 was scheduled after driven swing 4: its torques in force are the chapter's at the
  // end, not the driver's.
  const SessionRestState sixth = Decoded(written[1]);
  EXPECT_EQ(sixth.qalpha, 100.0);
  EXPECT_EQ(sixth.qbeta, 0.0);
  EXPECT_GT(sixth.state.t_s, 0.0);
}

// ---------------------------------------------------------------------------------------------
// 2. Adversarial values.

// A client that resets every swing before it ends never reaches a swing's end at rest; its
// resets are rests too, so it still gets a checkpoint every kEvery swings (else a restore would
// replay its whole history).
TEST_F(SessionCheckpointTest, SwingsEndedByResetsAreCheckpointedToo) {
  SessionRegistry reg(Limits(), nullptr, /*workers=*/1);
  reg.SetJournal(&journal_);
  absl::StatusOr<v1::CreateSessionResponse> s = reg.Create(CreateReq());
  ASSERT_TRUE(s.ok()) << s.status();
  for (uint64_t k = 1; k <= 7; ++k) {
    v1::StartSwingRequest start;
    start.set_session_id(s->session_id());
    start.set_token(s->token());
    ASSERT_TRUE(reg.Start(start).ok());
    EXPECT_EQ(Info(reg, s->session_id()).phase(), v1::SWING_PHASE_SWINGING);
    v1::ResetSwingRequest reset;
    reset.set_session_id(s->session_id());
    reset.set_token(s->token());
    ASSERT_TRUE(reg.Reset(reset).ok());
  }
  const std::vector<MemoryJournal::Written> written = journal_.checkpoints(s->session_id());
  ASSERT_EQ(written.size(), 2u) << "a checkpoint at the resets after swings 3 and 6";
  for (size_t c = 0; c < written.size(); ++c) {
    const SessionRestState state = Decoded(written[c]);
    EXPECT_EQ(state.swings, kEvery * (c + 1));
    EXPECT_EQ(state.phase, SessionPhase::kAddress);
    EXPECT_EQ(state.last_end_reason, "reset");
  }
}

// A session restored from its whole journal has no checkpoint yet, and its runs since then
// are due one: the first call at rest writes it (C, a reset). A deletion is such a call too,
// but nothing of a world is written after its removal (B): a checkpoint there would put a
// world without a creation back in the store.
TEST_F(SessionCheckpointTest, TheFirstCallAfterARestoreCheckpointsButADeletionDoesNot) {
  SessionRegistry a(Limits(), nullptr, /*workers=*/1);
  a.SetJournal(&journal_);
  v1::CreateSessionResponse s;
  ASSERT_EQ(Play(a, &s, 4).size(), 5u);
  const std::string& id = s.session_id();
  const StoredWorld whole = journal_.Stored(id, nullptr, Info(a, id).tick());
  MemoryJournal journal_b, journal_c;
  SessionRegistry b(Limits(), nullptr, /*workers=*/1);
  SessionRegistry c(Limits(), nullptr, /*workers=*/1);
  b.SetJournal(&journal_b);
  c.SetJournal(&journal_c);
  ASSERT_TRUE(b.Restore(whole).ok());
  ASSERT_TRUE(c.Restore(whole).ok());
  v1::ResetSwingRequest reset;
  reset.set_session_id(id);
  reset.set_token(s.token());
  ASSERT_TRUE(c.Reset(reset).ok());
  ASSERT_EQ(journal_c.checkpoints(id).size(), 1u);
  EXPECT_EQ(Decoded(journal_c.checkpoints(id)[0]).swings, 4u);
  v1::DeleteSessionRequest del;
  del.set_session_id(id);
  del.set_token(s.token());
  ASSERT_TRUE(b.Delete(del).ok());
  EXPECT_TRUE(journal_b.checkpoints(id).empty()) << "a checkpoint after the deletion";
}

TEST(SessionCheckpointValuesTest, EveryDoubleIsKeptBitForBit) {
  const std::vector<double> values = {
      0.0, -0.0, 1.0, -1.0, std::numeric_limits<double>::denorm_min(),
      -std::numeric_limits<double>::denorm_min(), std::numeric_limits<double>::min(),
      std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest(),
      std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
      std::numeric_limits<double>::epsilon(), Bits(0x7FF8000000000001ull),
      Bits(0xFFF0000000000ABCull), Bits(0x7FF4000000000000ull), 0.1, M_PI};
  for (double d : values) {
    SessionRestState s;
    s.state = sw::SwingSample{.t_s = d, .alpha = d, .beta = -d, .theta = d, .phi = d,
                              .alpha_dot = d, .beta_dot = d, .clubhead_speed_mps = d,
                              .clubhead_speed_ground_mps = d, .clubhead_x_m = d,
                              .clubhead_y_m = d, .clubhead_vx_mps = d, .clubhead_vy_mps = d,
                              .clubhead_vx_ground_mps = d, .clubhead_vy_ground_mps = -d};
    s.last_impact = s.state;
    s.last_impact->phi = -d;
    s.qalpha = d;
    s.qbeta = -d;
    s.params.set_gamma_deg(d);
    s.params.set_shoulder_accel_mps2(-d);
    const std::string what = absl::StrFormat("double bits %016x", std::bit_cast<uint64_t>(d));
    ExpectRoundTrip(s, what);
    absl::StatusOr<SessionRestState> back = DecodeSessionRestState(EncodeSessionRestState(s));
    ASSERT_TRUE(back.ok());
    EXPECT_EQ(std::bit_cast<uint64_t>(back->state.clubhead_vy_ground_mps),
              std::bit_cast<uint64_t>(-d))
        << what;
    EXPECT_EQ(std::bit_cast<uint64_t>(back->params.shoulder_accel_mps2()),
              std::bit_cast<uint64_t>(-d))
        << what;
  }
  // The comparison itself tells -0.0 from 0.0, NaN payloads, and a parameter set to its
  // default from one left unset.
  SessionRestState a, b;
  b.qbeta = -0.0;
  EXPECT_FALSE(SameSessionRestState(a, b));
  EXPECT_THAT(SessionRestStateDifference(a, b), HasSubstr("qbeta: 0 (bits 0000000000000000)"));
  b = a;
  a.last_impact = sw::SwingSample{.beta = Bits(0x7FF8000000000001ull)};
  b.last_impact = sw::SwingSample{.beta = Bits(0x7FF8000000000002ull)};
  EXPECT_THAT(SessionRestStateDifference(a, b), HasSubstr("last_impact.beta"));
  b.last_impact.reset();
  EXPECT_EQ(SessionRestStateDifference(a, b), "last_impact: present vs absent");
  b = a;
  EXPECT_TRUE(SameSessionRestState(a, b));
  b.params.set_gravity_mps2(0.0);
  EXPECT_EQ(SessionRestStateDifference(a, b), "params: added: gravity_mps2: 0");
  a.params.set_gravity_mps2(-0.0);
  EXPECT_EQ(SessionRestStateDifference(a, b), "params: modified: gravity_mps2: -0 -> 0");
}

TEST(SessionCheckpointValuesTest, IntegersStringsPhasesAndAbsentParametersRoundTrip) {
  SessionRestState s;
  ExpectRoundTrip(s, "defaults");
  s.tick = std::numeric_limits<int64_t>::min();
  s.start_tick = std::numeric_limits<int64_t>::max();
  s.sequence = std::numeric_limits<uint64_t>::max();
  s.swings = std::numeric_limits<uint64_t>::max();
  s.seat = std::numeric_limits<uint32_t>::max();
  s.last_end_reason = std::string("error: \0\xff binary", 16) + std::string(70000, 'x');
  for (SessionPhase p : {SessionPhase::kAddress, SessionPhase::kSwinging,
                         SessionPhase::kFinished}) {
    s.phase = p;
    ExpectRoundTrip(s, absl::StrFormat("phase %d", static_cast<int>(p)));
  }
  const v1::SwingParameters all = [] {
    v1::SwingParameters p;
    const google::protobuf::Descriptor* d = p.GetDescriptor();
    for (int i = 0; i < d->field_count(); ++i) {
      if (d->field(i)->cpp_type() != google::protobuf::FieldDescriptor::CPPTYPE_DOUBLE) continue;
      p.GetReflection()->SetDouble(&p, d->field(i), 0.5 + i);
    }
    return p;
  }();
  s.params = all;
  ExpectRoundTrip(s, "every parameter set");
  absl::StatusOr<SessionRestState> back = DecodeSessionRestState(EncodeSessionRestState(s));
  ASSERT_TRUE(back.ok());
  EXPECT_TRUE(MessageDifferencer::Equals(back->params, all));
  EXPECT_EQ(back->last_end_reason, s.last_end_reason);
  EXPECT_EQ(st::SessionRestState::Phase_ARRAYSIZE, 3);  // one per SessionPhase
}

TEST(SessionCheckpointValuesTest, VersionAndTrailerAreWritten) {
  ExpectVersionAndTrailer<st::SessionRestState>(EncodeSessionRestState(SessionRestState{}),
                                               kSessionCheckpointVersion);
}

// ---------------------------------------------------------------------------------------------
// 3. Damaged bytes.

TEST_F(SessionCheckpointTest, DamagedCheckpointsAreRefusedNamingTheField) {
  SessionRegistry reg(Limits(), nullptr, /*workers=*/1);
  reg.SetJournal(&journal_);
  v1::CreateSessionResponse s;
  Play(reg, &s, kEvery);
  const std::vector<MemoryJournal::Written> written = journal_.checkpoints(s.session_id());
  ASSERT_EQ(written.size(), 1u);
  const std::string bytes = written[0].state;

  ExpectEveryPrefixAndFlipRefused(bytes, DecodeSessionRestState, "session checkpoint: ");
  std::string flipped = bytes;
  flipped[10] = static_cast<char>(flipped[10] ^ 0x40);
  EXPECT_THAT(DecodeSessionRestState(flipped).status().message(),
              HasSubstr("crc32c "));

  // Hand-made damage, sealed with a valid trailer.
  const st::SessionRestState good = Parsed<st::SessionRestState>(bytes);
  ASSERT_TRUE(DecodeSessionRestState(checkpoint::Seal(good)).ok());
  for (uint32_t v : {0u, 2u, 0xFFFFFFFFu}) {
    st::SessionRestState m = good;
    m.set_version(v);
    const absl::Status status = DecodeSessionRestState(checkpoint::Seal(m)).status();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << v << ": " << status;
    EXPECT_THAT(status.message(), HasSubstr(absl::StrFormat("version %d", v)));
  }
  struct Case {
    std::string name;
    std::function<void(st::SessionRestState*)> damage;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"no state", [](st::SessionRestState* m) { m->clear_state(); }, "state: missing"},
      {"phase 3",
       [](st::SessionRestState* m) { m->set_phase(static_cast<st::SessionRestState::Phase>(3)); },
       "phase: unknown phase 3"},
      {"negative phase",
       [](st::SessionRestState* m) { m->set_phase(static_cast<st::SessionRestState::Phase>(-2)); },
       "phase: unknown phase -2"},
      {"params not a message", [](st::SessionRestState* m) { m->set_params("\xff\xff\xff"); },
       "params: not a sportsim.v1.SwingParameters message"},
      {"unknown field in params",
       [](st::SessionRestState* m) {
         v1::SwingParameters p;
         p.GetReflection()->MutableUnknownFields(&p)->AddFixed64(99, 1);
         m->set_params(p.SerializeAsString());
       },
       "params: unknown field 99"},
      {"unknown top field",
       [](st::SessionRestState* m) {
         m->GetReflection()->MutableUnknownFields(m)->AddVarint(14, 5);
       },
       "(top): unknown field 14"},
      {"unknown field in the impact",
       [](st::SessionRestState* m) {
         st::SwingSample* x = m->mutable_last_impact();
         x->GetReflection()->MutableUnknownFields(x)->AddLengthDelimited(16, "x");
       },
       "last_impact: unknown field 16"},
      {"crc32c in the body", [](st::SessionRestState* m) { m->set_crc32c(5); },
       "crc32c: found before the end"},
  };
  for (const Case& c : cases) {
    st::SessionRestState m = good;
    c.damage(&m);
    const absl::Status status = DecodeSessionRestState(checkpoint::Seal(m)).status();
    EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << c.name << ": " << status;
    EXPECT_THAT(status.message(), HasSubstr("session checkpoint: " + c.message)) << c.name;
  }
}

// A restore from a damaged checkpoint, or from one no session at rest could have written, fails
// with DATA_LOSS naming the field, and serves nothing: the entries it covered are gone.
TEST_F(SessionCheckpointTest, ARestoreFromADamagedCheckpointIsDataLoss) {
  SessionRegistry reg(Limits(), nullptr, /*workers=*/1);
  reg.SetJournal(&journal_);
  v1::CreateSessionResponse s;
  const std::vector<v1::SessionInfo> infos = Play(reg, &s, kEvery);
  const std::vector<MemoryJournal::Written> written = journal_.checkpoints(s.session_id());
  ASSERT_EQ(written.size(), 1u);
  const int64_t reached = infos.back().tick();
  const st::SessionRestState good = Parsed<st::SessionRestState>(written[0].state);

  struct Case {
    std::string name;
    std::string bytes;
    std::string message;
  };
  std::string cut = written[0].state;
  cut.resize(cut.size() / 2);
  st::SessionRestState swinging = good;
  swinging.set_phase(st::SessionRestState::PHASE_SWINGING);
  st::SessionRestState inhuman = good;
  v1::SwingParameters params;
  params.set_arm_length_m(-1);
  inhuman.set_params(params.SerializeAsString());
  const std::vector<Case> cases = {
      {"cut short", cut, "checkpoint: session checkpoint: "},
      {"swinging", checkpoint::Seal(swinging), "checkpoint: session checkpoint: phase: swinging"},
      {"bad parameters", checkpoint::Seal(inhuman),
       "checkpoint: session checkpoint: params: parameters.arm_length_m"},
  };
  for (const Case& c : cases) {
    SessionRegistry restored(Limits(), nullptr, /*workers=*/1);
    MemoryJournal::Written damaged = written[0];
    damaged.state = c.bytes;
    const absl::Status status =
        restored.Restore(journal_.Stored(s.session_id(), &damaged, reached));
    EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << c.name << ": " << status;
    EXPECT_THAT(status.message(), HasSubstr(c.message)) << c.name;
    v1::GetSessionRequest get;
    get.set_session_id(s.session_id());
    EXPECT_EQ(restored.Get(get).status().code(), absl::StatusCode::kNotFound) << c.name;
  }
}

// ---------------------------------------------------------------------------------------------
// 4. Restores.

// Three sessions after the same history: A ran it uninterrupted; B is restored from its whole
// journal; C from its latest checkpoint (swing 6) and the entries after it (driven swing 7 and
// swing 8, stopped by its duration). B and C replay swing 8 at the ticks A ran it: they end it
// with A's state, sequence numbers and events, bit for bit. Then each runs swing 9 live, on its
// own clock, and writes a checkpoint after it: the three are the same but for the swing's start
// tick (the clocks differ), and C's holds what B's does.
TEST_F(SessionCheckpointTest, ARestoreFromTheCheckpointEndsTheNextSwingAsTheUninterruptedSession) {
  SessionRegistry a(Limits(), nullptr, /*workers=*/1);
  a.SetJournal(&journal_);
  v1::CreateSessionResponse s;
  const std::vector<v1::SessionInfo> infos = Play(a, &s, 8);
  ASSERT_EQ(infos.size(), 9u);
  const std::string& id = s.session_id();
  const v1::SessionInfo at_rest = Info(a, id);
  const std::vector<MemoryJournal::Written> written = journal_.checkpoints(id);
  ASSERT_EQ(written.size(), 2u);
  const MemoryJournal::Written& latest = written.back();
  const SessionRestState from = Decoded(latest);
  ASSERT_EQ(from.swings, 6u);

  const StoredWorld whole = journal_.Stored(id, nullptr, at_rest.tick());
  const StoredWorld short_cut = journal_.Stored(id, &latest, at_rest.tick());
  // The checkpoint leaves the creation and swings 7 (driven: start, command, and the driver's
  // end unless the swing had ended first) and 8.
  const auto type = [&](size_t i) {
    return static_cast<SessionCommand>(short_cut.entries[i].type);
  };
  ASSERT_GE(short_cut.entries.size(), 4u);
  ASSERT_LE(short_cut.entries.size(), 5u);
  EXPECT_EQ(type(1), SessionCommand::kDriveStart);
  EXPECT_EQ(type(2), SessionCommand::kDriveCommand);
  if (short_cut.entries.size() == 5) {
    EXPECT_EQ(type(3), SessionCommand::kDriveEnd);
  }
  EXPECT_EQ(type(short_cut.entries.size() - 1), SessionCommand::kStart);
  EXPECT_GE(whole.entries.size(), short_cut.entries.size() + 8);

  MemoryJournal journal_b, journal_c;
  SessionRegistry b(Limits(), nullptr, /*workers=*/1);
  SessionRegistry c(Limits(), nullptr, /*workers=*/1);
  b.SetJournal(&journal_b);
  c.SetJournal(&journal_c);
  ASSERT_TRUE(b.Restore(whole).ok());
  ASSERT_TRUE(c.Restore(short_cut).ok());
  // Nothing is written while a session is replayed (B passed swings 3 and 6).
  EXPECT_TRUE(journal_b.checkpoints(id).empty());
  EXPECT_TRUE(journal_c.checkpoints(id).empty());

  // Swing 8's end: GetSession and the events since the checkpoint, bit for bit.
  const v1::SessionInfo info_b = Info(b, id);
  const v1::SessionInfo info_c = Info(c, id);
  EXPECT_EQ(at_rest.swings(), 8u);
  EXPECT_EQ(at_rest.last_end_reason(), "duration");
  std::string report;
  EXPECT_TRUE(SameBut(at_rest, info_b, &report)) << "whole journal: " << report;
  report.clear();
  EXPECT_TRUE(SameBut(at_rest, info_c, &report)) << "from the checkpoint: " << report;
  const v1::SwingSnapshot events_a = Resume(a, id, from.sequence);
  const v1::SwingSnapshot events_b = Resume(b, id, from.sequence);
  const v1::SwingSnapshot events_c = Resume(c, id, from.sequence);
  EXPECT_FALSE(events_c.resync());
  EXPECT_EQ(events_a.sequence(), at_rest.sequence());
  ASSERT_GE(events_a.events_size(), 7);  // 7: started, torque, impact, ended; 8: started, ...
  std::map<v1::SwingEventKind, int> kinds;
  for (const v1::SwingEvent& e : events_a.events()) {
    ++kinds[e.kind()];
    EXPECT_GT(e.sequence(), from.sequence);
  }
  EXPECT_EQ(kinds[v1::SWING_EVENT_STARTED], 2);
  EXPECT_EQ(kinds[v1::SWING_EVENT_TORQUE], 1);
  EXPECT_EQ(kinds[v1::SWING_EVENT_ENDED], 2);
  EXPECT_GE(kinds[v1::SWING_EVENT_IMPACT], 1);
  report.clear();
  EXPECT_TRUE(SameBut(events_a, events_b, &report)) << "whole journal: " << report;
  report.clear();
  EXPECT_TRUE(SameBut(events_a, events_c, &report)) << "from the checkpoint: " << report;
  // B rebuilt every event since the creation.
  report.clear();
  EXPECT_TRUE(SameBut(Resume(a, id, 0), Resume(b, id, 0), &report)) << report;

  // D: from the checkpoint alone (as if the server stopped right after swing 6). It is A at swing
  // 6's end: every member a client can see came from the checkpoint.
  StoredWorld only = journal_.Stored(id, &latest, infos[6].tick());
  only.entries.resize(1);
  SessionRegistry d(Limits(), nullptr, /*workers=*/1);
  ASSERT_TRUE(d.Restore(only).ok());
  report.clear();
  EXPECT_TRUE(SameBut(infos[6], Info(d, id), &report)) << "at the checkpoint: " << report;
  const v1::SwingSnapshot at_checkpoint = Resume(d, id, from.sequence);
  EXPECT_EQ(at_checkpoint.sequence(), infos[6].sequence());
  EXPECT_EQ(at_checkpoint.events_size(), 0);
  EXPECT_EQ(at_checkpoint.qalpha_nm(), 100.0);  // the chapter's torques at swing 6's end
  EXPECT_EQ(at_checkpoint.qbeta_nm(), 0.0);
  EXPECT_TRUE(Resume(d, id, from.sequence - 1).resync()) << "events before the checkpoint";

  // Swing 9, live on each: the checkpoint each writes after it.
  std::vector<SessionRestState> ninth;
  for (auto [reg, journal] : {std::pair{&a, &journal_}, std::pair{&b, &journal_b},
                              std::pair{&c, &journal_c}}) {
    Swing(*reg, s, 9);
    const std::vector<MemoryJournal::Written> w = journal->checkpoints(id);
    ASSERT_FALSE(w.empty());
    ninth.push_back(Decoded(w.back()));
  }
  ASSERT_EQ(ninth.size(), 3u);
  EXPECT_EQ(ninth[0].swings, 9u);
  for (size_t i = 1; i < 3; ++i) {
    SessionRestState got = ninth[i];
    EXPECT_EQ(got.tick - got.start_tick, ninth[0].tick - ninth[0].start_tick);
    got.tick = ninth[0].tick;
    got.start_tick = ninth[0].start_tick;
    EXPECT_TRUE(SameSessionRestState(ninth[0], got))
        << (i == 1 ? "whole journal: " : "from the checkpoint: ")
        << SessionRestStateDifference(ninth[0], got);
  }
}

}  // namespace
}  // namespace sportsim::server
