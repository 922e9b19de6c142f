// The viewer's gRPC-Web client (src/rpc.js: connect-web's gRPC-Web transport and the generated
// messages) against a tiny fake gRPC-Web server written here by hand: 5-byte frames (flag,
// big-endian length), a trailers frame (flag 0x80) with grpc-status and a percent-encoded
// grpc-message, trailers-only errors in the HTTP headers, and a server stream whose messages
// must reach the client one by one, before the server has finished. Run: node --test web/test/
import { test } from "node:test";
import assert from "node:assert/strict";
import http from "node:http";
import { create, fromBinary, toBinary } from "@bufbuild/protobuf";
import { Code, ConnectError } from "@connectrpc/connect";
import { makeClients } from "../src/rpc.js";
import {
  GetTableRequestSchema, TableInfoSchema, TableSnapshotSchema, WatchTableRequestSchema,
  PreviewShotRequestSchema, PreviewShotResponseSchema, EventKind,
} from "../gen/sportsim/v1/billiards_pb.js";

function frame(flag, bytes) {
  const out = Buffer.alloc(5 + bytes.length);
  out[0] = flag;
  out.writeUInt32BE(bytes.length, 1);
  Buffer.from(bytes).copy(out, 5);
  return out;
}
const trailers = (code, message = "") =>
  frame(0x80, Buffer.from(`grpc-status: ${code}\r\ngrpc-message: ${encodeURIComponent(message)}\r\n`));

function readRequest(req) {
  return new Promise((resolve) => {
    const chunks = [];
    req.on("data", (c) => chunks.push(c));
    req.on("end", () => {
      const body = Buffer.concat(chunks);
      assert.equal(body[0], 0, "request frame flag");
      const len = body.readUInt32BE(1);
      assert.equal(body.length, 5 + len, "one request frame");
      resolve(body.subarray(5));
    });
  });
}

// The fake server. `streamGate` lets a test release the stream's second message.
let streamGate = null;
const server = http.createServer(async (req, res) => {
  assert.equal(req.method, "POST");
  assert.match(req.headers["content-type"], /^application\/grpc-web\+proto/);
  const body = await readRequest(req);
  const ok = { "content-type": "application/grpc-web+proto" };
  switch (req.url) {
    case "/sportsim.v1.Billiards/GetTable": {
      const r = fromBinary(GetTableRequestSchema, body);
      if (r.tableId === "missing") {   // trailers-only: the status in the HTTP headers
        res.writeHead(200, { ...ok, "grpc-status": "5", "grpc-message": encodeURIComponent("table missing not found") });
        res.end();
        return;
      }
      const info = create(TableInfoSchema, {
        tableId: r.tableId, tick: 1234n, tS: 1234 / 120, atRest: true,
        geometry: r.includeGeometry ? { preset: "pool-9ft", lengthM: 2.54, widthM: 1.27 } : undefined,
        balls: [{ id: "cue", xM: -0.635, yM: 0 }],
      });
      res.writeHead(200, ok);
      // The message split across two writes, then the trailers.
      const f = frame(0, toBinary(TableInfoSchema, info));
      res.write(f.subarray(0, 3));
      setTimeout(() => { res.write(f.subarray(3)); res.end(trailers(0)); }, 10);
      return;
    }
    case "/sportsim.v1.Billiards/PreviewShot": {
      const r = fromBinary(PreviewShotRequestSchema, body);
      res.writeHead(200, ok);
      if (r.token !== "seat0") {       // an error after the headers: in the trailers frame
        res.end(trailers(7, "not the seat to play: 50% sure"));
        return;
      }
      const out = create(PreviewShotResponseSchema, {
        paths: [{ ball: r.strike.ball, points: [{ tS: 0, xM: -0.6, yM: 0 }, { tS: 0.5, xM: 0.5, yM: 0 }] }],
      });
      res.end(Buffer.concat([frame(0, toBinary(PreviewShotResponseSchema, out)), trailers(0)]));
      return;
    }
    case "/sportsim.v1.Billiards/WatchTable": {
      const r = fromBinary(WatchTableRequestSchema, body);
      res.writeHead(200, ok);
      const snap = (seq) => frame(0, toBinary(TableSnapshotSchema, create(TableSnapshotSchema, {
        tableId: r.tableId, sequence: BigInt(seq), tick: BigInt(seq * 2), tS: seq / 60,
        balls: [{ id: "cue", xM: seq / 100, yM: 0 }],
        events: seq === 2 ? [{ kind: EventKind.ball_cushion, balls: ["cue"], cushion: "top_rail" }] : [],
      })));
      res.write(snap(1));
      await new Promise((resolve) => { streamGate = resolve; });
      res.write(snap(2));
      res.end(trailers(0));
      return;
    }
    default:
      res.writeHead(200, { ...ok, "grpc-status": "12", "grpc-message": "unimplemented" });
      res.end();
  }
});

await new Promise((r) => server.listen(0, "127.0.0.1", r));
const base = `http://127.0.0.1:${server.address().port}`;
const { billiards } = makeClients(base);
test.after(() => server.close());

test("unary call: request and response through the generated messages", async () => {
  const info = await billiards.getTable({ tableId: "t-1", includeGeometry: true });
  assert.equal(info.tableId, "t-1");
  assert.equal(info.tick, 1234n);
  assert.equal(info.geometry.lengthM, 2.54);
  assert.equal(info.balls[0].xM, -0.635);
});

test("trailers-only error: status and message from the HTTP headers", async () => {
  await assert.rejects(billiards.getTable({ tableId: "missing" }), (e) => {
    assert.ok(e instanceof ConnectError);
    assert.equal(e.code, Code.NotFound);
    assert.equal(e.rawMessage, "table missing not found");
    return true;
  });
});

test("error in the trailers frame, percent-decoded", async () => {
  await assert.rejects(
    billiards.previewShot({ tableId: "t-1", token: "other", strike: { ball: "cue", speed: { case: "speedMps", value: 2 } } }),
    (e) => e.code === Code.PermissionDenied && e.rawMessage === "not the seat to play: 50% sure");
  const ok = await billiards.previewShot({ tableId: "t-1", token: "seat0", strike: { ball: "cue" } });
  assert.equal(ok.paths[0].ball, "cue");
  assert.equal(ok.paths[0].points[1].xM, 0.5);
});

test("server stream: each message arrives before the server sends the next", async () => {
  const got = [];
  for await (const s of billiards.watchTable({ tableId: "t-1", rateHz: 60 })) {
    got.push(s);
    if (got.length === 1) {
      assert.equal(s.sequence, 1n);
      assert.ok(streamGate, "the server is waiting: the first message was delivered incrementally");
      streamGate();
    }
  }
  assert.equal(got.length, 2);
  assert.equal(got[1].events[0].cushion, "top_rail");
  assert.equal(got[1].balls[0].xM, 0.02);
});

test("unknown method: UNIMPLEMENTED", async () => {
  const { swing } = makeClients(base);
  await assert.rejects(swing.getSession({ sessionId: "s" }), (e) => e.code === Code.Unimplemented);
});
