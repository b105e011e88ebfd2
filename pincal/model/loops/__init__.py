"""Closed-loop kinematics, one pose at a time.

Kinematics of one pose: frame queries, Newton on the loop closures,
the assembly at home, the branch-following loop solver and the inverse configuration.
"""

from __future__ import annotations

from pincal.model.loops._assembly import Assembly, model_size
from pincal.model.loops._branch import CORRECTOR_ITERATIONS, MIN_STEP, LoopSolver
from pincal.model.loops._fixing import fixing_components
from pincal.model.loops._inverse import check_actuator_limits, inverse_configuration
from pincal.model.loops._jacobian_shape import six_by_nv
from pincal.model.loops._kinematics import KinematicQueries, Kinematics, frame_index
from pincal.model.loops._newton import REDUNDANT_RTOL, SolverOptions

__all__ = [
    "CORRECTOR_ITERATIONS",
    "MIN_STEP",
    "REDUNDANT_RTOL",
    "Assembly",
    "KinematicQueries",
    "Kinematics",
    "LoopSolver",
    "SolverOptions",
    "check_actuator_limits",
    "fixing_components",
    "frame_index",
    "inverse_configuration",
    "model_size",
    "six_by_nv",
]
