"""What a trainee sees, driven with the real mouse and keyboard in JupyterLab.

Two notebooks stay open for the whole module (one page and one kernel each, so the
kernel starts and the cells run once):

- **Pick-and-place** (a test copy of notebook 03 written into the workdir: five start
  forms made with ``pick_and_place_experiment(scene3d=False)``; the 3-D view has its own
  tests). The condition is clicked on the form for NF, RF and BF, and set by the
  "educator" through ``TUTOR_CONDITION`` for SF (the form then locks it). Each form gets
  its own trainee name, typed on the keyboard, so their run files never meet.

  - each condition shows only its r, in the panel and on the tray map, and nothing of
    efficacy or efficiency (ε, η) until Finish run, which then reveals all 100 plants
    and one η;
  - three plants clicked one after another: exactly one is highlighted each time;
  - RF's map shows the replayed plant's result.

- **The maze** (notebook 02 as shipped): after NF is finished, the VF run gets a
  scripted series of good and bad strokes (one through an obstacle, one repeating an
  earlier demo, an Undo) and the panel is read after each: no pair of its lines may
  contradict each other or the picture, and "you may finish" is said at most once.
  Then Reset: one click asks and changes nothing (and the question expires after 5 s), a
  second click within 5 s starts attempt 2, and Bring back restores attempt 1.

- **axe-core** (axe-playwright-python) runs on both pages, restricted to the tutors' own
  widgets; no violation may be serious or critical. The full results go to
  test-artifacts/axe_maze.json and axe_pickplace.json.

The pages fail the module on any page error or console error (conftest's
:func:`watch_errors`). Screenshots go to test-artifacts/trainee_*.png.
"""

from __future__ import annotations

import json
import re
import time

import nbformat
import numpy as np
import pytest

from tests.browser.conftest import (
    accept_kernel_dialog,
    axe_check,
    fail_on_errors,
    start_notebook_kernel,
    watch_errors,
)
from tests.browser.test_maze_browser import (
    LAYOUT,
    MAP,
    STARTS,
    WIDGET_TIMEOUT_MS,
    draw_stroke,
    open_notebook,
    sketchpad_for,
    wait_for_demos,
)

pytestmark = pytest.mark.browser

PICKPLACE_NOTEBOOK = "trainee_pickplace.ipynb"
TUTOR = ".lfd-pickplace-tutor"
#: the forms of the test notebook, in cell order
FORMS = ("NF", "RF", "BF", "SF", "clicks")
#: the condition the educator sets for a form (through TUTOR_CONDITION), not the trainee
EDUCATOR_SET = {"SF"}
#: BF's five sample plants: the corners and the centre, row-major indices of the 10 x 10 tray
SAMPLES = {0, 9, 44, 90, 99}
#: the plant each condition demonstrates (row 3, column 4: not a sample) and SF tests
DEMO_PLANT, TEST_PLANT = 23, 67
SECRET = ("efficacy", "ε", "η")
PASS_FAIL = {"✓", "✗"}

#: every tray button's glyph, tooltip, selection class and border width, in plant order
TRAY_STATE = """(grid) => [...grid.querySelectorAll('button')].map((b) => ({
  glyph: b.textContent.trim(),
  title: b.title,
  selected: b.classList.contains('lfd-selected'),
  border: getComputedStyle(b).borderTopWidth,
}))"""


# ---------------------------------------------------------------- pages kept for the module


def _run_all_cells(page, url: str, token: str, path: str, workspace: str) -> None:
    """Open ``path`` on the kernel session started for it and run all its cells.

    The page gets a JupyterLab workspace of its own, so another page of the same server
    (notebook 02's, on the default workspace) does not restore this notebook's tab.
    """
    start_notebook_kernel(url, token, path)
    page.goto(f"{url}/lab/workspaces/{workspace}/tree/{path}?token={token}")
    page.locator(".jp-Notebook").wait_for(timeout=WIDGET_TIMEOUT_MS)
    idle = ".jp-Notebook-ExecutionIndicator[data-status='idle']"
    page.locator(idle).wait_for(timeout=WIDGET_TIMEOUT_MS)
    # a "Select Kernel" question is answered by the page's handler (accept_kernel_dialog)
    page.get_by_role("menuitem", name="Run", exact=True).click()
    page.get_by_role("menuitem", name="Run All Cells", exact=True).click()


