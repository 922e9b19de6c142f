#!/usr/bin/python3
"""Abuse probe: what a real sportsim-server does under heavy, huge or hostile requests.

Runs with Debian's python3-grpcio (/usr/bin/python3: the pyenv python3 on PATH cannot see it).
Generates its Python stubs from proto/ into a temporary directory (protoc + grpc_python_plugin,
as tests/python's build does), starts the given server binary on a free loopback port for each
phase, and prints one JSON document (and a short human summary on stderr).

Phases (--phases, comma-separated; default all):
  latency  16 concurrent heaviest valid SimulateShot calls (8-ball rack, ball speed 20, b 0.5,
           stepped engine, dt 1e-5; --deadline_calls of them with a 3 s deadline), then
           grpc.health.v1.Health/Check and Billiards/GetTable latency on their own channel
           (--checks calls each, one at a time), against an idle baseline of the same calls.
  sigterm  16 such calls queued or running, then SIGTERM: time to exit and the exit code
           (capped at --sigterm_cap seconds; then SIGKILL).
  memory   SimulateShot with 64 moving balls on preset `unbounded`, mu_roll=0, sample_rate_hz
           10000, max_time_s 19.9, --memory_calls times in a row, then --memory_concurrent at
           once: the answers and the server's VmHWM (peak RSS) after each.
  strings  60 kB strings in string fields: every status a default client sees must be short
           (<= 512 bytes) and INVALID_ARGUMENT, and GetInfo on the same channel keeps working.

Usage:
  /usr/bin/python3 bench/abuse_probe.py --server build/bin/sportsim-server [--phases ...]
      [--server_arg=--sim_workers=2 ...] [--cap 120] [--json out.json]
"""
import argparse
import glob
import json
import os
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time

import grpc

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


# ---------------------------------------------------------------------------- stubs
def load_stubs():
    """protoc + grpc_python_plugin into a temporary directory, then import."""
    out = tempfile.mkdtemp(prefix="abuse-probe-stubs-")
    proto_root = os.path.join(ROOT, "proto")
    protos = sorted(glob.glob(os.path.join(proto_root, "sportsim", "v1", "*.proto")))
    plugin = "--plugin=protoc-gen-grpc=/usr/bin/grpc_python_plugin"
    subprocess.run(["protoc", "-I", proto_root, "--python_out=" + out, "--grpc_out=" + out,
                    plugin] + protos, check=True)
    health_dir = os.path.join(proto_root, "grpc", "health", "v1")
    subprocess.run(["protoc", "-I", health_dir, "--python_out=" + out, "--grpc_out=" + out,
                    plugin, os.path.join(health_dir, "health.proto")], check=True)
    sys.path.insert(0, out)
    global health_pb2, health_pb2_grpc, bpb, bgrpc, cpb, cgrpc, spb, sgrpc
    import health_pb2  # noqa: E402
    import health_pb2_grpc  # noqa: E402
    from sportsim.v1 import billiards_pb2 as bpb  # noqa: E402
    from sportsim.v1 import billiards_pb2_grpc as bgrpc  # noqa: E402
    from sportsim.v1 import common_pb2 as cpb  # noqa: E402
    from sportsim.v1 import common_pb2_grpc as cgrpc  # noqa: E402
    from sportsim.v1 import swing_pb2 as spb  # noqa: E402
    from sportsim.v1 import swing_pb2_grpc as sgrpc  # noqa: E402


