"""Checks on the project scaffold: packaging metadata, notebooks, the lab launcher."""

from __future__ import annotations

import ipaddress
import json
import os
import re
import secrets
import signal
import socket
import subprocess
import sys
import time
import tomllib
import urllib.error
import urllib.request
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]

# PyPI name (as in pyproject.toml) -> conda-forge name (as in environment.yml).
# Names not listed are the same on both.
CONDA_NAME = {
    "pin": "pinocchio",
    "meshcat": "meshcat-python",
    "example-robot-data-loaders": "example-robot-data",
    "build": "python-build",
}
# Not on conda-forge: environment.yml installs these in its `pip:` section.
PIP_ONLY = {"gmr", "axe-playwright-python"}
# Entries environment.yml may hold besides the dependencies above.
ENV_INFRASTRUCTURE = {"python", "pip"}
SELF_INSTALL = {"-e .", "."}

_NAME = re.compile(r"^\s*([A-Za-z0-9][A-Za-z0-9._-]*)")


def _name(spec: str) -> str:
    """Normalised project name of a requirement ('NumPy>=1.2' -> 'numpy')."""
    match = _NAME.match(spec)
    assert match, f"cannot read a package name from {spec!r}"
    return re.sub(r"[-_.]+", "-", match.group(1)).lower()


