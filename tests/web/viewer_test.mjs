// The browser viewer end to end: the real sportsim-server (gRPC on a free loopback port, gRPC-Web
// and the built viewer on --http_listen), headless Debian Chromium driven by puppeteer-core, and
// the sportsim CLI as an independent client that creates tables and sessions and reads the truth
// (table get). Checks what the pages draw against the server's state, saves a screenshot of each
// page under the build directory, and prints the measurements (transfer size, frames per second
// during a break, snapshot-to-paint delay).
//
// Environment: SPORTSIM_BIN_DIR (sportsim-server, sportsim), SPORTSIM_WEB_DIR (the built viewer),
// SPORTSIM_WEB_SRC (web/: node_modules and src/rpc.js), SPORTSIM_TEST_OUT (screenshots).
// SPORTSIM_WEB_URL with SPORTSIM_GRPC_ADDR: use a server that is already running instead.
import { test, before, after } from "node:test";
import assert from "node:assert/strict";
import { spawn, execFileSync } from "node:child_process";
import { createRequire } from "node:module";
import fs from "node:fs";
import net from "node:net";
import os from "node:os";
import path from "node:path";
import readline from "node:readline";
import { pathToFileURL } from "node:url";

const BIN = path.resolve(process.env.SPORTSIM_BIN_DIR);
const WEB_DIR = path.resolve(process.env.SPORTSIM_WEB_DIR || "");
const WEB_SRC = path.resolve(process.env.SPORTSIM_WEB_SRC);
const OUT = process.env.SPORTSIM_TEST_OUT || fs.mkdtempSync(path.join(os.tmpdir(), "sportsim-web-"));
const require = createRequire(path.join(WEB_SRC, "package.json"));
const puppeteer = require("puppeteer-core");
const { PNG } = require("pngjs");
const { makeClients } = await import(pathToFileURL(path.join(WEB_SRC, "src", "rpc.js")).href);

const CHROMIUM = process.env.SPORTSIM_CHROMIUM || "/usr/bin/chromium";
const CHROMIUM_ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking",
  "--disable-component-update", "--disable-sync", "--no-first-run", "--disable-quic"];

let server = null, browser = null, userDataDir = null, baseUrl = "", grpcAddr = "", rpc = null;

const measurements = {};

function freePort() {
  return new Promise((resolve, reject) => {
    const s = net.createServer();
    s.once("error", reject);
    s.listen(0, "127.0.0.1", () => { const p = s.address().port; s.close(() => resolve(p)); });
  });
}

function cli(...args) {
  const out = execFileSync(path.join(BIN, "sportsim"), ["--server", grpcAddr, "--format", "json", ...args],
    { encoding: "utf8", timeout: 60000 });
  return out.trim() ? JSON.parse(out) : null;
}

async function startServer() {
  const httpPort = await freePort();
  const proc = spawn(path.join(BIN, "sportsim-server"),
    ["--listen", "127.0.0.1:0", "--http_listen", `127.0.0.1:${httpPort}`, "--web_root", WEB_DIR],
    { stdio: ["ignore", "pipe", "pipe"] });
  let stderr = "";
  proc.stderr.on("data", (d) => { stderr += d; });
  const lines = readline.createInterface({ input: proc.stdout });
  const port = await new Promise((resolve, reject) => {
    const timer = setTimeout(() => reject(new Error("server did not start: " + stderr)), 20000);
    lines.on("line", (line) => {
      const m = line.match(/listening on (\S+):(\d+)$/);
      if (m) { clearTimeout(timer); resolve(+m[2]); }
    });
    proc.once("exit", (code) => reject(new Error(`server exited ${code}: ${stderr}`)));
  });
  const url = `http://127.0.0.1:${httpPort}`;
  for (let i = 0; ; i++) {          // the HTTP listener may come up a moment after gRPC's
    try { if ((await fetch(url + "/")).ok) break; } catch { /* not yet */ }
    if (i > 100) throw new Error("no viewer at " + url + ": " + stderr);
    await new Promise((r) => setTimeout(r, 100));
  }
  return { proc, grpcAddr: `127.0.0.1:${port}`, url };
}

