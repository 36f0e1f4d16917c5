r"""Teaching failures of Sena & Howard (section "Teaching Failures").

After demo m (eps_m the efficacy after it, :math:`\Delta = \varepsilon_m - \varepsilon_{m-1}`):

incorrect
    The demo is not an example of the task (:math:`b \setminus B \neq \emptyset`: it
    fails the task criteria itself), or its effect marks it as wrong:
    :math:`\Delta \le 0` although it is *not* similar to the earlier demos (a
    similar demo that changes little is ambiguous instead, see below). When eps
    was already 1 nothing can improve, so there only a drop counts.
ambiguous
    The demo is similar to the earlier ones, :math:`s(b, \mathbf b) \le \delta_a`,
    and changes efficacy only a little, :math:`\delta_l \le \Delta \le \delta_u`.
    By default s is the mean distance, sample by sample after aligning in time,
    to the nearest earlier demo.
undemonstrated
    Test conditions the learner fails and no demo covers:
    :math:`B^ \setminus (R^ \cup b)`, counted and located.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..errors import InvalidParameterError

__all__ = [
    "Thresholds",
    "TeachingWarning",
    "similarity",
    "INCORRECT",
    "AMBIGUOUS",
    "UNDEMONSTRATED",
]

INCORRECT = "incorrect"
AMBIGUOUS = "ambiguous"
UNDEMONSTRATED = "undemonstrated"


@dataclass(frozen=True)
class Thresholds:
    """Thresholds of the failure definitions.

    Attributes
    ----------
    ambiguity_distance : float or None
        delta_a, in the task's units; None takes the task's default.
    delta_lower, delta_upper : float
        delta_l and delta_u: the range of efficacy change that counts as
        "little or no change" for a similar demo (default -0.05 to +0.02, i.e.
        losing at most 5 % or gaining at most 2 % of the test conditions).
    """

    ambiguity_distance: float | None = None
    delta_lower: float = -0.05
    delta_upper: float = 0.02

    def __post_init__(self):
        if self.ambiguity_distance is not None and not self.ambiguity_distance >= 0:
            raise InvalidParameterError(
                f"ambiguity_distance must be >= 0, got {self.ambiguity_distance}"
            )
        if not self.delta_lower <= self.delta_upper:
            raise InvalidParameterError(
                f"delta_lower ({self.delta_lower}) must not exceed delta_upper ({self.delta_upper})"
            )

    def to_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
class TeachingWarning:
    """One failure found after a demo.

    Attributes
    ----------
    kind : {"incorrect", "ambiguous", "undemonstrated"}
    message : str
        Plain words for the trainee, saying what to do next.
    demo : int or None
        1-based number of the demo concerned (None for undemonstrated states).
    count : int
        How many test conditions (undemonstrated) or demos (otherwise) it concerns.
    """

    kind: str
    message: str
    demo: int | None = None
    count: int = 1

    def to_dict(self) -> dict:
        return asdict(self)


def similarity(demo: np.ndarray, others) -> tuple[float, int]:
    """s(b, b_set): mean distance to the nearest earlier demo, aligned sample by sample.

    Parameters
    ----------
    demo : ndarray (T, 1 + d)
    others : sequence of ndarray (T, 1 + d)
        Earlier demos, resampled to the same length as ``demo``.

    Returns
    -------
    distance : float
        inf when there is no earlier demo.
    nearest : int
        Index of the nearest earlier demo (-1 when none).
    """
    if len(others) == 0:
        return float("inf"), -1
    stack = np.asarray(others)[:, :, 1:]
    dist = np.linalg.norm(stack - demo[None, :, 1:], axis=2).mean(axis=1)
    nearest = int(np.argmin(dist))
    return float(dist[nearest]), nearest
