"""Durability against the real server binary: kill -9 in the middle of shots, matches and swings,
restart on the same journal (SQLite in a temporary directory; PostgreSQL 15 started here in a
throwaway cluster), and check that every world comes back with its ids, tokens, turn, scores and
sequence, and that what was in flight ends bit-identical to an uninterrupted run."""
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import unittest

sys.path.insert(0, os.environ["SPORTSIM_PYTHON_STUBS"])
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "support"))

import grpc  # noqa: E402
import health_pb2  # noqa: E402
import health_pb2_grpc  # noqa: E402
from sportsim.v1 import billiards_pb2 as bp  # noqa: E402
from sportsim.v1 import billiards_pb2_grpc as bg  # noqa: E402
from sportsim.v1 import swing_pb2 as sp  # noqa: E402
from sportsim.v1 import swing_pb2_grpc as sg  # noqa: E402
from server_proc import ServerProcess  # noqa: E402

SERVER = os.path.join(os.environ["SPORTSIM_BIN_DIR"], "sportsim-server")
PG_BIN = "/usr/lib/postgresql/15/bin"
BREAK = bp.CueStrike(ball_speed_mps=8.0, phi_deg=0.5)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class PostgresCluster:
    """A throwaway PostgreSQL 15 cluster on a loopback port, run as an unprivileged user (initdb
    and pg_ctl refuse root)."""

    def __init__(self):
        self.dir = tempfile.mkdtemp(prefix="sportsim-pg-")
        os.chmod(self.dir, 0o755)
        self.data = os.path.join(self.dir, "pg")
        os.mkdir(self.data)
        self.port = free_port()
        self.as_user = []
        if os.geteuid() == 0:
            shutil.chown(self.data, "nobody")
            self.as_user = ["runuser", "-u", "nobody", "--"]
        self._run("initdb", "-D", self.data, "-U", "sportsim", "--auth=trust", "-N")
        self.start()
        self._run("createdb", "-h", "127.0.0.1", "-p", str(self.port), "-U", "sportsim",
                  "sportsim")
        self.uri = "postgresql://sportsim@127.0.0.1:%d/sportsim" % self.port

    def _run(self, tool, *args):
        subprocess.run(self.as_user + [os.path.join(PG_BIN, tool), *args], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)

    def start(self):
        self._run("pg_ctl", "-D", self.data, "-o",
                  "-p %d -k %s -c listen_addresses=127.0.0.1 -c fsync=on" % (self.port, self.data),
                  "-l", os.path.join(self.data, "log"), "-w", "start")

    def stop(self):
        self._run("pg_ctl", "-D", self.data, "-m", "immediate", "-w", "stop")

    def close(self):
        try:
            self.stop()
        except subprocess.CalledProcessError:
            pass
        shutil.rmtree(self.dir, ignore_errors=True)


class Server:
    """A server on a journal, killable with SIGKILL and restartable on the same journal."""

    def __init__(self, journal_args, *extra):
        self.args = list(journal_args) + list(extra)
        self.proc = ServerProcess(SERVER, *self.args)
        self.channel = grpc.insecure_channel(self.proc.address)
        grpc.channel_ready_future(self.channel).result(timeout=30)
        self.tables = bg.BilliardsStub(self.channel)
        self.swings = sg.SwingStub(self.channel)
        self.health = health_pb2_grpc.HealthStub(self.channel)

    def kill9(self):
        self.proc.proc.send_signal(signal.SIGKILL)
        self.proc.proc.wait()
        self._close()

    def stop(self):
        if self.proc.proc.poll() is None:
            self.proc.terminate()
        self._close()

    def _close(self):
        self.channel.close()
        for pipe in (self.proc.proc.stdout, self.proc.proc.stderr):
            if pipe is not None:
                pipe.close()

    def serving(self):
        return self.health.Check(health_pb2.HealthCheckRequest(), timeout=10).status


def ball_bits(balls):
    """The balls as exact tuples (every double compared by value, bit for bit in practice)."""
    return [(b.id, b.state, b.x_m, b.y_m, b.vx_mps, b.vy_mps, b.wx_rps, b.wy_rps, b.wz_rps,
             b.pocket) for b in balls]


def event_key(e, t0=0.0):
    """An engine event; a table's events carry table time, a shot's its own from 0 (t0)."""
    return (e.kind, round(e.t_s - t0, 9), tuple(e.balls), e.cushion, e.pocket)


