"""Machine-specific closed forms kept outside the generic core (wedge, hexaslide)."""

from __future__ import annotations

from pincal.machines._hexaslide import (
    LegGeometry,
    leg_geometry,
    legs_from_table,
    pus54_values,
)
from pincal.machines._wedge import (
    WedgeConstraintJacobians,
    WedgeGeometry,
    wedge_constraint_jacobians,
    wedge_constraints,
    wedge_forward,
    wedge_inverse,
)
from pincal.machines._wedge_errors import (
    PATENT_ERROR_NAMES,
    PATENT_PRESET_NAMES,
    WedgeSensitivity,
    wedge_compensation,
    wedge_error_matrix,
    wedge_global_sensitivity,
    wedge_patent_error_matrix,
    wedge_workspace_grid,
)
from pincal.machines._wedge_urdf import (
    wedge_urdf,
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