def _write_pickplace_notebook(folder) -> None:
    """Notebook 03's start form, once per form of FORMS, without the 3-D view."""
    cells = [
        nbformat.v4.new_markdown_cell(
            "Test copy of notebook 03 (written by tests/browser/test_trainee_browser.py): "
            "one start form per condition, no 3-D view."
        ),
        nbformat.v4.new_code_cell(
            "import os\nfrom tutor.views.start_pickplace import pick_and_place_experiment"
        ),
    ]
    for name in FORMS:
        make = f"form_{name} = pick_and_place_experiment(scene3d=False)"
        if name in EDUCATOR_SET:  # as an educator would set it on the server
            make = (
                f'os.environ["TUTOR_CONDITION"] = "{name}"\n{make}\n'
                'del os.environ["TUTOR_CONDITION"]'
            )
        cells.append(nbformat.v4.new_code_cell(f"{make}\nform_{name}"))
    nb = nbformat.v4.new_notebook(cells=cells)
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3"}
    nbformat.write(nb, folder / PICKPLACE_NOTEBOOK)


@pytest.fixture(scope="module")
def pages(browser, jupyterlab):
    """Pages kept open for the module (closed before the server stops); each fails the
    module on any page or console error."""
    contexts, watched = [], []

    def new_page(name: str):
        context = browser.new_context(viewport={"width": 1400, "height": 1000})
        pg = context.new_page()
        accept_kernel_dialog(pg)
        contexts.append(context)
        watched.append((name, watch_errors(pg)))
        return pg

    yield new_page
    for context in contexts:
        context.close()
    for name, errors in watched:
        fail_on_errors(errors, f"trainee_{name}")


@pytest.fixture(scope="module")
def pickplace_page(pages, jupyterlab, workdir, artifacts):
    root, _ = workdir
    _write_pickplace_notebook(root / "notebooks")
    page = pages("pickplace")
    url, token = jupyterlab
    _run_all_cells(page, url, token, PICKPLACE_NOTEBOOK, workspace="trainee-pickplace")
    forms = page.locator(".lfd-start-form")
    try:
        forms.nth(len(FORMS) - 1).locator(".lfd-start-go").wait_for(timeout=WIDGET_TIMEOUT_MS)
    except Exception:
        page.screenshot(path=str(artifacts / "trainee_pickplace_timeout.png"))
        raise
    page.screenshot(path=str(artifacts / "trainee_pickplace_forms.png"))
    return page


@pytest.fixture(scope="module")
def maze_page(pages, jupyterlab, artifacts):
    """Notebook 02 with NF finished (one stroke): the VF run is shown."""
    page = pages("maze")
    url, token = jupyterlab
    open_notebook(page, url, token, artifacts, "trainee_maze")
    return page


# ---------------------------------------------------------------- pick-and-place helpers


def _form(page, name: str):
    return page.locator(".lfd-start-form").nth(FORMS.index(name))


def _run_tutor(form, run: int = 1):
    return form.locator(TUTOR).filter(has_text=re.compile(rf"\brun {run}\b")).first


def _wait_for_run(form, run: int, artifacts, shot: str):
    """Run ``run``'s tutor once shown; on a timeout, a screenshot of the form and an
    assertion that says what the form and its cell showed instead (its note, the runs
    it shows, any stderr of the cell such as the server's IOPub rate message)."""
    tutor = _run_tutor(form, run)
    try:
        tutor.wait_for(timeout=60_000)
    except Exception as exc:
        form.screenshot(path=str(artifacts / f"trainee_{shot}_run{run}_timeout.png"))
        note = form.locator(".lfd-start-note").all_inner_texts()
        shown = [
            next((line for line in t.splitlines() if "Condition" in line), t[:200])
            for t in form.locator(TUTOR).all_inner_texts()
        ]
        cell = form.locator("xpath=ancestor::div[contains(@class, 'jp-Cell')][1]")
        stderr = cell.locator("[data-mime-type='application/vnd.jupyter.stderr']")
        raise AssertionError(
            f"run {run} was not shown within 60 s ({type(exc).__name__}); the form's note: "
            f"{note}; its runs: {shown}; the cell's stderr: {stderr.all_inner_texts()}"
        ) from exc
    return tutor


