"""The steadiness check of a maze's geometry (tutor.study.steadiness)."""

from __future__ import annotations

import pytest

from tutor.study import calibration
from tutor.study.steadiness import MAX_FALL, steadiness, steadiness_of_blocks

#: the blocks a 2026-12-06 calibration chose (16.9 cm in): hard through an unsteady learner
UNSTEADY = (0.169, 0.082, 0.033, 0.041)


def test_the_bundled_maze_is_steady():
    found = steadiness()
    assert found.steady and found.median_fall <= MAX_FALL
    assert max(found.needed) <= 4  # a guided teacher reaches 90 % with 3 or 4 demos


def test_narrow_side_gaps_make_the_learner_unsteady():
    found = steadiness_of_blocks(UNSTEADY)
    assert not found.steady and found.median_fall > 2 * MAX_FALL
    assert steadiness_of_blocks(UNSTEADY) is found  # remembered per geometry
    assert steadiness_of_blocks((0.15, 0.09, 0.035, 0.04)).steady


def test_the_calibration_simulates_nothing_on_an_unsteady_maze():
    theta = {n: p.from_unit(0.5) for n, p in calibration.PARAMETERS.items()}
    theta.update(maze_reach=0.169, maze_low=0.082, maze_height=0.033)
    population, settings = calibration.apply(theta)
    assert not steadiness_of_blocks(tuple(settings.maze_blocks)).steady
    stats = calibration.simulate(theta, 0, 3, 2, engine=None)
    assert stats == {}
    fitted = sum(s.fitted for s in calibration.STATISTICS.values())
    assert calibration.distance(stats) == pytest.approx(4 * fitted**0.5)  # far from the paper
