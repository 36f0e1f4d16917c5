"""Drive notebook 03 (pick and place, BF) in JupyterLab with real mouse clicks, with the
guided hand (the start form's "The tutor guides the arm for me" ticked).

- Demonstrate to the 3-D view updated: the page records when the click happened and the
  viewer records when it applied the update the click caused (the notebook viewer's
  ``data-applied-at``, or the live page's ``document.body.dataset.appliedAt``); the
  median over the demos goes to test-artifacts/latency.json as
  ``pickplace_demonstrate_to_3d_ms`` (merged with what is there, e.g. the maze's).
- The attempt plays by itself after each demo, and Replay plays it again from its start.
- A double click on Demonstrate gives one demonstration.
- The 15-minute cap: runs 2 and 3 are resumed from files written before the notebook
  opens, with 2:14 and 1:40 left: run 2 refuses a demo that would end after 15:00 and
  says how much time is left; run 3 is over (Demonstrate disabled).
- No page errors.

Screenshots go to test-artifacts/pickplace_*.png.
"""

from __future__ import annotations

import json
import os
import re
import time

import numpy as np
import pytest

from tests.browser.conftest import RECORD_CLIPS, open_and_run_all, start_notebook_kernel, wait_clip

pytestmark = pytest.mark.browser

NOTEBOOK = "03_pick_and_place.ipynb"
# a busy 2-core machine: kernel start, Pinocchio, the meshes
WIDGET_TIMEOUT_MS = int(os.environ.get("TUTOR_WIDGET_TIMEOUT_MS", 300_000))
TUTOR = ".lfd-pickplace-tutor"
#: the name typed in the start form (a blank one is refused)
BROWSER_TRAINEE = "Browser Trainee"
LATENCY_KEY = "pickplace_demonstrate_to_3d_ms"

#: Records, in the page, when the last real click on a Demonstrate button happened.
CLICK_CLOCK = """() => {
  if (window.__lfdClicks) return;
  window.__lfdClicks = [];
  document.addEventListener('click', (e) => {
    const b = e.target.closest('button');
    if (b && b.textContent.trim() === 'Demonstrate') window.__lfdClicks.push(Date.now());
  }, true);
}"""


def _write_run_near_the_cap(folder, task, run: int, left: float, seed: int):
    """The browser trainee's BF run file with one real demo and the clock spent up to
    ``left`` seconds (another trainee's file would be refused as another run)."""
    from tutor.framework import Trainee
    from tutor.tasks.pickplace_protocol import PickPlaceRun

    record = PickPlaceRun("BF", task, run=run, trainee=Trainee.from_name(BROWSER_TRAINEE))
    record.demonstrate(44, rng=np.random.default_rng(seed))
    record.spend(record.cap - record.elapsed - left)
    record.save(folder / f"pickplace_BF_run{run}.json")
    return record


@pytest.fixture(scope="module")
def runs_near_the_cap(workdir):
    """Run 2 with 1 s less than its first demo needs (the notebook's seed 2), run 3 with
    less than the shortest demo needs; written where notebook 03 resumes them."""
    from tutor.runtime import trainee_dir
    from tutor.tasks.pickplace import PickPlaceTask

    root, env = workdir
    task = PickPlaceTask()
    before = os.environ.get("TUTOR_RUNS_DIR")
    os.environ["TUTOR_RUNS_DIR"] = env["TUTOR_RUNS_DIR"]
    try:
        folder = trainee_dir(BROWSER_TRAINEE)
    finally:
        if before is None:
            del os.environ["TUTOR_RUNS_DIR"]
        else:
            os.environ["TUTOR_RUNS_DIR"] = before
    # the tutor's hand in run 2 is seeded 2 and guides the arm to plant 44 first
    first = task.duration(task.demonstrate(44, np.random.default_rng(2)))
    two = _write_run_near_the_cap(folder, task, 2, first + 125.0 - 1.0, seed=20)
    three = _write_run_near_the_cap(folder, task, 3, 100.0, seed=30)
    return two, three


def _tutor(page, run: int):
    return page.locator(TUTOR).filter(has_text=re.compile(rf"run {run}\b")).first


def _n_demos(tutor) -> int:
    return int(re.search(r"demonstrations: (\d+)", tutor.inner_text())[1])


