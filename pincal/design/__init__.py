"""Stage 3 — where to measure: observability indices and Jacobian scalings, candidate
poses, exchange / DETMAX / greedy selection, Cramér–Rao predictions.
"""

from __future__ import annotations

from pincal.design._candidates import (
    CandidateSet,
    candidate_set,
    default_grid_ranges,
    evaluate_candidates,
    grid_candidates,
    orthogonal_candidates,
    parse_candidate_spec,
    random_candidates,
)
from pincal.design._crb import (
    CramerRaoReport,
    Efficiency,
    cramer_rao,
    cramer_rao_from_jacobian,
    efficiency,
)
from pincal.design._exchange import (
    PoseSelection,
    bose_array,
    detmax,
    exchange,
    greedy,
    map_to_ranges,
    orthogonal_array,
)
from pincal.design._indices import (
    COLUMN_SCALINGS,
    INDEX_NAMES,
    ROW_SCALINGS,
    DesignScaling,
    JacobianScaling,
    ObservabilityIndices,
    characteristic_length,
    crb_covariance,
    dimensionless_rows,
    indices_from_singular_values,
    numerical_rank,
    observability,
    predicted_std,
    predicted_validation_rms,
    scale_columns,
    weight_rows,
)
from pincal.design._selection import (
    SELECTION_METHODS,
    PoseDesign,
    select_poses,
    write_pose_design,
)

__all__ = [
    "COLUMN_SCALINGS",
    "INDEX_NAMES",
    "ROW_SCALINGS",
    "SELECTION_METHODS",
    "CandidateSet",
    "CramerRaoReport",
    "DesignScaling",
    "Efficiency",
    "JacobianScaling",
    "ObservabilityIndices",
    "PoseDesign",
    "PoseSelection",
    "bose_array",
    "candidate_set",
    "characteristic_length",
    "cramer_rao",
    "cramer_rao_from_jacobian",
    "crb_covariance",
    "default_grid_ranges",
    "detmax",
    "dimensionless_rows",
    "efficiency",
    "evaluate_candidates",
    "exchange",
    "greedy",
    "grid_candidates",
    "indices_from_singular_values",
    "map_to_ranges",
    "numerical_rank",
    "observability",
    "orthogonal_array",
    "orthogonal_candidates",
    "parse_candidate_spec",
    "predicted_std",
    "predicted_validation_rms",
    "random_candidates",
    "scale_columns",
    "select_poses",
    "weight_rows",
    "write_pose_design",
]
