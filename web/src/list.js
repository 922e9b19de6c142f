// "/": the tables, swing sessions and golf rounds the server holds, with links to their pages.
import { SwingPhase } from "../gen/sportsim/v1/swing_pb.js";
import { setConnection } from "./conn.js";
import { viewer, resetViewer } from "./state.js";

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  for (const c of children) e.append(c);
  return e;
}

export function showList(app, clients) {
  resetViewer();
  let stopped = false;
  const tables = el("div");
  const sessions = el("div");
  const rounds = el("div");
  app.append(el("h2", {}, "Tables"), tables, el("h2", {}, "Swing sessions"), sessions,
             el("h2", {}, "Golf rounds"), rounds);

  async function load() {
    try {
      const [t, s, r] = await Promise.all([
        clients.billiards.listTables({ pageSize: 1000 }),
        clients.swing.listSessions({ pageSize: 1000 }),
        clients.swing.listRounds({ pageSize: 1000 }),
      ]);
      if (stopped) return;
      setConnection("connected", false);
      tables.textContent = "";
      sessions.textContent = "";
      if (t.tables.length === 0) tables.append(el("p", { class: "muted" }, "No tables."));
      else {
        const tb = el("table", { class: "list", id: "tables" },
          el("tr", {}, ...["table", "preset", "balls", "seats", "shots", "watchers", "state"].map((h) => el("th", {}, h))));
        for (const b of t.tables) {
          tb.append(el("tr", {},
            el("td", {}, el("a", { href: "/table/" + encodeURIComponent(b.tableId) }, b.tableId)),
            el("td", {}, b.preset), el("td", {}, String(b.ballsOnTable)), el("td", {}, String(b.seats)),
            el("td", {}, String(b.shots)), el("td", {}, String(b.watchers)),
            el("td", {}, b.atRest ? "at rest" : "moving")));
        }
        tables.append(tb);
      }
      if (s.sessions.length === 0) sessions.append(el("p", { class: "muted" }, "No sessions."));
      else {
        const tb = el("table", { class: "list", id: "sessions" },
          el("tr", {}, ...["session", "phase", "swings", "watchers", "tick rate"].map((h) => el("th", {}, h))));
        for (const b of s.sessions) {
          tb.append(el("tr", {},
            el("td", {}, el("a", { href: "/swing/" + encodeURIComponent(b.sessionId) }, b.sessionId)),
            el("td", {}, (SwingPhase[b.phase] || "").toLowerCase()), el("td", {}, String(b.swings)),
            el("td", {}, String(b.watchers)), el("td", {}, b.tickHz + " Hz")));
        }
        sessions.append(tb);
      }
      rounds.textContent = "";
      if (r.rounds.length === 0) rounds.append(el("p", { class: "muted" }, "No rounds."));
      else {
        const tb = el("table", { class: "list", id: "rounds" },
          el("tr", {}, ...["round", "course", "play", "hole", "players", "watchers", "state"].map((h) => el("th", {}, h))));
        for (const b of r.rounds) {
          tb.append(el("tr", {},
            el("td", {}, el("a", { href: "/round/" + encodeURIComponent(b.roundId) }, b.roundId)),
            el("td", {}, b.course), el("td", {}, b.play), el("td", {}, String(b.hole)),
            el("td", {}, b.players.join(", ")), el("td", {}, String(b.watchers)),
            el("td", {}, b.result || "playing")));
        }
        rounds.append(tb);
      }
      viewer.ready = true;
      viewer.listed = { tables: t.tables.map((b) => b.tableId), sessions: s.sessions.map((b) => b.sessionId),
                        rounds: r.rounds.map((b) => b.roundId) };
    } catch (e) {
      setConnection("error: " + e.message, true);
      viewer.error = String(e.message);
    }
  }
  load();
  const timer = setInterval(load, 2000);
  return () => { stopped = true; clearInterval(timer); };
}
