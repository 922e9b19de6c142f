// The viewer: a single page; routes /, /table/ID, /swing/ID, /round/ID (also #/table/ID, ...).
// A seat token rides in the hash: /table/ID#token=SECRET, /round/ID#token=SECRET.
import { makeClients } from "./rpc.js";
import { showList } from "./list.js";
import { showTable } from "./table.js";
import { showSwing } from "./swing.js";
import { showRound } from "./round.js";
import { viewer } from "./state.js";

const clients = makeClients(location.origin);
window.__viewer = viewer;

function hashParams() {
  const out = {};
  for (const part of location.hash.replace(/^#/, "").split("&")) {
    const i = part.indexOf("=");
    if (i > 0) out[decodeURIComponent(part.slice(0, i))] = decodeURIComponent(part.slice(i + 1));
  }
  return out;
}

function route() {
  // The path, or a "#/table/ID" style hash for static hosting without rewrites.
  let path = location.pathname;
  const hashPath = location.hash.match(/^#(\/(?:table|swing|round)\/[^&#]+)/);
  if (hashPath) path = hashPath[1];
  const m = path.match(/^\/(table|swing|round)\/([^/]+)\/?$/);
  const app = document.getElementById("app");
  const crumb = document.getElementById("crumb");
  if (viewer.stop) { viewer.stop(); viewer.stop = null; }
  app.textContent = "";
  const params = hashParams();
  if (m && m[1] === "table") {
    crumb.textContent = "› table " + decodeURIComponent(m[2]);
    viewer.page = "table";
    viewer.stop = showTable(app, clients, decodeURIComponent(m[2]), params.token || "");
  } else if (m && m[1] === "swing") {
    crumb.textContent = "› swing " + decodeURIComponent(m[2]);
    viewer.page = "swing";
    viewer.stop = showSwing(app, clients, decodeURIComponent(m[2]));
  } else if (m && m[1] === "round") {
    crumb.textContent = "› round " + decodeURIComponent(m[2]);
    viewer.page = "round";
    viewer.stop = showRound(app, clients, decodeURIComponent(m[2]), params.token || "");
  } else {
    crumb.textContent = "";
    viewer.page = "list";
    viewer.stop = showList(app, clients);
  }
}


window.addEventListener("hashchange", route);
window.addEventListener("popstate", route);
route();
