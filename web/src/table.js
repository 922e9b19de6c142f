// "/table/ID": a live table seen from above. The geometry (cushion lines, pocket circles, in
// metres) comes from GetTable(include_geometry); the balls from WatchTable snapshots, drawn at
// the display's frame rate and interpolated between snapshots by their table time. With a seat
// token (#token=...) the page plays: aim with the mouse (PreviewShot's aim line), speed and spin
// sliders, Shoot, and PlaceBall on a click while the cue ball is in hand.
import { EventKind, MotionState } from "../gen/sportsim/v1/billiards_pb.js";
import { follow, setConnection } from "./conn.js";
import { viewer, resetViewer } from "./state.js";

const WATCH_RATE_HZ = 60;                    // snapshots asked for while balls move
const PLAYOUT_DELAY_MS = 1.5 * 1000 / WATCH_RATE_HZ + 8;  // behind the newest snapshot
const PREVIEW_MIN_INTERVAL_MS = 80;          // aim line requests at most this often
const CANVAS_WIDTH = 960;
const MARGIN_PX = 36;

const POOL_COLOURS = {
  1: "#f2c511", 2: "#1f4fd1", 3: "#d62b2b", 4: "#6a2c91", 5: "#f07c1b", 6: "#138a3c",
  7: "#7b2a1d", 8: "#111111",
};
const NAMED_COLOURS = {
  cue: "#f7f7f2", white: "#f7f7f2", yellow: "#f2d21b", red: "#d42424", green: "#138a3c",
  brown: "#7b4a1d", blue: "#1f4fd1", pink: "#f27fb2", black: "#111111",
};

function ballStyle(id) {
  if (NAMED_COLOURS[id]) return { fill: NAMED_COLOURS[id], stripe: false };
  if (/^red/.test(id)) return { fill: NAMED_COLOURS.red, stripe: false };
  const n = parseInt(id, 10);
  if (n >= 1 && n <= 8) return { fill: POOL_COLOURS[n], stripe: false };
  if (n >= 9 && n <= 15) return { fill: POOL_COLOURS[n - 8], stripe: true };
  return { fill: "#c0c0c0", stripe: false };
}

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  for (const c of children) e.append(c);
  return e;
}

function kindName(k) { return EventKind[k] || String(k); }
function stateName(s) { return MotionState[s] || String(s); }

