// "/round/ID": a round of golf. The hole being played from above (north up): the course's
// surfaces by their OpenStreetMap classes over hill shading from the heightfield, the pin, every
// player's ball with its path on this hole (the live frames of a moving ball, then each rest,
// drop and replay), the lie and distance of each, the scorecard in the round's form of play,
// and the events. With a seat token in the hash (/round/ID#token=SECRET) the page plays: a club
// (its launch at full power is the published tour average), power, aim left or right of the
// pin, and the relief choices of a pending decision.
import { follow, setConnection } from "./conn.js";
import { viewer, resetViewer } from "./state.js";

const WATCH_RATE_HZ = 30;
const MPH = 0.44704;

// Full-power launches: TrackMan's published PGA Tour averages (ball speed mph, launch deg, spin
// rpm); the sand wedge's is an estimate in the same series. The putter's full power is the
// speed that rolls a putt about to the hole on a flat green of stimp 10.
const CLUBS = [
  { name: "driver", mph: 167, launch: 10.9, spin: 2686 },
  { name: "3-wood", mph: 158, launch: 9.2, spin: 3655 },
  { name: "5-iron", mph: 132, launch: 12.1, spin: 5361 },
  { name: "7-iron", mph: 120, launch: 16.3, spin: 7097 },
  { name: "9-iron", mph: 109, launch: 20.4, spin: 8647 },
  { name: "pitching-wedge", mph: 102, launch: 24.2, spin: 9304 },
  { name: "sand-wedge", mph: 85, launch: 30, spin: 10000 },
  { name: "putter" },
];

const SURFACE = {
  rough: "#3b6a2c", first_cut: "#4c8636", fairway: "#5ea443", fringe: "#68b74c", green: "#7bd05c",
  tee: "#6cb451", bunker: "#e4d49a", water_hazard: "#3a78c9", lateral_water_hazard: "#3a78c9",
  cartpath: "#9b958a", out_of_bounds: "#4a4a4a",
};
const STAKES = { water_hazard: "#ffd400", lateral_water_hazard: "#ff3b30", out_of_bounds: "#ffffff" };
const SEAT_COLORS = ["#ffffff", "#ffd84d", "#ff7a7a", "#7ad0ff", "#c9a0ff", "#8dff9a", "#ffae5c", "#d0d0d0"];

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  for (const c of children) e.append(c);
  return e;
}

const deg = (r) => r * 180 / Math.PI;

// The heightfield's height at (x, y), bilinear (for shading only).
function heightAt(hf, x, y) {
  const fx = (x - hf.x0M) / hf.spacingM, fy = (y - hf.y0M) / hf.spacingM;
  const i = Math.max(0, Math.min(hf.columns - 2, Math.floor(fx)));
  const j = Math.max(0, Math.min(hf.rows - 2, Math.floor(fy)));
  const u = Math.max(0, Math.min(1, fx - i)), v = Math.max(0, Math.min(1, fy - j));
  const z = (a, b) => hf.zM[b * hf.columns + a];
  return (1 - v) * ((1 - u) * z(i, j) + u * z(i + 1, j)) + v * ((1 - u) * z(i, j + 1) + u * z(i + 1, j + 1));
}

