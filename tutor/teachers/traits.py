r"""Who the simulated teachers are: every parameter of the population in one place.

Sena & Howard model a teacher by their human factors Q, an interpretation
:math:`\tilde R = \omega(r, Q)` of the realisations r they are shown, and a
demonstration function :math:`b_{m+1} = \Omega(\tilde R, \tilde B, b_m, Q)`. The tutor's
simulated teachers follow that model. This module holds Q: :class:`Population`
describes how people differ (the distributions), :class:`TeacherTraits` is one person
drawn from it.

**One population, every condition.** A teacher's traits are drawn once and used
unchanged in every condition they teach under (Experiment 1: the same person does NF,
VF and VR; Experiment 2: the same kind of person is assigned to NF, RF, BF or SF).
No trait depends on the condition. A condition changes only what the teacher sees
(r) and what that costs in time, so every difference between conditions in a
simulated cohort comes from the information shown and the clock.

The paper does not measure any of these traits. The defaults of :class:`Population`
that the paper's numbers constrain (the maze and tray priors and scatters, the least
precise aim, the lowest satisfaction, the repeat and slip rates, the set-up time and
heed) are the point of the bundled calibration (``lfd-tutor calibrate``,
:mod:`tutor.study.calibration`; its report is ``tutor/assets/calibration``), written
here by ``scripts/apply_calibration.py``; the others are our judgement of novices.
Either way they are chosen once for the whole population and never per condition, and
written down so an educator can change them and see what follows.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numpy as np

from ..errors import InvalidParameterError
from ..limits import MAX_DEMOS_PER_RUN

__all__ = ["Population", "TeacherTraits", "DEFAULT_POPULATION", "TASKS"]

#: the tasks a teacher's per-task traits are kept for
TASKS = ("maze", "pickplace")


@dataclass(frozen=True)
class TeacherTraits:
    """One simulated teacher's human factors Q (the same in every condition).

    Positions on B^ are in *unit-box* coordinates: (0, 0) and (1, 1) are the opposite
    corners of the test grid (the maze's start grid, the plant tray).

    Attributes
    ----------
    enough_maze, enough_pickplace : int
        How many demonstrations the teacher believes the robot needs for the maze and
        for pick-and-place (one personal factor times the population's median for the
        task, so an optimist is optimistic about both). With nothing shown (NF), this
        prior is all they have: they stop after this many demos.
    plan_focus : tuple of float
        The part of B^ the teacher habitually demonstrates from (unit box).
    plan_spread_maze, plan_spread_pickplace : float
        How widely their own plan scatters demos around the focus in the maze and on
        the plant tray (unit box, standard deviation; one personal factor times the
        population's median for the task, like ``enough_*``). Small: demos cluster
        (ambiguous demos, undemonstrated states).
    plan_choices_maze, plan_choices_pickplace : int
        How many places from their plan they weigh for the next demo of their own
        choosing, taking the one farthest from the demos already given (1: the first
        place that comes to mind).
    aim_sd : float
        Imprecision when aiming at a place they chose (unit box, standard deviation):
        reading a red region off the picture, a circle, or which plant to pick.
    motor_noise : float
        Maze: wobble of the hand during a stroke (metres, standard deviation of the
        path's deviation). Pick-and-place uses the task's own model of a guiding hand.
    slip_rate : float
        Chance that one demonstration is a slip: in the maze the stroke cuts an
        obstacle's corner; in pick-and-place the hand goes to a neighbouring plant.
    satisfaction : float
        Share of B^ the teacher must believe the robot succeeds at before stopping
        (their belief, not the truth).
    patience : int
        The most demonstrations they are willing to give in one run.
    setup_seconds : float
        Pick-and-place: time per demo besides the motion (point at the plant, the
        experimenter sets the target, the arm goes back to its start).
    test_rate : float
        Pick-and-place SF: chance of asking the robot to try plants after a demo.
    notice_rate : float
        Chance that, watching the robot perform the plant they just demonstrated,
        they notice their demo went to the wrong plant (they then redo it). Only
        possible when r includes that plant: always in RF, sometimes in BF and SF.
    repeat_rate : float
        Chance that a demo from their own plan deliberately repeats one they already
        gave ("showing it again helps"): the paper's ambiguous demonstrations.
    compliance : float
        Chance that they demonstrate the plant the next-demo hint names (HF, beyond the
        paper) instead of one of their own choosing. Used only in HF. A teacher made by
        hand rather than drawn from a :class:`Population` follows half the hints.
    heed : float
        Chance that, with failures shown on the picture (VF, VR; RF, BF, SF), they
        choose the next demo by reading the picture (its worst red region) rather than
        from their own plan. People look at feedback without always acting on it; 1
        (the default) always acts on it. It changes nothing where nothing is shown (NF).
    """

    enough_maze: int
    enough_pickplace: int
    plan_focus: tuple[float, float]
    plan_spread_maze: float
    plan_spread_pickplace: float
    plan_choices_maze: int
    plan_choices_pickplace: int
    aim_sd: float
    motor_noise: float
    slip_rate: float
    satisfaction: float
    patience: int
    setup_seconds: float
    test_rate: float
    notice_rate: float
    repeat_rate: float
    compliance: float = 0.5
    heed: float = 1.0

    def _for(self, trait: str, task: str):
        if task not in TASKS:
            raise InvalidParameterError(
                f"task must be one of {', '.join(map(repr, TASKS))}, got {task!r}"
            )
        return getattr(self, f"{trait}_{task}")

    def enough_demos(self, task: str) -> int:
        """The prior count for ``task`` ("maze" or "pickplace")."""
        return self._for("enough", task)

    def plan_spread(self, task: str) -> float:
        """How widely their own plan scatters demos for ``task`` ("maze" or "pickplace")."""
        return self._for("plan_spread", task)

    def plan_choices(self, task: str) -> int:
        """How many plan places they weigh for ``task`` ("maze" or "pickplace")."""
        return self._for("plan_choices", task)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["plan_focus"] = list(self.plan_focus)
        return d


@dataclass(frozen=True)
class Population:
    """How novice teachers differ from one another: the distributions traits come from.

    Every field is documented with the distribution it parametrises; change a value
    here to simulate a different population (e.g. more careful teachers). The values
    the notes below reason about are the hand-set ones that came before the
    calibration; the notes still say what each field means and what the paper says
    about it, and the calibration's priors are in :mod:`tutor.study.calibration`.

    Attributes
    ----------
    enough_median_maze, enough_median_pickplace, enough_sigma, enough_range
        ``enough_*`` = round(median * z) clipped to the range, with one personal
        z ~ lognormal(0, sigma) for both tasks. Maze: the paper's unguided teachers
        "tend to underestimate the number of demonstrations required" and 7 of 30 did
        well without feedback; with this learner, teachers who see R^ need 4-5 demos,
        so the median prior is 4. Pick-and-place: the paper gives no demo counts, but
        its NF numbers imply them. 499 undemonstrated states over 27 NF runs leave
        about 81.5 % of the 100 plants succeeding at the end of a run; with that
        efficacy, NF's mean eta of 12.8 % (a mean of eps / |b| over runs) needs a mean
        of 1 / |b| near 0.157. Drawn as above, median 6 gives mean 1 / |b| = 0.185
        (eta 15.1 %), median 7 gives 0.160 (eta 13.0 %), median 8 gives 0.141
        (11.5 %); the median prior is 7 (mean 7.4 demos). (It was 6 until the
        undemonstrated-state check below; 7 was chosen knowing that it moves BF
        towards the paper's "most undemonstrated", see ``setup_low``.)
    focus_sd
        ``plan_focus`` ~ normal around the centre of B^ (unit box), clipped to it.
    spread_median_maze, spread_median_pickplace, spread_sigma
        ``plan_spread_*`` = median * s with one personal s ~ lognormal(0, sigma) for
        both tasks (a teacher who scatters widely does so on both). Maze, median
        0.22: the paper's failure pictures show demos co-located (ambiguous) and not
        covering the space (undemonstrated). Pick-and-place, median 0.5 (half the
        tray's width around the focus): the paper's teachers *without* feedback
        ended their runs with about 81.5 % (NF: 499 undemonstrated states in 27 runs)
        and 82 % (SF: 485) of the plants succeeding, from about 7 demos of which about
        2 per run were ambiguous (NF: 54). Only demos spread over the tray do that;
        with this learner, 6-7 demos clustered at scatter 0.22 leave 55-65 % of the
        tray succeeding. Asked to teach "pick any plant", people pick plants all over
        the tray. Their co-located demos come from ``repeat_rate`` instead.
    plan_choices_maze, plan_choices_pickplace
        Every teacher's ``plan_choices_*`` (the same for all). Maze, 1: the paper's
        unguided maze demos sit together. Pick-and-place, 2: set from the paper's NF
        condition, which shows the teachers' unaided plan: 499 undemonstrated states in
        27 runs (81.5 % of the tray succeeding) and mean eta 12.8 %. Measured on 60
        simulated NF teachers x 3 runs (:class:`PickPlaceTeacher`, rng seeds [99, i],
        task without the arm check; final efficacy and eta of each run): weighing
        1 place gives 72.9 % and eta 10.9 %, 2 places 83.1 % and 13.1 %, 3 places
        86.4 % and 13.7 %, 5 places 80.6 % and 12.5 %. Chosen from NF alone, before
        rerunning the cohorts, though knowing that better-spread unaided demos leave
        fewer undemonstrated states in NF, RF and SF, and that BF chooses its demos
        from the five samples instead.
    aim_low, aim_high
        ``aim_sd`` ~ uniform (unit box: 0.04 of the maze's 19 cm grid is 8 mm).
    motor_low, motor_high
        ``motor_noise`` ~ uniform, metres (the paper's trackers: +-1 mm; hands: a few mm).
    slip_a, slip_b
        ``slip_rate`` ~ beta(a, b): about 3 % of demos on average (the paper's NF
        teachers left 4 wrong-plant demos in roughly 160).
    satisfaction_low, satisfaction_high
        ``satisfaction`` ~ uniform.
    patience_low, patience_high
        ``patience`` ~ uniform integer (inclusive).
    setup_low, setup_high
        ``setup_seconds`` ~ uniform (s per pick-and-place demo besides the guided
        motion, which the task times at about 10 s): naming and marking the plant,
        the teacher taking the 7-DoF arm, pressing the hand's button twice, the arm
        going back to its start pose and the plant being put back. From the paper's
        BF numbers: mean eta 23.5 % with about 69 % of plants succeeding (827
        undemonstrated states in 27 runs) means about 3 demos kept per run, and the
        paper says BF teachers stopped early *or ran out of the 15 minutes*. With
        about 3 kept and 1-2 redone (seen failing at the demonstrated plant), a run
        that fills 900 s holds 4-5 cycles of one demo plus the 125 s of the five
        samples: 180-225 s a cycle, i.e. 55-100 s per demo, about 75 s of it set-up
        (uniform 50-100 s). The other conditions fit the same clock: about 7 NF demos
        at 85 s take 10 minutes; RF's 5-6 demos plus replays and redone demos at
        110 s take 13-14. (Until the undemonstrated-state check, set-up was 20-45 s
        and BF teachers reached 87 % of the tray with 3-4 demos, leaving the fewest
        undemonstrated states in 10 of 10 seeds.)
    test_low, test_high
        ``test_rate`` ~ uniform.
    notice_low, notice_high
        ``notice_rate`` ~ uniform (the paper: replays "help them spot errors as they
        happen"; its RF teachers left no wrong-plant demo).
    repeat_a, repeat_b
        ``repeat_rate`` ~ beta(a, b), mean 0.15: the paper counts ambiguous demos
        (demos that add nothing, e.g. co-located ones) in every condition.
    compliance_low, compliance_high
        ``compliance`` ~ uniform (mean 0.7), drawn last so that every other trait of a
        teacher is the same draw as before the trait existed. The paper has no hint
        condition and measures nothing like it; our judgement of novices told "the
        robot would learn most from this plant next" is that most follow it most of
        the time and some prefer their own plan. The adaptive study sets it to 0.5 and
        1 instead (``dataclasses.replace``) to bracket the effect.
    heed_low, heed_high
        ``heed`` ~ uniform (the calibration's 0-0.42; both 1 would have every teacher
        read the picture every time, as the hand-set teachers did). Drawn after
        ``compliance`` and only when the two differ, so a population whose teachers all
        heed draws every other trait exactly as before the trait existed. A free
        parameter of the calibration (:mod:`tutor.study.calibration`).
    """

    enough_median_maze: float = 2.8887
    enough_median_pickplace: float = 5.2197
    enough_sigma: float = 0.45
    enough_range: tuple[int, int] = (2, 12)
    focus_sd: float = 0.2
    spread_median_maze: float = 0.3066
    spread_median_pickplace: float = 0.3086
    spread_sigma: float = 0.5
    plan_choices_maze: int = 1
    plan_choices_pickplace: int = 2
    aim_low: float = 0.02
    aim_high: float = 0.0694
    motor_low: float = 0.002
    motor_high: float = 0.005
    slip_a: float = 2.32
    slip_b: float = 47.68
    satisfaction_low: float = 0.8037
    satisfaction_high: float = 1.0
    patience_low: int = 12
    patience_high: int = 20
    setup_low: float = 13.0062
    setup_high: float = 63.0062
    test_low: float = 0.3
    test_high: float = 0.8
    notice_low: float = 0.7
    notice_high: float = 1.0
    repeat_a: float = 2.28
    repeat_b: float = 7.72
    compliance_low: float = 0.4
    compliance_high: float = 1.0
    heed_low: float = 0.0
    heed_high: float = 0.4205

    def __post_init__(self):
        lo, hi = self.enough_range
        checks = [
            (1 <= lo <= hi, f"enough_range must be 1 <= low <= high, got {self.enough_range}"),
            (
                self.enough_median_maze > 0 and self.enough_median_pickplace > 0,
                "enough_median_maze and enough_median_pickplace must be > 0",
            ),
            (
                min(self.plan_choices_maze, self.plan_choices_pickplace) >= 1,
                "plan_choices_maze and plan_choices_pickplace must be >= 1",
            ),
            (0 < self.aim_low <= self.aim_high, "need 0 < aim_low <= aim_high"),
            (0 <= self.motor_low <= self.motor_high, "need 0 <= motor_low <= motor_high"),
            (self.slip_a > 0 and self.slip_b > 0, "slip_a and slip_b must be > 0"),
            (
                0 < self.satisfaction_low <= self.satisfaction_high <= 1,
                "need 0 < satisfaction_low <= satisfaction_high <= 1",
            ),
            (1 <= self.patience_low <= self.patience_high, "need 1 <= patience_low <= high"),
            (
                self.patience_high <= MAX_DEMOS_PER_RUN,
                f"patience_high must be at most {MAX_DEMOS_PER_RUN}, the most demos a run "
                "can have (tutor.limits.MAX_DEMOS_PER_RUN)",
            ),
            (0 <= self.setup_low <= self.setup_high, "need 0 <= setup_low <= setup_high"),
            (0 <= self.test_low <= self.test_high <= 1, "need 0 <= test_low <= test_high <= 1"),
            (
                0 <= self.notice_low <= self.notice_high <= 1,
                "need 0 <= notice_low <= notice_high <= 1",
            ),
            (self.repeat_a > 0 and self.repeat_b > 0, "repeat_a and repeat_b must be > 0"),
            (
                0 <= self.compliance_low <= self.compliance_high <= 1,
                "need 0 <= compliance_low <= compliance_high <= 1",
            ),
            (0 <= self.heed_low <= self.heed_high <= 1, "need 0 <= heed_low <= heed_high <= 1"),
        ]
        for ok, message in checks:
            if not ok:
                raise InvalidParameterError(f"Population: {message}")

    def sample(self, rng) -> TeacherTraits:
        """Draw one teacher (uses ``rng``, a numpy Generator, in a fixed order; the
        traits are drawn in the order of :class:`TeacherTraits`' fields)."""
        rng = np.random.default_rng(rng)
        lo, hi = self.enough_range
        z = rng.lognormal(0, self.enough_sigma)
        maze = int(np.clip(np.rint(self.enough_median_maze * z), lo, hi))
        pickplace = int(np.clip(np.rint(self.enough_median_pickplace * z), lo, hi))
        focus = np.clip(0.5 + rng.normal(0, self.focus_sd, 2), 0.0, 1.0)
        spread = float(rng.lognormal(0, self.spread_sigma))
        return TeacherTraits(
            enough_maze=maze,
            enough_pickplace=pickplace,
            plan_focus=(float(focus[0]), float(focus[1])),
            plan_spread_maze=float(self.spread_median_maze * spread),
            plan_spread_pickplace=float(self.spread_median_pickplace * spread),
            plan_choices_maze=int(self.plan_choices_maze),
            plan_choices_pickplace=int(self.plan_choices_pickplace),
            aim_sd=float(rng.uniform(self.aim_low, self.aim_high)),
            motor_noise=float(rng.uniform(self.motor_low, self.motor_high)),
            slip_rate=float(rng.beta(self.slip_a, self.slip_b)),
            satisfaction=float(rng.uniform(self.satisfaction_low, self.satisfaction_high)),
            patience=int(rng.integers(self.patience_low, self.patience_high + 1)),
            setup_seconds=float(rng.uniform(self.setup_low, self.setup_high)),
            test_rate=float(rng.uniform(self.test_low, self.test_high)),
            notice_rate=float(rng.uniform(self.notice_low, self.notice_high)),
            repeat_rate=float(rng.beta(self.repeat_a, self.repeat_b)),
            # last: the draws of every trait above are those of a population without it
            compliance=float(rng.uniform(self.compliance_low, self.compliance_high)),
            heed=(
                float(self.heed_low) if self.heed_low == self.heed_high
                else float(rng.uniform(self.heed_low, self.heed_high))
            ),
        )

    def to_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}


DEFAULT_POPULATION = Population()
