"""Stage 8 — a calibration as the commands run it, callable from Python.

The orchestration of a calibration — read the data, settle the settings the data
decide, fit, judge, cross-validate — is here, under the command line; a command parses
its options, calls one function of this stage and prints what it returns. Nothing here
prints or writes files.

- :func:`calibrate_markers` (``pincal calibrate --link``): a marker table in an
  unknown instrument frame, with the defaults of real data (:class:`MarkerSettings`);
  :func:`rebuild` and :func:`replay_procedure` run it again for ``validate --cv``;
  :func:`transfer_markers` carries it to another session (``validate --data``).
- fleets (``pincal fleet``): :func:`draw_fleet` / :func:`simulate_unit` simulate a
  production line with planted faulty units; :func:`fleet_statistics` flags the units
  out of family, each judged with its own covariance.
- compensation (``pincal compensate``): :func:`compensate_targets` gives the commands
  of a targets file (:class:`TargetCompensation`, starts from :func:`nominal_starts`);
  :func:`compensate_program` rewrites a G-code program's moves
  (:class:`CompensatedProgram`).
- views (``pincal view``): :func:`view_poses` gives the poses drawn,
  :func:`prediction_changes` the nominal → calibrated arrows at each.
"""

from __future__ import annotations

from pincal.workflow._fleet_draw import FleetDraw, draw_fleet, simulate_unit
from pincal.workflow._fleet_stats import (
    FleetStatistics,
    UnitEstimate,
    UnitVerdict,
    fleet_statistics,
)
from pincal.workflow._marker_replay import rebuild, replay_procedure
from pincal.workflow._marker_run import (
    MISFIT_RMS,
    ROBUST_LOSS,
    MarkerRun,
    calibrate_markers,
    marker_procedure,
)
from pincal.workflow._marker_settings import PRIOR_GRID, MarkerSettings, parse_prior
from pincal.workflow._prior_choice import (
    PriorChoice,
    choose_prior,
    cross_validated,
    nested_choice,
)
from pincal.workflow._program_compensation import CompensatedProgram, compensate_program
from pincal.workflow._target_compensation import (
    TargetCompensation,
    compensate_targets,
    nominal_starts,
)
from pincal.workflow._transfer import transfer_markers
from pincal.workflow._view_poses import (
    PredictionChanges,
    ViewPoses,
    prediction_changes,
    view_poses,
)

__all__ = [
    "MISFIT_RMS",
    "PRIOR_GRID",
    "ROBUST_LOSS",
    "CompensatedProgram",
    "FleetDraw",
    "FleetStatistics",
    "MarkerRun",
    "MarkerSettings",
    "PredictionChanges",
    "PriorChoice",
    "TargetCompensation",
    "UnitEstimate",
    "UnitVerdict",
    "ViewPoses",
    "calibrate_markers",
    "choose_prior",
    "compensate_program",
    "compensate_targets",
    "cross_validated",
    "draw_fleet",
    "fleet_statistics",
    "marker_procedure",
    "nested_choice",
    "nominal_starts",
    "parse_prior",
    "prediction_changes",
    "rebuild",
    "replay_procedure",
    "simulate_unit",
    "transfer_markers",
    "view_poses",
]
