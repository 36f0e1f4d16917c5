"""The class plan (tutor.framework.assignment): formats, balanced dealing, bad files."""

from __future__ import annotations

import hashlib
import json
import math
import os
import unicodedata
from collections import Counter

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tutor.errors import InvalidFileError, InvalidPlanError
from tutor.framework.assignment import (
    PLAN_ENV,
    ClassPlan,
    hash_rank,
    load_plan,
    plan_from_env,
)
from tutor.runtime import trainee_key

CONDITIONS = ("NF", "RF", "BF", "SF")
ROSTER = [f"Trainee {k:02d}" for k in range(36)]


def balanced(names, conditions=CONDITIONS) -> ClassPlan:
    return ClassPlan.from_entries([(f"line {k}", n, "") for k, n in enumerate(names)], conditions)


def write(tmp_path, name: str, text: str):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def plan_json(**fields) -> str:
    data = {"format": "lfd-tutor-class-plan", "version": 1, "experiment": 2, **fields}
    return json.dumps(data, ensure_ascii=False)


# ------------------------------------------------------------------ balanced dealing


@settings(max_examples=60, deadline=None)
@given(st.permutations(ROSTER))
def test_36_roster_names_get_9_each_in_any_order(order):
    plan = balanced(order)
    assert plan.counts() == dict.fromkeys(CONDITIONS, 9)
    assert plan.table == balanced(ROSTER).table  # who gets what does not depend on order


names = st.text(
    alphabet=st.characters(categories=("L", "N", "Zs", "P")), min_size=1, max_size=12
).filter(lambda n: n.strip())


@settings(max_examples=40, deadline=None)
@given(st.lists(names, min_size=1, max_size=60, unique_by=trainee_key), st.randoms())
def test_any_roster_is_dealt_as_evenly_as_it_can_be(roster, rng):
    plan = balanced(roster)
    counts = plan.counts()
    assert max(counts.values()) - min(counts.values()) <= 1
    assert sum(counts.values()) == len(roster)
    shuffled = list(roster)
    rng.shuffle(shuffled)
    assert balanced(shuffled).table == plan.table
    for name in roster:
        assert plan.assign(name).how == "balanced"


def test_a_hash_alone_would_rarely_give_9_each():
    """Why the roster is dealt: key mod 4 gives 9 each with probability about 0.45 %."""
    p = math.factorial(36) / (math.factorial(9) ** 4 * 4**36)
    assert p == pytest.approx(0.0045428, rel=1e-4)
    hashed = Counter(CONDITIONS[hash_rank(trainee_key(n)) % 4] for n in ROSTER)
    assert hashed != dict.fromkeys(CONDITIONS, 9)  # this roster is one of the other 99.5 %


def test_named_conditions_count_when_the_rest_is_balanced():
    entries = [("line", n, "RF") for n in ROSTER[:6]] + [("line", n, None) for n in ROSTER[6:]]
    plan = ClassPlan.from_entries(entries, CONDITIONS)
    assert plan.counts() == dict.fromkeys(CONDITIONS, 9)
    assert {plan.assign(n).how for n in ROSTER[:6]} == {"listed"}


def test_the_dealing_is_stable_across_versions():
    """The hash is SHA-256 of the folder key, pinned, so a class keeps its conditions."""
    assert hash_rank("mai-anh") == int(hashlib.sha256(b"mai-anh").hexdigest(), 16)
    plan = balanced(ROSTER)
    assert [plan.assign(n).condition for n in ROSTER[:8]] == PINNED_FIRST_8


PINNED_FIRST_8 = ["BF", "BF", "RF", "SF", "RF", "RF", "BF", "NF"]


def test_a_trainee_not_on_the_plan_gets_hash_mod_k():
    plan = balanced(ROSTER)
    outsider = plan.assign("Late Arrival")
    key = trainee_key("Late Arrival")
    assert outsider.how == "hashed" and outsider.key == key
    assert outsider.condition == CONDITIONS[hash_rank(key) % 4]
    assert "not on your educator's class plan" in outsider.reason
    # over many names, hash mod 4 spreads out (each condition 20-30 % of 2000 names)
    spread = Counter(plan.assign(f"visitor {k}").condition for k in range(2000))
    assert all(400 <= spread[c] <= 600 for c in CONDITIONS), spread
    empty = ClassPlan.from_entries([], CONDITIONS)
    assert "by a hash of each trainee's name" in empty.assign("Ana").reason


