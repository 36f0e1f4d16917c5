// Maze sketchpad for lfd-tutor (an anywidget front end).
//
// Draws the maze, the shown realisations (pass: solid, fail: dashed, with a mark where
// each failure happened), the demos (numbered), an optional rule circle, the target to
// scale and, under the map, a zoomed view of the target area; records a stroke with the
// pointer or the keyboard and sends it to Python once, on release / Enter. Coordinates
// on the Python side are metres; time is seconds. Colours come from Python (tutor.views.style).
//
// Keyboard: the canvas is focusable (Tab); arrow keys move a cursor (Shift: 1 cm steps),
// Space places a waypoint, Enter places the last one and finishes the demonstration,
// Backspace removes the last waypoint, Escape cancels.
//
// A stroke on a widget whose kernel is gone (comm closed, kernel dead or disposed)
// shows "no longer connected" instead of vanishing.

const STEP = 0.002;        // metres per arrow key press
const BIG_STEP = 0.01;     // with Shift
const KEY_SPEED = 0.1;     // metres per second of a keyboard stroke
const KEY_SPACING = 0.001; // metres between the samples of a keyboard stroke
const INSET_PX = 110;      // side of the zoomed target view (px)
const INSET_HALF = 0.008;  // half the side of the region it shows (metres)

const CSS = `
.lfd-sketchpad { font: 12px sans-serif; color: #222; }
.lfd-sketchpad .lfd-pad-map { display: block; touch-action: none; cursor: crosshair; }
.lfd-sketchpad .lfd-pad-map:focus { outline: none; }
.lfd-sketchpad .lfd-pad-map:focus-visible { outline: 3px solid #013ad1; outline-offset: 2px; }
.lfd-sketchpad .lfd-pad-row { display: flex; gap: 8px; align-items: flex-start;
  margin: 4px 0 0 0; max-width: 360px; }
.lfd-sketchpad .lfd-pad-zoom { flex: none; }
.lfd-sketchpad .lfd-pad-help { color: #444; margin: 4px 0 0 0; max-width: 360px; }
.lfd-sketchpad .lfd-pad-summary { margin: 4px 0 0 0; max-width: 360px; font-weight: 600; }
.lfd-sketchpad .lfd-pad-note { margin: 4px 0 0 0; max-width: 360px; font-style: italic; }
.lfd-sketchpad .lfd-pad-alert { margin: 4px 0 0 0; max-width: 360px; padding: 4px 6px;
  background: #fff4cc; border: 2px solid #661a05; color: #3a0d00; font-weight: 600; }
.lfd-sketchpad .lfd-pad-alert:empty { display: none; }
.lfd-sketchpad .lfd-pad-legend { display: flex; flex-wrap: wrap; gap: 2px 10px;
  margin: 4px 0 0 0; max-width: 360px; color: #333; }
.lfd-sketchpad .lfd-pad-legend span { white-space: nowrap; }
.lfd-sketchpad .lfd-pad-legend svg { vertical-align: middle; margin-right: 3px; }
.lfd-sketchpad .lfd-sr-only { position: absolute; width: 1px; height: 1px; overflow: hidden;
  clip: rect(0 0 0 0); white-space: nowrap; }
`;

// Element ids must be unique in the page. Each widget may load its own copy of this
// module (a counter here would restart at 1 in each), so the count lives on the page.
const UID_KEY = "__lfdSketchpadCount";

function floats(value) {
  // Binary traits arrive as a DataView (or an ArrayBuffer); copy so the floats are aligned.
  if (!value) return new Float32Array(0);
  if (value instanceof ArrayBuffer) return new Float32Array(value.slice(0));
  if (ArrayBuffer.isView(value)) {
    const start = value.byteOffset;
    return new Float32Array(value.buffer.slice(start, start + value.byteLength));
  }
  return new Float32Array(0);
}