before(async () => {
  if (process.env.SPORTSIM_WEB_URL) {
    baseUrl = process.env.SPORTSIM_WEB_URL;
    grpcAddr = process.env.SPORTSIM_GRPC_ADDR;
  } else {
    server = await startServer();
    baseUrl = server.url;
    grpcAddr = server.grpcAddr;
  }
  rpc = makeClients(baseUrl);
  userDataDir = fs.mkdtempSync(path.join(os.tmpdir(), "sportsim-chromium-"));
  browser = await puppeteer.launch({ executablePath: CHROMIUM, headless: true, userDataDir, args: CHROMIUM_ARGS });
  fs.mkdirSync(OUT, { recursive: true });
});

after(async () => {
  if (browser) await browser.close();
  if (server) { server.proc.kill("SIGTERM"); }
  if (userDataDir) fs.rmSync(userDataDir, { recursive: true, force: true });
  console.log("measurements " + JSON.stringify(measurements));
});

async function openPage(route) {
  const page = await browser.newPage();
  const errors = [];
  page.on("pageerror", (e) => errors.push(e.message));
  page.on("console", (m) => { if (m.type() === "error") errors.push(m.text()); });
  await page.setViewport({ width: 1400, height: 820 });
  await page.goto(baseUrl + route, { waitUntil: "load" });
  page.errors = errors;
  return page;
}

const viewer = (page) => page.evaluate(() => {
  const v = { ...window.__viewer };
  delete v.stop;
  return v;
});

async function waitFor(page, fn, arg, timeout = 20000) {
  await page.waitForFunction(fn, { timeout, polling: 50 }, arg);
}

// A screenshot that shows something: decoded, with many colours, none of them (nearly) everywhere.
async function screenshot(page, name, maxShare = 0.9) {
  const file = path.join(OUT, name);
  await page.screenshot({ path: file });
  const png = PNG.sync.read(fs.readFileSync(file));
  const counts = new Map();
  for (let i = 0; i < png.data.length; i += 4) {
    const key = (png.data[i] << 16) | (png.data[i + 1] << 8) | png.data[i + 2];
    counts.set(key, (counts.get(key) || 0) + 1);
  }
  const pixels = png.width * png.height;
  const top = Math.max(...counts.values());
  assert.ok(counts.size >= 16, `${name}: only ${counts.size} colours`);
  assert.ok(top / pixels < maxShare, `${name}: one colour covers ${(100 * top / pixels).toFixed(1)}%`);
  return { file, colours: counts.size, dominantShare: +(top / pixels).toFixed(3) };
}

function expectedPx(t, x, y) { return [t.ox + x * t.scale, t.oy - y * t.scale]; }

function compareBalls(v, truth, tolPx) {
  const onTable = truth.filter((b) => b.state !== "pocketed");
  assert.equal(v.ballsDrawn.length, onTable.length, "balls drawn vs on the table");
  const drawn = new Map(v.ballsDrawn.map((b) => [b.id, b]));
  let worst = 0;
  for (const b of onTable) {
    const d = drawn.get(b.id);
    assert.ok(d, `ball ${b.id} not drawn`);
    const [ex, ey] = expectedPx(v.transform, b.x_m, b.y_m);
    worst = Math.max(worst, Math.hypot(d.x - ex, d.y - ey));
  }
  assert.ok(worst <= tolPx, `drawn positions off by ${worst.toFixed(3)} px`);
  return worst;
}

function stats(xs) {
  const s = [...xs].sort((a, b) => a - b);
  const q = (p) => s[Math.min(s.length - 1, Math.floor(p * s.length))];
  return { n: s.length, median: +q(0.5).toFixed(1), p95: +q(0.95).toFixed(1), max: +s[s.length - 1].toFixed(1) };
}

test("list page shows tables, sessions and rounds with links", async () => {
  const t = cli("table", "create", "--table", "pool-9ft");
  const s = cli("swing", "create");
  const r = cli("round", "create", "--players", "Cat");
  const page = await openPage("/");
  await waitFor(page, ([tid, sid, rid]) => {
    const v = window.__viewer;
    return v.listed && v.listed.tables.includes(tid) && v.listed.sessions.includes(sid) &&
      v.listed.rounds.includes(rid);
  }, [t.table_id, s.session_id, r.round_id]);
  const links = await page.$$eval("a", (as) => as.map((a) => a.getAttribute("href")));
  assert.ok(links.includes("/table/" + t.table_id));
  assert.ok(links.includes("/swing/" + s.session_id));
  assert.ok(links.includes("/round/" + r.round_id));
  // Transfer size of the page itself: the document and its script and style sheet.
  const size = await page.evaluate(() => {
    const nav = performance.getEntriesByType("navigation")[0];
    const res = performance.getEntriesByType("resource").filter((r) => r.initiatorType !== "fetch");
    return {
      transfer: nav.transferSize + res.reduce((a, r) => a + r.transferSize, 0),
      decoded: nav.decodedBodySize + res.reduce((a, r) => a + r.decodedBodySize, 0),
      files: res.map((r) => [new URL(r.name).pathname, r.transferSize]),
    };
  });
  measurements.page_transfer_bytes = size.transfer;
  measurements.page_decoded_bytes = size.decoded;
  measurements.screenshot_list = await screenshot(page, "web-list.png", 0.99);  // text on a plain page
  assert.deepEqual(page.errors, []);
  await page.close();
});

