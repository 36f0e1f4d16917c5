"""Fixtures for browser tests: real servers on loopback and Debian's headless chromium.

Each server gets a free port on 127.0.0.1, a copy of the notebooks (so the browser's
autosave never writes outputs into the repository) and its own runs folder.
"""

from __future__ import annotations

import contextlib
import ipaddress
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path
from urllib.parse import urlparse

import pytest

REPO = Path(__file__).resolve().parents[2]
ARTIFACTS = REPO / "test-artifacts"
CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
CHROMIUM_FLAGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_http(url: str, proc: subprocess.Popen, timeout: float = 90.0) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"server exited early with code {proc.returncode}")
        try:
            with urllib.request.urlopen(url, timeout=2):
                return
        except OSError:
            time.sleep(0.3)
    raise TimeoutError(f"{url} did not answer within {timeout} s")


def start_notebook_kernel(url: str, token: str, path: str, fresh: bool = False) -> str:
    """Start the kernel session of notebook ``path`` through the server's REST API.

    JupyterLab then attaches to this session when the notebook opens. Left to itself,
    opening a notebook can start two kernels at once and shut one down; cells run
    straight after may go to the one shut down and never execute. Returns the kernel id
    (the page's own execution indicator says when it is idle). With ``fresh``, a session
    of ``path`` an earlier test left is shut down first, so the notebook runs in a new
    kernel.
    """
    if fresh:  # the server would hand back a session an earlier test left running
        with urllib.request.urlopen(f"{url}/api/sessions?token={token}", timeout=60) as r:
            earlier = [x["id"] for x in json.loads(r.read()) if x.get("path") == path]
        for session in earlier:
            gone = urllib.request.Request(
                f"{url}/api/sessions/{session}?token={token}", method="DELETE"
            )
            urllib.request.urlopen(gone, timeout=60).close()
    body = json.dumps(
        {"path": path, "type": "notebook", "name": path, "kernel": {"name": "python3"}}
    ).encode()
    request = urllib.request.Request(
        f"{url}/api/sessions?token={token}",
        data=body,
        method="POST",
        headers={"Content-Type": "application/json"},
    )
    with urllib.request.urlopen(request, timeout=60) as reply:
        return json.loads(reply.read())["kernel"]["id"]


def open_and_run_all(
    page, url: str, token: str, path: str, timeout_ms: float, workspace: str | None = None
) -> None:
    """Open notebook ``path`` in JupyterLab, wait until its kernel is idle, and run all its
    cells from the Run menu with the mouse. In a ``workspace`` of its own (a fresh one,
    reset), the notebook is the only one open: notebooks an earlier test opened are not
    restored beside it."""
    where = f"workspaces/{workspace}/" if workspace else ""
    reset = "&reset" if workspace else ""
    page.goto(f"{url}/lab/{where}tree/{path}?token={token}{reset}")
    page.locator(".jp-Notebook").wait_for(timeout=timeout_ms)
    page.locator(".jp-Notebook-ExecutionIndicator[data-status='idle']").wait_for(
        timeout=timeout_ms
    )
    page.get_by_role("menuitem", name="Run", exact=True).click()
    page.get_by_role("menuitem", name="Run All Cells", exact=True).click()


def session_kernel(url: str, token: str, path: str) -> str:
    """The kernel id notebook ``path``'s session has now (JupyterLab may have replaced the
    kernel :func:`start_notebook_kernel` started, e.g. after a "Select Kernel" question)."""
    with urllib.request.urlopen(f"{url}/api/sessions?token={token}", timeout=60) as reply:
        sessions = json.loads(reply.read())
    kernels = [s["kernel"]["id"] for s in sessions if s.get("path") == path and s.get("kernel")]
    assert kernels, f"no session of {path} is running"
    return kernels[-1]


def stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


@pytest.fixture(scope="session")
def artifacts() -> Path:
    ARTIFACTS.mkdir(exist_ok=True)
    return ARTIFACTS


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    root = tmp_path_factory.mktemp("browser")
    shutil.copytree(REPO / "notebooks", root / "notebooks")
    env = {k: v for k, v in os.environ.items() if k != "TUTOR_HEADLESS"}  # a person, not CI
    env["TUTOR_RUNS_DIR"] = str(root / "sessions")
    return root, env


@pytest.fixture(scope="module")
def jupyterlab(workdir):
    root, env = workdir
    port, token = free_port(), "lfd-tutor-test"
    log = open(root / "jupyterlab.log", "w")  # noqa: SIM115
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "jupyterlab",
            "--no-browser",
            "--ServerApp.ip=127.0.0.1",
            f"--port={port}",
            f"--ServerApp.token={token}",
            "--allow-root",
            f"--ServerApp.root_dir={root / 'notebooks'}",
            # a workspace of its own: tabs left open by another server are not restored
            f"--LabApp.workspaces_dir={root / 'workspaces'}",
        ],
        env=env,
        stdout=log,
        stderr=subprocess.STDOUT,
        cwd=root / "notebooks",
    )
    try:
        wait_http(f"http://127.0.0.1:{port}/api/status?token={token}", proc)
        yield f"http://127.0.0.1:{port}", token
    finally:
        stop(proc)
        log.close()


