"""tutor.compiled's shared seed: a trainee's cache starts as a copy of kernels compiled once.

numba refuses to read a cache folder it cannot write, so on a hub every trainee would
compile every kernel on their first demo. The hub kit compiles them once
(``lfd-tutor warm`` with ``NUMBA_CACHE_DIR`` set) and each trainee's process copies them
into its own cache on import. These tests build such a seed with the real command and
count numba's own cache hits and misses in fresh processes.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from tutor.compiled import SEED_VARIABLE, seed_cache

#: a trainee's first demos on both tasks (what ``lfd-tutor warm`` does), then numba's
#: own count of kernels loaded from a cache (hits) and compiled (misses)
PROBE = """
import json, sys
import numba
from tutor.__main__ import warm_command
warm_command(None)
hits = misses = 0
for name, module in list(sys.modules.items()):
    if not name.startswith("tutor"):
        continue
    for value in vars(module).values():
        if isinstance(value, numba.core.registry.CPUDispatcher):
            hits += sum(value.stats.cache_hits.values())
            misses += sum(value.stats.cache_misses.values())
print(json.dumps({"hits": hits, "misses": misses}))
"""


def run(code_or_args, cache: Path, seed: Path | None = None) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != SEED_VARIABLE}
    env["NUMBA_CACHE_DIR"] = str(cache)
    if seed is not None:
        env[SEED_VARIABLE] = str(seed)
    args = ["-c", code_or_args] if isinstance(code_or_args, str) else code_or_args
    done = subprocess.run([sys.executable, *args], env=env, capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    return done


def counts(done: subprocess.CompletedProcess) -> dict:
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_a_process_seeded_from_lfd_tutor_warm_compiles_nothing(tmp_path):
    seed, own, alone = tmp_path / "room", tmp_path / "trainee", tmp_path / "alone"
    warmed = run(["-m", "tutor", "warm"], seed)
    assert "compiled kernels ready" in warmed.stdout
    assert any(seed.rglob("*.nbc")) and any(seed.rglob("*.nbi"))
    # without the seed, an empty cache compiles (the control: the probe can fail)
    control = counts(run(PROBE, alone))
    assert control["misses"] > 0
    # seeded, every kernel a first demo calls comes from the cache (a kernel called only
    # from another is loaded inside its caller, so hits count fewer than misses did)
    seeded = counts(run(PROBE, own, seed))
    assert seeded["misses"] == 0 and seeded["hits"] > 0
    copied = sorted(p.relative_to(own) for p in own.rglob("*") if p.is_file())
    assert copied == sorted(p.relative_to(seed) for p in seed.rglob("*") if p.is_file())
    # a second process of the same trainee finds them in its own cache, copying nothing
    assert counts(run(PROBE, own, seed))["misses"] == 0


def test_seeding_copies_only_kernel_files_the_cache_lacks(tmp_path):
    seed, own = tmp_path / "seed", tmp_path / "own"
    folder = seed / "tpgmm_0123abcd"
    folder.mkdir(parents=True)
    (folder / "em._run-10.py311.1.nbc").write_bytes(b"machine code")
    (folder / "em._run-10.py311.nbi").write_bytes(b"room's index")
    (folder / "em._run-10.py311.nbi.tmp.9f8e").write_bytes(b"half written")
    (folder / "notes.txt").write_text("not a kernel")
    outside = tmp_path / "secret.nbc"
    outside.write_bytes(b"not the room's")
    (folder / "linked.nbc").symlink_to(outside)
    (seed / "elsewhere").symlink_to(tmp_path, target_is_directory=True)
    (own / folder.name).mkdir(parents=True)
    (own / folder.name / "em._run-10.py311.nbi").write_bytes(b"trainee's own index")

    assert seed_cache(seed, own) == 1
    got = {p.name: p.read_bytes() for p in (own / folder.name).iterdir()}
    assert got == {"em._run-10.py311.1.nbc": b"machine code",
                   "em._run-10.py311.nbi": b"trainee's own index"}  # never replaced
    assert not (own / "elsewhere").exists()
    assert seed_cache(seed, own) == 0  # nothing missing any more


def test_seeding_with_nothing_to_seed_from_does_nothing(tmp_path, monkeypatch):
    own = tmp_path / "own"
    monkeypatch.delenv(SEED_VARIABLE, raising=False)
    assert seed_cache(None, own) == 0  # no seed named
    assert seed_cache(tmp_path / "missing", own) == 0
    assert seed_cache(tmp_path, tmp_path) == 0  # the cache itself
    assert seed_cache(tmp_path, "") == 0  # no own cache: numba's own places
    assert not own.exists()
