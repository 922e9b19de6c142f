// "/swing/ID": a live swing session. The golfer is Jorgensen's double pendulum seen from the
// front (docs/swing.md): the arm from the shoulder to the wrists at R (sin theta, -cos theta),
// the club from the wrists to the clubhead at L (sin phi, -cos phi), x toward the backswing
// side, y up. Beside it the clubhead speed over the swing's time with the impact marked, and the
// ball's flight from the IMPACT event's launch (x downrange, z up) as a side view.
import { SwingEventKind, SwingPhase } from "../gen/sportsim/v1/swing_pb.js";
import { follow, setConnection } from "./conn.js";
import { viewer, resetViewer } from "./state.js";

const WATCH_RATE_HZ = 120;
const DEFAULT_ARM_M = 0.62, DEFAULT_CLUB_M = 1.1;

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  for (const c of children) e.append(c);
  return e;
}

const rad = (d) => d * Math.PI / 180;

// Arm and club lengths from one state: clubhead = R u(theta) + L u(phi), u(a) = (sin a, -cos a).
function lengthsFrom(s) {
  const t = rad(s.thetaDeg), p = rad(s.phiDeg);
  const a11 = Math.sin(t), a12 = Math.sin(p), a21 = -Math.cos(t), a22 = -Math.cos(p);
  const det = a11 * a22 - a12 * a21;
  if (Math.abs(det) < 0.05 || (s.clubheadXM === 0 && s.clubheadYM === 0)) return null;
  const R = (s.clubheadXM * a22 - a12 * s.clubheadYM) / det;
  const L = (a11 * s.clubheadYM - a21 * s.clubheadXM) / det;
  if (!(R > 0.1 && R < 3 && L > 0.1 && L < 3)) return null;
  return { R, L };
}

