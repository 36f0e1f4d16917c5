"""The package installs anywhere: build the wheel, install it non-editable, use it.

The wheel is built from a copy of the repository (building writes ``build/`` and
``*.egg-info`` into the source tree, and the checkout must stay clean), installed with
``pip install --target`` into a fresh folder, and then used by a Python started outside
the repository with only that folder on ``PYTHONPATH``: the venv gives the dependencies,
the folder gives ``tutor``. Nothing of the repository may be reachable, so a file read
from the repository's layout instead of the package fails here.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tomllib
import zipfile
from importlib import metadata
from importlib.util import find_spec
from pathlib import Path

import pytest
from packaging.requirements import Requirement

from tests.helpers import REPO

#: not copied for the build: version control, environments, caches, earlier builds
_NOT_SOURCE = (
    ".git",
    ".venv",
    "venv",
    "build",
    "dist",
    "*.egg-info",
    "__pycache__",
    ".ipynb_checkpoints",
    ".ruff_cache",
    ".pytest_cache",
    ".hypothesis",
    "test-artifacts",
    "sessions",
    "results",
)

#: files the wheel must carry besides the modules (paths inside the wheel)
_PACKAGE_DATA = (
    "tutor/assets/maze.json",
    "tutor/assets/pickplace.json",
    "tutor/assets/feasibility_map.npz",
    "tutor/assets/calibration/calibration_summary.json",
    "tutor/assets/calibration/calibration_report.txt",
    "tutor/assets/calibration/calibration_posterior.csv",
    "tutor/views/static/sketchpad.js",
)

# Run by the installed package's Python (with ``-c``, so the script's folder is not put
# on sys.path). Prints one JSON line with what it found.
_PROBE = r"""
import json, os, sys
from pathlib import Path

target = Path(os.environ["PROBE_TARGET"]).resolve()
repo = Path(os.environ["PROBE_REPO"]).resolve()
env_dirs = {Path(p).resolve() for p in (sys.prefix, sys.base_prefix, sys.exec_prefix)}


def inside(path, folder):
    return path == folder or folder in path.parents


# the venv may sit inside the repository (CI's .venv): its own folders are allowed
repo_on_path = [
    p for p in sys.path
    if inside(Path(p or ".").resolve(), repo)
    and not any(inside(Path(p or ".").resolve(), e) for e in env_dirs)
]

import numpy as np
from importlib.resources import files

import tutor
from tutor.demofiles import bundled_demos
from tutor.framework import TeachingSession
from tutor.resources import asset
from tutor.tasks.maze import MazeTask
from tutor.tasks.pickplace import PickPlaceTask

records = {}
maze = MazeTask()
good = bundled_demos("maze_good")
rec = TeachingSession(maze).add_demo(good[0])
records["maze"] = [len(good), rec.n_demos, rec.efficacy]

pick = PickPlaceTask()
corners = bundled_demos("pickplace_corners")
rec = TeachingSession(pick).add_demo(corners[0], point=corners.demo_points[0])
records["pickplace"] = [len(corners), rec.n_demos, rec.efficacy]

modules = {
    name: getattr(m, "__file__", None)
    for name, m in list(sys.modules.items())
    if name == "tutor" or name.startswith("tutor.")
}
print(json.dumps({
    "tutor_file": tutor.__file__,
    "target": str(target),
    "repo_on_path": repo_on_path,
    "outside_target": sorted(
        n for n, f in modules.items() if f and not inside(Path(f).resolve(), target)
    ),
    "n_modules": len(modules),
    "assets": str(asset("maze.json").resolve()),
    "static_js": str(Path(str(files("tutor.views") / "static" / "sketchpad.js")).resolve()),
    "records": records,
}))
"""


def _setuptools_meets(requires: list[str]) -> bool:
    """Whether this environment's setuptools satisfies the build-system requirement."""
    for text in requires:
        req = Requirement(text)
        if req.name == "setuptools":
            try:
                return req.specifier.contains(metadata.version("setuptools"), prereleases=True)
            except metadata.PackageNotFoundError:
                return False
    return True


def _build_command(source: Path, outdir: Path) -> list[str]:
    """Build with ``build`` (or ``pip wheel``), offline when the venv's setuptools is new
    enough; otherwise isolated (pip fetches the build requirement from its index)."""
    requires = tomllib.loads((source / "pyproject.toml").read_text())["build-system"]["requires"]
    offline = _setuptools_meets(requires)
    if find_spec("build") is not None:
        cmd = [sys.executable, "-m", "build", "--wheel", "--outdir", str(outdir)]
        return [*cmd, *(["--no-isolation"] if offline else []), str(source)]
    cmd = [sys.executable, "-m", "pip", "wheel", "--no-deps", "-w", str(outdir)]
    return [*cmd, *(["--no-build-isolation"] if offline else []), str(source)]


