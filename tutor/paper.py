"""Every number the tutor takes from Sena & Howard, "Quantifying Teaching Behaviour in
Robot Learning from Demonstration", in one place.

The comment above each value names the section (or table) of the paper it comes from
(A. Sena and M. Howard, King's College London; the experiments' data:
http://doi.org/10.18742/RDM01-242).
Proportions, not percentages: the paper's 7.6 % is 0.076 here.

This module sits at the bottom of the layers (like :mod:`tutor.errors`) and imports
nothing from :mod:`tutor`, so the views, the tasks, the simulated teachers and the
study can all read the same numbers.

Constants
---------
EXPERIMENT_1, EXPERIMENT_2
    The results of the two experiments, as printed beside the simulated cohorts'.
PAPER_MEDIAN_ETA, PAPER_MEAN_ETA, PAPER_THIRD_RUN_ETA
    The teaching efficiencies eta the views show beside a trainee's.
MAZE_*, PICKPLACE_*, COVERAGE_TARGET, ...
    The experimental set-up (sizes, test sets, learner settings, time limits).
"""

from __future__ import annotations

__all__ = [
    "EXPERIMENT_1",
    "EXPERIMENT_2",
    "PAPER_MEDIAN_ETA",
    "PAPER_MEAN_ETA",
    "PAPER_THIRD_RUN_ETA",
    "MAZE_CONDITIONS",
    "MAZE_N_TEACHERS",
    "MAZE_WORKSPACE_SIZE",
    "MAZE_START_ZONE_SIZE",
    "MAZE_TARGET_DIAMETER",
    "MAZE_GRID_SHAPE",
    "MAZE_N_COMPONENTS",
    "MAZE_TRACKER_HZ",
    "MAZE_TRACKER_RMSE",
    "MAZE_RULE_RADIUS",
    "COVERAGE_TARGET",
    "PICKPLACE_BEST",
    "PICKPLACE_CONDITIONS",
    "PICKPLACE_N_TEACHERS",
    "PICKPLACE_N_RUNS",
    "PICKPLACE_N_PLANTS",
    "PICKPLACE_N_COMPONENTS",
    "PICKPLACE_N_GENERALISATION_SAMPLES",
    "PICKPLACE_REALISATION_SECONDS",
    "PICKPLACE_RUN_SECONDS",
    "PICKPLACE_FAMILIARISATION_SECONDS",
    "PICKPLACE_THRESHOLD_SDS",
    "PICKPLACE_THRESHOLD_MARGIN",
]

# --- Experiment 1, point-to-point reaching through a maze (section "Experiment 1:
# Point-to-Point Reaching")

#: the three conditions, one attempt each by every participant (subsection "Conditions")
MAZE_CONDITIONS = ("NF", "VF", "VR")
#: participants, within subjects (abstract; "Results", F(2, 58))
MAZE_N_TEACHERS = 30
#: admissible space X, a 20 cm x 30 cm rectangle, in metres ("Materials and Methods")
MAZE_WORKSPACE_SIZE = (0.20, 0.30)
#: start zone I, a 20 cm x 6 cm rectangle, in metres ("Materials and Methods")
MAZE_START_ZONE_SIZE = (0.20, 0.06)
#: target beta, a circle of 0.5 cm diameter, in metres ("Materials and Methods")
MAZE_TARGET_DIAMETER = 0.005
#: I discretised into a 20 x 7 grid, |B^| = 140 ("Materials and Methods")
MAZE_GRID_SHAPE = (20, 7)
#: TP-GMM components K ("Materials and Methods")
MAZE_N_COMPONENTS = 11
#: NDI TrakStar sampling rate (Hz) and RMSE (m) ("Materials and Methods")
MAZE_TRACKER_HZ = 80.0
MAZE_TRACKER_RMSE = 0.0013
#: VR's rules 2 and 3: demos within 4 cm of a start point, in metres ("Conditions")
MAZE_RULE_RADIUS = 0.04
#: M counts the demos needed to cover at least 90 % of the test grid ("Results")
COVERAGE_TARGET = 0.9

#: median eta per condition: NF 7.6 %, VF 13.4 %, VR 14 % ("Results", figure
#: "icra_results")
PAPER_MEDIAN_ETA = {"NF": 0.076, "VF": 0.134, "VR": 0.14}