# ---------------------------------------------------------------------------- the server
class Server:
    """The binary on 127.0.0.1:0 (the port read off its 'listening on' line)."""

    def __init__(self, binary, extra_args, grace="3s"):
        self.log = tempfile.NamedTemporaryFile(prefix="abuse-probe-server-", suffix=".log",
                                               delete=False)
        self.proc = subprocess.Popen(
            [binary, "--listen", "127.0.0.1:0", "--shutdown_grace", grace] + list(extra_args),
            stdout=subprocess.PIPE, stderr=self.log, text=True)
        line = self.proc.stdout.readline()
        m = re.search(r"listening on (\S+):(\d+)$", line.strip())
        if not m:
            self.proc.kill()
            raise RuntimeError("server did not start: %r (log %s)" % (line, self.log.name))
        self.address = "127.0.0.1:%s" % m.group(2)
        # Keep reading stdout so the server never blocks on a full pipe.
        threading.Thread(target=self.proc.stdout.read, daemon=True).start()

    def status(self, key):
        """A /proc/PID/status field in kB (VmHWM, VmRSS), or None once the process is gone."""
        try:
            with open("/proc/%d/status" % self.proc.pid) as f:
                for line in f:
                    if line.startswith(key + ":"):
                        return int(line.split()[1])
        except OSError:
            return None
        return None

    def cpu_s(self):
        try:
            with open("/proc/%d/stat" % self.proc.pid) as f:
                fields = f.read().rsplit(")", 1)[1].split()
            return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
        except OSError:
            return None

    def stop(self, sig=signal.SIGTERM, cap=30.0):
        """Sends sig; returns (exit code or None, seconds); SIGKILL after cap seconds."""
        if self.proc.poll() is not None:
            return self.proc.returncode, 0.0
        t0 = time.monotonic()
        self.proc.send_signal(sig)
        try:
            self.proc.wait(timeout=cap)
            return self.proc.returncode, time.monotonic() - t0
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            return None, time.monotonic() - t0

    def log_tail(self, n=5):
        with open(self.log.name, errors="replace") as f:
            return f.read().splitlines()[-n:]


# ---------------------------------------------------------------------------- requests
def heavy_shot():
    """The heaviest valid SimulateShot: a full 8-ball break at 20 m/s with draw, stepped at 10 us."""
    return bpb.SimulateShotRequest(
        table=bpb.TableSetup(preset="pool-9ft", rack="8ball"),
        strike=bpb.CueStrike(ball_speed_mps=20.0, b=0.5),
        solver=bpb.SolverConfig(engine=bpb.ENGINE_STEPPED, dt_s=1e-5))