def _run(cmd, **kwargs) -> subprocess.CompletedProcess:
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600, **kwargs)
    assert proc.returncode == 0, (
        f"{' '.join(map(str, cmd))} failed ({proc.returncode}):\n{proc.stdout[-3000:]}\n"
        f"{proc.stderr[-3000:]}"
    )
    return proc


def _build_artefacts(folder: Path) -> set[str]:
    return {p.name for p in folder.iterdir() if p.name in ("build", "dist")} | {
        p.name for p in folder.glob("*.egg-info")
    }


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(wheel, target, environment) for the package installed from a freshly built wheel."""
    base = tmp_path_factory.mktemp("wheel")
    before = _build_artefacts(REPO)
    source = base / "source"
    shutil.copytree(REPO, source, ignore=shutil.ignore_patterns(*_NOT_SOURCE))
    _run(_build_command(source, base / "dist"), cwd=base)
    assert _build_artefacts(REPO) == before, "building left files in the checkout"
    wheels = sorted((base / "dist").glob("lfd_tutor-*.whl"))
    assert len(wheels) == 1, f"expected one lfd_tutor wheel, found {wheels}"
    target = base / "target"
    _run([sys.executable, "-m", "pip", "install", "--no-deps", "--target", str(target), wheels[0]])
    env = {
        key: value
        for key, value in os.environ.items()
        if key not in ("PYTHONPATH", "PYTHONHOME", "PYTHONSTARTUP", "PYTHONSAFEPATH")
    }
    env.update(PYTHONPATH=str(target), MPLBACKEND="Agg", TUTOR_HEADLESS="1")
    workdir = base / "elsewhere"
    workdir.mkdir()
    return wheels[0], target, env, workdir


def test_wheel_carries_the_package_data(installed):
    wheel = installed[0]
    names = set(zipfile.ZipFile(wheel).namelist())
    missing = [n for n in _PACKAGE_DATA if n not in names]
    assert not missing, f"{wheel.name} lacks {missing}"
    bundled = sorted(p.name for p in (REPO / "tutor" / "assets" / "demos").glob("*.json"))
    in_wheel = sorted(
        Path(n).name for n in names if n.startswith("tutor/assets/demos/") and n.endswith(".json")
    )
    assert bundled and in_wheel == bundled
    # Voila's page for the tutor's notebooks, as data files installed under share/jupyter
    template = "share/jupyter/voila/templates/lfd-tutor"
    shipped = sorted(p.name for p in (REPO / template).iterdir())
    in_data = sorted(Path(n).name for n in names if f".data/data/{template}/" in n)
    assert shipped and in_data == shipped, (in_data, shipped)
    scripts = [n for n in names if n.endswith("entry_points.txt")]
    assert scripts, "the wheel has no entry_points.txt"
    entry_points = zipfile.ZipFile(wheel).read(scripts[0]).decode()
    assert "lfd-tutor = tutor.__main__:run" in entry_points


def test_installed_package_teaches_both_tasks(installed):
    _, target, env, workdir = installed
    env = {**env, "PROBE_TARGET": str(target), "PROBE_REPO": str(REPO)}
    proc = _run([sys.executable, "-c", _PROBE], cwd=workdir, env=env)
    found = json.loads(proc.stdout.strip().splitlines()[-1])
    target = target.resolve()
    assert Path(found["tutor_file"]).resolve() == target / "tutor" / "__init__.py"
    assert found["repo_on_path"] == [], "the repository is reachable on sys.path"
    assert found["n_modules"] > 5 and found["outside_target"] == []
    assert Path(found["assets"]).is_relative_to(target)
    assert Path(found["static_js"]).is_relative_to(target)
    for task, (n_set, n_demos, efficacy) in found["records"].items():
        assert n_set >= 3, f"the bundled {task} set has only {n_set} demos"
        assert n_demos == 1
        assert 0.0 <= efficacy <= 1.0


def test_console_script_reproduces_an_experiment(installed):
    _, target, env, workdir = installed
    script = target / "bin" / "lfd-tutor"
    assert script.is_file() and os.access(script, os.X_OK)
    out = workdir / "results"
    cmd = [script, "reproduce", "--experiment", "1", "--n", "6", "--out", out]
    _run([*map(str, cmd), "--no-figures", "--no-progress"], cwd=workdir, env=env)
    summary = json.loads((out / "experiment1_summary.json").read_text())
    assert summary["experiment"] == 1 and summary["n_teachers"] == 6
    runs = (out / "experiment1_runs.csv").read_text().splitlines()
    assert runs[0].startswith("teacher,condition,")
    assert len(runs) == 1 + 6 * 3  # a header, then each teacher under NF, VF and VR
    assert not list(out.glob("*.png"))
