"""The adaptive-feedback study (``lfd-tutor adaptive``): end to end on the quick plan,
common random numbers, the paired statistics, and refusals before any work."""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from tutor.errors import InvalidParameterError
from tutor.study import adaptive_stats as st
from tutor.study.adaptive import (
    POLICIES,
    QUICK,
    SETTINGS,
    StudyPlan,
    _Checkpoint,
    available_policies,
    check_plan,
    run_study,
    teach_policy,
)
from tutor.study.adaptive_report import load_study, paper_bf_undemonstrated_per_run
from tutor.study.cohort import simulate_teacher, teacher_rng
from tutor.teachers.pickplace import PickPlaceTeacher
from tutor.teachers.traits import DEFAULT_POPULATION

ROOT = Path(__file__).resolve().parents[1]
FILES = ("runs.csv", "curves.csv", "plan.json", "summary.json", "report.txt", "figure.png")


def _tutor(*args: str, cwd: Path, timeout: float = 60) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    return subprocess.run(
        [sys.executable, "-m", "tutor", "adaptive", *args],
        cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout,
    )


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("adaptive") / "results"
    proc = _tutor("--quick", "--no-progress", "--out", str(out), cwd=out.parent, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return out, proc.stdout


def test_quick_run_writes_every_file(quick):
    out, stdout = quick
    for name in FILES:
        path = out / f"adaptive_{name}"
        assert path.is_file() and path.stat().st_size > 0, name
    assert (out / "adaptive_figure.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    summary = json.loads((out / "adaptive_summary.json").read_text())
    arms = available_policies()
    assert list(summary["headline"]) == list(arms)
    assert summary["plan"]["quick"] is True
    for name in arms:
        assert f"\n{name} " in stdout  # a row in the per-policy table
    assert "QUICK" in stdout and "Claims" in stdout and "Caveats" in stdout
    # every claim is stated with a CI over the seeds
    claims = [line for line in stdout.splitlines() if line.startswith("- ")]
    assert len(claims) == len(arms) - 1
    assert all("95 % CI [" in c and "seeds" in c for c in claims)


def test_quick_runs_have_every_measure_and_curves_end_each_run(quick):
    result = load_study(quick[0])
    runs, curves = result.runs, result.curves
    plan = result.plan
    main = result.main
    assert set(main.policy) == set(plan.policies)
    assert (main.groupby("policy").size().drop([p for p in plan.policies if "HF" in p])
            == plan.n * plan.seeds * plan.runs).all()
    for column in (*st.MEASURES, "eta", "eta_target", "robot_seconds", "seconds"):
        assert runs[column].notna().all(), column
    # a demo and the robot's attempts end by 15:00; the set-up before a demo that then
    # does not fit may run past it (the teacher had started it)
    assert (runs.seconds <= 900 + runs.trait_setup_seconds + 1e-6).all()
    assert runs.efficacy.between(0, 1).all()
    # BF shows 5 plants a demo: at least 125 robot seconds a demo kept
    bf = main[main.policy == "BF"]
    assert (bf.robot_seconds >= 125 * bf.n_demos).all()
    ends = curves[curves.event == "end"].merge(
        runs, on=["variant", "seed", "teacher", "policy", "run"], suffixes=("", "_run")
    )
    assert len(ends) == len(runs)
    assert np.allclose(ends.efficacy, ends.efficacy_run)
    assert np.allclose(ends.seconds, ends.seconds_run)
    # the clock only moves forward within a run
    for _, c in curves.groupby(["variant", "seed", "teacher", "policy", "run"]):
        assert (np.diff(c.seconds.to_numpy()) >= -1e-9).all()


def test_same_traits_in_every_policy(quick):
    runs = load_study(quick[0]).runs
    traits = [c for c in runs.columns if c.startswith("trait_") and c != "trait_compliance"]
    per_teacher = runs.groupby(["variant", "seed", "teacher"])[traits].nunique()
    assert (per_teacher == 1).all().all()
    hinted = runs[runs.policy.isin(["HF0.5", "HF1"])]
    for name, group in hinted.groupby("policy"):
        assert (group.trait_compliance == POLICIES[name].compliance).all()


def test_bf_arm_is_the_cohorts_bf_teacher():
    """Teacher 18 of a 36-teacher cohort is in BF: the study's BF arm gives their runs."""
    rows, _ = teach_policy("BF", 0, 18, runs=2)
    cohort, _ = simulate_teacher(2, 18, 0, 36)
    assert [r["condition"] for r in cohort] == ["BF"] * 3
    for mine, theirs in zip(rows, cohort[:2], strict=True):
        for key, value in theirs.items():
            assert mine[key] == value or (pd.isna(value) and pd.isna(mine[key])), key


def test_traced_af_run_is_the_teachers_own_run():
    """The study's traced run is made as PickPlaceTeacher.teach makes its own (the random
    selector's generator spawned from the run's), so tracing changes no number."""
    rows, curve = teach_policy("RAND2", 3, 5, runs=1)
    traits = DEFAULT_POPULATION.sample(teacher_rng(3, 2, 5, 0))
    run = PickPlaceTeacher(traits).teach("AF", teacher_rng(3, 2, 5, 1), selector="random", k=2)
    assert rows[0]["efficacy"] == run.session.latest.efficacy
    assert rows[0]["n_demos"] == run.session.n_demos
    assert rows[0]["seconds"] == pytest.approx(run.elapsed)
    shown = [d.shown for d in run.attempt.demos]
    assert sum(map(len, shown)) * 25.0 <= rows[0]["robot_seconds"]
    demos = [c for c in curve if c["event"] == "demo"]
    assert len(demos) == run.session.n_demos + len(run.attempt.undone)


def test_policy_traits_change_only_compliance():
    traits = DEFAULT_POPULATION.sample(teacher_rng(0, 2, 0, 0))
    assert POLICIES["BF"].traits(traits) is traits
    if "compliance" in {f.name for f in dataclasses.fields(traits)}:
        hinted = POLICIES["HF0.5"].traits(traits)
        assert hinted.compliance == 0.5
        assert dataclasses.replace(hinted, compliance=traits.compliance) == traits


def test_check_plan_refuses_bad_plans():
    with pytest.raises(InvalidParameterError, match="from 36 to 60"):
        check_plan(StudyPlan(n=20))
    with pytest.raises(InvalidParameterError, match="must include BF"):
        check_plan(StudyPlan(policies=("KC2", "DIS2")))
    with pytest.raises(InvalidParameterError, match="distinct names"):
        check_plan(StudyPlan(policies=("BF", "KC7")))
    with pytest.raises(InvalidParameterError, match="seeds"):
        check_plan(StudyPlan(seeds=1))
    assert check_plan(QUICK).n == 4


@pytest.mark.parametrize(
    "args, words",
    [
        (("--n", "20"), ("InvalidParameterError", "from 36 to 60")),
        (("--quick", "--n", "40"), ("InvalidParameterError", "--quick fixes the size")),
        (("--seeds", "1"), ("--seeds", ">= 2")),
        (("--workers", "0"), ("--workers",)),
        (("--hf-teachers", "40"), ("InvalidParameterError", "--hf-teachers, at most --n")),
        (("--hf-teachers", "1"), ("--hf-teachers", ">= 2")),
    ],
)
def test_bad_arguments_are_refused_before_work(tmp_path, args, words):
    out = tmp_path / "results"
    proc = _tutor(*args, "--no-progress", "--out", str(out), cwd=tmp_path)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert proc.stdout == "" and "Traceback" not in proc.stderr
    for word in words:
        assert word in proc.stderr, proc.stderr
    assert not out.exists()


def test_out_that_is_a_file_is_refused(tmp_path):
    target = tmp_path / "results"
    target.write_text("keep me")
    proc = _tutor("--quick", "--no-progress", "--out", str(target), cwd=tmp_path)
    assert proc.returncode == 2 and "SaveError" in proc.stderr and proc.stdout == ""
    assert target.read_text() == "keep me"


# ---------------------------------------------------------------- the statistics


def _runs(deltas_by_seed: dict, policy="KC2", base=0.5) -> pd.DataFrame:
    rows = []
    for seed, deltas in deltas_by_seed.items():
        for teacher, d in enumerate(deltas):
            for run in (1, 2):
                common = {"variant": "default", "seed": seed, "teacher": teacher, "run": run}
                rows.append({**common, "policy": "BF", "efficacy": base})
                rows.append({**common, "policy": policy, "efficacy": base + d})
    return pd.DataFrame(rows)


def test_paired_deltas_pair_the_same_teacher_seed_and_run():
    runs = _runs({0: [0.1, 0.2, 0.3], 1: [-0.1, 0.0, 0.4]})
    d = st.teacher_deltas(runs)
    assert d.sort_values(["seed", "teacher"]).delta.round(12).tolist() == [
        0.1, 0.2, 0.3, -0.1, 0.0, 0.4
    ]
    per_seed, overall = st.delta_table(runs, n_boot=500)
    assert per_seed["mean"].round(12).tolist() == [0.2, 0.1]
    row = overall.loc["KC2"]
    assert row["mean"] == pytest.approx(0.15)
    # t interval over two seeds: 0.15 +- t(0.975, 1) * sd / sqrt(2)
    half = 12.7062047 * np.std([0.2, 0.1], ddof=1) / np.sqrt(2)
    assert row["low"] == pytest.approx(0.15 - half, rel=1e-6)
    assert row["pooled_low"] <= 0.15 <= row["pooled_high"]


def test_a_clear_gain_replicates_and_no_gain_does_not():
    gain = _runs({s: [0.3, 0.25, 0.35, 0.3, 0.28, 0.32] for s in range(3)})
    rates = st.replication_table(gain, n=6, n_boot=300)
    assert rates.seed_rate.item() == 1.0 and rates.boot_rate.item() == 1.0
    rng = np.random.default_rng(1)
    none = _runs({s: list(rng.normal(0, 0.1, 6)) for s in range(3)})
    rates = st.replication_table(none, n=6, n_boot=300)
    assert rates.boot_rate.item() < 0.5


def test_mean_curve_is_each_runs_latest_efficacy():
    curves = pd.DataFrame(
        {"variant": "default", "seed": 0, "teacher": [0, 0, 1, 1], "run": 1,
         "policy": "BF", "seconds": [100.0, 300.0, 200.0, 800.0],
         "efficacy": [0.2, 0.6, 1.0, 1.0]}
    )
    mean = st.mean_curves(curves, step=100.0)["BF"]
    assert mean.loc[0.0] == 0.0
    assert mean.loc[100.0] == pytest.approx(0.1)
    assert mean.loc[200.0] == pytest.approx(0.6)
    assert mean.loc[300.0] == pytest.approx(0.8)
    assert mean.loc[900.0] == pytest.approx(0.8)


def test_papers_bf_undemonstrated_per_run():
    assert paper_bf_undemonstrated_per_run() == pytest.approx(827 / 27)


def test_an_interrupted_study_resumes_from_its_checkpoint(tmp_path):
    plan = dataclasses.replace(
        QUICK, n=2, policies=("BF", "KC2"), variants=(), variant_seeds=0, hf_teachers=None
    )
    path = tmp_path / "partial.jsonl"
    first = run_study(plan, workers=1, progress=False, checkpoint=path)
    lines = path.read_text().splitlines()
    assert len(lines) == 1 + 2 * 2 * 2  # the plan, then seeds x teachers x arms
    path.write_text("\n".join(lines[:4]) + "\n" + lines[4][:40])  # killed mid-line
    again = run_study(plan, workers=1, progress=False, checkpoint=path)
    assert again.resumed == 3
    drop = ["compute_seconds"]
    pd.testing.assert_frame_equal(first.runs.drop(columns=drop), again.runs.drop(columns=drop))
    pd.testing.assert_frame_equal(first.curves, again.curves)
    # a plan with other seeds keeps every job it shares; other runs per teacher start over
    more = _Checkpoint(path, check_plan(dataclasses.replace(plan, seeds=3)), SETTINGS)
    more.close()
    same = _Checkpoint(path, check_plan(plan), SETTINGS)
    same.close()
    assert set(more.done) == set(same.done) and len(more.done) == 8
    other = _Checkpoint(path, check_plan(dataclasses.replace(plan, runs=2)), SETTINGS)
    other.close()
    assert other.done == {} and len(path.read_text().splitlines()) == 1