def place_cue_ball(server, tid, token, info):
    """Ball in hand: puts the cue ball on the first free spot the referee accepts."""
    for x, y in [(-0.6, 0.0), (-0.6, 0.3), (-0.6, -0.3), (-0.8, 0.15), (-0.4, 0.45),
                 (0.3, 0.4), (-0.9, -0.4), (0.6, -0.45), (0.0, -0.55), (-1.0, 0.5)]:
        try:
            server.tables.PlaceBall(bp.PlaceBallRequest(
                table_id=tid, token=token, ball=bp.BallPlacement(id="cue", x_m=x, y_m=y)),
                timeout=10)
            return
        except grpc.RpcError as e:
            if e.code() not in (grpc.StatusCode.INVALID_ARGUMENT,
                                grpc.StatusCode.FAILED_PRECONDITION):
                raise
    raise AssertionError("no spot for the cue ball: %s" % info.game)


def wait_at_rest(server, table_id, timeout=60):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        info = server.tables.GetTable(bp.GetTableRequest(table_id=table_id), timeout=10)
        if info.at_rest:
            return info
        time.sleep(0.05)
    raise AssertionError("table %s still moving after %g s" % (table_id, timeout))


def wait_adopted(server, table_id, timeout=20):
    """Waits until `server` (started with --adopt) serves the table of a lapsed node."""
    deadline = time.monotonic() + timeout
    while True:
        try:
            return server.tables.GetTable(bp.GetTableRequest(table_id=table_id), timeout=10)
        except grpc.RpcError as e:
            if e.code() != grpc.StatusCode.NOT_FOUND or time.monotonic() > deadline:
                raise AssertionError("the table was never adopted: %s" % e.details())
            time.sleep(0.2)


def take_turn(server, tid, tokens, strike):
    """A ruled game's next shot by the seat to play: the pending decision taken (its first
    choice), the cue ball placed when in hand, a safety declared when a call is required."""
    info = wait_at_rest(server, tid)
    if info.game.HasField("decision") and info.game.decision.choices:
        server.tables.Decide(bp.DecideRequest(table_id=tid, token=tokens[info.game.to_play],
                                              choice=info.game.decision.choices[0]), timeout=10)
        info = wait_at_rest(server, tid)
    if info.game.ball_in_hand not in ("", "none"):
        place_cue_ball(server, tid, tokens[info.game.to_play], info)
    req = bp.ShootRequest(table_id=tid, token=tokens[info.game.to_play], strike=strike)
    if info.game.call_required:
        req.call.safety = True
    server.tables.Shoot(req, timeout=10)


def wait_swing_over(server, session_id, timeout=60):
    """Waits until the session's swing in flight (if any) has ended; returns its SessionInfo."""
    deadline = time.monotonic() + timeout
    while True:
        info = server.swings.GetSession(sp.GetSessionRequest(session_id=session_id), timeout=10)
        if info.phase != sp.SWING_PHASE_SWINGING:
            return info
        if time.monotonic() > deadline:
            raise AssertionError("session %s still swinging after %g s" % (session_id, timeout))
        time.sleep(0.05)


def drive_swing(server, session_id, token, commands):
    """Starts a driven swing that sends `commands` and keeps its stream open until `done` is
    set; returns (the stream, its first snapshot, done)."""
    msgs = [sp.DriveSwingRequest(start=sp.DriveStart(
        session_id=session_id, token=token, qalpha_nm=60, qbeta_nm=10))]
    msgs += [sp.DriveSwingRequest(torque=c) for c in commands]
    done = threading.Event()

    def requests():
        for m in msgs:
            yield m
        done.wait(30)

    stream = server.swings.DriveSwing(requests())
    first = next(stream)  # the swing started
    return stream, first, done


def swing_events_after(server, session_id, sequence):
    """A spectator's first snapshot when it resumes after `sequence`: (resync, its events)."""
    stream = server.swings.WatchSwing(sp.WatchSwingRequest(session_id=session_id,
                                                           from_sequence=sequence))
    try:
        first = next(stream)
    finally:
        stream.cancel()
    return first.resync, list(first.events)


