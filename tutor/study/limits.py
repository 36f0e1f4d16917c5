"""Limits of the cohort study, light enough for the command line to check its arguments
before pandas, pingouin and the simulation load (the numbers live in :mod:`tutor.limits`)."""

from ..limits import MAX_TEACHERS

__all__ = ["MAX_TEACHERS"]
