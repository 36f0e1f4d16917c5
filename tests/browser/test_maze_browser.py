"""Drive notebook 02 in a real browser with real mouse strokes (JupyterLab and Voila).

Each test draws a demonstration with the mouse on the VF run's sketchpad, from the
start zone through the gaps to the target, and checks that the demo count and the
efficacy shown change, that the picture redraws and that why the failing attempts fail
is written under it. Screenshots go to test-artifacts/. The JupyterLab test also
measures, in the browser, the time from pointer release to the redrawn feedback over 12
strokes (written to test-artifacts/latency.json, key "maze"), then draws a demonstration
with the keyboard alone. Another test shuts the kernel down through the server's REST
API and checks that a stroke then says the tutor is no longer connected. The ``page``
fixture fails any test that raised a page error.
"""

from __future__ import annotations

import json
import re
import time
import urllib.request

import numpy as np
import pytest

from tests.browser.conftest import ARTIFACTS, session_kernel, start_notebook_kernel
from tutor.tasks.maze import load_layout

pytestmark = pytest.mark.browser

LAYOUT = load_layout()
STARTS = [
    (0.03, 0.03),
    (0.17, 0.03),
    (0.10, 0.03),
    (0.06, 0.05),
    (0.14, 0.01),
    (0.02, 0.01),
    (0.185, 0.05),
    (0.10, 0.055),
    (0.045, 0.015),
    (0.125, 0.045),
    (0.08, 0.01),
    (0.16, 0.055),
]


#: the sketchpad's map (the canvas one draws on; the zoomed target view is another)
MAP = "canvas.lfd-pad-map"

# generous: on a busy 2-core machine starting a kernel and running the notebook is slow
WIDGET_TIMEOUT_MS = 300_000


def sketchpad_for(page, condition: str):
    tutor = page.locator(".lfd-maze-tutor").filter(has_text=f"Condition {condition}")
    try:
        tutor.wait_for(timeout=WIDGET_TIMEOUT_MS)
    except Exception:
        page.screenshot(path=str(ARTIFACTS / f"timeout_waiting_for_{condition}.png"))
        raise
    tutor.scroll_into_view_if_needed()
    return tutor, tutor.locator(".lfd-sketchpad")


def draw_stroke(page, pad, start, n_points: int = 40) -> None:
    """Press in the start zone, move through the maze to the target, release."""
    box = pad.locator(MAP).bounding_box()
    ws = LAYOUT.workspace
    scale = box["width"] / (ws.x1 - ws.x0)
    path = LAYOUT.reference_path(start, n_samples=n_points)[:, 1:]
    pts = [(box["x"] + (x - ws.x0) * scale, box["y"] + (ws.y1 - y) * scale) for x, y in path]
    page.mouse.move(*pts[0])
    page.mouse.down()
    for px, py in pts[1:]:
        page.mouse.move(px, py, steps=2)
    page.mouse.up()


def wait_for_demos(pad, n: int) -> None:
    pad.locator(f"xpath=self::*[@data-n-demos='{n}']").wait_for(timeout=30_000)


def colour_counts(pad) -> dict:
    """Pixels of the pass (green) and fail (dark red) colours on the canvas."""
    return pad.locator(MAP).evaluate(
        """(c) => {
          const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
          const near = (i, r, g, b) =>
            Math.abs(d[i] - r) + Math.abs(d[i + 1] - g) + Math.abs(d[i + 2] - b) < 60;
          let green = 0, red = 0;
          for (let i = 0; i < d.length; i += 4) {
            if (near(i, 0x53, 0xa8, 0x46)) green++;
            if (near(i, 0x66, 0x1a, 0x05)) red++;
          }
          return {green, red};
        }"""
    )


def start_and_finish_nf(page, artifacts, name: str) -> None:
    """Press Start on the notebook's form (default name), then teach NF one demo and
    finish it: the form shows VF only after NF, as the paper ran them."""
    go = page.locator(".lfd-start-go")
    try:
        go.wait_for(timeout=WIDGET_TIMEOUT_MS)
    except Exception:
        page.screenshot(path=str(ARTIFACTS / f"timeout_waiting_for_start_{name}.png"))
        raise
    go.scroll_into_view_if_needed()
    # each test teaches as a trainee of its own (the runs of one name resume each other)
    field = page.locator(".lfd-start-name input")
    field.click()
    field.fill(f"browser {name}")
    field.press("Tab")
    page.screenshot(path=str(artifacts / f"{name}_start_form.png"))
    go.click()
    nf, pad = sketchpad_for(page, "NF")
    draw_stroke(page, pad, STARTS[0])
    wait_for_demos(pad, 1)
    nf.get_by_role("button", name="Finish", exact=True).click()


