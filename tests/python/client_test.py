"""A non-C++ client from our proto alone: Debian's python3-grpcio with stubs that the build
generated (protoc + grpc_python_plugin), against the real server binary."""
import math
import os
import sys
import unittest

sys.path.insert(0, os.environ["SPORTSIM_PYTHON_STUBS"])
sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "support"))

import grpc  # noqa: E402
import health_pb2  # noqa: E402  (grpc.health.v1, generated flat)
import health_pb2_grpc  # noqa: E402
from sportsim.v1 import billiards_pb2, billiards_pb2_grpc  # noqa: E402
from sportsim.v1 import common_pb2, common_pb2_grpc, swing_pb2, swing_pb2_grpc  # noqa: E402
from server_proc import ServerProcess  # noqa: E402

SERVER = os.path.join(os.environ["SPORTSIM_BIN_DIR"], "sportsim-server")


class PythonClient(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.server = ServerProcess(SERVER)
        cls.channel = grpc.insecure_channel(cls.server.address)
        grpc.channel_ready_future(cls.channel).result(timeout=30)

    @classmethod
    def tearDownClass(cls):
        cls.channel.close()
        cls.server.__exit__()

    def test_get_info(self):
        info = common_pb2_grpc.ServerStub(self.channel).GetInfo(common_pb2.GetInfoRequest(),
                                                                timeout=30)
        self.assertEqual(info.version, "0.1.0")
        self.assertIn("dp45", info.capabilities.swing_integrators)
        self.assertIn("sportsim.v1.Swing", info.capabilities.services)

    def test_health(self):
        r = health_pb2_grpc.HealthStub(self.channel).Check(health_pb2.HealthCheckRequest(),
                                                          timeout=30)
        self.assertEqual(r.status, health_pb2.HealthCheckResponse.SERVING)

    def test_simulate_swing(self):
        req = swing_pb2.SimulateSwingRequest(
            solver=swing_pb2.SwingSolver(integrator=swing_pb2.SWING_INTEGRATOR_DP45,
                                         tolerance=1e-10))
        r = swing_pb2_grpc.SwingStub(self.channel).SimulateSwing(req, timeout=30)
        self.assertTrue(r.HasField("impact"))
        self.assertAlmostEqual(r.impact.t_s, 0.291391707953, delta=1e-9)
        self.assertAlmostEqual(r.impact.clubhead_speed_mps, 42.5162746884, delta=1e-7)
        self.assertTrue(all(math.isfinite(s.phi_deg) for s in r.samples))

    def test_invalid_argument(self):
        req = swing_pb2.SimulateSwingRequest(
            parameters=swing_pb2.SwingParameters(club_length_m=float("inf")))
        with self.assertRaises(grpc.RpcError) as e:
            swing_pb2_grpc.SwingStub(self.channel).SimulateSwing(req, timeout=30)
        self.assertEqual(e.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("parameters.club_length_m", e.exception.details())

    def test_simulate_shot(self):
        req = billiards_pb2.SimulateShotRequest(
            table=billiards_pb2.TableSetup(
                preset="pool-9ft", rack="empty",
                balls=[billiards_pb2.BallPlacement(id="cue", x_m=-0.5, y_m=0),
                       billiards_pb2.BallPlacement(id="1", x_m=0, y_m=0)]),
            strike=billiards_pb2.CueStrike(ball_speed_mps=2.0))
        r = billiards_pb2_grpc.BilliardsStub(self.channel).SimulateShot(req, timeout=30)
        self.assertTrue(r.at_rest)
        self.assertGreater(r.t_rest_s, 0)
        self.assertEqual([b.id for b in r.balls], ["cue", "1"])
        self.assertEqual([billiards_pb2.MotionState.Name(b.state) for b in r.balls],
                         ["stationary", "stationary"])
        # The enum value names are the lower-case JSON spelling of the command-line contract.
        first = next(e for e in r.events if e.kind == billiards_pb2.ball_ball)
        self.assertEqual(billiards_pb2.EventKind.Name(first.kind), "ball_ball")
        for e in r.events:
            kind = billiards_pb2.EventKind.Name(e.kind)
            self.assertIn(kind, ("ball_ball", "ball_cushion", "ball_pocket", "transition"))
        self.assertEqual(list(first.balls), ["cue", "1"])
        self.assertEqual([a.id for a in first.after], ["cue", "1"])
        self.assertGreater(first.after[1].vx_mps, 1.0)
        for e in r.events:
            if e.kind == billiards_pb2.transition:
                self.assertTrue(e.HasField("from") and e.HasField("to"))

    def test_simulate_shot_invalid_argument(self):
        req = billiards_pb2.SimulateShotRequest(
            table=billiards_pb2.TableSetup(rack="7ball"),
            strike=billiards_pb2.CueStrike(ball_speed_mps=2.0))
        with self.assertRaises(grpc.RpcError) as e:
            billiards_pb2_grpc.BilliardsStub(self.channel).SimulateShot(req, timeout=30)
        self.assertEqual(e.exception.code(), grpc.StatusCode.INVALID_ARGUMENT)
        self.assertIn("table.rack", e.exception.details())

    def test_server_reflection_lists_our_services(self):
        # grpc.reflection.v1alpha.ServerReflectionRequest{list_services: ""}: field 7, length 0.
        call = self.channel.stream_stream(
            "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
            request_serializer=lambda b: b, response_deserializer=lambda b: b)
        responses = list(call(iter([b"\x3a\x00"]), timeout=30))
        self.assertEqual(len(responses), 1)
        self.assertIn(b"sportsim.v1.Swing", responses[0])
        self.assertIn(b"sportsim.v1.Server", responses[0])
        self.assertIn(b"sportsim.v1.Billiards", responses[0])


if __name__ == "__main__":
    unittest.main(verbosity=2)