export function showSwing(app, clients, sessionId) {
  resetViewer();
  const ac = new AbortController();
  let stopped = false;

  const pend = el("canvas", { id: "pendulum", width: "480", height: "480" });
  const speed = el("canvas", { id: "speed", width: "480", height: "220" });
  const flight = el("canvas", { id: "flight", width: "480", height: "220" });
  const stateBox = el("div", { class: "state", id: "swing-state" }, "…");
  const eventsBox = el("div", { class: "events", id: "events" });
  app.append(el("div", { class: "layout" }, pend,
    el("div", {}, speed, el("div", { style: "height:8px" }), flight),
    el("div", { class: "side" }, stateBox, el("h2", {}, "Events"), eventsBox)));

  let lengths = { R: DEFAULT_ARM_M, L: DEFAULT_CLUB_M };
  let lengthsKnown = false;
  let state = null;            // the newest SwingSample
  let phase = SwingPhase.ADDRESS;
  let swingId = 0n;
  let samples = [];            // this swing: {t, v} clubhead speed (relative to the shoulder)
  let trail = [];              // clubhead positions this swing (m)
  let impact = null;           // SwingImpact of this swing
  let ball = null;             // BallLaunch of this swing
  let lastSeq = 0n;
  let info = null;
  let dirty = true;

  viewer.swing = { phase: "", swingId: 0, states: 0, samples: 0, impact: null, flight: null,
                   armPx: null, clubPx: null, speedPointsDrawn: 0, flightPointsDrawn: 0 };

  function newSwing(id) {
    swingId = id;
    samples = [];
    trail = [];
    impact = null;
    ball = null;
  }

  function onState(s) {
    state = s;
    if (!lengthsKnown) { const l = lengthsFrom(s); if (l) { lengths = l; lengthsKnown = true; } }
    if (phase === SwingPhase.SWINGING || (samples.length && s.tS > samples[samples.length - 1].t)) {
      if (!samples.length || s.tS > samples[samples.length - 1].t) {
        samples.push({ t: s.tS, v: s.clubheadSpeedMps });
        trail.push([s.clubheadXM, s.clubheadYM]);
      }
    }
    viewer.swing.states++;
    viewer.swing.samples = samples.length;
    dirty = true;
  }

  function addEvent(e) {
    const k = SwingEventKind[e.kind] || String(e.kind);
    let s = `${e.tS.toFixed(4)} ${k.replace("SWING_EVENT_", "").toLowerCase()}`;
    if (e.kind === SwingEventKind.SWING_EVENT_STARTED) {
      newSwing(e.swingId);
      s += ` swing ${e.swingId}${e.driven ? " (driven)" : ""}`;
    }
    if (e.kind === SwingEventKind.SWING_EVENT_IMPACT && e.impact) {
      impact = e.impact;
      s += ` ${e.impact.clubheadSpeedMps.toFixed(2)} m/s`;
      viewer.swing.impact = { tS: impact.tS, clubheadSpeedMps: impact.clubheadSpeedMps };
      if (e.ball) {
        ball = e.ball;
        if (ball.error) s += ` (no ball: ${ball.error})`;
        else if (ball.flight) {
          s += `, ball ${ball.launch.ballSpeedMps.toFixed(1)} m/s, carry ${ball.flight.carryM.toFixed(1)} m`;
          viewer.swing.flight = { carryM: ball.flight.carryM, apexM: ball.flight.apexM,
                                  samples: ball.flight.samples.length };
        }
      }
    }
    if (e.reason) s += " " + e.reason;
    if (e.kind === SwingEventKind.SWING_EVENT_TORQUE) s += ` Qa ${e.qalphaNm} Qb ${e.qbetaNm}`;
    eventsBox.append(el("div", {}, s));
    while (eventsBox.childNodes.length > 200) eventsBox.removeChild(eventsBox.firstChild);
    eventsBox.scrollTop = eventsBox.scrollHeight;
    dirty = true;
  }

  function onSnapshot(snap) {
    lastSeq = snap.sequence;
    phase = snap.phase;
    if (snap.swingId !== swingId && snap.swingId !== 0n && phase === SwingPhase.SWINGING) newSwing(snap.swingId);
    for (const e of snap.events) addEvent(e);
    if (snap.state) onState(snap.state);
    viewer.swing.phase = (SwingPhase[phase] || "").toLowerCase();
    viewer.swing.swingId = Number(snap.swingId);
    viewer.lastSnapshotSeq = Number(snap.sequence);
    viewer.lastSnapshotTick = Number(snap.tick);
    viewer.snapshots++;
    renderText(snap);
  }

  function renderText(snap) {
    const lines = [`Phase: ${(SwingPhase[phase] || "?").toLowerCase()}${swingId ? `, swing ${swingId}` : ""}`];
    if (state) {
      lines.push(`t = ${state.tS.toFixed(3)} s`);
      lines.push(`arm θ ${state.thetaDeg.toFixed(1)}°, wrist β ${state.betaDeg.toFixed(1)}°, shaft φ ${state.phiDeg.toFixed(1)}°`);
      lines.push(`clubhead ${state.clubheadSpeedMps.toFixed(2)} m/s (ground ${state.clubheadSpeedGroundMps.toFixed(2)} m/s)`);
    }
    if (snap) lines.push(`torques Qα ${snap.qalphaNm.toFixed(1)} N m, Qβ ${snap.qbetaNm.toFixed(1)} N m`);
    if (impact) lines.push(`Impact at ${impact.tS.toFixed(4)} s: ${impact.clubheadSpeedMps.toFixed(2)} m/s`);
    if (ball && ball.flight && !ball.error) {
      lines.push(`Ball: ${ball.launch.ballSpeedMps.toFixed(1)} m/s at ${ball.launch.launchAngleDeg.toFixed(1)}°, ` +
        `${ball.launch.spinRpm.toFixed(0)} rpm; carry ${ball.flight.carryM.toFixed(1)} m, apex ${ball.flight.apexM.toFixed(1)} m`);
    }
    stateBox.textContent = lines.join("\n");
  }

  // ---- drawing ----
  function drawPendulum() {
    const c = pend.getContext("2d");
    c.fillStyle = "#10161c";
    c.fillRect(0, 0, pend.width, pend.height);
    const reach = lengths.R + lengths.L;
    const s = (pend.width / 2 - 20) / reach;
    const ox = pend.width / 2, oy = pend.height / 2 - 10;
    const P = (x, y) => [ox + x * s, oy - y * s];
    // ground line under the lowest clubhead position
    c.strokeStyle = "#3a4a3a";
    c.beginPath();
    const [, gy] = P(0, -reach);
    c.moveTo(0, gy + 4); c.lineTo(pend.width, gy + 4);
    c.stroke();
    if (trail.length > 1) {
      c.strokeStyle = "rgba(120,180,255,0.5)";
      c.beginPath();
      trail.forEach(([x, y], i) => { const [px, py] = P(x, y); i ? c.lineTo(px, py) : c.moveTo(px, py); });
      c.stroke();
    }
    if (!state) return;
    const t = rad(state.thetaDeg), p = rad(state.phiDeg);
    const wx = lengths.R * Math.sin(t), wy = -lengths.R * Math.cos(t);
    const cx = wx + lengths.L * Math.sin(p), cy = wy - lengths.L * Math.cos(p);
    const sh = P(0, 0), wr = P(wx, wy), ch = P(cx, cy);
    c.lineCap = "round";
    c.strokeStyle = "#e0b080"; c.lineWidth = 8;
    c.beginPath(); c.moveTo(...sh); c.lineTo(...wr); c.stroke();
    c.strokeStyle = "#d0d0d8"; c.lineWidth = 3;
    c.beginPath(); c.moveTo(...wr); c.lineTo(...ch); c.stroke();
    c.fillStyle = "#f0f0f0";
    c.beginPath(); c.arc(...sh, 6, 0, 2 * Math.PI); c.fill();
    c.fillStyle = "#ff8040";
    c.beginPath(); c.arc(...ch, 7, 0, 2 * Math.PI); c.fill();
    viewer.swing.armPx = [sh, wr];
    viewer.swing.clubPx = [wr, ch];
  }

  function axes(c, w, h, m, xmax, ymax, xlabel, ylabel) {
    c.fillStyle = "#10161c"; c.fillRect(0, 0, w, h);
    c.strokeStyle = "#556"; c.lineWidth = 1;
    c.beginPath(); c.moveTo(m, 8); c.lineTo(m, h - m); c.lineTo(w - 8, h - m); c.stroke();
    c.fillStyle = "#aab"; c.font = "11px sans-serif";
    c.textAlign = "left"; c.fillText(ylabel + " " + ymax.toFixed(0), m + 4, 14);
    c.textAlign = "right"; c.fillText(xlabel + " " + xmax.toFixed(2), w - 10, h - m - 4);
    return { x: (v) => m + v / xmax * (w - m - 10), y: (v) => h - m - v / ymax * (h - m - 12) };
  }

  function drawSpeed() {
    const c = speed.getContext("2d");
    const tmax = Math.max(0.3, samples.length ? samples[samples.length - 1].t : 0);
    const vmax = Math.max(10, ...samples.map((q) => q.v)) * 1.1;
    const A = axes(c, speed.width, speed.height, 24, tmax, vmax, "t s", "clubhead m/s");
    c.strokeStyle = "#6cf"; c.lineWidth = 2;
    c.beginPath();
    samples.forEach((q, i) => (i ? c.lineTo(A.x(q.t), A.y(q.v)) : c.moveTo(A.x(q.t), A.y(q.v))));
    c.stroke();
    if (impact) {
      c.fillStyle = "#ff8040";
      c.beginPath(); c.arc(A.x(impact.tS), A.y(impact.clubheadSpeedMps), 5, 0, 2 * Math.PI); c.fill();
      c.fillText(`impact ${impact.clubheadSpeedMps.toFixed(1)} m/s`, A.x(impact.tS) - 8, A.y(impact.clubheadSpeedMps) - 8);
    }
    viewer.swing.speedPointsDrawn = samples.length;
  }

  function drawFlight() {
    const c = flight.getContext("2d");
    const pts = ball && ball.flight && !ball.error ? ball.flight.samples : [];
    const xmax = Math.max(50, ...pts.map((q) => q.xM)) * 1.05;
    const zmax = Math.max(10, ...pts.map((q) => q.zM)) * 1.15;
    const A = axes(c, flight.width, flight.height, 24, xmax, zmax, "downrange m", "height m");
    c.strokeStyle = "#fff"; c.lineWidth = 2;
    c.beginPath();
    pts.forEach((q, i) => (i ? c.lineTo(A.x(q.xM), A.y(Math.max(0, q.zM))) : c.moveTo(A.x(q.xM), A.y(Math.max(0, q.zM)))));
    c.stroke();
    if (!pts.length) {
      c.fillStyle = "#889"; c.textAlign = "center";
      c.fillText(impact ? "no ball launched" : "ball flight appears at impact", flight.width / 2, flight.height / 2);
    }
    viewer.swing.flightPointsDrawn = pts.length;
  }

  function frame() {
    if (stopped) return;
    requestAnimationFrame(frame);
    viewer.frames++;
    if (!dirty) return;
    dirty = false;
    drawPendulum();
    drawSpeed();
    drawFlight();
    viewer.ready = true;
  }

  function watch() {
    return follow({
      open: () => {
        const req = { sessionId, rateHz: WATCH_RATE_HZ };
        if (lastSeq > 0n) req.fromSequence = lastSeq;
        return clients.swing.watchSwing(req, { signal: ac.signal });
      },
      onItem: onSnapshot,
      stopped: () => stopped,
      onError: (e) => { viewer.error = e.message; },
    });
  }

  (async () => {
    try {
      info = await clients.swing.getSession({ sessionId });
      if (stopped) return;
      setConnection("connected", false);
      phase = info.phase;
      if (info.state) onState(info.state);
      renderText(null);
      requestAnimationFrame(frame);
      watch();
    } catch (e) {
      setConnection("error: " + e.message, true);
      viewer.error = e.message;
      app.append(el("p", { class: "err" }, `Session ${sessionId}: ${e.message}`));
    }
  })();

  return () => { stopped = true; ac.abort(); };
}
