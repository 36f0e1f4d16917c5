// The wheel over the 3-D view scrolls the page until the view has the focus (as web maps
// do): a click (or Tab) into the view gives it the focus, and the wheel then zooms; Escape,
// or a click outside, gives it back. Unfocused, a hint says so on hover. Both 3-D pages
// run it (tutor/views/scene_page.py: the notebook viewer's and the live server's). A page
// opened on its own (not in a frame) has nothing else to scroll: there the wheel always
// zooms.
//
// How: a wheel listener on the window in the capture phase, which runs before
// OrbitControls' own listener on the viewer's pane. Unfocused, it stops the event there
// (stopPropagation), so the controls never see it, and does not call preventDefault, so
// the browser scrolls: the frame cannot scroll, so the scroll goes on to the page.
// document.body.dataset.wheel is "page" or "view" (what the wheel does now).
(function () {
  if (window.top === window.self) return;
  const body = document.body;
  const style = document.createElement("style");
  style.textContent = [
    "#lfd-wheel-hint { display: none; position: absolute; left: 50%; bottom: 12px;",
    "  transform: translateX(-50%); padding: 4px 10px; border-radius: 4px;",
    "  background: rgba(0,0,0,.72); color: #fff; font: 13px sans-serif;",
    "  pointer-events: none; z-index: 10; }",
    "body:not(.lfd-wheel-focused):hover #lfd-wheel-hint { display: block; }",
    "body.lfd-wheel-focused #meshcat-pane { outline: 2px solid #1a73e8; outline-offset: -2px; }",
  ].join("\n");
  document.head.appendChild(style);
  const hint = document.createElement("div");
  hint.id = "lfd-wheel-hint";
  hint.textContent = "Click to zoom with the wheel";
  body.appendChild(hint);
  const focus = (on) => {
    body.classList.toggle("lfd-wheel-focused", on);
    body.dataset.wheel = on ? "view" : "page";
  };
  focus(false);
  // OrbitControls calls preventDefault on mousedown, which keeps the browser from moving
  // the focus into the frame: move it here, so that a click outside is seen (blur)
  window.addEventListener("pointerdown", () => { focus(true); window.focus(); }, true);
  window.addEventListener("focus", () => focus(true));
  window.addEventListener("blur", () => focus(false));
  window.addEventListener("keydown", (e) => { if (e.key === "Escape") focus(false); }, true);
  window.addEventListener("wheel", (e) => {
    if (!body.classList.contains("lfd-wheel-focused")) e.stopPropagation();
  }, { capture: true, passive: true });
})();
