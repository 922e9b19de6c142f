#!/usr/bin/python3
"""Bot throughput: candidate shots per second a Python grpcio client gets from sportsim-server.

The workload of a billiards bot: random cue strikes on a 9-ball rack (pool-9ft), each
fast-forwarded to rest with the SUMMARY outcome (first contact, pocketed balls, when at rest).
Measured three ways, each over the same candidates:
  batch       Billiards/SimulateShots, --batch strikes per call (default 1000), the stream read
              to its end; one call at a time.
  unary       Billiards/SimulateShot, one call per candidate, one at a time (a plain loop).
  unary_par   Billiards/SimulateShot, one call per candidate, --inflight calls in flight
              (grpcio futures).
Each way runs --runs times (default 5); the report gives every run and the median, in
candidates per second of wall time, with the machine (CPU model, cores) and the server flags.

Runs with Debian's python3-grpcio (/usr/bin/python3). Generates its Python stubs from proto/
into a temporary directory (protoc + grpc_python_plugin, as the build does for tests/python),
starts the given server binary on a free loopback port (or uses --address), and prints one
JSON document on stdout and a table on stderr.

Usage:
  /usr/bin/python3 bench/bot_throughput.py --server build/bin/sportsim-server
      [--candidates 5000] [--batch 1000] [--runs 5] [--inflight 8] [--server_arg=--sim_workers=2]
  /usr/bin/python3 bench/bot_throughput.py --address 127.0.0.1:50051
"""
import argparse
import glob
import json
import os
import platform
import random
import re
import statistics
import subprocess
import sys
import tempfile
import time

import grpc

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def load_stubs():
    """protoc + grpc_python_plugin into a temporary directory, then import."""
    out = tempfile.mkdtemp(prefix="bot-throughput-stubs-")
    proto_root = os.path.join(ROOT, "proto")
    protos = sorted(glob.glob(os.path.join(proto_root, "sportsim", "v1", "*.proto")))
    subprocess.run(["protoc", "-I", proto_root, "--python_out=" + out, "--grpc_out=" + out,
                    "--plugin=protoc-gen-grpc=/usr/bin/grpc_python_plugin"] + protos,
                   check=True)
    sys.path.insert(0, out)
    from sportsim.v1 import billiards_pb2, billiards_pb2_grpc  # noqa: E402
    return billiards_pb2, billiards_pb2_grpc


class Server:
    """The binary on 127.0.0.1:0 (the port read off its 'listening on' line)."""

    def __init__(self, binary, extra_args):
        self.proc = subprocess.Popen([binary, "--listen", "127.0.0.1:0", *extra_args],
                                     stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        line = self.proc.stdout.readline()
        m = re.search(r"listening on (\S+):(\d+)$", line.strip())
        if not m:
            self.proc.kill()
            raise RuntimeError("server did not start: %r" % line)
        self.address = "127.0.0.1:%s" % m.group(2)

    def stop(self):
        self.proc.terminate()
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


def machine():
    model = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {"cpu": model, "cores": os.cpu_count(), "kernel": platform.release(),
            "python": platform.python_version(), "grpcio": grpc.__version__}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--server", default=os.path.join(ROOT, "build", "bin", "sportsim-server"))
    ap.add_argument("--server_arg", action="append", default=[],
                    help="a flag for the server (repeatable), e.g. --server_arg=--sim_workers=2")
    ap.add_argument("--address", help="use a running server instead of starting one")
    ap.add_argument("--candidates", type=int, default=5000, help="candidates per run")
    ap.add_argument("--batch", type=int, default=1000, help="strikes per SimulateShots call")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--inflight", type=int, default=8, help="unary_par: calls in flight")
    ap.add_argument("--ways", default="batch,unary,unary_par")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()

    pb, pb_grpc = load_stubs()
    server = None if args.address else Server(args.server, args.server_arg)
    address = args.address or server.address
    try:
        channel = grpc.insecure_channel(address)
        grpc.channel_ready_future(channel).result(timeout=30)
        stub = pb_grpc.BilliardsStub(channel)
        table = pb.TableSetup(preset="pool-9ft", rack="9ball")
        rng = random.Random(args.seed)
        strikes = [pb.CueStrike(ball_speed_mps=rng.uniform(0.5, 6.0),
                                phi_deg=rng.uniform(-180, 180),
                                a=rng.uniform(-0.3, 0.3), b=rng.uniform(-0.3, 0.3))
                   for _ in range(args.candidates)]

        def run_batch():
            n = 0
            for i in range(0, len(strikes), args.batch):
                req = pb.SimulateShotsRequest(table=table, strikes=strikes[i:i + args.batch],
                                              outcome=pb.SHOT_OUTCOME_SUMMARY)
                for response in stub.SimulateShots(req, timeout=600):
                    n += len(response.outcomes)
            return n

        def run_unary():
            for s in strikes:
                stub.SimulateShot(pb.SimulateShotRequest(table=table, strike=s), timeout=60)
            return len(strikes)

        def run_unary_par():
            pending = []
            done = 0
            for s in strikes:
                pending.append(stub.SimulateShot.future(
                    pb.SimulateShotRequest(table=table, strike=s), timeout=60))
                if len(pending) >= args.inflight:
                    pending.pop(0).result()
                    done += 1
            for f in pending:
                f.result()
                done += 1
            return done

        ways = {"batch": run_batch, "unary": run_unary, "unary_par": run_unary_par}
        chosen = [w for w in args.ways.split(",") if w]
        results = {}
        for way in chosen:
            rates = []
            for _ in range(args.runs):
                t0 = time.perf_counter()
                n = ways[way]()
                dt = time.perf_counter() - t0
                assert n == len(strikes), (way, n)
                rates.append(n / dt)
            results[way] = {"runs_per_s": [round(r, 1) for r in rates],
                            "median_per_s": round(statistics.median(rates), 1)}
        report = {"machine": machine(), "server_args": args.server_arg,
                  "workload": {"table": "pool-9ft", "rack": "9ball", "outcome": "summary",
                               "candidates": args.candidates, "batch": args.batch,
                               "inflight": args.inflight, "seed": args.seed},
                  "results": results}
        print(json.dumps(report, indent=2))
        m = report["machine"]
        print("%s, %s cores; %d candidates a run, %d runs" %
              (m["cpu"], m["cores"], args.candidates, args.runs), file=sys.stderr)
        for way, r in results.items():
            print("  %-10s median %9.1f candidates/s  (runs: %s)" %
                  (way, r["median_per_s"], ", ".join("%.0f" % x for x in r["runs_per_s"])),
                  file=sys.stderr)
    finally:
        if server is not None:
            server.stop()


if __name__ == "__main__":
    main()
