"""Guiding the arm with one's own hand in the 3-D view (JupyterLab, headless chromium).

A small notebook (written into the test's folder) shows a ``Scene3D`` and starts a guide
with the real :class:`~tutor.robot.follow.HandFollower`; its ``on_end`` writes what the
kernel received to a JSON file. The test guides with a real mouse (drags at the points
``lfdGuideScreen`` gives), real key presses and a stubbed gamepad
(``navigator.getGamepads`` replaced in every frame before its scripts run), ends, and
checks the recording the kernel got: one message, samples at most 50 ms apart, the
hand closed and opened, the arm drawn where the handle went. Once in the notebook
viewer (static) and once with the live Meshcat server's page in the frame.
"""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from tests.browser.conftest import ARTIFACTS, open_and_run_all, start_notebook_kernel
from tests.browser.guiding import GAMEPAD, Guide

pytestmark = pytest.mark.browser

VIEW = ".lfd-scene3d-view, .lfd-scene3d-live"

def _notebook(mode: str, out: str) -> dict:
    source = (
        "import json\n"
        "import os\n"
        "from tutor.robot.follow import HandFollower\n"
        "from tutor.views.scene3d import Scene3D\n"
        f"scene = Scene3D(mode={mode!r}, height=460)\n"
        "follower = HandFollower.for_scene(scene.scene)\n"
        "def on_end(end):\n"
        "    raw = end.raw\n"
        f"    with open({out + '.part'!r}, 'w') as f:\n"
        "        json.dump({'raw': raw.tolist(), 'setup': end.setup_seconds,\n"
        "                   'moves': moves[0], 'mode': scene.mode}, f)\n"
        f"    os.replace({out + '.part'!r}, {out!r})\n"
        "moves = [0]\n"
        "step = follower.step\n"
        "def counted(*a):\n"
        "    moves[0] += 1\n"
        "    return step(*a)\n"
        "follower.step = counted\n"
        "scene.start_guide(follower, on_end)\n"
        "scene"
    )
    return {
        "cells": [
            {
                "cell_type": "code",
                "execution_count": None,
                "id": "guide",
                "metadata": {},
                "outputs": [],
                "source": source,
            }
        ],
        "metadata": {
            "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"}
        },
        "nbformat": 4,
        "nbformat_minor": 5,
    }


def _wait_json(path, timeout=60.0) -> dict:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if path.exists() and path.stat().st_size:
            return json.loads(path.read_text())
        time.sleep(0.2)
    raise AssertionError(f"the kernel got no recording within {timeout} s")


def _run(jupyterlab, workdir, page, mode: str, name: str):
    url, token = jupyterlab
    root, _ = workdir
    out = root / f"guide_{name}.json"
    nb = f"guide_{name}.ipynb"
    (root / "notebooks" / nb).write_text(json.dumps(_notebook(mode, str(out))))
    page.add_init_script(GAMEPAD)
    start_notebook_kernel(url, token, nb, fresh=True)
    # a workspace of its own: the notebook an earlier test opened is not restored beside it
    open_and_run_all(page, url, token, nb, 240_000, workspace=f"guide-{name}")
    try:
        guide = Guide(page, page.locator(f"{VIEW} >> visible=true").first)
        guide.wait_state("armed", timeout_ms=240_000)
    except Exception:
        page.screenshot(path=str(ARTIFACTS / f"guide_{name}_timeout.png"))
        raise
    return guide, out


def _check_recording(got):
    raw = np.array(got["raw"])
    assert raw.ndim == 2 and raw.shape[1] == 5 and len(raw) >= 40
    spacing = np.diff(raw[:, 0])
    assert spacing.min() > 0 and spacing.max() <= 0.050, (
        f"samples {spacing.min() * 1e3:.1f} to {spacing.max() * 1e3:.1f} ms apart"
    )
    assert 0 < got["setup"] <= 120
    assert got["moves"] >= 5  # the kernel followed the handle as it moved
    return raw


