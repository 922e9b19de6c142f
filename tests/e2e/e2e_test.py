"""End to end: the real sportsim-server binary on a free loopback port, the real sportsim CLI
against it, checking the JSON of DESIGN.md's command-line contract, exit codes and signals."""
import csv
import io
import json
import os
import signal
import socket
import subprocess
import sys
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "support"))
from server_proc import ServerProcess  # noqa: E402

BIN = os.environ["SPORTSIM_BIN_DIR"]
SERVER = os.path.join(BIN, "sportsim-server")
CLI = os.path.join(BIN, "sportsim")


def cli(address, *args):
    return subprocess.run([CLI, "--server", address, *args], capture_output=True, text=True,
                          timeout=60)


class CliAgainstServer(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = ServerProcess(SERVER)

    @classmethod
    def tearDownClass(cls):
        cls.server.__exit__()

    def test_info_json(self):
        r = cli(self.server.address, "info", "--format", "json")
        self.assertEqual(r.returncode, 0, r.stderr)
        info = json.loads(r.stdout)
        self.assertEqual(info["version"], "0.1.0")
        caps = info["capabilities"]
        self.assertEqual(caps["swing_integrators"],
                         ["book", "euler", "semi_implicit_euler", "rk4", "dp45"])
        for key in ("engines", "integrators", "table_presets", "racks"):
            self.assertIn(key, caps)  # present even while empty

    def test_health(self):
        r = cli(self.server.address, "health")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(r.stdout.strip(), "SERVING")

    def test_swing_simulate_json_contract(self):
        r = cli(self.server.address, "swing", "simulate", "--integrator", "rk4", "--dt", "0.0025",
                "--format", "json")
        self.assertEqual(r.returncode, 0, r.stderr)
        out = json.loads(r.stdout)
        impact = out["impact"]
        for key in ("t_s", "alpha_deg", "beta_deg", "theta_deg", "phi_deg", "alpha_dot_rps",
                    "beta_dot_rps", "clubhead_speed_mps", "clubhead_speed_ground_mps"):
            self.assertIn(key, impact)
        # The chapter swing's converged impact: 0.291391708 s, 42.5163 m/s (docs/swing-accuracy.md);
        # rk4 at the chapter's step is within 2e-8 s and 5e-5 m/s of it.
        self.assertAlmostEqual(impact["t_s"], 0.2913917080, delta=2e-8)
        self.assertAlmostEqual(impact["clubhead_speed_mps"], 42.51627469, delta=5e-5)
        self.assertIsInstance(out["steps"], int)
        self.assertEqual(out["steps"], 117)
        self.assertGreater(out["cpu_s"], 0)
        s0 = out["samples"][0]
        for key in ("t_s", "theta_deg", "alpha_deg", "beta_deg", "phi_deg", "clubhead_speed_mps"):
            self.assertIn(key, s0)
        self.assertEqual(s0["t_s"], 0)
        self.assertAlmostEqual(s0["theta_deg"], 135, places=9)
        self.assertAlmostEqual(s0["phi_deg"], 255, places=9)

    def test_swing_simulate_csv(self):
        r = cli(self.server.address, "--format", "csv", "swing", "simulate", "--integrator",
                "book", "--until", "duration", "--duration", "0.5")
        self.assertEqual(r.returncode, 0, r.stderr)
        rows = list(csv.reader(io.StringIO(r.stdout)))
        self.assertEqual(rows[0], ["t_s", "theta_deg", "alpha_deg", "beta_deg", "phi_deg",
                                   "clubhead_speed_mps"])
        self.assertEqual(len(rows), 1 + 201)  # the chapter's 200 steps plus the start
        self.assertAlmostEqual(float(rows[-1][0]), 0.5, places=12)

    def test_flight_simulate_json_contract(self):
        r = cli(self.server.address, "flight", "simulate", "--ball-speed", "74.66", "--launch-deg",
                "10.9", "--spin-rpm", "2686", "--spin-axis-deg", "-3", "--wind", "4,180",
                "--format", "json")
        self.assertEqual(r.returncode, 0, r.stderr)
        out = json.loads(r.stdout)
        for key in ("carry_m", "apex_m", "flight_time_s", "landing_angle_deg", "lateral_m",
                    "samples"):
            self.assertIn(key, out)
        self.assertLess(out["lateral_m"], 0)  # negative tilt draws left
        self.assertGreater(out["carry_m"], 150)
        self.assertEqual(out["samples"][0]["t_s"], 0)
        r = cli(self.server.address, "--format", "csv", "flight", "simulate", "--ball-speed",
                "50", "--launch-deg", "20", "--spin-rpm", "5000")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertTrue(r.stdout.startswith("t_s,x_m,y_m,z_m,"))
        r = cli(self.server.address, "flight", "simulate", "--ball-speed", "50")
        self.assertEqual(r.returncode, 64)
        self.assertIn("needs --ball-speed, --launch-deg and --spin-rpm", r.stderr)

    def test_dashed_flags_and_negative_values(self):
        r = cli(self.server.address, "swing", "simulate", "--qbeta", "-20", "--qbeta-until",
                "0.05", "--shoulder-accel", "0", "--format", "json")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("impact", json.loads(r.stdout))

    def test_server_error_has_code_name_and_exit_status(self):
        r = cli(self.server.address, "swing", "simulate", "--dt", "0.5")
        self.assertEqual(r.returncode, 3)  # INVALID_ARGUMENT
        self.assertTrue(r.stderr.startswith("sportsim: INVALID_ARGUMENT: solver.dt_s"), r.stderr)
        self.assertEqual(r.stdout, "")

    def test_usage_error(self):
        r = cli(self.server.address, "swing", "simulate", "--integrator", "leapfrog")
        self.assertEqual(r.returncode, 64)
        self.assertIn("--integrator must be", r.stderr)

    def test_unreachable_server(self):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]  # bound, not listening: nothing answers
            r = cli("127.0.0.1:%d" % port, "--timeout", "2s", "health")
        self.assertNotEqual(r.returncode, 0)
        self.assertRegex(r.stderr, r"^sportsim: (UNAVAILABLE|DEADLINE_EXCEEDED): ")


class ServerLifecycle(unittest.TestCase):
    def test_bad_listen_is_one_clear_line(self):
        for bad in ("nonsense", "127.0.0.1:99999", "[::1"):
            r = subprocess.run([SERVER, "--listen", bad], capture_output=True, text=True,
                               timeout=30)
            self.assertNotEqual(r.returncode, 0, bad)
            lines = r.stderr.strip().splitlines()
            self.assertEqual(len(lines), 1, r.stderr)
            self.assertIn("--listen must be host:port", lines[0])

    def test_port_in_use_is_one_clear_line(self):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            s.listen()
            port = s.getsockname()[1]
            r = subprocess.run([SERVER, "--listen", "127.0.0.1:%d" % port], capture_output=True,
                               text=True, timeout=30)
        self.assertNotEqual(r.returncode, 0)
        lines = r.stderr.strip().splitlines()
        self.assertEqual(len(lines), 1, r.stderr)
        self.assertIn("cannot listen on 127.0.0.1:%d: Address already in use" % port, lines[0])

    def test_sigterm_and_sigint_exit_zero(self):
        for sig in (signal.SIGTERM, signal.SIGINT):
            with ServerProcess(SERVER) as server:
                self.assertEqual(cli(server.address, "health").returncode, 0)
                code, seconds, out = server.terminate(sig)
                self.assertEqual(code, 0)
                self.assertLess(seconds, 5)
                self.assertIn("stopped", out)


if __name__ == "__main__":
    unittest.main(verbosity=2)
