"""Compiled kernels: numba's ``njit``, cached on disk where a cache can be written.

The learner's EM, the feasibility map's lookups and the pick-and-place criteria run as
compiled loops (:mod:`tutor.tpgmm.em`, :mod:`tutor.robot.feasibility`,
:mod:`tutor.tasks.pickplace`). numba compiles each kernel on its first call (a few
seconds in all) and keeps the machine code beside the source (``__pycache__``) or, where
that folder is read-only (an install shared by a hub's trainees), in the user's own
cache folder, so later processes load it in milliseconds. Where neither can be written
(numba then refuses ``cache=True`` outright) a kernel is compiled in memory in every
process instead: slower to start, the same results.
"""

from __future__ import annotations

import numba

__all__ = ["compiled"]


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
