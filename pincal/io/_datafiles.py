"""Measurement, pose and command files (CSV with a ``#`` header).

Measurement file (one row per pose)::

    # pincal measurements 1
    # frame: platform                 measured frame (must match the model's)
    # kind: pose                      pose | targets
    # length_unit: mm                 m | mm | um  (measured coordinates, std, targets)
    # angle_unit: mrad                rad | mrad | urad | deg  (rotation columns, std)
    # components: x y z rx ry rz      components used for identification (pose kind)
    # orientation: rotvec             rotvec (rx ry rz = log3 R) | matrix (r11 … r33)
    # noise: position_mm=0.01 orientation_mrad=0.02     optional instrument noise
    leg1_slide [mm],…,leg6_slide [mm],x,y,z,rx,ry,rz,std_x,…,std_rz

- actuator columns come first, named by the model's actuated joints; a bracketed
  unit (``[mm]``, ``[deg]``…) is optional, without one the value is SI (m or rad);
- ``x y z`` is the measured frame's origin in the world (machine base) frame;
  the orientation is the frame's rotation in the world frame, as a rotation
  vector (``rx ry rz``) or as the 9 entries of the matrix, row-major
  (``r11 r12 r13 r21 … r33``, unitless); a position-only file has no rotation
  columns;
- ``std_<component>`` columns are optional per-pose standard deviations (e.g. a
  laser tracker's fit covariance), in the file's units.

Tracker target file (``kind: targets``): the header lists the targets fixed on
the measured body (``# target: T1 0.1 0.0 0.02`` — name and coordinates in the
measured frame, length unit) and optionally ``# point_std: 0.01`` (1σ per point
coordinate, length unit) and ``# max_residual: 0.05`` (moved-target threshold);
each row holds the actuator values and the measured points ``T1.x T1.y T1.z …``
in the world frame. Reading fits each row's pose (Kabsch, :mod:`pincal.measure._tracker`).

Exactness: values are written with ``repr`` (shortest round-trip form). In SI
units (``m``, ``rad``, ``orientation: matrix``, the defaults of
:func:`write_measurements`) a file round-trips bit-exactly in both directions;
other units scale by powers of ten and round-trip to one unit in the last place.

Pose file (targets for compensation; ``# pincal poses 1``): columns
``x y z`` and ``rx ry rz`` (rotation vector, ``orientation: rotvec``) or
``roll pitch yaw`` (``orientation: rpy``, R = Rz(yaw)·Ry(pitch)·Rx(roll)).
Command file (``# pincal commands 1``): column ``pose`` (index of the target)
then one column per actuated joint.
"""

from __future__ import annotations

import csv
import io
import logging
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from pincal.errors import (
    BadValueError,
    ColumnError,
    FrameMismatchError,
    MeasurementError,
    MeasurementFormatError,
    NonFiniteValueError,
    PoseFitError,
    TooFewPosesError,
)
from pincal.io._atomic import atomic_write_text
from pincal.measure._measurements import Measurements, NoiseModel
from pincal.measure._tracker import fit_rigid_transform, rigid_fit_covariance
from pincal.model._closures import COMPONENTS
from pincal.model._mechanism import Mechanism

__all__ = [
    "ANGLE_UNITS",
    "LENGTH_UNITS",
    "MeasurementFile",
    "TargetMeasurements",
    "check_enough_poses",
    "read_actuator_rows",
    "read_commands",
    "read_measurement_file",
    "read_measurements",
    "read_poses",
    "write_commands",
    "write_measurements",
    "write_poses",
    "write_target_measurements",
]

log = logging.getLogger(__name__)

#: units per SI unit (value_in_unit = SI value × factor)
LENGTH_UNITS = {"m": 1.0, "mm": 1e3, "um": 1e6}
ANGLE_UNITS = {"rad": 1.0, "mrad": 1e3, "urad": 1e6, "deg": 180.0 / math.pi}
MATRIX_COLUMNS = tuple(f"r{i}{j}" for i in range(1, 4) for j in range(1, 4))
ORIENTATIONS = ("rotvec", "matrix")
KINDS = ("pose", "targets")
_COLUMN = re.compile(r"^\s*([^\[\]]+?)\s*(?:\[\s*([A-Za-z]+)\s*\])?\s*$")