def sketchpad_ids(page) -> list[str]:
    """The ids of every sketchpad's elements in the page (NF's and VF's both shown)."""
    return page.evaluate(
        "() => Array.from(document.querySelectorAll('[id^=\"lfd-pad-\"]'), (e) => e.id)"
    )


def teach_one_demo(page, artifacts, name: str):
    tutor, pad = sketchpad_for(page, "VF")
    # NF's finished sketchpad is still on the page: each element id is there once, so
    # a screen reader's aria-describedby reads the sketchpad it belongs to
    ids = sketchpad_ids(page)
    assert page.locator(".lfd-sketchpad").count() >= 2 and len(ids) >= 4
    assert len(ids) == len(set(ids)), f"element ids repeat across sketchpads: {sorted(ids)}"
    assert "demonstrations: 0" in tutor.inner_text()
    assert "efficacy" not in tutor.inner_text()
    before_id = int(pad.get_attribute("data-render-id"))
    before = colour_counts(pad)
    page.screenshot(path=str(artifacts / f"{name}_before.png"))
    draw_stroke(page, pad, STARTS[0])
    wait_for_demos(pad, 1)
    tutor.get_by_text(re.compile("efficacy")).wait_for(timeout=30_000)
    after = colour_counts(pad)
    pad.screenshot(path=str(artifacts / f"{name}_sketchpad.png"))
    page.screenshot(path=str(artifacts / f"{name}_after.png"))
    text = tutor.inner_text()
    assert "demonstrations: 1" in text
    assert re.search(r"efficacy ε = \d+%", text)
    assert int(pad.get_attribute("data-render-id")) > before_id
    assert before["green"] + before["red"] == 0  # nothing realised before the first demo
    assert after["green"] + after["red"] > 500  # R^ is drawn now
    # why the failing attempts fail is written under the picture, counted by cause
    efficacy = int(re.search(r"efficacy ε = (\d+)%", text).group(1))
    reasons = pad.locator(".lfd-pad-summary").inner_text()
    if efficacy < 100:
        assert after["red"] > 0
        assert re.match(r"\d+ (miss|misses|end|ends|hit|hits|leave|leaves|start) ", reasons), (
            reasons
        )
        counted = sum(int(n) for n in re.findall(r"(?:^|; )(\d+) ", reasons))
        assert abs(counted - (100 - efficacy) / 100 * 140) <= 1  # every failure counted once
    return tutor, pad


def open_notebook(page, url, token, artifacts, name: str = "jupyterlab"):
    """Open notebook 02 in JupyterLab, run all its cells, press Start and finish NF with
    one demo (VF appears after NF); returns the kernel id."""
    kernel = start_notebook_kernel(url, token, "02_maze_experiment.ipynb")
    page.goto(f"{url}/lab/tree/02_maze_experiment.ipynb?token={token}")
    page.locator(".jp-Notebook").wait_for(timeout=WIDGET_TIMEOUT_MS)
    idle = ".jp-Notebook-ExecutionIndicator[data-status='idle']"
    page.locator(idle).wait_for(timeout=WIDGET_TIMEOUT_MS)
    # a "Select Kernel" question is answered by the page's handler (accept_kernel_dialog)
    page.get_by_role("menuitem", name="Run", exact=True).click()
    page.get_by_role("menuitem", name="Run All Cells", exact=True).click()
    start_and_finish_nf(page, artifacts, name)
    return kernel


def n_demos(pad) -> int:
    return int(pad.get_attribute("data-n-demos"))