class Viewer:
    """The 3-D view of run 1, live (the tutor's page on the kernel's Meshcat server) or
    in the notebook (meshcat's page in the widget's iframe)."""

    def __init__(self, page):
        self.scene = page.locator(".lfd-scene3d").first
        self.scene.wait_for(timeout=WIDGET_TIMEOUT_MS)
        self.notebook_view = self.scene.locator(".lfd-scene3d-view")
        self.mode = "static" if self.notebook_view.count() else "live"
        self.body = self.scene.locator("iframe").first.content_frame.locator("body")

    def state(self) -> dict:
        el = self.notebook_view if self.mode == "static" else self.body
        return el.evaluate("(e) => ({...e.dataset})")

    def updates(self) -> int:
        return int(self.state().get("updates") or 0)

    def wait_updates(self, n: int, timeout: float = 60.0) -> dict:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            state = self.state()
            if int(state.get("updates") or 0) >= n:
                return state
            time.sleep(0.02)
        raise AssertionError(f"the 3-D view did not report update {n}: {self.state()}")

    def js(self, expression: str):
        return self.body.evaluate(f"() => {expression}")

    def clips(self) -> int:
        """Start recording the clips the viewer loads (once); the number so far."""
        return int(self.body.evaluate(RECORD_CLIPS))

    def wait_clip(self, n: int, timeout: float = 30.0) -> list:
        """``[clip time, playing, duration, clips]`` right after the ``n``-th load."""
        return wait_clip(self.body, n, timeout)


