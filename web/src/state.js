// What the page exposes for tests and curious people (window.__viewer): drawn positions in
// canvas pixels, the aim line, animation frame counts and snapshot-to-paint delays.
export const viewer = {
  page: "",
  ready: false,          // the page drew its first complete frame
  frames: 0,             // animation frames drawn (requestAnimationFrame callbacks)
  error: "",
  // table page
  transform: null,       // {scale, ox, oy}: px = ox + x_m * scale, py = oy - y_m * scale
  cushionsDrawn: 0,
  pocketsDrawn: 0,
  ballsDrawn: [],        // [{id, x, y}] canvas pixels, this frame
  lastSnapshotSeq: 0,
  lastSnapshotTick: 0,
  snapshots: 0,
  atRest: true,
  aimLine: [],           // [[{x, y}, ...] per path] canvas pixels, as drawn
  aimPaths: [],          // PreviewShot's paths as received: [{ball, points: [{t, x, y}]}]
  aimStrike: null,       // the strike of the preview drawn
  previews: 0,
  shots: 0,
  paintDelaysMs: [],     // per snapshot: arrival -> the end of the frame that first showed it
  publishToPaintMs: [],  // per snapshot: publication (table time mapped to this clock) -> paint
  gameText: "",
  events: 0,
  // swing page
  swing: null,
  // round page
  round: null,
  stop: null,
};

export function resetViewer() {
  Object.assign(viewer, {
    ready: false, frames: 0, error: "", transform: null, cushionsDrawn: 0, pocketsDrawn: 0,
    ballsDrawn: [], lastSnapshotSeq: 0, lastSnapshotTick: 0, snapshots: 0, atRest: true,
    aimLine: [], aimPaths: [], aimStrike: null, previews: 0, shots: 0, paintDelaysMs: [],
    publishToPaintMs: [], gameText: "", events: 0, swing: null, round: null,
  });
}
