"""Instrument files: one scalar reading per pose (ballbar, sphere probe, planes, gauge).

::

    # pincal instrument 1
    # kind: distance                  distance | sphere | plane | point | a registered kind
    # frame: effector                 the tool frame (must match the model's)
    # length_unit: mm                 m | mm | um  (value, std, radius, initial)
    # std: 0.001                      1σ noise of one reading, in length_unit
    # radius: 12.7                    sphere only: calibrated radius (probe tip included)
    # direction: 0, 0, 1              point only: the gauge axis (default +z)
    # normal: 0, 0, 0, 1              plane only, optional, repeatable: id, nx, ny, nz
    # initial: 0.1, 0.2, 0.3, 0       optional start values of the instrument parameters
    leg1_slide [mm],…,leg6_slide [mm],value[,plane]

The actuator columns come first (optional bracketed units), then ``value`` (the
reading) and, for planes, ``plane`` (integer plane id). Plane tilts in ``initial``
are in rad. In metres the file round-trips exactly.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pincal._yaml import shown
from pincal.errors import ColumnError, MeasurementError, MeasurementFormatError, clip
from pincal.io._csv import (
    actuator_columns,
    fmt,
    header_value,
    parse_column,
    parse_float,
    parse_numbers,
    positive_value,
    split_file,
    write_csv,
)
from pincal.io._joint_columns import joint_columns, read_joints
from pincal.io._measurement_header import length_sigma
from pincal.io._names import quote_value
from pincal.io._units import (
    LENGTH_UNITS,
    unit_factor,
)
from pincal.measure import InstrumentData, instrument_class, instrument_kinds
from pincal.model import Mechanism

__all__ = ["read_instrument_data", "write_instrument_data"]


def _vector(text: str, n: int, key: str, name: str) -> np.ndarray:
    v = np.array([parse_float(x, f"{name} header {key!r}") for x in text.replace(",", " ").split()])
    if v.size != n or not np.all(np.isfinite(v)):
        raise MeasurementFormatError(
            f"{name}: header {key!r} is {clip(text)}; it needs {n} finite numbers"
        )
    return v


class _Header:
    """:class:`pincal.measure.HeaderValues` of one file (lengths in metres)."""

    def __init__(self, header: dict[str, list[str]], lf: float, name: str) -> None:
        self.header, self.lf, self.name = header, lf, name

    def has(self, key: str) -> bool:
        return key in self.header

    def length(self, key: str, default: float | None = None) -> float:
        if default is not None and key not in self.header:
            return default
        text = header_value(self.header, key, None, self.name)
        return positive_value(text, key, self.name) / self.lf

    def vector(self, key: str, n: int, default: str | None = None) -> np.ndarray:
        return _vector(header_value(self.header, key, default, self.name), n, key, self.name)

    def vectors(self, key: str, n: int) -> list[np.ndarray]:
        return [_vector(t, n, key, self.name) for t in self.header.get(key, [])]


def read_instrument_data(path: str | Path, mech: Mechanism) -> InstrumentData:
    """Read an instrument file (see the module doc) against ``mech``.

    The kind's class (:func:`pincal.measure.instrument_class`) reads its own header
    keys and names its id column.

    Returns:
        InstrumentData [SI].

    Raises:
        MeasurementFormatError: bad header or kind; ColumnError: missing columns;
        BadValueError / NonFiniteValueError: bad cells; ActuatorRangeError: an actuator
        far outside its URDF limits; FrameMismatchError is reported as
        MeasurementFormatError naming both frames.
    """
    name = Path(path).name
    header, columns, rows = split_file(path, "instrument")
    kind = header_value(header, "kind", None, name)
    if kind not in instrument_kinds():
        raise MeasurementFormatError(
            f"{name}: kind {shown(kind)} unknown; use one of {instrument_kinds()}"
        )
    cls = instrument_class(kind)
    lf = unit_factor(LENGTH_UNITS, header_value(header, "length_unit", "m", name), "length", name)
    frame = header_value(header, "frame", mech.measured_frame, name)
    if frame != mech.measured_frame:
        raise MeasurementFormatError(
            f"{name} measures frame {shown(frame)} but the model's tool frame is "
            f"{mech.measured_frame!r}"
        )
    if "std" not in header:
        raise MeasurementFormatError(
            f"{name}: header line '# std: …' is required: the 1σ noise of one reading in the "
            f"file's length unit (e.g. '# std: 0.001' with '# length_unit: mm' for a ballbar "
            f"read to 1 µm); the fit weights the file by it and the quality gate judges its "
            f"residuals against it"
        )
    std = positive_value(header_value(header, "std", None, name), "std", name)
    std = length_sigma(std, "header 'std'", lf, name)
    try:
        inst = cls.from_header(std, _Header(header, lf, name))
    except MeasurementFormatError:
        raise
    except MeasurementError as e:
        raise MeasurementFormatError(f"{name}: {e}") from None
    parsed = [parse_column(c) for c in columns]
    names = [p[0] for p in parsed]
    need = ["value", *([cls.id_column] if cls.id_column else [])]
    missing = [c for c in need if c not in names]
    if missing:
        raise ColumnError(f"{name}: missing columns {missing}", missing=missing)
    # the joints as the pose route reads them: header/sidecar columns, units, reference
    act, declared = joint_columns(mech, header, parsed, name)
    data = parse_numbers(rows, columns, name)
    if data.shape[0] == 0:
        raise MeasurementFormatError(f"{name}: no data rows")
    col = {c: k for k, c in enumerate(names)}
    q_act = read_joints(mech, data[:, act], declared, [parsed[k][1] for k in act],
                        [columns[k] for k in act], name)  # fmt: skip
    values = data[:, col["value"]] / lf
    ids = data[:, col[cls.id_column]] if cls.id_column else None
    initial = None
    if "initial" in header:
        k = len(inst.parameter_names)
        if k == 0:
            raise MeasurementFormatError(
                f"{name}: 'initial' gives start values of the {kind} parameters, which the "
                "header does not define yet (a plane file: give the 'normal' lines with it)"
            )
        raw = _vector(header_value(header, "initial", None, name), k, "initial", name)
        units = np.array([1.0 if u == "rad" else lf for u in inst.parameter_units])
        initial = raw / units
    try:
        return InstrumentData(inst, q_act, values, mech.actuated, frame, ids, initial)
    except MeasurementFormatError:
        raise
    except MeasurementError as e:
        raise MeasurementFormatError(f"{name}: {e}") from None


def write_instrument_data(path: str | Path, data: InstrumentData, length_unit: str = "m") -> Path:
    """Write ``data`` as an instrument file (actuators in SI, lengths in ``length_unit``).

    Returns:
        The written path.

    Raises:
        MeasurementFormatError: unknown length unit.
    """
    lf = unit_factor(LENGTH_UNITS, length_unit, "length", "write_instrument_data")
    inst = data.instrument
    lines = [
        f"kind: {inst.kind}",
        f"frame: {quote_value(data.frame, 'frame')}",
        f"length_unit: {length_unit}",
        f"std: {fmt(inst.std * lf)}",
        *inst.header(lambda x: fmt(x * lf), fmt),
    ]
    if data.initial is not None:
        units = np.array([1.0 if u == "rad" else lf for u in inst.parameter_units])
        lines.append("initial: " + ", ".join(fmt(x) for x in data.initial * units))
    id_col = inst.id_column
    columns = [*actuator_columns(data.actuated, None), "value", *([id_col] if id_col else [])]
    rows = []
    for i in range(len(data)):
        row = [fmt(v) for v in data.q_act[i]] + [fmt(data.values[i] * lf)]
        if data.ids is not None:
            row.append(str(int(data.ids[i])))
        rows.append(row)
    return write_csv(path, "instrument", lines, columns, rows)