def _start(page, form, condition: str, trainee: str, artifacts, shot: str):
    """Choose ``condition`` (unless the educator set it), type the name, press Start."""
    form.scroll_into_view_if_needed()
    buttons = form.locator(".lfd-start-condition")
    if condition in EDUCATOR_SET:  # locked by TUTOR_CONDITION, and the form says why
        assert "set by your educator" in form.locator(".lfd-start-note").inner_text()
        for button in buttons.get_by_role("button").all():
            assert button.is_disabled()
    else:  # nothing is preselected: the trainee chooses with a click
        assert buttons.locator("button.mod-active").count() == 0
        prompt = form.locator(".lfd-start-condition-prompt").inner_text()
        assert "Choose your condition" in prompt
        buttons.get_by_role("button", name=condition, exact=True).click()
    active = buttons.locator("button.mod-active")
    assert active.inner_text().strip() == condition
    form.locator(".lfd-start-name input").click()
    page.keyboard.type(trainee)
    form.screenshot(path=str(artifacts / f"trainee_{shot}_1_form.png"))
    form.locator(".lfd-start-go").click()
    tutor = _wait_for_run(form, 1, artifacts, shot)
    text = tutor.inner_text()
    assert f"Condition {condition}" in text and "demonstrations: 0" in text
    assert trainee in text  # the run is recorded under the typed name
    return tutor


def _tray(tutor, timeout: float = 15.0) -> list[dict]:
    """The tray as drawn, once it has settled: the kernel redraws its 100 buttons in many
    small messages, which may still be arriving when the text the test waited for shows."""
    grid = tutor.locator(".widget-gridbox")
    state, deadline = grid.evaluate(TRAY_STATE), time.monotonic() + timeout
    while time.monotonic() < deadline:
        time.sleep(0.25)
        again = grid.evaluate(TRAY_STATE)
        if again == state:
            return state
        state = again
    raise AssertionError(f"the tray was still changing {timeout} s on: {state}")


def _plant_button(tutor, plant: int):
    return tutor.locator(".widget-gridbox button").nth(plant)


def _click_plant(tutor, plant: int) -> None:
    """Click plant ``plant`` with the mouse and wait until the kernel has selected it."""
    button = _plant_button(tutor, plant)
    button.click()
    button.and_(tutor.locator("button.lfd-selected")).wait_for(timeout=30_000)


def _panel(tutor) -> str:
    """What the tutor says and shows: its text and every tooltip of the tray."""
    return tutor.inner_text() + "\n" + "\n".join(b["title"] for b in _tray(tutor))


def _revealed(tray) -> set[int]:
    return {i for i, b in enumerate(tray) if b["glyph"] in PASS_FAIL}


def _assert_secret(tutor, when: str) -> None:
    text = _panel(tutor)
    for word in SECRET:
        assert word not in text, f"{word!r} shown {when}: {text[:800]}"


def _demonstrate(tutor, n: int) -> None:
    tutor.get_by_role("button", name="Demonstrate", exact=True).click()
    tutor.get_by_text(re.compile(rf"demonstrations: {n}(?!\d)")).wait_for(timeout=60_000)
    # the demonstrated plant shows ● (or, in RF, the replay's ✓ or ✗)
    _plant_button(tutor, DEMO_PLANT).filter(has_text=re.compile("[●✓✗]")).wait_for(timeout=30_000)


# ---------------------------------------------------------------- pick-and-place tests


