r"""What a task must supply to the teaching framework.

Sena & Howard, section "Learning and Teaching Framework": a task defines the
task space B through success criteria, and an objective approximation B^ of it
through a finite set of test points. A *test point* is whatever selects one
way of doing the task (a start point in the maze, a plant in pick-and-place; the
paper's "task condition"); the framework only ever handles test points as rows of an
array. "Condition" in this package always means an experiment's feedback condition
(NF, VF, ...: :mod:`tutor.framework.protocol`).

The framework never names a particular task: everything task-specific goes
through this interface.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..errors import InvalidFileError, InvalidParameterError
from ..tpgmm import TPGMM, Frame, FrameBatch
from ..tpgmm.checks import check_real_array
from ..tpgmm.tracking import (
    DEFAULT_CONTROL_COST,
    check_control_cost,
    track,
    tracking_precision,
)
from .wording import REASON_WORDS, listing

__all__ = ["Task", "Verdict", "Reason", "control_cost_entry"]


def control_cost_entry(data: dict, where: str, default: float) -> float:
    """A task file's ``control_cost`` (the tracking controller's r), checked: a named
    :class:`~tutor.errors.InvalidFileError` that names the file if it is no finite
    positive number."""
    try:
        return check_control_cost(data.get("control_cost", default), f"control_cost in {where}")
    except InvalidParameterError as exc:
        raise InvalidFileError(f"{exc}; fix or remove the entry") from None


@dataclass(frozen=True)
class Reason:
    """One way a trajectory fails the task's criteria, as data.

    A task's :meth:`Task.judge` gives each failing trajectory a tuple of these, in the
    order they happen along the path; the pictures and the panel read the data, and the
    words come from :meth:`Task.reason_words` (templates in
    :data:`tutor.framework.wording.REASON_WORDS`). Nothing reads words back.

    Attributes
    ----------
    kind : str
        A key of :data:`~tutor.framework.wording.REASON_WORDS` ("obstacle", "end", ...).
    sample : int or None
        0-based index of the first sample that breaks criterion (i), for the kinds that
        happen at a sample.
    samples : int or None
        How many samples the judged path has (with ``sample``).
    distance : float or None
        How far off (task units): the end from the target, the grasp from the plant.
    obstacle : int or None
        0-based index of the obstacle hit (the task names it: :meth:`Task.obstacle_name`).
    plant, chosen : int or None
        Test-point indices: the one grabbed and the one meant ("wrong_plant").
    """

    kind: str
    sample: int | None = None
    samples: int | None = None
    distance: float | None = None
    obstacle: int | None = None
    plant: int | None = None
    chosen: int | None = None


@dataclass(frozen=True)
class Verdict:
    """The task criteria applied to a batch of trajectories.

    Attributes
    ----------
    passed : ndarray of bool, shape (B,)
        True where the trajectory is in B (meets every criterion).
    causes : tuple of tuple of Reason, length B
        Empty for a passing trajectory, otherwise why it fails, as data.
    reasons : tuple of str, length B
        The same in plain words ("hit obstacle 2 at sample 57 of 200"), "" for a pass.
    """

    passed: np.ndarray
    causes: tuple[tuple[Reason, ...], ...]
    #: turns one entry of ``causes`` into words (the task's :meth:`Task.reason_words`)
    words: Callable[[tuple], str] = field(default=None, repr=False, compare=False)

    @cached_property
    def reasons(self) -> tuple[str, ...]:
        # worded on first use: the lookahead and the studies judge thousands of
        # realisations a second and read only ``passed``
        if self.words is None:
            return tuple("" for _ in self.causes)
        return tuple(self.words(c) for c in self.causes)

    def __reduce__(self):
        # copied or sent to another process with its words, not with the task
        return (_worded_verdict, (self.passed, self.causes, self.reasons))


def _worded_verdict(passed, causes, reasons) -> Verdict:
    verdict = Verdict(passed, causes)
    verdict.__dict__["reasons"] = tuple(reasons)
    return verdict


class Task(ABC):
    """A task the teacher demonstrates and the learner must generalise."""

    #: short identifier stored in run files
    name: str = "task"
    #: distance (in the task's units) below which a demo counts as similar (delta_a)
    ambiguity_distance: float = 0.0
    #: what one test point is called in messages ("start point", "plant")
    point_noun: str = "test point"
    point_noun_plural: str = "test points"

    def __deepcopy__(self, memo):
        # A task is a fixed definition (geometry, criteria, robot models), shared by
        # every copy of a session rather than copied with it.
        return self

    def format_distance(self, distance: float) -> str:
        """A distance in the task's units, in words for a trainee."""
        return f"{distance:.3g}"

    def point_name(self, index: int) -> str:
        """Test point ``index`` (0-based) in words ("start point 3")."""
        return f"{self.point_noun} {int(index) + 1}"

    def scripted_demo(self, index: int, rng) -> np.ndarray:
        """A careful scripted recording for test point ``index`` (raw, as a hand gives
        it), for banks of demos the lookahead chooses from."""
        raise InvalidParameterError(
            f"the task {self.name!r} has no scripted demonstrations: give it a "
            "scripted_demo(index, rng) method"
        )

    def obstacle_name(self, index: int) -> str:
        """Obstacle ``index`` (0-based) in words ("obstacle 2")."""
        return f"obstacle {int(index) + 1}"

    def reason_words(self, causes, samples: bool = True) -> str:
        """``causes`` (a tuple of :class:`Reason`) in plain words, "" for none; with
        ``samples`` False, without "at sample k of n"."""
        parts = []
        for r in causes:
            at = ""
            if samples and r.sample is not None:
                at = f" at sample {r.sample + 1} of {r.samples}"
            parts.append(
                REASON_WORDS[r.kind].format(
                    at=at,
                    distance="" if r.distance is None else self.format_distance(r.distance),
                    obstacle="" if r.obstacle is None else self.obstacle_name(r.obstacle),
                    plant="" if r.plant is None else self.point_name(r.plant),
                    chosen="" if r.chosen is None else self.point_name(r.chosen),
                )
            )
        return listing(parts)

    def verdict(self, passed, causes) -> Verdict:
        """A :class:`Verdict` of ``passed`` (B,) and ``causes`` (B tuples of
        :class:`Reason`), with the words."""
        causes = tuple(tuple(c) for c in causes)
        return Verdict(np.asarray(passed, dtype=bool), causes, self.reason_words)

    @property
    @abstractmethod
    def test_points(self) -> np.ndarray:
        """B^: the test points, shape (n_conditions, point_dim)."""

    @property
    @abstractmethod
    def times(self) -> np.ndarray:
        """Times at which realisations are produced, shape (T,)."""

    @abstractmethod
    def frames(self, point) -> list[Frame]:
        """The task frames of one condition."""

    def frame_batch(self, points) -> FrameBatch:
        """Frames of many conditions; override for speed."""
        return FrameBatch.from_frames([self.frames(c) for c in np.asarray(points)])

    # ---------------------------------------------------------------- realisation

    #: r of the tracking controller's control cost R = r I (:mod:`tutor.tpgmm.tracking`)
    control_cost: float = DEFAULT_CONTROL_COST
    #: the leading coordinates the robot moves through (tracked from its start state);
    #: the others (a gripper) are commands it follows as the model gives them
    moving_dims: int | None = None

    def check_points(self, points, name: str = "points") -> np.ndarray:
        """``points`` as a finite float array (B, c) like the rows of :attr:`test_points`."""
        expected = np.asarray(self.test_points).shape[1:]
        shape = ", ".join(map(str, ("B", *expected)))
        wanted = f"a finite array of shape ({shape}) like task.test_points"
        array = check_real_array(points, name, InvalidParameterError, wanted)
        if array.ndim != 1 + len(expected) or array.shape[1:] != expected:
            raise InvalidParameterError(f"{name} must be {wanted}, got shape {array.shape}")
        if not np.isfinite(array).all():
            raise InvalidParameterError(f"{name} must be {wanted}; it holds NaN or inf")
        return array

    @abstractmethod
    def start_states(self, points) -> np.ndarray:
        """Where the robot is when it starts each of ``points``, at rest: shape (B, n)
        for the first n = :attr:`moving_dims` coordinates."""

    def commands(self, modelled: np.ndarray) -> np.ndarray:
        """The coordinates past :attr:`moving_dims` as the robot carries them out
        (B, T, d - n); default: as the model gives them."""
        return modelled

    def realise(self, learner, points=None) -> np.ndarray:
        r"""Lambda: the attempts the robot makes from ``points`` (default B^), (B, T, d).

        The learner's TP-GMR gives :math:`\mathcal N(\mu_t, \Sigma_t)` under each test
        point's frames; the robot, at rest at :meth:`start_states`, tracks it with the
        linear quadratic controller of :func:`tutor.tpgmm.tracking.track` (precision as
        the weight, control cost :attr:`control_cost`). So every attempt starts where
        the robot is, whatever the regression's first mean; the criteria judge this
        executed path.
        """
        if points is None or points is self.test_points:  # B^ itself: its frames are cached
            points = self.test_points
        else:
            points = self.check_points(points)
        if not callable(getattr(learner, "reproduce_batch", None)):
            raise InvalidParameterError(
                f"learner must be a fitted TPGMM (task.make_learner().fit(...)), got "
                f"{type(learner).__name__}"
            )
        mean, cov = learner.reproduce_batch(self.frame_batch(points), self.times)
        n = mean.shape[-1] if self.moving_dims is None else self.moving_dims
        precision = tracking_precision(cov[..., :n, :n])
        start = np.asarray(self.start_states(points), dtype=float)
        if start.shape != (mean.shape[0], n):
            raise InvalidParameterError(
                f"start_states must give shape {(mean.shape[0], n)}, got {start.shape}"
            )
        dt = float(self.times[1] - self.times[0])
        moved = track(mean[..., :n], precision, start, dt, self.control_cost)
        if n == mean.shape[-1]:
            return moved
        return np.concatenate([moved, self.commands(mean[..., n:])], axis=-1)

    @abstractmethod
    def preprocess(self, raw) -> np.ndarray:
        """Turn a raw recording into a demo (T, 1 + d), or raise InvalidDemoError."""

    @abstractmethod
    def test_point_of(self, demo: np.ndarray) -> np.ndarray:
        """The condition a (preprocessed) demo was given under."""

    def criteria_context(self, demos, points):
        """Anything the criteria derive from the demo set (e.g. thresholds); default None.

        Parameters
        ----------
        demos : list of ndarray (T, 1 + d)
        conditions : ndarray (M, c)
        """
        return None

    @abstractmethod
    def judge(self, trajectories: np.ndarray, points: np.ndarray, context=None) -> Verdict:
        """Apply the success criteria to trajectories (B, T, d) meant for conditions (B, c).

        ``context`` is what :meth:`criteria_context` returned for the current demos.
        """

    def judge_demo(self, demo: np.ndarray, point, context=None) -> Verdict:
        """Whether a demo (T, 1 + d) is a correct example for ``condition`` (b in B)."""
        return self.judge(demo[None, :, 1:], np.asarray(point)[None], context)

    def nearest_test_point(self, point) -> int:
        """Index in B^ of the test point closest to ``condition`` (for replays)."""
        gap = np.asarray(self.test_points, float) - np.asarray(point, float)
        return int(np.argmin(np.linalg.norm(gap.reshape(len(gap), -1), axis=1)))

    @abstractmethod
    def demonstrated(self, demo_points: np.ndarray) -> np.ndarray:
        """Mask (n_conditions,) of the test points that the demos' conditions cover."""

    @abstractmethod
    def describe_where(self, mask: np.ndarray) -> str:
        """Plain words for where the masked test points lie ("mostly bottom left")."""

    @abstractmethod
    def make_learner(self) -> TPGMM:
        """A fresh learner (lambda) for this task, with warm starts enabled."""

    def to_spec(self) -> dict:
        """What a run file records about the task, to rebuild it on loading."""
        return {"name": self.name}