export function showRound(app, clients, roundId, token) {
  resetViewer();
  const ac = new AbortController();
  let stopped = false;

  const canvas = el("canvas", { id: "hole", width: "820", height: "600" });
  const stateBox = el("div", { class: "state", id: "round-state" }, "…");
  const card = el("div", { id: "scorecard" });
  const eventsBox = el("div", { class: "events", id: "events" });
  const side = el("div", { class: "side" }, stateBox, card);
  app.append(el("div", { class: "layout" }, canvas, side));

  viewer.round = {
    hole: 0, areasDrawn: 0, shadedCells: 0, ballsDrawn: [], pinPx: null, pathPoints: {},
    snapshots: 0, scorecardRows: 0, transform: null, played: 0, lastError: "", play: "",
  };

  let info = null;        // RoundInfo
  let round = null;       // the newest RoundState
  let course = null;      // CourseInfo of the hole shown (geometry)
  let shownHole = 0;
  let background = null;  // the hole's surfaces and shading, drawn once per hole
  let tf = null;          // {scale, ox, oy}: px = ox + x * scale, py = oy - y * scale
  let moving = null;      // RoundMovingBall
  let paths = {};         // seat -> [[x, y], ...] on this hole
  let lastSeq = 0n;
  let dirty = true;

  const px = (x, y) => [tf.ox + x * tf.scale, tf.oy - y * tf.scale];

  function track(seat, x, y) {
    const p = paths[seat] || (paths[seat] = []);
    const last = p[p.length - 1];
    if (!last || Math.hypot(last[0] - x, last[1] - y) > 0.05) p.push([x, y]);
    viewer.round.pathPoints[seat] = p.length;
  }

  // The view: the hole's tees, pin and balls with 30 m around, north up, to fit the canvas.
  function frame(hole) {
    const pts = hole.tees.map((t) => [t.xM, t.yM]);
    pts.push([hole.pin.xM, hole.pin.yM]);
    for (const p of round.players) pts.push([p.ball.xM, p.ball.yM]);
    const xs = pts.map((p) => p[0]), ys = pts.map((p) => p[1]);
    const m = 30;
    const x0 = Math.min(...xs) - m, x1 = Math.max(...xs) + m, y0 = Math.min(...ys) - m, y1 = Math.max(...ys) + m;
    const scale = Math.min(canvas.width / (x1 - x0), canvas.height / (y1 - y0));
    const ox = (canvas.width - (x1 - x0) * scale) / 2 - x0 * scale;
    const oy = canvas.height - (canvas.height - (y1 - y0) * scale) / 2 + y0 * scale;
    tf = { scale, ox, oy };
    viewer.round.transform = tf;
  }

  function drawBackground() {
    background = document.createElement("canvas");
    background.width = canvas.width;
    background.height = canvas.height;
    const g = background.getContext("2d");
    g.fillStyle = SURFACE.rough;
    g.fillRect(0, 0, canvas.width, canvas.height);
    let drawn = 0;
    for (const a of course.areas) {  // painter's order, as the course has them
      if (a.xyM.length < 6) continue;
      g.beginPath();
      for (let k = 0; k < a.xyM.length; k += 2) {
        const [x, y] = px(a.xyM[k], a.xyM[k + 1]);
        if (k === 0) g.moveTo(x, y); else g.lineTo(x, y);
      }
      g.closePath();
      g.fillStyle = SURFACE[a.golf] || SURFACE.rough;
      g.fill("evenodd");
      if (STAKES[a.golf]) { g.strokeStyle = STAKES[a.golf]; g.lineWidth = 1.5; g.stroke(); }
      drawn++;
    }
    // Hill shading: light from the north-west, on 6-pixel cells.
    const hf = course.heightfield;
    let cells = 0;
    if (hf && hf.zM.length) {
      const step = 6, h = step / tf.scale;
      for (let py = 0; py < canvas.height; py += step) {
        for (let qx = 0; qx < canvas.width; qx += step) {
          const x = (qx + step / 2 - tf.ox) / tf.scale, y = (tf.oy - py - step / 2) / tf.scale;
          const dzdx = (heightAt(hf, x + h, y) - heightAt(hf, x - h, y)) / (2 * h);
          const dzdy = (heightAt(hf, x, y + h) - heightAt(hf, x, y - h)) / (2 * h);
          const shade = Math.max(-0.35, Math.min(0.35, 4 * (-dzdx + dzdy) / Math.SQRT2));
          g.fillStyle = shade > 0 ? `rgba(255,255,255,${shade})` : `rgba(0,0,0,${-shade})`;
          g.fillRect(qx, py, step, step);
          cells++;
        }
      }
    }
    viewer.round.areasDrawn = drawn;
    viewer.round.shadedCells = cells;
  }

  function draw() {
    if (!background || !round) return;
    const g = canvas.getContext("2d");
    g.drawImage(background, 0, 0);
    const hole = course.holes[0];
    // The pin: a flag on the hole.
    const [fx, fy] = px(hole.pin.xM, hole.pin.yM);
    g.fillStyle = "#111";
    g.beginPath(); g.arc(fx, fy, 3, 0, 2 * Math.PI); g.fill();
    g.strokeStyle = "#eee"; g.lineWidth = 1.5;
    g.beginPath(); g.moveTo(fx, fy); g.lineTo(fx, fy - 22); g.stroke();
    g.fillStyle = "#ff3b30";
    g.beginPath(); g.moveTo(fx, fy - 22); g.lineTo(fx + 12, fy - 18); g.lineTo(fx, fy - 14); g.fill();
    viewer.round.pinPx = [fx, fy];
    // Paths, then balls.
    round.players.forEach((p, seat) => {
      const path = paths[seat] || [];
      if (path.length > 1) {
        g.strokeStyle = SEAT_COLORS[seat % SEAT_COLORS.length];
        g.globalAlpha = 0.8;
        g.lineWidth = 1.5;
        g.beginPath();
        path.forEach(([x, y], k) => { const [a, b] = px(x, y); if (k === 0) g.moveTo(a, b); else g.lineTo(a, b); });
        g.stroke();
        g.globalAlpha = 1;
      }
    });
    const drawn = [];
    round.players.forEach((p, seat) => {
      let x = p.ball.xM, y = p.ball.yM;
      if (moving && moving.seat === seat) { x = moving.xM; y = moving.yM; }
      if (p.ball.holed && !(moving && moving.seat === seat)) return;
      const [a, b] = px(x, y);
      g.fillStyle = SEAT_COLORS[seat % SEAT_COLORS.length];
      g.strokeStyle = "#000";
      g.lineWidth = 1;
      g.beginPath(); g.arc(a, b, 4.5, 0, 2 * Math.PI); g.fill(); g.stroke();
      g.font = "11px system-ui"; g.fillStyle = "#fff";
      g.fillText(p.name, a + 7, b - 6);
      drawn.push({ seat, x: a, y: b });
    });
    viewer.round.ballsDrawn = drawn;
    viewer.frames++;
  }

  function lieText(lie) {
    return { green: "on the green", tee: "on the tee", water_hazard: "in a yellow penalty area",
             lateral_water_hazard: "in a red penalty area", out_of_bounds: "out of bounds",
             first_cut: "in the first cut", cartpath: "on the cart path" }[lie] || "in the " + lie;
  }

  function renderState() {
    const r = round;
    const lines = [`${r.course}, hole ${r.hole} of ${r.firstHole}-${r.lastHole}, par ${r.par} (${r.play} play)`];
    if (r.result) lines.push(r.play === "match" ? r.matchStatus : `Over: ${r.result}`);
    else if (r.strokeInPlay) lines.push("A ball is moving");
    else if (r.decision) lines.push(`${r.players[r.decision.seat].name} decides: ${r.decision.choices.join(", ")}`);
    else if (r.toPlay >= 0) lines.push(`${r.players[r.toPlay].name} to play`);
    if (r.play === "match" && !r.result) lines.push(r.matchStatus);
    for (const p of r.players) {
      const b = p.ball;
      const where = b.holed ? `holed in ${p.strokes}` : b.pickedUp ? "picked up"
        : `${p.strokes} stroke${p.strokes === 1 ? "" : "s"}, ${b.distanceToPinM.toFixed(1)} m (${(b.distanceToPinM / 0.9144).toFixed(0)} yd), ${lieText(b.lie)}`;
      lines.push(`${p.name}: ${where}`);
    }
    stateBox.textContent = lines.join("\n");
    viewer.round.play = r.play;
    // The scorecard: holes across, a row per player (net and points where they apply).
    const holes = [];
    for (let h = r.firstHole; h <= r.lastHole; h++) holes.push(h);
    const t = el("table", { class: "list", id: "card" },
      el("tr", {}, el("th", {}, "hole"), ...holes.map((h) => el("th", {}, String(h))), el("th", {}, "total"),
         ...(r.handicaps ? [el("th", {}, "net")] : []), ...(r.play === "stableford" ? [el("th", {}, "pts")] : [])));
    let rows = 0;
    for (const p of r.players) {
      const cells = p.scores.map((s, k) => el("td", {}, p.noScore[k] ? "x" : s ? String(s) : "-"));
      t.append(el("tr", { class: "player" }, el("td", {}, p.name), ...cells, el("td", {}, String(p.total)),
        ...(r.handicaps ? [el("td", {}, String(p.netTotal))] : []),
        ...(r.play === "stableford" ? [el("td", {}, String(p.pointsTotal))] : [])));
      rows++;
    }
    if (r.play === "match") {
      t.append(el("tr", {}, el("td", {}, "won by"),
        ...r.holeWinners.map((w) => el("td", {}, w === -2 ? "-" : w === -1 ? "=" : r.players[w].name.slice(0, 3)))));
    }
    card.textContent = "";
    card.append(t);
    viewer.round.scorecardRows = rows;
    renderDecision();
  }

  async function showHole(h) {
    shownHole = h;
    paths = {};
    viewer.round.pathPoints = {};
    course = await clients.swing.getCourse({ name: round.course, hole: h, geometry: true }, { signal: ac.signal });
    if (stopped) return;
    frame(course.holes[0]);
    drawBackground();
    for (const [seat, p] of round.players.entries()) track(seat, p.ball.xM, p.ball.yM);
    viewer.round.hole = h;
    dirty = true;
  }

  function setRound(r) {
    round = r;
    if (r.hole !== shownHole) { showHole(r.hole).catch(fail); }
    else if (!r.strokeInPlay) {
      moving = null;
      for (const [seat, p] of r.players.entries()) if (!p.ball.holed) track(seat, p.ball.xM, p.ball.yM);
    }
    renderState();
    dirty = true;
  }

  function onSnapshot(s) {
    viewer.round.snapshots++;
    if (s.sequence > lastSeq) lastSeq = s.sequence;
    for (const e of s.events) {
      const who = e.seat >= 0 && round && e.seat < round.players.length ? round.players[e.seat].name + ": " : "";
      eventsBox.prepend(el("div", {}, `${who}${e.kind}${e.lie ? " " + e.lie : ""}${e.rule ? " (Rule " + e.rule + ")" : ""}`));
      if (e.kind === "holed" && e.seat >= 0 && round && round.hole === e.hole) track(e.seat, e.xM, e.yM);
    }
    if (s.round) setRound(s.round);
    if (s.ball) {
      moving = s.ball;
      if (round && round.hole === shownHole) track(s.ball.seat, s.ball.xM, s.ball.yM);
      dirty = true;
    }
  }

  // ---- playing ----
  const message = el("div", { class: "err", id: "play-error" });
  const decisionBox = el("div", { id: "decision" });
  function renderDecision() {
    decisionBox.textContent = "";
    if (!token || !round || !round.decision) return;
    for (const c of round.decision.choices) {
      const b = el("button", { "data-choice": c }, c.replaceAll("_", " "));
      b.onclick = () => act(() => clients.swing.decideRound({ roundId, token, choice: c }));
      decisionBox.append(b);
    }
  }
  async function act(call) {
    message.textContent = "";
    try {
      await call();
      viewer.round.played++;
    } catch (e) {
      message.textContent = e.rawMessage || e.message;
      viewer.round.lastError = message.textContent;
    }
  }
  if (token) {
    const club = el("select", { id: "club" }, ...CLUBS.map((c) => el("option", { value: c.name }, c.name)));
    const power = el("input", { type: "range", id: "power", min: "10", max: "110", value: "100" });
    const aim = el("input", { type: "range", id: "aim", min: "-30", max: "30", value: "0", step: "0.5" });
    const powerText = el("span", {}, "100 %"), aimText = el("span", {}, "at the pin");
    power.oninput = () => { powerText.textContent = power.value + " %"; };
    aim.oninput = () => {
      const a = +aim.value;
      aimText.textContent = a === 0 ? "at the pin" : `${Math.abs(a)} deg ${a > 0 ? "right" : "left"}`;
    };
    const play = el("button", { id: "play" }, "Play");
    play.onclick = () => act(async () => {
      // The seat to play's ball: the server checks the turn; the page aims from that ball.
      const seat = round.toPlay >= 0 ? round.toPlay : 0;
      const b = round.players[seat].ball;
      const heading = deg(Math.atan2(round.pinYM - b.yM, round.pinXM - b.xM));
      const aimDeg = heading - +aim.value;  // + right of the pin: clockwise
      const f = +power.value / 100;
      const c = CLUBS.find((k) => k.name === club.value);
      const req = { roundId, token, aimDeg };
      if (!c.mph) {
        const d = b.distanceToPinM;
        req.stroke = { case: "puttSpeedMps", value: Math.min(12, f * 1.4 * Math.sqrt(1.2 * (d + 0.3))) };
      } else {
        req.stroke = { case: "launch", value: { ballSpeedMps: f * c.mph * MPH, launchAngleDeg: c.launch,
                                                launchDirectionDeg: 0, spinRpm: f * c.spin, spinAxisDeg: 0 } };
      }
      await clients.swing.playStroke(req);
    });
    side.append(el("div", { class: "controls", id: "controls" },
      el("label", {}, "Club ", club), el("label", {}, "Power ", power, " ", powerText),
      el("label", {}, "Aim ", aim, " ", aimText), play, decisionBox, message));
  }
  side.append(el("h2", {}, "Events"), eventsBox);

  function fail(e) {
    if (stopped) return;
    setConnection("error: " + e.message, true);
    viewer.error = String(e.message);
  }

  function loop() {
    if (stopped) return;
    if (dirty) { dirty = false; draw(); }
    requestAnimationFrame(loop);
  }

  (async () => {
    try {
      info = await clients.swing.getRound({ roundId }, { signal: ac.signal });
      round = info.round;
      await showHole(round.hole);
      renderState();
      setConnection("connected", false);
      draw();
      viewer.ready = true;
      requestAnimationFrame(loop);
      await follow({
        open: () => {
          const req = { roundId, rateHz: WATCH_RATE_HZ };
          if (lastSeq > 0n) req.fromSequence = lastSeq;
          return clients.swing.watchRound(req, { signal: ac.signal });
        },
        onItem: onSnapshot,
        stopped: () => stopped,
        onError: (e) => { viewer.error = e.message; },
      });
    } catch (e) { fail(e); }
  })();

  return () => { stopped = true; ac.abort(); };
}