def test_guide_with_mouse_keys_and_gamepad_in_the_notebook_viewer(jupyterlab, workdir, page):
    guide, out = _run(jupyterlab, workdir, page, "static", "static")
    s0 = guide.state()
    h0 = np.array(s0["handle"])
    assert s0["samples"] == 0 and s0["grip"] == 0
    panel = guide.frame.locator("#lfd-guide")
    assert "Enter ends" in panel.inner_text()
    # the view takes the keys once clicked (away from the handle: a camera turn of 0 px)
    box = guide.element.bounding_box()
    page.mouse.click(box["x"] + 40, box["y"] + 80)
    guide.frame.wait_for_function("() => document.hasFocus()", timeout=10_000)
    assert "has the keys" in guide.frame.locator("#lfd-guide-focus").inner_text()
    # a drag in the horizontal plane
    target = h0 + [0.08, -0.06, 0.0]
    guide.drag(target)
    s1 = guide.state()
    assert s1["state"] == "recording"
    assert np.allclose(s1["handle"][:2], target[:2], atol=0.01)
    assert abs(s1["handle"][2] - h0[2]) < 1e-6
    camera = guide.frame.evaluate("() => viewer.camera.position.toArray()")
    # Shift+drag: up and down only
    guide.drag(np.array(s1["handle"]) + [0, 0, -0.08], shift=True)
    s2 = guide.state()
    assert np.allclose(s2["handle"][:2], s1["handle"][:2], atol=1e-6)
    assert s2["handle"][2] < s1["handle"][2] - 0.04
    assert guide.frame.evaluate("() => viewer.camera.position.toArray()") == camera
    # keys: arrows move, Q lowers, Space closes the hand
    guide.hold("ArrowUp", 0.6)
    s3 = guide.state()
    assert np.linalg.norm(np.array(s3["handle"][:2]) - s2["handle"][:2]) > 0.03
    guide.hold("q", 0.4)
    assert guide.state()["handle"][2] < s3["handle"][2] - 0.02
    page.keyboard.press("Space")
    assert guide.state()["grip"] == 1
    # the gamepad: left stick to the side, button A opens the hand
    s4 = guide.state()
    guide.pad("pad.axes[0] = 0.9")
    time.sleep(0.6)
    guide.pad("pad.axes[0] = 0")
    s5 = guide.state()
    assert np.linalg.norm(np.array(s5["handle"][:2]) - s4["handle"][:2]) > 0.03
    guide.press_button(0, until=lambda s: s["grip"] == 0)
    assert guide.state()["grip"] == 0
    # the arm was drawn where the handle went: the hand marker follows the tool
    guide.frame.wait_for_function("() => window.lfdGuideLatency.length > 5", timeout=30_000)
    time.sleep(1.0)  # the last move's answer
    hand = guide.frame.evaluate(
        "() => viewer.scene_tree.find(['meshcat', 'lfd', 'hand']).object.position.toArray()"
    )
    assert np.linalg.norm(np.array(hand) - guide.state()["handle"]) < 0.02
    page.screenshot(path=str(ARTIFACTS / "guide_static.png"))
    n = guide.state()["samples"]
    page.keyboard.press("Enter")
    got = _wait_json(out)
    raw = _check_recording(got)
    assert len(raw) >= n
    assert raw[:, 4].max() == 1 and raw[-1, 4] == 0  # closed, then opened
    assert np.allclose(raw[0, 1:4], h0 + [0, 0, 0], atol=0.03)  # from where the hand was
    guide.frame.wait_for_function("() => window.lfdGuideState().state === 'off'", timeout=30_000)
    assert guide.frame.evaluate(
        "() => !viewer.scene_tree.find(['meshcat', 'lfd']).children['guide'] "
    )


def test_guide_in_the_live_viewer_ends_with_the_gamepad(jupyterlab, workdir, page):
    guide, out = _run(jupyterlab, workdir, page, "live", "live")
    src = guide.element.get_attribute("src") or ""
    caption = guide.view.inner_text()
    assert "/lfd/" in src, f"no live viewer: {caption}"
    box = guide.element.bounding_box()
    page.mouse.click(box["x"] + 40, box["y"] + 80)
    h0 = np.array(guide.state()["handle"])
    guide.drag(h0 + [0.05, 0.05, 0.0])
    guide.hold("e", 0.4)
    guide.press_button(0, until=lambda s: s["grip"] == 1)  # close
    assert guide.state()["grip"] == 1
    guide.pad("pad.axes[1] = -0.9")
    time.sleep(0.5)
    guide.pad("pad.axes[1] = 0")
    guide.press_button(9, until=lambda s: s["state"] != "recording")  # start: ends
    got = _wait_json(out)
    assert got["mode"] == "live"
    raw = _check_recording(got)
    assert raw[:, 4].max() == 1