# ------------------------------------------------------------------ names by folder key


def test_names_are_matched_by_their_folder_key():
    nfd = unicodedata.normalize("NFD", "Zoë")
    plan = ClassPlan.from_entries(
        [("line 2", "Zoë ", "SF"), ("line 3", nfd, "sf"), ("line 4", "Mai_Anh", "RF")],
        CONDITIONS,
    )
    assert len(plan.table) == 2
    for typed in ("Zoë", "  Zoë", "Zo\u00eb\u200b", nfd):
        found = plan.assign(typed)
        assert (found.condition, found.how) == ("SF", "listed")
        assert found.reason == "your educator's class plan assigns you SF"
    assert plan.assign("Mai Anh").how == "hashed"  # another trainee than Mai_Anh


def test_one_trainee_with_two_conditions_is_refused_naming_both():
    with pytest.raises(InvalidPlanError) as caught:
        ClassPlan.from_entries([("line 2", "Zoë", "RF"), ("line 9", " Zoë ", "SF")], CONDITIONS)
    message = str(caught.value)
    assert "line 2" in message and "line 9" in message and "RF and SF" in message
    assert "keep one" in message
    with pytest.raises(InvalidPlanError, match="RF and balanced"):
        ClassPlan.from_entries([("a", "Zoë", "RF"), ("b", "Zoë", "balanced")], CONDITIONS)


# ------------------------------------------------------------------ the CSV format


def test_csv_plans(tmp_path):
    path = write(
        tmp_path,
        "plan.csv",
        "\ufeffTrainee , Condition,email\n"
        "Mai Anh,rf,m@example.org\n"
        "\n"
        '"Smith, Jo",SF,\n'
        "Zoë,balanced,\n"
        "Ana,,\n"
        "Ben\n",
    )
    plan = load_plan(path, CONDITIONS)
    assert plan.assign("Mai Anh").condition == "RF"
    assert plan.assign("Smith, Jo").condition == "SF"
    assert {plan.assign(n).how for n in ("Zoë", "Ana", "Ben")} == {"balanced"}
    assert sum(plan.counts().values()) == 5


def test_csv_with_semicolons_or_only_a_roster(tmp_path):
    semi = load_plan(write(tmp_path, "a.csv", "trainee;condition\nMai Anh;BF\n"), CONDITIONS)
    assert semi.assign("Mai Anh").condition == "BF"
    roster = load_plan(write(tmp_path, "b.CSV", "trainee\n" + "\n".join(ROSTER)), CONDITIONS)
    assert roster.counts() == dict.fromkeys(CONDITIONS, 9)


BAD_CSV = [
    ("", "is empty"),
    ("name,condition\nAna,RF\n", "must be the header trainee,condition"),
    ("trainee,trainee\nAna,RF\n", "each once"),
    ("trainee,condition\nAna,XF\n", "line 2: 'XF' (for 'Ana') is not a condition"),
    ("trainee,condition\nAna,RF\nBen,SF\nAna ,BF\n", "given two conditions, RF and BF"),
    ("trainee,condition\nSmith, Jo,SF\n", "line 2 has 3 cells"),
    ("trainee,condition\n,RF\n", "line 2 has no trainee name"),
    ("trainee,condition\nMai\u202eAnh,RF\n", "line 2: the trainee's name holds invisible"),
    ('trainee,condition\n"Ana,RF\nBen,SF\n', "line 3 is not readable as CSV"),  # no closing "
]


@pytest.mark.parametrize("text, fragment", BAD_CSV, ids=[f[1][:24] for f in BAD_CSV])
def test_bad_csv_plans_say_what_and_how(tmp_path, text, fragment):
    path = write(tmp_path, "plan.csv", text)
    with pytest.raises(InvalidPlanError) as caught:
        load_plan(path, CONDITIONS)
    message = str(caught.value)
    assert fragment in message and "plan.csv" in message
    assert isinstance(caught.value, InvalidFileError)


