"""Stage 8 — a calibration as the commands run it, callable from Python.

The orchestration of a calibration — read the data, settle the settings the data
decide, fit, judge, cross-validate — is here, under the command line; a command parses
its options, calls one function of this stage and prints what it returns. Nothing here
prints or writes files.

- :func:`calibrate_markers` (``pincal calibrate --link``): a marker table in an
  unknown instrument frame, with the defaults of real data (:class:`MarkerSettings`);
  :func:`rebuild` and :func:`replay_procedure` run it again for ``validate --cv``;
  :func:`transfer_markers` carries it to another session (``validate --data``);
  :func:`marker_doc` is its entry of the manifest and identification.json.
- :func:`calibrate_pose_file` (``pincal calibrate --data FILE``): a pose measurement
  file read (:func:`pose_parameters`, :func:`pose_problem`), fitted, judged, its σ
  checked (:class:`PoseRun`); :func:`calibrate_instrument_files` for instrument files
  (ballbar, probe, sockets); :class:`Steps` carries the progress of their long steps.
- :func:`select_pose_model` / :func:`select_marker_model` (``pincal select-model``):
  candidate error models ranked by K-fold held-out error.
- :func:`simulate_demo` (``pincal demo``): a simulated calibration of a seeded actual
  machine, poses chosen by design, predicted vs achieved accuracy (:class:`DemoResult`).
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
  production line with planted faulty units, :func:`plan_fleet` as ``fleet simulate``
  does it (:class:`FleetPlan`); :func:`fleet_jobs` lists the units of ``fleet run`` and
  :func:`unit_summary` reads one back; :func:`fleet_statistics` flags the units
  out of family, each judged with its own covariance; :func:`fleet_report` judges a
  run and writes up ``fleet.json`` (:func:`fleet_document`); :func:`session_drift`
  compares the sessions of a unit calibrated more than once.
- models described (``pincal info``): :func:`structure_lines` and
  :func:`describe_presets` (each preset's identifiability, the base set offered as a
  preset, :func:`base_line`); :func:`reduction_line` says a preset was reduced to it.
- measurement poses (``pincal poses``): :func:`pose_basis`, :func:`pose_candidates` and
  :func:`select_pose_design` (screens, selection, travel order, Cramér–Rao prediction:
  :class:`PoseSelection`); the reach screen compensates each candidate on displaced
  models (:func:`compensation_test`, :func:`controlled_components`; off, and
  :func:`unfixed_commands` says why, when the measured components do not fix the commands).
- simulated campaigns (``pincal simulate``): :func:`simulate_campaign` measures the
  nominal model with random errors (none a built machine cannot have,
  :func:`buildable_mask`) at the poses it reaches (:func:`reachable_rows`), as poses, a
  scalar instrument's readings or a ball seated in two sockets (:func:`default_sockets`).
- compensation (``pincal compensate``): :func:`compensate_targets` gives the commands
  of a targets file (:class:`TargetCompensation`, starts from :func:`nominal_starts`);
  :func:`compensate_program` rewrites a G-code program's moves
  (:class:`CompensatedProgram`).
- views (``pincal view``): :func:`view_poses` gives the poses drawn,
  :func:`prediction_changes` the nominal → calibrated arrows at each.
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
from pincal.workflow._buildable import buildable_mask
from pincal.workflow._cross_validation import cross_validate_calibration, fold_table
from pincal.workflow._demo import (
    DemoAccuracy,
    DemoResult,
    DemoSettings,
    draw_errors,
    simulate_demo,
)
from pincal.workflow._fleet_doc import FleetReport, fleet_document, fleet_report
from pincal.workflow._fleet_draw import FleetDraw, draw_fleet, simulate_unit
from pincal.workflow._fleet_drift import DriftVerdict, session_drift
from pincal.workflow._fleet_sim import SESSION_DATES, FleetPlan, plan_fleet
from pincal.workflow._fleet_stats import (
    FleetStatistics,
    UnitEstimate,
    UnitVerdict,
    fleet_statistics,
)
from pincal.workflow._fleet_units import UnitJob, file_digest, fleet_jobs, unit_summary
from pincal.workflow._instrument_run import calibrate_instrument_files
from pincal.workflow._marker_doc import marker_doc
from pincal.workflow._marker_replay import rebuild, replay_procedure
from pincal.workflow._marker_run import (
    MISFIT_RMS,
    ROBUST_LOSS,
    MarkerRun,
    calibrate_markers,
    marker_procedure,
)
from pincal.workflow._marker_settings import PRIOR_GRID, MarkerSettings, parse_prior
from pincal.workflow._model_choice import select_marker_model, select_pose_model
from pincal.workflow._model_description import (
    ModelDescription,
    base_line,
    describe_presets,
    reduction_line,
    structure_lines,
)
from pincal.workflow._pose_run import (
    PoseProblem,
    PoseRun,
    calibrate_pose_file,
    pose_parameters,
    pose_problem,
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
    NestedChoice,
    PriorChoice,
    choose_prior,
    cross_validated,
    nested_choice,
)
from pincal.workflow._program_compensation import CompensatedProgram, compensate_program
from pincal.workflow._reach_screen import (
    DRAWS,
    compensation_test,
    controlled_components,
    unfixed_commands,
)
from pincal.workflow._simulation import (
    SOCKET_SPACING,
    SimulatedCampaign,
    ThermalDraw,
    default_sockets,
    reachable_rows,
    simulate_campaign,
)
from pincal.workflow._steps import Steps
from pincal.workflow._target_compensation import (
    TargetCompensation,
    compensate_targets,
    nominal_starts,
)
from pincal.workflow._transfer import transfer_markers
from pincal.workflow._validate_data import (
    DataValidation,
    HeldOutData,
    read_held_out,
    validate_on_data,
)
from pincal.workflow._view_poses import (
    PredictionChanges,
    ViewPoses,
    prediction_changes,
    view_poses,
)

__all__ = [
    "DRAWS",
    "MISFIT_RMS",
    "PRIOR_GRID",
    "ROBUST_LOSS",
    "SESSION_DATES",
    "SOCKET_SPACING",
    "AcceptanceMachine",
    "CompensatedProgram",
    "DataValidation",
    "DemoAccuracy",
    "DemoResult",
    "DemoSettings",
    "DriftVerdict",
    "FleetDraw",
    "FleetPlan",
    "FleetReport",
    "FleetStatistics",
    "HeldOutData",
    "MarkerRun",
    "MarkerSettings",
    "ModelDescription",
    "NestedChoice",
    "PoseBasis",
    "PoseProblem",
    "PoseRequest",
    "PoseRun",
    "PoseSelection",
    "PredictionChanges",
    "PriorChoice",
    "SimulatedCampaign",
    "Steps",
    "TargetCompensation",
    "ThermalDraw",
    "UnitEstimate",
    "UnitJob",
    "UnitVerdict",
    "ViewPoses",
    "acceptance_machine",
    "base_line",
    "buildable_mask",
    "calibrate_instrument_files",
    "calibrate_markers",
    "calibrate_pose_file",
    "calibrated_controller",
    "choose_prior",
    "compensate_program",
    "compensate_targets",
    "compensation_test",
    "controlled_components",
    "cross_validate_calibration",
    "cross_validated",
    "cube_doc",
    "cycle_characteristics",
    "default_sockets",
    "describe_presets",
    "draw_errors",
    "draw_fleet",
    "file_digest",
    "fleet_document",
    "fleet_jobs",
    "fleet_report",
    "fleet_statistics",
    "fold_table",
    "marker_doc",
    "marker_procedure",
    "measured_characteristics",
    "nested_choice",
    "nominal_starts",
    "other_machine",
    "parse_prior",
    "plan_fleet",
    "pose_basis",
    "pose_candidates",
    "pose_parameters",
    "pose_problem",
    "prediction_changes",
    "reachable_rows",
    "read_held_out",
    "rebuild",
    "reduction_line",
    "replay_procedure",
    "select_marker_model",
    "select_pose_design",
    "select_pose_model",
    "session_drift",
    "simulate_campaign",
    "simulate_demo",
    "simulate_unit",
    "structure_lines",
    "transfer_markers",
    "unfixed_commands",
    "unit_summary",
    "validate_on_data",
    "view_poses",
]