class Watcher(threading.Thread):
    """Collects a table's events and the last sequence seen, until the stream ends."""

    def __init__(self, server, table_id, from_sequence=None):
        super().__init__(daemon=True)
        req = bp.WatchTableRequest(table_id=table_id)
        if from_sequence is not None:
            req.from_sequence = from_sequence
        self.stream = server.tables.WatchTable(req)
        self.events, self.sequence, self.resync = [], 0, False
        self.start()

    def run(self):
        try:
            for snap in self.stream:
                self.events.extend(snap.events)
                self.sequence = max(self.sequence, snap.sequence)
                self.resync = self.resync or snap.resync
        except grpc.RpcError:
            pass


def wait_round_at_rest(server, round_id, timeout=60):
    """Waits until no ball of the round moves; returns its RoundInfo."""
    deadline = time.monotonic() + timeout
    while True:
        info = server.swings.GetRound(sp.GetRoundRequest(round_id=round_id), timeout=10)
        if not info.round.stroke_in_play:
            return info
        if time.monotonic() > deadline:
            raise AssertionError("round %s: a ball still moves after %g s" % (round_id, timeout))
        time.sleep(0.02)


def round_command(state):
    """A scripted player's next command from the round's state, the same on any server holding
    the same state: a pending decision's last choice; else, for the seat to play, a putt on or
    near the green, otherwise a launch toward the pin sized by the distance (high under 60 m, a
    tenth shorter for each stroke over par on the hole)."""
    if state.HasField("decision") and state.decision.choices:
        return state.decision.seat, "decide", state.decision.choices[-1]
    seat = state.to_play
    ball = state.players[seat].ball
    d = ball.distance_to_pin_m
    if ball.lie == "green" or d < 20:
        return seat, "putt", min(12.0, 1.4 * (1.2 * (d + 0.3)) ** 0.5)
    f = 0.9 ** max(0, state.players[seat].strokes - state.par)
    if d < 60:
        return seat, "pitch", 3.6 * d ** 0.5 * f
    return seat, "launch", min(70.0, 4.5 * d ** 0.5) * f


def play_round_command(server, round_id, tokens):
    """Plays round_command on the round at rest; returns what was played."""
    info = wait_round_at_rest(server, round_id)
    seat, kind, value = round_command(info.round)
    if kind == "decide":
        server.swings.DecideRound(sp.DecideRoundRequest(round_id=round_id, token=tokens[seat],
                                                        choice=value), timeout=10)
    elif kind == "putt":
        server.swings.PlayStroke(sp.PlayStrokeRequest(round_id=round_id, token=tokens[seat],
                                                      putt_speed_mps=value), timeout=30)
    else:
        high = kind == "pitch"
        server.swings.PlayStroke(sp.PlayStrokeRequest(
            round_id=round_id, token=tokens[seat],
            launch=sp.LaunchConditions(ball_speed_mps=value, launch_angle_deg=40 if high else 20,
                                       spin_rpm=6000 if high else 5000)), timeout=30)
    return seat, kind, value


