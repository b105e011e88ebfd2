"""Socket files: poses of a ball on the flange seated in the sockets of a plate.

::

    # pincal sockets 1
    # frame: ee_link                  the flange frame (must match the model's)
    # length_unit: mm                 m | mm | um  (std, distance, ball)
    # plate: plate1                   files of one plate share its socket centres
    # std: 0.005                      1σ of one seating of the ball centre, per axis
    # distance: A, B, 50, 0.002       optional, repeatable: a known distance between two
    #                                 socket centres and its 1σ (calibrated plate or bar)
    # ball: unknown                   the ball centre in the flange frame: unknown
    #                                 (identified) or x, y, z (default 0, 0, 0)
    shoulder_pan_joint,…,wrist_3_joint,socket

The actuator columns come first (optional bracketed units), then ``socket`` (the name
of the socket the ball sits in). Without a known distance nothing measured fixes the
length scale (see :mod:`pincal.measure._sockets`). In metres the file round-trips exactly.
Bounds, as on the pose route: every σ between 1 nm and 1 m, a known distance within
10 km, a given ball within :data:`MAX_BALL` of the flange.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pincal.errors import ColumnError, MeasurementFormatError, clip
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
from pincal.io._measurement_header import MAX_COORDINATE, length_sigma
from pincal.io._names import quote_value
from pincal.io._units import (
    LENGTH_UNITS,
    unit_factor,
)
from pincal.measure import KnownDistance, SocketData, SocketPlate
from pincal.model import Mechanism

__all__ = ["MAX_BALL", "read_socket_data", "write_socket_data"]

#: farthest a given ball centre is from the flange [m]: a seated ball is on the tool
MAX_BALL = 2.0


def _distance(text: str, lf: float, name: str) -> KnownDistance:
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 4 or not all(parts):
        raise MeasurementFormatError(
            f"{name}: header 'distance' is {clip(text)}; write 'A, B, distance, std' "
            "(two socket names, the calibrated distance and its 1σ in length_unit)"
        )
    value, std = (parse_float(p, f"{name} header 'distance'") for p in parts[2:])
    if not (np.isfinite(value) and value > 0 and np.isfinite(std) and std > 0):
        raise MeasurementFormatError(
            f"{name}: header 'distance' is {clip(text)}; distance and std must be > 0"
        )
    if value / lf > MAX_COORDINATE:
        raise MeasurementFormatError(
            f"{name}: header 'distance' is {clip(text)}: more than {MAX_COORDINATE / 1e3:g} km "
            "between two sockets; check the value and '# length_unit'"
        )
    sigma = length_sigma(std, "header 'distance' std", lf, name)
    return KnownDistance(parts[0], parts[1], value / lf, sigma)


def read_socket_data(path: str | Path, mech: Mechanism) -> SocketData:
    """Read a socket file (see the module doc) against ``mech``.

    Returns:
        SocketData [SI].

    Raises:
        MeasurementFormatError: bad header, frame of another model; ColumnError: missing
        columns; BadValueError / NonFiniteValueError: bad cells; ActuatorRangeError: an
        actuator far outside its URDF limits.
    """
    name = Path(path).name
    header, columns, rows = split_file(path, "sockets")
    lf = unit_factor(LENGTH_UNITS, header_value(header, "length_unit", "m", name), "length", name)
    frame = header_value(header, "frame", mech.measured_frame, name)
    if frame != mech.measured_frame:
        raise MeasurementFormatError(
            f"{name} measures frame {frame!r} but the model's tool frame is {mech.measured_frame!r}"
        )
    std = length_sigma(positive_value(header_value(header, "std", None, name), "std", name),
                       "header 'std'", lf, name)  # fmt: skip
    distances = tuple(_distance(t, lf, name) for t in header.get("distance", []))
    plate = SocketPlate(header_value(header, "plate", "plate", name), std, distances)
    ball_text = header_value(header, "ball", "0, 0, 0", name)
    ball = None
    if ball_text.strip() != "unknown":
        ball = np.array([parse_float(x, f"{name} header 'ball'")
                         for x in ball_text.replace(",", " ").split()]) / lf  # fmt: skip
        if ball.size != 3 or not np.all(np.isfinite(ball)):
            raise MeasurementFormatError(
                f"{name}: header 'ball' is {clip(ball_text)}; give 'unknown' or x, y, z"
            )
        if np.linalg.norm(ball) > MAX_BALL:
            raise MeasurementFormatError(
                f"{name}: header 'ball' is {clip(ball_text)}, {np.linalg.norm(ball):.3g} m from "
                f"the flange; a ball the robot seats sits on its tool, within {MAX_BALL:g} m: "
                "check the value and '# length_unit' (or give 'unknown')"
            )
    parsed = [parse_column(c) for c in columns]
    names = [p[0] for p in parsed]
    if "socket" not in names:
        raise ColumnError(f"{name}: missing columns ['socket']", missing=["socket"])
    # the joints as the pose route reads them: header/sidecar columns, units, reference
    act, declared = joint_columns(mech, header, parsed, name)
    if not rows:
        raise MeasurementFormatError(f"{name}: no data rows")
    k_socket = names.index("socket")
    bad = [i for i, r in enumerate(rows, start=1) if len(r) != len(columns)]
    if bad:
        raise MeasurementFormatError(
            f"{name} data row {bad[0]}: {len(rows[bad[0] - 1])} fields, the column line has "
            f"{len(columns)}"
        )
    sockets = tuple(r[k_socket].strip() for r in rows)
    numeric = [c for k, c in enumerate(columns) if k != k_socket]
    data = parse_numbers([[c for k, c in enumerate(r) if k != k_socket] for r in rows],
                         numeric, name)  # fmt: skip
    in_data = [k - (k > k_socket) for k in act]  # data holds every column but the socket's
    q_act = read_joints(mech, data[:, in_data], declared, [parsed[k][1] for k in act],
                        [columns[k] for k in act], name)  # fmt: skip
    return SocketData(plate, q_act, sockets, mech.actuated, frame, ball)


def write_socket_data(path: str | Path, data: SocketData, length_unit: str = "m") -> Path:
    """Write ``data`` as a socket file (actuators in SI, lengths in ``length_unit``).

    Returns:
        The written path.

    Raises:
        MeasurementFormatError: unknown length unit.
    """
    lf = unit_factor(LENGTH_UNITS, length_unit, "length", "write_socket_data")
    plate = data.plate
    lines = [
        f"frame: {quote_value(data.frame, 'frame')}",
        f"length_unit: {length_unit}",
        f"plate: {plate.name}",
        f"std: {fmt(plate.std * lf)}",
    ]
    lines += [f"distance: {k.a}, {k.b}, {fmt(k.value * lf)}, {fmt(k.std * lf)}"
              for k in plate.distances]  # fmt: skip
    ball = "unknown" if data.ball is None else ", ".join(fmt(x * lf) for x in data.ball)
    lines.append(f"ball: {ball}")
    columns = [*actuator_columns(data.actuated, None), "socket"]
    rows = [[fmt(v) for v in data.q_act[i]] + [data.socket[i]] for i in range(len(data))]
    return write_csv(path, "sockets", lines, columns, rows)
