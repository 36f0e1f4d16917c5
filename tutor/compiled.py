"""Compiled kernels: numba's ``njit``, cached on disk where a cache can be written.

The learner's EM, the feasibility map's lookups and the pick-and-place criteria run as
compiled loops (:mod:`tutor.tpgmm.em`, :mod:`tutor.robot.feasibility`,
:mod:`tutor.tasks.pickplace`). numba compiles each kernel on its first call (a few
seconds in all) and keeps the machine code beside the source (``__pycache__``) or, where
that folder is read-only (an install shared by a hub's trainees), in the user's own
cache folder, so later processes load it in milliseconds. Where neither can be written
(numba then refuses ``cache=True`` outright) a kernel is compiled in memory in every
process instead: slower to start, the same results.

**A shared seed.** numba will not read a cache it cannot write, so on a hub each
trainee would compile every kernel once (about 5 s on their first demo). The hub kit
instead compiles them once into a folder every trainee may read (``lfd-tutor warm`` with
``NUMBA_CACHE_DIR`` set to it) and starts each trainee's server with their own
``NUMBA_CACHE_DIR`` and :data:`SEED_VARIABLE` naming that folder: on import, this
module copies the kernels the trainee's cache lacks from the seed (:func:`seed_cache`).
numba files a kernel under a name made from its source file's path alone, the same in
any cache folder, so copied files are found as they were written.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from pathlib import Path

import numba

__all__ = ["compiled", "seed_cache", "SEED_VARIABLE"]

#: the environment variable naming a read-only folder of pre-compiled kernels
SEED_VARIABLE = "TUTOR_KERNEL_CACHE_SEED"
#: numba's cache files: the machine code first, then the index that points at it
_KINDS = (".nbc", ".nbi")


def seed_cache(seed: str | os.PathLike | None = None,
               cache: str | os.PathLike | None = None) -> int:
    """Copy the compiled kernels ``cache`` lacks from the folder ``seed``.

    Parameters
    ----------
    seed : path, optional
        A cache folder written by numba with ``NUMBA_CACHE_DIR`` set to it (default: the
        environment's :data:`SEED_VARIABLE`; unset or empty: nothing to do).
    cache : path, optional
        This process's own cache folder (default: numba's ``NUMBA_CACHE_DIR``; unset:
        nothing to do, numba then uses its own places).

    Returns
    -------
    int
        How many files were copied. A file the cache already has is never replaced (a
        kernel the user compiled since wins; numba recompiles any that are stale), links
        and half-written files in the seed are skipped, and a file that cannot be
        copied is left for numba to compile: seeding only ever saves time.
    """
    seed = os.environ.get(SEED_VARIABLE, "") if seed is None else seed
    cache = numba.config.CACHE_DIR if cache is None else cache
    if not seed or not cache:
        return 0
    seed, cache = Path(seed), Path(cache)
    copied = 0
    try:
        if not seed.is_dir() or seed.resolve() == cache.resolve():
            return 0
        folders = [f for f in seed.iterdir() if f.is_dir() and not f.is_symlink()]
    except OSError:
        return 0
    for folder in folders:  # one per source folder, named by numba from its path
        try:
            files = sorted(
                (f for f in folder.iterdir()
                 if f.suffix in _KINDS and f.is_file() and not f.is_symlink()),
                key=lambda f: (_KINDS.index(f.suffix), f.name),
            )
        except OSError:
            continue
        for source in files:
            target = cache / folder.name / source.name
            if target.exists() or target.is_symlink():
                continue
            part = target.with_name(f"{target.name}.seed.{os.getpid()}")
            try:
                target.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(source, part)
                os.replace(part, target)  # another process never reads half a file
                copied += 1
            except OSError:
                with contextlib.suppress(OSError):
                    part.unlink(missing_ok=True)
    return copied


def compiled(func=None, *, inline: bool = False):
    """``numba.njit(cache=True)(func)``, or ``numba.njit(func)`` with no writable cache.

    ``@compiled(inline=True)`` marks a small kernel that other kernels call per element:
    numba inlines it into each caller, so the caller's loop can vectorise.
    """
    if func is None:
        return lambda f: compiled(f, inline=inline)
    options = {"inline": "always"} if inline else {}
    try:
        return numba.njit(cache=True, **options)(func)
    except RuntimeError:  # "cannot cache function ...: no locator available"
        return numba.njit(**options)(func)


seed_cache()  # before any kernel is first called (numba reads its cache then)