def amplification_shot():
    """64 balls moving in parallel forever (mu_roll 0, no cushions), sampled at 10 kHz for 19.9 s."""
    balls, motions = [], []
    for i in range(64):
        bid = "cue" if i == 0 else "b%d" % i
        balls.append(bpb.BallPlacement(id=bid, x_m=(i % 8) * 0.2, y_m=(i // 8) * 0.2))
        motions.append(bpb.BallMotion(id=bid, vx_mps=1.0))
    return bpb.SimulateShotRequest(
        table=bpb.TableSetup(preset="unbounded", rack="empty", balls=balls,
                             params={"mu_roll": 0.0}),
        motions=motions, sample_rate_hz=10000, max_time_s=19.9)


def percentiles(xs):
    if not xs:
        return {}
    s = sorted(xs)

    def q(p):
        return s[min(len(s) - 1, int(round(p / 100.0 * (len(s) - 1))))]
    return {"n": len(s), "p50_ms": round(q(50) * 1e3, 2), "p90_ms": round(q(90) * 1e3, 2),
            "p99_ms": round(q(99) * 1e3, 2), "max_ms": round(s[-1] * 1e3, 2),
            "mean_ms": round(statistics.mean(s) * 1e3, 2)}


def timed_calls(fns, n, timeout, interval=0.0):
    """n rounds of each named call in fns, one call at a time, interval seconds apart."""
    lat = {name: [] for name in fns}
    errors = {name: {} for name in fns}
    for _ in range(n):
        for name, fn in fns.items():
            t0 = time.monotonic()
            try:
                fn(timeout)
                lat[name].append(time.monotonic() - t0)
            except grpc.RpcError as e:
                errors[name][e.code().name] = errors[name].get(e.code().name, 0) + 1
            if interval:
                time.sleep(interval)
    out = {}
    for name in fns:
        out[name] = percentiles(lat[name])
        out[name]["errors"] = errors[name]
    return out


class HeavyCalls:
    """n SimulateShot futures on their own channel; records each outcome and when it came."""

    def __init__(self, address, n, deadline_calls, cap):
        self.channel = grpc.insecure_channel(address)
        stub = bgrpc.BilliardsStub(self.channel)
        self.t0 = time.monotonic()
        self.outcomes = [None] * n
        self.futures = []
        for i in range(n):
            timeout = 3.0 if i < deadline_calls else cap
            fut = stub.SimulateShot.future(heavy_shot(), timeout=timeout)
            fut.add_done_callback(self._done(i, timeout))
            self.futures.append(fut)

    def _done(self, i, timeout):
        def cb(fut):
            t = round(time.monotonic() - self.t0, 2)
            if fut.cancelled():
                self.outcomes[i] = {"deadline_s": timeout, "code": "CANCELLED(client)", "t_s": t}
                return
            e = fut.exception()
            if e is None:
                self.outcomes[i] = {"deadline_s": timeout, "code": "OK", "t_s": t}
            else:
                self.outcomes[i] = {"deadline_s": timeout, "code": e.code().name, "t_s": t,
                                    "message": (e.details() or "")[:160]}
        return cb

    def cancel(self):
        for f in self.futures:
            f.cancel()

    def summary(self):
        by = {}
        for o in self.outcomes:
            key = "pending" if o is None else "%s (deadline %gs)" % (o["code"], o["deadline_s"])
            by.setdefault(key, []).append(None if o is None else o["t_s"])
        return {k: {"count": len(v), "t_s": sorted(x for x in v if x is not None)}
                for k, v in by.items()}

    def messages(self):
        return sorted({o["message"] for o in self.outcomes if o and o.get("message")})


def loadavg():
    with open("/proc/loadavg") as f:
        return f.read().split()[0]


# ---------------------------------------------------------------------------- phases
def phase_latency(args):
    srv = Server(args.server, args.server_arg)
    try:
        ch = grpc.insecure_channel(srv.address)
        grpc.channel_ready_future(ch).result(timeout=30)
        health = health_pb2_grpc.HealthStub(ch)
        billiards = bgrpc.BilliardsStub(ch)
        table_id = billiards.CreateTable(
            bpb.CreateTableRequest(table=bpb.TableSetup(preset="pool-9ft", rack="8ball")),
            timeout=10).table_id

        def check(timeout):
            health.Check(health_pb2.HealthCheckRequest(), timeout=timeout)

        def get_table(timeout):
            billiards.GetTable(bpb.GetTableRequest(table_id=table_id), timeout=timeout)

        fns = {"health": check, "get_table": get_table}
        res = {"idle": timed_calls(fns, args.checks, 5, args.interval)}
        res["idle"]["loadavg_1min_at_start"] = loadavg()
        heavy = HeavyCalls(srv.address, args.heavy, args.deadline_calls, args.cap)
        time.sleep(1.0)  # let them reach the server and the pool
        load0, cpu0, t0 = loadavg(), srv.cpu_s(), time.monotonic()
        res["saturated"] = timed_calls(fns, args.checks, 5, args.interval)
        dt = time.monotonic() - t0
        cpu1 = srv.cpu_s()
        res["saturated"]["measured_for_s"] = round(dt, 2)
        res["saturated"]["interval_s"] = args.interval
        res["saturated"]["loadavg_1min_at_start"] = load0
        if cpu0 is not None and cpu1 is not None:
            res["saturated"]["server_cpu_cores_busy"] = round((cpu1 - cpu0) / dt, 2)
        res["saturated"]["heavy_calls_during"] = heavy.summary()
        # Then wait for the heavy calls (the pool's CPU budget ends each), capped.
        deadline = time.monotonic() + args.cap
        while time.monotonic() < deadline and any(o is None for o in heavy.outcomes):
            time.sleep(0.5)
        res["heavy_calls_final"] = heavy.summary()
        res["heavy_call_messages"] = heavy.messages()
        heavy.cancel()
        heavy.channel.close()
        ch.close()
        return res
    finally:
        code, secs = srv.stop(signal.SIGKILL, 10)


def phase_sigterm(args):
    srv = Server(args.server, args.server_arg, grace="3s")
    try:
        ch = grpc.insecure_channel(srv.address)
        grpc.channel_ready_future(ch).result(timeout=30)
        heavy = HeavyCalls(srv.address, args.heavy, 0, args.cap)
        time.sleep(1.5)
        pending_before = sum(o is None for o in heavy.outcomes)
        code, secs = srv.stop(signal.SIGTERM, args.sigterm_cap)
        time.sleep(0.5)
        res = {"calls_in_flight_at_sigterm": pending_before,
               "exit_code": code if code is not None else "killed after %gs" % args.sigterm_cap,
               "seconds_to_exit": round(secs, 2), "grace_s": 3,
               "within_grace_plus_1s": code is not None and secs <= 4.0,
               "heavy_calls": heavy.summary(), "messages": heavy.messages(),
               "server_log_tail": srv.log_tail(3)}
        heavy.cancel()
        heavy.channel.close()
        ch.close()
        return res
    finally:
        srv.stop(signal.SIGKILL, 5)


def phase_memory(args):
    srv = Server(args.server, args.server_arg)
    try:
        ch = grpc.insecure_channel(srv.address)
        grpc.channel_ready_future(ch).result(timeout=30)
        stub = bgrpc.BilliardsStub(ch)
        res = {"vmhwm_idle_mb": round(srv.status("VmHWM") / 1024, 1), "calls": []}
        for k in range(args.memory_calls + 1):
            concurrent = k == args.memory_calls  # the last round: --memory_concurrent at once
            peak_rss = [0]
            stop = threading.Event()

            def watch():
                while not stop.is_set():
                    v = srv.status("VmRSS")
                    if v:
                        peak_rss[0] = max(peak_rss[0], v)
                    time.sleep(0.05)
            w = threading.Thread(target=watch, daemon=True)
            w.start()
            t0 = time.monotonic()
            call = {"call": k + 1}
            if concurrent:
                call["concurrent"] = args.memory_concurrent
                futs = [stub.SimulateShot.future(amplification_shot(), timeout=args.cap)
                        for _ in range(args.memory_concurrent)]
                codes = {}
                for f in futs:
                    e = f.exception()
                    c = "OK" if e is None else e.code().name
                    codes[c] = codes.get(c, 0) + 1
                call["codes"] = codes
            else:
                try:
                    r = stub.SimulateShot(amplification_shot(), timeout=args.cap)
                    call.update(code="OK", samples=len(r.samples), bytes=r.ByteSize())
                except grpc.RpcError as e:
                    call.update(code=e.code().name, message=(e.details() or "")[:300])
            call["seconds"] = round(time.monotonic() - t0, 2)
            time.sleep(0.3)
            stop.set()
            w.join()
            call["vmhwm_mb"] = round((srv.status("VmHWM") or 0) / 1024, 1)
            call["vmrss_after_mb"] = round((srv.status("VmRSS") or 0) / 1024, 1)
            call["peak_vmrss_seen_mb"] = round(peak_rss[0] / 1024, 1)
            res["calls"].append(call)
        res["server_alive"] = srv.proc.poll() is None
        ch.close()
        return res
    finally:
        srv.stop(signal.SIGKILL, 5)


def string_cases(big, table_id, token, session_id):
    """(field, rpc name, callable(stub set, timeout)) for each 60 kB string field."""
    B, S = bpb, spb
    ok_table = B.TableSetup(preset="pool-9ft", rack="8ball")
    cases = [
        ("SimulateShot table.preset", "b", "SimulateShot",
         B.SimulateShotRequest(table=B.TableSetup(preset=big))),
        ("SimulateShot table.rack", "b", "SimulateShot",
         B.SimulateShotRequest(table=B.TableSetup(rack=big))),
        ("SimulateShot table.balls[].id", "b", "SimulateShot",
         B.SimulateShotRequest(table=B.TableSetup(rack="empty", balls=[
             B.BallPlacement(id=big, x_m=0, y_m=0)]))),
        ("SimulateShot table.params key", "b", "SimulateShot",
         B.SimulateShotRequest(table=B.TableSetup(params={big: 1.0}))),
        ("SimulateShot solver.disable[]", "b", "SimulateShot",
         B.SimulateShotRequest(table=ok_table, solver=B.SolverConfig(disable=[big]))),
        ("SimulateShot solver.enable[]", "b", "SimulateShot",
         B.SimulateShotRequest(table=ok_table, solver=B.SolverConfig(enable=[big]))),
        ("SimulateShot strike.ball", "b", "SimulateShot",
         B.SimulateShotRequest(table=ok_table, strike=B.CueStrike(ball=big, ball_speed_mps=1))),
        ("SimulateShot motions[].id", "b", "SimulateShot",
         B.SimulateShotRequest(table=ok_table, motions=[B.BallMotion(id=big, vx_mps=1)])),
        ("SimulateShots table.preset", "b", "SimulateShots",
         B.SimulateShotsRequest(table=B.TableSetup(preset=big),
                                strikes=[B.CueStrike(ball_speed_mps=1)])),
        ("CreateTable seat_names[]", "b", "CreateTable",
         B.CreateTableRequest(table=ok_table, seat_names=[big])),
        ("CreateTable game.name", "b", "CreateTable",
         B.CreateTableRequest(game=B.GameConfig(name=big))),
        ("CreateTable game.start", "b", "CreateTable",
         B.CreateTableRequest(game=B.GameConfig(name="8ball", start=big))),
        ("CreateTable game.rules key", "b", "CreateTable",
         B.CreateTableRequest(game=B.GameConfig(name="8ball", rules={big: "x"}))),
        ("CreateTable game.rules value", "b", "CreateTable",
         B.CreateTableRequest(game=B.GameConfig(name="8ball", rules={"break": big}))),
        ("GetTable table_id", "b", "GetTable", B.GetTableRequest(table_id=big)),
        ("ListTables page_token", "b", "ListTables", B.ListTablesRequest(page_token=big)),
        ("PlaceBall ball.id", "b", "PlaceBall",
         B.PlaceBallRequest(table_id=table_id, token=token,
                            ball=B.BallPlacement(id=big, x_m=0, y_m=0))),
        ("PlaceBall token", "b", "PlaceBall",
         B.PlaceBallRequest(table_id=table_id, token=big,
                            ball=B.BallPlacement(id="cue", x_m=0, y_m=0))),
        ("Shoot strike.ball", "b", "Shoot",
         B.ShootRequest(table_id=table_id, token=token,
                        strike=B.CueStrike(ball=big, ball_speed_mps=1))),
        ("Decide choice", "b", "Decide",
         B.DecideRequest(table_id=table_id, token=token, choice=big)),
        ("SimulateSwing ball.club", "s", "SimulateSwing",
         S.SimulateSwingRequest(ball=S.BallStrike(club=big))),
        ("CreateSession seat_names[]", "s", "CreateSession",
         S.CreateSessionRequest(seat_names=[big])),
        ("CreateSession ball.club", "s", "CreateSession",
         S.CreateSessionRequest(ball=S.BallStrike(club=big))),
        ("GetSession session_id", "s", "GetSession", S.GetSessionRequest(session_id=big)),
        ("StartSwing token", "s", "StartSwing",
         S.StartSwingRequest(session_id=session_id, token=big)),
    ]
    return cases


def phase_strings(args):
    srv = Server(args.server, args.server_arg)
    try:
        ch = grpc.insecure_channel(srv.address)  # a default client: 8 KiB metadata limit
        grpc.channel_ready_future(ch).result(timeout=30)
        stubs = {"b": bgrpc.BilliardsStub(ch), "s": sgrpc.SwingStub(ch)}
        info = cgrpc.ServerStub(ch)
        created = stubs["b"].CreateTable(
            bpb.CreateTableRequest(table=bpb.TableSetup(preset="pool-9ft", rack="8ball")),
            timeout=10)
        token = created.seats[0].token if created.seats else created.admin_token
        session = stubs["s"].CreateSession(spb.CreateSessionRequest(), timeout=10)
        big = "x" * args.string_bytes
        rows, bad = [], 0
        for field, svc, rpc, req in string_cases(big, created.table_id, token,
                                                 session.session_id):
            method = getattr(stubs[svc], rpc)
            row = {"field": field}
            try:
                r = method(req, timeout=30)
                if rpc == "SimulateShots":
                    r = list(r)
                row.update(code="OK", len=0)
            except grpc.RpcError as e:
                d = e.details() or ""
                row.update(code=e.code().name, len=len(d.encode()), message=d[:120])
            try:
                info.GetInfo(cpb.GetInfoRequest(), timeout=10)
                row["channel_ok_after"] = True
            except grpc.RpcError as e:
                row["channel_ok_after"] = e.code().name
            row["pass"] = (row["code"] == "INVALID_ARGUMENT" and row["len"] <= 512 and
                           row["channel_ok_after"] is True)
            bad += not row["pass"]
            rows.append(row)
        return {"string_bytes": args.string_bytes, "fields": len(rows), "failing": bad,
                "longest_message": max(r["len"] for r in rows), "rows": rows}
    finally:
        srv.stop(signal.SIGKILL, 5)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--server", default=os.path.join(ROOT, "build", "bin", "sportsim-server"))
    ap.add_argument("--server_arg", action="append", default=[],
                    help="extra server flag (repeat), e.g. --server_arg=--sim_workers=2")
    ap.add_argument("--phases", default="latency,sigterm,memory,strings")
    ap.add_argument("--heavy", type=int, default=16)
    ap.add_argument("--deadline_calls", type=int, default=4,
                    help="heavy calls with a 3 s deadline (the rest: --cap)")
    ap.add_argument("--checks", type=int, default=300,
                    help="health checks and GetTable calls each, while saturated")
    ap.add_argument("--interval", type=float, default=0.05,
                    help="pause after each check (s), so they spread over the saturation")
    ap.add_argument("--memory_calls", type=int, default=3,
                    help="amplification calls one after another (then one concurrent round)")
    ap.add_argument("--memory_concurrent", type=int, default=8)
    ap.add_argument("--cap", type=float, default=120.0, help="deadline of the other calls (s)")
    ap.add_argument("--sigterm_cap", type=float, default=30.0)
    ap.add_argument("--string_bytes", type=int, default=60000)
    ap.add_argument("--json", help="also write the result here")
    args = ap.parse_args()
    load_stubs()
    out = {"server": os.path.abspath(args.server), "server_args": args.server_arg,
           "nproc": os.cpu_count(), "loadavg_at_start": loadavg()}
    phases = {"latency": phase_latency, "sigterm": phase_sigterm, "memory": phase_memory,
              "strings": phase_strings}
    for name in args.phases.split(","):
        t0 = time.monotonic()
        print("abuse_probe: %s ..." % name, file=sys.stderr, flush=True)
        try:
            out[name] = phases[name](args)
        except Exception as e:  # a phase that breaks is a result too
            out[name] = {"error": "%s: %s" % (type(e).__name__, e)}
        out[name]["phase_seconds"] = round(time.monotonic() - t0, 1)
        print("abuse_probe: %s done in %.1fs" % (name, time.monotonic() - t0), file=sys.stderr,
              flush=True)
    text = json.dumps(out, indent=1)
    print(text)
    if args.json:
        with open(args.json, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
