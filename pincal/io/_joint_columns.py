"""Joint columns of measurement files: names, units and reference, declared once.

The declarations (:class:`pincal.model.Sidecar` ``readings``: ``columns``,
``joint_units``, ``joint_reference``) come from the model's sidecar; a file header
may give them too and wins key by key::

    # columns: torso1=torso_lift_joint armL1=arm_1_joint
    # joint_units: angle=deg length=mm          (or deg; or a joint: arm_1_joint=deg)
    # joint_reference: home                     (or arm_1_joint=0.5 …, SI values)

A joint's column is the column mapped to it, else the one named after it. Its unit
is the column title's bracketed unit, else the declared one (joint, then kind), else
SI. Values outside the joint's URDF range, and for joints without one values
implausible for their unit (more than two turns of angle, more than 10 m), are refused
naming the column and the row: they are the usual sign of a unit mistake.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from pincal._yaml import shown
from pincal.errors import (
    ActuatorRangeError,
    BadValueError,
    ColumnError,
    MeasurementFormatError,
    PincalError,
)
from pincal.io._csv import Header, header_value
from pincal.io._units import ANGLE_UNITS, LENGTH_UNITS, check_actuator_ranges, unit_factor
from pincal.model import JointReadings, Mechanism

__all__ = ["HEADER_KEYS", "joint_columns", "read_joints"]

HEADER_KEYS = ("columns", "joint_units", "joint_reference")
#: the largest plausible magnitude of a joint reading [SI]: two turns, 10 m
_PLAUSIBLE = {"angle": 4 * math.pi, "length": 10.0}


_EXAMPLE = {"columns": "torso1=torso_lift_joint", "joint_units": "elbow_joint=deg",
            "joint_reference": "elbow_joint=0.1 wrist_joint=-0.2"}


def _pairs(header: Header, key: str, name: str) -> dict[str, str]:
    if key not in header:
        return {}
    out = {}
    for item in header_value(header, key, None, name).split():
        k, eq, v = item.partition("=")
        if not eq or not k or not v:
            raise MeasurementFormatError(
                f"{name}: header '{key}' entry {shown(item)}; write NAME=VALUE entries "
                f"separated by spaces (e.g. '# {key}: {_EXAMPLE.get(key, 'NAME=VALUE')}')"
            )
        out[k] = v
    return out


def _declared(mech: Mechanism, header: Header, name: str) -> JointReadings:
    units: dict[str, str] | str = {}
    if "joint_units" in header:  # one unit (``deg``: every angle) or NAME=UNIT entries
        text = header_value(header, "joint_units", None, name).strip()
        units = text if text and "=" not in text else _pairs(header, "joint_units", name)
    ref: object = {}
    if "joint_reference" in header:
        text = header_value(header, "joint_reference", None, name)
        ref = "home" if text.strip() == "home" else _pairs(header, "joint_reference", name)
        if isinstance(ref, dict):
            try:
                ref = {k: float(v) for k, v in ref.items()}
            except ValueError:
                raise MeasurementFormatError(
                    f"{name}: header 'joint_reference' {shown(text)}; write 'home' or "
                    "JOINT=VALUE entries [rad or m]"
                ) from None
    try:
        file = JointReadings.from_values(
            _pairs(header, "columns", name), units or None, ref, f"{name} header"
        )
    except PincalError as exc:
        raise MeasurementFormatError(str(exc)) from None
    return mech.sidecar.readings.updated(file)


def _kind(mech: Mechanism, joint: str) -> str:
    return "angle" if mech.tree.joints[joint].type in ("revolute", "continuous") else "length"


def joint_columns(
    mech: Mechanism, header: Header, parsed: Sequence[tuple[str, str | None]], name: str
) -> tuple[list[int], JointReadings]:
    """The column index of each actuated joint and the declarations in force.

    Args:
        mech: the model (actuated joints, sidecar declarations).
        header: the file header.
        parsed: (name, bracketed unit) of each column title.
        name: file name for messages.

    Raises:
        ColumnError: a joint without a column, a mapping to a joint the model does not
            actuate; MeasurementFormatError: a malformed declaration.
    """
    decl = _declared(mech, header, name)
    names = [p[0] for p in parsed]
    wrong = {c: j for c, j in decl.columns.items() if j not in mech.actuated and c in names}
    if wrong:
        c, j = next(iter(wrong.items()))
        raise ColumnError(
            f"{name}: column {shown(c)} is mapped to joint {shown(j)}, which model "
            f"{mech.name!r} does not actuate (actuated: {list(mech.actuated)})",
            unknown=[c],
        )
    idx, missing = [], []
    for joint in mech.actuated:
        titles = [c for c, j in decl.columns.items() if j == joint] + [joint]
        found = [names.index(c) for c in titles if c in names]
        if not found:
            missing.append(joint if len(titles) == 1 else f"{joint} (or {titles[0]})")
            continue
        idx.append(found[0])
    if missing:
        raise ColumnError(
            f"{name}: missing actuator columns {missing} (model {mech.name!r} actuates "
            f"{list(mech.actuated)}; map other column names with 'columns' in the sidecar "
            f"or the header)",
            missing=missing,
        )
    return idx, decl


def read_joints(
    mech: Mechanism,
    raw: np.ndarray,
    decl: JointReadings,
    units: Sequence[str | None],
    titles: Sequence[str],
    name: str,
) -> np.ndarray:
    """Joint values (m, n_act) [SI] from the raw readings (m, n_act) of the joint columns.

    Args:
        mech: the model.
        raw: the readings as written, one column per actuated joint.
        decl: the declarations in force (:func:`joint_columns`).
        units: each column's bracketed unit, or None.
        titles: each column's title, for messages.
        name: file name for messages.

    Raises:
        MeasurementFormatError: an unknown unit; ActuatorRangeError: a value outside its
            joint's URDF range (names the column and data row); BadValueError: a reading
            of a joint without a URDF range implausible for its unit (the same).
    """
    if isinstance(decl.reference, dict):
        unknown = [j for j in decl.reference if j not in mech.actuated]
        if unknown:
            raise MeasurementFormatError(
                f"{name}: joint_reference names {shown(unknown)}, not actuated joints of "
                f"model {mech.name!r} ({list(mech.actuated)})"
            )
    q = np.empty_like(raw, dtype=float)
    home = mech.actuators_of(mech.q_home) if decl.reference == "home" else None
    factors: list[float] = []
    offsets: list[float] = []
    for k, joint in enumerate(mech.actuated):
        kind = _kind(mech, joint)
        unit = units[k] or decl.units.get(joint) or decl.units.get(kind)
        table = ANGLE_UNITS if kind == "angle" else LENGTH_UNITS
        factor = unit_factor(table, unit, kind, f"{name} column {titles[k]}") if unit else 1.0
        factors.append(factor)
        if home is not None:
            offset = float(home[k])
        elif isinstance(decl.reference, dict):
            offset = decl.reference.get(joint, 0.0)
        else:
            offset = 0.0
        q[:, k] = raw[:, k] / factor + offset
        offsets.append(offset)
    try:
        check_actuator_ranges(mech, q, name, titles)
    except ActuatorRangeError as exc:
        k = list(mech.actuated).index(exc.joint) if exc.joint in mech.actuated else -1
        if k < 0 or offsets[k] == 0.0:
            raise
        ref = "home" if home is not None else "the declared joint_reference"
        raise ActuatorRangeError(
            f"{exc}; the file's reading is relative to {ref} ({offsets[k]:+.6g} "
            f"{'rad' if _kind(mech, exc.joint) == 'angle' else 'm'} added, 'joint_reference'): "
            "if the readings are absolute, drop that declaration",
            exc.row, exc.column, exc.joint, exc.limits,
        ) from None
    for k, joint in enumerate(mech.actuated):  # joints without a URDF range
        kind, factor = _kind(mech, joint), factors[k]
        unit = units[k] or decl.units.get(joint) or decl.units.get(kind)
        si = "rad" if kind == "angle" else "m"
        limit = _PLAUSIBLE[kind] * factor
        bad = np.flatnonzero(np.abs(raw[:, k]) > limit)
        if bad.size:
            i = int(bad[0])
            hint = " (degrees read as radians?)" if kind == "angle" and factor == 1.0 else ""
            raise BadValueError(
                f"{name} data row {i + 1}, column {shown(titles[k])}: {raw[i, k]:.6g} "
                f"{unit or si} is implausible for joint {joint!r} (more than "
                f"{limit:.6g} {unit or si}){hint}; declare the column's unit (joint_units "
                f"in the sidecar or header, or '{titles[k]} [unit]')",
                i + 1,
                titles[k],
            )
    return q
