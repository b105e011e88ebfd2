"""Stage 8 — a calibration as the commands run it, callable from Python.

The orchestration of a calibration — read the data, settle the settings the data
decide, fit, judge, cross-validate — is here, under the command line; a command parses
its options, calls one function of this stage and prints what it returns. Nothing here
prints or writes files.

- :func:`calibrate_markers` (``pincal calibrate --link``): a marker table in an
  unknown instrument frame, with the defaults of real data (:class:`MarkerSettings`);
  :func:`rebuild` and :func:`replay_procedure` run it again for ``validate --cv``;
  :func:`transfer_markers` carries it to another session (``validate --data``).
- ISO 9283 acceptance (``pincal acceptance``): :func:`measured_characteristics` of
  measured repeated poses, or the test cube (:func:`cube_doc`) cycled by
  :func:`cycle_characteristics` on an :func:`acceptance_machine` commanded by the
  nominal or the calibrated model (:func:`calibrated_controller`); :func:`other_machine`
  warns when the simulated machine is not the calibration's.
- cross-validation (``pincal validate --cv``): :func:`cross_validate_calibration`
  refits each fold as calibrate ran it (a marker table, a pose file, ball-in-socket
  seatings) beside its baseline; :func:`fold_table` lists the folds as CSV text.
- a held-out file (``pincal validate --data``): :func:`read_held_out` reads it as the
  calibration's data was; :func:`validate_on_data` returns the before / after errors
  (:class:`DataValidation`, joint terms, further markers, transfer to its session).
- fleets (``pincal fleet``): :func:`draw_fleet` / :func:`simulate_unit` simulate a
  production line with planted faulty units; :func:`fleet_statistics` flags the units
  out of family, each judged with its own covariance.
"""

from __future__ import annotations

from pincal.workflow._acceptance import (
    AcceptanceMachine,
    acceptance_machine,
    calibrated_controller,
    cube_doc,
    cycle_characteristics,
    measured_characteristics,
    other_machine,
)
from pincal.workflow._cross_validation import cross_validate_calibration, fold_table
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
from pincal.workflow._transfer import transfer_markers
from pincal.workflow._validate_data import (
    DataValidation,
    HeldOutData,
    read_held_out,
    validate_on_data,
)

__all__ = [
    "MISFIT_RMS",
    "PRIOR_GRID",
    "ROBUST_LOSS",
    "AcceptanceMachine",
    "DataValidation",
    "FleetDraw",
    "FleetStatistics",
    "HeldOutData",
    "MarkerRun",
    "MarkerSettings",
    "PriorChoice",
    "UnitEstimate",
    "UnitVerdict",
    "acceptance_machine",
    "calibrate_markers",
    "calibrated_controller",
    "choose_prior",
    "cross_validate_calibration",
    "cross_validated",
    "cube_doc",
    "cycle_characteristics",
    "draw_fleet",
    "fleet_statistics",
    "fold_table",
    "marker_procedure",
    "measured_characteristics",
    "nested_choice",
    "other_machine",
    "parse_prior",
    "read_held_out",
    "rebuild",
    "replay_procedure",
    "simulate_unit",
    "transfer_markers",
    "validate_on_data",
]
