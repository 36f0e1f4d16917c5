"""A person guiding the arm in a 3-D view, with the real mouse, keys and a stubbed gamepad.

Shared by the browser tests of the own hand (:mod:`tutor.views.static.guide.js` in the
page; :mod:`tutor.views.scene_guide` in the kernel). Points are in the robot's base
frame (metres); :meth:`Guide.screen` turns them into page pixels with the page's own
``lfdGuideScreen`` hook, so a drag ends where the point is drawn.
"""

from __future__ import annotations

import time
from functools import lru_cache

import numpy as np

#: A gamepad the page can poll (``navigator.getGamepads`` replaced in every frame before
#: its scripts run: ``page.add_init_script(GAMEPAD)``); the test moves its sticks and
#: presses its buttons through ``window.__lfdPad``.
GAMEPAD = """
(() => {
  const pad = { id: "test pad", index: 0, connected: true, mapping: "standard",
    axes: [0, 0, 0, 0], timestamp: 0,
    buttons: Array.from({ length: 17 }, () => ({ pressed: false, touched: false, value: 0 })) };
  window.__lfdPad = pad;
  Object.defineProperty(Navigator.prototype, "getGamepads", {
    configurable: true, value: function () { return [pad, null, null, null]; } });
})();
"""

#: how high (m, above the grasp point) the scripted person lifts the plant to carry it
LIFT = 0.12


@lru_cache(maxsize=1)
def pickplace_scene():
    """The bundled pick-and-place scene (where the plants and the bin are)."""
    from tutor.tasks.pickplace import load_scene

    return load_scene()


