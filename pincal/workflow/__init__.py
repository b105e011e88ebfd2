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
- models described (``pincal info``): :func:`structure_lines` and
  :func:`describe_presets` (each preset's identifiability, the base set offered as a
  preset, :func:`base_line`); :func:`reduction_line` says a preset was reduced to it.
- measurement poses (``pincal poses``): :func:`pose_basis`, :func:`pose_candidates` and
  :func:`select_pose_design` (screens, selection, travel order, Cramér–Rao prediction:
  :class:`PoseSelection`); the reach screen compensates each candidate on displaced
  models (:func:`compensation_test`, :func:`controlled_components`).
- simulated campaigns (``pincal simulate``): :func:`simulate_campaign` measures the
  nominal model with random errors (none a built machine cannot have,
  :func:`buildable_mask`) at the poses it reaches (:func:`reachable_rows`), as poses, a
  scalar instrument's readings or a ball seated in two sockets (:func:`default_sockets`).
"""

from __future__ import annotations

from pincal.workflow._buildable import buildable_mask
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
from pincal.workflow._model_description import (
    ModelDescription,
    base_line,
    describe_presets,
    reduction_line,
    structure_lines,
)
from pincal.workflow._pose_selection import (
    PoseBasis,
    PoseRequest,
    PoseSelection,
    pose_basis,
    pose_candidates,
    select_pose_design,
)
from pincal.workflow._prior_choice import (
    PriorChoice,
    choose_prior,
    cross_validated,
    nested_choice,
)
from pincal.workflow._reach_screen import DRAWS, compensation_test, controlled_components
from pincal.workflow._simulation import (
    SOCKET_SPACING,
    SimulatedCampaign,
    ThermalDraw,
    default_sockets,
    reachable_rows,
    simulate_campaign,
)
from pincal.workflow._transfer import transfer_markers

__all__ = [
    "DRAWS",
    "MISFIT_RMS",
    "PRIOR_GRID",
    "ROBUST_LOSS",
    "SOCKET_SPACING",
    "FleetDraw",
    "FleetStatistics",
    "MarkerRun",
    "MarkerSettings",
    "ModelDescription",
    "PoseBasis",
    "PoseRequest",
    "PoseSelection",
    "PriorChoice",
    "SimulatedCampaign",
    "ThermalDraw",
    "UnitEstimate",
    "UnitVerdict",
    "base_line",
    "buildable_mask",
    "calibrate_markers",
    "choose_prior",
    "compensation_test",
    "controlled_components",
    "cross_validated",
    "default_sockets",
    "describe_presets",
    "draw_fleet",
    "fleet_statistics",
    "marker_procedure",
    "nested_choice",
    "parse_prior",
    "pose_basis",
    "pose_candidates",
    "reachable_rows",
    "rebuild",
    "reduction_line",
    "replay_procedure",
    "select_pose_design",
    "simulate_campaign",
    "simulate_unit",
    "structure_lines",
    "transfer_markers",
]