test("table page draws cushions, pockets and the balls where the server has them", async () => {
  const t = cli("table", "create", "--table", "pool-9ft", "--game", "8ball");
  const page = await openPage("/table/" + t.table_id);
  await waitFor(page, () => window.__viewer.ready && window.__viewer.snapshots > 0);
  const v = await viewer(page);
  const truth = cli("table", "get", t.table_id, "--geometry");
  assert.equal(v.cushionsDrawn, truth.geometry.cushions.length);
  assert.equal(v.pocketsDrawn, truth.geometry.pockets.length);
  assert.ok(v.cushionsDrawn > 0 && v.pocketsDrawn === 6);
  compareBalls(v, truth.balls, 1);
  assert.match(v.gameText, /8ball/);
  assert.match(v.gameText, /seat 0.*to play/);
  assert.match(v.gameText, /Ball in hand: kitchen/);
  measurements.screenshot_table = await screenshot(page, "web-table.png");
  assert.deepEqual(page.errors, []);
  await page.close();
});

test("seat token: aim line from PreviewShot, shoot, balls move, come to rest where the server says", async () => {
  const t = cli("table", "create", "--table", "pool-9ft", "--seats", "2");
  const token = t.seats[0].token;
  const before = cli("table", "get", t.table_id).balls;
  const page = await openPage(`/table/${t.table_id}#token=${token}`);
  await waitFor(page, () => window.__viewer.ready && window.__viewer.snapshots > 0);
  let v = await viewer(page);

  // Aim at the apex ball of the rack: the mouse over its drawn position.
  const canvas = await page.$("#table");
  const box = await canvas.boundingBox();
  const apex = v.ballsDrawn.find((b) => b.id === "1");
  await page.evaluate(() => {
    const speed = document.getElementById("speed");
    speed.value = "7";
    speed.dispatchEvent(new Event("input"));
  });
  await page.mouse.move(box.x + apex.x - 40, box.y + apex.y + 5);
  await page.mouse.move(box.x + apex.x, box.y + apex.y, { steps: 8 });
  await waitFor(page, () => window.__viewer.previews > 0 && window.__viewer.aimLine.length > 0);
  await new Promise((r) => setTimeout(r, 300));   // the throttled last request lands
  v = await viewer(page);
  const strike = v.aimStrike;
  assert.equal(strike.ball, "cue");
  assert.ok(Math.abs(strike.phiDeg) < 2, `aim phi ${strike.phiDeg}`);
  // The server's own PreviewShot for that strike, asked independently of the page.
  const preview = await rpc.billiards.previewShot({
    tableId: t.table_id, token,
    strike: { ball: strike.ball, speed: { case: "speedMps", value: strike.speedMps }, phiDeg: strike.phiDeg, a: strike.a, b: strike.b },
    maxEvents: 3,
  });
  assert.ok(preview.paths.length >= 1);
  assert.equal(preview.paths[0].ball, "cue");
  assert.equal(v.aimLine.length, preview.paths.length);
  let worstAim = 0;
  preview.paths.forEach((p, k) => {
    assert.equal(v.aimLine[k].length, p.points.length);
    p.points.forEach((q, i) => {
      const [ex, ey] = expectedPx(v.transform, q.xM, q.yM);
      worstAim = Math.max(worstAim, Math.hypot(v.aimLine[k][i].x - ex, v.aimLine[k][i].y - ey));
    });
  });
  assert.ok(worstAim <= 0.5, `aim line off PreviewShot's path by ${worstAim} px`);
  measurements.aim_line_max_error_px = +worstAim.toFixed(4);
  measurements.screenshot_aim = await screenshot(page, "web-table-aim.png");

  // Shoot (the break), count animation frames while the balls move.
  const f0 = await page.evaluate(() => ({ frames: window.__viewer.frames, t: performance.now(), n: window.__viewer.paintDelaysMs.length }));
  await page.click("#shoot");
  await waitFor(page, () => window.__viewer.shots === 1 && window.__viewer.atRest === false, null, 10000);
  const moving = await page.evaluate(() => ({ frames: window.__viewer.frames, t: performance.now() }));
  await page.screenshot({ path: path.join(OUT, "web-table-moving.png") });
  await waitFor(page, () => window.__viewer.atRest === true, null, 60000);
  const rest = await page.evaluate(() => ({ frames: window.__viewer.frames, t: performance.now() }));
  await new Promise((r) => setTimeout(r, 500));   // the playout clock reaches the last snapshot
  v = await viewer(page);
  const seconds = (rest.t - moving.t) / 1000;
  measurements.break_seconds = +seconds.toFixed(2);
  measurements.fps_during_break = +((rest.frames - moving.frames) / seconds).toFixed(1);
  assert.ok(measurements.fps_during_break > 20, `only ${measurements.fps_during_break} frames per second`);
  const delays = v.paintDelaysMs.slice(f0.n);
  const published = v.publishToPaintMs.slice(f0.n);
  assert.ok(delays.length > 10, "snapshots painted during the shot");
  measurements.snapshots_painted = delays.length;
  measurements.arrival_to_paint_ms = stats(delays);
  measurements.publication_to_paint_ms = stats(published);

  const truth = cli("table", "get", t.table_id);
  assert.equal(truth.at_rest, true);
  const moved = truth.balls.filter((b) => {
    const o = before.find((q) => q.id === b.id);
    return !o || b.state === "pocketed" || Math.hypot(b.x_m - o.x_m, b.y_m - o.y_m) > 0.01;
  });
  assert.ok(moved.length >= 3, `only ${moved.length} balls moved`);
  measurements.final_position_max_error_px = +compareBalls(v, truth.balls, 1).toFixed(4);
  assert.equal(v.lastSnapshotSeq >= Number(truth.sequence) - 1, true);
  measurements.screenshot_after_break = await screenshot(page, "web-table-after.png");
  assert.deepEqual(page.errors, []);
  await page.close();
});