def _pyproject_deps(*extras: str) -> set[str]:
    """Names of the runtime dependencies and those of ``extras`` (default: notebooks, test)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    optional = project["optional-dependencies"]
    specs = list(project["dependencies"])
    for extra in extras or ("notebooks", "test"):
        specs += optional[extra]
    return {_name(s) for s in specs}


def _environment(path: Path = ROOT / "environment.yml") -> tuple[dict, set, set, list[str]]:
    env = yaml.safe_load(path.read_text())
    conda, pip, self_install = set(), set(), []
    for entry in env["dependencies"]:
        if isinstance(entry, dict):
            assert set(entry) == {"pip"}, f"unexpected section in environment.yml: {entry}"
            for spec in entry["pip"]:
                if spec.strip() in SELF_INSTALL:
                    self_install.append(spec.strip())
                else:
                    pip.add(_name(spec))
        else:
            conda.add(_name(entry))
    return env, conda, pip, self_install


def test_environment_yml_matches_pyproject():
    env, conda, pip, self_install = _environment()
    assert env["name"] == "lfd-tutor"
    assert env["channels"] == ["conda-forge"]
    assert "python=3.11" in env["dependencies"]
    assert ENV_INFRASTRUCTURE <= conda, "environment.yml must list python and pip"
    assert len(self_install) == 1, "environment.yml must pip-install the package itself once"

    wanted = {CONDA_NAME.get(n, n) for n in _pyproject_deps()}
    listed = (conda - ENV_INFRASTRUCTURE) | pip
    missing, extra = sorted(wanted - listed), sorted(listed - wanted)
    assert not missing, f"in pyproject.toml but missing from environment.yml: {missing}"
    assert not extra, f"in environment.yml but not in pyproject.toml: {extra}"
    assert pip == {CONDA_NAME.get(n, n) for n in PIP_ONLY}, (
        f"environment.yml pip: section should hold exactly {sorted(PIP_ONLY)}, not {sorted(pip)}"
    )
    assert not conda & pip, f"listed both for conda and pip: {sorted(conda & pip)}"


def test_binder_environment_is_runtime_and_notebooks_only():
    """binder/ (repo2docker): runtime + notebooks dependencies exactly, no test tools."""
    env, conda, pip, self_install = _environment(ROOT / "binder" / "environment.yml")
    assert env["channels"] == ["conda-forge"]
    assert "python=3.11" in env["dependencies"]
    assert ENV_INFRASTRUCTURE <= conda, "binder/environment.yml must list python and pip"
    assert not self_install, (
        "binder/environment.yml must not install the package (binder/postBuild does, "
        "non-editable, so the environment is not rebuilt on every commit)"
    )
    wanted = {CONDA_NAME.get(n, n) for n in _pyproject_deps("notebooks")}
    listed = (conda - ENV_INFRASTRUCTURE) | pip
    test_only = {CONDA_NAME.get(n, n) for n in _pyproject_deps("test")} - wanted
    assert not listed & test_only, f"test tools in binder/environment.yml: {listed & test_only}"
    missing, extra = sorted(wanted - listed), sorted(listed - wanted)
    assert not missing, f"runtime/notebooks dependencies missing from binder/: {missing}"
    assert not extra, f"in binder/environment.yml but not runtime/notebooks: {extra}"


def _pip_installs(script: str) -> list[list[str]]:
    """The arguments of every ``pip install`` command in a shell script."""
    found = []
    for line in script.splitlines():
        words = line.split("#", 1)[0].split()
        for k in range(len(words) - 1):
            if words[k].endswith("pip") and words[k + 1] == "install":
                found.append(words[k + 2 :])
    return found


def test_binder_postbuild_installs_the_package_non_editable():
    path = ROOT / "binder" / "postBuild"
    assert path.is_file(), "binder/postBuild is missing"
    assert os.stat(path).st_mode & 0o111, "binder/postBuild must be executable (chmod +x)"
    script = path.read_text()
    assert script.startswith("#!"), "binder/postBuild needs a #! line (e.g. #!/usr/bin/env bash)"
    installs = _pip_installs(script)
    assert len(installs) == 1, f"binder/postBuild should run one pip install, found {installs}"
    (args,) = installs
    assert "--no-deps" in args, "postBuild's pip install needs --no-deps (conda installs them)"
    assert "." in args, f"postBuild must pip install the package itself (.), got {args}"
    assert not {"-e", "--editable"} & set(args), "postBuild must install non-editable"
    overrides = re.findall(r"\bcp\s+(\S+)", script)
    assert all((ROOT / src).is_file() for src in overrides), f"postBuild copies {overrides}"


NOTEBOOKS = sorted(
    p for p in (ROOT / "notebooks").rglob("*.ipynb") if ".ipynb_checkpoints" not in p.parts
)


def test_there_are_notebooks():
    assert NOTEBOOKS, "no notebooks found under notebooks/"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_is_stripped(path: Path):
    nb = json.loads(path.read_text(encoding="utf-8"))
    problems = []
    if "widgets" in nb.get("metadata", {}):
        problems.append("notebook metadata holds widget state")
    for i, cell in enumerate(nb["cells"]):
        if "widgets" in cell.get("metadata", {}):
            problems.append(f"cell {i}: widget state in metadata")
        if cell["cell_type"] != "code":
            continue
        if cell.get("outputs"):
            problems.append(f"cell {i}: has outputs")
        if cell.get("execution_count") is not None:
            problems.append(f"cell {i}: execution_count is {cell['execution_count']}")
    assert not problems, (
        f"{path.relative_to(ROOT)} is not stripped (clear all outputs, or run "
        f"`jupyter nbconvert --clear-output --inplace`): " + "; ".join(problems)
    )


# --- the lab launcher -------------------------------------------------------------

LAB_TIMEOUT = 60.0  # seconds for the whole start / check / stop cycle
TCP_LISTEN = "0A"


def _free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _hex_address(hex_ip: str) -> ipaddress.IPv4Address | ipaddress.IPv6Address:
    """Address in /proc/net/tcp{,6} notation: 32-bit words in host (little-endian) order."""
    raw = bytes.fromhex(hex_ip)
    if sys.byteorder == "little":
        raw = b"".join(raw[i : i + 4][::-1] for i in range(0, len(raw), 4))
    return ipaddress.ip_address(raw)


def _listening_addresses(port: int) -> list[ipaddress.IPv4Address | ipaddress.IPv6Address]:
    found = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            lines = Path(table).read_text().splitlines()[1:]
        except FileNotFoundError:  # e.g. IPv6 disabled
            continue
        for line in lines:
            fields = line.split()
            local, state = fields[1], fields[3]
            hex_ip, hex_port = local.split(":")
            if state == TCP_LISTEN and int(hex_port, 16) == port:
                found.append(_hex_address(hex_ip))
    return found


def _answers(url: str) -> bool:
    try:
        with urllib.request.urlopen(url, timeout=2) as response:
            return response.status == 200
    except (urllib.error.URLError, OSError):
        return False


def _stop(proc: subprocess.Popen, timeout: float) -> None:
    if proc.poll() is not None:
        return
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(timeout=10)


@pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="needs Linux /proc/net/tcp")
def test_lab_listens_on_loopback_only(tmp_path: Path):
    if sys.prefix == sys.base_prefix:
        pytest.skip("run the tests inside the project's virtualenv (bash scripts/test.sh)")
    port = _free_port()
    token = secrets.token_hex(16)
    env = dict(os.environ, TUTOR_VENV=sys.prefix, JUPYTER_RUNTIME_DIR=str(tmp_path / "runtime"))
    log_path = tmp_path / "lab.log"
    deadline = time.monotonic() + LAB_TIMEOUT
    with open(log_path, "wb") as log:
        proc = subprocess.Popen(
            [
                "bash",
                str(ROOT / "scripts" / "lab.sh"),
                "--no-browser",
                "--port",
                str(port),
                f"--ServerApp.token={token}",
            ],
            cwd=tmp_path,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,  # own process group, so it can be killed as a whole
        )
    try:
        url = f"http://127.0.0.1:{port}/api/status?token={token}"
        while not _answers(url):
            if proc.poll() is not None:
                pytest.fail(
                    f"lab.sh exited with {proc.returncode} before answering:\n"
                    + log_path.read_text(errors="replace")
                )
            if time.monotonic() > deadline - 15:  # keep time to stop it
                pytest.fail(
                    f"JupyterLab did not answer on 127.0.0.1:{port} in time:\n"
                    + log_path.read_text(errors="replace")
                )
            time.sleep(0.25)

        addresses = _listening_addresses(port)
        assert addresses, f"no LISTEN socket on port {port} in /proc/net/tcp{{,6}}"
        loopback = ipaddress.ip_address("127.0.0.1")
        for address in addresses:
            mapped = getattr(address, "ipv4_mapped", None)
            assert address == loopback or mapped == loopback, (
                f"JupyterLab listens on {address}:{port}; it must bind to 127.0.0.1 only"
            )
    finally:
        _stop(proc, timeout=max(5.0, deadline - time.monotonic()))
    # stopping lab.sh stops JupyterLab with it: nothing is left listening on the port
    gone_by = time.monotonic() + 10
    while _listening_addresses(port) and time.monotonic() < gone_by:
        time.sleep(0.25)
    assert not _listening_addresses(port), f"JupyterLab still listens on port {port} after stop"


def test_paper_numbers_agree_with_their_copies():
    """The set-up values the tasks, the teachers and the study hold are tutor.paper's."""
    from tutor import paper
    from tutor.framework.protocol import EXPERIMENTS
    from tutor.tasks.maze import load_layout
    from tutor.tasks.maze_rules import RULE_RADIUS
    from tutor.tasks.pickplace import load_scene
    from tutor.teachers.maze import RATE_HZ

    layout = load_layout()
    for box, size in [
        (layout.workspace, paper.MAZE_WORKSPACE_SIZE),
        (layout.start_zone, paper.MAZE_START_ZONE_SIZE),
    ]:
        assert (box.x1 - box.x0, box.y1 - box.y0) == pytest.approx(size)
    assert layout.target_diameter == pytest.approx(paper.MAZE_TARGET_DIAMETER)
    assert layout.grid_shape == paper.MAZE_GRID_SHAPE
    assert layout.n_components == paper.MAZE_N_COMPONENTS
    assert RULE_RADIUS == paper.MAZE_RULE_RADIUS
    assert RATE_HZ == paper.MAZE_TRACKER_HZ

    scene = load_scene()
    assert scene.rows * scene.cols == paper.PICKPLACE_N_PLANTS
    assert len(scene.generalisation_indices) == paper.PICKPLACE_N_GENERALISATION_SAMPLES
    assert scene.realisation_seconds == paper.PICKPLACE_REALISATION_SECONDS
    assert scene.run_seconds == paper.PICKPLACE_RUN_SECONDS

    assert EXPERIMENTS[1].paper_codes == paper.MAZE_CONDITIONS
    assert EXPERIMENTS[1].n_teachers == paper.EXPERIMENT_1["n"] == paper.MAZE_N_TEACHERS
    assert EXPERIMENTS[2].paper_codes == paper.PICKPLACE_CONDITIONS
    assert EXPERIMENTS[2].n_teachers == paper.EXPERIMENT_2["n"] == paper.PICKPLACE_N_TEACHERS
    assert EXPERIMENTS[2].runs == paper.PICKPLACE_N_RUNS
    # the paper's "about 180 %", "about 169 %" and "about 220 %"
    assert paper.EXPERIMENT_1["relative"]["VF/NF"] == pytest.approx(1.8, abs=0.05)
    assert paper.EXPERIMENT_2["relative"]["mean"] == pytest.approx(1.69, abs=0.01)
    assert paper.EXPERIMENT_2["relative"]["third run"] == pytest.approx(2.2, abs=0.01)


def test_imports_keep_the_layers():
    """lint-imports holds pyproject.toml's layers contract (CLI > study > ... > tpgmm)."""
    lint_imports = Path(sys.executable).with_name("lint-imports")
    assert lint_imports.exists(), "import-linter is a test dependency: pip install -e .[test]"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run(
        [str(lint_imports), "--no-logo", "--no-cache"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "1 kept, 0 broken" in proc.stdout
