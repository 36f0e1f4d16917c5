"""The 3-D view leaves input its time: a plant clicked right after a demo highlights fast.

A notebook with ``PickPlaceTutor("NF", scene3d=Scene3D(mode=...))`` (the guided hand
when the tutor has a ``hand`` parameter) runs in JupyterLab, in headless chromium with
software GL, for the notebook viewer ("static") and the kernel's live Meshcat page
("live"). Five times, with real mouse clicks: click a plant, press Demonstrate, and

- right away click another plant (the kernel is still learning from the demo: the click
  waits for it), then
- as soon as the 3-D view has applied the demo's update (its animation starts playing),
  click a third plant,

and measure, in the page, from each click to the tray button being drawn as selected (its
class ``lfd-selected``). The times go to test-artifacts/latency.json as
``click_after_demo_<mode>`` (``benchmarks/bench_click_after_demo.py`` reports the medians
and judges the 300 ms target); the test only asserts a loose bound that catches a starved
page (< 2 s once the update is in). It also checks that the page draws on demand:
``window.lfdRender`` is there, the frame rate is capped while the clip plays and no frame is
drawn while nothing changes; that a big batch of commands (2 s of work) is applied in
slices (a click meanwhile still highlights) and says it is working while it lasts; and
that there were no page or console errors.
"""

from __future__ import annotations

import json
import os
import time

import nbformat
import numpy as np
import pytest

from tests.browser.conftest import ARTIFACTS, open_and_run_all, start_notebook_kernel

pytestmark = pytest.mark.browser

WIDGET_TIMEOUT_MS = int(os.environ.get("TUTOR_WIDGET_TIMEOUT_MS", 300_000))
TUTOR = ".lfd-pickplace-tutor"
#: rounds of (plant before the demo, plant right after Demonstrate, plant after the update)
ROUNDS = ((3, 47, 71), (15, 88, 22), (56, 9, 64), (90, 35, 18), (41, 77, 5))
#: a starved page took 5-9 s; a responsive one well under a second
LOOSE_MS = 2000.0

CELL = """\
import inspect
from tutor.views.pickplace_app import PickPlaceTutor
from tutor.views.scene3d import Scene3D

options = {{"hand": "guided"}} if "hand" in inspect.signature(PickPlaceTutor).parameters else {{}}
tutor = PickPlaceTutor("NF", scene3d=Scene3D(mode={mode!r}), seed=1, **options)
tutor.widget
"""

#: Records in the page when each real click on a tray button happened and when each tray
#: button was first drawn as selected after it ("lfd-selected" added to its class).
CLOCKS = """(tutor) => {
  if (window.__lfdTray) return;
  const tray = tutor.querySelector('.widget-gridbox');
  const buttons = Array.from(tray.querySelectorAll('button'));
  window.__lfdTray = { clicks: {}, selected: {}, working: [] };
  tray.addEventListener('pointerdown', (e) => {
    const i = buttons.indexOf(e.target.closest('button'));
    if (i >= 0) window.__lfdTray.clicks[i] = Date.now();
  }, true);
  new MutationObserver((records) => {
    for (const r of records) {
      const i = buttons.indexOf(r.target);
      if (i >= 0 && r.target.classList.contains('lfd-selected'))
        window.__lfdTray.selected[i] = Date.now();
    }
  }).observe(tray, { attributes: true, attributeFilter: ['class'], subtree: true });
}"""

#: Records, in the viewer's page, when it said it was working (body's data-working "1").
WORKING = """() => {
  if (window.__lfdWorking) return;
  window.__lfdWorking = [];
  new MutationObserver(() => {
    if (document.body.dataset.working === "1") window.__lfdWorking.push(Date.now());
  }).observe(document.body, { attributes: true, attributeFilter: ['data-working'] });
}"""


def _write_notebook(folder, mode: str) -> str:
    name = f"render_probe_{mode}.ipynb"
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(CELL.format(mode=mode))]
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3"}
    nbformat.write(nb, folder / name)
    return name


