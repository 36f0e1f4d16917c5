"""The educator's dashboard (notebook 05) as a Voila app, driven with mouse and keyboard.

Voila serves notebook 05 with ``TUTOR_CLASS_DIR`` pointing at a generated class (8
simulated trainees, one run unfinished, one file spoiled). The test reads the page as an
educator would, adds a late trainee's folder and presses Refresh with the mouse, types
another folder with the keyboard, switches experiment, and runs axe-core on the page.
Any page or console error fails the test, and so does any request off the machine (a
CDN), any HTTP error response (a 403 for a POST without the ``_xsrf`` token) and any
failed request (``voila_page``). The page is served with the tutor's Voila template
(``share/jupyter/voila/templates/lfd-tutor``): the widgets' icon font comes from Voila
itself, and leaving the page shuts its kernel down, with no error in Voila's log.
"""

from __future__ import annotations

import json
import shutil
import time

import pytest

from tests.browser.conftest import axe_check, http_errors_in_log, voila_log, voila_server
from tutor.study.simulated_class import write_simulated_class

pytestmark = pytest.mark.browser

TIMEOUT_MS = 180_000


@pytest.fixture(scope="module")
def class_folder(tmp_path_factory):
    root = tmp_path_factory.mktemp("voila-class")
    folder = root / "lfd-class"
    write_simulated_class(folder, 1, 8, seed=11, unfinished=1, damaged=1)
    write_simulated_class(root / "late", 1, 9, seed=11)
    return folder, sorted((root / "late").iterdir())[-1]  # trainee 09, not in the class


NOTEBOOK = "05_class_results.ipynb"


@pytest.fixture(scope="module")
def dashboard_url(workdir, class_folder):
    from voila.paths import collect_template_paths

    try:
        collect_template_paths(["voila", "nbconvert"], "lfd-tutor", prune=True)
    except ValueError:
        pytest.fail(
            "Voila cannot find the tutor's template lfd-tutor: scripts/env.sh copies "
            "share/jupyter/voila/templates/lfd-tutor into the venv (a wheel installs it)"
        )
    root, env = workdir
    env = {**env, "TUTOR_CLASS_DIR": str(class_folder[0]), "MPLBACKEND": "Agg"}
    with voila_server(root, env, NOTEBOOK) as url:
        yield url


def _status(page) -> str:
    return page.locator(".lfd-class-status").inner_text()


def _wait_in_log(log, text: str, timeout: float = 30.0) -> str:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        found = log.read_text()
        if text in found:
            return found
        time.sleep(0.2)
    raise AssertionError(f"{text!r} not in Voila's log within {timeout} s:\n{found[-2000:]}")


def test_dashboard_in_voila(voila_page, workdir, dashboard_url, class_folder, artifacts):
    page = voila_page
    folder, late = class_folder
    page.goto(dashboard_url, timeout=TIMEOUT_MS)  # Voila runs the notebook first
    status = page.locator(".lfd-class-status")
    status.get_by_text("counted from").wait_for(timeout=TIMEOUT_MS)
    assert "22 runs counted from 8 trainees" in _status(page)
    assert "2 files not counted" in _status(page)
    beside = page.locator(".lfd-class-beside table")
    assert beside.locator("tbody tr").count() == 3  # NF, VF, VR
    assert "median η (paper)" in beside.inner_text()
    figure = page.locator(".lfd-class-figure img")
    figure.wait_for(state="visible")
    assert figure.bounding_box()["width"] > 400
    assert "repeated-measures ANOVA" in page.locator(".lfd-class-tests").inner_text()
    assert page.locator(".lfd-class-trainees li").count() == 2
    problems = page.locator(".lfd-class-problems li")
    assert (
        problems.count() == 2
        and "unfinished" in problems.all_inner_texts()[0] + problems.all_inner_texts()[1]
    )
    page.screenshot(path=str(artifacts / "class_dashboard_voila.png"), full_page=True)
    # the folder field fits the dashboard's width (its right end is on the page)
    board = page.locator(".lfd-class-dashboard").bounding_box()
    field = page.locator(".lfd-class-folder").bounding_box()
    assert field["x"] + field["width"] <= board["x"] + board["width"] + 0.5, (field, board)
    assert field["width"] > 0.9 * board["width"], (field, board)  # and is not cut short
    # the toolbar's controls stand 8 px apart (the gap reaches the page)
    refresh = page.locator(".lfd-class-refresh")
    assert refresh.locator("..").evaluate("(e) => getComputedStyle(e).columnGap") == "8px"

    # a late trainee's runs arrive; the educator presses Refresh with the mouse
    shutil.copytree(late, folder / late.name)
    button = page.locator(".lfd-class-refresh")
    box = button.bounding_box()
    page.mouse.click(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
    status.get_by_text("from 9 trainees").wait_for(timeout=60_000)
    assert "25 runs counted from 9 trainees" in _status(page)

    # the other experiment, by clicking its toggle
    page.locator(".lfd-class-experiment button", has_text="Experiment 2").click()
    status.get_by_text("0 runs").wait_for(timeout=60_000)
    assert "files of Experiment 1 are set aside" in _status(page)
    page.locator(".lfd-class-experiment button", has_text="Experiment 1").click()
    status.get_by_text("25 runs").wait_for(timeout=60_000)

    # a mistyped folder, with the keyboard: said in words, nothing breaks
    field = page.locator(".lfd-class-folder input")
    field.click()
    page.keyboard.press("End")
    page.keyboard.type("-typo")
    page.keyboard.press("Enter")
    status.get_by_text("there is no folder or zip file").wait_for(timeout=60_000)
    assert page.locator(".lfd-class-figure img").count() == 0
    field.fill(str(folder))
    page.keyboard.press("Enter")
    status.get_by_text("25 runs").wait_for(timeout=60_000)
    page.screenshot(path=str(artifacts / "class_dashboard_voila_after.png"), full_page=True)
    axe_check(page, artifacts, "class_dashboard", [".lfd-class-dashboard"])

    # the buttons' icons are drawn with the icon font Voila serves (no CDN was asked)
    icon = page.locator(".lfd-class-refresh i.fa")
    assert "Font Awesome" in icon.evaluate("(e) => getComputedStyle(e).fontFamily")
    assert page.evaluate(
        "async () => { await document.fonts.ready; "
        "return document.fonts.check('900 16px \"Font Awesome 5 Free\"'); }"
    )

    # leaving the page shuts its kernel down: Voila's POST carries a valid _xsrf token
    config = json.loads(page.locator("#jupyter-config-data").text_content())
    kernel = config["kernelId"]
    page.goto("about:blank")
    log = voila_log(workdir[0], NOTEBOOK)
    text = _wait_in_log(log, f"Kernel shutdown: {kernel}")
    assert not http_errors_in_log(text), http_errors_in_log(text)