class DurabilityBase:
    """The restart tests, for a journal given by journal_args()."""

    def journal_args(self):
        raise NotImplementedError

    def start(self, *extra):
        return Server(self.journal_args(), *extra)

    def shot_mid_flight(self, solver):
        rack = bp.TableSetup(preset="pool-9ft", rack="9ball")
        s = self.start()
        created = s.tables.CreateTable(bp.CreateTableRequest(table=rack, solver=solver),
                                       timeout=30)
        tid, tokens = created.table_id, [seat.token for seat in created.seats]
        watcher = Watcher(s, tid)
        time.sleep(0.3)
        shot = s.tables.Shoot(bp.ShootRequest(table_id=tid, token=tokens[0], strike=BREAK),
                              timeout=30)
        time.sleep(0.6)  # the break runs for seconds of table time
        before = s.tables.GetTable(bp.GetTableRequest(table_id=tid), timeout=10)
        self.assertFalse(before.at_rest, "kill the server mid-shot")
        s.kill9()
        watcher.join(timeout=10)
        seen = watcher.sequence
        self.assertGreater(seen, 0)

        s = self.start()
        try:
            info = s.tables.GetTable(bp.GetTableRequest(table_id=tid), timeout=10)
            self.assertEqual(info.table_id, tid)
            self.assertEqual(info.shots, 1)
            # The clock paused while no server ran: the table resumes where it was (within the
            # journal's clock interval), never behind what a watcher saw.
            self.assertGreaterEqual(info.tick, before.tick)
            self.assertLess(info.tick, before.tick + 120)
            self.assertGreaterEqual(info.sequence, seen)
            resumed = Watcher(s, tid, from_sequence=seen)
            end = wait_at_rest(s, tid)
            time.sleep(0.3)
            resumed.stream.cancel()
            resumed.join(timeout=10)
            self.assertFalse(resumed.resync)

            alone = s.tables.SimulateShot(bp.SimulateShotRequest(table=rack, strike=BREAK,
                                                                 solver=solver), timeout=60)
            self.assertEqual(ball_bits(end.balls), ball_bits(alone.balls))
            # Every event of the shot reached a watcher once, across the crash, in order.
            events = [e for e in watcher.events + resumed.events if e.shot_id == shot.shot_id]
            t0 = next(e.t_s for e in events if e.kind == bp.shot)
            engine = [event_key(e, t0) for e in events if e.kind not in (bp.shot, bp.shot_end)]
            self.assertEqual(engine, [event_key(e) for e in alone.events])
            seqs = [e.sequence for e in events]
            self.assertEqual(seqs, sorted(seqs))
            # The seats' tokens still work, and only they.
            s.tables.SetTurn(bp.SetTurnRequest(table_id=tid, token=tokens[0], seat=1),
                             timeout=10)
            with self.assertRaises(grpc.RpcError) as e:
                s.tables.SetTurn(bp.SetTurnRequest(table_id=tid, token="x" * 32, seat=0),
                                 timeout=10)
            self.assertEqual(e.exception.code(), grpc.StatusCode.PERMISSION_DENIED)
        finally:
            s.stop()

    def test_event_engine_shot_survives_kill9(self):
        self.shot_mid_flight(bp.SolverConfig())

    def test_stepped_engine_shot_survives_kill9(self):
        self.shot_mid_flight(bp.SolverConfig(engine=bp.ENGINE_STEPPED))

    def test_ruled_match_survives_kill9(self):
        game = bp.GameConfig(name="9ball", race_to=2, noise=0.5, seed=42, shot_clock_s=30)
        strikes = [BREAK] + [bp.CueStrike(ball_speed_mps=2.0 + 0.3 * i, phi_deg=37.0 * i)
                             for i in range(1, 6)]

        def play(server, kill_after=None):
            created = server.tables.CreateTable(bp.CreateTableRequest(game=game), timeout=30)
            tid = created.table_id
            tokens = [seat.token for seat in created.seats]
            for i, strike in enumerate(strikes):
                take_turn(server, tid, tokens, strike)
                if kill_after == i:
                    time.sleep(0.3)
                    return tid, tokens, server.tables.GetTable(bp.GetTableRequest(table_id=tid),
                                                               timeout=10)
            return tid, tokens, wait_at_rest(server, tid)

        # The uninterrupted match, in memory, with the same secret seed.
        ref = Server([], "--clock_rate", "20")
        try:
            _, _, ref_end = play(ref)
            ref_record = ref.tables.GetMatchRecord(
                bp.GetMatchRecordRequest(table_id=ref_end.table_id), timeout=10)
        finally:
            ref.stop()

        s = self.start("--clock_rate", "2")
        tid, tokens, mid = play(s, kill_after=3)
        self.assertFalse(mid.at_rest)
        s.kill9()
        s = self.start("--clock_rate", "2")
        try:
            info = s.tables.GetTable(bp.GetTableRequest(table_id=tid), timeout=10)
            self.assertEqual(info.shots, mid.shots)
            self.assertEqual(info.game.frames_won, mid.game.frames_won)
            end = wait_at_rest(s, tid)
            # Play on to the same number of shots and compare with the uninterrupted match; the
            # server dies once more mid-shot after a checkpoint (every 4 shots), so the second
            # restore starts from the checkpoint and replays what followed it.
            for k, strike in enumerate(strikes[4:]):
                if k == 1:
                    time.sleep(0.2)
                    s.kill9()
                    s = self.start("--clock_rate", "2")
                take_turn(s, tid, tokens, strike)
            end = wait_at_rest(s, tid)
            self.assertEqual(ball_bits(end.balls), ball_bits(ref_end.balls))
            self.assertEqual(end.game.scores, ref_end.game.scores)
            self.assertEqual(end.game.to_play, ref_end.game.to_play)
            record = s.tables.GetMatchRecord(bp.GetMatchRecordRequest(table_id=tid), timeout=10)
            self.assertEqual([(a.kind, a.seat) for a in record.actions],
                             [(a.kind, a.seat) for a in ref_record.actions])
            self.assertEqual([a.verdict for a in record.actions],
                             [a.verdict for a in ref_record.actions])
        finally:
            s.stop()

    def test_round_survives_kill9(self):
        # A whole round, two players on the three holes, strokes taking round time (no
        # fast-forward; the clock at 10x), the server killed twice while a ball moves. The
        # reference: the same round uninterrupted in memory. Commands follow from the round's
        # state, so equal states mean equal rounds.
        create = sp.CreateRoundRequest(course="sportsim_links",
                                       players=[sp.RoundPlayerSpec(name="Ann"),
                                                sp.RoundPlayerSpec(name="Bob", tee="red")],
                                       seed=5, noise=0.5, tick_hz=30)
        def play(server, kills=()):
            created = server.swings.CreateRound(create, timeout=30)
            rid, tokens = created.round_id, [seat.token for seat in created.seats]
            played = []
            for i in range(120):
                if wait_round_at_rest(server, rid).round.result:
                    break
                played.append(play_round_command(server, rid, tokens))
                if i in kills:
                    time.sleep(0.1)
                    moving = server.swings.GetRound(sp.GetRoundRequest(round_id=rid), timeout=10)
                    server.kill9()
                    server = self.start("--clock_rate", "10")
                    info = server.swings.GetRound(sp.GetRoundRequest(round_id=rid), timeout=10)
                    self.assertEqual(info.round.strokes, moving.round.strokes)
                    self.assertGreaterEqual(info.tick, moving.tick)
            end = wait_round_at_rest(server, rid)
            record = server.swings.GetRoundRecord(sp.GetRoundRecordRequest(round_id=rid),
                                                  timeout=10)
            return server, played, end, record, tokens

        ref = Server([], "--clock_rate", "10")
        try:
            _, ref_played, ref_end, ref_record, _ = play(ref)
        finally:
            ref.stop()
        self.assertEqual(ref_end.round.result, "finished")
        self.assertGreater(ref_end.round.strokes, 12)

        s = self.start("--clock_rate", "10")
        s, played, end, record, tokens = play(s, kills=(3, 9))
        try:
            self.assertEqual(played, ref_played)
            self.assertEqual(end.round, ref_end.round)  # every field, every double, bit for bit
            self.assertEqual([(c.seat, c.WhichOneof("command")) for c in record.commands],
                             [(c.seat, c.WhichOneof("command")) for c in ref_record.commands])
            self.assertEqual(record.round, ref_record.round)
            # The seats' tokens still work, and only they.
            with self.assertRaises(grpc.RpcError) as e:
                s.swings.PlayStroke(sp.PlayStrokeRequest(round_id=end.round_id, token="x" * 32,
                                                         putt_speed_mps=1), timeout=10)
            self.assertEqual(e.exception.code(), grpc.StatusCode.PERMISSION_DENIED)
            with self.assertRaises(grpc.RpcError) as e:  # the round is over
                play_round_command(s, end.round_id, tokens)
            self.assertEqual(e.exception.code(), grpc.StatusCode.FAILED_PRECONDITION)
        finally:
            s.stop()

    def test_driven_swing_survives_kill9(self):
        # Slow motion (table time at a tenth of real time) so that the kill lands mid-swing.
        commands = [sp.TorqueCommand(t_s=0.05 * k, qalpha_nm=60 + 5 * k, qbeta_nm=10 - k)
                    for k in range(1, 6)]

        def drive(server):
            created = server.swings.CreateSession(sp.CreateSessionRequest(), timeout=30)
            sid, token = created.session_id, created.token
            return (sid, token) + drive_swing(server, sid, token, commands)

        ref = Server([], "--clock_rate", "0.1")
        try:
            sid, _, stream, _, done = drive(ref)
            for _ in stream:
                pass
            done.set()
            ref_info = ref.swings.GetSession(sp.GetSessionRequest(session_id=sid), timeout=10)
        finally:
            ref.stop()

        s = self.start("--clock_rate", "0.1")
        sid, token, stream, first, done = drive(s)
        time.sleep(1.0)  # 0.1 s of swing time: every command accepted, the swing not over
        mid = s.swings.GetSession(sp.GetSessionRequest(session_id=sid), timeout=10)
        self.assertIn("SWINGING", sp.SwingPhase.Name(mid.phase))
        s.kill9()
        done.set()
        s = self.start("--clock_rate", "0.1")
        try:
            info = wait_swing_over(s, sid)
            self.assertEqual(info.swings, 1)
            self.assertTrue(info.HasField("last_impact"))
            self.assertEqual(info.last_impact, ref_info.last_impact)
            s.swings.ResetSwing(sp.ResetSwingRequest(session_id=sid, token=token), timeout=10)
        finally:
            s.stop()

    def test_swing_session_restores_from_its_checkpoint(self):
        # Ten swings, then an eleventh, driven, killed mid-swing. A session writes a checkpoint
        # at the end of every 8th swing, so the restore loads the one of swing 8 and replays only
        # what followed it: swings 9 and 10 and the swing in flight. Only swing 8 runs to impact
        # (the others stop after 0.02 s), so the last impact at the kill is in the checkpoint
        # alone; the address moves with a reset before swing 5 (in the checkpoint) and its wrist
        # cock with one before swing 10 (in the journal after it).
        commands = [sp.TorqueCommand(t_s=0.05 * k, qalpha_nm=60 + 5 * k, qbeta_nm=10 - k)
                    for k in range(1, 6)]
        resets = {5: dict(gamma_deg=130.0), 10: dict(beta0_deg=115.0)}

        def prepare(server):
            created = server.swings.CreateSession(sp.CreateSessionRequest(), timeout=30)
            sid, token = created.session_id, created.token
            for k in range(1, 11):
                if k in resets:
                    server.swings.ResetSwing(sp.ResetSwingRequest(
                        session_id=sid, token=token, **resets[k]), timeout=10)
                start = sp.StartSwingRequest(session_id=sid, token=token)  # the chapter's
                if k != 8:
                    start.stop = sp.SWING_STOP_DURATION
                    start.duration_s = 0.02
                self.assertEqual(server.swings.StartSwing(start, timeout=10).swing_id, k)
                info = wait_swing_over(server, sid)
                self.assertEqual(info.last_end_reason, "impact" if k == 8 else "duration")
                if k == 8:
                    checkpointed = info.sequence  # the checkpoint's: it is taken at this rest
            return sid, token, checkpointed, info

        def same_session(a, b):
            for field in ("swing_id", "swings", "gamma_deg", "beta0_deg", "integrator", "dt_s",
                          "tick_hz", "profile", "last_end_reason", "last_impact"):
                self.assertEqual(getattr(a, field), getattr(b, field), field)

        # Slow motion (a tenth of real time), as for the driven swing above.
        ref = Server([], "--clock_rate", "0.1")
        try:
            sid, token, _, ref_before = prepare(ref)
            stream, _, done = drive_swing(ref, sid, token, commands)
            for _ in stream:
                pass
            done.set()
            ref_end = wait_swing_over(ref, sid)
        finally:
            ref.stop()

        s = self.start("--clock_rate", "0.1")
        sid, token, checkpointed, before = prepare(s)
        same_session(before, ref_before)
        self.assertEqual((before.gamma_deg, before.beta0_deg), (130.0, 115.0))
        self.assertTrue(before.HasField("last_impact"))
        stream, _, done = drive_swing(s, sid, token, commands)
        time.sleep(1.0)  # 0.1 s of swing time: every command accepted, the swing not over
        mid = s.swings.GetSession(sp.GetSessionRequest(session_id=sid), timeout=10)
        self.assertEqual(mid.phase, sp.SWING_PHASE_SWINGING)
        self.assertEqual(mid.swings, 11)
        self.assertEqual(mid.last_impact, before.last_impact)  # swing 8's, still
        resync, live = swing_events_after(s, sid, checkpointed)
        self.assertFalse(resync)
        s.kill9()
        done.set()
        s = self.start("--clock_rate", "0.1")
        try:
            info = s.swings.GetSession(sp.GetSessionRequest(session_id=sid), timeout=10)
            self.assertEqual(info.session_id, sid)
            self.assertEqual(info.phase, sp.SWING_PHASE_SWINGING)  # the swing goes on
            same_session(info, mid)  # swing 8's impact and the first reset: the checkpoint's
            self.assertGreaterEqual(info.sequence, mid.sequence)
            # The restore started from the checkpoint: the events up to it are no longer held
            # (a spectator resuming from before it is resynced), and the ones after it were
            # replayed as they happened (swings 9 and 10, the second reset, the swing in flight).
            resync, _ = swing_events_after(s, sid, checkpointed - 1)
            self.assertTrue(resync, "a restore that replayed every swing keeps all events")
            resync, replayed = swing_events_after(s, sid, checkpointed)
            self.assertFalse(resync)
            self.assertEqual(replayed[:len(live)], live)
            self.assertEqual(live[0].sequence, checkpointed + 1)
            self.assertEqual([e.swing_id for e in live if e.kind == sp.SWING_EVENT_STARTED],
                             [9, 10, 11])

            end = wait_swing_over(s, sid)
            same_session(end, ref_end)  # the swing in flight ended as uninterrupted
            self.assertEqual(end.swings, 11)
            self.assertEqual(end.last_end_reason, "impact")
            self.assertNotEqual(end.last_impact, before.last_impact)
            self.assertEqual(end.state, ref_end.state)
            # The seat's token still works, and only it.
            s.swings.ResetSwing(sp.ResetSwingRequest(session_id=sid, token=token), timeout=10)
            with self.assertRaises(grpc.RpcError) as e:
                s.swings.ResetSwing(sp.ResetSwingRequest(session_id=sid, token="x" * 32),
                                    timeout=10)
            self.assertEqual(e.exception.code(), grpc.StatusCode.PERMISSION_DENIED)
        finally:
            s.stop()

    def test_kill9_while_many_tables_shoot(self):
        s = self.start("--clock_rate", "4")
        rack = bp.TableSetup(preset="pool-9ft", rack="9ball")
        tables = []
        for _ in range(40):
            c = s.tables.CreateTable(bp.CreateTableRequest(table=rack), timeout=30)
            tables.append((c.table_id, c.seats[0].token))
        acked = {}
        stop = threading.Event()

        def shooter(tid, token):
            n = 0
            while not stop.is_set():
                try:
                    s.tables.Shoot(bp.ShootRequest(
                        table_id=tid, token=token,
                        strike=bp.CueStrike(ball_speed_mps=0.3 + 0.01 * n, phi_deg=n)),
                        timeout=5)
                    n += 1
                    acked[tid] = n
                except grpc.RpcError as e:
                    if e.code() == grpc.StatusCode.FAILED_PRECONDITION:
                        time.sleep(0.01)  # still moving
                        continue
                    return  # the server died
                except ValueError:
                    return  # its channel was closed

        threads = [threading.Thread(target=shooter, args=t, daemon=True) for t in tables]
        for t in threads:
            t.start()
        time.sleep(2.0)
        s.kill9()
        stop.set()
        for t in threads:
            t.join(timeout=10)
        self.assertGreater(sum(acked.values()), 40)
        s = self.start("--clock_rate", "4")
        try:
            for tid, _ in tables:
                info = s.tables.GetTable(bp.GetTableRequest(table_id=tid), timeout=10)
                # Every acknowledged shot is there; at most the one in flight at the kill more.
                self.assertGreaterEqual(info.shots, acked.get(tid, 0))
                self.assertLessEqual(info.shots, acked.get(tid, 0) + 1)
        finally:
            s.stop()