class View:
    """The tutor's 3-D view: the notebook viewer or the live page, and its lfdRender."""

    def __init__(self, tutor):
        self.scene = tutor.locator(".lfd-scene3d").first
        self.scene.wait_for(timeout=WIDGET_TIMEOUT_MS)
        self.notebook_view = self.scene.locator(".lfd-scene3d-view")
        self.mode = "static" if self.notebook_view.count() else "live"
        self.body = self.scene.locator("iframe").first.content_frame.locator("body")

    def updates(self) -> int:
        el = self.notebook_view if self.mode == "static" else self.body
        return int(el.evaluate("(e) => e.dataset.updates || 0"))

    def wait_updates(self, n: int, timeout: float = 120.0) -> None:
        deadline = time.monotonic() + timeout
        while self.updates() < n:
            if time.monotonic() > deadline:
                raise AssertionError(f"the 3-D view did not report update {n}")
            time.sleep(0.01)

    def render(self) -> dict:
        return self.body.evaluate(
            "() => ({present: !!window.lfdRender, frames: lfdRender.frames, "
            "frameMs: lfdRender.frameMs(), busy: lfdRender.busy(), soft: lfdRender.soft, "
            "visible: lfdRender.visible(), playing: viewer.animator.playing})"
        )


def _wait_selected(page, plant: int, timeout: float = 60.0) -> float:
    """ms from the click on tray button ``plant`` to it being drawn as selected."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        seen = page.evaluate(
            "(i) => [window.__lfdTray.clicks[i], window.__lfdTray.selected[i]]", plant
        )
        if seen[0] is not None and seen[1] is not None and seen[1] >= seen[0]:
            return float(seen[1] - seen[0])
        time.sleep(0.01)
    page.screenshot(path=str(ARTIFACTS / f"render_not_selected_{plant}.png"))
    raise AssertionError(
        f"tray button {plant} was not drawn as selected within {timeout} s (clicked, "
        f"selected at: {seen})"
    )


@pytest.mark.parametrize("mode", ["static", "live"])
def test_plant_clicked_right_after_a_demo_highlights_fast(page, jupyterlab, workdir, mode):
    root, _ = workdir
    url, token = jupyterlab
    notebook = _write_notebook(root / "notebooks", mode)
    start_notebook_kernel(url, token, notebook, fresh=True)
    open_and_run_all(page, url, token, notebook, WIDGET_TIMEOUT_MS, workspace=f"render-{mode}")
    # this notebook's tutor (only it is open in its workspace; hidden ones would not count)
    tutor = page.locator(f"{TUTOR} >> visible=true").first
    try:
        tutor.wait_for(timeout=WIDGET_TIMEOUT_MS)
    except Exception:
        page.screenshot(path=str(ARTIFACTS / f"render_{mode}_timeout.png"))
        raise
    view = View(tutor)
    assert view.mode == mode
    view.scene.scroll_into_view_if_needed()
    view.wait_updates(1, timeout=WIDGET_TIMEOUT_MS / 1000)
    page.locator(".jp-Notebook-ExecutionIndicator[data-status='idle']").wait_for(
        timeout=WIDGET_TIMEOUT_MS
    )
    tutor.evaluate(CLOCKS)
    view.body.evaluate(WORKING)
    tray = tutor.locator(".widget-gridbox button")
    demonstrate = tutor.get_by_role("button", name="Demonstrate", exact=True)
    state = view.render()
    assert state["present"] and state["visible"], state
    # a message posted to the page is handled once, not echoed back to it (meshcat's
    # bundle leaves a GIF worker's onmessage in the page that posted every message back)
    echoes = view.body.evaluate(
        """() => new Promise((done) => {
          let n = 0;
          window.addEventListener("message", (e) => {
            if (e.data && e.data.type === "lfd-echo-probe") n++;
          });
          window.postMessage({ type: "lfd-echo-probe" }, "*");
          setTimeout(() => done([n, window.onmessage === null]), 1000);
        })"""
    )
    assert echoes == [1, True], f"a message was seen {echoes[0]} times in 1 s: {echoes}"

    # no frame while nothing changes (the scene loaded, nothing plays)
    time.sleep(1.0)
    idle0 = view.render()["frames"]
    time.sleep(2.0)
    idle_frames = view.render()["frames"] - idle0

    during, after, rates, frame_ms = [], [], [], []
    for first, during_demo, after_update in ROUNDS:
        tray.nth(first).click()
        _wait_selected(page, first)
        before = view.updates()
        demonstrate.click()
        tray.nth(during_demo).click()  # the kernel is still learning from the demo
        during.append(_wait_selected(page, during_demo))
        try:
            view.wait_updates(before + 1)  # the demo's update applied: its clip starts
        except AssertionError as exc:
            page.screenshot(path=str(ARTIFACTS / f"render_{mode}_no_update.png"))
            raise AssertionError(f"{exc}; the tutor says: {tutor.inner_text()}") from exc
        f0, t0 = view.render()["frames"], time.monotonic()
        tray.nth(after_update).click()
        after.append(_wait_selected(page, after_update))
        time.sleep(1.5)  # the clip plays: frames are drawn, at a capped rate
        shown = view.render()
        rates.append((shown["frames"] - f0) / (time.monotonic() - t0))
        frame_ms.append(shown["frameMs"])
        print(
            f"{mode}: click during the demo {during[-1]:.0f} ms, after its update "
            f"{after[-1]:.0f} ms; {rates[-1]:.1f} frames/s at {frame_ms[-1]:.0f} ms a frame",
            flush=True,
        )

    # a big batch (2 s of commands, 1 ms each) is applied in slices: it says it is working
    # while it lasts, and a plant clicked meanwhile still highlights fast
    view.body.evaluate(
        "() => { window.__lfdBatch = lfdRender.applyCommands(Array(2000).fill(0), () => {"
        " const t = performance.now(); while (performance.now() - t < 1); }, true); }"
    )
    time.sleep(0.3)
    tray.nth(60).click()
    during_batch = _wait_selected(page, 60)
    said = view.body.evaluate("() => document.getElementById('lfd-working').textContent")
    view.body.evaluate("() => window.__lfdBatch")  # until the batch is in
    working = view.body.evaluate("() => window.__lfdWorking.length")
    left = view.body.evaluate("() => [document.body.dataset.working, lfdRender.busy()]")
    print(f"{mode}: click during a 2 s batch {during_batch:.0f} ms; it said {said!r}", flush=True)

    ARTIFACTS.mkdir(exist_ok=True)
    path = ARTIFACTS / "latency.json"
    report = json.loads(path.read_text()) if path.exists() else {}
    report[f"click_after_demo_{mode}"] = {
        "after_update_ms": after,
        "during_demo_ms": during,
        "median_after_update_ms": float(np.median(after)),
        "median_during_demo_ms": float(np.median(during)),
        "frames_per_s_playing": rates,
        "frame_ms": frame_ms,
        "idle_frames_in_2s": idle_frames,
        "during_big_batch_ms": during_batch,
        "software_gl": bool(state["soft"]),
        "what": "NF tutor in JupyterLab, headless chromium (software GL): a real click on a "
        "tray button to it being drawn as selected, right after Demonstrate (waits for the "
        "kernel's demo) and right after the 3-D view applied the demo's update",
    }
    path.write_text(json.dumps(report, indent=2))

    assert idle_frames <= 1, f"{idle_frames} frames drawn in 2 s while nothing changed"
    assert all(r <= 31 for r in rates), f"frame rate not capped: {rates}"
    assert all(r > 0 for r in rates), f"no frame drawn while the clip played: {rates}"
    assert working >= 1 and said.startswith("Working"), (working, said)
    assert left == ["0", False], f"the working line stayed after the batch: {left}"
    assert during_batch < LOOSE_MS, f"a click during a big batch waited {during_batch} ms"
    assert max(after) < LOOSE_MS, f"a click after the demo's update waited {after} ms"