export function showTable(app, clients, tableId, token) {
  resetViewer();
  const ac = new AbortController();
  let stopped = false;

  const canvas = el("canvas", { id: "table", width: String(CANVAS_WIDTH), height: "500" });
  const stateBox = el("div", { class: "state", id: "game" }, "…");
  const status = el("div", { class: "muted", id: "status" });
  const eventsBox = el("div", { class: "events", id: "events" });
  const side = el("div", { class: "side" }, stateBox);
  let controls = null;
  const ui = {};
  if (token) {
    ui.speed = el("input", { type: "range", min: "0.3", max: "8", step: "0.1", value: "2.5", id: "speed" });
    ui.side = el("input", { type: "range", min: "-0.5", max: "0.5", step: "0.05", value: "0", id: "spin-a" });
    ui.top = el("input", { type: "range", min: "-0.5", max: "0.5", step: "0.05", value: "0", id: "spin-b" });
    ui.speedOut = el("span"); ui.sideOut = el("span"); ui.topOut = el("span");
    ui.call = el("input", { type: "text", id: "call", placeholder: "ball:pocket", size: "12" });
    ui.place = el("input", { type: "checkbox", id: "place" });
    ui.shoot = el("button", { id: "shoot" }, "Shoot");
    controls = el("div", { class: "controls", id: "controls" },
      el("label", {}, "Cue speed ", ui.speed, " ", ui.speedOut),
      el("label", {}, "Side (a) ", ui.side, " ", ui.sideOut),
      el("label", {}, "Top/draw (b) ", ui.top, " ", ui.topOut),
      el("label", {}, "Call ", ui.call),
      el("label", {}, ui.place, " place the cue ball with a click"),
      ui.shoot);
    side.append(controls);
  }
  side.append(status, el("h2", {}, "Events"), eventsBox);
  app.append(el("div", { class: "layout" }, canvas, side));
  const ctx = canvas.getContext("2d");

  // ---- table state ----
  let geom = null;
  let T = null;                 // metres -> pixels
  let info = null;
  let game = null;
  let turn = 0;
  let atRest = true;
  let lastVerdict = null;
  const seatNames = [];
  const buffer = [];            // snapshots with balls: {t (ms table time), arrival, balls: Map}
  const recentOffsets = [];     // arrival - table time of recent snapshots (ms)
  let renderT = null;           // the table time drawn (ms)
  let lastFrameNow = null;
  let aimPaths = [];            // metres
  let aimWorld = null;          // where the mouse points (metres)
  let lastSeq = 0n;

  function toPx(x, y) { return [T.ox + x * T.scale, T.oy - y * T.scale]; }
  function toWorld(px, py) { return [(px - T.ox) / T.scale, (T.oy - py) / T.scale]; }

  function setupGeometry(g) {
    geom = g;
    let length = g ? g.lengthM : 0;
    let width = g ? g.widthM : 0;
    if (!length || !width) { length = 2.54; width = 1.27; }  // unbounded: a 9 ft view
    const scale = (CANVAS_WIDTH - 2 * MARGIN_PX) / length;
    const height = Math.round(width * scale + 2 * MARGIN_PX);
    canvas.width = CANVAS_WIDTH;
    canvas.height = height;
    T = { scale, ox: CANVAS_WIDTH / 2, oy: height / 2, lengthM: length, widthM: width };
    viewer.transform = { scale, ox: T.ox, oy: T.oy };
  }

  // ---- drawing ----
  function drawTable() {
    ctx.fillStyle = "#4a2c17";                       // rails
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    const [x0, y0] = toPx(-T.lengthM / 2, T.widthM / 2);
    ctx.fillStyle = "#1e6b3a";                       // cloth: the playing area
    ctx.fillRect(x0, y0, T.lengthM * T.scale, T.widthM * T.scale);
    let cushions = 0, pockets = 0;
    if (geom) {
      ctx.fillStyle = "#050505";
      for (const p of geom.pockets) {
        const [px, py] = toPx(p.xM, p.yM);
        ctx.beginPath();
        ctx.arc(px, py, p.radiusM * T.scale, 0, 2 * Math.PI);
        ctx.fill();
        pockets++;
      }
      ctx.strokeStyle = "#7fd39a";
      ctx.lineWidth = 2;
      ctx.beginPath();
      for (const c of geom.cushions) {
        const [ax, ay] = toPx(c.x1M, c.y1M);
        const [bx, by] = toPx(c.x2M, c.y2M);
        ctx.moveTo(ax, ay);
        ctx.lineTo(bx, by);
        cushions++;
      }
      ctx.stroke();
    }
    viewer.cushionsDrawn = cushions;
    viewer.pocketsDrawn = pockets;
  }

  function interpolated() {
    // Balls at table time renderT: linear between the two snapshots around it.
    if (buffer.length === 0) return new Map();
    if (renderT <= buffer[0].t) return buffer[0].balls;
    const last = buffer[buffer.length - 1];
    if (renderT >= last.t) return last.balls;
    let i = buffer.length - 2;
    while (i > 0 && buffer[i].t > renderT) i--;
    const a = buffer[i], b = buffer[i + 1];
    const u = (renderT - a.t) / (b.t - a.t);
    const out = new Map();
    for (const [id, bb] of b.balls) {
      const ba = a.balls.get(id);
      if (!ba || ba.pocketed) { out.set(id, bb); continue; }
      out.set(id, { x: ba.x + (bb.x - ba.x) * u, y: ba.y + (bb.y - ba.y) * u, pocketed: ba.pocketed && bb.pocketed });
    }
    return out;
  }

  function drawBalls(balls) {
    const r = (geom && geom.ballRadiusM ? geom.ballRadiusM : 0.028575) * T.scale;
    const drawn = [];
    ctx.lineWidth = 1;
    for (const [id, b] of balls) {
      if (b.pocketed || b.x === undefined) continue;
      const [px, py] = toPx(b.x, b.y);
      const st = ballStyle(id);
      ctx.beginPath();
      ctx.arc(px, py, r, 0, 2 * Math.PI);
      ctx.fillStyle = st.stripe ? "#f7f7f2" : st.fill;
      ctx.fill();
      if (st.stripe) {
        ctx.save();
        ctx.clip();
        ctx.fillStyle = st.fill;
        ctx.fillRect(px - r, py - r * 0.55, 2 * r, r * 1.1);
        ctx.restore();
      }
      ctx.strokeStyle = "#000";
      ctx.stroke();
      if (r >= 7 && /^\d+$/.test(id)) {
        ctx.fillStyle = id === "8" ? "#fff" : "#000";
        ctx.font = `${Math.round(r * 0.9)}px sans-serif`;
        ctx.textAlign = "center";
        ctx.textBaseline = "middle";
        ctx.fillText(id, px, py + 0.5);
      }
      drawn.push({ id, x: px, y: py });
    }
    viewer.ballsDrawn = drawn;
  }

  function drawAim() {
    const lines = [];
    if (token && atRest && aimPaths.length) {
      const colours = ["rgba(255,255,255,0.9)", "rgba(255,220,80,0.9)"];
      aimPaths.forEach((path, k) => {
        const pts = path.points.map((p) => { const [x, y] = toPx(p.x, p.y); return { x, y }; });
        ctx.strokeStyle = colours[k] || "rgba(200,200,255,0.8)";
        ctx.lineWidth = 1.5;
        ctx.setLineDash(k === 0 ? [6, 4] : [3, 3]);
        ctx.beginPath();
        pts.forEach((p, i) => (i ? ctx.lineTo(p.x, p.y) : ctx.moveTo(p.x, p.y)));
        ctx.stroke();
        ctx.setLineDash([]);
        lines.push(pts);
      });
    }
    viewer.aimLine = lines;
  }

  function frame(now) {
    if (stopped) return;
    requestAnimationFrame(frame);
    if (!T) return;
    // The playout clock: advances with the display, steered gently toward "newest snapshot's
    // table time plus the time since it arrived, minus the playout delay"; it jumps when far
    // off (a new shot after a rest) and never runs past the newest snapshot.
    if (buffer.length) {
      const last = buffer[buffer.length - 1];
      const target = last.t + (now - last.arrival) - PLAYOUT_DELAY_MS;
      if (renderT === null || Math.abs(target - renderT) > 250) renderT = target;
      else renderT += (now - (lastFrameNow ?? now)) + 0.1 * (target - renderT);
      if (renderT > last.t) renderT = last.t;
    }
    lastFrameNow = now;
    drawTable();
    drawBalls(interpolated());
    drawAim();
    viewer.frames++;
    const painted = performance.now();
    const minOffset = recentOffsets.length ? Math.min(...recentOffsets) : 0;
    for (const s of buffer) {
      if (!s.painted && renderT !== null && renderT >= s.t) {
        s.painted = true;
        pushBounded(viewer.paintDelaysMs, painted - s.arrival);
        pushBounded(viewer.publishToPaintMs, painted - (s.t + minOffset));
      }
    }
    if (buffer.length) viewer.ready = true;
  }

  function pushBounded(arr, v) { arr.push(v); if (arr.length > 5000) arr.shift(); }

  // ---- words ----
  function seatName(i) {
    return seatNames[i] && seatNames[i] !== String(i) ? `${seatNames[i]} (seat ${i})` : `seat ${i}`;
  }

  function renderState() {
    const lines = [];
    if (!game || !game.name || game.name === "free") {
      lines.push(`Free play — ${seatName(turn)} to play`);
    } else {
      lines.push(`${game.name}, frame ${game.frame} (race to ${game.raceTo}); frames ${game.framesWon.join(" – ")}`);
      if (game.result) {
        lines.push(game.winner !== undefined ? `Match over: ${seatName(game.winner)} ${game.result}` : `Match over: ${game.result}`);
      } else {
        lines.push(`${seatName(game.toPlay)} to play${game.isBreak ? " (break)" : ""}`);
      }
      if (game.scores.length) lines.push(`Score ${game.scores.join(" – ")}`);
      const groups = Object.entries(game.groups);
      if (groups.length) lines.push("Groups: " + groups.map(([s, g]) => `${seatName(+s)} ${g}`).join(", "));
      if (game.on.length) lines.push("On: " + game.on.join(", "));
      lines.push("Ball in hand: " + (game.ballInHand && game.ballInHand !== "none" ? game.ballInHand : "no"));
      if (game.callRequired) lines.push("A call is required");
      if (game.pushOutAvailable) lines.push("Push-out available");
      if (game.decision && game.decision.choices.length) {
        lines.push(`Decision for ${seatName(game.decision.seat)}: ${game.decision.choices.join(" / ")}`);
      }
      if (game.shotClockDeadlineS !== undefined) lines.push(`Shot clock until t = ${game.shotClockDeadlineS.toFixed(1)} s`);
    }
    if (lastVerdict) {
      const v = lastVerdict;
      const what = v.foul ? `foul (${v.reason})` : v.reason ? v.reason : "legal";
      lines.push(`Last shot: ${what}${v.points ? `, ${v.points} points` : ""}${v.turnPasses ? ", turn passes" : ""}` +
        (v.respotted.length ? `, respotted ${v.respotted.join(", ")}` : ""));
    }
    lines.push(atRest ? "Balls at rest" : "Balls moving");
    const text = lines.join("\n");
    stateBox.textContent = text;
    viewer.gameText = text;
    viewer.atRest = atRest;
    if (ui.place && game && game.ballInHand && game.ballInHand !== "none" && !game.isBreak &&
        !ui.place.dataset.touched) {
      ui.place.checked = true;
    }
  }

  function describeEvent(e) {
    const k = kindName(e.kind);
    let s = `${e.tS.toFixed(3)} ${k}`;
    if (e.balls.length) s += " " + e.balls.join(",");
    if (e.cushion) s += " " + e.cushion;
    if (e.pocket) s += " → " + e.pocket;
    if (e.seat !== undefined && e.kind >= EventKind.shot) s += " seat " + e.seat;
    if (e.reason) s += " " + e.reason;
    if (e.points) s += ` ${e.points} pts`;
    if (e.winner !== undefined) s += " winner " + e.winner;
    if (e.choices.length) s += " [" + e.choices.join("/") + "]";
    return s;
  }

  function addEvents(events) {
    for (const e of events) {
      viewer.events++;
      if (e.kind === EventKind.transition) continue;   // too many to read; counted
      if (e.kind === EventKind.shot_end && e.summary && e.summary.verdict) lastVerdict = e.summary.verdict;
      const line = el("div", {}, describeEvent(e));
      eventsBox.append(line);
    }
    while (eventsBox.childNodes.length > 200) eventsBox.removeChild(eventsBox.firstChild);
    eventsBox.scrollTop = eventsBox.scrollHeight;
  }

  // ---- snapshots ----
  function onSnapshot(s) {
    const arrival = performance.now();
    viewer.snapshots++;
    lastSeq = s.sequence;
    viewer.lastSnapshotSeq = Number(s.sequence);
    viewer.lastSnapshotTick = Number(s.tick);
    turn = s.turn;
    atRest = s.atRest;
    if (s.game) game = s.game;
    if (s.events.length) addEvents(s.events);
    if (!s.heartbeat && s.balls.length) {
      const t = s.tS * 1000;
      if (buffer.length && t < buffer[buffer.length - 1].t) { buffer.length = 0; renderT = null; }
      const prev = buffer.length ? buffer[buffer.length - 1].balls : null;
      const balls = new Map(prev && !s.resync ? prev : []);
      for (const b of s.balls) {
        balls.set(b.id, { x: b.xM, y: b.yM, pocketed: b.state === MotionState.pocketed, state: stateName(b.state) });
      }
      buffer.push({ t, arrival, balls, painted: false });
      if (buffer.length > 120) buffer.splice(0, buffer.length - 120);
      recentOffsets.push(arrival - t);
      if (recentOffsets.length > 120) recentOffsets.shift();
    }
    if (atRest && aimWorld && token) requestPreview();
    if (!atRest) aimPaths = [];
    renderState();
  }

  function watch() {
    return follow({
      open: () => {
        const req = { tableId, rateHz: WATCH_RATE_HZ };
        if (lastSeq > 0n) req.fromSequence = lastSeq;
        return clients.billiards.watchTable(req, { signal: ac.signal });
      },
      onItem: onSnapshot,
      stopped: () => stopped,
      onError: (e) => { viewer.error = e.message; },
    });
  }

  // ---- playing ----
  function struckBall() {
    if (game && game.name === "three-cushion" && game.toPlay === 1) return "yellow";
    return "cue";
  }

  function currentBallPos(id) {
    if (!buffer.length) return null;
    const b = buffer[buffer.length - 1].balls.get(id);
    return b && !b.pocketed ? b : null;
  }

  function currentStrike() {
    const ball = struckBall();
    const pos = currentBallPos(ball);
    if (!pos || !aimWorld) return null;
    const phi = Math.atan2(aimWorld[1] - pos.y, aimWorld[0] - pos.x) * 180 / Math.PI;
    return {
      ball,
      speedMps: +ui.speed.value,
      phiDeg: Math.round(phi * 100) / 100,
      a: +ui.side.value,
      b: +ui.top.value,
    };
  }

  function toProtoStrike(s) {
    return { ball: s.ball, speed: { case: "speedMps", value: s.speedMps }, phiDeg: s.phiDeg, a: s.a, b: s.b };
  }

  let previewInFlight = false, previewWanted = false, previewTimer = null, previewSent = 0;
  function requestPreview() { previewWanted = true; pumpPreview(); }
  async function pumpPreview() {
    if (previewInFlight || !previewWanted || previewTimer || stopped) return;
    const wait = previewSent + PREVIEW_MIN_INTERVAL_MS - performance.now();
    if (wait > 0) { previewTimer = setTimeout(() => { previewTimer = null; pumpPreview(); }, wait); return; }
    const strike = currentStrike();
    previewWanted = false;
    if (!strike || !atRest) return;
    previewInFlight = true;
    previewSent = performance.now();
    try {
      const r = await clients.billiards.previewShot({ tableId, token, strike: toProtoStrike(strike), maxEvents: 3 });
      if (atRest) {
        aimPaths = r.paths.map((p) => ({ ball: p.ball, points: p.points.map((q) => ({ t: q.tS, x: q.xM, y: q.yM })) }));
        viewer.aimPaths = aimPaths;
        viewer.aimStrike = strike;
        viewer.previews++;
        status.textContent = "";
      }
    } catch (e) {
      aimPaths = [];
      viewer.aimPaths = [];
      status.textContent = "aim line: " + e.message;
    } finally {
      previewInFlight = false;
      pumpPreview();
    }
  }

  function pointerWorld(ev) {
    const r = canvas.getBoundingClientRect();
    const px = (ev.clientX - r.left) * canvas.width / r.width;
    const py = (ev.clientY - r.top) * canvas.height / r.height;
    return toWorld(px, py);
  }

  if (token) {
    const showValues = () => {
      ui.speedOut.textContent = (+ui.speed.value).toFixed(1) + " m/s";
      ui.sideOut.textContent = (+ui.side.value).toFixed(2);
      ui.topOut.textContent = (+ui.top.value).toFixed(2);
    };
    showValues();
    for (const input of [ui.speed, ui.side, ui.top]) {
      input.addEventListener("input", () => { showValues(); if (aimWorld) requestPreview(); });
    }
    ui.place.addEventListener("change", () => { ui.place.dataset.touched = "1"; });
    canvas.addEventListener("mousemove", (ev) => {
      if (!T) return;
      aimWorld = pointerWorld(ev);
      if (atRest) requestPreview();
    });
    canvas.addEventListener("click", async (ev) => {
      if (!T) return;
      const [x, y] = pointerWorld(ev);
      if (ui.place.checked) {
        try {
          await clients.billiards.placeBall({ tableId, token, ball: { id: struckBall(), xM: x, yM: y } });
          status.textContent = `placed ${struckBall()} at ${x.toFixed(3)}, ${y.toFixed(3)}`;
          ui.place.checked = false;
          delete ui.place.dataset.touched;
        } catch (e) {
          status.textContent = "place: " + e.message;
        }
      } else {
        aimWorld = [x, y];
        requestPreview();
      }
    });
    ui.shoot.addEventListener("click", async () => {
      const strike = currentStrike();
      if (!strike) { status.textContent = "aim first: move the mouse over the table"; return; }
      const req = { tableId, token, strike: toProtoStrike(strike) };
      const call = ui.call.value.trim();
      if (call) {
        if (call === "safety") req.call = { safety: true };
        else { const [ball, pocket] = call.split(":"); req.call = { ball, pocket: pocket || "" }; }
      }
      try {
        const r = await clients.billiards.shoot(req);
        viewer.shots++;
        viewer.lastShot = { shotId: Number(r.shotId), startTick: Number(r.startTick), strike };
        status.textContent = `shot ${r.shotId} from tick ${r.startTick}`;
        aimPaths = [];
      } catch (e) {
        status.textContent = "shoot: " + e.message;
      }
    });
  }

  // ---- start ----
  (async () => {
    try {
      info = await clients.billiards.getTable({ tableId, includeGeometry: true });
      if (stopped) return;
      setConnection("connected", false);
      for (const s of info.seats) seatNames[s.seat] = s.name;
      setupGeometry(info.geometry);
      game = info.game || null;
      turn = info.turn;
      atRest = info.atRest;
      if (info.lastShot && info.lastShot.verdict) lastVerdict = info.lastShot.verdict;
      const balls = new Map();
      for (const b of info.balls) balls.set(b.id, { x: b.xM, y: b.yM, pocketed: b.state === MotionState.pocketed });
      buffer.push({ t: info.tS * 1000, arrival: performance.now(), balls, painted: false });
      renderState();
      requestAnimationFrame(frame);
      watch();
    } catch (e) {
      setConnection("error: " + e.message, true);
      viewer.error = e.message;
      app.append(el("p", { class: "err" }, `Table ${tableId}: ${e.message}`));
    }
  })();

  return () => { stopped = true; ac.abort(); if (previewTimer) clearTimeout(previewTimer); };
}