def voila_log(root: Path, notebook: str) -> Path:
    """The file :func:`voila_server` writes Voila's log to."""
    return root / f"voila-{Path(notebook).stem}.log"


#: a line of Jupyter server's request log for an answer of 400 or more, e.g.
#: ``403 POST /voila/api/shutdown/<id> (127.0.0.1) 11.93ms``
HTTP_ERROR_LINE = re.compile(
    r"^(?:\[[^\]]*\]\s*)?(?:\w+\s*\|\s*)?([45]\d\d) (GET|HEAD|POST|PUT|PATCH|DELETE|OPTIONS) \S+",
    re.MULTILINE,
)


def http_errors_in_log(text: str) -> list[str]:
    """The requests a server's log says it answered with 400 or more (one line each)."""
    return [m.group(0) for m in HTTP_ERROR_LINE.finditer(text)]


@contextlib.contextmanager
def voila_server(root: Path, env: dict, notebook: str):
    """Voila serving ``root/notebooks/<notebook>`` on a free loopback port; yields its URL."""
    port = free_port()
    log = open(voila_log(root, notebook), "w")  # noqa: SIM115
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "voila",
            str(root / "notebooks" / notebook),
            "--no-browser",
            f"--port={port}",
            "--Voila.ip=127.0.0.1",
        ],
        env=env,
        stdout=log,
        stderr=subprocess.STDOUT,
        cwd=root / "notebooks",
    )
    try:
        # a static file, not the page: a GET of the page would start a kernel that runs
        # the notebook and holds its runs' files until Voila culls it
        wait_http(f"http://127.0.0.1:{port}/voila/static/voila.js", proc, timeout=120)
        yield f"http://127.0.0.1:{port}"
    finally:
        stop(proc)
        log.close()


@pytest.fixture(scope="module")
def voila(workdir):
    root, env = workdir
    env = {**env, "TUTOR_RUNS_DIR": str(root / "voila-sessions")}
    with voila_server(root, env, "02_maze_experiment.ipynb") as url:
        yield url


def axe_check(page, artifacts: Path, name: str, include: list[str]) -> None:
    """Run axe-core on the parts ``include`` (CSS selectors) of ``page``; fail on serious
    or critical violations. The full results go to test-artifacts/axe_<name>.json."""
    from axe_playwright_python.sync_playwright import Axe

    context = {"include": [[s] for s in include]}
    options = {"resultTypes": ["violations", "incomplete"]}
    results = Axe().run(page, context=context, options=options).response
    (artifacts / f"axe_{name}.json").write_text(json.dumps(results, indent=2))
    assert results["passes"], "axe checked nothing"
    serious = [
        f"{v['id']} ({v['impact']}): {v['help']} at "
        + "; ".join(" ".join(node["target"]) for node in v["nodes"][:5])
        for v in results["violations"]
        if v["impact"] in ("serious", "critical")
    ]
    assert not serious, "\n".join(serious)


@pytest.fixture(scope="module")
def browser():
    if not Path(CHROMIUM).exists():
        pytest.fail(
            "Debian's chromium is missing: scripts/test.sh installs it (apt-get install chromium)"
        )
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_FLAGS, headless=True)
        yield b
        b.close()


#: Installs, once per viewer page, a record of every clip meshcat's animator loads:
#: ``[clip time, playing, duration, clips]`` right after the load. Reading the animator
#: from Playwright takes about a second per call while the software renderer draws, so
#: a 10 s clip can start and finish between two polls; the record in the page cannot
#: miss it. Evaluate it on the viewer iframe's body; it returns the clips so far.
RECORD_CLIPS = """() => {
  if (!window.__lfdClips) {
    window.__lfdClips = [];
    const animator = viewer.animator;
    const load = animator.load.bind(animator);
    animator.load = function (...args) {
      load(...args);
      window.__lfdClips.push([
        Math.max(0, ...this.actions.map((a) => a.time)),
        this.playing,
        this.duration,
        this.actions.length,
      ]);
    };
  }
  return window.__lfdClips.length;
}"""