@pytest.mark.parametrize("condition", ["NF", "RF", "BF", "SF"])
def test_condition_shows_only_its_r(pickplace_page, artifacts, condition):
    page = pickplace_page
    shot = f"pickplace_{condition}"
    tutor = _start(
        page, _form(page, condition), condition, f"trainee-{condition.lower()}", artifacts, shot
    )
    assert _revealed(_tray(tutor)) == set()
    _click_plant(tutor, DEMO_PLANT)
    _demonstrate(tutor, 1)
    tutor.screenshot(path=str(artifacts / f"trainee_{shot}_2_demo.png"))
    tray = _tray(tutor)
    lines = tutor.locator("ul.lfd-feedback li").all_inner_texts()
    said = " ".join(lines)
    replayed = condition == "RF"  # RF's r is the demonstrated plant: its result shows
    assert tray[DEMO_PLANT]["glyph"] in ({"✓", "✗"} if replayed else {"●"}), tray[DEMO_PLANT]
    assert "demonstrated" in tray[DEMO_PLANT]["title"]
    if condition == "NF":
        assert _revealed(tray) == set()
        assert "shows nothing" in said
    elif condition == "RF":
        # r is the replay of the demonstrated plant: the panel and the map give its result
        assert _revealed(tray) == {DEMO_PLANT}
        assert re.search(r"The robot tried plant \(3, 4\): it (succeeds|fails)", said), said
        assert len(re.findall(r"plant \(\d+, \d+\)", said)) == 1, said
    elif condition == "BF":
        assert _revealed(tray) == SAMPLES  # the four corners and the centre
        assert "The robot tried 5 plants" in said
        for plant in SAMPLES:
            title = tray[plant]["title"]
            assert "the robot succeeds" in title or "the robot fails" in title, title
    else:  # SF: nothing until a plant is tested, then that plant
        assert _revealed(tray) == set()
        assert "shows nothing" in said
        _assert_secret(tutor, f"in {condition} after the demo")
        _click_plant(tutor, TEST_PLANT)
        tutor.get_by_role("button", name="Test plant", exact=True).click()
        tutor.get_by_text("The robot tried plant (7, 8)").first.wait_for(timeout=30_000)
        tutor.screenshot(path=str(artifacts / f"trainee_{shot}_3_tested.png"))
        tray = _tray(tutor)
        assert _revealed(tray) == {TEST_PLANT}
        said = " ".join(tutor.locator("ul.lfd-feedback li").all_inner_texts())
        assert re.search(r"The robot tried plant \(7, 8\): it (succeeds|fails)", said), said
    # the tooltips say nothing about plants the condition did not show
    shown = _revealed(tray) | {DEMO_PLANT}
    told = [
        (i, b["title"])
        for i, b in enumerate(tray)
        if i not in shown
        and not re.fullmatch(r"plant \(\d+, \d+\): not seen yet( \(selected\))?", b["title"])
    ]
    assert not told, told
    _assert_secret(tutor, f"in {condition} before Finish run")

    tutor.get_by_role("button", name="Finish run", exact=True).click()
    tutor.locator(".lfd-score").wait_for(timeout=60_000)
    tutor.screenshot(path=str(artifacts / f"trainee_{shot}_4_finished.png"))
    tray = _tray(tutor)
    assert all(b["glyph"] in PASS_FAIL | {"●"} for b in tray), [b["glyph"] for b in tray]
    assert sum(b["glyph"] == "●" for b in tray) == 1
    text = tutor.inner_text()
    # one score, said once, and the optimal teacher's reference beside it
    assert text.count("teaching efficiency is η") == 1, text
    assert text.count("the best possible η") == 1, text
    assert "Run over." in text and "efficacy ε" in text
    # run 2 appears under run 1, as the paper ran them
    _wait_for_run(_form(page, condition), 2, artifacts, shot)


def test_exactly_one_plant_highlighted(pickplace_page, artifacts):
    page = pickplace_page
    form = _form(page, "clicks")
    tutor = _ensure_started(page, form, artifacts)
    for k, plant in enumerate((12, 57, 90), start=1):
        _click_plant(tutor, plant)
        tray = _tray(tutor)
        selected = [i for i, b in enumerate(tray) if b["selected"]]
        thick = [i for i, b in enumerate(tray) if b["border"] == "3px"]
        assert selected == [plant] and thick == [plant], (selected, thick)
        assert tray[plant]["title"].endswith("(selected)")
        assert sum(b["title"].endswith("(selected)") for b in tray) == 1
        name = f"plant ({plant // 10 + 1}, {plant % 10 + 1})"
        assert f"selected: {name}" in tutor.inner_text()
        tutor.screenshot(path=str(artifacts / f"trainee_pickplace_click_{k}.png"))


def _ensure_started(page, form, artifacts):
    """The "clicks" form, started in RF by the trainee "trainee-clicks" (once)."""
    tutor = _run_tutor(form)
    if not tutor.count():
        tutor = _start(page, form, "RF", "trainee-clicks", artifacts, "pickplace_clicks")
    return tutor


