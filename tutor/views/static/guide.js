// Guiding the arm with one's own hand (both 3-D pages run it after meshcat's viewer is
// built; tutor/views/scene_guide.py is the kernel's side and describes the messages).
//
// When the kernel arms it ({cmd: "start"}), a handle (an orange ball on a stem down to
// its shadow on the table) sits at the gripper. The trainee moves it:
// - mouse: drag the ball to move in the horizontal plane (the ray under the pointer meets
//   the plane at the ball's height); Shift+drag, or dragging the stem, moves it up/down;
//   while dragging, the camera's orbit controls are off;
// - keys (the view must have the focus: a click gives it, the panel says so): arrows move
//   as seen from the camera, E/Q or PageUp/PageDown up and down, Shift for fine moves,
//   with an eased velocity while held; Space closes/opens the hand; Enter ends; Escape
//   cancels;
// - a gamepad (navigator.getGamepads): left stick moves, right stick (or the triggers)
//   up/down, button 0 closes/opens the hand, button 9 (start) ends.
// The handle stays in the box the kernel gives (limits), so the hand never goes into
// the table. From the first move to Enter it records (t, x, y, z, g) every TICK_MS and
// sends the recording ONCE, on Enter, as one Float64Array (guide-end), with the set-up
// time (arming to first move). Meanwhile each move goes to the kernel (at most one in
// flight: the newest is sent once the previous answer is on screen); its answer carries
// the links' placements, which are put on the robot's nodes directly, a link in
// collision in red, and the words shown on screen. No frame is started while a move
// waits for its answer (lfdRender.awaitAnswer: with software GL a frame keeps the page
// busy ~40-60 ms, and the answer would wait behind it). Nothing recorded waits for the
// kernel.
//
// Test hooks: window.lfdGuideState(), window.lfdGuideScreen(x, y, z) (viewport px of a
// point in the robot's frame, in this page), window.lfdGuideLatency (ms from a move sent
// to the frame with its answer applied being on screen: the animation frame after it was
// drawn), window.lfdGuideRoundTrip (ms from a move sent to its answer received),
// window.lfdGuideTickGaps (ms between the
// clock's ticks while recording).
(function () {
  if (typeof viewer === "undefined" || typeof MeshCat === "undefined") return;
  const THREE = MeshCat.THREE;
  const TICK_MS = 25;          // recording period (40 Hz)
  const SPEED = 0.25;          // m/s with a key held (or a stick fully over)
  const FINE = 0.05;           // with Shift
  const EASE_S = 0.08;         // time constant of the velocity's easing
  const BALL = 0.025;          // handle radius (m)
  const HIT_PX = 14;           // a press this close to the ball (or stem) grabs it
  const ACK_MS = 1500;         // a move unanswered this long is given up
  const DEAD = 0.15;           // gamepad stick dead zone
  const GUIDE = ["meshcat", "lfd", "guide"];
  const STEM = ["meshcat", "lfd", "guide-stem"];
  const SHADOW = ["meshcat", "lfd", "guide-shadow"];
  const latency = [];
  window.lfdGuideLatency = latency;
  const roundTrip = []; // ms from a move sent to its answer received (the kernel's part)
  window.lfdGuideRoundTrip = roundTrip;
  const gaps = []; // ms between the clock's ticks while recording (how busy the page is)
  window.lfdGuideTickGaps = gaps;

  let state = "off";           // "off" | "armed" | "recording" | "sent"
  let G = null;                // the guide while not "off" (set in start)
  let drag = null;
  let timer = null;
  const held = new Set();

  // ---------------------------------------------------------------- on screen
  const css = document.createElement("style");
  css.textContent = [
    "#lfd-guide { display: none; position: absolute; left: 6px; right: 6px; bottom: 6px;",
    "  padding: 6px 10px; border-radius: 4px; background: rgba(255,255,255,.92);",
    "  color: #111; font: 13px sans-serif; border: 2px solid #888; z-index: 20; }",
    "body.lfd-guiding #lfd-guide { display: block; }",
    "body.lfd-guiding #lfd-wheel-hint { display: none !important; }",
    "#lfd-guide.lfd-focused { border-color: #1a73e8; }",
    "#lfd-guide-focus { font-weight: 600; }",
    "#lfd-guide-words { color: #8a0000; font-weight: 600; min-height: 1em; }",
  ].join("\n");
  document.head.appendChild(css);
  const panel = document.createElement("div");
  panel.id = "lfd-guide";
  panel.setAttribute("role", "region");
  panel.setAttribute("aria-label", "Guiding the arm");
  panel.innerHTML =
    '<div id="lfd-guide-focus"></div>' +
    "<div>Drag the orange ball to move the hand (Shift+drag, or drag its stem: up and " +
    "down). Keys: arrows move, E/Q (or PageUp/PageDown) up/down, Shift moves finely, " +
    "Space closes/opens the hand, Enter ends the demonstration, Esc cancels. " +
    "A gamepad works too (sticks move, button A grips, Start ends).</div>" +
    '<div id="lfd-guide-words" role="status" aria-live="polite"></div>';
  document.body.appendChild(panel);
  const focusLine = panel.querySelector("#lfd-guide-focus");
  const wordsLine = panel.querySelector("#lfd-guide-words");
  const showFocus = () => {
    const on = document.hasFocus();
    panel.classList.toggle("lfd-focused", on);
    focusLine.textContent = on
      ? "The view has the keys" + (state === "recording" ? " - recording." : ": move to start.")
      : "Click the view to give it the keys.";
  };
  window.addEventListener("focus", showFocus);
  window.addEventListener("blur", showFocus);
  const say = (text) => { wordsLine.textContent = text || ""; };

  // ---------------------------------------------------------------- geometry
  const rootObject = () => viewer.scene_tree.find(["meshcat"]).object;
  const canvasRect = () => viewer.renderer.domElement.getBoundingClientRect();
  function toScreen(p) {
    const v = new THREE.Vector3(p[0], p[1], p[2]);
    rootObject().updateMatrixWorld();
    rootObject().localToWorld(v);
    viewer.camera.updateMatrixWorld();
    v.project(viewer.camera);
    const r = canvasRect();
    return [r.left + ((v.x + 1) / 2) * r.width, r.top + ((1 - v.y) / 2) * r.height];
  }
  function ray(cx, cy) { // the ray under a viewport point, in the robot's frame
    const r = canvasRect();
    const x = ((cx - r.left) / r.width) * 2 - 1;
    const y = -((cy - r.top) / r.height) * 2 + 1;
    viewer.camera.updateMatrixWorld();
    const a = new THREE.Vector3(x, y, -1).unproject(viewer.camera);
    const b = new THREE.Vector3(x, y, 1).unproject(viewer.camera);
    rootObject().worldToLocal(a);
    rootObject().worldToLocal(b);
    return [a, b.sub(a)];
  }
  function onPlane(cx, cy, z) { // where the ray meets the plane at height z (or null)
    const [a, d] = ray(cx, cy);
    if (Math.abs(d.z) < 1e-9) return null;
    const s = (z - a.z) / d.z;
    return s > 0 ? [a.x + s * d.x, a.y + s * d.y] : null;
  }
  function cameraAxes() { // forward and right, horizontal, in the robot's frame
    const c = new THREE.Vector3();
    viewer.camera.getWorldPosition(c);
    rootObject().worldToLocal(c);
    let fx = G.h[0] - c.x;
    let fy = G.h[1] - c.y;
    const n = Math.hypot(fx, fy) || 1;
    fx /= n; fy /= n;
    return [[fx, fy], [fy, -fx]];
  }
  const clamp = (v, lim) => Math.min(Math.max(v, lim[0]), lim[1]);
  function place(p) {
    const L = G.limits;
    const q = [clamp(p[0], L.x), clamp(p[1], L.y), clamp(p[2], L.z)];
    const tableHit = p[2] < L.z[0] - 1e-6;
    const changed = q.some((v, k) => Math.abs(v - G.h[k]) > 1e-6);
    G.h = q;
    if (tableHit) say("The hand cannot go lower: that is the table.");
    return changed;
  }

  // ---------------------------------------------------------------- the handle
  const mat = (m) => m.toArray();
  function drawHandle() {
    const [x, y, z] = G.h;
    const floor = G.table;
    const len = Math.max(z - floor, 1e-3);
    viewer.set_transform(GUIDE, mat(new THREE.Matrix4().makeTranslation(x, y, z)));
    const stem = new THREE.Matrix4().makeTranslation(x, y, floor + len / 2)
      .multiply(new THREE.Matrix4().makeRotationX(Math.PI / 2))
      .multiply(new THREE.Matrix4().makeScale(1, len, 1));
    viewer.set_transform(STEM, mat(stem));
    viewer.set_transform(SHADOW, mat(new THREE.Matrix4().makeTranslation(x, y, floor + 0.001)));
    const ball = viewer.scene_tree.find(GUIDE.concat(["<object>"])).object;
    if (ball.material) ball.material.color.setHex(G.g >= 0.5 ? 0x7b1fa2 : 0xff8c00);
    viewer.set_dirty();
  }
  function addHandle() {
    const lambert = (c, o) => new THREE.MeshLambertMaterial({ color: c, transparent: o < 1, opacity: o });
    viewer.set_object(GUIDE, new THREE.Mesh(new THREE.SphereGeometry(BALL, 24, 16), lambert(0xff8c00, 1)));
    viewer.set_object(STEM, new THREE.Mesh(new THREE.CylinderGeometry(0.004, 0.004, 1, 8), lambert(0xff8c00, 0.8)));
    const disc = new THREE.Mesh(new THREE.CylinderGeometry(BALL, BALL, 0.002, 24), lambert(0x333333, 0.45));
    disc.rotation.x = Math.PI / 2;
    viewer.set_object(SHADOW, disc);
  }
  function removeHandle() {
    for (const p of [GUIDE, STEM, SHADOW]) viewer.delete_path(p);
    viewer.set_dirty();
  }
  function hit(cx, cy) {
    const b = toScreen(G.h);
    const edge = toScreen([G.h[0], G.h[1], G.h[2] + BALL]);
    const r = Math.max(HIT_PX, Math.hypot(edge[0] - b[0], edge[1] - b[1]));
    if (Math.hypot(cx - b[0], cy - b[1]) <= r) return "ball";
    const f = toScreen([G.h[0], G.h[1], G.table]);
    const dx = f[0] - b[0];
    const dy = f[1] - b[1];
    const n2 = dx * dx + dy * dy || 1;
    const s = Math.min(1, Math.max(0, ((cx - b[0]) * dx + (cy - b[1]) * dy) / n2));
    const d = Math.hypot(cx - (b[0] + s * dx), cy - (b[1] + s * dy));
    return d <= 8 ? "stem" : null;
  }

  // ---------------------------------------------------------------- the arm
  function paint(nodeIndex, red) {
    G.nodes[nodeIndex].object.traverse((o) => {
      if (!o.material || !o.material.color) return;
      if (o.userData.lfdColour === undefined) o.userData.lfdColour = o.material.color.getHex();
      o.material.color.setHex(red ? 0xd00000 : o.userData.lfdColour);
    });
  }
  function showArm(msg, buffer) {
    const P = new Float32Array(buffer);
    const n = Math.min(G.nodes.length, Math.floor(P.length / 16));
    for (let i = 0; i < n; i++) G.nodes[i].set_transform(P.subarray(16 * i, 16 * i + 16));
    const red = new Set(msg.red || []);
    for (let i = 0; i < G.nodes.length; i++) {
      if (red.has(i) || G.red.has(i)) paint(i, red.has(i));
    }
    G.red = red;
    if (G.hand && Array.isArray(msg.position)) {
      const [x, y, z] = msg.position;
      G.hand.set_transform(mat(new THREE.Matrix4().makeTranslation(x, y, z)));
      const closed = msg.grip >= 0.5;
      G.hand.find(["open"]).object.scale.setScalar(closed ? 1e-3 : 1);
      G.hand.find(["closed"]).object.scale.setScalar(closed ? 1 : 1e-3);
    }
    say(msg.words);
    viewer.set_dirty();
  }

  // ---------------------------------------------------------------- messages
  function post(msg, buffers) {
    if (window.parent === window) return;
    window.parent.postMessage({ lfd: "guide", msg, buffers: buffers || [] }, "*", buffers || []);
  }
  function sendMove() {
    const now = performance.now();
    if (G.out && now - G.out.at < ACK_MS) { G.dirty = true; return; }
    G.dirty = false;
    G.seq += 1;
    G.out = { seq: G.seq, at: now };
    if (window.lfdRender) lfdRender.awaitAnswer(true);
    post({ type: "guide-move", seq: G.seq, x: G.h[0], y: G.h[1], z: G.h[2], g: G.g });
  }
  function answered(msg, buffers) {
    if (!G.out || msg.seq !== G.out.seq) return;
    const sent = G.out.at;
    roundTrip.push(performance.now() - sent);
    if (buffers && buffers[0]) showArm(msg, buffers[0]);
    // the latency ends when a frame with the arm at its answer has been drawn
    if (window.lfdRender) lfdRender.afterFrame((end) => latency.push(end - sent));
    else requestAnimationFrame(() => latency.push(performance.now() - sent));
    G.out = null;
    if (!window.lfdRender) { if (G.dirty) sendMove(); return; }
    lfdRender.awaitAnswer(false);
    // the next move goes once this answer is drawn (or 100 ms on, if no frame comes)
    const next = () => { if (G && G.dirty && !G.out) sendMove(); };
    lfdRender.afterFrame(next);
    setTimeout(next, 100);
  }
  window.addEventListener("message", (event) => {
    if (event.source !== window.parent || window.parent === window) return;
    const d = event.data;
    if (!d || d.lfd !== "guide" || !d.msg) return;
    const msg = d.msg;
    if (msg.cmd === "start") start(msg);
    else if (!G) return;
    else if (msg.cmd === "arm") answered(msg, d.buffers);
    else if (msg.cmd === "stop") stop();
    else if (msg.cmd === "refused") refused(msg);
  });

  // ---------------------------------------------------------------- states
  function start(msg) {
    if (G) stop();
    const links = Array.isArray(msg.links) ? msg.links : [];
    const split = (p) => String(p).split("/").filter((s) => s.length > 0);
    G = {
      h: msg.start.slice(0, 3),
      g: Number(msg.grip) >= 0.5 ? 1 : 0,
      limits: msg.limits,
      table: Number(msg.limits.z[0]),
      nodes: links.map((p) => viewer.scene_tree.find(split(p))),
      hand: msg.hand ? viewer.scene_tree.find(split(msg.hand)) : null,
      red: new Set(),
      rec: [],
      knots: [],
      k: 0,
      next: 0,
      seq: 0,
      out: null,
      dirty: false,
      armedAt: performance.now(),
      t0: null,
      setup: 0,
      vel: [0, 0, 0],
      last: performance.now(),
      buttons: [],
    };
    if (typeof msg.table === "number") G.table = msg.table;
    state = "armed";
    held.clear();
    addHandle();
    drawHandle();
    say(msg.words);
    document.body.classList.add("lfd-guiding");
    if (window.lfdRender) lfdRender.interactive(true);
    showFocus();
    timer = setInterval(tick, TICK_MS);
  }
  function stop() {
    if (timer !== null) clearInterval(timer);
    timer = null;
    if (G) {
      for (const i of G.red) paint(i, false);
      removeHandle();
    }
    if (drag) { viewer.controls.enabled = true; drag = null; }
    G = null;
    state = "off";
    held.clear();
    document.body.classList.remove("lfd-guiding");
    if (window.lfdRender) { lfdRender.interactive(false); lfdRender.awaitAnswer(false); }
  }
  function refused(msg) {
    say(msg.words);
    if (msg.what === "guide-move") {
      G.out = null;
      if (window.lfdRender) lfdRender.awaitAnswer(false);
      return;
    }
    if (msg.what === "guide-end") { // guide again, from where the hand is
      G.rec = [];
      G.knots = [];
      G.k = 0;
      G.t0 = null;
      G.armedAt = performance.now();
      state = "armed";
      showFocus();
    }
  }
  // What was recorded: every change of the hand is a knot (its time: the input event's
  // own timestamp, or the clock's tick for keys and the gamepad), and the recording is
  // the knots sampled every TICK_MS (linear in x, y, z between knots; g as it was). So a
  // main thread kept busy by drawing (software GL takes ~200 ms a frame) delays when the
  // samples are taken, never where they are: the events keep their timestamps.
  function moved(at) {
    if (state === "sent") return;
    const now = performance.now();
    const t = Math.min(now, at === undefined ? now : at);
    if (state === "armed") {
      state = "recording";
      G.t0 = t;
      G.setup = Math.min(120, Math.max(0, (t - G.armedAt) / 1000));
      G.knots = [];
      G.next = t;
      showFocus();
    }
    knot(t);
    drawHandle();
    sendMove();
  }
  function knot(t) {
    const last = G.knots[G.knots.length - 1];
    G.knots.push([last ? Math.max(t, last[0]) : t, G.h[0], G.h[1], G.h[2], G.g]);
  }
  function fill(now) { // the samples due up to now
    const K = G.knots;
    while (G.next <= now) {
      const t = G.next;
      while (G.k + 1 < K.length && K[G.k + 1][0] <= t) G.k += 1;
      const a = K[G.k];
      const b = G.k + 1 < K.length ? K[G.k + 1] : null;
      const s = b && b[0] > a[0] ? (t - a[0]) / (b[0] - a[0]) : 0;
      const at = (i) => (b ? a[i] + s * (b[i] - a[i]) : a[i]);
      G.rec.push((t - G.t0) / 1000, at(1), at(2), at(3), a[4]);
      G.next += TICK_MS;
    }
  }
  function end() {
    if (state !== "recording") {
      if (state === "armed") say("Move the hand first: Enter ends a demonstration once it has begun.");
      return;
    }
    const now = performance.now();
    knot(now);
    fill(now);
    if (now - G.t0 > 1000 * G.rec[G.rec.length - 5] + 1) {
      G.rec.push((now - G.t0) / 1000, G.h[0], G.h[1], G.h[2], G.g);
    }
    const data = new Float64Array(G.rec);
    state = "sent";
    say("Sent: the tutor is looking at your demonstration...");
    post({ type: "guide-end", n: data.length / 5, setup: G.setup }, [data.buffer]);
  }
  function cancel() {
    if (state === "off" || state === "sent") return;
    state = "sent";
    post({ type: "guide-cancel" });
  }
  function toggleGrip() {
    if (state === "off" || state === "sent") return;
    G.g = G.g >= 0.5 ? 0 : 1;
    moved();
  }

  // ---------------------------------------------------------------- the clock
  function tick() {
    if (!G || state === "sent") return;
    const now = performance.now();
    if (state === "recording" && gaps.length < 100000) gaps.push(now - G.last);
    const dt = Math.min(0.25, (now - G.last) / 1000);
    G.last = now;
    const want = [0, 0, 0];
    const fine = held.has("Shift");
    const speed = fine ? FINE : SPEED;
    const [fw, rt] = cameraAxes();
    const plane = (a, b) => { // a along forward, b along right, both -1..1
      want[0] += speed * (a * fw[0] + b * rt[0]);
      want[1] += speed * (a * fw[1] + b * rt[1]);
    };
    plane((held.has("ArrowUp") ? 1 : 0) - (held.has("ArrowDown") ? 1 : 0),
      (held.has("ArrowRight") ? 1 : 0) - (held.has("ArrowLeft") ? 1 : 0));
    want[2] += speed * ((held.has("up") ? 1 : 0) - (held.has("down") ? 1 : 0));
    pad(plane, want, speed);
    if (!G) return; // the pad ended it
    const k = 1 - Math.exp(-dt / EASE_S);
    let moving = false;
    for (let i = 0; i < 3; i++) {
      G.vel[i] += (want[i] - G.vel[i]) * k;
      if (want[i] === 0 && Math.abs(G.vel[i]) < 1e-3) G.vel[i] = 0;
      if (G.vel[i] !== 0) moving = true;
    }
    if (moving && !drag) {
      const p = G.h.map((v, i) => v + G.vel[i] * dt);
      if (place(p)) moved();
      else G.vel = [0, 0, 0];
    }
    if (state === "recording") { knot(now); fill(now); }
  }
  function pad(plane, want, speed) {
    const pads = navigator.getGamepads ? navigator.getGamepads() : [];
    const p = Array.from(pads || []).find((x) => x && x.connected !== false);
    if (!p) return;
    const ax = (i) => (Math.abs(p.axes[i] || 0) > DEAD ? p.axes[i] : 0);
    plane(-ax(1), ax(0));
    const btn = (i) => { const b = p.buttons[i]; return b ? (typeof b === "object" ? b.value || (b.pressed ? 1 : 0) : b) : 0; };
    want[2] += speed * (-ax(3) + btn(7) - btn(6));
    const pressed = (i) => btn(i) > 0.5;
    const was = G.buttons;
    G.buttons = [pressed(0), pressed(9)];
    if (G.buttons[0] && !was[0]) toggleGrip();
    if (G.buttons[1] && !was[1]) end();
  }

  // ---------------------------------------------------------------- input
  const KEYS = {
    ArrowUp: "ArrowUp", ArrowDown: "ArrowDown", ArrowLeft: "ArrowLeft", ArrowRight: "ArrowRight",
    e: "up", E: "up", PageUp: "up", q: "down", Q: "down", PageDown: "down", Shift: "Shift",
  };
  window.addEventListener("keydown", (e) => {
    if (!G || state === "off") return;
    if (e.key === "Enter") { e.preventDefault(); end(); return; }
    if (e.key === "Escape") { e.preventDefault(); cancel(); return; }
    if (e.key === " " || e.code === "Space") { e.preventDefault(); if (!e.repeat) toggleGrip(); return; }
    const k = KEYS[e.key];
    if (k) { e.preventDefault(); held.add(k); }
  }, true);
  window.addEventListener("keyup", (e) => {
    const k = KEYS[e.key];
    if (k) held.delete(k);
    if (e.key === "Shift") held.delete("Shift");
  }, true);
  window.addEventListener("blur", () => held.clear());
  window.addEventListener("pointerdown", (e) => {
    if (!G || state === "off" || state === "sent" || e.button !== 0) return;
    const what = hit(e.clientX, e.clientY);
    if (!what) return;
    e.stopPropagation();
    e.preventDefault();
    viewer.controls.enabled = false;
    const vertical = what === "stem" || e.shiftKey;
    const at = onPlane(e.clientX, e.clientY, G.h[2]);
    drag = {
      id: e.pointerId,
      vertical,
      y0: e.clientY,
      z0: G.h[2],
      off: at ? [G.h[0] - at[0], G.h[1] - at[1]] : [0, 0],
    };
    if (vertical) { // px per metre upwards at the handle
      const a = toScreen(G.h);
      const b = toScreen([G.h[0], G.h[1], G.h[2] + 0.1]);
      drag.pxPerM = Math.max(50, Math.hypot(b[0] - a[0], b[1] - a[1]) / 0.1);
    }
  }, true);
  function dragTo(ev) { // the handle where the pointer event ev takes it (or null)
    if (drag.vertical) return [G.h[0], G.h[1], drag.z0 + (drag.y0 - ev.clientY) / drag.pxPerM];
    const at = onPlane(ev.clientX, ev.clientY, G.h[2]);
    return at ? [at[0] + drag.off[0], at[1] + drag.off[1], G.h[2]] : null;
  }
  window.addEventListener("pointermove", (e) => {
    if (!drag || !G || e.pointerId !== drag.id) return;
    e.stopPropagation();
    // the moves the browser merged into this event while the page was busy, each at its time
    const all = e.getCoalescedEvents ? e.getCoalescedEvents() : [];
    for (const ev of all.length ? all : [e]) {
      const p = dragTo(ev);
      if (p && place(p)) moved(ev.timeStamp);
    }
  }, true);
  const release = (e) => {
    if (!drag || e.pointerId !== drag.id) return;
    e.stopPropagation();
    drag = null;
    viewer.controls.enabled = true;
  };
  window.addEventListener("pointerup", release, true);
  window.addEventListener("pointercancel", release, true);

  // ---------------------------------------------------------------- test hooks
  window.lfdGuideState = () => ({
    state,
    samples: G ? G.rec.length / 5 : 0,
    handle: G ? G.h.slice() : null,
    grip: G ? G.g : null,
    focused: document.hasFocus(),
    words: wordsLine.textContent,
  });
  window.lfdGuideScreen = (x, y, z) => toScreen([x, y, z]);
})();
