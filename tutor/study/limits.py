"""Limits of the studies, light enough for the command line to check its arguments
before pandas, pingouin and the simulation load (the numbers live in :mod:`tutor.limits`).

Each is stated in the command line's ``--help`` and in the refusal of a larger value.
"""

from ..limits import MAX_SEED, MAX_SEEDS, MAX_TEACHERS

__all__ = ["MAX_TEACHERS", "MAX_SEEDS", "MAX_SEED"]