test("place mode: a click on the cloth puts the cue ball there (PlaceBall)", async () => {
  const t = cli("table", "create", "--table", "pool-9ft", "--rack", "empty", "--ball", "1@0.5,0", "--ball", "cue@-0.5,0");
  const token = t.seats[0].token;
  const page = await openPage(`/table/${t.table_id}#token=${token}`);
  await waitFor(page, () => window.__viewer.ready && window.__viewer.snapshots > 0);
  const v = await viewer(page);
  await page.click("#place");
  const box = await (await page.$("#table")).boundingBox();
  const [px, py] = expectedPx(v.transform, -0.3, 0.2);
  await page.mouse.click(box.x + px, box.y + py);
  await waitFor(page, () => {
    const c = window.__viewer.ballsDrawn.find((b) => b.id === "cue");
    const t = window.__viewer.transform;
    return c && Math.hypot(c.x - (t.ox - 0.3 * t.scale), c.y - (t.oy - 0.2 * t.scale)) < 2;
  });
  const truth = cli("table", "get", t.table_id);
  const cue = truth.balls.find((b) => b.id === "cue");
  assert.ok(Math.abs(cue.x_m + 0.3) < 0.01 && Math.abs(cue.y_m - 0.2) < 0.01, JSON.stringify(cue));
  assert.deepEqual(page.errors, []);
  await page.close();
});