class Guide:
    """The guide in the 3-D view ``view`` (a locator of the view widget, or of an element
    holding exactly one), driven as a person would."""

    def __init__(self, page, view, timeout_ms: float = 240_000):
        self.page = page
        self.view = view
        self.element = view.locator("iframe").first
        self.element.wait_for(timeout=timeout_ms)
        self.frame = self.element.element_handle(timeout=timeout_ms).content_frame()

    def wait_state(self, state: str, timeout_ms: float = 60_000) -> None:
        self.frame.wait_for_function(
            "(s) => window.lfdGuideState && window.lfdGuideState().state === s",
            arg=state,
            timeout=timeout_ms,
        )

    def state(self) -> dict:
        return self.frame.evaluate("() => window.lfdGuideState()")

    def handle(self) -> np.ndarray:
        return np.array(self.state()["handle"], dtype=float)

    def screen(self, p) -> tuple[float, float]:
        """Page px of the robot-frame point ``p``."""
        x, y = self.frame.evaluate("(p) => window.lfdGuideScreen(p[0], p[1], p[2])", list(p))
        box = self.element.bounding_box()
        return box["x"] + x, box["y"] + y

    def focus(self) -> None:
        """Click the view away from the handle, so that it takes the keys."""
        box = self.element.bounding_box()
        self.page.mouse.click(box["x"] + 30, box["y"] + 60)
        self.frame.wait_for_function("() => document.hasFocus()", timeout=10_000)

    def drag(self, to, shift: bool = False, steps: int = 20, pause: float = 0.015) -> None:
        """Drag the ball to the robot-frame point ``to`` (with Shift: up/down only)."""
        mouse, kb = self.page.mouse, self.page.keyboard
        x0, y0 = self.screen(self.handle())
        x1, y1 = self.screen(to)
        if shift:
            kb.down("Shift")
        mouse.move(x0, y0)
        mouse.down()
        for k in range(1, steps + 1):
            mouse.move(x0 + (x1 - x0) * k / steps, y0 + (y1 - y0) * k / steps)
            time.sleep(pause)
        mouse.up()
        if shift:
            kb.up("Shift")

    def hold(self, key: str, seconds: float) -> None:
        """Hold ``key`` down for ``seconds``."""
        self.page.keyboard.down(key)
        time.sleep(seconds)
        self.page.keyboard.up(key)

    def key_to_height(self, z: float, timeout: float = 10.0) -> None:
        """Hold Shift+Q (fine, down) or Shift+E (fine, up) until the handle is at ``z``."""
        kb = self.page.keyboard
        down = self.handle()[2] > z
        key = "q" if down else "e"
        kb.down("Shift")
        kb.down(key)
        deadline = time.monotonic() + timeout
        try:
            while time.monotonic() < deadline:
                h = self.handle()[2]
                if (h <= z + 0.004) if down else (h >= z - 0.004):
                    break
                time.sleep(0.01)
        finally:
            kb.up(key)
            kb.up("Shift")

    def pad(self, script: str) -> None:
        self.frame.evaluate(f"() => {{ const pad = window.__lfdPad; {script}; }}")

    def press_button(self, i: int, until=None, timeout: float = 5.0) -> None:
        """Press gamepad button ``i``, held until ``until(state)`` holds (as a person holds
        a button until the view shows it took: a busy page polls the pad late)."""
        self.pad(f"pad.buttons[{i}].pressed = true; pad.buttons[{i}].value = 1")
        deadline = time.monotonic() + timeout
        time.sleep(0.3)
        while until is not None and not until(self.state()) and time.monotonic() < deadline:
            time.sleep(0.05)
        self.pad(f"pad.buttons[{i}].pressed = false; pad.buttons[{i}].value = 0")
        time.sleep(0.2)

    def grip(self, closed: bool, with_pad: bool = False) -> None:
        """Close (or open) the hand with Space, or the gamepad's button A."""
        if self.state()["grip"] == (1 if closed else 0):
            return
        if with_pad:
            self.press_button(0, until=lambda s: s["grip"] == (1 if closed else 0))
        else:
            self.page.keyboard.press("Space")
        self.frame.wait_for_function(
            "(g) => window.lfdGuideState().grip === g", arg=1 if closed else 0, timeout=5_000
        )

    def latencies(self) -> list[float]:
        """ms from each move sent to the frame drawn with the arm at its answer."""
        return [float(x) for x in self.frame.evaluate("() => window.lfdGuideLatency.slice()")]

    def pick_and_place(self, grasp, release, style: str = "mouse") -> None:
        """One whole demonstration, as a person gives it: to above the plant, down to its
        grasp point, close the hand, lift, carry to above the bin, open the hand, Enter.

        ``style`` "mouse": drags only (Shift+drag for height), Space, Enter; "keys": the
        height with Shift+Q/E; "gamepad": the hand with button A and the end with Start.
        """
        grasp, release = np.asarray(grasp, float), np.asarray(release, float)
        self.focus()
        h = self.handle()
        self.drag([grasp[0], grasp[1], h[2]])
        if style == "keys":
            self.key_to_height(grasp[2])
        else:
            self.drag([grasp[0], grasp[1], grasp[2]], shift=True)
        self.grip(True, with_pad=style == "gamepad")
        carry = max(grasp[2] + LIFT, release[2])
        h = self.handle()
        self.drag([h[0], h[1], carry], shift=True)
        self.drag([release[0], release[1], carry])
        if carry - release[2] > 0.01:
            h = self.handle()
            self.drag([h[0], h[1], release[2]], shift=True)
        self.grip(False, with_pad=style == "gamepad")
        if style == "gamepad":
            self.press_button(9, until=lambda s: s["state"] != "recording")
        else:
            self.page.keyboard.press("Enter")



#: the plants of a tray map (``.widget-gridbox`` buttons under ``root``) that are not
#: wholly in sight within the tutor: cut off by a box around them that clips or scrolls
#: (a map squeezed by the controls beside it scrolls sideways, with no sign that
#: columns are hidden). Checked without scrolling anything.
UNREACHABLE_PLANTS = """
(root) => [...root.querySelectorAll(".widget-gridbox button")].flatMap((button, i) => {
  const r = button.getBoundingClientRect();
  for (let box = button.parentElement; box !== null && box !== root.parentElement;
       box = box.parentElement) {
    const style = getComputedStyle(box);
    if (style.overflowX === "visible" && style.overflowY === "visible") continue;
    const c = box.getBoundingClientRect();
    if (r.left < c.left - 0.5 || r.right > c.right + 0.5 ||
        r.top < c.top - 0.5 || r.bottom > c.bottom + 0.5) return [i];
  }
  return [];
})
"""