def wait_clip(body, n: int, timeout: float = 30.0) -> list:
    """Wait until the viewer (iframe ``body``, recorded by RECORD_CLIPS) has loaded its
    ``n``-th clip and return what the animator held right after that load."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        clips = body.evaluate("() => window.__lfdClips")
        if len(clips) >= n:
            return clips[n - 1]
        time.sleep(0.05)
    raise AssertionError(f"the viewer loaded {len(clips)} clips within {timeout} s, not {n}")


#: console errors that are not the page's fault: the browser's own network log lines
#: (a resource the server answers 404, e.g. a missing favicon or an optional settings
#: file JupyterLab probes for). Page errors (uncaught exceptions) are never ignored.
BENIGN_CONSOLE = ("Failed to load resource",)


def watch_errors(pg) -> list[str]:
    """Collect ``pg``'s page errors and console errors (see :func:`fail_on_errors`).

    Tests that mean to cause a console error (e.g. a dead kernel's failed websocket) set
    ``pg.allowed_console_errors`` to a tuple of substrings to tolerate, and
    ``pg.allowed_page_errors`` likewise for the page's uncaught errors.
    """
    errors: list[str] = []
    pg.allowed_console_errors = ()
    pg.allowed_page_errors = ()

    def on_page_error(exc):
        if not any(s in str(exc) for s in pg.allowed_page_errors):
            errors.append(f"page error: {exc}\n{exc.stack or ''}")

    pg.on("pageerror", on_page_error)

    def on_console(msg):
        if msg.type != "error":
            return
        text = msg.text
        if any(s in text for s in BENIGN_CONSOLE + tuple(pg.allowed_console_errors)):
            return
        errors.append(f"console error: {text} ({msg.location.get('url', '')})")

    pg.on("console", on_console)
    return errors


def fail_on_errors(errors: list[str], name: str) -> None:
    """Fail (writing them to test-artifacts/page_errors_<name>.txt) if there were errors."""
    if errors:
        ARTIFACTS.mkdir(exist_ok=True)
        log = ARTIFACTS / f"page_errors_{name}.txt"
        log.write_text("\n\n".join(errors))
        pytest.fail(f"{len(errors)} page/console error(s) (see {log.name}): {errors[0][:500]}")


def accept_kernel_dialog(pg) -> None:
    """Whenever JupyterLab asks "Select Kernel" although the notebook's session has one
    (it does so now and then, more often on a loaded machine, and at any moment while the
    notebook opens), press Select, as a person would, before the test's next action."""
    dialog = pg.locator(".jp-Dialog", has_text="Select Kernel")

    def accept(_):
        # Playwright waits, after this handler, until no such dialog is visible. On a
        # loaded machine the dialog's button may not be there yet when the handler starts,
        # or JupyterLab asks a second time right after the first answer: keep answering
        # until no dialog is left (seen once on a loaded machine: the dialog stayed open for
        # 5 minutes after the handler's one try).
        from playwright.sync_api import Error as PlaywrightError

        deadline = time.monotonic() + 120
        while dialog.count() and time.monotonic() < deadline:
            try:
                dialog.first.get_by_role("button", name="Select", exact=True).click(timeout=5_000)
                dialog.first.wait_for(state="hidden", timeout=5_000)
            except PlaywrightError:
                pass  # not ready, or asked again: look again

    pg.add_locator_handler(dialog, accept)


def is_loopback(url: str) -> bool:
    """Whether ``url`` stays on this machine: a loopback host, or no host at all (data:,
    blob:, about:)."""
    parsed = urlparse(url)
    if parsed.scheme not in ("http", "https", "ws", "wss"):
        return True
    host = (parsed.hostname or "").strip("[]")
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def watch_network(pg) -> list[str]:
    """Collect what ``pg`` asks of the network that a page served offline must not: any
    request or websocket to a host off this machine (a CDN, say), any response of 400 or
    more (a 403 for a POST without the ``_xsrf`` token, a missing file), and any request
    that fails. Returns the growing list (see :func:`fail_on_errors`)."""
    problems: list[str] = []

    def on_request(req):
        if not is_loopback(req.url):
            problems.append(f"request off the machine: {req.method} {req.url}")

    def on_response(resp):
        if resp.status >= 400:
            problems.append(f"HTTP {resp.status}: {resp.request.method} {resp.url}")

    def on_failed(req):
        problems.append(f"request failed ({req.failure}): {req.method} {req.url}")

    def on_websocket(ws):
        if not is_loopback(ws.url):
            problems.append(f"websocket off the machine: {ws.url}")

    pg.on("request", on_request)
    pg.on("response", on_response)
    pg.on("requestfailed", on_failed)
    pg.on("websocket", on_websocket)
    return problems


@pytest.fixture
def voila_page(browser, request):
    """A fresh page for a Voila app: the test fails at teardown on any page or console
    error, and on any request off the machine, any HTTP error response and any failed
    request (:func:`watch_network`), as a workshop room with no internet would show."""
    context = browser.new_context(viewport={"width": 1400, "height": 1000})
    pg = context.new_page()
    errors = watch_errors(pg)
    network = watch_network(pg)
    yield pg
    seen = errors + network  # before closing: requests cut short by the close are not faults
    context.close()
    fail_on_errors(seen, request.node.name)


@pytest.fixture
def page(browser, tmp_path, request):
    """A fresh page; the test fails at teardown on any page error or console error.

    Tests that mean to cause a console error set ``pg.allowed_console_errors`` (see
    :func:`watch_errors`).
    """
    context = browser.new_context(viewport={"width": 1400, "height": 1000})
    pg = context.new_page()
    errors = watch_errors(pg)
    accept_kernel_dialog(pg)
    yield pg
    context.close()
    fail_on_errors(errors, request.node.name)