EXPERIMENT_1 = {
    "n": MAZE_N_TEACHERS,
    # repeated-measures ANOVA and the multiple comparisons ("Results")
    "anova": {"ddof1": 2, "ddof2": 58, "F": 7.952, "p": 0.001},
    "pairwise_p": {("NF", "VF"): 0.006, ("NF", "VR"): 0.017, ("VF", "VR"): 0.801},
    "median_eta": PAPER_MEDIAN_ETA,
    # the paper: "a relative improvement of approximately 180 %" (13.4 / 7.6 = 176 %)
    "relative": {
        "VF/NF": PAPER_MEDIAN_ETA["VF"] / PAPER_MEDIAN_ETA["NF"],
        "VR/NF": PAPER_MEDIAN_ETA["VR"] / PAPER_MEDIAN_ETA["NF"],
    },
    # section "Discussion": 7 of the 30 did well without feedback
    "did_well_without_feedback": 7,
}

# --- Experiment 2, pick-and-place of plants (section "Pick-and-Place Experiment")

#: the four conditions, between subjects ("Conditions")
PICKPLACE_CONDITIONS = ("NF", "RF", "BF", "SF")
#: participants, 9 per condition ("Procedure": power analysis, N = 36)
PICKPLACE_N_TEACHERS = 36
#: teaching sessions of the same task per participant ("Procedure")
PICKPLACE_N_RUNS = 3
#: plants in the tray, |B^| = 100 ("Materials and Methods"; the paper gives no grid
#: shape, the tutor's 10 x 10 tray is its own choice)
PICKPLACE_N_PLANTS = 100
#: TP-GMM components K ("Materials and Methods"); the tutor's own learner may differ
PICKPLACE_N_COMPONENTS = 7
#: BF's generalisation sampling set: the four corner plants and the centre one
#: ("Hypotheses")
PICKPLACE_N_GENERALISATION_SAMPLES = 5
#: one realisation on the real robot takes about 25 s (section's first paragraph)
PICKPLACE_REALISATION_SECONDS = 25.0
#: each teaching session is capped at 15 minutes ("Procedure")
PICKPLACE_RUN_SECONDS = 15 * 60.0
#: the 5-minute familiarisation period with the robot ("Procedure")
PICKPLACE_FAMILIARISATION_SECONDS = 5 * 60.0
#: grab/release thresholds delta_g, delta_r: mean distance in the demo set + 2 standard
#: deviations + a 1 mm regularisation term, in metres ("Materials and Methods")
PICKPLACE_THRESHOLD_SDS = 2.0
PICKPLACE_THRESHOLD_MARGIN = 0.001

#: mean eta over the three runs: NF 12.78 %, RF 13.89 %, BF 23.54 %, SF 15.34 %
#: ("Results", last paragraph)
PAPER_MEAN_ETA = {"NF": 0.1278, "RF": 0.1389, "BF": 0.2354, "SF": 0.1534}
#: eta in the third run: NF 11.35 %, RF 11.94 %, BF 27.04 %, SF 13.7 % ("Results",
#: simple main effects)
PAPER_THIRD_RUN_ETA = {"NF": 0.1135, "RF": 0.1194, "BF": 0.2704, "SF": 0.137}


#: the condition the paper's "relative improvement" of Experiment 2 is for: BF over the
#: mean of the other three ("Results")
PICKPLACE_BEST = "BF"


def _bf_over_rest(eta: dict) -> float:
    """BF's eta over the mean of the other three conditions' (the paper's "relative")."""
    rest = [eta[c] for c in PICKPLACE_CONDITIONS if c != PICKPLACE_BEST]
    return eta[PICKPLACE_BEST] / (sum(rest) / len(rest))


EXPERIMENT_2 = {
    "n": PICKPLACE_N_TEACHERS,
    # mixed-factors ANOVA ("Results")
    "mixed_anova": {
        "condition": {"ddof1": 3, "ddof2": 32, "F": 13.864, "p": 5.797e-6},
        "interaction": {"ddof1": 6, "ddof2": 64, "F": 2.7845, "p": 0.01808},
        "run": "not significant",
    },
    # Mauchly's test ("Results", first paragraph)
    "sphericity": {"chi2": 1.2423, "dof": 2, "p": 0.5372},
    "mean_eta": PAPER_MEAN_ETA,
    "third_run_eta": PAPER_THIRD_RUN_ETA,
    # BF over the mean of the other three: the paper's "about 169 %" and "about 220 %"
    "relative": {
        "mean": _bf_over_rest(PAPER_MEAN_ETA),
        "third run": _bf_over_rest(PAPER_THIRD_RUN_ETA),
    },
    # table "error_table": failure counts over all participants
    "failures": {
        "errors": {"NF": 4, "RF": 0, "BF": 3, "SF": 3},
        "undemonstrated": {"NF": 499, "RF": 619, "BF": 827, "SF": 485},
        "ambiguous": {"NF": 54, "RF": 51, "BF": 6, "SF": 39},
    },
}