function paths(value, samples) {
  // float32 (n, samples, 2) -> array of arrays of [x, y]
  const f = floats(value);
  const n = Math.floor(f.length / (2 * samples));
  const out = [];
  for (let i = 0; i < n; i++) {
    const p = [];
    for (let k = 0; k < samples; k++) {
      const j = 2 * (i * samples + k);
      p.push([f[j], f[j + 1]]);
    }
    out.push(p);
  }
  return out;
}

function render({ model, el }) {
  globalThis[UID_KEY] = (globalThis[UID_KEY] || 0) + 1;
  const id = `lfd-pad-${globalThis[UID_KEY]}`;
  const root = document.createElement("div");
  root.className = "lfd-sketchpad";
  // JupyterLab's keyboard shortcuts (Enter = edit cell, arrows = select cell...) must not
  // fire while the sketchpad has the keys.
  root.setAttribute("data-lm-suppress-shortcuts", "true");
  const style = document.createElement("style");
  style.textContent = CSS;
  const canvas = document.createElement("canvas");  // the map, on which one draws
  canvas.className = "lfd-pad-map";
  canvas.tabIndex = 0;
  canvas.setAttribute("role", "application");
  canvas.setAttribute("aria-roledescription", "sketchpad");
  canvas.setAttribute("aria-describedby", `${id}-summary ${id}-alert`);
  const help = document.createElement("div");
  help.className = "lfd-pad-help";
  help.textContent = "Keyboard: Tab here, arrows move, Space places a waypoint, " +
    "Enter finishes, Esc cancels.";
  const alertBox = document.createElement("div");
  alertBox.className = "lfd-pad-alert";
  alertBox.id = `${id}-alert`;
  alertBox.setAttribute("role", "alert");
  const summary = document.createElement("div");
  summary.className = "lfd-pad-summary";
  summary.id = `${id}-summary`;
  summary.setAttribute("aria-live", "polite");
  const note = document.createElement("div");
  note.className = "lfd-pad-note";
  const legend = document.createElement("div");
  legend.className = "lfd-pad-legend";
  const live = document.createElement("div");
  live.className = "lfd-sr-only";
  live.setAttribute("aria-live", "polite");
  const zoom = document.createElement("canvas");  // the target area, zoomed
  zoom.className = "lfd-pad-zoom";
  zoom.width = INSET_PX;
  zoom.height = INSET_PX;
  zoom.setAttribute("role", "img");
  zoom.setAttribute("aria-label", "The target area, zoomed in, with rings 1 mm apart.");
  const words = document.createElement("div");
  words.append(summary, note);
  const row = document.createElement("div");
  row.className = "lfd-pad-row";
  row.append(zoom, words);
  root.append(style, canvas, alertBox, row, legend, help, live);
  el.appendChild(root);

  const ctx = canvas.getContext("2d");
  const base = document.createElement("canvas"); // the picture without the stroke in hand
  const bctx = base.getContext("2d");
  let stroke = null;          // pointer stroke in progress: [[t, x, y], ...]
  let keys = null;            // keyboard stroke: {cursor: [x, y], waypoints: [[x, y], ...]}
  let strokeReleasedAt = null;
  let renderIdAtRelease = 0;
  let commClosed = false;
  let watchdog = null;
  let scheduled = false;

  // ------------------------------------------------------------ connection

  model.on("comm_live_update", () => { commClosed = true; });  // only ever goes false
  model.on("comm:close", () => { commClosed = true; });

  function connected() {
    if (commClosed) return false;
    const wm = model.widget_manager;
    if (!wm || !("kernel" in wm)) return true;  // a manager without kernels: cannot tell
    let kernel;
    try { kernel = wm.kernel; } catch (e) { return false; }
    if (!kernel || kernel.isDisposed) return false;
    if (kernel.status === "dead") return false;
    if (kernel.connectionStatus === "disconnected") return false;
    return true;
  }

  function showDisconnected() {
    stroke = null;
    keys = keys ? { cursor: keys.cursor, waypoints: [] } : null;
    strokeReleasedAt = null;
    alertBox.textContent = model.get("disconnected_text");
    root.dataset.connected = "false";
    paint();
  }

  function say(text) { live.textContent = text; }

  // ------------------------------------------------------------ geometry

  function geometry() {
    const lay = model.get("maze");
    const ws = lay.workspace;
    const width = model.get("width_px");
    const scale = width / (ws.x[1] - ws.x[0]);
    const height = Math.round(scale * (ws.y[1] - ws.y[0]));
    return { lay, ws, width, height, scale };
  }

  function toPx(g, x, y) {
    return [(x - g.ws.x[0]) * g.scale, g.height - (y - g.ws.y[0]) * g.scale];
  }

  function toWorld(g, px, py) {
    return [g.ws.x[0] + px / g.scale, g.ws.y[0] + (g.height - py) / g.scale];
  }

  function inside(b, x, y) {
    return x >= b.x[0] && x <= b.x[1] && y >= b.y[0] && y <= b.y[1];
  }

  // ------------------------------------------------------------ drawing

  function linesPath(c, map, list) {
    c.beginPath();
    list.forEach((pts) => {
      pts.forEach(([x, y], i) => {
        const [px, py] = map(x, y);
        if (i === 0) c.moveTo(px, py); else c.lineTo(px, py);
      });
    });
  }

  function strokeLines(c, map, list, color, width, alpha, dash) {
    if (!list.length) return;
    c.save();
    c.globalAlpha = alpha;
    c.strokeStyle = color;
    c.lineWidth = width;
    c.setLineDash(dash || []);
    linesPath(c, map, list);
    c.stroke();
    c.restore();
  }

  function box(c, g, b, color) {
    const [x0, y1] = toPx(g, b.x[0], b.y[1]);
    c.fillStyle = color;
    c.fillRect(x0, y1, (b.x[1] - b.x[0]) * g.scale, (b.y[1] - b.y[0]) * g.scale);
  }

  function marks(c, map, list, cross, r, color, width) {
    // all the marks of one kind in one path: × (cross) or ○, white halo under colour
    if (!list.length) return;
    c.save();
    c.beginPath();
    list.forEach(([x, y]) => {
      const [px, py] = map(x, y);
      if (cross) {
        c.moveTo(px - r, py - r); c.lineTo(px + r, py + r);
        c.moveTo(px - r, py + r); c.lineTo(px + r, py - r);
      } else {
        c.moveTo(px + r, py);
        c.arc(px, py, r, 0, 2 * Math.PI);
      }
    });
    c.strokeStyle = "#ffffff";
    c.lineWidth = width + 2;
    c.stroke();
    c.strokeStyle = color;
    c.lineWidth = width;
    c.stroke();
    c.restore();
  }

  function ring(c, px, py, r, color, width) {
    c.save();
    for (const [w, col] of [[width + 2, "#ffffff"], [width, color]]) {
      c.strokeStyle = col;
      c.lineWidth = w;
      c.beginPath();
      c.arc(px, py, r, 0, 2 * Math.PI);
      c.stroke();
    }
    c.restore();
  }

  function feedback() {
    const samples = model.get("samples");
    const reals = paths(model.get("real_xy"), samples);
    const passed = model.get("passed");
    const pass = [], fail = [];
    model.get("shown").forEach((i) => {
      if (i < reals.length) (passed[i] ? pass : fail).push(reals[i]);
    });
    const all = model.get("marks");
    return {
      pass, fail, demos: paths(model.get("demo_xy"), samples),
      crosses: all.filter((m) => m[2] !== 4), rings: all.filter((m) => m[2] === 4),
    };
  }

  function drawBase() {
    const g = geometry();
    const P = model.get("palette");
    for (const c of [canvas, base]) {
      if (c.width !== g.width || c.height !== g.height) {
        c.width = g.width;
        c.height = g.height;
      }
    }
    const c = bctx;
    const map = (x, y) => toPx(g, x, y);
    c.clearRect(0, 0, g.width, g.height);
    c.fillStyle = "#ffffff";
    c.fillRect(0, 0, g.width, g.height);
    box(c, g, g.lay.start_zone, P.zone);
    g.lay.obstacles.forEach((o, i) => {
      box(c, g, o, P.obstacle);
      const [cx, cy] = toPx(g, (o.x[0] + o.x[1]) / 2, (o.y[0] + o.y[1]) / 2);
      c.fillStyle = "#ffffff";
      c.font = "11px sans-serif";
      c.textAlign = "center";
      c.textBaseline = "middle";
      c.fillText(`obstacle ${i + 1}`, cx, cy);
      c.textAlign = "start";
      c.textBaseline = "alphabetic";
    });
    c.strokeStyle = "#000";
    c.lineWidth = 2;
    c.strokeRect(1, 1, g.width - 2, g.height - 2);

    const fb = feedback();
    strokeLines(c, map, fb.pass, P.pass, 1.2, 0.85, []);
    strokeLines(c, map, fb.fail, P.fail, 1.2, 0.9, [5, 3]);
    marks(c, map, fb.crosses, true, 3.5, P.fail, 2);
    marks(c, map, fb.rings, false, 2.5, P.fail, 1.2);

    const rule = model.get("rule_circle");
    if (rule && rule.center) {
      const [cx, cy] = toPx(g, rule.center[0], rule.center[1]);
      c.save();
      c.setLineDash([6, 4]);
      c.strokeStyle = P.rule;
      c.lineWidth = 2.5;
      c.beginPath();
      c.arc(cx, cy, rule.radius * g.scale, 0, 2 * Math.PI);
      c.stroke();
      c.restore();
    }

    // the target, to scale (0.5 cm across: a few pixels), outlined so it shows
    const t = g.lay.target;
    const [tx, ty] = toPx(g, t.center[0], t.center[1]);
    c.fillStyle = P.target;
    c.beginPath();
    c.arc(tx, ty, (t.diameter / 2) * g.scale, 0, 2 * Math.PI);
    c.fill();

    fb.demos.forEach((pts, i) => {
      strokeLines(c, map, [pts], P.demo, 2.5, 1.0, []);
      const [sx, sy] = toPx(g, pts[0][0], pts[0][1]);
      c.fillStyle = P.demo;
      c.font = "bold 13px sans-serif";
      c.fillText(String(i + 1), sx + 4, sy - 4);
    });
    drawInset(zoom.getContext("2d"), c, g, P, fb);
  }

  function drawInset(c, main, g, P, fb) {
    // A zoomed view of the target beside the summary (its box is dashed on the map), so
    // that millimetre misses can be seen without hiding any of the maze.
    const t = g.lay.target;
    const [tx, ty] = toPx(g, t.center[0], t.center[1]);
    const x0 = 0, y0 = 0;
    const ppm = INSET_PX / (2 * INSET_HALF);  // px per metre in the zoomed view
    const map = (x, y) => [
      x0 + INSET_PX / 2 + (x - t.center[0]) * ppm,
      y0 + INSET_PX / 2 - (y - t.center[1]) * ppm,
    ];
    const half = INSET_HALF * g.scale;
    main.save();
    main.strokeStyle = "#555";
    main.lineWidth = 1;
    main.setLineDash([2, 2]);
    main.strokeRect(tx - half, ty - half, 2 * half, 2 * half);
    main.restore();

    c.clearRect(0, 0, INSET_PX, INSET_PX);
    c.save();
    c.beginPath();
    c.rect(x0, y0, INSET_PX, INSET_PX);
    c.fillStyle = "#ffffff";
    c.fill();
    c.clip();
    const r = (t.diameter / 2) * ppm;
    const [cx, cy] = map(t.center[0], t.center[1]);
    c.strokeStyle = "#c8c8c8";
    c.lineWidth = 1;
    for (let mm = 1; mm <= 8; mm++) {  // rings 1 mm apart beyond the target's edge
      c.beginPath();
      c.arc(cx, cy, r + mm * 0.001 * ppm, 0, 2 * Math.PI);
      c.stroke();
    }
    c.fillStyle = P.target;
    c.beginPath();
    c.arc(cx, cy, r, 0, 2 * Math.PI);
    c.fill();
    // only the part of each path near the target: from its last sample outside the region
    const far = 1.5 * INSET_HALF;
    const tail = (pts) => {
      let k = pts.length - 1;
      while (k > 0 && Math.abs(pts[k][0] - t.center[0]) < far &&
        Math.abs(pts[k][1] - t.center[1]) < far) k--;
      return pts.slice(Math.max(0, k - 1));
    };
    strokeLines(c, map, fb.pass.map(tail), P.pass, 1.5, 0.85, []);
    strokeLines(c, map, fb.fail.map(tail), P.fail, 1.5, 0.9, [5, 3]);
    fb.demos.forEach((pts) => strokeLines(c, map, [tail(pts)], P.demo, 2.5, 1.0, []));
    c.fillStyle = P.pass;
    c.beginPath();
    fb.pass.forEach((pts) => {
      const [px, py] = map(...pts[pts.length - 1]);
      c.moveTo(px + 2.5, py);
      c.arc(px, py, 2.5, 0, 2 * Math.PI);
    });
    c.fill();
    marks(c, map, fb.crosses, true, 4, P.fail, 2);
    marks(c, map, fb.rings, false, 3.5, P.fail, 1.5);
    c.restore();
    c.strokeStyle = "#000";
    c.lineWidth = 1.5;
    c.strokeRect(x0 + 0.75, y0 + 0.75, INSET_PX - 1.5, INSET_PX - 1.5);
    c.fillStyle = "#222";
    c.font = "10px sans-serif";
    c.fillText(`target ×${Math.round(ppm / g.scale)}`, x0 + 4, y0 + 12);
    c.fillText("rings 1 mm apart", x0 + 4, y0 + INSET_PX - 5);
  }

  function drawLegend() {
    const P = model.get("palette");
    const line = (color, dash) => `<svg width="22" height="8" aria-hidden="true">` +
      `<line x1="1" y1="4" x2="21" y2="4" stroke="${color}" stroke-width="2.5"` +
      (dash ? ` stroke-dasharray="5 3"` : "") + `/></svg>`;
    const items = [
      `${line(P.pass, false)}succeeds`,
      `${line(P.fail, true)}fails`,
      `<b style="color:${P.fail}">×</b> hit or left the maze here`,
      `<b style="color:${P.fail}">○</b> ended outside the target`,
      `${line(P.demo, false)}your demonstrations`,
    ];
    legend.innerHTML = items.map((s) => `<span>${s}</span>`).join("");
  }

  function paint() {
    // the picture, then what is in hand (pointer stroke, keyboard cursor and waypoints)
    const g = geometry();
    const P = model.get("palette");
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    ctx.drawImage(base, 0, 0);
    const map = (x, y) => toPx(g, x, y);
    if (stroke) strokeLines(ctx, map, [stroke.map((p) => [p[1], p[2]])], P.demo, 2.5, 0.6, []);
    if (keys && document.activeElement === canvas) {
      const wp = keys.waypoints;
      if (wp.length) {
        strokeLines(ctx, map, [wp], P.demo, 2.5, 0.7, []);
        strokeLines(ctx, map, [[wp[wp.length - 1], keys.cursor]], P.demo, 1.5, 0.7, [4, 3]);
        wp.forEach(([x, y]) => {
          const [px, py] = toPx(g, x, y);
          ctx.fillStyle = P.demo;
          ctx.beginPath();
          ctx.arc(px, py, 3, 0, 2 * Math.PI);
          ctx.fill();
        });
      }
      const [cx, cy] = toPx(g, keys.cursor[0], keys.cursor[1]);
      ring(ctx, cx, cy, 6, P.demo, 2);
      ctx.strokeStyle = P.demo;
      ctx.lineWidth = 1;
      ctx.beginPath();
      ctx.moveTo(cx - 10, cy); ctx.lineTo(cx + 10, cy);
      ctx.moveTo(cx, cy - 10); ctx.lineTo(cx, cy + 10);
      ctx.stroke();
    }
  }

  function redraw() {
    scheduled = false;
    drawBase();
    paint();
    const demoBytes = model.get("demo_xy");
    const n = demoBytes ? Math.floor(demoBytes.byteLength / (8 * model.get("samples"))) : 0;
    summary.textContent = model.get("summary").replace(/ (mm|cm)\b/g, "\u00a0$1");
    note.textContent = model.get("note");
    canvas.setAttribute("aria-label", model.get("help_text"));
    root.dataset.renderId = String(model.get("render_id"));
    root.dataset.nDemos = String(n);
    root.dataset.enabled = String(model.get("enabled"));
    // Latency: from pointer release to the first painted frame showing Python's answer
    // (a render_id newer than the one on screen at release).
    if (strokeReleasedAt !== null && model.get("render_id") > renderIdAtRelease) {
      const releasedAt = strokeReleasedAt;
      strokeReleasedAt = null;
      requestAnimationFrame(() => {
        root.dataset.latencyMs = (performance.now() - releasedAt).toFixed(1);
        root.dataset.latencyFor = String(n);
      });
    }
  }

  function schedule() {
    if (scheduled) return;
    scheduled = true;
    requestAnimationFrame(redraw);
  }

  // ------------------------------------------------------------ sending a stroke

  function send(done) {
    if (!connected()) { showDisconnected(); return; }
    strokeReleasedAt = performance.now();
    renderIdAtRelease = model.get("render_id");
    try {
      model.set("stroke", done);
      model.set("stroke_count", model.get("stroke_count") + 1);
      model.save_changes();
    } catch (e) {
      showDisconnected();
      return;
    }
    // The kernel may die with the stroke on its way: keep checking until Python answers.
    clearInterval(watchdog);
    const sentFor = renderIdAtRelease;
    watchdog = setInterval(() => {
      if (model.get("render_id") > sentFor) { clearInterval(watchdog); return; }
      if (!connected()) { clearInterval(watchdog); showDisconnected(); }
    }, 500);
  }

  // ------------------------------------------------------------ pointer

  function point(ev) {
    const g = geometry();
    const r = canvas.getBoundingClientRect();
    const px = ((ev.clientX - r.left) * canvas.width) / r.width;
    const py = ((ev.clientY - r.top) * canvas.height) / r.height;
    const [x, y] = toWorld(g, px, py);
    return [performance.now() / 1000.0, x, y];
  }

  canvas.addEventListener("pointerdown", (ev) => {
    if (!model.get("enabled")) return;
    if (!connected()) { showDisconnected(); ev.preventDefault(); return; }
    canvas.setPointerCapture(ev.pointerId);
    stroke = [point(ev)];
    ev.preventDefault();
  });
  canvas.addEventListener("pointermove", (ev) => {
    if (!stroke) return;
    const p = point(ev);
    if (p[0] > stroke[stroke.length - 1][0]) stroke.push(p);
    paint();
  });
  canvas.addEventListener("pointerup", (ev) => {
    if (!stroke) return;
    const p = point(ev);
    if (p[0] > stroke[stroke.length - 1][0]) stroke.push(p);
    const done = stroke;
    stroke = null;
    paint();
    send(done);
  });
  canvas.addEventListener("pointercancel", () => { stroke = null; paint(); });

  // ------------------------------------------------------------ keyboard

  function where(x, y) {
    const g = geometry();
    const cm = (v) => (100 * v).toFixed(1);
    let place = "";
    const t = g.lay.target;
    const d = Math.hypot(x - t.center[0], y - t.center[1]);
    if (d <= t.diameter / 2) place = ", on the target";
    else if (d <= 0.02) place = `, ${(1000 * (d - t.diameter / 2)).toFixed(0)} mm from the target`;
    g.lay.obstacles.forEach((o, i) => {
      if (inside(o, x, y)) place = `, inside obstacle ${i + 1}`;
    });
    if (inside(g.lay.start_zone, x, y)) place += ", in the start zone";
    return `x ${cm(x)} cm, y ${cm(y)} cm${place}`;
  }

  function keyStroke(waypoints) {
    // straight segments between the waypoints, sampled every KEY_SPACING at KEY_SPEED
    const t0 = performance.now() / 1000.0;
    const out = [[t0, waypoints[0][0], waypoints[0][1]]];
    let s = 0;
    for (let i = 1; i < waypoints.length; i++) {
      const [ax, ay] = waypoints[i - 1], [bx, by] = waypoints[i];
      const len = Math.hypot(bx - ax, by - ay);
      const n = Math.max(1, Math.ceil(len / KEY_SPACING));
      for (let k = 1; k <= n; k++) {
        const f = k / n;
        out.push([t0 + (s + f * len) / KEY_SPEED, ax + f * (bx - ax), ay + f * (by - ay)]);
      }
      s += len;
    }
    return out;
  }

  canvas.addEventListener("focus", () => {
    if (!keys) {
      const z = geometry().lay.start_zone;
      keys = { cursor: [(z.x[0] + z.x[1]) / 2, (z.y[0] + z.y[1]) / 2], waypoints: [] };
    }
    paint();
  });
  canvas.addEventListener("blur", () => paint());

  canvas.addEventListener("keydown", (ev) => {
    const moves = { ArrowLeft: [-1, 0], ArrowRight: [1, 0], ArrowUp: [0, 1], ArrowDown: [0, -1] };
    const handled = ev.key in moves || [" ", "Enter", "Escape", "Backspace"].includes(ev.key);
    if (!handled || ev.ctrlKey || ev.metaKey || ev.altKey) return;
    ev.preventDefault();
    ev.stopPropagation();
    if (!keys) return;
    if (!model.get("enabled")) {
      say("Drawing is switched off: this run is finished or read-only.");
      return;
    }
    const g = geometry();
    if (ev.key in moves) {
      const step = ev.shiftKey ? BIG_STEP : STEP;
      const [dx, dy] = moves[ev.key];
      const x = Math.min(g.ws.x[1], Math.max(g.ws.x[0], keys.cursor[0] + dx * step));
      const y = Math.min(g.ws.y[1], Math.max(g.ws.y[0], keys.cursor[1] + dy * step));
      keys.cursor = [x, y];
      say(where(x, y));
    } else if (ev.key === "Escape") {
      if (keys.waypoints.length) say("Demonstration cancelled.");
      keys.waypoints = [];
    } else if (ev.key === "Backspace") {
      keys.waypoints.pop();
      say(`${keys.waypoints.length} waypoint(s).`);
    } else {
      if (!connected()) { showDisconnected(); return; }
      const wp = keys.waypoints;
      const last = wp[wp.length - 1];
      if (!last || Math.hypot(last[0] - keys.cursor[0], last[1] - keys.cursor[1]) > 1e-9) {
        wp.push([keys.cursor[0], keys.cursor[1]]);
      }
      if (ev.key === " ") {
        say(`Waypoint ${wp.length} at ${where(...keys.cursor)}.` +
          (wp.length === 1 ? " Move on and press Space for the next, Enter for the last." : ""));
      } else if (wp.length < 2) {
        say("A demonstration needs at least two waypoints: press Space, move, then Enter.");
      } else {
        const done = keyStroke(wp);
        keys.waypoints = [];
        say(`Demonstration with ${wp.length} waypoints sent.`);
        paint();
        send(done);
      }
    }
    paint();
  });

  // ------------------------------------------------------------ model changes

  model.on("change:render_id", () => {
    // Python's answer: draw it now, in this task, so the latency counts no extra frame
    const t0 = performance.now();
    if (strokeReleasedAt !== null) {
      root.dataset.answerMs = (t0 - strokeReleasedAt).toFixed(1);
      root.dataset.pythonMs = String(model.get("python_ms"));
    }
    scheduled = true;
    redraw();
    root.dataset.drawMs = (performance.now() - t0).toFixed(1);
  });
  ["maze", "palette", "width_px", "enabled", "help_text"].forEach((name) =>
    model.on(`change:${name}`, schedule));
  model.on("change:palette", drawLegend);
  drawLegend();
  redraw();
  return () => { clearInterval(watchdog); };
}

export default { render };