class SqliteDurability(DurabilityBase, unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="sportsim-data-")

    def tearDown(self):
        shutil.rmtree(self.dir, ignore_errors=True)

    def journal_args(self):
        return ["--data_dir", self.dir]

    def test_a_second_server_on_the_same_directory_refuses_to_start(self):
        s = self.start()
        try:
            p = subprocess.run([SERVER, "--listen", "127.0.0.1:0", "--data_dir", self.dir],
                               capture_output=True, text=True, timeout=30)
            self.assertEqual(p.returncode, 2)
            self.assertIn(self.dir, p.stderr)
            self.assertIn("in use", p.stderr)
        finally:
            s.stop()

    def test_an_unwritable_data_dir_is_a_clear_error_at_start(self):
        blocker = os.path.join(self.dir, "file")
        with open(blocker, "w") as f:
            f.write("not a directory")
        p = subprocess.run([SERVER, "--listen", "127.0.0.1:0", "--data_dir",
                            os.path.join(blocker, "data")],
                           capture_output=True, text=True, timeout=30)
        self.assertEqual(p.returncode, 2)
        self.assertIn(os.path.join(blocker, "data"), p.stderr)  # the path, and why
        self.assertIn("Not a directory", p.stderr)

    def test_a_deleted_table_leaves_the_store(self):
        s = self.start()
        c = s.tables.CreateTable(bp.CreateTableRequest(), timeout=30)
        s.tables.DeleteTable(bp.DeleteTableRequest(table_id=c.table_id,
                                                   token=c.seats[0].token), timeout=10)
        s.kill9()
        s = self.start()
        try:
            listed = s.tables.ListTables(bp.ListTablesRequest(), timeout=10)
            self.assertEqual(listed.total, 0)
        finally:
            s.stop()


