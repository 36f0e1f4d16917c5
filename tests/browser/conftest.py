"""Fixtures for browser tests: real servers on loopback and Debian's headless chromium.

Each server gets a free port on 127.0.0.1, a copy of the notebooks (so the browser's
autosave never writes outputs into the repository) and its own session folder.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

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


def start_notebook_kernel(url: str, token: str, path: str) -> str:
    """Start the kernel session of notebook ``path`` through the server's REST API.

    JupyterLab then attaches to this session when the notebook opens. Left to itself,
    opening a notebook can start two kernels at once and shut one down; cells run
    straight after may go to the one shut down and never execute. Returns the kernel id
    (the page's own execution indicator says when it is idle).
    """
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
    env["TUTOR_SESSION_DIR"] = str(root / "sessions")
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


@pytest.fixture(scope="module")
def voila(workdir):
    root, env = workdir
    env = {**env, "TUTOR_SESSION_DIR": str(root / "voila-sessions")}
    port = free_port()
    log = open(root / "voila.log", "w")  # noqa: SIM115
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "voila",
            str(root / "notebooks" / "02_maze_experiment.ipynb"),
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


@pytest.fixture
def page(browser, tmp_path):
    context = browser.new_context(viewport={"width": 1400, "height": 1000})
    pg = context.new_page()
    yield pg
    context.close()
