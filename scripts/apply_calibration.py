"""Put a calibration's point into the bundled population and maze.

``lfd-tutor calibrate --out DIR`` writes the posterior; this script takes its point
(:meth:`Calibration.bundled`: the particle refine chose) and writes it
where the tutor reads its defaults:

- the maze's two blocks and guide points into ``tutor/assets/maze.json``;
- the population's fitted fields into the defaults of ``Population`` in
  ``tutor/teachers/traits.py`` (the lines ``name: float = value``);
- the calibration's files (without pyabc's history database) into
  ``tutor/assets/calibration``, which notebook 04 and ``calibration.load()`` read.

``tests/test_calibration.py`` checks that the bundled population and maze are the
bundled calibration's point. Everything downstream (the optimal teacher, the demo sets,
the cohorts, the robustness files, the adaptive study) is then regenerated with its own
command (README, "Calibrating the simulated teachers").

Run:  .venv/bin/python scripts/apply_calibration.py DIR
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import re
import shutil
from pathlib import Path

from tutor.study import calibration
from tutor.tasks.maze import load_layout
from tutor.teachers.traits import DEFAULT_POPULATION

ROOT = Path(__file__).resolve().parents[1]
FILES = ("calibration_posterior.csv", "calibration_generations.csv",
         "calibration_predictive.csv", "calibration_point_predictive.csv",
         "calibration_refined.csv", "calibration_report.txt", "calibration_summary.json")


def _number(v) -> str:
    return repr(round(float(v), 4)) if isinstance(v, float) else repr(v)


def _flat(value) -> bool:
    """Whether ``value`` is written on one line: numbers, strings, and lists or dicts of
    those (a box, a point, a list of points), as the file was written by hand."""
    if isinstance(value, dict):
        return all(_flat(v) and not isinstance(v, dict) for v in value.values())
    if isinstance(value, list):
        return all(_flat(v) and not isinstance(v, dict) for v in value)
    return True


def _compact_json(value, indent: str = "") -> str:
    if _flat(value):
        return json.dumps(value)
    inner = indent + "  "
    if isinstance(value, list):
        items = [inner + _compact_json(v, inner) for v in value]
        return "[\n" + ",\n".join(items) + "\n" + indent + "]"
    items = [f"{inner}{json.dumps(k)}: {_compact_json(v, inner)}" for k, v in value.items()]
    return "{\n" + ",\n".join(items) + "\n" + indent + "}"


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", help="a folder lfd-tutor calibrate --out wrote")
    args = parser.parse_args(argv)
    folder = Path(args.folder)
    found, _, _ = calibration.load(folder)
    point = {k: round(v, 4) for k, v in found.bundled().items()}
    population, _ = calibration.apply(point)

    # the maze: blocks (to the millimetre) and guide points of the calibrated geometry
    layout = load_layout().with_blocks(*calibration.bundled_blocks(point))
    maze_path = ROOT / "tutor" / "assets" / "maze.json"
    data = json.loads(maze_path.read_text(encoding="utf-8"))
    for entry, box in zip(data["obstacles"], layout.obstacles, strict=True):
        entry["x"] = [round(box.x0, 6), round(box.x1, 6)]
        entry["y"] = [round(box.y0, 6), round(box.y1, 6)]
    data["guide_points"] = [[round(float(v), 6) for v in p] for p in layout.guide_points]
    maze_path.write_text(_compact_json(data) + "\n", encoding="utf-8")

    # the population: the fields the calibration changed
    traits_path = ROOT / "tutor" / "teachers" / "traits.py"
    source = traits_path.read_text(encoding="utf-8")
    changed = {
        f.name: getattr(population, f.name) for f in dataclasses.fields(population)
        if getattr(population, f.name) != getattr(DEFAULT_POPULATION, f.name)
    }
    for name, value in changed.items():
        pattern = re.compile(rf"^(    {name}: \w+ = )(.+)$", re.MULTILINE)
        if not pattern.search(source):
            raise SystemExit(f"no default line for {name} in {traits_path}")
        source = pattern.sub(lambda m, v=value: m.group(1) + _number(v), source, count=1)
    traits_path.write_text(source, encoding="utf-8")

    bundled = ROOT / "tutor" / "assets" / "calibration"
    bundled.mkdir(exist_ok=True)
    for name in FILES:
        shutil.copyfile(folder / name, bundled / name)
    print(f"maze blocks: {layout.blocks}")
    print(f"population fields changed: {changed}")
    print(f"calibration files copied to {bundled}")


if __name__ == "__main__":
    main()