class PostgresDurability(DurabilityBase, unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.pg = PostgresCluster()

    @classmethod
    def tearDownClass(cls):
        cls.pg.close()

    def setUp(self):
        self.node = "node-%s" % self.id().split(".")[-1][-20:]

    def journal_args(self):
        return ["--store", self.pg.uri, "--node", self.node, "--lease", "2s"]

    def test_takeover_after_the_lease(self):
        rack = bp.TableSetup(preset="pool-9ft", rack="9ball")
        a = self.start()
        created = a.tables.CreateTable(bp.CreateTableRequest(table=rack), timeout=30)
        tid, token = created.table_id, created.seats[0].token
        a.tables.Shoot(bp.ShootRequest(table_id=tid, token=token, strike=BREAK), timeout=10)
        time.sleep(0.5)
        a.kill9()
        b = Server(["--store", self.pg.uri, "--node", self.node + "-b", "--lease", "2s",
                    "--adopt"])
        try:
            wait_adopted(b, tid)
            end = wait_at_rest(b, tid)
            alone = b.tables.SimulateShot(bp.SimulateShotRequest(table=rack, strike=BREAK),
                                          timeout=60)
            self.assertEqual(ball_bits(end.balls), ball_bits(alone.balls))
            b.tables.SetTurn(bp.SetTurnRequest(table_id=tid, token=token, seat=1), timeout=10)
        finally:
            b.stop()

    def test_a_node_that_lost_its_lease_cannot_write(self):
        a = self.start()
        created = a.tables.CreateTable(bp.CreateTableRequest(), timeout=30)
        tid, token = created.table_id, created.seats[0].token
        a.proc.proc.send_signal(signal.SIGSTOP)  # frozen past its lease
        b = Server(["--store", self.pg.uri, "--node", self.node + "-b", "--lease", "2s",
                    "--adopt"])
        try:
            wait_adopted(b, tid)
            a.proc.proc.send_signal(signal.SIGCONT)
            with self.assertRaises(grpc.RpcError) as e:
                a.tables.SetTurn(bp.SetTurnRequest(table_id=tid, token=token, seat=1), timeout=10)
            self.assertEqual(e.exception.code(), grpc.StatusCode.UNAVAILABLE)
            # B serves it, and A's attempt changed nothing.
            self.assertEqual(b.tables.GetTable(bp.GetTableRequest(table_id=tid),
                                               timeout=10).turn, 0)
        finally:
            a.proc.proc.send_signal(signal.SIGCONT)
            a.stop()
            b.stop()

    def test_the_database_stopped_under_a_running_server(self):
        s = self.start()
        try:
            created = s.tables.CreateTable(bp.CreateTableRequest(), timeout=30)
            tid, token = created.table_id, created.seats[0].token
            self.pg.stop()
            try:
                with self.assertRaises(grpc.RpcError) as e:
                    s.tables.SetTurn(bp.SetTurnRequest(table_id=tid, token=token, seat=1),
                                     timeout=15)
                self.assertEqual(e.exception.code(), grpc.StatusCode.UNAVAILABLE)
                self.assertEqual(s.tables.GetTable(bp.GetTableRequest(table_id=tid),
                                                   timeout=10).turn, 0)
                deadline = time.monotonic() + 10
                while s.serving() != health_pb2.HealthCheckResponse.NOT_SERVING:
                    self.assertLess(time.monotonic(), deadline)
                    time.sleep(0.1)
            finally:
                self.pg.start()
            deadline = time.monotonic() + 20
            while s.serving() != health_pb2.HealthCheckResponse.SERVING:
                self.assertLess(time.monotonic(), deadline)
                time.sleep(0.2)
            s.tables.SetTurn(bp.SetTurnRequest(table_id=tid, token=token, seat=1), timeout=10)
        finally:
            s.stop()


if __name__ == "__main__":
    unittest.main(verbosity=2)
