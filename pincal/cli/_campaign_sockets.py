"""The ``sockets`` section of a campaign file: a plain CSV of ball-in-socket seatings.

``measurements.file`` is then a lab's table (no pincal header); the section says what
it lacks (:class:`pincal.io.SocketTable`). ``pincal run`` turns it into a sockets file
(``pincal import-sockets``, into ``OUT-inputs/sockets.csv``) before calibrating.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from pincal._yaml import shown
from pincal.errors import CampaignError

__all__ = ["SOCKETS_HELP", "Sockets", "plain_socket_section"]

SOCKETS_HELP = """\
  sockets:                   optional: measurements.file is a plain CSV of ball-in-socket
                             seatings (one row per seating, no pincal header)
    column: socket           the socket-id column (numbers 1, 2 or names A, B)
    distances: []            [[A, B, DIST, STD], …] known distances between sockets and
                             their 1σ [length_unit]; none: the scale is unidentifiable
    std: 0.005               1σ of one seating of the ball centre, per axis [length_unit]
    plate: plate             the plate's name
    ball: [0, 0, 0]          ball centre in the flange frame [length_unit], or unknown
    length_unit: mm          m | mm | um (std, distances, ball)
    columns: {}              {FILE_COLUMN: URDF_JOINT}: joint columns named otherwise
    joint_units: null        deg (every angle) or {angle: deg, length: mm} or {JOINT: UNIT}
    joint_reference: null    home or {JOINT: VALUE} [rad, m]: readings relative to a pose
"""


@dataclass(frozen=True)
class Sockets:
    """A plain socket table's declarations (see :data:`SOCKETS_HELP`)."""

    column: str = "socket"
    distances: tuple[tuple[str, str, float, float], ...] = ()
    std: float = 0.005
    plate: str = "plate"
    ball: tuple[float, float, float] | None = (0.0, 0.0, 0.0)
    length_unit: str = "mm"
    columns: dict[str, str] = field(default_factory=dict)
    joint_units: str | None = None
    joint_reference: str | None = None

    def check(self, key: str) -> None:
        """Raise CampaignError naming ``key.field`` for the first invalid entry of this section."""
        if self.length_unit not in ("m", "mm", "um"):
            raise CampaignError(
                f"{key}.length_unit: {shown(self.length_unit)} is not valid; use m, mm or um"
            )
        if not self.std > 0:
            raise CampaignError(f"{key}.std must be > 0 [{self.length_unit}], got {self.std}")
        for i, (a, b, value, std) in enumerate(self.distances):
            where = f"{key}.distances[{i}]"
            if a == b:
                raise CampaignError(f"{where}: a known distance joins two sockets, got {a!r} twice")
            if not (value > 0 and std > 0):
                raise CampaignError(
                    f"{where}: distance and std must be > 0 [{self.length_unit}], got "
                    f"{value}, {std}"
                )

    def options(self) -> list[str]:
        """The ``pincal import-sockets`` options of this section."""
        opts = ["--socket-column", self.column, "--std", repr(self.std), "--plate", self.plate]
        opts += [x for d in self.distances for x in ("--distance", ",".join(map(str, d)))]
        ball = "unknown" if self.ball is None else ",".join(repr(v) for v in self.ball)
        opts += ["--ball", ball, "--length-unit", self.length_unit]
        if self.columns:
            opts += ["--columns", ",".join(f"{c}={j}" for c, j in self.columns.items())]
        opts += ["--joint-units", self.joint_units] if self.joint_units else []
        opts += ["--joint-reference", self.joint_reference] if self.joint_reference else []
        return opts


def _entries(value: object) -> object:
    """``{a: b, …}`` → ``'a=b …'`` (the header form); anything else unchanged."""
    if isinstance(value, dict):
        return " ".join(f"{k}={v}" for k, v in value.items())
    return value


def _socket(value: object) -> object:
    """A socket id written as a number in YAML (``1``) → its text (``'1'``)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return value
    return str(int(value)) if float(value).is_integer() else str(value)


def plain_socket_section(data: object) -> object:
    """The raw ``sockets`` mapping with YAML's conveniences spelt in the typed form.

    Socket ids written as numbers become text, ``ball: unknown`` becomes None, and
    ``joint_units`` / ``joint_reference`` mappings become ``NAME=VALUE`` entries.
    """
    if not isinstance(data, dict):
        return data
    out = dict(data)
    if out.get("ball") == "unknown":
        out["ball"] = None
    for key in ("joint_units", "joint_reference"):
        if key in out:
            out[key] = _entries(out[key])
    if isinstance(out.get("columns"), dict):
        out["columns"] = {str(k): v for k, v in out["columns"].items()}
    d = out.get("distances")
    if isinstance(d, list):
        out["distances"] = [
            [_socket(x[0]), _socket(x[1]), *x[2:]] if isinstance(x, list) and len(x) >= 2 else x
            for x in d
        ]
    return out
