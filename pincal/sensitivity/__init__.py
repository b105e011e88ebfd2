"""Stage 2 — how errors show.

The analytic identification Jacobian, identifiability
(rank, base set, absorbed combinations, parameters that break loop closure), the one
numerical-rank rule, the bound beyond which the poses do not place a parameter
(:data:`PLACEMENT_BOUND`), global sensitivity over a workspace, and :func:`parameters` — the
preset resolver with the ``"base"`` preset computed here (later stages resolve preset
names through it).
"""

from __future__ import annotations

from pincal.sensitivity._base_set import BASE_POSES, BaseSet, base_parameters, base_set
from pincal.sensitivity._closure_loops import ClosureLoop, closure_line, closure_loops
from pincal.sensitivity._global import (
    GlobalSensitivity,
    global_sensitivity,
    global_sensitivity_from_jacobians,
)
from pincal.sensitivity._identifiability import (
    BASE_RTOL,
    Identifiability,
    analyse_jacobian,
    identifiability,
)
from pincal.sensitivity._identification_jacobian import (
    closure_breaking,
    identification_jacobian,
)
from pincal.sensitivity._jacobian import BatchSensitivity, PoseSensitivity, pose_sensitivity
from pincal.sensitivity._placement import (
    PLACEMENT_BOUND,
    beyond_placement,
    placement_limits,
    placement_words,
)
from pincal.sensitivity._presets import COMPUTED_PRESETS, parameters
from pincal.sensitivity._rank import (
    RANK_RTOL,
    RangeSolver,
    full_jacobian_ranks,
    jacobian_rank,
    numerical_rank,
    numerical_ranks,
    unit_columns,
)
from pincal.sensitivity.batch import sensitivities_batch

__all__ = [
    "BASE_POSES",
    "BASE_RTOL",
    "COMPUTED_PRESETS",
    "PLACEMENT_BOUND",
    "RANK_RTOL",
    "BaseSet",
    "BatchSensitivity",
    "ClosureLoop",
    "GlobalSensitivity",
    "Identifiability",
    "PoseSensitivity",
    "RangeSolver",
    "analyse_jacobian",
    "base_parameters",
    "base_set",
    "beyond_placement",
    "closure_breaking",
    "closure_line",
    "closure_loops",
    "full_jacobian_ranks",
    "global_sensitivity",
    "global_sensitivity_from_jacobians",
    "identifiability",
    "identification_jacobian",
    "jacobian_rank",
    "numerical_rank",
    "numerical_ranks",
    "parameters",
    "placement_limits",
    "placement_words",
    "pose_sensitivity",
    "sensitivities_batch",
    "unit_columns",
]
