"""Measurement files (CSV with a ``#`` header), one row per measured pose.

::

    # pincal measurements 1
    # frame: platform                 measured frame (must match the model's)
    # kind: pose                      pose | targets
    # length_unit: mm                 m | mm | um  (measured coordinates, std, targets)
    # angle_unit: mrad                rad | mrad | urad | deg  (rotation columns, std)
    # components: x y z rx ry rz      components used for identification (pose kind)
    # orientation: rotvec             rotvec (rx ry rz = log3 R) | matrix (r11 … r33)
    # noise: position_mm=0.01 orientation_mrad=0.02     optional instrument noise
    # instrument: laser-tracker       optional instrument profile (judges an estimated noise)
    leg1_slide [mm],…,leg6_slide [mm],x,y,z,rx,ry,rz,std_x,…,std_rz

- actuator columns come first, named by the model's actuated joints; a bracketed
  unit (``[mm]``, ``[deg]``…) is optional, without one the value is SI (m or rad);
  other column names, units declared once and readings relative to a reference pose
  are declared in the sidecar or the header (``# columns: torso1=torso_lift_joint``,
  ``# joint_units: angle=deg``, ``# joint_reference: home``; see ``_joint_columns``);
- ``x y z`` is the measured frame's origin in the world (machine base) frame;
  the orientation is the frame's rotation in the world frame, as a rotation
  vector (``rx ry rz``) or as the 9 entries of the matrix, row-major
  (``r11 r12 r13 r21 … r33``, unitless); a position-only file has no rotation
  columns;
- ``std_<component>`` columns are optional per-pose standard deviations (e.g. a
  laser tracker's fit covariance), in the file's units;
- ``temperature_C`` is an optional per-pose machine temperature [°C] (for the
  thermal-expansion term; see ``_condition_columns``).

A laser-tracker file (``kind: targets``) holds target points instead of poses; see
:mod:`pincal.io._tracker_file`.

Exactness: values are written with ``repr`` (shortest round-trip form). In SI
units (``m``, ``rad``, ``orientation: matrix``, the defaults of
:func:`write_measurements`) a file round-trips bit-exactly in both directions;
other units scale by powers of ten and round-trip to one unit in the last place.
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from pincal._yaml import path_text, shown
from pincal.errors import (
    BadValueError,
    ColumnError,
    FrameMismatchError,
    MeasurementError,
    MeasurementFormatError,
    TooFewPosesError,
)
from pincal.identification import (
    QualityVerdict,
    check_measurements,
)
from pincal.io._condition_columns import TEMPERATURE_COLUMN, read_temperature
from pincal.io._csv import (
    actuator_columns,
    fmt,
    header_value,
    parse_column,
    parse_numbers,
    split_file,
    write_csv,
)
from pincal.io._joint_columns import joint_columns, read_joints
from pincal.io._measurement_header import (
    MAX_COORDINATE,
    NOISE_RANGE,
    parse_components,
    parse_instrument,
    parse_noise,
)
from pincal.io._names import quote_value
from pincal.io._tracker_file import TargetMeasurements, parse_target_limits, parse_targets
from pincal.io._units import (
    ANGLE_UNITS,
    LENGTH_UNITS,
    actuator_write_factors,
    unit_factor,
)
from pincal.measure import Measurements
from pincal.model import COMPONENTS, Mechanism

__all__ = [
    "MeasurementFile",
    "check_enough_poses",
    "read_measurement_file",
    "read_measurements",
    "write_measurements",
]

log = logging.getLogger(__name__)

MATRIX_COLUMNS = tuple(f"r{i}{j}" for i in range(1, 4) for j in range(1, 4))
ORIENTATIONS = ("rotvec", "matrix")
KINDS = ("pose", "targets")
#: column names a pose-kind file gives a meaning (an actuated joint may not use them)
_RESERVED = frozenset(
    [*COMPONENTS, *MATRIX_COLUMNS, *(f"std_{c}" for c in COMPONENTS), TEMPERATURE_COLUMN]
)


@dataclass(frozen=True)
class MeasurementFile:
    """What :func:`read_measurement_file` found.

    Attributes:
        measurements: the poses (SI).
        targets: the raw tracker data for a ``targets`` file, else None.
        length_unit, angle_unit: as declared.
        suspect_units: True when magnitudes suggest a wrong length unit (also logged).
        warnings: human-readable warnings.
        data_check: the quality gate's look at the data
            (:func:`pincal.identification.check_measurements`, default limits), computed
            once here so that ``calibrate`` does not repeat it.
        instrument: the ``# instrument:`` profile name (see
            :data:`pincal.identification.INSTRUMENT_PROFILES`), or None.
    """

    measurements: Measurements
    targets: TargetMeasurements | None
    length_unit: str
    angle_unit: str
    suspect_units: bool
    warnings: tuple[str, ...]
    data_check: QualityVerdict
    instrument: str | None = None


def _unit_warning(verdict: QualityVerdict) -> str | None:
    """The unit finding of the gate's data check as a reader's warning, if any.

    The test is the quality gate's (spread of the measured positions about their centroid
    against the nominal model's at the same actuator values), so reading warns exactly
    where ``calibrate`` would refuse.
    """
    found = [i.message for i in verdict.issues if i.kind == "units"]
    return f"{found[0]}; {verdict.cause_text}" if found else None


def read_measurement_file(path: str | Path, mech: Mechanism) -> MeasurementFile:
    """Read and validate a measurement file against ``mech`` (see the module doc).

    Args:
        path: the file.
        mech: the model whose actuated joints and measured frame the file must use.

    Returns:
        The measurements [SI] with the declared units and any warnings.

    Raises:
        MeasurementFormatError, FrameMismatchError, ColumnError, BadValueError,
        NonFiniteValueError, ActuatorRangeError, PoseFitError (all MeasurementError),
        each naming the line, row or column; MeasurementFileError: missing, a FIFO or
        device, not UTF-8; InputLimitError: over the size cap.
    """
    name = Path(path).name
    header, columns, rows = split_file(path, "measurements")
    kind = header_value(header, "kind", "pose", name)
    if kind not in KINDS:
        raise MeasurementFormatError(f"{name}: kind {shown(kind)} unknown; use one of {KINDS}")
    lu = header_value(header, "length_unit", None, name)
    au = header_value(header, "angle_unit", "rad", name)
    lf = unit_factor(LENGTH_UNITS, lu, "length", name)
    af = unit_factor(ANGLE_UNITS, au, "angle", name)
    frame = header_value(header, "frame", mech.measured_frame, name)
    if frame != mech.measured_frame:
        raise FrameMismatchError(
            f"{name} measures frame {shown(frame)} but the model measures {mech.measured_frame!r} "
            f"(load the model with --frame {shown(frame)} or measured_frame= in its sidecar)"
        )
    parsed = [parse_column(c) for c in columns]
    names = [p[0] for p in parsed]
    dup = sorted({c for c in names if names.count(c) > 1})
    if dup:
        raise ColumnError(f"{name}: duplicate columns {shown(dup)}")
    act_idx, declared = joint_columns(mech, header, parsed, name)
    data = parse_numbers(rows, columns, name)
    if data.shape[0] == 0:
        raise MeasurementFormatError(f"{name}: no data rows")
    col = {c: k for k, c in enumerate(names)}
    titles = [columns[k] for k in act_idx]
    units = [parsed[k][1] for k in act_idx]
    q_act = read_joints(mech, data[:, act_idx], declared, units, titles, name)  # range-checked
    used = set(act_idx)

    def take(cols: Sequence[str], what: str) -> np.ndarray:
        miss = [c for c in cols if c not in col]
        if miss:
            raise ColumnError(f"{name}: missing {what} columns {miss}", missing=miss)
        used.update(col[c] for c in cols)
        return data[:, [col[c] for c in cols]]

    noise = parse_noise(header, name)
    instrument = parse_instrument(header, name)
    targets = None
    if kind == "targets":
        tnames, local = parse_targets(header, lf, name)
        pts = take([f"{t}.{a}" for t in tnames for a in "xyz"], "target point") / lf
        point_std, max_residual = parse_target_limits(header, lf, name)
        targets = TargetMeasurements(
            q_act=q_act,
            points=pts.reshape(len(rows), len(tnames), 3),
            targets_local=local,
            names=tuple(tnames),
            frame=frame,
            actuated=tuple(mech.actuated),
            point_std=point_std,
            max_residual=max_residual,
        )
        comps = parse_components(header, name) if "components" in header else COMPONENTS
        meas = targets.to_measurements(tuple(comps))
    else:
        comps = parse_components(header, name)
        positions = take(["x", "y", "z"], "position") / lf
        far = np.argwhere(np.abs(positions) > MAX_COORDINATE)
        if far.size:
            i, j = far[0]
            raise BadValueError(
                f"{name} data row {i + 1}, column {'xyz'[j]!r}: {positions[i, j]:g} m is more "
                f"than {MAX_COORDINATE / 1e3:g} km from the origin; check the value and the "
                "length unit",
                int(i) + 1,
                "xyz"[j],
            )
        rotations = None
        orient = header_value(header, "orientation", "rotvec", name)
        if orient not in ORIENTATIONS:
            raise MeasurementFormatError(
                f"{name}: orientation {shown(orient)} unknown; use one of {ORIENTATIONS}"
            )
        has_rot = any(c in col for c in ("rx", *MATRIX_COLUMNS))
        if has_rot or any(c.startswith("r") for c in comps):
            if orient == "matrix":
                mats = take(MATRIX_COLUMNS, "rotation matrix").reshape(-1, 3, 3)
                for i, R in enumerate(mats, start=1):
                    if np.abs(R.T @ R - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0:
                        raise BadValueError(
                            f"{name} data row {i}: r11…r33 is not a rotation matrix", i, "r11"
                        )
                rotations = mats
            else:
                rv = take(["rx", "ry", "rz"], "rotation") / af
                rotations = np.array([pin.exp3(r) for r in rv])
        std = None
        std_cols = [f"std_{c}" for c in comps]
        if any(c in col for c in std_cols):
            std = take(std_cols, "standard deviation")
            std = std / np.array([lf if c in "xyz" else af for c in comps])
            lo, hi = NOISE_RANGE
            bad = np.argwhere(~((std * 1e3 >= lo) & (std * 1e3 <= hi)))  # mm, mrad
            if bad.size:
                i, j = bad[0]
                raise BadValueError(
                    f"{name} data row {i + 1}, column {shown(std_cols[j])}: std must be "
                    f"between {lo:g} and {hi:g} mm (mrad for angles); a σ outside makes the "
                    "weights under- or overflow",
                    int(i) + 1,
                    std_cols[j],
                )
        meas = Measurements(
            q_act, positions, rotations, tuple(comps), frame, tuple(mech.actuated), noise, std
        )
    if TEMPERATURE_COLUMN in col:
        temperature = read_temperature(take([TEMPERATURE_COLUMN], "temperature")[:, 0], name)
        meas = dataclasses.replace(meas, temperature=temperature)
    unknown = [columns[k] for k in range(len(columns)) if k not in used]
    if unknown:
        raise ColumnError(
            f"{name}: columns {shown(unknown)} not understood (kind {shown(kind)}, "
            f"model {mech.name!r})",
            unknown=unknown,
        )
    check = check_measurements(mech, meas, length_unit=lu)
    w = _unit_warning(check)
    if w:
        log.warning("%s: %s", name, w)
    return MeasurementFile(
        meas, targets, lu, au, w is not None, (w,) if w else (), check, instrument
    )


def read_measurements(path: str | Path, mech: Mechanism) -> Measurements:
    """The measurements of a file (see :func:`read_measurement_file`, same errors)."""
    return read_measurement_file(path, mech).measurements


def check_enough_poses(measurements: Measurements, n_identifiable: int) -> None:
    """Refuse fewer measurement equations than parameters to identify.

    Raises:
        TooFewPosesError: ``len(measurements) · k < n_identifiable``.
    """
    k = len(measurements.components)
    m = len(measurements)
    if m * k < n_identifiable:
        need = -(-n_identifiable // k)
        raise TooFewPosesError(
            f"{m} poses × {k} components = {m * k} equations for {n_identifiable} identifiable "
            f"parameters; measure at least {need} poses"
        )


def write_measurements(
    path: str | Path,
    measurements: Measurements,
    *,
    length_unit: str = "m",
    angle_unit: str = "rad",
    orientation: str = "matrix",
    actuator_units: Sequence[str] | None = None,
) -> Path:
    """Write a pose measurement file atomically (see the module doc for the format).

    Args:
        path: output file.
        measurements: the data (SI).
        length_unit: unit of the file's measured position columns, one of ``"m"``,
            ``"mm"``, ``"um"``.
        angle_unit: unit of the file's measured angle columns, one of ``"rad"``,
            ``"mrad"``, ``"urad"``, ``"deg"``.
        orientation: ``"matrix"`` (exact) or ``"rotvec"``.
        actuator_units: optional unit per actuator column (``"mm"``, ``"deg"``…); SI if None.

    Returns:
        The written path.

    Raises:
        MeasurementFormatError: unknown length or angle unit; a name the file cannot
            hold (control characters, an actuated joint named like a data column).
        MeasurementError: unknown orientation or bad ``actuator_units``.
    """
    lf = unit_factor(LENGTH_UNITS, length_unit, "length", "write_measurements")
    af = unit_factor(ANGLE_UNITS, angle_unit, "angle", "write_measurements")
    if orientation not in ORIENTATIONS:
        raise MeasurementError(f"orientation {orientation!r}; use one of {ORIENTATIONS}")
    meas = measurements
    clash = [a for a in meas.actuated if a in _RESERVED]
    if clash:
        raise MeasurementFormatError(
            f"cannot write {path_text(path)}: actuated joint {shown(clash[0])} would appear "
            "twice as a measurement column name (x y z rx ry rz r11…r33 std_* temperature_C); "
            "rename the joint"
        )
    lines = [
        f"frame: {quote_value(meas.frame, 'frame')}",
        "kind: pose",
        f"length_unit: {length_unit}",
        f"angle_unit: {angle_unit}",
        f"components: {' '.join(meas.components)}",
        f"orientation: {orientation}",
    ]
    if meas.noise is not None:
        lines.append(
            f"noise: position_mm={fmt(meas.noise.position)} "
            f"orientation_mrad={fmt(meas.noise.orientation)}"
        )
    cols = [*actuator_columns(meas.actuated, actuator_units), "x", "y", "z"]
    rot_cols = []
    if meas.rotations is not None:
        rot_cols = list(MATRIX_COLUMNS) if orientation == "matrix" else ["rx", "ry", "rz"]
    extra_cols = [] if meas.std is None else [f"std_{c}" for c in meas.components]
    if meas.temperature is not None:
        extra_cols.append(TEMPERATURE_COLUMN)
    afac = actuator_write_factors(actuator_units, len(meas.actuated))
    std_fac = np.array([lf if c in "xyz" else af for c in meas.components])
    rows = []
    for i in range(len(meas)):
        row = [*(meas.q_act[i] * afac), *(meas.positions[i] * lf)]
        if meas.rotations is not None:
            R = meas.rotations[i]
            row += list(R.ravel()) if orientation == "matrix" else list(pin.log3(R) * af)
        if meas.std is not None:
            row += list(meas.std[i] * std_fac)
        if meas.temperature is not None:
            row.append(meas.temperature[i])
        rows.append([fmt(v) for v in row])
    return write_csv(path, "measurements", lines, cols + rot_cols + extra_cols, rows)
