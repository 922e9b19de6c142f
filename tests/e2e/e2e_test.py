"""End to end: the real sportsim-server binary on a free loopback port, the real sportsim CLI
against it, checking the JSON of the command-line contract (docs/cli.md), exit codes and signals."""
import csv
import io
import json
import math
import os
import re
import select
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "support"))
from server_proc import ServerProcess  # noqa: E402

BIN = os.environ["SPORTSIM_BIN_DIR"]
SERVER = os.path.join(BIN, "sportsim-server")
CLI = os.path.join(BIN, "sportsim")


def cli(address, *args):
    return subprocess.run([CLI, "--server", address, *args], capture_output=True, text=True,
                          timeout=60)


# A straight 2 m/s full-ball shot on an otherwise empty 9 ft table: cue at (-0.5, 0), 1 at (0, 0).
STRAIGHT_SHOT = ("shot", "simulate", "--table", "pool-9ft", "--rack", "empty", "--ball",
                 "cue@-0.5,0", "--ball", "1@0,0", "--ball-speed", "2")
MOTION_STATES = {"stationary", "spinning", "sliding", "rolling", "airborne", "pocketed"}
EVENT_KINDS = {"ball_ball", "ball_cushion", "ball_pocket", "transition"}
SVG_NS = "{http://www.w3.org/2000/svg}"


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
        self.assertEqual(caps["golf_courses"][0], "sportsim_links")
        self.assertIn("bunker", caps["golf_surfaces"])

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
        with tempfile.TemporaryDirectory() as d:
            svg = os.path.join(d, "flight.svg")
            r = cli(self.server.address, "flight", "simulate", "--ball-speed", "60",
                    "--launch-deg", "14", "--spin-rpm", "4000", "--spin-axis-deg", "10",
                    "--svg", svg)
            self.assertEqual(r.returncode, 0, r.stderr)
            with open(svg) as f:
                text = f.read()
            self.assertEqual(text.count("<polyline"), 2)  # side and top views
            self.assertIn("right</text>", text)  # the landing, right of the target line
        r = cli(self.server.address, "flight", "simulate", "--ball-speed", "50")
        self.assertEqual(r.returncode, 64)
        self.assertIn("needs --ball-speed, --launch-deg and --spin-rpm", r.stderr)

    def test_course_list_and_show_json_contract(self):
        r = cli(self.server.address, "--format", "json", "course", "list")
        self.assertEqual(r.returncode, 0, r.stderr)
        names = [c["name"] for c in json.loads(r.stdout)["courses"]]
        self.assertEqual(names[0], "sportsim_links")
        self.assertIn("practice", names)
        r = cli(self.server.address, "--format", "json", "course", "show", "sportsim_links")
        self.assertEqual(r.returncode, 0, r.stderr)
        course = json.loads(r.stdout)
        self.assertEqual(course["name"], "sportsim_links")
        self.assertEqual(sorted(h["par"] for h in course["holes"]), [3, 4, 5])
        for hole in course["holes"]:
            for key in ("number", "par", "stroke_index", "tees", "pin", "length_m"):
                self.assertIn(key, hole)
            self.assertEqual(set(hole["pin"]), {"x_m", "y_m", "z_m"})
            self.assertEqual(set(hole["tees"][0]), {"name", "x_m", "y_m", "z_m"})
        self.assertIn("green", [s["name"] for s in course["surfaces"]])
        r = cli(self.server.address, "--format", "json", "course", "show", "sportsim_links",
                "--hole", "2")
        self.assertEqual([h["number"] for h in json.loads(r.stdout)["holes"]], [2])
        with tempfile.TemporaryDirectory() as d:
            svg = os.path.join(d, "course.svg")
            r = cli(self.server.address, "course", "show", "sportsim_links", "--hole", "3",
                    "--svg", svg)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("hole 3: par 5", r.stdout)
            root = ET.parse(svg).getroot()
            titles = {t.text for t in root.iter(SVG_NS + "title")}
            self.assertTrue({"green", "bunker", "water_hazard", "lateral_water_hazard"} <= titles)
        r = cli(self.server.address, "course", "show", "augusta")
        self.assertEqual(r.returncode, 5, r.stderr)  # NOT_FOUND
        self.assertIn("NOT_FOUND", r.stderr)

    def test_golf_simulate_on_a_course(self):
        r = cli(self.server.address, "--format", "json", "golf", "simulate", "--course",
                "sportsim_links", "--hole", "2", "--tee", "white", "--ball-speed", "33",
                "--launch-deg", "17", "--spin-rpm", "7000")
        self.assertEqual(r.returncode, 0, r.stderr)
        out = json.loads(r.stdout)
        for key in ("carry_m", "total_m", "lateral_m", "t_rest_s", "rest", "events", "flight",
                    "cpu_s"):
            self.assertIn(key, out)
        self.assertEqual(out["rest"]["lie"], "water_hazard")  # short, into the pond
        self.assertTrue(out["rest"]["penalty_area"])
        self.assertIn("penalty_area", [e["kind"] for e in out["events"]])
        with tempfile.TemporaryDirectory() as d:
            svg = os.path.join(d, "shot.svg")
            r = cli(self.server.address, "golf", "simulate", "--course", "sportsim_links",
                    "--hole", "1", "--ball-speed", "70", "--launch-deg", "12", "--spin-rpm",
                    "2800", "--svg", svg)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("carry", r.stdout)
            root = ET.parse(svg).getroot()
            self.assertEqual(len(list(root.iter(SVG_NS + "polyline"))), 1)
        for args, message in ((("--tee", "gold"), "tee"), (("--hole", "7"), "hole"),
                              (("--tee", "white", "--from", "1,2"), "--tee or --from")):
            r = cli(self.server.address, "golf", "simulate", "--course", "sportsim_links",
                    "--putt-speed", "1", *args)
            self.assertNotEqual(r.returncode, 0)
            self.assertIn(message, r.stderr)

    def test_round_create_stroke_decide_scorecard_record(self):
        a = self.server.address
        r = cli(a, "--format", "json", "round", "create", "--players", "Ann,Bob", "--holes",
                "2-2", "--tees", "white,red", "--fast-forward")
        self.assertEqual(r.returncode, 0, r.stderr)
        made = json.loads(r.stdout)
        for key in ("round_id", "seats", "admin_token"):
            self.assertIn(key, made)
        self.assertEqual([(s["seat"], s["name"]) for s in made["seats"]], [(0, "Ann"), (1, "Bob")])
        rid, ann, bob = made["round_id"], made["seats"][0]["token"], made["seats"][1]["token"]
        # Bob is not first on the tee: refused, naming the Rule; nothing changed.
        r = cli(a, "round", "stroke", rid, "--token", bob, "--putt-speed", "3")
        self.assertEqual(r.returncode, 9, r.stderr)  # FAILED_PRECONDITION
        self.assertIn("Rule 6.4", r.stderr)
        # Ann's tee shot, short into the pond.
        r = cli(a, "round", "stroke", rid, "--token", ann, "--ball-speed", "30", "--launch-deg",
                "20", "--spin-rpm", "5000", "--aim-deg", "88")
        self.assertEqual(r.returncode, 0, r.stderr)
        time.sleep(0.3)
        r = cli(a, "--format", "json", "round", "get", rid)
        self.assertEqual(r.returncode, 0, r.stderr)
        state = json.loads(r.stdout)["round"]
        for key in ("play", "hole", "to_play", "players", "decision", "result", "winner"):
            self.assertIn(key, state)
        for key in ("seat", "name", "strokes", "score", "ball"):
            self.assertIn(key, state["players"][0])
        self.assertEqual(set(state["players"][0]["ball"]) >= {"x_m", "y_m", "z_m", "lie",
                                                              "distance_to_pin_m", "holed"}, True)
        self.assertEqual(state["players"][0]["ball"]["lie"], "water_hazard")
        self.assertEqual(state["decision"]["seat"], 0)
        self.assertEqual(state["decision"]["choices"], ["stroke_and_distance", "back_on_the_line"])
        r = cli(a, "round", "get", rid)
        self.assertIn("Ann must decide", r.stdout)
        self.assertIn("yellow penalty area", r.stdout)
        r = cli(a, "round", "decide", rid, "--token", ann, "--choice", "lateral")
        self.assertEqual(r.returncode, 3, r.stderr)  # a yellow area has no lateral relief
        r = cli(a, "round", "decide", rid, "--token", ann, "--choice", "back_on_the_line")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("Bob to play", r.stdout)
        r = cli(a, "round", "scorecard", rid)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("Ann", r.stdout)
        r = cli(a, "--format", "json", "round", "record", rid)
        record = json.loads(r.stdout)
        self.assertEqual([("stroke" in c, "decide" in c) for c in record["commands"]],
                         [(True, False), (False, True)])
        self.assertEqual(record["commands"][1]["decide"]["choice"], "back_on_the_line")
        r = cli(a, "round", "delete", rid, "--token", ann)
        self.assertEqual(r.returncode, 7, r.stderr)  # PERMISSION_DENIED: the admin deletes
        r = cli(a, "round", "delete", rid, "--token", made["admin_token"])
        self.assertEqual(r.returncode, 0, r.stderr)
        r = cli(a, "round", "create", "--players", "Ann", "--play", "match")
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn("two players", r.stderr)
        r = cli(a, "round", "create", "--players", "Ann", "--play", "skins")
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn("--play", r.stderr)
        r = cli(a, "round", "create")
        self.assertEqual(r.returncode, 64, r.stderr)

    def test_round_match_play_with_handicaps_and_concessions(self):
        a = self.server.address
        r = cli(a, "--format", "json", "round", "create", "--players", "Ann,Bob", "--play",
                "match", "--handicaps", "3.2,+1.5", "--fast-forward")
        self.assertEqual(r.returncode, 0, r.stderr)
        made = json.loads(r.stdout)
        rid, ann, bob = made["round_id"], made["seats"][0]["token"], made["seats"][1]["token"]
        state = made["round"]
        self.assertEqual(state["play"], "match")
        self.assertTrue(state["handicaps"])
        # Ann's index is the higher: she receives the difference, Bob plays off scratch.
        self.assertGreater(state["players"][0]["playing_handicap"], 0)
        self.assertEqual(state["players"][1].get("playing_handicap", 0), 0)
        self.assertEqual(sum(state["players"][0]["received"]),
                         state["players"][0]["playing_handicap"])
        # Ann concedes the first hole, Bob then Ann's next stroke on the second (her ball is
        # holed with it), then the match.
        r = cli(a, "round", "concede", rid, "--token", ann, "--hole")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("Bob 1 up with 2 to play", r.stdout)
        r = cli(a, "--format", "json", "round", "concede", rid, "--token", bob, "--stroke")
        self.assertEqual(r.returncode, 0, r.stderr)
        after = json.loads(r.stdout)["round"]
        self.assertTrue(after["players"][0]["ball"]["holed"])
        self.assertEqual(after["players"][0]["strokes"], 1)
        r = cli(a, "round", "scorecard", rid)
        self.assertIn("hole won by", r.stdout)
        r = cli(a, "round", "concede", rid, "--token", bob, "--match")
        self.assertEqual(r.returncode, 0, r.stderr)
        r = cli(a, "--format", "json", "round", "get", rid)
        state = json.loads(r.stdout)["round"]
        self.assertEqual((state["result"], state["winner"]), ("conceded", 0))
        self.assertIn("Ann won", state["match_status"])
        r = cli(a, "round", "concede", rid, "--token", bob)
        self.assertEqual(r.returncode, 9, r.stderr)  # over
        # This server has no Open Connect listener: binding a monitor says how to start one.
        r = cli(a, "round", "monitor", rid, "--token", bob, "--device", "MEVO-1")
        self.assertEqual(r.returncode, 9, r.stderr)
        self.assertIn("--open_connect_listen", r.stderr)
        r = cli(a, "round", "monitor", rid, "--token", bob)
        self.assertEqual(r.returncode, 64, r.stderr)
        # Concessions are match play's; picking up is Stableford's.
        r = cli(a, "--format", "json", "round", "create", "--players", "Cat,Dan", "--play",
                "stableford", "--holes", "2-2", "--fast-forward")
        made = json.loads(r.stdout)
        rid, cat = made["round_id"], made["seats"][0]["token"]
        r = cli(a, "round", "concede", rid, "--token", cat, "--hole")
        self.assertEqual(r.returncode, 9, r.stderr)
        self.assertIn("3.2b", r.stderr)
        r = cli(a, "round", "stroke", rid, "--token", cat, "--ball-speed", "3", "--launch-deg",
                "20", "--spin-rpm", "1000")
        self.assertEqual(r.returncode, 0, r.stderr)
        time.sleep(0.3)
        r = cli(a, "--format", "json", "round", "pickup", rid, "--token", cat)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertTrue(json.loads(r.stdout)["round"]["players"][0]["ball"]["picked_up"])

    def test_info_lists_billiards(self):
        r = cli(self.server.address, "info", "--format", "json")
        self.assertEqual(r.returncode, 0, r.stderr)
        caps = json.loads(r.stdout)["capabilities"]
        self.assertEqual(caps["engines"], ["event", "stepped"])
        self.assertIn("pool-9ft", caps["table_presets"])
        self.assertIn("chapter19", caps["racks"])
        self.assertIn("squirt", caps["effects"])
        names = {p["name"] for p in caps["parameters"]}
        for name in ("gravity_mps2", "mu_slide", "mu_roll", "spin_decel_rps2", "e_ball",
                     "e_cushion", "f_cushion", "ball_radius_m", "ball_mass_kg", "cue_mass_kg",
                     "slide_fade_speed_mps", "slide_fade_bands", "cushion_restitution_exponent"):
            self.assertIn(name, names)
        self.assertIn("sportsim.v1.Billiards", caps["services"])
        # The design's names: build, capabilities.presets (the same list as table_presets).
        info = json.loads(r.stdout)
        self.assertIn(info["build_type"], info["build"])
        self.assertEqual(caps["presets"], caps["table_presets"])
        self.assertIn("10ball", caps["racks"])
        games = {g["name"]: g for g in caps["games"]}
        for game in games.values():  # every game's default rack is a rack
            if game["default_rack"]:
                self.assertIn(game["default_rack"], caps["racks"])

    def test_ten_ball_rack_and_step_settings_choose_the_stepped_engine(self):
        r = cli(self.server.address, "--format", "json", "shot", "simulate", "--rack", "10ball",
                "--ball-speed", "5")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(len(json.loads(r.stdout)["balls"]), 11)
        r = cli(self.server.address, "--format", "json", "shot", "simulate", "--integrator",
                "euler", "--dt", "0.001", *STRAIGHT_SHOT[2:])
        self.assertEqual(r.returncode, 0, r.stderr)
        out = json.loads(r.stdout)
        self.assertEqual(out["engine"], "stepped")
        self.assertEqual(out["integrator"], "euler")

    def test_shot_simulate_json_contract(self):
        r = cli(self.server.address, "--format", "json", *STRAIGHT_SHOT)
        self.assertEqual(r.returncode, 0, r.stderr)
        out = json.loads(r.stdout)
        for key in ("t_rest_s", "balls", "events", "cpu_s"):
            self.assertIn(key, out)
        self.assertGreater(out["t_rest_s"], 0)
        self.assertIsInstance(out["cpu_s"], (int, float))
        self.assertGreaterEqual(out["cpu_s"], 0)
        self.assertEqual([b["id"] for b in out["balls"]], ["cue", "1"])
        for b in out["balls"]:
            for key in ("id", "x_m", "y_m", "state"):
                self.assertIn(key, b)
            self.assertIn(b["state"], MOTION_STATES)
            self.assertEqual(b["state"], "stationary")  # every ball at rest at the end
        events = out["events"]
        self.assertTrue(events)
        times = [e["t_s"] for e in events]
        self.assertEqual(times, sorted(times))  # in time order
        for e in events:
            for key in ("t_s", "kind", "balls"):
                self.assertIn(key, e)
            self.assertIn(e["kind"], EVENT_KINDS)
            self.assertTrue(e["balls"])
            if e["kind"] == "transition":
                self.assertIn(e["from"], MOTION_STATES)
                self.assertIn(e["to"], MOTION_STATES)
                self.assertNotEqual(e["from"], e["to"])
        hits = [e for e in events if e["kind"] == "ball_ball"]
        self.assertTrue(hits)
        first = hits[0]
        self.assertEqual(first["balls"], ["cue", "1"])
        self.assertEqual(len(first["after"]), 2)
        for a in first["after"]:
            for key in ("id", "vx_mps", "vy_mps"):
                self.assertIn(key, a)
        after = {a["id"]: a for a in first["after"]}
        self.assertEqual(set(after), {"cue", "1"})
        # A straight full-ball hit at e_ball = 0.95: ball 1 takes almost all the speed along +x,
        # the cue ball keeps (1 - e) / 2 of it, nothing goes sideways.
        self.assertGreater(after["1"]["vx_mps"], 1.0)
        self.assertLess(abs(after["cue"]["vx_mps"]), 0.1 * after["1"]["vx_mps"])
        self.assertAlmostEqual(after["1"]["vy_mps"], 0.0, places=9)
        self.assertAlmostEqual(after["cue"]["vy_mps"], 0.0, places=9)
        self.assertGreater(out["balls"][1]["x_m"], 0)  # ball 1 ended up on the +x side

    def test_slip_speed_friction(self):
        # A 2 m/s stun shot on the endless cloth, with the cloth's friction constant and then
        # fading below u_c = 0.3 m/s: below u_c the slip integrates twice what it would, and
        # rolling resistance slows the rolling part from the moment the slip reaches u_c,
        # (7/2) mu_s g earlier than the constant law lets it (pool cloth: mu_s 0.2, mu_r 0.01).
        shot = ("--format", "json", "shot", "simulate", "--table", "unbounded", "--rack",
                "empty", "--ball", "cue@0,0", "--ball-speed", "2", "--phi", "0")
        rest = {}
        for fade in (None, "0.3"):
            extra = ("--param", "slide_fade_speed_mps=" + fade) if fade else ()
            r = cli(self.server.address, *shot, *extra)
            self.assertEqual(r.returncode, 0, r.stderr)
            rest[fade] = json.loads(r.stdout)["balls"][0]["x_m"]
        g, mu_s, uc, v_r0 = 9.81, 0.2, 0.3, 2.0 * 5 / 7
        moved = -v_r0 * uc / (3.5 * mu_s * g) + (2 / 7) * uc * uc / (7 * mu_s * g)
        self.assertAlmostEqual(rest["0.3"] - rest[None], moved, places=7)
        r = cli(self.server.address, *shot, "--param", "slide_fade_bands=2.5")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("slide_fade_bands must be a whole number", r.stderr)

    def test_cushion_restitution_falls_with_speed(self):
        # A stun ball square into the top rail of the pool table, frictionless there: Han's
        # rebound is v (1 - (1 + e) cos^2 theta), the restitution e = 1 - (1 - e_c) v^p at
        # the arrival speed v (e_c 0.85, the nose at 63.5 % of the diameter, the slide to the
        # rail at mu_s g = 0.2 g).
        radius = 0.028575
        sin_theta = (0.635 * 2 * radius - radius) / radius
        cos2 = 1 - sin_theta * sin_theta
        gap = 1.27 / 2 - radius * math.sqrt(cos2) - 0.5
        arrival = math.sqrt(3.0 * 3.0 - 2 * 0.2 * 9.81 * gap)
        shot = ("--format", "json", "shot", "simulate", "--table", "pool-9ft", "--rack",
                "empty", "--ball", "cue@0.6,0.5", "--ball-speed", "3", "--phi", "90",
                "--param", "f_cushion=0")
        for p in (0.0, 0.5, 1.0):
            r = cli(self.server.address, *shot, "--param",
                    "cushion_restitution_exponent=%g" % p)
            self.assertEqual(r.returncode, 0, r.stderr)
            hit = [e for e in json.loads(r.stdout)["events"] if e["kind"] == "ball_cushion"][0]
            e = 1 - 0.15 * arrival ** p
            self.assertAlmostEqual(hit["after"][0]["vy_mps"], arrival * (1 - (1 + e) * cos2),
                                   places=9)
        r = cli(self.server.address, *shot, "--param", "cushion_restitution_exponent=3")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("cushion_restitution_exponent", r.stderr)

    def test_ball_ball_models(self):
        # A ball rolling from the strike (b = 0.4: natural roll) 0.5 m into a ball at rest,
        # square. TP A-14's single impulse sends the object ball off at (1 + e) v / 2;
        # Mathavan 2014's integration presses it into the cloth (the cue ball's follow drags
        # its contact point down), whose friction holds it back: (1 - ms mu) (1 + e) v /
        # (2 - ms mu), v the arrival speed after rolling resistance, mu TP A-14's at the slip v.
        g, mu_r, ms, e, radius = 9.81, 0.01, 0.2, 0.95, 0.028575
        v = math.sqrt(1.5 * 1.5 - 2 * mu_r * g * (0.5 - 2 * radius))
        mu = 0.00995 + 0.108 * math.exp(-1.088 * v)
        shot = ("--format", "json", "shot", "simulate", "--table", "pool-9ft", "--rack",
                "empty", "--ball", "cue@-0.25,0", "--ball", "1@0.25,0", "--ball-speed", "1.5",
                "--b", "0.4")
        for model, want in (("alciatore", (1 + e) * v / 2),
                            ("mathavan2014", (1 - ms * mu) * (1 + e) * v / (2 - ms * mu))):
            r = cli(self.server.address, *shot, "--ball-ball-model", model)
            self.assertEqual(r.returncode, 0, r.stderr)
            hit = [ev for ev in json.loads(r.stdout)["events"] if ev["kind"] == "ball_ball"][0]
            after = {a["id"]: a for a in hit["after"]}
            self.assertAlmostEqual(after["1"]["vx_mps"], want, places=9)
        r = cli(self.server.address, *shot, "--ball-ball-model", "sticky")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("alciatore or mathavan2014", r.stderr)

    def test_cushion_models(self):
        # A stun ball into the top rail, slightly off square (still sliding when it gets
        # there): every model rebounds it; the compliant cushion's tangential spring sends it
        # off elsewhere than Han's rigid nose.
        shot = ("shot", "simulate", "--table", "pool-9ft", "--rack", "empty", "--ball",
                "cue@0.6,0.45", "--ball-speed", "3", "--phi", "85")
        rests = {}
        for model in ("han", "stronge", "mathavan2010", "mirror"):
            r = cli(self.server.address, "--format", "json", *shot, "--cushion-model", model)
            self.assertEqual(r.returncode, 0, r.stderr)
            out = json.loads(r.stdout)
            cushions = [e for e in out["events"] if e["kind"] == "ball_cushion"]
            self.assertTrue(cushions, model)
            rests[model] = (out["balls"][0]["x_m"], out["balls"][0]["y_m"])
        self.assertNotEqual(rests["han"], rests["stronge"])
        r = cli(self.server.address, *shot, "--cushion-model", "stronge", "--param",
                "cushion_poisson_ratio=0.7")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("cushion_poisson_ratio", r.stderr)
        r = cli(self.server.address, *shot, "--cushion-model", "springy")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("han, mathavan2010, stronge or mirror", r.stderr)

    def test_shot_simulate_svg(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "shot.svg")
            r = cli(self.server.address, *STRAIGHT_SHOT, "--svg", path)
            self.assertEqual(r.returncode, 0, r.stderr)
            root = ET.parse(path).getroot()
        self.assertEqual(root.tag, SVG_NS + "svg")
        self.assertGreaterEqual(len(root.findall(".//" + SVG_NS + "polyline")), 1)

    def test_ball_ids_with_markup_or_controls_are_refused(self):
        # Ball ids are letters, digits, '.', '_' and '-' only: an id like "a&b<c" (once written
        # into the SVG unescaped) or one with control characters never reaches a table, a
        # log or a picture, and the message quotes it short and printable.
        for bad in ("a&b<c", "x\u202ey", "a" * 40):
            r = cli(self.server.address, "shot", "simulate", "--table", "pool-9ft", "--rack",
                    "empty", "--ball", "cue@-0.5,0", "--ball", bad + "@0,0", "--ball-speed", "2")
            self.assertEqual(r.returncode, 3, r.stderr)  # INVALID_ARGUMENT
            self.assertIn("table.balls[1].id", r.stderr)
            self.assertLess(len(r.stderr), 200, r.stderr)

    def test_shot_simulate_csv(self):
        r = cli(self.server.address, "--format", "csv", *STRAIGHT_SHOT)
        self.assertEqual(r.returncode, 0, r.stderr)
        rows = list(csv.reader(io.StringIO(r.stdout)))
        self.assertEqual(rows[0], ["t_s", "id", "x_m", "y_m", "state"])
        self.assertGreater(len(rows), 3)
        for row in rows[1:]:
            self.assertEqual(len(row), 5, row)
            self.assertIn(row[1], ("cue", "1"))
            self.assertIn(row[4], MOTION_STATES)
        self.assertEqual(rows[1][:4], ["0", "cue", "-0.5", "0"])
        self.assertEqual(rows[2][:4], ["0", "1", "0", "0"])
        times = [float(row[0]) for row in rows[1:]]
        self.assertEqual(times, sorted(times))

    def test_shot_miscue_is_invalid_argument(self):
        r = cli(self.server.address, *STRAIGHT_SHOT, "--a", "0.6")
        self.assertEqual(r.returncode, 3, r.stderr)  # INVALID_ARGUMENT
        self.assertTrue(r.stderr.startswith("sportsim: INVALID_ARGUMENT: "), r.stderr)
        self.assertIn("miscue", r.stderr)
        self.assertEqual(r.stdout, "")

    def test_shot_bad_ball_is_usage(self):
        r = cli(self.server.address, "shot", "simulate", "--ball", "bad", "--ball-speed", "2")
        self.assertEqual(r.returncode, 64)
        self.assertIn("--ball", r.stderr)
        self.assertEqual(r.stdout, "")

    def test_shot_chapter_scene(self):
        # The chapter's scene: the unbounded table's default rack (chapter19).
        r = cli(self.server.address, "--format", "json", "shot", "simulate", "--table",
                "unbounded", "--ball-speed", "7")
        self.assertEqual(r.returncode, 0, r.stderr)
        out = json.loads(r.stdout)
        self.assertEqual(sorted(b["id"] for b in out["balls"]), ["1", "2", "8", "cue"])
        self.assertTrue(out["at_rest"])
        self.assertGreater(out["t_rest_s"], 0)
        self.assertTrue(any(e["kind"] == "ball_ball" for e in out["events"]))
        for b in out["balls"]:
            self.assertNotEqual(b["state"], "pocketed")  # nothing to fall into

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

    def assert_usage(self, args, message):
        r = cli(self.server.address, *args)
        self.assertEqual(r.returncode, 64, (args, r.stderr))
        self.assertTrue(r.stderr.startswith("sportsim: usage: "), (args, r.stderr))
        self.assertIn(message, r.stderr, args)
        self.assertEqual(r.stdout, "", args)

    def test_flags_that_do_not_apply_are_usage_errors(self):
        flight = ("flight", "simulate", "--ball-speed", "70", "--launch-deg", "12",
                  "--spin-rpm", "2500")
        for args, message in (
                (("table", "shoot", "t-x", "--token", "x", "--ball-speed", "1", "--rack",
                  "9ball"), "--rack: not a flag of table shoot"),
                (("table", "shoot", "t-x", "--token", "x", "--ball-speed", "1", "--table",
                  "pool-7ft"), "--table: not a flag of table shoot"),
                (("table", "create", "--ball-speed", "3"), "--ball-speed: not a flag of table "
                                                           "create"),
                (("table", "place", "t-x", "--token", "x", "--ball", "cue@0,0", "--phi", "3"),
                 "--phi: not a flag of table place"),
                (("table", "turn", "t-x", "--token", "x", "--seat", "1", "--ball-speed", "3"),
                 "--ball-speed: not a flag of table turn"),
                (("shot", "simulate", "--engine", "event", "--integrator", "rk4", "--dt",
                  "0.001", "--ball-speed", "1"),
                 "--integrator: applies to the stepped engine only"),
                (("shot", "simulate", "--engine", "event", "--dt", "0.001", "--ball-speed", "1"),
                 "--dt: applies to the stepped engine only"),
                (("shot", "simulate", "--engine", "event", "--no-ccd", "--ball-speed", "1"),
                 "--no-ccd: applies to the stepped engine only"),
                (flight + ("--integrator", "dp45", "--tolerance", "1e-6"),
                 "--integrator: not a flag of flight simulate"),
                (flight + ("--tolerance", "1e-6"), "--tolerance: not a flag of flight simulate"),
                (("swing", "start", "s-x", "--token", "x", "--gamma", "100", "--integrator",
                  "dp45", "--dt", "0.5"), "--gamma: not a flag of swing start"),
                (("swing", "start", "s-x", "--token", "x", "--integrator", "dp45"),
                 "--integrator: not a flag of swing start"),
                (("swing", "watch", "s-x", "--token", "x"), "--token: not a flag of swing watch"),
                (("info", "--phi", "1"), "--phi: not a flag of info"),
                (("swing", "simulate", "--cor", "0.8"), "--cor: describes the ball"),
        ):
            self.assert_usage(args, message)
        # The stepped engine takes them all.
        r = cli(self.server.address, "--format", "json", "shot", "simulate", "--engine",
                "stepped", "--integrator", "rk4", "--dt", "0.001", "--no-ccd", *STRAIGHT_SHOT[2:])
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual((json.loads(r.stdout)["integrator"], json.loads(r.stdout)["dt_s"]),
                         ("rk4", 0.001))

    def test_flag_values_unknown_flags_and_help(self):
        for args, message in (
                (("shot", "simulate", "--ball-speed=abc"), "--ball-speed: 'abc' is not a number"),
                (("--bogus", "1", "info"), "--bogus: unknown flag"),
                (("--timeout", "abc", "info"), "--timeout: 'abc' is not a duration"),
                (("--timeout", "0s", "info"), "--timeout: must be a finite duration more than 0"),
                (("--timeout", "-5s", "info"), "--timeout: must be a finite duration more than 0"),
                (("table", "get", "t-x", "--geometry=maybe"), "--geometry: 'maybe' is not true"),
                (("table", "turn", "t-x", "--token", "x", "--seat", "one"),
                 "--seat: 'one' is not an integer"),
                (("shot", "simulate", "--ball-speed"), "--ball-speed: needs a value"),
                (("shot", "simulate", "--ball-speed", "1", "--phi", "1", "--phi", "2"),
                 "--phi: given twice"),
                ((), "give a command"),
        ):
            self.assert_usage(args, message)
        r = cli(self.server.address, "--help")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("Commands:", r.stdout)
        self.assertNotIn("No flags matched", r.stdout + r.stderr)
        r = cli(self.server.address, "--helpfull")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("--ball-speed", r.stdout)
        self.assertNotIn("/", "".join(line for line in r.stdout.splitlines()
                                      if ".cc" in line or ".h:" in line))
        self.assertNotIn(".cc", r.stdout)
        # Every command's help lists exactly the flags it takes: each one listed is accepted
        # (no "not a flag of" error), and a flag of another command is refused.
        for words in (("info",), ("health",), ("shot", "simulate"), ("flight", "simulate"),
                      ("swing", "simulate"), ("swing", "create"), ("swing", "start"),
                      ("swing", "drive"), ("table", "create"), ("table", "shoot"),
                      ("table", "place"), ("table", "watch"), ("table", "list")):
            r = cli(self.server.address, *words, "--help")
            self.assertEqual(r.returncode, 0, (words, r.stderr))
            self.assertIn("sportsim " + " ".join(words), r.stdout)
            flags = [line.split()[0] for line in r.stdout.split("Global flags")[0].splitlines()
                     if line.startswith("  --")]
            for flag in flags:
                check = cli(self.server.address, "--server", "127.0.0.1:1", "--timeout", "1s",
                            *words, flag + "=1")
                self.assertNotIn("not a flag of", check.stderr, (words, flag))
        r = cli(self.server.address, "table", "shoot", "--help")
        for flag in ("--token", "--speed", "--ball-speed", "--phi", "--theta", "--a", "--b",
                     "--noise", "--seed", "--strike-ball", "--next-seat", "--call", "--safety",
                     "--push-out", "--nominate"):
            self.assertIn("\n  " + flag + " ", r.stdout)
        self.assertNotIn("--rack", r.stdout)

    def test_ranges_stated_are_enforced(self):
        # Values out of their range: INVALID_ARGUMENT, as the server would say, before any call.
        for args, message in (
                (("table", "list", "--page-size", "-5"), "--page-size: must be in [0, 1000]"),
                (("swing", "list", "--page-size", "1001"), "--page-size: must be in [0, 1000]"),
                (("table", "create", "--seats", "0"), "--seats: must be in [1, 16], got 0"),
                (("swing", "create", "--seats", "17"), "--seats: must be in [1, 16], got 17"),
                (("table", "create", "--tick-hz", "0"), "--tick-hz: must be in [1, 1000], got 0"),
                (("swing", "create", "--tick-hz", "0"), "--tick-hz: must be in [1, 1000]"),
                (STRAIGHT_SHOT + ("--max-time", "0"), "--max-time: must be in (0, 3600] s"),
                (("table", "create", "--game", "9ball", "--race-to", "0"), "--race-to"),
        ):
            r = cli(self.server.address, *args)
            self.assertEqual(r.returncode, 3, (args, r.stderr))
            self.assertTrue(r.stderr.startswith("sportsim: INVALID_ARGUMENT: "), r.stderr)
            self.assertIn(message, r.stderr)
            self.assertEqual(r.stdout, "")
        # Malformed values: usage errors.
        for args, message in (
                (("shot", "simulate", "--table", "", "--ball-speed", "1"), "--table: needs a preset"),
                (("shot", "simulate", "--rack", "", "--ball-speed", "1"), "--rack: needs a rack"),
                (STRAIGHT_SHOT + ("--ball", "cue@0.5,0.3"), "--ball: cue given twice"),
                (("table", "create", "--seat-names", "ann,bob,ann"), "--seat-names: 'ann' given "
                                                                     "twice"),
                (("swing", "create", "--seat-names", "a,a"), "--seat-names: 'a' given twice"),
        ):
            self.assert_usage(args, message)
        r = cli(self.server.address, "--format", "json", "table", "list", "--page-size", "0")
        self.assertEqual(r.returncode, 0, r.stderr)

    def test_messages_name_the_flags(self):
        # An empty rack without the struck ball: the CLI says which flag places it.
        r = cli(self.server.address, "shot", "simulate", "--rack", "empty", "--ball-speed", "5")
        self.assertEqual(r.returncode, 3, r.stderr)  # INVALID_ARGUMENT, before any call
        self.assertIn("--rack empty: no cue ball to strike: place it with --ball cue@X,Y",
                      r.stderr)
        # The server's field names come with the flags that set them.
        r = cli(self.server.address, "shot", "simulate", "--rack", "9ball", "--strike-ball",
                "15", "--ball-speed", "1")
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn("strike.ball: ", r.stderr)  # the server's message, as it is
        self.assertIn("[flags: --strike-ball, --ball]", r.stderr)
        # A ball launched downward lands at once: exit 0, but a note says why the carry is 0.
        r = cli(self.server.address, "flight", "simulate", "--ball-speed", "50", "--launch-deg",
                "-10", "--spin-rpm", "3000")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("carry 0.00 m", r.stdout)
        self.assertIn("sportsim: note: the ball landed at launch", r.stderr)
        r = cli(self.server.address, "flight", "simulate", "--ball-speed", "50", "--launch-deg",
                "10", "--spin-rpm", "3000")
        self.assertEqual(r.stderr, "")

    def test_formats_and_negative_zero(self):
        self.assert_usage(("--format", "jsonl", *STRAIGHT_SHOT), "--format jsonl: shot simulate")
        self.assert_usage(("--format", "jsonl", "info"), "--format jsonl: info")
        self.assert_usage(("--format", "csv", "info"), "--format csv: info has no csv form")
        negative_zero = re.compile(r"(?<![\w.])-0(?![\d.eE])")
        # Balls placed at y = -0 keep that zero's sign through the physics: the server sends
        # -0, and the CLI once printed it (this input makes the check able to fail).
        signed = ("shot", "simulate", "--table", "pool-9ft", "--rack", "empty", "--ball",
                  "cue@-0.5,-0", "--ball", "1@0.5,-0", "--ball-speed", "0.5", "--phi", "180")
        for args in (signed,
                     STRAIGHT_SHOT + ("--phi", "-0", "--a", "-0", "--sample-rate", "50"),
                     ("flight", "simulate", "--ball-speed", "50", "--launch-deg", "20",
                      "--spin-rpm", "3000", "--spin-axis-deg", "-0",
                      "--launch-direction-deg", "-0"),
                     ("swing", "simulate", "--club", "7-iron", "--face-angle-deg", "-0")):
            for fmt in ("json", "csv"):
                r = cli(self.server.address, "--format", fmt, *args)
                self.assertEqual(r.returncode, 0, r.stderr)
                self.assertIsNone(negative_zero.search(r.stdout), (fmt, args))
        # Physics events carry no game keys.
        r = cli(self.server.address, "--format", "json", *STRAIGHT_SHOT)
        for e in json.loads(r.stdout)["events"]:
            for key in ("reason", "points", "choices"):
                self.assertNotIn(key, e)

    def test_flight_svg_has_equal_scales_and_axes(self):
        args = ("flight", "simulate", "--ball-speed", "70", "--launch-deg", "12", "--spin-rpm",
                "2800")
        flight = json.loads(cli(self.server.address, "--format", "json", *args).stdout)
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "flight.svg")
            r = cli(self.server.address, *args, "--svg", path)
            self.assertEqual(r.returncode, 0, r.stderr)
            root = ET.parse(path).getroot()
        side = root.findall(".//" + SVG_NS + "polyline")[0].get("points").split()
        pts = [tuple(map(float, p.split(","))) for p in side]
        samples = flight["samples"]
        apex = max(range(len(samples)), key=lambda i: samples[i]["z_m"])
        across = (pts[apex][0] - pts[0][0]) / samples[apex]["x_m"]
        up = (pts[0][1] - pts[apex][1]) / samples[apex]["z_m"]
        self.assertAlmostEqual(across / up, 1.0, delta=0.02)  # one scale both ways
        labels = [t.text for t in root.iter(SVG_NS + "text")]
        self.assertIn("m", labels)
        self.assertIn("yd", labels)
        self.assertTrue(any(t.endswith(" m") and t[:-2].replace(".", "").isdigit()
                            for t in labels), labels)  # height ticks
        self.assertGreaterEqual(sum(1 for t in labels if t.isdigit()), 8)  # downrange ticks

    def test_unreachable_server(self):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]  # bound, not listening: nothing answers
            r = cli("127.0.0.1:%d" % port, "--timeout", "2s", "health")
        self.assertNotEqual(r.returncode, 0)
        self.assertRegex(r.stderr, r"^sportsim: (UNAVAILABLE|DEADLINE_EXCEEDED): ")