def test_unreadable_plans(tmp_path):
    cases = [
        (tmp_path / "missing.csv", "does not exist"),
        (tmp_path / "plan.txt", "must be a .csv file"),
        (tmp_path / "folder.csv", "is a folder"),
    ]
    (tmp_path / "folder.csv").mkdir()
    (tmp_path / "latin1.csv").write_bytes("trainee\nZo\xeb\n".encode("latin-1"))
    cases.append((tmp_path / "latin1.csv", "not UTF-8"))
    for path, fragment in cases:
        with pytest.raises(InvalidPlanError, match=fragment):
            load_plan(path, CONDITIONS)


# ------------------------------------------------------------------ the JSON format


def test_json_plans(tmp_path):
    path = write(
        tmp_path,
        "plan.json",
        plan_json(assign={"Mai Anh": "RF", "Zoë": "balanced"}, trainees=["Ana", "Mai Anh"]),
    )
    plan = load_plan(path, CONDITIONS)
    assert plan.assign("Mai Anh").how == "listed" and plan.assign("Mai Anh").condition == "RF"
    assert plan.assign("Ana").how == plan.assign("Zoë").how == "balanced"
    roster = load_plan(write(tmp_path, "r.json", plan_json(trainees=ROSTER)), CONDITIONS)
    assert roster.counts() == dict.fromkeys(CONDITIONS, 9)
    also = load_plan(
        write(tmp_path, "b.json", plan_json(assign="balanced", trainees=ROSTER[::-1])), CONDITIONS
    )
    assert also.table == roster.table


BAD_JSON = [
    ("[1, 2]", "is not a class plan"),
    ('{"format": "lfd-tutor-run"}', "is not a class plan"),
    (plan_json(version=2), "is version 2"),
    (plan_json(experiment=1), "only Experiment 2 assigns conditions"),
    (plan_json(assign="random"), '"assign" must be "balanced" or an object'),
    (plan_json(assign={"Ana": "VR"}), "'VR' (for 'Ana') is not a condition"),
    (plan_json(assign={"Ana": 3}), "must be text"),
    (plan_json(assign={"Ana": "RF", "Ana ": "SF"}), "given two conditions"),
    (plan_json(trainees="Ana, Ben"), '"trainees" must be a list'),
    (plan_json(trainees=["Ana", 7]), 'entry 1 of "trainees"'),
    (plan_json(seed=3), "fields a class plan does not have: seed"),
    ('{"format": "lfd-tutor-class-plan", "format": "x"}', "appears twice"),
    ('{"format": "lfd-tutor-class-pl', "not valid JSON"),
]


@pytest.mark.parametrize("text, fragment", BAD_JSON, ids=[f[1][:24] for f in BAD_JSON])
def test_bad_json_plans_say_what_and_how(tmp_path, text, fragment):
    path = write(tmp_path, "plan.json", text)
    with pytest.raises(InvalidPlanError) as caught:
        load_plan(path, CONDITIONS)
    assert fragment in str(caught.value) and "plan.json" in str(caught.value)


def test_a_plan_needs_the_experiments_conditions():
    with pytest.raises(InvalidPlanError, match="distinct conditions"):
        ClassPlan.from_entries([], ("NF", "NF"))


# ------------------------------------------------------------------ the environment


def test_the_plan_comes_from_tutor_class_plan(tmp_path, monkeypatch):
    monkeypatch.delenv(PLAN_ENV, raising=False)
    assert plan_from_env(CONDITIONS) is None
    monkeypatch.setenv(PLAN_ENV, "  ")
    assert plan_from_env(CONDITIONS) is None
    path = write(tmp_path, "plan.csv", "trainee,condition\nAna,SF\n")
    monkeypatch.setenv(PLAN_ENV, str(path))
    assert plan_from_env(CONDITIONS).assign("Ana").condition == "SF"
    monkeypatch.setenv(PLAN_ENV, os.fspath(tmp_path / "nope.csv"))
    with pytest.raises(InvalidPlanError, match="TUTOR_CLASS_PLAN names this file"):
        plan_from_env(CONDITIONS)
