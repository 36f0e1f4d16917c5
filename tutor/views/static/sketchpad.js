// Maze sketchpad for lfd-tutor (an anywidget front end).
// Draws the maze, the realisations R^ (green pass / red fail), the demos (blue, numbered)
// and an optional rule circle; records a stroke with the pointer and sends it to Python
// once, on release. Coordinates on the Python side are metres; time is seconds.

const COLORS = {
  pass: "#1b9e77", fail: "#d95f02", demo: "#1f4e9c", obstacle: "#4d4d4d",
  zone: "#d9e6f2", target: "#7570b3", stroke: "#1f4e9c", rule: "#e69f00",
};

function render({ model, el }) {
  const root = document.createElement("div");
  root.className = "lfd-sketchpad";
  const canvas = document.createElement("canvas");
  canvas.style.touchAction = "none";  // a finger draws instead of scrolling
  canvas.style.cursor = "crosshair";
  root.appendChild(canvas);
  el.appendChild(root);
  const ctx = canvas.getContext("2d");
  let stroke = null;
  let strokeReleasedAt = null;
  let renderIdAtRelease = 0;

  function geometry() {
    const lay = model.get("layout");
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

  function polyline(g, pts, color, width, alpha) {
    if (!pts || pts.length < 2) return;
    ctx.globalAlpha = alpha;
    ctx.strokeStyle = color;
    ctx.lineWidth = width;
    ctx.beginPath();
    pts.forEach(([x, y], i) => {
      const [px, py] = toPx(g, x, y);
      if (i === 0) ctx.moveTo(px, py); else ctx.lineTo(px, py);
    });
    ctx.stroke();
    ctx.globalAlpha = 1.0;
  }

  function box(g, b, color) {
    const [x0, y1] = toPx(g, b.x[0], b.y[1]);
    ctx.fillStyle = color;
    ctx.fillRect(x0, y1, (b.x[1] - b.x[0]) * g.scale, (b.y[1] - b.y[0]) * g.scale);
  }

  function draw() {
    const g = geometry();
    if (canvas.width !== g.width || canvas.height !== g.height) {
      canvas.width = g.width;
      canvas.height = g.height;
    }
    ctx.clearRect(0, 0, g.width, g.height);
    ctx.fillStyle = "#ffffff";
    ctx.fillRect(0, 0, g.width, g.height);
    box(g, g.lay.start_zone, COLORS.zone);
    g.lay.obstacles.forEach((o) => box(g, o, COLORS.obstacle));
    ctx.strokeStyle = "#000";
    ctx.lineWidth = 2;
    ctx.strokeRect(1, 1, g.width - 2, g.height - 2);

    const reals = model.get("realisations");
    const passed = model.get("passed");
    const shown = new Set(model.get("shown"));
    reals.forEach((pts, i) => {
      if (!shown.has(i)) return;
      polyline(g, pts, passed[i] ? COLORS.pass : COLORS.fail, 1, 0.8);
    });

    const rule = model.get("rule_circle");
    if (rule && rule.center) {
      const [cx, cy] = toPx(g, rule.center[0], rule.center[1]);
      ctx.setLineDash([6, 4]);
      ctx.strokeStyle = COLORS.rule;
      ctx.lineWidth = 2.5;
      ctx.beginPath();
      ctx.arc(cx, cy, rule.radius * g.scale, 0, 2 * Math.PI);
      ctx.stroke();
      ctx.setLineDash([]);
    }

    const [tx, ty] = toPx(g, g.lay.target.center[0], g.lay.target.center[1]);
    ctx.fillStyle = COLORS.target;
    ctx.beginPath();
    ctx.arc(tx, ty, Math.max(2, (g.lay.target.diameter / 2) * g.scale), 0, 2 * Math.PI);
    ctx.fill();
    ctx.strokeStyle = COLORS.target;
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    ctx.arc(tx, ty, 9, 0, 2 * Math.PI);
    ctx.stroke();

    model.get("demos").forEach((pts, i) => {
      polyline(g, pts, COLORS.demo, 2.5, 1.0);
      const [sx, sy] = toPx(g, pts[0][0], pts[0][1]);
      ctx.fillStyle = COLORS.demo;
      ctx.font = "bold 13px sans-serif";
      ctx.fillText(String(i + 1), sx + 4, sy - 4);
    });
    if (stroke) polyline(g, stroke.map((p) => [p[1], p[2]]), COLORS.stroke, 2.5, 0.6);

    const note = model.get("note");
    if (note) {
      ctx.fillStyle = "#333";
      ctx.font = "12px sans-serif";
      ctx.fillText(note, 8, 16);
    }
    root.dataset.renderId = String(model.get("render_id"));
    root.dataset.nDemos = String(model.get("demos").length);
    // Latency: from pointer release to the first painted frame showing Python's answer
    // (a render_id newer than the one on screen at release).
    if (strokeReleasedAt !== null && model.get("render_id") > renderIdAtRelease) {
      const releasedAt = strokeReleasedAt;
      const nDemos = model.get("demos").length;
      strokeReleasedAt = null;
      requestAnimationFrame(() => {
        root.dataset.latencyMs = (performance.now() - releasedAt).toFixed(1);
        root.dataset.latencyFor = String(nDemos);
      });
    }
  }

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
    canvas.setPointerCapture(ev.pointerId);
    stroke = [point(ev)];
    ev.preventDefault();
  });
  canvas.addEventListener("pointermove", (ev) => {
    if (!stroke) return;
    const p = point(ev);
    if (p[0] > stroke[stroke.length - 1][0]) stroke.push(p);
    draw();
  });
  const finish = (ev) => {
    if (!stroke) return;
    const p = point(ev);
    if (p[0] > stroke[stroke.length - 1][0]) stroke.push(p);
    const done = stroke;
    stroke = null;
    strokeReleasedAt = performance.now();
    renderIdAtRelease = model.get("render_id");
    model.set("stroke", done);
    model.set("stroke_count", model.get("stroke_count") + 1);
    model.save_changes();
    draw();
  };
  canvas.addEventListener("pointerup", finish);
  canvas.addEventListener("pointercancel", () => { stroke = null; draw(); });

  ["layout", "demos", "realisations", "passed", "shown", "rule_circle", "note", "render_id",
   "width_px"].forEach((name) => model.on(`change:${name}`, draw));
  draw();
}

export default { render };
