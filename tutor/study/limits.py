"""Limits of the cohort study, light enough for the command line to check its arguments
before pandas, pingouin and the simulation load."""

__all__ = ["MAX_TEACHERS"]

#: the largest cohort simulated: 100 times the paper's Experiment 1 (about a quarter of an
#: hour per core for Experiment 1, more for Experiment 2); larger requests are refused
#: before any work rather than left running for days
MAX_TEACHERS = 3000
