"""Machine-specific closed forms kept outside the generic core (wedge, hexaslide).
"""

from __future__ import annotations

from pincal.machines._hexaslide import (
    LegGeometry,
    leg_geometry,
    legs_from_table,
    pus54_values,
)
from pincal.machines._wedge import (
    PATENT_ERROR_NAMES,
    PATENT_PRESET_NAMES,
    WedgeConstraintJacobians,
    WedgeGeometry,
    WedgeSensitivity,
    wedge_compensation,
    wedge_constraint_jacobians,
    wedge_constraints,
    wedge_error_matrix,
    wedge_forward,
    wedge_global_sensitivity,
    wedge_inverse,
    wedge_patent_error_matrix,
    wedge_urdf,
    wedge_workspace_grid,
)

__all__ = [
    "PATENT_ERROR_NAMES",
    "PATENT_PRESET_NAMES",
    "LegGeometry",
    "WedgeConstraintJacobians",
    "WedgeGeometry",
    "WedgeSensitivity",
    "leg_geometry",
    "legs_from_table",
    "pus54_values",
    "wedge_compensation",
    "wedge_constraint_jacobians",
    "wedge_constraints",
    "wedge_error_matrix",
    "wedge_forward",
    "wedge_global_sensitivity",
    "wedge_inverse",
    "wedge_patent_error_matrix",
    "wedge_urdf",
    "wedge_workspace_grid",
]
