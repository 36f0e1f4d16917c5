"""The 3-D view inside a notebook page (Voila, headless chromium), without a Meshcat server.

A tiny notebook shows a pick-and-place tutor with ``Scene3D(mode="static")``: the
viewer in the widget gets the whole scene once, then only the changes. The test turns
the camera with the mouse, demonstrates, and checks that the update arrived, that the
robot's attempt is animated and that the camera stayed where it was turned.
Screenshots go to test-artifacts/.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.browser.conftest import (
    ARTIFACTS,
    RECORD_CLIPS,
    free_port,
    stop,
    wait_clip,
    wait_http,
)

pytestmark = pytest.mark.browser

NOTEBOOK = {
    "cells": [
        {
            "cell_type": "code",
            "execution_count": None,
            "id": "scene3d",
            "metadata": {},
            "outputs": [],
            "source": (
                "from tutor.views.pickplace_app import PickPlaceTutor\n"
                "from tutor.views.scene3d import Scene3D\n"
                "scene = Scene3D(mode='static', height=420)\n"
                "tutor = PickPlaceTutor('RF', scene3d=scene, seed=1, task=scene.task,\n"
                "                       hand='guided')\n"
                "tutor"
            ),
        }
    ],
    "metadata": {
        "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"}
    },
    "nbformat": 4,
    "nbformat_minor": 5,
}
VIEW = ".lfd-scene3d-view"


@pytest.fixture(scope="module")
def voila_scene(workdir):
    root, env = workdir
    nb = root / "scene3d_test.ipynb"
    nb.write_text(json.dumps(NOTEBOOK))
    port = free_port()
    log = open(root / "voila-scene3d.log", "w")  # noqa: SIM115
    proc = subprocess.Popen(
        [sys.executable, "-m", "voila", str(nb), "--no-browser", f"--port={port}"]
        + ["--Voila.ip=127.0.0.1"],
        env={**env, "TUTOR_RUNS_DIR": str(root / "scene3d-sessions")},
        stdout=log,
        stderr=subprocess.STDOUT,
        cwd=root,
    )
    try:
        # a static file, not the page: a GET of the page would start a kernel that runs
        # the notebook and holds its runs' files until Voila culls it
        wait_http(f"http://127.0.0.1:{port}/voila/static/voila.js", proc, timeout=120)
        yield f"http://127.0.0.1:{port}/"
    finally:
        stop(proc)
        log.close()


def updates(page) -> int:
    return int(page.locator(VIEW).first.get_attribute("data-updates") or 0)


def test_notebook_viewer_updates_without_resetting_the_camera(page, voila_scene, artifacts):
    page.goto(voila_scene)
    view = page.locator(VIEW).first
    try:
        view.wait_for(timeout=240_000)
        page.wait_for_function(
            f"document.querySelector('{VIEW}').dataset.updates === '1'", timeout=120_000
        )
    except Exception:
        page.screenshot(path=str(artifacts / "scene3d_voila_timeout.png"))
        raise
    frame = view.locator("iframe").content_frame
    body = frame.locator("body")
    # the meshes drawn, by the node above them: the 100 balls as one instanced mesh (one
    # colour per plant, by status), the 100 stems as one mesh, each of the Panda's 11
    # links as one mesh
    meshes = body.evaluate(
        """() => { const out = {instances: 0, colours: 0};
            viewer.scene.traverse(o => {
                if (!o.isMesh) return;
                const names = []; for (let p = o.parent; p; p = p.parent) names.push(p.name);
                const key = names.includes("balls") ? "balls" : names.includes("stems")
                    ? "stems" : names.includes("visuals") ? "links" : "other";
                out[key] = (out[key] || 0) + 1;
                if (o.isInstancedMesh) {
                    out.instances += o.count;
                    out.colours += o.instanceColor ? o.instanceColor.count : 0;
                }
            });
            return out; }"""
    )
    assert meshes["balls"] == 1 and meshes["stems"] == 1 and meshes["links"] == 11, meshes
    assert meshes["instances"] == 100 and meshes["colours"] == 100, meshes
    assert meshes["other"] >= 3  # table, tray, bin (and the hand)
    box = view.bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(cx, cy)
    page.mouse.down()
    page.mouse.move(cx + 150, cy, steps=10)
    page.mouse.up()
    turned = body.evaluate("() => viewer.camera.position.toArray()")
    page.screenshot(path=str(ARTIFACTS / "scene3d_voila_0.png"))

    loaded = body.evaluate(RECORD_CLIPS)
    page.locator(".lfd-pickplace-tutor").first.get_by_role("button", name="Demonstrate").click()
    page.wait_for_function(
        f"document.querySelector('{VIEW}').dataset.updates === '2'", timeout=120_000
    )
    assert view.get_attribute("data-error") is None
    assert body.evaluate("() => viewer.camera.position.toArray()") == turned
    # the replay of the demonstrated plant plays by itself, from its start (the viewer's
    # command queue sets the clip up just after the update is counted)
    start, playing, duration, clips = wait_clip(body, loaded + 1)
    assert start < 1e-6 and playing and clips > 0
    assert 8 <= duration <= 12
    caption = page.locator(".lfd-scene3d").first.inner_text()
    assert "attempt at plant (5, 5)" in caption
    time.sleep(3)
    page.screenshot(path=str(ARTIFACTS / "scene3d_voila_1.png"))


def test_frame_benchmark_runs_and_the_scene_keeps_its_triangle_budget(tmp_path):
    """``benchmarks/bench_frame.py``, run small: it draws the saved scene page and reports
    one frame; on software GL a frame's cost follows its triangles, so the scene keeps to
    a budget (27k: the arm's 14.5k, the balls' 8k, the stems' 3.2k, the rest)."""
    out = tmp_path / "frame.json"
    script = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_frame.py"
    done = subprocess.run(
        [sys.executable, str(script), "--frames", "2", "--repeats", "1", "--out", str(out)],
        capture_output=True, text=True, timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert "one frame of the 3-D view" in done.stdout
    result = json.loads(out.read_text())
    assert result["frame_ms_median"] > 0 and result["guiding_frame_ms_median"] > 0
    meshes = result["meshes"]
    assert meshes["balls"] == 1 and meshes["balls (instances)"] == 100, meshes
    assert meshes["stems"] == 1 and meshes["arm links"] == 11, meshes
    assert result["draw calls"] <= 30 and 20_000 < result["triangles"] <= 30_000, result