def keys_to(page, cursor, goal):
    """Arrow key presses moving the keyboard cursor from ``cursor`` to ``goal`` (metres):
    Shift+arrow for each whole centimetre, then plain arrows (2 mm each)."""
    out = list(cursor)
    for axis, (minus, plus) in enumerate((("ArrowLeft", "ArrowRight"), ("ArrowDown", "ArrowUp"))):
        gap = goal[axis] - out[axis]
        key = plus if gap > 0 else minus
        for _ in range(int(abs(gap) // 0.01)):
            page.keyboard.press(f"Shift+{key}")
        rest = round((abs(gap) % 0.01) / 0.002)
        for _ in range(rest):
            page.keyboard.press(key)
        steps = int(abs(gap) // 0.01) * 0.01 + rest * 0.002
        out[axis] += steps if gap > 0 else -steps
    return out


def draw_with_keyboard(page, tutor, pad, artifacts, name: str) -> None:
    """Reach the sketchpad with Shift+Tab from its Undo button, then draw with keys only."""
    canvas = pad.locator(MAP)
    assert canvas.get_attribute("tabindex") == "0"
    assert canvas.get_attribute("role") == "application"
    label = canvas.get_attribute("aria-label")
    assert "arrow keys" in label and "Enter" in label and "Escape" in label
    tutor.get_by_role("button", name="Undo").focus()
    page.keyboard.press("Shift+Tab")
    assert canvas.evaluate("(c) => document.activeElement === c"), "Shift+Tab did not reach it"
    before = n_demos(pad)
    z = LAYOUT.start_zone
    cursor = [(z.x0 + z.x1) / 2, (z.y0 + z.y1) / 2]  # where the cursor starts
    # Escape drops a half-made demonstration: nothing is sent
    cursor = keys_to(page, cursor, (0.05, 0.03))
    page.keyboard.press("Space")
    cursor = keys_to(page, cursor, (0.08, 0.05))
    page.keyboard.press("Escape")
    assert "cancelled" in pad.locator(".lfd-sr-only").inner_text()
    start = (0.03, 0.03)
    waypoints = [start, *map(tuple, LAYOUT.guide_points), tuple(LAYOUT.target_center)]
    for i, goal in enumerate(waypoints):
        cursor = keys_to(page, cursor, goal)
        if i == 1:
            page.screenshot(path=str(artifacts / f"{name}_keyboard_waypoints.png"))
        page.keyboard.press("Enter" if i == len(waypoints) - 1 else "Space")
        if i == 0:
            assert "Waypoint 1" in pad.locator(".lfd-sr-only").inner_text()
    wait_for_demos(pad, before + 1)
    page.screenshot(path=str(artifacts / f"{name}_keyboard_demo.png"))
    assert f"demonstrations: {before + 1}" in tutor.inner_text()


def write_latency(artifacts, report: dict) -> None:
    """Put the maze numbers under "maze" in latency.json, keeping the other tutors' keys."""
    path = artifacts / "latency.json"
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        data = {}
    if not isinstance(data, dict) or "latency_ms_by_demo" in data:
        data = {}  # the old flat file, maze only
    data["maze"] = report
    path.write_text(json.dumps(data, indent=2))


def test_jupyterlab_asks_a_trainee_nothing(jupyterlab):
    """The room's JupyterLab settings (scripts/jupyterlab_overrides.json, installed by the
    README's commands) reach the server as its defaults: no news or update pop-ups, and a
    notebook without a kernel starts the preferred one instead of asking "Select
    Kernel", and no debugger."""
    url, token = jupyterlab
    defaults = {}
    for plugin in ("notebook-extension:tracker", "apputils-extension:notification"):
        with urllib.request.urlopen(
            f"{url}/lab/api/settings/@jupyterlab/{plugin}?token={token}", timeout=30
        ) as reply:
            schema = json.loads(reply.read())["schema"]["properties"]
        defaults[plugin] = {key: value.get("default") for key, value in schema.items()}
    assert defaults["notebook-extension:tracker"]["autoStartDefaultKernel"] is True
    notification = defaults["apputils-extension:notification"]
    assert notification["fetchNews"] == "false" and notification["checkForUpdates"] is False
    # and no debugger (scripts/jupyterlab_page_config.json): the page's own config says so
    with urllib.request.urlopen(f"{url}/lab?token={token}", timeout=30) as reply:
        html = reply.read().decode()
    config = html.split('id="jupyter-config-data"', 1)[1].split(">", 1)[1].split("</script>", 1)[0]
    config = json.loads(config)
    assert "@jupyterlab/debugger-extension" in config["disabledExtensions"]


def test_jupyterlab_draw_demos_and_measure_latency(page, jupyterlab, artifacts):
    url, token = jupyterlab
    open_notebook(page, url, token, artifacts)
    tutor, pad = teach_one_demo(page, artifacts, "jupyterlab")

    latencies, parts = [], {}
    for i, start in enumerate(STARTS[1:], start=2):
        draw_stroke(page, pad, start)
        wait_for_demos(pad, i)
        pad.locator(f"xpath=self::*[@data-latency-for='{i}']").wait_for(timeout=30_000)
        latencies.append(float(pad.get_attribute("data-latency-ms")))
        # where the time went: in the kernel, until the answer arrived, drawing it
        parts[i] = {
            key: float(pad.get_attribute(f"data-{key}-ms")) for key in ("python", "answer", "draw")
        }
    page.screenshot(path=str(artifacts / "jupyterlab_12_demos.png"))
    pad.screenshot(path=str(artifacts / "jupyterlab_12_demos_sketchpad.png"))
    text = tutor.inner_text()
    assert f"demonstrations: {len(STARTS)}" in text
    late = latencies[8 - 2 :]
    report = {
        "what": "maze: pointer release to the first frame painted with Python's answer (ms)",
        "latency_ms_by_demo": dict(zip(range(2, len(STARTS) + 1), latencies, strict=True)),
        "latency_ms_at_demo_10": latencies[10 - 2],
        "median_ms_demos_8_to_12": float(np.median(late)),
        "p90_ms_demos_8_to_12": float(np.percentile(late, 90)),
        "median_ms_all": float(np.median(latencies)),
        "parts_ms_by_demo": parts,
    }
    write_latency(artifacts, report)
    print("pointer release -> feedback visible:", json.dumps(report))

    # VR appears once VF is finished (the paper's order): draw it with the keyboard
    tutor.get_by_role("button", name="Finish", exact=True).click()
    vr, vr_pad = sketchpad_for(page, "VR")
    draw_with_keyboard(page, vr, vr_pad, artifacts, "jupyterlab")
    # the latency targets (median <= 100 ms, p90 <= 200 ms) are judged by
    # benchmarks/bench_browser.py on a quiet machine; here every demo only had to answer
    assert all(0 < ms < 30_000 for ms in latencies), latencies


def kernel_alive(url, token, kernel) -> bool:
    try:
        with urllib.request.urlopen(f"{url}/api/kernels/{kernel}?token={token}", timeout=10):
            return True
    except urllib.error.HTTPError as exc:
        if exc.code == 404:
            return False
        raise


def test_jupyterlab_dead_kernel_says_so(page, jupyterlab, artifacts):
    """A stroke after the kernel is gone says "no longer connected" (it used to vanish)."""
    url, token = jupyterlab
    # the page's own complaints about the lost kernel (websocket, kernel status) are expected
    page.allowed_console_errors = ("WebSocket", "Kernel", "kernel", "404", "Connection")
    # and JupyterLab's own requests to the kernel that was deleted under them (e.g. its
    # create_subshell_request), refused with "Canceled future for ... before replies were
    # done": seen now and then, depending on what JupyterLab had in flight
    page.allowed_page_errors = ("Canceled future for",)
    open_notebook(page, url, token, artifacts, "dead_kernel")
    tutor, pad = sketchpad_for(page, "VF")
    pad.locator("xpath=self::*[@data-render-id]").wait_for(timeout=30_000)
    before = n_demos(pad)
    kernel = session_kernel(url, token, "02_maze_experiment.ipynb")  # the one running now
    request = urllib.request.Request(f"{url}/api/kernels/{kernel}?token={token}", method="DELETE")
    urllib.request.urlopen(request, timeout=60).close()
    deadline = time.monotonic() + 60
    while kernel_alive(url, token, kernel) and time.monotonic() < deadline:
        time.sleep(0.5)
    assert not kernel_alive(url, token, kernel)
    draw_stroke(page, pad, STARTS[0])
    alert = pad.locator(".lfd-pad-alert")
    alert.get_by_text("no longer connected").wait_for(timeout=60_000)
    page.screenshot(path=str(artifacts / "jupyterlab_dead_kernel.png"))
    pad.screenshot(path=str(artifacts / "jupyterlab_dead_kernel_sketchpad.png"))
    assert "run the cell again" in alert.inner_text()
    assert n_demos(pad) == before
    # and a key press says the same, rather than drawing on
    pad.locator(MAP).focus()
    page.keyboard.press("Space")
    assert "no longer connected" in alert.inner_text()


def test_voila_draw_a_demo(page, voila, artifacts):
    page.goto(voila)
    start_and_finish_nf(page, artifacts, "voila")
    teach_one_demo(page, artifacts, "voila")
