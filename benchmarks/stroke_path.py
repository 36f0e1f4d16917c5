"""Which of the tutor's modules one maze stroke passes on its way to the panel.

A maze tutor in each condition takes one demonstration, then a second stroke arrives as
the page sends it (the sketchpad's ``stroke`` and ``stroke_count``). While the tutor
handles that stroke, a profiler (``sys.setprofile``) records two things:

chain
    The deepest call chain from the stroke's event to any function: the distinct
    ``tutor`` modules on the call stack, outermost first. This is the path the stroke
    travels *through* (each module hands it, or what was made of it, to the next).
data
    Every ``tutor`` module with a function that receives the stroke, or a value a
    function made from it (the demo, its record, the demo step, the causes...),
    in the order first reached. This counts the modules it merely touches too: the
    learner's maths, the record that stores it, the words.

``tutor.tpgmm`` counts as one module. Also reported: how often the page's stroke is
preprocessed (``preprocess``) and the VR rule's advice computed (``advise_from``, the
rule itself; the run's ``advice()`` only hands back what it computed for the latest
demo). Each should run once.

Run:  .venv/bin/python benchmarks/stroke_path.py [--out PATH]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

import numpy as np
from results_file import RESULTS, save

DEFAULT_OUT = RESULTS / "stroke_path.json"
CONDITIONS = ("NF", "VF", "VR", "VA")


def _module(frame) -> str:
    name = frame.f_globals.get("__name__", "")
    return "tutor.tpgmm" if name.startswith("tutor.tpgmm") else name


def trace(condition: str) -> dict:
    """The chain, the data path and the repeated work for one stroke in ``condition``."""
    from tutor.demofiles import bundled_demos
    from tutor.views.maze_app import MazeTutor

    demos = list(bundled_demos("maze_incorrect"))
    tutor = MazeTutor(condition, trainee=f"stroke-path-{condition.lower()}")
    tutor.add(np.asarray(demos[0]))
    points = [[float(v) for v in row] for row in np.asarray(demos[1])]
    tutor.pad.stroke = points

    tracked, keep = {id(points)}, [points]
    data_path, chain, carrying = [], [], set()
    calls = {"preprocess": 0, "advise_from": 0}

    def is_tracked(value, depth=0) -> bool:
        if id(value) in tracked:
            return True
        if depth < 1 and isinstance(value, (list, tuple)) and len(value) < 100:
            return any(is_tracked(v, depth + 1) for v in value)
        return False

    def profile(frame, event, arg):
        name = _module(frame)
        if not name.startswith("tutor"):
            return
        if event == "call":
            code = frame.f_code
            if code.co_name in calls:
                calls[code.co_name] += 1
            stack, f = [], frame
            while f is not None:
                m = _module(f)
                if m.startswith("tutor") and (not stack or stack[-1] != m):
                    stack.append(m)
                f = f.f_back
            stack.reverse()
            if len(dict.fromkeys(stack)) > len(dict.fromkeys(chain)):
                chain[:] = stack
            args = [
                frame.f_locals[n]
                for n in code.co_varnames[: code.co_argcount]
                if n in frame.f_locals and n != "self"
            ]
            if any(is_tracked(a) for a in args):
                carrying.add(id(frame))
                if name not in data_path:
                    data_path.append(name)
        elif event == "return" and id(frame) in carrying:
            carrying.discard(id(frame))
            if arg is not None:
                tracked.add(id(arg))
                keep.append(arg)

    sys.setprofile(profile)
    try:
        tutor.pad.stroke_count = tutor.pad.stroke_count + 1
    finally:
        sys.setprofile(None)
    if tutor.session.n_demos != 2:
        raise RuntimeError(f"the stroke was not taken in {condition}: {tutor.message}")
    chain = list(dict.fromkeys(chain))
    return {"chain": chain, "data": data_path, "calls": calls}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = parser.parse_args(argv)
    os.environ["TUTOR_HEADLESS"] = "1"
    os.environ["TUTOR_RUNS_DIR"] = tempfile.mkdtemp(prefix="stroke-path-")
    result = {}
    for condition in CONDITIONS:
        r = result[condition] = trace(condition)
        print(
            f"{condition}: chain {len(r['chain'])} modules, data reaches {len(r['data'])}; "
            f"preprocess x{r['calls']['preprocess']}, rule advice x{r['calls']['advise_from']}"
        )
        print("   chain:", " > ".join(m.removeprefix("tutor.") for m in r["chain"]))
        print("   data: ", ", ".join(m.removeprefix("tutor.") for m in r["data"]))
    save(result, args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
