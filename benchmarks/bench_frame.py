"""Benchmark one frame of the 3-D pick-and-place view (headless chromium, software GL).

The scene (the Panda, table, tray, bin and the 100 plants coloured as after a finished
run) is saved as the static page a trainee can download (``Scene3D.save_html``) and
opened in the headless chromium of the browser tests. In the page, one frame is
``renderer.render`` followed by a one-pixel ``readPixels`` (which waits for the software
rasteriser); the same view is drawn ``--frames`` times per repeat. Printed, and written
to ``benchmarks/results/bench_frame.json``:

- the frame's median and p90 (ms), over every frame of every repeat, as drawn normally
  and as while a hand is guided (``lfdRender.interactive``: on software GL, half the
  pixels a side);
- the draw calls and triangles of one frame (three.js's ``renderer.info``) and the
  meshes in the scene, by kind (instanced meshes counted once, with their instances).

A frame longer than one vsync interval (16.7 ms) shows a vsync later: this is the part of
the own hand's "handle moved -> arm drawn" latency (``bench_guide_browser.py``) spent
drawing. ``--screenshot PATH`` also saves the page as drawn (to compare two versions of
the scene by eye or pixel by pixel).

Run:  .venv/bin/python benchmarks/bench_frame.py [--frames 15] [--repeats 5]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from results_file import RESULTS, save  # noqa: E402

from tests.browser.conftest import CHROMIUM, CHROMIUM_FLAGS  # noqa: E402

#: the page's size (the saved page's view fills it)
VIEWPORT = {"width": 1000, "height": 700}

#: draws ``n`` frames of the current view, each finished; returns their times (ms) and one
#: frame's draw calls and triangles
FRAMES_JS = """(n) => {
  const r = viewer.renderer, gl = r.getContext(), px = new Uint8Array(4), out = [];
  for (let i = 0; i < n; i++) {
    const t = performance.now();
    r.render(viewer.scene, viewer.camera);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    out.push(performance.now() - t);
  }
  return {ms: out, calls: r.info.render.calls, triangles: r.info.render.triangles};
}"""

#: the scene's meshes by the node above them, and the instances of instanced ones
MESHES_JS = """() => {
  const out = {};
  viewer.scene.traverse((o) => {
    if (!o.isMesh || !o.visible) return;
    const names = []; for (let p = o.parent; p; p = p.parent) names.push(p.name);
    const key = names.includes("balls") ? "balls" : names.includes("stems") ? "stems"
      : names.includes("visuals") ? "arm links" : "other";
    out[key] = (out[key] || 0) + 1;
    if (o.isInstancedMesh) out[key + " (instances)"] = o.count;
  });
  return out;
}"""


def scene_page(folder: Path) -> Path:
    """The static page of the bundled scene, plants coloured as after a finished run."""
    from tutor.tasks.pickplace import PickPlaceTask
    from tutor.views.scene3d import Scene3D

    task = PickPlaceTask()
    scene = Scene3D(task, mode="static")
    rng = np.random.default_rng(0)
    status = rng.choice(["pass", "fail"], size=len(task.test_points), p=[0.7, 0.3])
    status[[23, 45, 67]] = "demo"
    scene.set_status(status.astype(object))
    return scene.save_html(folder / "scene.html")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--frames", type=int, default=15, help="frames drawn per repeat")
    parser.add_argument("--repeats", type=int, default=5, help="page loads")
    parser.add_argument("--screenshot", type=Path, help="save the drawn page here")
    parser.add_argument("--out", type=Path, default=RESULTS / "bench_frame.json")
    args = parser.parse_args()

    from playwright.sync_api import sync_playwright

    times, guiding, info = [], [], {}
    with tempfile.TemporaryDirectory() as tmp, sync_playwright() as p:
        path = scene_page(Path(tmp))
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_FLAGS)
        for k in range(args.repeats):
            page = browser.new_page(viewport=VIEWPORT)
            page.goto(path.as_uri())
            page.wait_for_function("document.body.dataset.ready === '1'", timeout=120_000)
            page.evaluate(FRAMES_JS, 3)  # warm up: shaders compiled, buffers uploaded
            result = page.evaluate(FRAMES_JS, args.frames)
            times += result["ms"]
            # as while a hand is guided: on software GL half the pixels a side
            page.evaluate("window.lfdRender.interactive(true)")
            page.evaluate(FRAMES_JS, 3)
            guiding += page.evaluate(FRAMES_JS, args.frames)["ms"]
            page.evaluate("window.lfdRender.interactive(false)")
            info = {
                "draw calls": result["calls"],
                "triangles": result["triangles"],
                "meshes": page.evaluate(MESHES_JS),
            }
            if k == 0 and args.screenshot is not None:
                page.screenshot(path=str(args.screenshot))
                print(f"screenshot: {args.screenshot}")
            page.close()
        browser.close()
    ms, ms_guiding = np.asarray(times), np.asarray(guiding)
    out = {
        "viewport": VIEWPORT,
        "frame_ms_median": round(float(np.median(ms)), 2),
        "frame_ms_p90": round(float(np.percentile(ms, 90)), 2),
        "guiding_frame_ms_median": round(float(np.median(ms_guiding)), 2),
        "guiding_frame_ms_p90": round(float(np.percentile(ms_guiding, 90)), 2),
        "frames": len(ms),
        **info,
    }
    print(
        f"one frame of the 3-D view ({VIEWPORT['width']} x {VIEWPORT['height']} px page): "
        f"median {out['frame_ms_median']} ms, p90 {out['frame_ms_p90']} ms; while a hand "
        f"is guided median {out['guiding_frame_ms_median']} ms, "
        f"p90 {out['guiding_frame_ms_p90']} ms ({len(ms)} frames each, {args.repeats} "
        "page loads)"
    )
    print(f"draw calls {info['draw calls']}, triangles {info['triangles']}")
    print(f"meshes: {info['meshes']}")
    save(out, args.out)


if __name__ == "__main__":
    main()
