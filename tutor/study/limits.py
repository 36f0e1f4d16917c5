"""Limits of the studies, light enough for the command line to check its arguments
before pandas, pingouin and the simulation load.

Each is stated in the command line's ``--help`` and in the refusal of a larger value.
"""

__all__ = ["MAX_TEACHERS", "MAX_SEEDS", "MAX_SEED"]

#: the largest cohort simulated: 100 times the paper's Experiment 1 (about a quarter of an
#: hour per core for Experiment 1, more for Experiment 2); larger requests are refused
#: before any work rather than left running for days
MAX_TEACHERS = 3000
#: the most seeds one robustness run or adaptive study goes over (each seed is a whole
#: cohort: 1000 of the paper's Experiment 1 take about a day on two cores)
MAX_SEEDS = 1000
#: the largest seed: it must fit the 64-bit integers of the result tables
MAX_SEED = 2**63 - 1