def test_demonstrate_updates_the_3d_view_fast_and_the_cap_holds(
    page, jupyterlab, artifacts, runs_near_the_cap
):
    errors = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    url, token = jupyterlab
    start_notebook_kernel(url, token, NOTEBOOK)
    open_and_run_all(page, url, token, NOTEBOOK, WIDGET_TIMEOUT_MS)
    # the start form: choose BF with the mouse, type the name, press Start
    form = page.locator(".lfd-start-form")
    form.wait_for(timeout=WIDGET_TIMEOUT_MS)
    buttons = form.locator(".lfd-start-condition")
    assert buttons.locator("button.mod-active").count() == 0  # nothing preselected
    buttons.get_by_role("button", name="BF", exact=True).click()
    buttons.locator("button.mod-active", has_text="BF").wait_for(timeout=WIDGET_TIMEOUT_MS)
    form.locator(".lfd-start-name input").click()
    page.keyboard.type(BROWSER_TRAINEE)
    # this trainee has the tutor guide the arm (the own hand has its own tests)
    form.locator(".lfd-start-hand input").click()
    assert form.locator(".lfd-start-hand input").is_checked()
    page.screenshot(path=str(artifacts / "pickplace_start_form.png"))
    form.locator(".lfd-start-go").click()
    tutor = _tutor(page, 1)
    try:
        tutor.wait_for(timeout=WIDGET_TIMEOUT_MS)
        viewer = Viewer(page)
        viewer.scene.scroll_into_view_if_needed()
        viewer.wait_updates(1, timeout=WIDGET_TIMEOUT_MS / 1000)
        viewer.body.evaluate("() => viewer.scene !== undefined")
        page.locator(".jp-Notebook-ExecutionIndicator[data-status='idle']").wait_for(
            timeout=WIDGET_TIMEOUT_MS
        )
    except Exception:
        page.screenshot(path=str(artifacts / "pickplace_timeout.png"))
        page.mouse.wheel(0, 2500)
        page.screenshot(path=str(artifacts / "pickplace_timeout_below.png"))
        raise
    page.evaluate(CLICK_CLOCK)
    loaded = viewer.clips()
    demonstrate = tutor.get_by_role("button", name="Demonstrate", exact=True)
    tray = tutor.locator(".widget-gridbox button")
    assert _n_demos(tutor) == 0
    page.screenshot(path=str(artifacts / "pickplace_0_start.png"))

    samples, added = [], []
    plants = [3, 47, 71, 15, 88]  # positions in the drawn grid (any five plants)
    for i, cell in enumerate(plants):
        tray.nth(cell).click()
        n, before = _n_demos(tutor), viewer.updates()
        if i == 3:
            demonstrate.dblclick()  # a double click gives one demonstration
        else:
            demonstrate.click()
        state = viewer.wait_updates(before + 1)
        clicked = page.evaluate("() => window.__lfdClicks")
        first_click = clicked[-2] if i == 3 else clicked[-1]
        samples.append(float(state["appliedAt"]) - first_click)
        # the attempt plays by itself, from its start
        start, playing, duration, _ = viewer.wait_clip(loaded + 1)
        loaded += 1
        assert start < 1e-6 and playing and duration > 5
        time.sleep(2.5 if i == 3 else 0.3)  # a second demo from the double click would be in
        added.append(_n_demos(tutor) - n)
        print(f"demo {i + 1}: {samples[-1]:.0f} ms, {added[-1]} demo(s) added", flush=True)
        page.screenshot(path=str(artifacts / f"pickplace_{i + 1}_demo.png"))

    # Replay plays the attempt again, from its start. The clip is first moved to 3 s (the
    # viewer's own scrubber call), so that a replay that went on from where the clip was
    # would be told apart from one that restarts.
    time.sleep(1.0)
    viewer.js("viewer.animator.seek(3.0)")
    was = float(viewer.js("Math.max(0, ...viewer.animator.actions.map(a => a.time))"))
    assert was >= 2.9, f"the clip did not move to 3 s ({was:.2f} s)"
    before = viewer.updates()
    viewer.scene.get_by_role("button", name="Replay").click()
    viewer.wait_updates(before + 1)
    replay = viewer.wait_clip(loaded + 1)
    print(f"replay: clip at {was:.2f} s before; loaded again as {replay}", flush=True)
    assert viewer.clips() == loaded + 1, "Replay loaded more than one clip"
    start, playing, _, clips = replay
    assert start < 1e-6 and playing and clips > 0, "Replay did not restart the clip"
    # one frame drawn and finished (readPixels waits for the software rasteriser)
    render_ms = viewer.js(
        "(() => { const gl = viewer.renderer.getContext(), px = new Uint8Array(4); "
        "const t = performance.now(); for (let i = 0; i < 5; i++) { "
        "viewer.renderer.render(viewer.scene, viewer.camera); "
        "gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px); } "
        "return (performance.now() - t) / 5; })()"
    )
    page.screenshot(path=str(artifacts / "pickplace_replay.png"))

    report_path = artifacts / "latency.json"
    report = json.loads(report_path.read_text()) if report_path.exists() else {}
    report[LATENCY_KEY] = {
        "median": float(np.median(samples)),
        "samples": samples,
        "viewer": viewer.mode,
        "render_ms_per_frame": float(render_ms),
        "what": "real click on Demonstrate (BF, notebook 03 in JupyterLab, headless chromium, "
        "software GL) to the 3-D viewer having applied the update",
    }
    report_path.write_text(json.dumps(report, indent=2))
    print("Demonstrate -> 3-D view updated:", json.dumps(report[LATENCY_KEY]))

    # the 15-minute cap: run 2 has 1 s less than its next demo needs
    from tutor.tasks.pickplace_protocol import clock

    two, _ = runs_near_the_cap
    # run 2 appears once run 1 is finished (the paper's three runs, in turn)
    tutor.get_by_role("button", name="Finish run", exact=True).click()
    run2 = _tutor(page, 2)
    run2.wait_for(timeout=WIDGET_TIMEOUT_MS)
    run2.scroll_into_view_if_needed()
    assert two.clock_text() in run2.inner_text()  # e.g. "12:46 of 15:00 used"
    n2 = _n_demos(run2)
    run2.get_by_role("button", name="Demonstrate", exact=True).click()
    run2.get_by_text(re.compile(r"of the 15 minutes is left")).wait_for(timeout=60_000)
    text = run2.inner_text()
    assert f"Only {clock(two.remaining)} of the 15 minutes is left: not enough" in text
    assert "not started" in text and _n_demos(run2) == n2
    run2.screenshot(path=str(artifacts / "pickplace_cap_refused.png"))
    # run 3 has 1:40 left, less than the shortest demo and the 5 attempts after it
    run2.get_by_role("button", name="Finish run", exact=True).click()
    run3 = _tutor(page, 3)
    run3.wait_for(timeout=WIDGET_TIMEOUT_MS)
    run3.scroll_into_view_if_needed()
    assert run3.get_by_role("button", name="Demonstrate", exact=True).is_disabled()
    run3.screenshot(path=str(artifacts / "pickplace_cap_over.png"))

    assert not errors, f"page errors: {errors}"
    # the latency target (median <= 500 ms) is judged by benchmarks/bench_browser.py
    assert all(0 < ms < 60_000 for ms in samples), report[LATENCY_KEY]
    assert added == [1] * len(plants), f"demos added per click (the 4th a double click): {added}"
