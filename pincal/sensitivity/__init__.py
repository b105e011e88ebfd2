"""Stage 2 — how errors show: the analytic identification Jacobian, identifiability
(rank, base set, absorbed combinations) and global sensitivity over a workspace.
"""

from __future__ import annotations

from pincal.sensitivity._global import (
    GlobalSensitivity,
    global_sensitivity,
    global_sensitivity_from_jacobians,
)
from pincal.sensitivity._identifiability import (
    Identifiability,
    analyse_jacobian,
    identifiability,
)
from pincal.sensitivity._jacobian import (
    PoseSensitivity,
    identification_jacobian,
    pose_sensitivity,
)

__all__ = [
    "GlobalSensitivity",
    "Identifiability",
    "PoseSensitivity",
    "analyse_jacobian",
    "global_sensitivity",
    "global_sensitivity_from_jacobians",
    "identifiability",
    "identification_jacobian",
    "pose_sensitivity",
]
