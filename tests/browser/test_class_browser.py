"""The educator's dashboard (notebook 05) as a Voila app, driven with mouse and keyboard.

Voila serves notebook 05 with ``TUTOR_CLASS_DIR`` pointing at a generated class (8
simulated trainees, one run unfinished, one file spoiled). The test reads the page as an
educator would, adds a late trainee's folder and presses Refresh with the mouse, types
another folder with the keyboard, switches experiment, and runs axe-core on the page.
Any page or console error fails the test.
"""

from __future__ import annotations

import shutil

import pytest

from tests.browser.conftest import axe_check, voila_server
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


@pytest.fixture(scope="module")
def dashboard_url(workdir, class_folder):
    root, env = workdir
    env = {**env, "TUTOR_CLASS_DIR": str(class_folder[0]), "MPLBACKEND": "Agg"}
    with voila_server(root, env, "05_class_results.ipynb") as url:
        yield url


def _status(page) -> str:
    return page.locator(".lfd-class-status").inner_text()


def test_dashboard_in_voila(page, dashboard_url, class_folder, artifacts):
    folder, late = class_folder
    page.goto(dashboard_url)
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