# A quick table: a 9-ball rack on heavy cloth, so a 3 m/s break is over in about a second.
QUICK_TABLE = ("--table", "pool-9ft", "--rack", "9ball", "--param", "mu_roll=0.3",
               "--param", "spin_decel_rps2=100")
QUICK_BREAK = ("--ball-speed", "3", "--phi", "0.4", "--a", "0.1")


class TablesAgainstServer(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = ServerProcess(SERVER)

    @classmethod
    def tearDownClass(cls):
        cls.server.__exit__()

    def cli_json(self, *args):
        r = cli(self.server.address, "--format", "json", *args)
        self.assertEqual(r.returncode, 0, r.stderr)
        return json.loads(r.stdout)

    def test_create_shoot_watch_until_rest_matches_shot_simulate(self):
        created = self.cli_json("table", "create", *QUICK_TABLE, "--tick-hz", "240")
        self.assertEqual(set(created) >= {"table_id", "seats"}, True, created)
        self.assertEqual([s["seat"] for s in created["seats"]], [0, 1])
        table, token = created["table_id"], created["seats"][0]["token"]
        # The watcher is live (its first snapshot is in) before the shot.
        watch = subprocess.Popen([CLI, "--server", self.server.address, "--format", "jsonl",
                                  "table", "watch", table, "--rate", "60", "--until-rest"],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        first = watch.stdout.readline()
        shot = self.cli_json("table", "shoot", table, "--token", token, *QUICK_BREAK,
                             "--next-seat", "1")
        self.assertEqual(shot["shot_id"], 1)
        self.assertIsInstance(shot["start_tick"], int)
        out, err = watch.communicate(timeout=60)
        self.assertEqual(watch.returncode, 0, err)
        lines = [json.loads(line) for line in [first] + out.splitlines()]
        self.assertGreater(len(lines), 5)
        for snap in lines:
            for key in ("sequence", "tick", "t_s", "balls", "events", "at_rest"):
                self.assertIn(key, snap)
            self.assertIsInstance(snap["tick"], int)
        last = lines[-1]
        self.assertTrue(last["at_rest"])
        kinds = [e["kind"] for snap in lines for e in snap["events"]]
        self.assertEqual(kinds.count("shot"), 1)
        self.assertEqual(kinds.count("shot_end"), 1)
        self.assertIn("ball_ball", kinds)
        end = [e for snap in lines for e in snap["events"] if e["kind"] == "shot_end"][0]
        self.assertEqual(end["summary"]["first_ball_hit"], "1")
        # The same shot fast-forwarded: the same final state, to the bit (JSON numbers are
        # shortest round-trip text, so equal text is equal doubles).
        sim = self.cli_json("shot", "simulate", *QUICK_TABLE, *QUICK_BREAK)
        want = {b["id"]: (b["x_m"], b["y_m"], b["state"]) for b in sim["balls"]}
        got = {b["id"]: (b["x_m"], b["y_m"], b["state"]) for b in last["balls"]}
        self.assertEqual(got, want)
        sim_kinds = [e["kind"] for e in sim["events"]]
        self.assertEqual([k for k in kinds if k in EVENT_KINDS], sim_kinds)
        # Seat 1 plays next; seat 0 is refused with PERMISSION_DENIED (exit 7).
        r = cli(self.server.address, "table", "shoot", table, "--token", token, *QUICK_BREAK)
        self.assertEqual(r.returncode, 7, r.stderr)
        self.assertIn("PERMISSION_DENIED", r.stderr)
        info = self.cli_json("table", "get", table)
        self.assertEqual(info["turn"], 1)
        self.assertEqual(info["last_shot"]["shot_id"], 1)

    def test_list_place_reset_delete(self):
        created = self.cli_json("table", "create", *QUICK_TABLE, "--seats", "3")
        table, token = created["table_id"], created["seats"][0]["token"]
        listed = self.cli_json("table", "list")
        self.assertIn(table, [t["table_id"] for t in listed["tables"]])
        self.cli_json("table", "place", table, "--token", token, "--ball", "cue@-0.7,0.2")
        info = self.cli_json("table", "get", table)
        cue = [b for b in info["balls"] if b["id"] == "cue"][0]
        self.assertEqual((cue["x_m"], cue["y_m"]), (-0.7, 0.2))
        r = cli(self.server.address, "table", "place", table, "--token", token, "--ball",
                "cue@nan,0")
        self.assertEqual(r.returncode, 3, r.stderr)  # INVALID_ARGUMENT
        self.assertIn("ball", r.stderr)
        self.cli_json("table", "reset", table, "--token", token)
        info = self.cli_json("table", "get", table)
        cue = [b for b in info["balls"] if b["id"] == "cue"][0]
        self.assertNotEqual((cue["x_m"], cue["y_m"]), (-0.7, 0.2))
        r = cli(self.server.address, "table", "delete", table, "--token", "wrong")
        self.assertEqual(r.returncode, 7, r.stderr)
        self.cli_json("table", "delete", table, "--token", created["seats"][2]["token"])
        r = cli(self.server.address, "table", "get", table)
        self.assertEqual(r.returncode, 5, r.stderr)
        self.assertIn("NOT_FOUND", r.stderr)

    def test_tokens_only_where_they_are_given(self):
        created = self.cli_json("table", "create", *QUICK_TABLE)
        self.assertTrue(all(s["token"] for s in created["seats"]))
        info = self.cli_json("table", "get", created["table_id"])
        self.assertEqual([s["seat"] for s in info["seats"]], [0, 1])
        for seat in info["seats"]:
            self.assertNotIn("token", seat)  # no empty "token": "" per seat

    def test_until_rest_at_rest_waits_for_the_next_shot(self):
        created = self.cli_json("table", "create", *QUICK_TABLE, "--tick-hz", "240")
        table, token = created["table_id"], created["seats"][0]["token"]
        r = cli(self.server.address, "table", "watch", "--help")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("end of the next shot", r.stdout)
        watch = subprocess.Popen([CLI, "--server", self.server.address, "--format", "jsonl",
                                  "table", "watch", table, "--until-rest"],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        first = json.loads(watch.stdout.readline())
        self.assertTrue(first["at_rest"])
        time.sleep(0.3)
        self.assertIsNone(watch.poll())  # at rest: still waiting for a shot
        self.cli_json("table", "shoot", table, "--token", token, *QUICK_BREAK)
        out, err = watch.communicate(timeout=60)
        self.assertEqual(watch.returncode, 0, err)
        kinds = [e["kind"] for line in out.splitlines() for e in json.loads(line)["events"]]
        self.assertIn("shot_end", kinds)

    def test_rack_labels_do_not_overlap(self):
        # A 9-ball rack barely touched: its labels sit inside their balls, not on their
        # neighbours.
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "rack.svg")
            r = cli(self.server.address, "shot", "simulate", "--rack", "9ball", "--ball-speed",
                    "0.2", "--svg", path)
            self.assertEqual(r.returncode, 0, r.stderr)
            root = ET.parse(path).getroot()
        # Each final ball is a filled circle followed by its label.
        ids = {"cue"} | {str(i) for i in range(1, 10)}
        balls, labels = [], []
        children = list(root)
        for i, el in enumerate(children):
            if el.tag != SVG_NS + "text" or (el.text or "") not in ids:
                continue
            c = children[i - 1]
            self.assertEqual(c.tag, SVG_NS + "circle")
            balls.append((float(c.get("cx")), float(c.get("cy")), float(c.get("r"))))
            fs, x, y = float(el.get("font-size")), float(el.get("x")), float(el.get("y"))
            w = len(el.text) * 0.6 * fs
            left = x - w / 2 if el.get("text-anchor") == "middle" else x
            labels.append((left, left + w, y - 0.7 * fs, y))
        self.assertEqual(len(labels), 10)
        # No label covers another ball (racked balls touch: a label beside its ball would).
        for i, (x0, x1, y0, y1) in enumerate(labels):
            for j, (cx, cy, r) in enumerate(balls):
                if i == j:
                    continue
                dx = max(x0 - cx, 0, cx - x1)
                dy = max(y0 - cy, 0, cy - y1)
                self.assertGreater(dx * dx + dy * dy, r * r, (i, j, labels[i], balls[j]))

    def test_watch_text_and_svg(self):
        created = self.cli_json("table", "create", *QUICK_TABLE, "--tick-hz", "240")
        table, token = created["table_id"], created["seats"][0]["token"]
        self.cli_json("table", "shoot", table, "--token", token, *QUICK_BREAK)
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "watch.svg")
            r = subprocess.run([CLI, "--server", self.server.address, "table", "watch", table,
                                "--until-rest", "--from-sequence", "0", "--svg", path],
                               capture_output=True, text=True, timeout=60)
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn("shot 1 by seat 0 (cue): first hit 1", r.stdout)
            root = ET.parse(path).getroot()
            self.assertEqual(root.tag, SVG_NS + "svg")
            self.assertGreaterEqual(len(root.findall(".//" + SVG_NS + "polyline")), 2)

    def test_watch_with_format_json_is_one_document(self):
        created = self.cli_json("table", "create", *QUICK_TABLE, "--tick-hz", "240")
        table, token = created["table_id"], created["seats"][0]["token"]
        watch = subprocess.Popen([CLI, "--server", self.server.address, "--format", "json",
                                  "table", "watch", table, "--rate", "60", "--until-rest"],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        head = watch.stdout.readline() + watch.stdout.readline()  # "[" and the first snapshot
        self.cli_json("table", "shoot", table, "--token", token, *QUICK_BREAK)
        out, err = watch.communicate(timeout=60)
        self.assertEqual(watch.returncode, 0, err)
        doc = json.loads(head + out)
        self.assertIsInstance(doc, list)
        self.assertGreater(len(doc), 2)
        self.assertTrue(doc[-1]["at_rest"])
        kinds = [e["kind"] for snap in doc for e in snap["events"]]
        self.assertEqual(kinds.count("shot_end"), 1)

    def test_aim_lines_flag(self):
        for value, allowed in (("on", True), ("off", False)):
            created = self.cli_json("table", "create", "--aim-lines", value)
            info = self.cli_json("table", "get", created["table_id"])
            self.assertEqual(info["aim_lines"], allowed, info)
        r = cli(self.server.address, "table", "create", "--aim-lines", "maybe")
        self.assertEqual(r.returncode, 64, r.stderr)
        self.assertIn("--aim-lines must be on or off", r.stderr)


# A 9-ball position after the break (--start in-play) on heavy cloth: the 1 straight in to
# top_right (35 cm away), the cue ball 30 cm behind it on the same line, the 9 far away. A 3 m/s
# strike with draw pots the 1 and brings the cue ball back.
GAME_TABLE = ("--table", "pool-9ft", "--rack", "empty", "--ball", "cue@0.6830,0.3387",
              "--ball", "1@0.9513,0.4728", "--ball", "9@-0.5,-0.2",
              "--param", "mu_roll=0.3", "--param", "spin_decel_rps2=100", "--tick-hz", "240")
POT_THE_ONE = ("--ball-speed", "3", "--phi", "26.565051", "--b", "-0.4")
GAME_NAMES = {"free", "8ball", "9ball", "10ball", "snooker", "three-cushion"}
GAME_KEYS = {"name", "frame", "race_to", "frames_won", "to_play", "ball_in_hand", "on", "groups",
             "scores", "fouls_in_row", "call_required", "push_out_available", "decision",
             "winner", "result", "shot_clock_deadline_s"}
VERDICT_KEYS = {"foul", "reason", "points", "turn_passes", "respotted"}


class GamesAgainstServer(unittest.TestCase):
    """The games commands of the CLI against a server that referees (docs/games.md)."""

    @classmethod
    def setUpClass(cls):
        cls.server = ServerProcess(SERVER)

    @classmethod
    def tearDownClass(cls):
        cls.server.__exit__()

    def run_cli(self, *args):
        return cli(self.server.address, *args)

    def cli_json(self, *args):
        r = self.run_cli("--format", "json", *args)
        self.assertEqual(r.returncode, 0, r.stderr)
        return json.loads(r.stdout)

    def until_rest(self, table):
        """Waits for the shot in progress (if any) to end; returns the jsonl snapshots seen."""
        r = self.run_cli("--format", "jsonl", "table", "watch", table, "--until-rest",
                         "--from-sequence", "0")
        self.assertEqual(r.returncode, 0, r.stderr)
        return [json.loads(line) for line in r.stdout.splitlines()]

    def create_game(self, *extra):
        created = self.cli_json("table", "create", "--game", "9ball", "--start", "in-play",
                                *GAME_TABLE, *extra)
        return created, created["seats"][0]["token"], created["seats"][1]["token"]

    def test_info_lists_games_with_variants(self):
        info = self.cli_json("info")
        games = {g["name"]: g for g in info["capabilities"]["games"]}
        self.assertTrue(GAME_NAMES <= set(games), sorted(games))
        for g in games.values():
            self.assertIn("default_rack", g)
            for v in g["variants"]:
                self.assertTrue({"name", "values", "min", "max", "default_value",
                                 "description"} <= set(v), v)
        self.assertIn("target", [v["name"] for v in games["three-cushion"]["variants"]])
        r = self.run_cli("info")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("games", r.stdout)
        self.assertIn("three-cushion", r.stdout)

    def test_nine_ball_in_play_call_foul_decide_concede_record(self):
        created, seat0, seat1 = self.create_game()
        table, admin = created["table_id"], created["admin_token"]
        self.assertTrue(admin)
        self.assertNotIn(admin, (seat0, seat1))
        game = created["game"]
        self.assertTrue(set(game) <= GAME_KEYS | {"warned", "breaker", "is_break", "innings",
                                                  "phase", "free_ball", "shot"}, game)
        self.assertEqual(game["name"], "9ball")
        self.assertEqual((game["frame"], game["race_to"], game["to_play"]), (1, 1, 0))
        self.assertEqual(game["frames_won"], [0, 0])
        self.assertEqual(game["ball_in_hand"], "none")
        self.assertEqual(game["on"], ["1"])
        self.assertFalse(game["push_out_available"])  # in-play: no push-out
        # Keys that do not apply to 9-ball, or not yet, are absent.
        for key in ("groups", "scores", "decision", "winner", "shot_clock_deadline_s", "result",
                    "phase", "free_ball"):
            self.assertNotIn(key, game)
        # Nor push-outs outside 9- and 10-ball, nor ball in hand and calls in three-cushion.
        eight = self.cli_json("table", "create", "--game", "8ball")["game"]
        self.assertNotIn("push_out_available", eight)
        self.assertEqual(eight["ball_in_hand"], "kitchen")
        carom = self.cli_json("table", "create", "--game", "three-cushion")["game"]
        for key in ("push_out_available", "ball_in_hand", "call_required", "result"):
            self.assertNotIn(key, carom)

        info = self.cli_json("table", "get", table)
        self.assertEqual(info["game"]["on"], ["1"])
        self.assertNotIn("last_shot", info)
        # Nobody sets the turn in a ruled game.
        r = self.run_cli("table", "turn", table, "--token", seat0, "--seat", "1")
        self.assertEqual(r.returncode, 9, r.stderr)  # FAILED_PRECONDITION

        # No decision is pending: refused, naming the rule; nothing changes.
        r = self.run_cli("table", "decide", table, "--token", seat0, "--choice", "accept_table")
        self.assertEqual(r.returncode, 9, r.stderr)
        self.assertTrue(r.stderr.startswith("sportsim: FAILED_PRECONDITION: "), r.stderr)
        self.assertIn("decision", r.stderr)
        self.assertEqual(r.stdout, "")

        # Shot 1: the 1, called in top_right, goes in; seat 0 plays on, the 9 is on.
        shot = self.cli_json("table", "shoot", table, "--token", seat0, *POT_THE_ONE,
                             "--call", "1:top_right")
        self.assertEqual(shot["shot_id"], 1)
        snaps = self.until_rest(table)
        self.assertTrue(any("game" in s for s in snaps if not s["heartbeat"]))
        info = self.cli_json("table", "get", table)
        last = info["last_shot"]
        self.assertEqual(last["call"]["ball"], "1")
        self.assertEqual(last["call"]["pocket"], "top_right")
        self.assertEqual(last["pocketed"], ["1"])
        self.assertTrue(VERDICT_KEYS <= set(last["verdict"]), last["verdict"])
        self.assertFalse(last["verdict"]["foul"], last["verdict"])
        self.assertFalse(last["verdict"]["turn_passes"])
        self.assertEqual(info["game"]["to_play"], 0)
        self.assertEqual(info["game"]["on"], ["9"])
        self.assertNotIn("winner", info["game"])

        # Shot 2: straight up the table, touching nothing: a foul, seat 1 has ball in hand.
        self.cli_json("table", "shoot", table, "--token", seat0, "--ball-speed", "1",
                      "--phi", "90")
        snaps = self.until_rest(table)
        fouls = [e for s in snaps for e in s["events"] if e["kind"] == "foul"]
        self.assertEqual(len(fouls), 1, [e["kind"] for s in snaps for e in s["events"]])
        self.assertEqual(fouls[0]["seat"], 0)
        self.assertTrue(fouls[0]["reason"])
        self.assertIn("points", fouls[0])  # a game event keeps its game keys, zero or not
        # Physics and table events leave the game keys out (they never fill them).
        others = [e for s in snaps for e in s["events"] if e["kind"] in EVENT_KINDS | {
            "shot", "shot_end", "turn"}]
        self.assertTrue(others)
        for e in others:
            for key in ("reason", "points", "choices"):
                self.assertNotIn(key, e, e)
        info = self.cli_json("table", "get", table)
        verdict = info["last_shot"]["verdict"]
        self.assertTrue(verdict["foul"])
        self.assertTrue(verdict["turn_passes"])
        self.assertEqual(info["game"]["to_play"], 1)
        self.assertEqual(info["game"]["ball_in_hand"], "anywhere")
        r = self.run_cli("table", "get", table)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRegex(r.stdout, r"seat 1 to play, ball in hand anywhere[^\n]*; last shot: "
                         r"foul by seat 0 \(%s\)" % verdict["reason"])
        r = self.run_cli("table", "watch", table, "--until-rest", "--from-sequence", "0")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("foul by seat 0 (%s)" % verdict["reason"], r.stdout)

        # Seat 0 may not play out of turn; seat 1 places the cue ball, then concedes.
        r = self.run_cli("table", "shoot", table, "--token", seat0, "--ball-speed", "1")
        self.assertNotEqual(r.returncode, 0)
        self.cli_json("table", "place", table, "--token", seat1, "--ball", "cue@0,0.3")
        conceded = self.cli_json("table", "concede", table, "--token", seat1)
        self.assertEqual(conceded["game"]["winner"], 0)
        self.assertEqual(conceded["game"]["result"], "conceded")
        info = self.cli_json("table", "get", table)
        self.assertEqual(info["game"]["winner"], 0)

        # The record: every action, in order; the seeds once the match has ended.
        record = self.cli_json("table", "record", table)
        self.assertEqual(record["table_id"], table)
        self.assertTrue(record["ended"])
        self.assertEqual(record["create"]["game"]["name"], "9ball")
        kinds = [a["kind"] for a in record["actions"]]
        self.assertEqual(kinds, ["SHOOT", "SHOOT", "PLACE", "CONCEDE"])
        first = record["actions"][0]
        self.assertEqual((first["seat"], first["shot_id"]), (0, 1))
        self.assertEqual(first["call"]["ball"], "1")
        self.assertIn("seed", first)
        self.assertFalse(first["verdict"]["foul"])
        self.assertTrue(record["actions"][1]["verdict"]["foul"])
        self.assertEqual(record["actions"][2]["place"]["id"], "cue")
        r = self.run_cli("table", "record", table)
        self.assertEqual(r.returncode, 0, r.stderr)
        lines = [line for line in r.stdout.splitlines() if line.startswith("tick ")]
        self.assertEqual(len(lines), 4, r.stdout)
        self.assertIn("called 1 in top_right", lines[0])
        self.assertIn("conceded", lines[3])

    def test_admin_concedes_for_a_seat(self):
        created, seat0, _ = self.create_game("--race-to", "2")
        table, admin = created["table_id"], created["admin_token"]
        self.assertEqual(created["game"]["race_to"], 2)
        r = self.run_cli("table", "concede", table, "--token", admin, "--seat", "0")
        self.assertEqual(r.returncode, 0, r.stderr)
        game = self.cli_json("table", "get", table)["game"]
        self.assertEqual(game["frames_won"], [0, 1])
        # A seat's token is not the admin's: it cannot delete a ruled table.
        r = self.run_cli("table", "delete", table, "--token", seat0)
        self.assertEqual(r.returncode, 7, r.stderr)  # PERMISSION_DENIED
        self.cli_json("table", "delete", table, "--token", admin)

    def test_games_usage_errors(self):
        for args, message in (
                (("table", "create", "--game", "9ball", "--call", "1:top_left"),
                 "--call applies to table shoot only"),
                (("table", "shoot", "t-x", "--token", "x", "--ball-speed", "1", "--call",
                  "1:top_left", "--safety"), "--call BALL:POCKET or --safety"),
                (("table", "shoot", "t-x", "--token", "x", "--ball-speed", "1", "--call", "1"),
                 "--call must be BALL:POCKET"),
                (("shot", "simulate", "--ball-speed", "1", "--rule", "target=10"),
                 "--rule applies to table create and round create only"),
                (("table", "create", "--game", "9ball", "--rule", "target"),
                 "--rule must be NAME=VALUE"),
                (("table", "create", "--game", "9ball", "--start", "late"),
                 "--start must be break or in-play"),
                (("table", "decide", "t-x", "--token", "x"), "--choice"),
                (("table", "get", "t-x", "--choice", "a"), "--choice applies to table decide"),
        ):
            r = self.run_cli(*args)
            self.assertEqual(r.returncode, 64, (args, r.stderr))
            self.assertTrue(r.stderr.startswith("sportsim: usage: "), r.stderr)
            self.assertIn(message, r.stderr)

    def test_unknown_game_and_rule_are_invalid_argument(self):
        r = self.run_cli("table", "create", "--game", "croquet")
        self.assertEqual(r.returncode, 3, r.stderr)
        r = self.run_cli("table", "create", "--game", "9ball", "--rule", "no_such_rule=1")
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn("no_such_rule", r.stderr)


SAMPLE_KEYS = ("t_s", "theta_deg", "alpha_deg", "beta_deg", "phi_deg", "clubhead_speed_mps")
# The chapter's torques as live input: Q_alpha 100 N m throughout, Q_beta -10 N m until 0.1 s.
CHAPTER_DRIVE = "0,100,-10\n0.1,100,0\n"


class SessionsAgainstServer(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = ServerProcess(SERVER)

    @classmethod
    def tearDownClass(cls):
        cls.server.__exit__()

    def cli_json(self, *args):
        r = cli(self.server.address, "--format", "json", *args)
        self.assertEqual(r.returncode, 0, r.stderr)
        return json.loads(r.stdout)

    def create(self, *args):
        created = self.cli_json("swing", "create", *args)
        self.assertTrue({"session_id", "token"} <= set(created), created)
        return created["session_id"], created["token"]

    def simulated_impact(self):
        # The same golfer, club, integrator (rk4) and step (0.0025 s) as a default session.
        return self.cli_json("swing", "simulate")["impact"]

    def drive(self, session, token, stdin, *args):
        return subprocess.run([CLI, "--server", self.server.address, "--format", "jsonl",
                               "swing", "drive", session, "--token", token, *args],
                              input=stdin, capture_output=True, text=True, timeout=10)

    def start_watch(self, session, *args):
        """A `swing watch` that is live before the swing starts: its first line is in, or the
        server counts it. Returns the process and the lines read so far."""
        watch = subprocess.Popen([CLI, "--server", self.server.address, "--format", "jsonl",
                                  "swing", "watch", session, *args],
                                 stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline:
            ready, _, _ = select.select([watch.stdout], [], [], 0.05)
            if ready:
                return watch, [watch.stdout.readline()]
            if self.cli_json("swing", "get", session)["watchers"] >= 1:
                return watch, []
        watch.kill()
        self.fail("swing watch did not go live: %r" % watch.communicate()[1])

    def test_create_start_watch_until_impact_matches_simulate(self):
        session, token = self.create()
        watch, first = self.start_watch(session, "--until-impact")
        started = self.cli_json("swing", "start", session, "--token", token)
        self.assertIsInstance(started["start_tick"], int)
        try:
            out, err = watch.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            watch.kill()
            raise
        self.assertEqual(watch.returncode, 0, err)
        lines = [json.loads(line) for line in first + out.splitlines() if line.strip()]
        self.assertGreater(len(lines), 10)  # every tick by default: ~117 in the swing
        for line in lines:
            for key in SAMPLE_KEYS:
                self.assertIn(key, line)
            self.assertIsInstance(line["tick"], int)
        impacts = [line["impact"] for line in lines if "impact" in line]
        self.assertEqual(len(impacts), 1)
        self.assertIn("impact", lines[-1])  # --until-impact ends with the impact's line
        swinging = [line["t_s"] for line in lines if line["phase"] == "SWING_PHASE_SWINGING"]
        self.assertEqual(swinging, sorted(swinging))
        # Bit for bit: JSON numbers are shortest round-trip text, so equal values are equal
        # doubles.
        self.assertEqual(impacts[0], self.simulated_impact())

    def test_drive_from_stdin_matches_simulate(self):
        session, token = self.create()
        r = self.drive(session, token, CHAPTER_DRIVE)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertNotIn("refused", r.stderr)
        lines = [json.loads(line) for line in r.stdout.splitlines()]
        self.assertGreater(len(lines), 10)
        impacts = [line["impact"] for line in lines if "impact" in line]
        self.assertEqual(len(impacts), 1)
        want = self.simulated_impact()
        self.assertEqual(impacts[0], want)
        info = self.cli_json("swing", "get", session)
        self.assertEqual(info["phase"], "SWING_PHASE_FINISHED")
        self.assertEqual(info["last_impact"], want)

    def test_drive_reports_refused_commands(self):
        session, token = self.create()
        # Before the previous command (OUT_OF_RANGE), and not finite (INVALID_ARGUMENT): both
        # refused and reported on stderr; the swing goes on with the chapter's torques.
        r = self.drive(session, token, "# t_s,qalpha_nm,qbeta_nm\n" + CHAPTER_DRIVE +
                       "\n0.05,100,0\n0.2,nan,0\n")
        # Some commands refused: exit 65 with the count (the first line is the start's
        # torques, not a command).
        self.assertEqual(r.returncode, 65, r.stderr)
        self.assertIn("refused: OUT_OF_RANGE", r.stderr)
        self.assertIn("refused: INVALID_ARGUMENT", r.stderr)
        self.assertIn("sportsim: 2 of 3 commands refused", r.stderr)
        lines = [json.loads(line) for line in r.stdout.splitlines()]
        impacts = [line["impact"] for line in lines if "impact" in line]
        self.assertEqual(impacts, [self.simulated_impact()])
        # A malformed line is a usage error, before any call.
        r = self.drive(session, token, "0,100\n")
        self.assertEqual(r.returncode, 64, r.stderr)
        self.assertIn("stdin line 1", r.stderr)

    def test_errors_tokens_ids_and_realism(self):
        session, token = self.create()
        r = cli(self.server.address, "swing", "start", session, "--token", "wrong")
        self.assertEqual(r.returncode, 7, r.stderr)  # PERMISSION_DENIED
        self.assertIn("PERMISSION_DENIED", r.stderr)
        r = self.drive(session, "wrong", CHAPTER_DRIVE)
        self.assertEqual(r.returncode, 7, r.stderr)
        r = cli(self.server.address, "swing", "delete", session, "--token", "wrong")
        self.assertEqual(r.returncode, 7, r.stderr)
        for args in (("get", "no-such-session"), ("watch", "no-such-session"),
                     ("start", "no-such-session", "--token", token)):
            r = cli(self.server.address, "swing", *args)
            self.assertEqual(r.returncode, 5, r.stderr)  # NOT_FOUND
            self.assertIn("NOT_FOUND", r.stderr)
        # 1000 N m at the shoulder is beyond a human: refused, and nothing changed.
        r = cli(self.server.address, "swing", "start", session, "--token", token, "--qalpha",
                "1000")
        self.assertEqual(r.returncode, 3, r.stderr)  # INVALID_ARGUMENT
        self.assertIn("INVALID_ARGUMENT", r.stderr)
        info = self.cli_json("swing", "get", session)
        self.assertEqual(info["phase"], "SWING_PHASE_ADDRESS")
        self.assertEqual(info["swings"], 0)
        arcade, arcade_token = self.create("--profile", "arcade")
        started = self.cli_json("swing", "start", arcade, "--token", arcade_token, "--qalpha",
                                "1000")
        self.assertEqual(started["swing_id"], 1)
        r = cli(self.server.address, "swing", "create", "--profile", "heroic")
        self.assertEqual(r.returncode, 64, r.stderr)

    def test_create_with_club_launches_a_ball_at_each_impact(self):
        session, token = self.create("--club", "7-iron")
        watch, first = self.start_watch(session, "--until-impact")
        self.cli_json("swing", "start", session, "--token", token)
        try:
            out, err = watch.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            watch.kill()
            raise
        self.assertEqual(watch.returncode, 0, err)
        lines = [json.loads(line) for line in first + out.splitlines() if line.strip()]
        impacts = [e for line in lines for e in line.get("events", [])
                   if e["kind"] == "SWING_EVENT_IMPACT"]
        self.assertEqual(len(impacts), 1)
        ball = impacts[0]["ball"]
        self.assertEqual(ball["club"], "7-iron")
        self.assertFalse(ball["error"])
        self.assertGreater(ball["flight"]["carry_m"], 100)
        # The same ball as swing simulate --club gives for the same swing.
        simulated = self.cli_json("swing", "simulate", "--club", "7-iron")["ball"]
        self.assertEqual(ball["launch"], simulated["launch"])
        # The ball's flags mean nothing without --club.
        r = cli(self.server.address, "swing", "create", "--face-angle-deg", "2")
        self.assertEqual(r.returncode, 64, r.stderr)
        self.assertIn("--face-angle-deg: describes the ball: give --club too", r.stderr)

    def test_swing_svg_text_fits(self):
        session, token = self.create()
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "swing.svg")
            r = subprocess.run([CLI, "--server", self.server.address, "swing", "drive", session,
                                "--token", token, "--svg", path],
                               input=CHAPTER_DRIVE, capture_output=True, text=True, timeout=10)
            self.assertEqual(r.returncode, 0, r.stderr)
            root = ET.parse(path).getroot()
        width = float(root.get("width"))
        texts = list(root.iter(SVG_NS + "text"))
        self.assertGreaterEqual(len(texts), 4)
        for t in texts:
            # A generous width per character (sans-serif averages ~0.55 em).
            w = len(t.text) * 0.6 * float(t.get("font-size"))
            x = float(t.get("x"))
            left, right = (x - w, x) if t.get("text-anchor") == "end" else (x, x + w)
            self.assertGreaterEqual(left, 0, t.text)
            self.assertLessEqual(right, width, t.text)

    def test_list_reset_delete(self):
        created = self.cli_json("swing", "create", "--seats", "2", "--tick-hz", "200")
        session = created["session_id"]
        self.assertEqual(len(created["seats"]), 2)
        self.assertEqual(created["token"], created["seats"][0]["token"])
        listed = self.cli_json("swing", "list")
        self.assertIn(session, [s["session_id"] for s in listed["sessions"]])
        self.cli_json("swing", "reset", session, "--token", created["token"], "--gamma", "120",
                      "--beta0", "100")
        info = self.cli_json("swing", "get", session)
        self.assertEqual((info["gamma_deg"], info["beta0_deg"]), (120, 100))
        self.assertEqual(info["phase"], "SWING_PHASE_ADDRESS")
        self.cli_json("swing", "delete", session, "--token", created["seats"][1]["token"])
        r = cli(self.server.address, "swing", "get", session)
        self.assertEqual(r.returncode, 5, r.stderr)

    def test_drive_csv_and_svg(self):
        session, token = self.create()
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "swing.svg")
            r = subprocess.run([CLI, "--server", self.server.address, "--format", "csv", "swing",
                                "drive", session, "--token", token, "--svg", path],
                               input=CHAPTER_DRIVE, capture_output=True, text=True, timeout=10)
            self.assertEqual(r.returncode, 0, r.stderr)
            rows = list(csv.reader(io.StringIO(r.stdout)))
            self.assertEqual(tuple(rows[0]), SAMPLE_KEYS)
            self.assertGreater(len(rows), 10)
            with open(path) as f:
                self.assertIn("<svg", f.read())
            root = ET.parse(path).getroot()
            self.assertEqual(root.tag, SVG_NS + "svg")
            rods = (root.findall(".//" + SVG_NS + "line") +
                    root.findall(".//" + SVG_NS + "polyline"))
            self.assertGreaterEqual(len(rods), 10)
            self.assertIn("m/s over the ground", "".join(root.itertext()))  # the impact label


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


    def test_sigterm_while_tables_move_and_watchers_stream(self):
        with ServerProcess(SERVER) as server:
            # Slow cloth: the break is still moving after the watchers start.
            created = json.loads(cli(server.address, "--format", "json", "table", "create",
                                     "--table", "pool-9ft", "--rack", "9ball", "--param",
                                     "mu_roll=0.01").stdout)
            table, token = created["table_id"], created["seats"][0]["token"]
            self.assertEqual(cli(server.address, "table", "shoot", table, "--token", token,
                                 "--ball-speed", "6").returncode, 0)
            watchers = [subprocess.Popen([CLI, "--server", server.address, "--format", "jsonl",
                                          "table", "watch", table, "--rate", "30"],
                                         stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                         text=True) for _ in range(3)]
            for w in watchers:  # each has its first snapshot: the streams are live
                self.assertTrue(w.stdout.readline().startswith("{"))
            code, seconds, _ = server.terminate(signal.SIGTERM)
            self.assertEqual(code, 0)
            self.assertLess(seconds, 5)
            for w in watchers:
                out, err = w.communicate(timeout=10)
                self.assertEqual(w.returncode, 14, err)  # UNAVAILABLE
                self.assertIn("UNAVAILABLE", err)
                last = json.loads(out.splitlines()[-1])
                self.assertFalse(last["at_rest"])  # the last snapshot, mid-shot
                self.assertEqual(len(last["balls"]), 10)


OUTCOME_KEYS = {"index", "sample", "events_handled", "first_contact", "pocketed", "pockets",
                "t_rest_s", "balls", "events", "error"}


class ShotBatchAgainstServer(unittest.TestCase):
    """`sportsim shot batch`: strikes as JSON lines on stdin, outcomes as JSON lines on stdout."""

    STRIKES = [{"ball_speed_mps": 3, "phi_deg": 0.3, "a": 0.1},
               {"speed_mps": 2.5, "phi_deg": 10},
               {"ballSpeedMps": 1.2, "phiDeg": -135, "b": -0.2},
               {"ball_speed_mps": 6, "phi_deg": 0.1, "theta_deg": 5}]

    @classmethod
    def setUpClass(cls):
        cls.server = ServerProcess(SERVER)

    @classmethod
    def tearDownClass(cls):
        cls.server.__exit__()

    def batch(self, strikes, *args):
        text = strikes if isinstance(strikes, str) else \
            "".join(json.dumps(s) + "\n" for s in strikes)
        return subprocess.run([CLI, "--server", self.server.address, "shot", "batch", *args],
                              input=text, capture_output=True, text=True, timeout=60)

    def outcomes(self, r):
        self.assertEqual(r.returncode, 0, r.stderr)
        return [json.loads(line) for line in r.stdout.splitlines()]

    def test_one_outcome_a_line_in_input_order(self):
        for fmt in ((), ("--format", "jsonl")):
            out = self.outcomes(self.batch(self.STRIKES, "--rack", "9ball", *fmt))
            self.assertEqual(len(out), 4)
            for i, o in enumerate(out):
                self.assertEqual(set(o), OUTCOME_KEYS)
                self.assertEqual((o["index"], o["sample"]), (i, 0))
                self.assertEqual(o["error"], "")
                self.assertIsInstance(o["events_handled"], int)
                self.assertGreater(o["t_rest_s"], 0)
                self.assertEqual(o["balls"], [])
                self.assertEqual(o["events"], [])
                self.assertEqual(len(o["pocketed"]), len(o["pockets"]))
            self.assertEqual(out[0]["first_contact"], "1")  # straight at the head ball

    def test_outcomes_equal_shot_simulate(self):
        out = self.outcomes(self.batch(self.STRIKES, "--rack", "9ball", "--outcome", "events"))
        flags = {"ball_speed_mps": "--ball-speed", "speed_mps": "--speed", "phi_deg": "--phi",
                 "theta_deg": "--theta", "a": "--a", "b": "--b", "ballSpeedMps": "--ball-speed",
                 "phiDeg": "--phi"}
        for strike, o in zip(self.STRIKES, out):
            args = [a for k, v in strike.items() for a in (flags[k], str(v))]
            r = cli(self.server.address, "shot", "simulate", "--rack", "9ball", *args,
                    "--format", "json")
            self.assertEqual(r.returncode, 0, r.stderr)
            want = json.loads(r.stdout)
            self.assertEqual(o["t_rest_s"], want["t_rest_s"])  # the same double
            self.assertEqual(o["balls"], want["balls"])
            self.assertEqual(o["events"], want["events"])
            pocketed = [e["balls"][0] for e in want["events"] if e["kind"] == "ball_pocket"]
            self.assertEqual(o["pocketed"], pocketed)

    def test_noise_samples_and_seed(self):
        args = ("--rack", "9ball", "--samples", "3", "--noise", "1", "--seed", "5",
                "--outcome", "final")
        a = self.batch(self.STRIKES[:2], *args)
        out = self.outcomes(a)
        self.assertEqual([(o["index"], o["sample"]) for o in out],
                         [(i, k) for i in range(2) for k in range(3)])
        self.assertEqual(len({json.dumps(o["balls"]) for o in out[:3]}), 3)
        self.assertEqual(self.batch(self.STRIKES[:2], *args).stdout, a.stdout)
        other = self.batch(self.STRIKES[:2], *args[:-4], "--seed", "6", "--outcome", "final")
        self.assertEqual(other.returncode, 0, other.stderr)
        self.assertNotEqual(other.stdout, a.stdout)
        final = self.outcomes(other)
        self.assertEqual(len(final[0]["balls"]), 10)
        self.assertEqual(final[0]["events"], [])

    def test_a_batch_longer_than_one_request_is_sent_in_chunks(self):
        # 4000 strikes are more than the server's default request limit (64 KiB) holds: the
        # CLI sends them in chunks, and the outcomes are those of one long batch (indices, and
        # noise seeds from the index in the whole batch).
        strikes = [{"ball_speed_mps": 0.5 + (i % 7) * 0.1, "phi_deg": (i * 37) % 360,
                    "a": 0.1, "b": -0.1} for i in range(4000)]
        args = ("--rack", "empty", "--ball", "cue@0,0", "--noise", "1", "--seed", "3")
        out = self.outcomes(self.batch(strikes, *args))
        self.assertEqual([o["index"] for o in out], list(range(4000)))
        self.assertTrue(all(o["error"] == "" for o in out))
        # The tail alone, sent as its own batch, gives other noise (its indices start at 0):
        # the chunks did carry the whole batch's indices.
        tail = self.outcomes(self.batch(strikes[3990:], *args))
        self.assertEqual([o["index"] for o in tail], list(range(10)))
        self.assertNotEqual([o["t_rest_s"] for o in tail], [o["t_rest_s"] for o in out[3990:]])
        # Without noise a strike's outcome does not depend on its index.
        plain = self.outcomes(self.batch(strikes, *args[:4]))
        tail = self.outcomes(self.batch(strikes[3990:], *args[:4]))
        self.assertEqual([o["t_rest_s"] for o in tail], [o["t_rest_s"] for o in plain[3990:]])

    def test_setup_flags_and_a_strike_that_cannot_be_played(self):
        strikes = ("# candidates\n"
                   '{"ball_speed_mps": 2, "phi_deg": 0}\n'
                   "\n"
                   '{"ball_speed_mps": 2, "a": 0.9, "b": 0.9}\n'
                   '{"ball_speed_mps": 2, "ball": "ghost"}\n'
                   '{"ball_speed_mps": 2, "ball": "1", "phi_deg": 180}\n')
        out = self.outcomes(self.batch(strikes, "--table", "pool-9ft", "--rack", "empty",
                                       "--ball", "cue@-0.5,0", "--ball", "1@0,0",
                                       "--disable", "spin_decay", "--engine", "event"))
        self.assertEqual([o["index"] for o in out], [0, 1, 2, 3])
        self.assertEqual(out[0]["error"], "")
        self.assertEqual(out[0]["first_contact"], "1")
        self.assertIn("miscue", out[1]["error"])
        self.assertIn("ghost", out[2]["error"])
        self.assertEqual(out[3]["error"], "")
        self.assertEqual(out[3]["first_contact"], "cue")

    def test_json_is_one_document(self):
        r = self.batch(self.STRIKES[:2], "--format", "json")
        self.assertEqual(r.returncode, 0, r.stderr)
        doc = json.loads(r.stdout)
        self.assertEqual([o["index"] for o in doc["outcomes"]], [0, 1])
        self.assertEqual(set(doc["outcomes"][0]), OUTCOME_KEYS)

    def test_usage_errors(self):
        good = [{"ball_speed_mps": 2}]
        cases = [
            ('{"ball_speed_mps": 2}\n{"ball_speed_mps": \n', (), "line 2"),
            ('{"ball_speed_mps": 2, "spin": 1}\n', (), "line 1"),
            ('{"phi_deg": 10}\n', (), "speed"),
            ('{"ball_speed_mps": 2, "noise": 1}\n', (), "--noise"),
            ('[1, 2]\n', (), "line 1"),
            ("", (), "stdin"),
            (good, ("--outcome", "everything"), "--outcome"),
            (good, ("--speed", "2"), "--speed"),
            (good, ("--sample-rate", "100"), "--sample-rate"),
            (good, ("--format", "csv"), "csv"),
            (good, ("extra",), "extra"),
            (good, ("--engine", "warp"), "--engine"),
        ]
        for strikes, args, needle in cases:
            with self.subTest(args=args, strikes=strikes):
                r = self.batch(strikes, *args)
                self.assertEqual(r.returncode, 64, r.stderr)
                self.assertIn("sportsim: usage:", r.stderr)
                self.assertIn(needle, r.stderr)
                self.assertEqual(r.stdout, "")

    def test_server_errors_exit_with_the_code(self):
        r = self.batch([{"ball_speed_mps": 2}], "--table", "no-such-table")
        self.assertEqual(r.returncode, 3, r.stderr)  # INVALID_ARGUMENT
        self.assertIn("INVALID_ARGUMENT", r.stderr)

    def test_help_lists_the_flags(self):
        r = subprocess.run([CLI, "shot", "batch", "--help"], capture_output=True, text=True,
                           timeout=60)
        self.assertEqual(r.returncode, 0, r.stderr)
        for flag in ("--samples", "--noise", "--seed", "--outcome", "--table", "--rack", "--ball",
                     "--param", "--disable", "--engine"):
            self.assertIn(flag, r.stdout)


class CalibrateAgainstServer(unittest.TestCase):
    """`table calibrate`: track files written by `shot simulate --format csv` on a carom table
    with another rolling resistance calibrate the preset back to it."""

    @classmethod
    def setUpClass(cls):
        # Recorded shots are larger than the requests a server takes by default (64 KiB): the
        # CLI uploads them in parts, and `small` (the default) must give what `server`, which
        # would take them in one message, gives.
        cls.server = ServerProcess(SERVER, "--max_request_bytes", str(8 << 20))
        cls.small = ServerProcess(SERVER)
        cls.dir = tempfile.TemporaryDirectory()
        cls.files = []
        for name, cue, speed, phi, b in (("a.csv", "-1.0,0.1", "2.5", "20", "0.2"),
                                         ("b.csv", "0.9,-0.4", "3", "160", "-0.1")):
            r = cli(cls.server.address, "--format", "csv", "shot", "simulate", "--table", "carom",
                    "--rack", "empty", "--ball", "white@" + cue, "--ball", "yellow@0.4,0.2",
                    "--ball", "red@-0.5,-0.3", "--strike-ball", "white", "--ball-speed", speed,
                    "--phi", phi, "--b", b, "--param", "mu_roll=0.006", "--sample-rate", "50")
            assert r.returncode == 0, r.stderr
            path = os.path.join(cls.dir.name, name)
            with open(path, "w") as f:
                f.write(r.stdout)
            cls.files.append(path)

    @classmethod
    def tearDownClass(cls):
        cls.server.__exit__()
        cls.small.__exit__()
        cls.dir.cleanup()

    def test_calibrate_json_contract(self):
        r = cli(self.server.address, "--format", "json", "table", "calibrate", *self.files,
                "--table", "carom", "--fit", "mu_roll")
        self.assertEqual(r.returncode, 0, r.stderr)
        report = json.loads(r.stdout)
        self.assertAlmostEqual(report["params"]["mu_roll"], 0.006, delta=0.006 * 0.01)
        self.assertEqual([p["name"] for p in report["fitted"]], ["mu_roll"])
        self.assertEqual(report["fitted"][0]["before"], 0.0047)  # the carom preset's
        # Exact tracks determine it to within rounding; it did not end at a bound.
        self.assertLess(report["fitted"][0]["standard_error"], 1e-6)
        self.assertIs(report["fitted"][0]["at_bound"], False)
        self.assertEqual([s["name"] for s in report["shots"]], ["a.csv", "b.csv"])
        for shot in report["shots"]:
            self.assertGreater(shot["before"]["mean_m"], 0.01)
            self.assertLess(shot["after"]["mean_m"], 1e-3)
            self.assertEqual(shot["strike_after"]["ball"], "white")
            self.assertIn("ball_speed_mps", shot["strike_after"])
        for key in ("train_before_m", "train_after_m", "heldout_before_m", "heldout_after_m",
                    "iterations", "simulations", "cpu_s"):
            self.assertIn(key, report)
        self.assertIn("calibrate: 100%", r.stderr)  # progress on stderr

    def test_held_out_shots_predicted_from_their_start(self):
        # The second shot held out and fitted on its first 0.4 s, its strike the plausible
        # strikes' central rest among those that score the three-cushion point: the report
        # says how many were weighed, the text too; bad choices are usage errors.
        r = cli(self.server.address, "--format", "json", "--timeout", "300s", "table",
                "calibrate", *self.files, "--table", "carom", "--heldout", "1", "--window", "0.4",
                "--predict", "central", "--intent", "three-cushion")
        self.assertEqual(r.returncode, 0, r.stderr)
        report = json.loads(r.stdout)
        self.assertEqual(report["shots"][0]["plausible"], 0)  # a training shot: none weighed
        self.assertGreater(report["shots"][1]["plausible"], 1)
        self.assertIsInstance(report["shots"][1]["intent_met"], bool)
        r = cli(self.server.address, "--timeout", "300s", "table", "calibrate", *self.files,
                "--table", "carom", "--heldout", "1", "--window", "0.4", "--predict", "central")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRegex(r.stdout, r"b\.csv .*held out, predicted from \d+ plausible strikes?")
        for flag, value, needle in (("--predict", "median", "--predict: best-fit or central"),
                                    ("--intent", "pool", "--intent: none, three-cushion or pot")):
            r = cli(self.server.address, "table", "calibrate", *self.files, "--table", "carom",
                    flag, value)
            self.assertEqual(r.returncode, 64, r.stderr)
            self.assertIn(needle, r.stderr)

    def test_held_out_pots_predicted_with_the_pot_intended(self):
        # Two pots on a 9 ft table, the second held out and fitted on its first 0.4 s with the
        # pool player's intent: its predicted strike pots the 1 and keeps the cue ball up. A pot
        # meant on a carom table is refused, naming the field.
        files = []
        for name, cue, obj, phi, b in (("a.csv", "-0.0156,0.1687", "1.0,0.45", "14.418", "0.3"),
                                       ("b.csv", "0.1136,-0.3052", "0.9,0.4", "42.421", "-0.3")):
            r = cli(self.server.address, "--format", "csv", "shot", "simulate", "--table",
                    "pool-9ft", "--rack", "empty", "--ball", "cue@" + cue, "--ball", "1@" + obj,
                    "--strike-ball", "cue", "--ball-speed", "2.5", "--phi", phi, "--b", b,
                    "--sample-rate", "50")
            self.assertEqual(r.returncode, 0, r.stderr)
            self.assertIn(",1,", r.stdout.splitlines()[-1])
            self.assertTrue(r.stdout.rstrip().endswith(",pocketed"), r.stdout[-200:])
            path = os.path.join(self.dir.name, "pot-" + name)
            with open(path, "w") as f:
                f.write(r.stdout)
            files.append(path)
        r = cli(self.server.address, "--format", "json", "--timeout", "300s", "table",
                "calibrate", *files, "--table", "pool-9ft", "--heldout", "1", "--window", "0.4",
                "--predict", "central", "--intent", "pot")
        self.assertEqual(r.returncode, 0, r.stderr)
        report = json.loads(r.stdout)
        self.assertGreaterEqual(report["shots"][1]["plausible"], 1)
        self.assertIs(report["shots"][1]["intent_met"], True)
        r = cli(self.server.address, "--timeout", "300s", "table", "calibrate", *files,
                "--table", "pool-9ft", "--heldout", "1", "--window", "0.4", "--predict",
                "central", "--intent", "pot")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRegex(r.stdout, r"pot-b\.csv .*held out, predicted from (1 plausible strike|"
                                   r"\d+ plausible strikes), as intended")
        r = cli(self.server.address, "table", "calibrate", *files, "--table", "carom",
                "--heldout", "1", "--window", "0.4", "--intent", "pot")
        self.assertNotEqual(r.returncode, 0)
        self.assertIn("intent: POT needs a table with pockets; table 'carom' has none", r.stderr)

    def test_json_lines_track_files_calibrate_as_their_csv(self):
        # A recording's first 0.3 s as CSV and as JSON lines (as a tracker logging a detection
        # a line writes them): the strikes fitted and the report are the same, bit for bit.
        with open(self.files[0]) as f:
            rows = [row for row in csv.DictReader(f) if float(row["t_s"]) <= 0.3]
        short_csv = os.path.join(self.dir.name, "short.csv")
        short_jsonl = os.path.join(self.dir.name, "short.jsonl")
        with open(short_csv, "w") as f:
            f.write("t,ball,x,y\n")
            for row in rows:
                f.write("%s,%s,%s,%s\n" % (row["t_s"], row["id"], row["x_m"], row["y_m"]))
        with open(short_jsonl, "w") as f:
            f.write("# exported\n")
            for row in rows:
                f.write(json.dumps({"t": float(row["t_s"]), "ball": row["id"],
                                    "x": float(row["x_m"]), "y": float(row["y_m"]),
                                    "state": row["state"]}) + "\n")
        runs = []
        for path in (short_csv, short_jsonl):
            r = cli(self.server.address, "--format", "json", "--timeout", "300s", "table",
                    "calibrate", path, "--table", "carom")
            self.assertEqual(r.returncode, 0, r.stderr)
            report = json.loads(r.stdout)
            self.assertEqual(len(report["shots"]), 1)
            del report["shots"][0]["name"]
            del report["cpu_s"]
            runs.append(report)
        self.assertEqual(runs[0], runs[1])

    def test_shot_sets_in_a_trackers_frame_calibrate_as_their_csv(self):
        # Both recordings in one file, as public tracking sets come: a shot set in millimetres
        # from a corner of the playing area (2.84 x 1.42 m), balls keyed by id, and a match
        # tracker's export (fractions of the playing area, ticks of 500 us). Read in their
        # frames they calibrate the rolling resistance back as the CSV files do; --heldout
        # counts the file's shots.
        shots, entries = [], []
        for name, path in (("a", self.files[0]), ("b", self.files[1])):
            balls, datasets = {}, {}
            with open(path) as f:
                for row in csv.DictReader(f):
                    t, x, y = float(row["t_s"]), float(row["x_m"]), float(row["y_m"])
                    ball = balls.setdefault(row["id"], {"t": [], "x": [], "y": []})
                    ball["t"].append(t)
                    ball["x"].append(1000 * (x + 1.42))
                    ball["y"].append(1000 * (y + 0.71))
                    color = {"white": 1, "yellow": 2, "red": 3}[row["id"]]
                    datasets.setdefault(color, []).append(
                        {"DeltaT_500us": round(t / 0.0005), "X": (x + 1.42) / 2.84,
                         "Y": (y + 0.71) / 1.42})
            shots.append({"id": name, "balls": balls})
            entries.append({"PathTrackingId": 100 + len(entries), "PathTracking": {"DataSets": [
                {"BallColor": c, "Coords": coords} for c, coords in datasets.items()]}})
        shot_set = os.path.join(self.dir.name, "set.json")
        with open(shot_set, "w") as f:
            json.dump(shots, f)
        match = os.path.join(self.dir.name, "match.json")
        with open(match, "w") as f:
            json.dump({"Match": {"Sets": [{"Entries": [{"Scoring": {}}] + entries}]}}, f, indent=1)
        for path, frame, names in (
                (shot_set, ["--track-origin", "corner", "--track-scale", "0.001"],
                 ["set.json#a", "set.json#b"]),
                (match, [], ["match.json#100", "match.json#101"])):
            r = cli(self.server.address, "--format", "json", "table", "calibrate", path,
                    "--table", "carom", "--fit", "mu_roll", "--heldout", "1", *frame)
            self.assertEqual(r.returncode, 0, r.stderr)
            report = json.loads(r.stdout)
            self.assertAlmostEqual(report["params"]["mu_roll"], 0.006, delta=0.006 * 0.01)
            self.assertEqual([s["name"] for s in report["shots"]], names)
            self.assertEqual([s.get("heldout", False) for s in report["shots"]], [False, True])
            for shot in report["shots"]:
                self.assertEqual(shot["strike_after"]["ball"], "white" if path == shot_set else "1")
                self.assertLess(shot["after"]["mean_m"], 1e-3)
        # In the table's own frame the same numbers are kilometres off the cloth: refused.
        r = cli(self.server.address, "table", "calibrate", shot_set, "--table", "carom")
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn("not on the cloth", r.stderr)
        r = cli(self.server.address, "table", "calibrate", match, "--table", "carom",
                "--track-scale", "2")
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn("sets its own frame", r.stderr)
        r = cli(self.server.address, "table", "calibrate", shot_set, "--table", "carom",
                "--track-origin", "middle")
        self.assertEqual(r.returncode, 64, r.stderr)
        self.assertIn("--track-origin: centre or corner", r.stderr)

    def test_a_trackers_clock_started_before_the_strike(self):
        # The first recording as a tracker whose clock ran 0.25 s before the strike gives it:
        # the balls at rest at 50 Hz, then the shot. The strike's time comes back from the
        # track, and the rolling resistance as from the file that starts at the strike.
        lead = 0.25
        with open(self.files[0]) as f:
            rows = list(csv.DictReader(f))
        spots = [row for row in rows if float(row["t_s"]) <= 0]
        path = os.path.join(self.dir.name, "early.csv")
        with open(path, "w") as f:
            f.write("t,ball,x,y\n")
            for k in range(13):  # t = 0 .. 0.24
                for row in spots:
                    f.write("%g,%s,%s,%s\n" % (0.02 * k, row["id"], row["x_m"], row["y_m"]))
            for row in rows:
                if float(row["t_s"]) > 0:
                    f.write("%.17g,%s,%s,%s\n" % (float(row["t_s"]) + lead, row["id"],
                                                   row["x_m"], row["y_m"]))
        runs = {}
        for name in (path, self.files[0]):
            r = cli(self.server.address, "--format", "json", "table", "calibrate", name,
                    "--table", "carom", "--fit", "mu_roll")
            self.assertEqual(r.returncode, 0, r.stderr)
            runs[name] = json.loads(r.stdout)
        for name, when in ((path, lead), (self.files[0], 0.0)):
            report = runs[name]
            self.assertAlmostEqual(report["params"]["mu_roll"], 0.006, delta=0.006 * 0.01)
            shot = report["shots"][0]
            self.assertAlmostEqual(shot.get("strike_time_after_s", 0.0), when, delta=1e-3)
            self.assertLess(shot["after"]["mean_m"], 1e-3)
        r = cli(self.server.address, "table", "calibrate", path, "--table", "carom")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("strike s", r.stdout)
        self.assertRegex(r.stdout, r"early\.csv +[0-9.]+ +[0-9.]+ +0\.2[45]\d\d")

    def test_calibrate_text_names_the_flags_to_use(self):
        r = cli(self.server.address, "table", "calibrate", *self.files, "--table", "carom",
                "--fit", "mu_roll=0.002:0.015", "--heldout", "1")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("held out", r.stdout)
        self.assertRegex(r.stdout, r"parameter +before +after +std error +bounds")
        self.assertRegex(r.stdout, r"use: --param mu_roll=0\.00\d+")

    def test_a_constant_no_shot_moves_is_unidentified(self):
        # Air drag's coefficient, with drag off, moves no ball: its standard error is infinite
        # ("unidentified"; JSON's "Infinity"), and the rolling resistance's stays finite.
        args = ("--timeout", "5m", "table", "calibrate", *self.files, "--table", "carom",
                "--fit", "mu_roll,drag_coefficient")
        r = cli(self.server.address, *args)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRegex(r.stdout, r"drag_coefficient +\S+ +\S+ +unidentified")
        r = cli(self.server.address, "--format", "json", *args)
        self.assertEqual(r.returncode, 0, r.stderr)
        fitted = {p["name"]: p for p in json.loads(r.stdout)["fitted"]}
        self.assertEqual(fitted["drag_coefficient"]["standard_error"], "Infinity")
        self.assertIsInstance(fitted["mu_roll"]["standard_error"], float)

    def test_a_fit_stopped_by_its_bound_says_so(self):
        # The tracks' rolling resistance is 0.006; bounded to 0.003-0.005 (the preset's 0.0047
        # within them) the fit ends at 0.005.
        args = ("table", "calibrate", *self.files, "--table", "carom", "--fit",
                "mu_roll=0.003:0.005")
        r = cli(self.server.address, *args)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertRegex(r.stdout, r"mu_roll +0\.0047 +0\.00(5|49)\d* +at a bound")
        r = cli(self.server.address, "--format", "json", *args)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIs(json.loads(r.stdout)["fitted"][0]["at_bound"], True)

    def test_bad_files_and_limits(self):
        bad = os.path.join(self.dir.name, "bad.csv")
        with open(bad, "w") as f:
            f.write("t,ball,x,y\n0,white,0,0\n0.02,white,zero,0\n")
        r = cli(self.server.address, "table", "calibrate", bad, "--table", "carom")
        self.assertEqual(r.returncode, 3, r.stderr)  # INVALID_ARGUMENT, before any call
        self.assertIn("line 3: x must be a finite number", r.stderr)
        r = cli(self.server.address, "table", "calibrate", *self.files, "--table", "carom",
                "--fit", "mu_rol")
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn("fit: unknown parameter", r.stderr)
        r = cli(self.server.address, "table", "calibrate", *self.files, "--rack", "empty")
        self.assertEqual(r.returncode, 64, r.stderr)  # a usage error

    def test_hubers_loss_calibrates_through_false_detections(self):
        # Every 17th row of each file a metre off, as a tracker's false detections: under
        # --huber 0.01 the rolling resistance comes back as from the clean files, closer than
        # by least squares (the flag reaches the fit); a bad scale is refused naming the field.
        paths = []
        for path in self.files:
            with open(path) as f:
                rows = list(csv.DictReader(f))
            for i in range(16, len(rows), 17):
                if float(rows[i]["t_s"]) > 0:
                    x = float(rows[i]["x_m"])
                    rows[i]["x_m"] = repr(x - 1.0 if x > 0 else x + 1.0)
            noisy = os.path.join(self.dir.name, "false-" + os.path.basename(path))
            with open(noisy, "w") as f:
                f.write("t,ball,x,y\n")
                for row in rows:
                    f.write("%s,%s,%s,%s\n" % (row["t_s"], row["id"], row["x_m"], row["y_m"]))
            paths.append(noisy)
        fitted = []
        for extra in (["--huber", "0.01"], []):
            r = cli(self.server.address, "--format", "json", "table", "calibrate", *paths,
                    "--table", "carom", "--fit", "mu_roll", *extra)
            self.assertEqual(r.returncode, 0, r.stderr)
            fitted.append(json.loads(r.stdout)["params"]["mu_roll"])
        self.assertAlmostEqual(fitted[0], 0.006, delta=0.006 * 0.01)
        self.assertGreater(abs(fitted[1] - 0.006), 10 * abs(fitted[0] - 0.006))
        r = cli(self.server.address, "table", "calibrate", *paths, "--table", "carom",
                "--huber", "-1")
        self.assertEqual(r.returncode, 3, r.stderr)
        self.assertIn("huber_m must be in [0, 1] m", r.stderr)

    def test_read_cloth_takes_the_cloth_from_the_tracks(self):
        # --read-cloth reads the files' cloth with no model of the table: the tracks' rolling
        # resistance (0.006) and the preset's sliding friction they were made with, taken for
        # the preset's before the strikes are fitted, in the text, the json and the `use:` line.
        r = cli(self.server.address, "--format", "json", "table", "calibrate", *self.files,
                "--table", "carom", "--read-cloth")
        self.assertEqual(r.returncode, 0, r.stderr)
        report = json.loads(r.stdout)
        cloth = report["cloth"]
        self.assertAlmostEqual(cloth["mu_roll"], 0.006, delta=1e-6)
        self.assertAlmostEqual(cloth["mu_slide"], 0.175, delta=1e-5)
        self.assertGreaterEqual(cloth["rolling_stretches"], 3)
        self.assertIs(cloth["mu_roll_taken"], True)
        self.assertEqual(cloth["mu_roll_before"], 0.0047)  # the carom preset's
        self.assertEqual(report["params"]["mu_roll"], cloth["mu_roll"])
        for shot in report["shots"]:
            self.assertLess(shot["before"]["mean_m"], 1e-3)  # scored on the read cloth
        r = cli(self.server.address, "table", "calibrate", *self.files, "--table", "carom",
                "--read-cloth")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertIn("cloth read", r.stdout)
        self.assertRegex(r.stdout, r"use: --param mu_roll=0\.006 --param mu_slide=0\.175")

    def test_a_calibrations_report_is_a_param_file(self):
        # The json report of a calibration, saved, is the table's parameters for any command
        # that takes --param: calibrated (mu_roll 0.006), the same files' strikes alone fit
        # them exactly from the start; a --param beside it overrides it; a plain object of
        # parameters works too; a value that is not a number is a usage error naming it.
        r = cli(self.server.address, "--format", "json", "table", "calibrate", *self.files,
                "--table", "carom", "--fit", "mu_roll")
        self.assertEqual(r.returncode, 0, r.stderr)
        report = os.path.join(self.dir.name, "report.json")
        with open(report, "w") as f:
            f.write(r.stdout)
        plain = os.path.join(self.dir.name, "params.json")
        with open(plain, "w") as f:
            json.dump({"mu_roll": 0.006}, f)
        for path in (report, plain):
            r = cli(self.server.address, "--format", "json", "table", "calibrate", *self.files,
                    "--table", "carom", "--param-file", path)
            self.assertEqual(r.returncode, 0, r.stderr)
            for shot in json.loads(r.stdout)["shots"]:
                self.assertLess(shot["before"]["mean_m"], 1e-3)
        r = cli(self.server.address, "--format", "json", "table", "calibrate", *self.files,
                "--table", "carom", "--param-file", report, "--param", "mu_roll=0.0047")
        self.assertEqual(r.returncode, 0, r.stderr)
        for shot in json.loads(r.stdout)["shots"]:
            self.assertGreater(shot["before"]["mean_m"], 0.01)
        r = cli(self.server.address, "--format", "json", "shot", "simulate", "--table", "carom",
                "--rack", "empty", "--ball", "white@-1.0,0.1", "--strike-ball", "white",
                "--ball-speed", "1", "--param-file", report)
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(plain, "w") as f:
            json.dump({"mu_roll": "fast"}, f)
        r = cli(self.server.address, "table", "create", "--table", "carom", "--param-file", plain)
        self.assertEqual(r.returncode, 64, r.stderr)
        self.assertIn('"mu_roll" must be a number', r.stderr)
        # The report of strikes alone moved no parameter: said so, not a confusing key.
        r = cli(self.server.address, "--format", "json", "table", "calibrate", *self.files,
                "--table", "carom")
        self.assertEqual(r.returncode, 0, r.stderr)
        with open(report, "w") as f:
            f.write(r.stdout)
        r = cli(self.server.address, "table", "create", "--table", "carom", "--param-file", report)
        self.assertEqual(r.returncode, 64, r.stderr)
        self.assertIn("a calibration report that moved no parameters", r.stderr)

    def test_a_server_with_the_default_request_limit_calibrates_uploaded_shots(self):
        # The two recordings are larger than one request may be by default (64 KiB); the CLI
        # uploads them in parts (UploadCalibration), and the report is the one a server with
        # a larger limit gives.
        size = sum(os.path.getsize(f) for f in self.files)
        self.assertGreater(size, 64 << 10)
        reports = []
        for server in (self.small, self.server):
            r = cli(server.address, "--format", "json", "table", "calibrate", *self.files,
                    "--table", "carom", "--fit", "mu_roll")
            self.assertEqual(r.returncode, 0, r.stderr)
            report = json.loads(r.stdout)
            del report["cpu_s"]
            reports.append(report)
        self.assertEqual(reports[0], reports[1])
        self.assertAlmostEqual(reports[0]["params"]["mu_roll"], 0.006, delta=0.006 * 0.01)


if __name__ == "__main__":
    unittest.main(verbosity=2)