# ----------------------------------------------------------------------------- data
@dataclass(frozen=True)
class TargetMeasurements:
    """Raw laser-tracker data: measured target points per pose.

    Attributes:
        q_act: (m, n_act) actuator values [m, rad].
        points: (m, n_t, 3) measured target points, world frame [m].
        targets_local: (n_t, 3) target coordinates in the measured frame [m].
        names: target names (n_t,).
        frame: measured frame name.
        actuated: actuated joint names.
        point_std: 1σ per point coordinate [m], or None if unknown.
        max_residual: moved-target threshold [m], or None.
    """

    q_act: np.ndarray
    points: np.ndarray
    targets_local: np.ndarray
    names: tuple[str, ...]
    frame: str
    actuated: tuple[str, ...]
    point_std: float | None = None
    max_residual: float | None = None

    def to_measurements(self, components: tuple[str, ...] | None = None) -> Measurements:
        """Fit each pose (weighted Kabsch); per-pose std from the fit covariance.

        Raises:
            MovedTargetError (a MeasurementError) naming the pose when a target residual
            exceeds ``max_residual``.
        """
        comps = tuple(components or COMPONENTS)
        m = self.q_act.shape[0]
        positions = np.empty((m, 3))
        rotations = np.empty((m, 3, 3))
        for i in range(m):
            try:
                fit = fit_rigid_transform(
                    self.targets_local, self.points[i], max_residual=self.max_residual
                )
            except MeasurementError as exc:
                raise PoseFitError(f"data row {i + 1}: {exc}", i + 1) from exc
            positions[i] = fit.T.translation
            rotations[i] = fit.T.rotation
        std = None
        if self.point_std is not None:
            cov = rigid_fit_covariance(self.targets_local, self.point_std)
            sd = np.sqrt(np.diag(cov))
            idx = [COMPONENTS.index(c) for c in comps]
            # The covariance is of a local twist; the world-frame position std equals the
            # local one only for isotropic noise, which rigid_fit_covariance assumes per
            # point, so the RMS of the three local linear stds is used for x, y, z.
            lin = float(np.sqrt(np.mean(sd[:3] ** 2)))
            row = np.array([lin if k < 3 else sd[k] for k in idx])
            std = np.tile(row, (m, 1))
        return Measurements(
            self.q_act.copy(), positions, rotations, comps, self.frame, self.actuated, None, std
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
    """

    measurements: Measurements
    targets: TargetMeasurements | None
    length_unit: str
    angle_unit: str
    suspect_units: bool
    warnings: tuple[str, ...]


# ----------------------------------------------------------------------------- helpers
def _fmt(x: float) -> str:
    return repr(float(x))


def _unit(table: dict[str, float], name: str, what: str, where: str) -> float:
    if name not in table:
        raise MeasurementFormatError(
            f"{where}: unknown {what} unit {name!r}; use one of {', '.join(table)}"
        )
    return table[name]


def _read_lines(path: str | Path) -> list[str]:
    try:
        return Path(path).read_text(encoding="utf-8").splitlines()
    except OSError as exc:
        raise MeasurementError(f"cannot read {str(path)!r}: {exc.strerror}") from exc
    except UnicodeDecodeError as exc:
        raise MeasurementFormatError(f"{str(path)!r} is not a UTF-8 text file") from exc


def _split(path: str | Path, magic: str) -> tuple[dict[str, list[str]], list[str], list[list[str]]]:
    """Header (key → values, repeated keys collected), column names, data rows."""
    lines = _read_lines(path)
    name = Path(path).name
    header: dict[str, list[str]] = {}
    body: list[str] = []
    seen_magic = False
    for n, line in enumerate(lines, start=1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            if body:
                continue  # comments between rows are allowed
            text = s[1:].strip()
            if text.startswith("pincal "):
                if text.split()[1:2] != [magic]:
                    raise MeasurementFormatError(
                        f"{name} line {n}: this is a {text!r} file, expected 'pincal {magic}'"
                    )
                seen_magic = True
                continue
            if ":" in text:
                key, _, value = text.partition(":")
                header.setdefault(key.strip().lower(), []).append(value.split("#")[0].strip())
            continue
        body.append(line)
    if not seen_magic:
        raise MeasurementFormatError(f"{name}: missing the first header line '# pincal {magic} 1'")
    if not body:
        raise MeasurementFormatError(f"{name}: no column line and no data rows")
    rows = list(csv.reader(body, skipinitialspace=True))
    columns = [c.strip() for c in rows[0]]
    return header, columns, rows[1:]


def _one(header: dict[str, list[str]], key: str, default: str | None, name: str) -> str:
    if key not in header:
        if default is None:
            raise MeasurementFormatError(f"{name}: header line '# {key}: …' is required")
        return default
    if len(header[key]) > 1:
        raise MeasurementFormatError(f"{name}: header '{key}' given {len(header[key])} times")
    return header[key][0]


def _parse_column(col: str) -> tuple[str, str | None]:
    m = _COLUMN.match(col)
    if not m:
        raise MeasurementFormatError(f"column name {col!r} is not understood")
    return m.group(1), m.group(2)


def _numbers(rows: list[list[str]], columns: list[str], name: str) -> np.ndarray:
    out = np.empty((len(rows), len(columns)))
    for i, row in enumerate(rows, start=1):
        if len(row) != len(columns):
            raise MeasurementFormatError(
                f"{name} data row {i}: {len(row)} fields, the column line has {len(columns)}"
            )
        for j, cell in enumerate(row):
            try:
                v = float(cell)
            except ValueError:
                raise BadValueError(
                    f"{name} data row {i}, column {columns[j]!r}: {cell.strip()!r} is not a number",
                    i,
                    columns[j],
                ) from None
            if not math.isfinite(v):
                raise NonFiniteValueError(
                    f"{name} data row {i}, column {columns[j]!r}: value is {cell.strip()}",
                    i,
                    columns[j],
                )
            out[i - 1, j] = v
    return out


def _actuator_factors(mech: Mechanism, units: list[str | None], name: str) -> np.ndarray:
    factors = []
    for joint, unit in zip(mech.actuated, units, strict=True):
        if unit is None:
            factors.append(1.0)
            continue
        revolute = mech.tree.joints[joint].type in ("revolute", "continuous")
        table = ANGLE_UNITS if revolute else LENGTH_UNITS
        factors.append(_unit(table, unit, "angle" if revolute else "length", f"{name} {joint}"))
    return np.array(factors)


def _check_magnitudes(mech: Mechanism, positions: np.ndarray, unit: str) -> str | None:
    """A warning when measured positions are ~1000× off the model's home pose scale."""
    home = mech.frame_placement(mech.q_home).translation
    scale_model = max(float(np.linalg.norm(home)), 1e-3)
    scale_data = float(np.median(np.linalg.norm(positions, axis=1)))
    ratio = scale_data / scale_model
    if 0.03 < ratio < 30.0:
        return None
    return (
        f"measured positions are {ratio:.3g}× the model's size (median distance "
        f"{scale_data:.4g} m vs home {scale_model:.4g} m): is length_unit {unit!r} right?"
    )


# ----------------------------------------------------------------------------- reading
def read_measurement_file(path: str | Path, mech: Mechanism) -> MeasurementFile:
    """Read and validate a measurement file against ``mech`` (see the module doc).

    Raises:
        MeasurementFormatError, FrameMismatchError, ColumnError, BadValueError,
        NonFiniteValueError (all MeasurementError), each naming the line, row or column.
    """
    name = Path(path).name
    header, columns, rows = _split(path, "measurements")
    kind = _one(header, "kind", "pose", name)
    if kind not in KINDS:
        raise MeasurementFormatError(f"{name}: kind {kind!r} unknown; use one of {KINDS}")
    lu = _one(header, "length_unit", None, name)
    au = _one(header, "angle_unit", "rad", name)
    lf = _unit(LENGTH_UNITS, lu, "length", name)
    af = _unit(ANGLE_UNITS, au, "angle", name)
    frame = _one(header, "frame", mech.measured_frame, name)
    if frame != mech.measured_frame:
        raise FrameMismatchError(
            f"{name} measures frame {frame!r} but the model measures {mech.measured_frame!r} "
            f"(load the model with measured_frame={frame!r})"
        )
    parsed = [_parse_column(c) for c in columns]
    names = [p[0] for p in parsed]
    dup = sorted({c for c in names if names.count(c) > 1})
    if dup:
        raise ColumnError(f"{name}: duplicate columns {dup}")
    missing_act = [j for j in mech.actuated if j not in names]
    if missing_act:
        raise ColumnError(
            f"{name}: missing actuator columns {missing_act} (model {mech.name!r} actuates "
            f"{list(mech.actuated)})",
            missing=missing_act,
        )
    data = _numbers(rows, columns, name)
    if data.shape[0] == 0:
        raise MeasurementFormatError(f"{name}: no data rows")
    col = {c: k for k, c in enumerate(names)}
    act_idx = [col[j] for j in mech.actuated]
    q_act = data[:, act_idx] / _actuator_factors(mech, [parsed[k][1] for k in act_idx], name)
    used = set(act_idx)

    def take(cols: Sequence[str], what: str) -> np.ndarray:
        miss = [c for c in cols if c not in col]
        if miss:
            raise ColumnError(f"{name}: missing {what} columns {miss}", missing=miss)
        used.update(col[c] for c in cols)
        return data[:, [col[c] for c in cols]]

    noise = _parse_noise(header, name)
    targets = None
    if kind == "targets":
        tnames, local = _parse_targets(header, lf, name)
        pts = take([f"{t}.{a}" for t in tnames for a in "xyz"], "target point") / lf
        ps = header.get("point_std")
        targets = TargetMeasurements(
            q_act=q_act,
            points=pts.reshape(len(rows), len(tnames), 3),
            targets_local=local,
            names=tuple(tnames),
            frame=frame,
            actuated=tuple(mech.actuated),
            point_std=None if ps is None else _positive(ps[0], "point_std", name) / lf,
            max_residual=(
                None
                if "max_residual" not in header
                else _positive(header["max_residual"][0], "max_residual", name) / lf
            ),
        )
        comps = _components(header, name) if "components" in header else COMPONENTS
        meas = targets.to_measurements(tuple(comps))
    else:
        comps = _components(header, name)
        positions = take(["x", "y", "z"], "position") / lf
        rotations = None
        orient = _one(header, "orientation", "rotvec", name)
        if orient not in ORIENTATIONS:
            raise MeasurementFormatError(
                f"{name}: orientation {orient!r} unknown; use one of {ORIENTATIONS}"
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
            bad = np.argwhere(std <= 0)
            if bad.size:
                i, j = bad[0]
                raise BadValueError(
                    f"{name} data row {i + 1}, column {std_cols[j]!r}: std must be > 0",
                    int(i) + 1,
                    std_cols[j],
                )
        meas = Measurements(
            q_act, positions, rotations, tuple(comps), frame, tuple(mech.actuated), noise, std
        )
    unknown = [columns[k] for k in range(len(columns)) if k not in used]
    if unknown:
        raise ColumnError(
            f"{name}: columns {unknown} not understood (kind {kind!r}, model {mech.name!r})",
            unknown=unknown,
        )
    warnings = []
    w = _check_magnitudes(mech, meas.positions, lu)
    if w:
        log.warning("%s: %s", name, w)
        warnings.append(w)
    return MeasurementFile(meas, targets, lu, au, w is not None, tuple(warnings))


def read_measurements(path: str | Path, mech: Mechanism) -> Measurements:
    """The measurements of a file (see :func:`read_measurement_file`)."""
    return read_measurement_file(path, mech).measurements


def _positive(text: str, key: str, name: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise MeasurementFormatError(f"{name}: header {key!r} must be a number") from None
    if not (math.isfinite(v) and v > 0):
        raise MeasurementFormatError(f"{name}: header {key!r} must be finite and > 0")
    return v


def _components(header, name: str) -> list[str]:
    comps = _one(header, "components", "x y z rx ry rz", name).split()
    bad = [c for c in comps if c not in COMPONENTS]
    if bad or not comps or len(set(comps)) != len(comps):
        raise MeasurementFormatError(
            f"{name}: components {comps} invalid; choose distinct names from {COMPONENTS}"
        )
    return [c for c in COMPONENTS if c in comps]


def _parse_noise(header, name: str) -> NoiseModel | None:
    if "noise" not in header:
        return None
    vals = {}
    for item in _one(header, "noise", None, name).split():
        key, _, v = item.partition("=")
        if key not in ("position_mm", "orientation_mrad"):
            raise MeasurementFormatError(
                f"{name}: noise entry {item!r}; use position_mm=<σ> orientation_mrad=<σ>"
            )
        try:
            sigma = float(v)
        except ValueError:
            raise MeasurementFormatError(f"{name}: noise entry {item!r} is not a number") from None
        if not (math.isfinite(sigma) and sigma >= 0):
            raise MeasurementFormatError(f"{name}: noise entry {item!r} must be finite, ≥ 0")
        vals[key.split("_")[0]] = sigma
    return NoiseModel(vals.get("position", 0.0), vals.get("orientation", 0.0))


def _parse_targets(header, lf: float, name: str) -> tuple[list[str], np.ndarray]:
    names, coords = [], []
    for entry in header.get("target", []):
        parts = entry.split()
        if len(parts) != 4:
            raise MeasurementFormatError(f"{name}: target line {entry!r}: expected 'name x y z'")
        try:
            coords.append([float(v) / lf for v in parts[1:]])
        except ValueError:
            raise MeasurementFormatError(f"{name}: target line {entry!r}: bad number") from None
        names.append(parts[0])
    if len(names) < 3:
        raise MeasurementFormatError(
            f"{name}: a targets file needs at least 3 '# target: name x y z' lines, got "
            f"{len(names)}"
        )
    return names, np.array(coords)


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


# ----------------------------------------------------------------------------- writing
def _header(lines: list[str], magic: str) -> io.StringIO:
    buf = io.StringIO()
    buf.write(f"# pincal {magic} 1\n")
    for line in lines:
        buf.write(f"# {line}\n")
    return buf


def _act_columns(actuated: Sequence[str], units: Sequence[str] | None) -> list[str]:
    if units is None:
        return list(actuated)
    if len(units) != len(actuated):
        raise MeasurementError(f"{len(units)} actuator units for {len(actuated)} actuators")
    return [f"{a} [{u}]" for a, u in zip(actuated, units, strict=True)]


def _act_factors(units: Sequence[str] | None, n: int) -> np.ndarray:
    if units is None:
        return np.ones(n)
    return np.array([{**LENGTH_UNITS, **ANGLE_UNITS}[u] for u in units])


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
        length_unit, angle_unit: units of the file's measured columns.
        orientation: ``"matrix"`` (exact) or ``"rotvec"``.
        actuator_units: optional unit per actuator column (``"mm"``, ``"deg"``…); SI if None.
    """
    lf = _unit(LENGTH_UNITS, length_unit, "length", "write_measurements")
    af = _unit(ANGLE_UNITS, angle_unit, "angle", "write_measurements")
    if orientation not in ORIENTATIONS:
        raise MeasurementError(f"orientation {orientation!r}; use one of {ORIENTATIONS}")
    meas = measurements
    lines = [
        f"frame: {meas.frame}",
        "kind: pose",
        f"length_unit: {length_unit}",
        f"angle_unit: {angle_unit}",
        f"components: {' '.join(meas.components)}",
        f"orientation: {orientation}",
    ]
    if meas.noise is not None:
        lines.append(
            f"noise: position_mm={_fmt(meas.noise.position)} "
            f"orientation_mrad={_fmt(meas.noise.orientation)}"
        )
    buf = _header(lines, "measurements")
    cols = [*_act_columns(meas.actuated, actuator_units), "x", "y", "z"]
    rot_cols = []
    if meas.rotations is not None:
        rot_cols = list(MATRIX_COLUMNS) if orientation == "matrix" else ["rx", "ry", "rz"]
    std_cols = [] if meas.std is None else [f"std_{c}" for c in meas.components]
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(cols + rot_cols + std_cols)
    afac = _act_factors(actuator_units, len(meas.actuated))
    std_fac = np.array([lf if c in "xyz" else af for c in meas.components])
    for i in range(len(meas)):
        row = [*(meas.q_act[i] * afac), *(meas.positions[i] * lf)]
        if meas.rotations is not None:
            R = meas.rotations[i]
            row += list(R.ravel()) if orientation == "matrix" else list(pin.log3(R) * af)
        if meas.std is not None:
            row += list(meas.std[i] * std_fac)
        writer.writerow([_fmt(v) for v in row])
    return atomic_write_text(path, buf.getvalue())


def write_target_measurements(
    path: str | Path,
    data: TargetMeasurements,
    *,
    length_unit: str = "m",
    actuator_units: Sequence[str] | None = None,
) -> Path:
    """Write raw tracker target data (``kind: targets``) atomically."""
    lf = _unit(LENGTH_UNITS, length_unit, "length", "write_target_measurements")
    lines = [f"frame: {data.frame}", "kind: targets", f"length_unit: {length_unit}"]
    for n, p in zip(data.names, data.targets_local, strict=True):
        lines.append(f"target: {n} {' '.join(_fmt(v * lf) for v in p)}")
    if data.point_std is not None:
        lines.append(f"point_std: {_fmt(data.point_std * lf)}")
    if data.max_residual is not None:
        lines.append(f"max_residual: {_fmt(data.max_residual * lf)}")
    buf = _header(lines, "measurements")
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(
        _act_columns(data.actuated, actuator_units)
        + [f"{n}.{a}" for n in data.names for a in "xyz"]
    )
    afac = _act_factors(actuator_units, len(data.actuated))
    for i in range(data.q_act.shape[0]):
        row = [*(data.q_act[i] * afac), *(data.points[i].ravel() * lf)]
        writer.writerow([_fmt(v) for v in row])
    return atomic_write_text(path, buf.getvalue())


# ----------------------------------------------------------------------------- poses
def read_poses(path: str | Path) -> list[pin.SE3]:
    """Target poses of the measured frame in the world frame (see the module doc)."""
    name = Path(path).name
    header, columns, rows = _split(path, "poses")
    lf = _unit(LENGTH_UNITS, _one(header, "length_unit", None, name), "length", name)
    af = _unit(ANGLE_UNITS, _one(header, "angle_unit", "rad", name), "angle", name)
    orient = _one(header, "orientation", "rotvec", name)
    rot = {"rotvec": ["rx", "ry", "rz"], "rpy": ["roll", "pitch", "yaw"]}
    if orient not in rot:
        raise MeasurementFormatError(f"{name}: orientation {orient!r}; use rotvec or rpy")
    want = ["x", "y", "z", *rot[orient]]
    names = [_parse_column(c)[0] for c in columns]
    missing = [c for c in want if c not in names]
    extra = [c for c in names if c not in want]
    if missing or extra:
        raise ColumnError(
            f"{name}: pose columns must be {want}; missing {missing}, not understood {extra}",
            missing,
            extra,
        )
    data = _numbers(rows, columns, name)
    if data.shape[0] == 0:
        raise MeasurementFormatError(f"{name}: no data rows")
    data = data[:, [names.index(c) for c in want]]
    poses = []
    for row in data:
        a = row[3:] / af
        R = pin.exp3(a) if orient == "rotvec" else pin.rpy.rpyToMatrix(*a)
        poses.append(pin.SE3(R, row[:3] / lf))
    return poses


def write_poses(
    path: str | Path,
    poses: Sequence[pin.SE3],
    *,
    length_unit: str = "mm",
    angle_unit: str = "mrad",
    orientation: str = "rotvec",
) -> Path:
    """Write target poses (world frame) atomically."""
    lf = _unit(LENGTH_UNITS, length_unit, "length", "write_poses")
    af = _unit(ANGLE_UNITS, angle_unit, "angle", "write_poses")
    if orientation not in ("rotvec", "rpy"):
        raise MeasurementError(f"orientation {orientation!r}; use rotvec or rpy")
    buf = _header(
        [f"length_unit: {length_unit}", f"angle_unit: {angle_unit}", f"orientation: {orientation}"],
        "poses",
    )
    cols = [
        "x",
        "y",
        "z",
        *(("rx", "ry", "rz") if orientation == "rotvec" else ("roll", "pitch", "yaw")),
    ]
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(cols)
    for T in poses:
        a = pin.log3(T.rotation) if orientation == "rotvec" else pin.rpy.matrixToRpy(T.rotation)
        writer.writerow([_fmt(v) for v in [*(T.translation * lf), *(np.asarray(a) * af)]])
    return atomic_write_text(path, buf.getvalue())


# ----------------------------------------------------------------------------- commands
def write_commands(
    path: str | Path,
    actuated: Sequence[str],
    q_act: np.ndarray,
    indices: Sequence[int] | None = None,
    actuator_units: Sequence[str] | None = None,
) -> Path:
    """Write actuator commands (m, n_act) [SI] with the target index per row."""
    q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
    idx = list(range(q_act.shape[0])) if indices is None else list(indices)
    buf = _header([], "commands")
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(["pose", *_act_columns(actuated, actuator_units)])
    fac = _act_factors(actuator_units, len(actuated))
    for k, row in zip(idx, q_act, strict=True):
        writer.writerow([str(int(k)), *(_fmt(v) for v in row * fac)])
    return atomic_write_text(path, buf.getvalue())


def read_commands(path: str | Path, mech: Mechanism) -> tuple[np.ndarray, np.ndarray]:
    """(indices (m,), q_act (m, n_act) [SI]) from a command file."""
    name = Path(path).name
    _, columns, rows = _split(path, "commands")
    parsed = [_parse_column(c) for c in columns]
    names = [p[0] for p in parsed]
    missing = [c for c in ("pose", *mech.actuated) if c not in names]
    if missing:
        raise ColumnError(f"{name}: missing columns {missing}", missing=missing)
    data = _numbers(rows, columns, name)
    act = [names.index(j) for j in mech.actuated]
    fac = _actuator_factors(mech, [parsed[k][1] for k in act], name)
    return data[:, names.index("pose")].astype(int), data[:, act] / fac


#: largest file :func:`read_actuator_rows` reads [bytes]
MAX_POSES_BYTES = 5_000_000


def read_actuator_rows(
    path: str | Path, actuated: tuple[str, ...], max_rows: int | None = None
) -> np.ndarray:
    """Actuator rows (m, n_act) [m, rad] from any CSV whose header names the joints.

    Lenient on purpose (for viewing): ``#`` lines are comments, other columns are
    ignored, values are SI. A command file (:func:`write_commands`) qualifies.

    Raises:
        MeasurementError: unreadable file, missing columns, non-numeric or
            non-finite values, no rows.
    """
    path = Path(path)
    try:
        raw = path.read_bytes()[: MAX_POSES_BYTES + 1]
    except OSError as exc:
        raise MeasurementError(f"cannot read poses file {str(path)!r}: {exc.strerror}") from exc
    if len(raw) > MAX_POSES_BYTES:
        raise MeasurementError(f"poses file {str(path)!r} is larger than {MAX_POSES_BYTES} bytes")
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise MeasurementError(f"poses file {str(path)!r} is not UTF-8 text") from exc
    lines = [
        (n, line)
        for n, line in enumerate(text.splitlines(), 1)
        if not line.lstrip().startswith("#")
    ]
    lines = [(n, line) for n, line in lines if line.strip()]
    if not lines:
        raise MeasurementError(f"poses file {str(path)!r} is empty; expected a header line")
    header = [h.strip() for h in next(csv.reader([lines[0][1]]))]
    missing = [name for name in actuated if name not in header]
    if missing:
        raise MeasurementError(
            f"poses file {str(path)!r}: header lacks actuated joint(s) {missing}; the header "
            f"must name the actuated joints {list(actuated)}"
        )
    columns = [header.index(name) for name in actuated]
    rows = []
    for n, line in lines[1:]:
        cells = next(csv.reader(io.StringIO(line)), [])
        if len(cells) != len(header):
            raise MeasurementError(
                f"{path.name} line {n}: {len(cells)} values for {len(header)} header columns"
            )
        try:
            row = [float(cells[c]) for c in columns]
        except ValueError:
            raise MeasurementError(
                f"{path.name} line {n}: non-numeric value in {[cells[c] for c in columns]}"
            ) from None
        if not all(math.isfinite(v) for v in row):
            raise MeasurementError(f"{path.name} line {n}: NaN or infinite value")
        rows.append(row)
    if not rows:
        raise MeasurementError(f"poses file {str(path)!r} has a header but no poses")
    if max_rows is not None and len(rows) > max_rows:
        raise MeasurementError(
            f"poses file {str(path)!r} has {len(rows)} poses; at most {max_rows}"
        )
    return np.array(rows, dtype=float)