def test_rf_map_shows_the_replayed_plant(pickplace_page, artifacts):
    page = pickplace_page
    tutor = _ensure_started(page, _form(page, "clicks"), artifacts)
    _click_plant(tutor, DEMO_PLANT)
    n = int(re.search(r"demonstrations: (\d+)", tutor.inner_text())[1])
    _demonstrate(tutor, n + 1)
    tutor.screenshot(path=str(artifacts / "trainee_pickplace_RF_replay_on_map.png"))
    tray = _tray(tutor)
    assert _revealed(tray) == {DEMO_PLANT}, (
        f"RF's map should show the replayed plant's result; it shows "
        f"{tray[DEMO_PLANT]['glyph']!r} ({tray[DEMO_PLANT]['title']})"
    )


# ---------------------------------------------------------------- the maze: one voice


def draw_points(page, pad, points) -> None:
    """A stroke through ``points`` (metres) on the sketchpad's map, with the mouse."""
    box = pad.locator(MAP).bounding_box()
    ws = LAYOUT.workspace
    scale = box["width"] / (ws.x1 - ws.x0)
    pixels = [(box["x"] + (x - ws.x0) * scale, box["y"] + (ws.y1 - y) * scale) for x, y in points]
    page.mouse.move(*pixels[0])
    page.mouse.down()
    for px, py in pixels[1:]:
        page.mouse.move(px, py, steps=2)
    page.mouse.up()


def through_obstacle(page, pad) -> None:
    """A straight line from the middle of the start zone to the target: hits obstacle 1."""
    start, goal = np.array([0.10, 0.03]), np.asarray(LAYOUT.target_center, dtype=float)
    draw_points(page, pad, np.linspace(start, goal, 40))


#: a start point or plant named in a line, with what the line says the robot does there
VERDICT = re.compile(
    r"((?:start point|plant) (?:\d+|\(\d+, \d+\)))(?::| ) ?(?:it )?(succeeds|fails)"
)
WARNINGS = ("does not do the task", "went wrong", "made things no better", "almost the same")


def contradictions(lines: list[str], summary: str) -> list[str]:
    """Pairs of things the panel (its lines, and the counts under the picture) says that
    cannot both be true; empty when it speaks with one voice."""
    text = " ".join(lines)
    found = []
    wrong = "does not do the task" in text or "went wrong" in text
    warned = any(w in text for w in WARNINGS)
    finish = "you may finish" in text
    go_on = "demonstrate there next" in text
    if wrong and (finish or go_on):
        found.append("a demo that does not do the task, yet 'you may finish' or 'go on'")
    if warned and finish:
        found.append("a warning about the demo beside 'you may finish'")
    if "No failures" in text and (warned or "still fail" in text):
        found.append("'No failures' beside a warning")
    if finish and go_on:
        found.append("'you may finish' beside 'demonstrate there next'")
    counts = re.search(r"succeeds from (\d+) of the (\d+)", text)
    eps = re.search(r"efficacy ε = (\d+)%", text)
    if eps and finish and int(eps[1]) < 90:
        found.append(f"'you may finish' at ε = {eps[1]}%")
    if counts and counts[1] == counts[2] and ("still fail" in text or go_on):
        found.append("every start point succeeds, yet some 'still fail'")
    verdicts: dict[str, set[str]] = {}
    for name, verdict in VERDICT.findall(text):
        verdicts.setdefault(name, set()).add(verdict)
    found += [f"{name} both succeeds and fails" for name, v in verdicts.items() if len(v) > 1]
    if counts:  # the picture's counts of why attempts fail add up to the failures said
        counted = sum(int(n) for n in re.findall(r"(?:^|; )(\d+) ", summary))
        failing = int(counts[2]) - int(counts[1])
        if counted != failing:
            found.append(f"the panel says {failing} fail, the picture counts {counted}")
    return found