test("round page draws the hole, the balls where the server has them, and plays a stroke", async () => {
  const made = cli("round", "create", "--players", "Ann,Bob", "--play", "stableford", "--handicaps", "12,-");
  const ann = made.seats[0].token;
  const page = await openPage("/round/" + made.round_id + "#token=" + ann);
  await waitFor(page, () => window.__viewer.ready && window.__viewer.round && window.__viewer.round.ballsDrawn.length === 2);
  let v = await viewer(page);
  assert.ok(v.round.areasDrawn > 10, `${v.round.areasDrawn} surface areas drawn`);
  assert.ok(v.round.shadedCells > 1000, "hill shading drawn");
  assert.equal(v.round.scorecardRows, 2);
  assert.equal(v.round.play, "stableford");
  const at = (tf, x, y) => [tf.ox + x * tf.scale, tf.oy - y * tf.scale];
  let truth = cli("round", "get", made.round_id).round;
  const pin = at(v.round.transform, truth.pin_x_m, truth.pin_y_m);
  assert.ok(Math.hypot(pin[0] - v.round.pinPx[0], pin[1] - v.round.pinPx[1]) < 0.5, "the pin where the server has it");
  for (const b of v.round.ballsDrawn) {
    const p = truth.players[b.seat].ball;
    const want = at(v.round.transform, p.x_m, p.y_m);
    assert.ok(Math.hypot(want[0] - b.x, want[1] - b.y) < 0.5, `seat ${b.seat} drawn at its ball`);
  }
  // Ann drives from the page: the driver at full power, at the pin.
  await page.select("#club", "driver");
  await page.click("#play");
  await waitFor(page, () => window.__viewer.round.played === 1 || window.__viewer.round.lastError);
  v = await viewer(page);
  assert.equal(v.round.lastError, "");
  for (let i = 0; i < 200; i++) {
    truth = cli("round", "get", made.round_id).round;
    if (!truth.stroke_in_play) break;
    await new Promise((r) => setTimeout(r, 100));
  }
  assert.equal(truth.players[0].strokes, 1);
  assert.equal(truth.stroke_in_play, false);
  const ball = truth.players[0].ball;
  assert.ok(ball.distance_to_pin_m < 250, `the drive went toward the pin (${ball.distance_to_pin_m} m left)`);
  await waitFor(page, (b) => {
    const r = window.__viewer.round;
    const d = r.ballsDrawn.find((x) => x.seat === 0);
    const tf = r.transform;
    return d && Math.hypot(d.x - (tf.ox + b.x_m * tf.scale), d.y - (tf.oy - b.y_m * tf.scale)) < 0.5;
  }, ball);
  v = await viewer(page);
  assert.ok(v.round.pathPoints[0] > 5, `the drive's path drawn from its live frames (${v.round.pathPoints[0]} points)`);
  // Not Ann's turn now: the page shows the server's refusal, and nothing changes.
  await page.click("#play");
  await waitFor(page, () => window.__viewer.round.lastError !== "");
  v = await viewer(page);
  assert.match(v.round.lastError, /Rule 6\.4/);
  assert.equal(cli("round", "get", made.round_id).round.players[0].strokes, 1);
  measurements.screenshot_round = await screenshot(page, "web-round.png");
  assert.deepEqual(page.errors, []);
  await page.close();
});

test("swing page shows the swing through impact and the ball's flight", async () => {
  const s = cli("swing", "create", "--club", "driver");
  const page = await openPage("/swing/" + s.session_id);
  await waitFor(page, () => window.__viewer.ready && window.__viewer.swing && window.__viewer.swing.armPx);
  cli("swing", "start", s.session_id, "--token", s.token);
  await waitFor(page, () => {
    const w = window.__viewer.swing;
    return w.impact && w.flightPointsDrawn > 0 && w.phase === "finished";
  }, null, 30000);
  await new Promise((r) => setTimeout(r, 200));
  const v = await viewer(page);
  const w = v.swing;
  assert.ok(w.speedPointsDrawn > 20, `${w.speedPointsDrawn} speed samples drawn`);
  assert.ok(w.impact.clubheadSpeedMps > 20 && w.impact.tS > 0.1, JSON.stringify(w.impact));
  assert.ok(w.flight.carryM > 50, JSON.stringify(w.flight));
  const info = await rpc.swing.getSession({ sessionId: s.session_id });
  assert.ok(Math.abs(info.lastImpact.clubheadSpeedMps - w.impact.clubheadSpeedMps) < 1e-9);
  // At impact the shaft points straight down: the clubhead is below the wrists.
  const [wr, ch] = w.clubPx;
  assert.ok(ch[1] > wr[1], "clubhead below the wrists after the swing");
  measurements.swing_impact_mps = +w.impact.clubheadSpeedMps.toFixed(2);
  measurements.swing_states_received = w.states;
  measurements.screenshot_swing = await screenshot(page, "web-swing.png");
  assert.deepEqual(page.errors, []);
  await page.close();
});
