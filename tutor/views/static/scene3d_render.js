// How the 3-D pages draw (both: the notebook viewer's scene3d_page.html and the live
// server's scene3d_live.html; tutor/views/scene_page.py puts it into their "render" slot,
// after meshcat's script). With software GL (headless chromium, a machine without a GPU)
// one frame of the scene costs ~0.2 s, and meshcat's own loop draws every animation
// frame while a clip plays: clicks then waited seconds. So this wraps meshcat's viewer:
//
// - it draws on demand only: when the scene, the camera or a playing clip changed;
// - at most FPS frames a second, and after each frame it leaves the page idle for at
//   least as long as that frame took (adaptive: on software GL ~2 frames a second while a
//   clip plays, so input events always get time between frames);
// - nothing is drawn while the view is off screen (document.visibilityState, the page's
//   own IntersectionObserver, and the 'lfd-visible' message the notebook widget posts from
//   its IntersectionObserver); a clip waits there, paused, and goes on when seen again;
// - on software GL: no antialiasing, pixel ratio 1, no shadow maps;
// - while a hand is guided (lfdRender.interactive(true), guide.js): no idle gap after a
//   frame beyond the FPS cap, and on software GL half the pixels a side; no frame starts
//   while a move waits for the kernel's answer (lfdRender.awaitAnswer, at most ANSWER_MS),
//   and lfdRender.afterFrame(cb) calls cb once the next frame is on screen;
// - lfdRender.applyCommands(list, handle) applies a batch of commands in slices of about
//   SLICE_MS, yielding to input (setTimeout 0) between slices, and draws nothing until the
//   batch is in; a batch that takes longer than WORKING_MS shows the "working" line.
//
// (And it takes away the onmessage handler meshcat's bundle leaves, see below.)
// window.lfdRender = {viewer, busy(), frameMs(), frames, soft, visible(), working(text),
// applyCommands(list, handle, big), BIG_BYTES, hold(), release(), afterFrame(cb),
// interactive(on), awaitAnswer(on)}; window.lfdViewer(pane) builds the viewer (once per page).
(function () {
  // meshcat's bundle carries CCapture's GIF worker, whose code, run in the page, sets
  // self.onmessage to "encode e.data, then self.postMessage(e.data)": every message
  // posted to the page (the widget's 'lfd-visible', 'lfd-working', the guide's) was
  // echoed back to it forever, a few thousand a second, starving input and frames. Our
  // listeners use addEventListener; the page needs no onmessage.
  if (window.onmessage) window.onmessage = null;
  const FPS = 30;           // the cap with a fast GPU
  const SLICE_MS = 8;       // work per slice of an incoming batch before yielding
  const WORKING_MS = 300;   // a batch longer than this says it is working
  const ANSWER_MS = 150;     // at most this long without a frame while a move is answered
  const SOFT_INTERACTIVE_RATIO = 0.5; // pixel ratio scale while guiding on software GL
  const HOLD_MS = 1500;     // at most this long without a frame while batches arrive
  const THREE = MeshCat.THREE;

  function softwareGL() {
    // SwiftShader (chromium --disable-gpu), llvmpipe (Mesa), Microsoft's Basic Render Driver
    try {
      const gl = document.createElement("canvas").getContext("webgl");
      if (!gl) return true;
      const info = gl.getExtension("WEBGL_debug_renderer_info");
      const name = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : "";
      const lose = gl.getExtension("WEBGL_lose_context");
      if (lose) lose.loseContext();
      return /swiftshader|llvmpipe|softpipe|software|basic render/i.test(name);
    } catch (e) {
      return true;
    }
  }

  function median(xs) {
    if (!xs.length) return 0;
    const s = xs.slice().sort((a, b) => a - b);
    return s[Math.floor(s.length / 2)];
  }

  function overlay() {
    let el = document.getElementById("lfd-working");
    if (!el) {
      el = document.createElement("div");
      el.id = "lfd-working";
      el.setAttribute("role", "status");
      el.setAttribute("aria-live", "polite");
      el.style.cssText = "position:absolute;right:8px;bottom:8px;padding:4px 10px;" +
        "border-radius:4px;background:rgba(0,0,0,.78);color:#fff;font:13px sans-serif;" +
        "pointer-events:none;z-index:11;display:none";
      document.body.appendChild(el);
    }
    return el;
  }

  window.lfdViewer = function (pane) {
    const soft = softwareGL();
    const renderer = new THREE.WebGLRenderer({ antialias: !soft, alpha: true });
    renderer.shadowMap.enabled = !soft;
    renderer.shadowMap.type = THREE.PCFSoftShadowMap;
    pane.appendChild(renderer.domElement);
    // false: meshcat's own loop (a frame on every animation frame) is not started
    const viewer = new MeshCat.Viewer(pane, false, renderer);
    renderer.setPixelRatio(soft ? 1 : Math.min(window.devicePixelRatio || 1, 2));
    const costs = [];        // ms of the recent frames
    let lastEnd = -1e9;      // when the last frame ended (performance.now())
    let holdSince = null;    // a batch is being applied since then (no frames meanwhile)
    let batches = 0;         // batches being applied
    let held = false;        // lfdRender.hold() until lfdRender.release()
    let pageVisible = document.visibilityState !== "hidden";
    let seenHere = true;     // the page's own IntersectionObserver
    let seenByParent = true; // the widget's 'lfd-visible' message
    let wasHidden = false;
    let kernelText = "";     // the kernel's "working" line (lfdRender.working)
    let pageWorking = false;
    let drawn = [];          // one-shot callbacks for after the next frame (afterFrame)
    let interactive = false; // a hand is being guided (lfdRender.interactive)
    let fullRatio = 1;       // the pixel ratio when not interactive
    let answerSince = null;  // a guided move waits for its answer since (awaitAnswer)
    const state = {
      viewer: viewer,
      soft: soft,
      frames: 0,
      skipped: 0,
      busy: () => batches > 0 || (held && holding()) || kernelText !== "",
      frameMs: () => median(costs),
      visible: () => pageVisible && seenHere && seenByParent,
      working: (text) => { kernelText = text || ""; showWorking(); },
      applyCommands: applyCommands,
      BIG_BYTES: 100000,
      // no frame while a guided move waits for the kernel's answer (at most ANSWER_MS):
      // a frame started then keeps the page (and the answer) waiting for the renderer
      awaitAnswer: (on) => { answerSince = on ? performance.now() : null; },
      // cb(ms) once the next frame is on screen: at the animation frame after it (the
      // renderer's work is done by then), ms = performance.now() then
      afterFrame: (cb) => { drawn.push(cb); },
      // while a hand is guided: frames follow the answers at once (no idle gap after a
      // frame) and, on software GL, at half the pixels a side (a quarter of the work),
      // the full picture coming back when it ends
      interactive: (on) => {
        on = Boolean(on);
        if (on === interactive) return;
        interactive = on;
        if (soft) {
          if (on) fullRatio = renderer.getPixelRatio();
          renderer.setPixelRatio(on ? fullRatio * SOFT_INTERACTIVE_RATIO : fullRatio);
        }
        viewer.set_dirty();
      },
      // an update that arrives in many pieces (the live page's websocket): no frame from
      // hold() until release() (at most HOLD_MS)
      hold: () => {
        if (!holding()) holdSince = performance.now();
        held = true;
      },
      release: () => {
        held = false;
        if (batches === 0) holdSince = null;
        viewer.set_dirty();
      },
    };
    window.lfdRender = state;

    function holding() {  // no frame now: a batch (or a held update) began < HOLD_MS ago
      return holdSince !== null && performance.now() - holdSince < HOLD_MS;
    }

    function showWorking() {
      const el = overlay();
      const text = kernelText || (pageWorking ? "Working: updating the 3-D view..." : "");
      el.textContent = text;
      el.style.display = text ? "block" : "none";
      document.body.dataset.working = text ? "1" : "0";
    }

    function gap() {
      // idle time after a frame: as long as the frame took, and the rest of 1/FPS (while
      // a hand is guided, only the rest of 1/FPS: the trainee waits for the arm)
      const cost = median(costs);
      return interactive ? 1000 / FPS - cost : Math.max(1000 / FPS - cost, cost);
    }

    let renderAt = null;     // when the frame whose cost is not yet known started
    let cpuMs = 0;
    function tick() {
      requestAnimationFrame(tick);
      const now = performance.now();
      if (renderAt !== null) {
        // a frame's cost: until the next animation frame came (the GPU's, or the software
        // rasteriser's, work is done by then; gl.finish() does not wait in chromium)
        costs.push(Math.min(Math.max(cpuMs, now - renderAt), 1000));
        if (costs.length > 15) costs.shift();
        renderAt = null;
        lastEnd = now;
        if (drawn.length) {  // the frame is on screen now
          const callbacks = drawn;
          drawn = [];
          for (const cb of callbacks) cb(now);
        }
      }
      if (!state.visible()) {
        if (viewer.animator.playing) wasHidden = true;
        return;
      }
      if (wasHidden) {  // the clip stood still while nobody saw it
        viewer.animator.clock.getDelta();
        wasHidden = false;
      }
      if (holding()) return;
      if (answerSince !== null && now - answerSince < ANSWER_MS) return;
      if (!(viewer.needs_render || viewer.animator.playing)) return;
      if (now - lastEnd < gap()) { state.skipped++; return; }
      viewer.animator.update();
      if (!viewer.needs_render) return;
      const t0 = performance.now();
      viewer.render();
      lastEnd = performance.now();
      cpuMs = lastEnd - t0;
      renderAt = t0;
      state.frames++;
      document.body.dataset.frames = String(state.frames);
    }
    requestAnimationFrame(tick);

    document.addEventListener("visibilitychange", () => {
      pageVisible = document.visibilityState !== "hidden";
    });
    if ("IntersectionObserver" in window) {
      new IntersectionObserver((entries) => {
        seenHere = entries[entries.length - 1].isIntersecting;
      }).observe(pane);
    }
    window.addEventListener("message", (e) => {
      const d = e.data;
      if (d && d.type === "lfd-visible") seenByParent = !!d.visible;
      else if (d && d.type === "lfd-working") state.working(String(d.text || ""));
    });

    async function applyCommands(items, handle, big) {
      // apply `items` in order with handle(item), in slices that leave input its turn; a
      // `big` batch (e.g. one with an animation) says it is working before it starts
      batches++;
      if (holdSince === null) holdSince = performance.now();
      try {
        if (big && !pageWorking) {
          pageWorking = true;
          showWorking();
          // let the line be painted before the work (a frame, or 50 ms when none comes)
          await new Promise((r) => { requestAnimationFrame(() => setTimeout(r, 0)); setTimeout(r, 50); });
        }
        const start = performance.now();
        let sliceStart = start;
        for (let i = 0; i < items.length; i++) {
          handle(items[i]);
          const now = performance.now();
          if (now - sliceStart > SLICE_MS && i + 1 < items.length) {
            if (!pageWorking && now - start > WORKING_MS) { pageWorking = true; showWorking(); }
            await new Promise((r) => setTimeout(r, 0));
            sliceStart = performance.now();
          }
        }
      } finally {
        batches--;
        if (batches === 0) {
          if (!held) holdSince = null;
          if (pageWorking) { pageWorking = false; showWorking(); }
          viewer.set_dirty();
        }
      }
    }
    showWorking();
    return viewer;
  };
})();
