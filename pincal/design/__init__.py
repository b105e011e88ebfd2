"""Stage 4 — where to measure.

Observability indices and Jacobian scalings, candidate
poses, screens for poses a machine can execute (limits, singularities, collisions),
exchange / DETMAX / greedy selection, Cramér–Rao predictions.

The files of a selection are written by :func:`pincal.io.write_pose_design`.
"""

from __future__ import annotations

from pincal.design._arrays import bose_array, map_to_ranges, orthogonal_array
from pincal.design._bounds import crb_covariance, predicted_std, predicted_validation_rms
from pincal.design._candidate_sources import (
    default_grid_ranges,
    grid_candidates,
    orthogonal_candidates,
    random_candidates,
)
from pincal.design._candidate_specs import (
    AUTO_LEAST,
    AUTO_ROWS,
    candidate_set,
    parse_candidate_spec,
)
from pincal.design._candidates import (
    MAX_CANDIDATE_BYTES,
    MAX_CANDIDATES,
    CandidateCost,
    CandidateSet,
    candidate_cost,
    evaluate_candidates,
)
from pincal.design._collisions import Box, CollisionChecker, parse_box
from pincal.design._crb import (
    CramerRaoReport,
    Efficiency,
    cramer_rao,
    cramer_rao_from_jacobian,
    efficiency,
)
from pincal.design._exchange import PoseSelection, detmax, exchange, greedy
from pincal.design._indices import (
    INDEX_NAMES,
    ObservabilityIndices,
    batch_indices,
    indices_from_singular_values,
    numerical_rank,
    observability,
)
from pincal.design._ordering import PoseOrder, travel_order
from pincal.design._scaling import (
    COLUMN_SCALINGS,
    ROW_SCALINGS,
    DesignScaling,
    JacobianScaling,
    characteristic_length,
    dimensionless_rows,
    scale_columns,
    weight_rows,
)
from pincal.design._screens import (
    SCREENS,
    ScreenReport,
    ScreenSettings,
    actuator_sigma_min,
    scaled_actuator_jacobians,
    screen_candidates,
)
from pincal.design._selection import SELECTION_METHODS, PoseDesign, select_poses

__all__ = [
    "AUTO_LEAST",
    "AUTO_ROWS",
    "COLUMN_SCALINGS",
    "INDEX_NAMES",
    "MAX_CANDIDATES",
    "MAX_CANDIDATE_BYTES",
    "ROW_SCALINGS",
    "SCREENS",
    "SELECTION_METHODS",
    "Box",
    "CandidateCost",
    "CandidateSet",
    "CollisionChecker",
    "CramerRaoReport",
    "DesignScaling",
    "Efficiency",
    "JacobianScaling",
    "ObservabilityIndices",
    "PoseDesign",
    "PoseOrder",
    "PoseSelection",
    "ScreenReport",
    "ScreenSettings",
    "actuator_sigma_min",
    "batch_indices",
    "bose_array",
    "candidate_cost",
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
    "parse_box",
    "parse_candidate_spec",
    "predicted_std",
    "predicted_validation_rms",
    "random_candidates",
    "scale_columns",
    "scaled_actuator_jacobians",
    "screen_candidates",
    "select_poses",
    "travel_order",
    "weight_rows",
]