def test_scripted_demos_never_contradict(maze_page, artifacts):
    """Good and bad strokes in VF, the panel read after each (see :func:`contradictions`)."""
    page = maze_page
    tutor, pad = sketchpad_for(page, "VF")
    obstacle = ("obstacle", lambda: through_obstacle(page, pad), +1)
    undo = ("undo", lambda: tutor.get_by_role("button", name="Undo", exact=True).click(), -1)
    good = [(f"good{i}", lambda s=s: draw_stroke(page, pad, s), +1) for i, s in enumerate(STARTS)]
    repeat = ("repeat", lambda: draw_stroke(page, pad, STARTS[0]), +1)
    steps = [good[0], obstacle, undo, repeat, *good[1:8]]
    n = int(pad.get_attribute("data-n-demos"))
    said, finish_prompts = {}, 0
    for k, (name, act, change) in enumerate(steps, start=1):
        act()
        n += change
        wait_for_demos(pad, n)
        tutor.get_by_text(re.compile(rf"demonstrations: {n}(?!\d)")).wait_for(timeout=30_000)
        lines = tutor.locator("ul.lfd-feedback li").all_inner_texts()
        summary = pad.locator(".lfd-pad-summary").inner_text()
        message = tutor.locator(".lfd-message")
        lines += message.all_inner_texts()
        tutor.screenshot(path=str(artifacts / f"trainee_maze_{k:02d}_{name}.png"))
        said[f"{k:02d} {name}"] = {"lines": lines, "under the picture": summary}
        finish_prompts += sum("you may finish" in line for line in lines)
        problems = contradictions(lines, summary)
        assert not problems, f"step {k} ({name}): {problems}\n{lines}\n{summary}"
        if name == "obstacle":  # the bad demo is called bad, with its reason
            assert any("does not do the task" in x and "hit obstacle" in x for x in lines), lines
    (artifacts / "trainee_maze_panel.json").write_text(json.dumps(said, indent=2))
    assert finish_prompts <= 1, f"'you may finish' said {finish_prompts} times"


def test_reset_asks_then_keeps_the_old_attempt(maze_page, artifacts):
    page = maze_page
    tutor, pad = sketchpad_for(page, "VF")
    if int(pad.get_attribute("data-n-demos")) == 0:
        draw_stroke(page, pad, STARTS[1])
        wait_for_demos(pad, 1)
    n = int(pad.get_attribute("data-n-demos"))
    reset = tutor.get_by_role("button", name="Reset", exact=True)
    attempts = tutor.locator(".widget-dropdown").filter(has_text="Earlier attempts")
    bring_back = tutor.get_by_role("button", name="Bring back", exact=True)
    message = tutor.locator(".lfd-message")

    reset.click()  # one click asks and changes nothing
    message.get_by_text("Press Reset again within 5 seconds").wait_for(timeout=30_000)
    tutor.screenshot(path=str(artifacts / "trainee_reset_1_asks.png"))
    assert f"demonstrations: {n}" in tutor.inner_text()
    assert int(pad.get_attribute("data-n-demos")) == n
    assert not attempts.is_visible()
    time.sleep(5.5)  # the question expires: the next click asks again
    reset.click()
    page.wait_for_timeout(1500)
    assert "Press Reset again" in message.inner_text()
    assert int(pad.get_attribute("data-n-demos")) == n
    reset.click()  # a second click within 5 s starts attempt 2
    message.get_by_text("Started attempt 2").wait_for(timeout=30_000)
    wait_for_demos(pad, 0)
    attempts.wait_for(state="visible", timeout=30_000)
    tutor.screenshot(path=str(artifacts / "trainee_reset_2_new_attempt.png"))
    assert "demonstrations: 0" in tutor.inner_text()
    options = [o.replace("\xa0", " ") for o in attempts.locator("option").all_inner_texts()]
    assert len(options) == 1 and options[0].startswith(f"attempt 1: {n} demo(s)"), options
    attempts.locator("select").select_option(index=0)  # choose it, then Bring back
    bring_back.click()
    message.get_by_text("Brought back attempt 1").wait_for(timeout=30_000)
    wait_for_demos(pad, n)
    tutor.screenshot(path=str(artifacts / "trainee_reset_3_brought_back.png"))
    assert f"demonstrations: {n}" in tutor.inner_text()
    assert f"({n} demonstration(s))" in message.inner_text()


# ---------------------------------------------------------------- axe-core


def test_axe_maze_tutor(maze_page, artifacts):
    maze_page.locator(".lfd-maze-tutor").first.wait_for(timeout=WIDGET_TIMEOUT_MS)
    maze_page.screenshot(path=str(artifacts / "trainee_axe_maze.png"))
    axe_check(maze_page, artifacts, "maze", [".lfd-start-form", ".lfd-maze-tutor"])


def test_axe_pickplace_tutor(pickplace_page, artifacts):
    page = pickplace_page
    _ensure_started(page, _form(page, "clicks"), artifacts)
    page.screenshot(path=str(artifacts / "trainee_axe_pickplace.png"))
    axe_check(page, artifacts, "pickplace", [".lfd-start-form", TUTOR])
