"""The numbers Sena & Howard report, to print beside the simulated cohorts' (section
"Evaluation"). Proportions, not percentages."""

from __future__ import annotations

__all__ = ["EXPERIMENT_1", "EXPERIMENT_2"]

EXPERIMENT_1 = {
    "n": 30,
    "anova": {"ddof1": 2, "ddof2": 58, "F": 7.952, "p": 0.001},
    "pairwise_p": {("NF", "VF"): 0.006, ("NF", "VR"): 0.017, ("VF", "VR"): 0.801},
    "median_eta": {"NF": 0.076, "VF": 0.134, "VR": 0.14},
    # the paper: "a relative improvement of approximately 180 %" (13.4 / 7.6 = 176 %)
    "relative": {"VF/NF": 0.134 / 0.076, "VR/NF": 0.14 / 0.076},
    "did_well_without_feedback": 7,
}

EXPERIMENT_2 = {
    "n": 36,
    "mixed_anova": {
        "condition": {"ddof1": 3, "ddof2": 32, "F": 13.864, "p": 5.797e-6},
        "interaction": {"ddof1": 6, "ddof2": 64, "F": 2.7845, "p": 0.01808},
        "run": "not significant",
    },
    "sphericity": {"chi2": 1.2423, "dof": 2, "p": 0.5372},
    "mean_eta": {"NF": 0.1278, "RF": 0.1389, "BF": 0.2354, "SF": 0.1534},
    "third_run_eta": {"NF": 0.1135, "RF": 0.1194, "BF": 0.2704, "SF": 0.137},
    # BF over the mean of the other three: the paper's "about 169 %" and "about 220 %"
    "relative": {
        "mean": 0.2354 / ((0.1278 + 0.1389 + 0.1534) / 3),
        "third run": 0.2704 / ((0.1135 + 0.1194 + 0.137) / 3),
    },
    "failures": {
        "errors": {"NF": 4, "RF": 0, "BF": 3, "SF": 3},
        "undemonstrated": {"NF": 499, "RF": 619, "BF": 827, "SF": 485},
        "ambiguous": {"NF": 54, "RF": 51, "BF": 6, "SF": 39},
    },
}
