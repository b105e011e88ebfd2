"""Plain socket tables: a lab's CSV of ball-in-socket seatings, read as it is.

A foreign delimited table (see :mod:`pincal.io._delimited`: ``,`` ``;`` or tab, one
title line, no pincal header) with one row per seating: a column per actuated joint and
a column naming the socket the ball sits in (numbers ``1``/``2`` or names ``A``/``B``;
``1`` and ``1.0`` are the same socket). What the file does not say is declared by a
:class:`SocketTable` (a campaign's ``sockets`` section, or ``pincal import-sockets``):
the socket column, the plate, the seating σ, the known distances, the ball.

Joint columns are read as in marker tables (:mod:`pincal.io._joint_columns`): named as
the URDF joint (any case) or mapped by ``columns``; units from the title's bracket,
else ``joint_units``, else SI; ``joint_reference`` for readings relative to a pose.
The table's declarations win over the model's sidecar, key by key.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pincal._yaml import shown
from pincal.errors import ColumnError, MeasurementError, MeasurementFormatError, clip
from pincal.io._csv import Header
from pincal.io._delimited import Table, read_table
from pincal.io._joint_columns import joint_columns, read_joints
from pincal.io._marker_file import check_titles, joint_titles
from pincal.io._measurement_header import length_sigma
from pincal.io._names import is_decimal
from pincal.io._socket_file import MAX_BALL
from pincal.io._units import LENGTH_UNITS, unit_factor
from pincal.measure import KnownDistance, SocketData, SocketPlate
from pincal.model import Mechanism

__all__ = ["SocketTable", "read_socket_table", "socket_id"]


def socket_id(value: object) -> str:
    """A socket id as text: ``1``, ``1.0`` and ``"1"`` are ``"1"``; names stripped."""
    text = str(value).strip()
    if is_decimal(text):
        x = float(text)
        if x.is_integer():
            return str(int(x))
    return text


@dataclass(frozen=True)
class SocketTable:
    """What a plain socket table does not say (lengths in ``length_unit``).

    Attributes:
        column: the title of the socket-id column.
        std: 1σ of one seating of the ball centre, per axis (> 0).
        distances: (A, B, distance, 1σ) per known distance between two sockets.
        plate: the plate's name (files of one plate share its socket centres).
        ball: (x, y, z) of the ball centre in the flange frame, or None (unknown).
        length_unit: m | mm | um of std, distances and ball.
        columns: file column → URDF joint.
        joint_units: one unit (``deg``) or ``NAME=UNIT`` entries (``angle=deg
            length=mm``, or per joint), or None.
        joint_reference: ``home`` or ``JOINT=VALUE`` entries [rad, m], or None.
    """

    column: str = "socket"
    std: float = 0.005
    distances: tuple[tuple[str, str, float, float], ...] = ()
    plate: str = "plate"
    ball: tuple[float, float, float] | None = (0.0, 0.0, 0.0)
    length_unit: str = "mm"
    columns: Mapping[str, str] = field(default_factory=dict)
    joint_units: str | None = None
    joint_reference: str | None = None

    def header(self) -> Header:
        """Units and reference as header entries of :mod:`pincal.io._joint_columns`.

        ``columns`` is applied to the titles instead (:func:`_mapped_titles`): a title
        may hold spaces (``Joint 1 [deg]``), which header entries cannot.
        """
        out: Header = {}
        if self.joint_units:
            out["joint_units"] = [self.joint_units]
        if self.joint_reference:
            out["joint_reference"] = [self.joint_reference]
        return out

    def plate_of(self, name: str) -> SocketPlate:
        """The plate [SI] (``name``: the table, for messages).

        Raises:
            MeasurementError: an unknown length unit, std or a distance ≤ 0, a distance
                joining a socket to itself.
        """
        lf = unit_factor(LENGTH_UNITS, self.length_unit, "length", name)
        known = []
        for a, b, value, std in self.distances:
            if not (np.isfinite(value) and value > 0 and np.isfinite(std) and std > 0):
                raise MeasurementError(
                    f"{name}: known distance {a}–{b}: the distance and its std must be finite "
                    f"and > 0 [{self.length_unit}], got {value:g}, {std:g}"
                )
            try:
                sigma = length_sigma(std, f"the std of distance {a}–{b}", lf, name)
                known.append(KnownDistance(socket_id(a), socket_id(b), value / lf, sigma))
            except MeasurementError as exc:
                raise _named(exc, name, f"distances in {self.length_unit}") from None
        try:
            std = length_sigma(self.std, "the seating std (--std)", lf, name)
            return SocketPlate(self.plate, std, tuple(known))
        except MeasurementError as exc:
            raise _named(exc, name, f"std in {self.length_unit}") from None


def _named(exc: MeasurementError, name: str, units: str) -> MeasurementError:
    """``exc`` naming the file once and the units (a format error stays one)."""
    text = str(exc) if str(exc).startswith(f"{name}:") else f"{name}: {exc}"
    kind = MeasurementFormatError if isinstance(exc, MeasurementFormatError) else MeasurementError
    return kind(f"{text} ({units})")


def _mapped_titles(
    table: Table, mech: Mechanism, columns: Mapping[str, str]
) -> list[tuple[str, str | None]]:
    """(name, unit) per title, a title mapped by ``columns`` named as its joint.

    A mapped column matches a title whole or without its bracketed unit, in any case.

    Raises:
        ColumnError: a mapped column not in the table, or mapped to a joint the model
            does not actuate.
    """
    parsed = joint_titles(table, mech)
    out = list(parsed)
    for column, joint in columns.items():
        want = column.strip().lower()
        hits = [k for k, (c, (n, _)) in enumerate(zip(table.columns, parsed, strict=True))
                if want in (c.lower(), n.lower())]  # fmt: skip
        if not hits:
            raise ColumnError(
                f"{table.name}: columns maps {shown(column)} to {shown(joint)}, but the table "
                f"has no column {shown(column)}; its columns are "
                f"{clip(', '.join(table.columns), 400)}",
                missing=[column],
            )
        if joint not in mech.actuated:
            raise ColumnError(
                f"{table.name}: columns maps {shown(column)} to {shown(joint)}, which model "
                f"{mech.name!r} does not actuate (actuated: {list(mech.actuated)})",
                unknown=[column],
            )
        out[hits[0]] = (joint, parsed[hits[0]][1])
    return out


def read_socket_table(path: str | Path, mech: Mechanism, spec: SocketTable) -> SocketData:
    """The seatings of a plain table [SI], as a socket file would give them.

    Args:
        path: the table (never modified).
        mech: the model (actuated joints, measured frame = the flange, sidecar).
        spec: the declarations the table lacks.

    Returns:
        SocketData of every row (``mech.measured_frame``; the ball as declared).

    Raises:
        ColumnError: the socket column or a joint column is missing (columns listed).
        MeasurementFormatError: no data rows, a single socket, a known distance naming a
            socket absent from the table, a malformed declaration.
        BadValueError: a joint cell that is not a number, an empty socket cell, a joint
            reading implausible for its unit; ActuatorRangeError: outside its URDF range.
    """
    table = read_table(path)
    check_titles(table)
    name = table.name
    if not table.rows:
        raise MeasurementFormatError(f"{name}: no data rows")
    k_socket = table.find("socket", [spec.column], {})
    if k_socket is None:
        raise ColumnError(
            f"{name}: no socket column {shown(spec.column)} (the column naming each row's "
            f"socket: sockets.column in a campaign file, --socket-column of import-sockets); "
            f"columns are {clip(', '.join(table.columns), 400)}",
            missing=[spec.column],
        )
    sockets = tuple(socket_id(table.text(i, k_socket)) for i in range(len(table.rows)))
    plate = spec.plate_of(name)
    seen = sorted(set(sockets))
    if len(seen) < 2:
        raise MeasurementFormatError(
            f"{name}: every row names socket {shown(seen[0])} (column {shown(spec.column)}): "
            "one socket fixes neither the length scale nor the plate; seat the ball in at "
            "least two sockets of known distance"
        )
    for k in plate.distances:
        absent = [s for s in (k.a, k.b) if s not in seen]
        if absent:
            raise MeasurementFormatError(
                f"{name}: known distance {k.a}–{k.b} names socket(s) {shown(absent)} that no "
                f"row of column {shown(spec.column)} holds; the sockets are {shown(seen)}"
            )
    parsed = _mapped_titles(table, mech, spec.columns)
    try:
        joints, decl = joint_columns(mech, spec.header(), parsed, name)
    except ColumnError as exc:
        found = clip(", ".join(table.columns), 400)
        raise ColumnError(
            f"{exc} (for a plain socket table: sockets.columns in a campaign file, "
            f"--columns of import-sockets); the table's columns are {found}",
            missing=exc.missing,
            unknown=exc.unknown,
        ) from None
    if k_socket in joints:
        raise ColumnError(
            f"{name}: column {shown(table.columns[k_socket])} is both the socket column and "
            "a joint's",
            unknown=[table.columns[k_socket]],
        )
    raw = np.array([[table.number(i, k) for k in joints] for i in range(len(table.rows))])
    titles = [table.columns[k] for k in joints]
    q_act = read_joints(mech, raw, decl, [parsed[k][1] for k in joints], titles, name)
    ball = None
    if spec.ball is not None:
        ball = np.asarray(spec.ball, dtype=float) / unit_factor(
            LENGTH_UNITS, spec.length_unit, "length", name
        )
        if not np.linalg.norm(ball) <= MAX_BALL:
            raise MeasurementError(
                f"{name}: the ball (--ball) is {np.linalg.norm(ball):.3g} m from the flange; a "
                f"ball the robot seats sits on its tool, within {MAX_BALL:g} m: check the value "
                "and --length-unit (or give 'unknown')"
            )
    return SocketData(plate, q_act, sockets, mech.actuated, mech.measured_frame, ball)
