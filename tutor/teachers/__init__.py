"""Simulated teachers built on Sena & Howard's teacher model (Q, omega, Omega).

- :mod:`.traits`: the population of teachers, every parameter in one place
  (:class:`Population`, :class:`TeacherTraits`).
- :mod:`.model`: the interpretation omega (:class:`Belief`) and the demonstration
  function Omega shared by both tasks (:class:`TeacherModel`).
- :mod:`.maze`: Experiment 1's NF, VF and VR teachers (:class:`MazeTeacher`).
- :mod:`.pickplace`: Experiment 2's NF, RF, BF and SF teachers (:class:`PickPlaceTeacher`).

Cohorts and their statistics are in :mod:`tutor.study`.
"""

from .maze import MazeTeacher
from .model import Belief, TeacherModel
from .pickplace import PickPlaceTeacher
from .traits import DEFAULT_POPULATION, Population, TeacherTraits

#: task name -> the simulated teacher of that task
TEACHERS = {"maze": MazeTeacher, "pickplace": PickPlaceTeacher}

__all__ = [
    "Belief",
    "DEFAULT_POPULATION",
    "MazeTeacher",
    "PickPlaceTeacher",
    "Population",
    "TeacherModel",
    "TeacherTraits",
    "TEACHERS",
]
