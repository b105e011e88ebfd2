"""Socket plates: their known distances and the centres their files share.

The files of one plate share its socket centres (three unknowns per socket: plates in
order of first appearance, their sockets in order of first appearance in any file);
each known distance of a plate gives ``D − ‖c_a − c_b‖``. See
:mod:`pincal.measure._sockets` for the model.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, cast

import numpy as np

from pincal.errors import MeasurementError
from pincal.measure._artefact_kind import Artefact, SharedTerms

__all__ = ["SCALE_MESSAGE", "KnownDistance", "SocketPlate", "SocketPlates"]

#: the warning of a socket campaign whose length scale nothing measured fixes
SCALE_MESSAGE = (
    "nothing measured fixes the length scale: add the plate's known distance "
    "('# distance: A, B, 50, 0.002' in the sockets file, length_unit; in a campaign file "
    "sockets.distances: [[A, B, 50, 0.002]]; --distance of pincal import-sockets); without "
    "it the fitted arm shrinks or grows with the socket centres and no residual shows it"
)


@dataclass(frozen=True)
class KnownDistance:
    """A calibrated distance between two socket centres.

    Attributes:
        a, b: socket names; value: the distance [m] (> 0); std: its 1σ [m] (> 0).
    """

    a: str
    b: str
    value: float
    std: float

    def __post_init__(self) -> None:
        if self.a == self.b:
            raise MeasurementError(f"a known distance joins two sockets, got {self.a!r} twice")
        for what, v in (("distance", self.value), ("distance std", self.std)):
            if not (np.isfinite(v) and v > 0):
                raise MeasurementError(f"{what} between {self.a!r} and {self.b!r} must be "
                                       f"finite and > 0 [m], got {v}")  # fmt: skip


@dataclass(frozen=True)
class SocketPlate:
    """A plate (or bar) of sockets whose centres are unknown.

    Attributes:
        name: the plate's name; files naming the same plate share its socket centres.
        std: 1σ of one seating of the ball centre, per axis [m] (> 0).
        distances: the known distances between its sockets.

    Raises:
        MeasurementError: std ≤ 0.
    """

    name: str = "plate"
    std: float = 5e-6
    distances: tuple[KnownDistance, ...] = ()

    def __post_init__(self) -> None:
        if not (np.isfinite(self.std) and self.std > 0):
            raise MeasurementError(f"socket seating std must be finite and > 0 [m], got {self.std}")
        object.__setattr__(self, "distances", tuple(self.distances))

    @property
    def fixes_scale(self) -> bool:
        """True when a known distance ties the plate (and so the arm) to a length."""
        return bool(self.distances)

    def distance_residuals(
        self, centres: dict[str, np.ndarray]
    ) -> tuple[np.ndarray, list[tuple[str, str, np.ndarray]]]:
        """``D − ‖c_a − c_b‖`` per known distance [m] and its derivatives.

        Args:
            centres: socket name → (3,) centre [m].

        Returns:
            residuals (d,), and per distance (a, b, u) with ∂r/∂c_a = −u, ∂r/∂c_b = +u.

        Raises:
            MeasurementError: a distance names a socket that was never measured.
        """
        r, derivs = np.empty(len(self.distances)), []
        for i, k in enumerate(self.distances):
            missing = [s for s in (k.a, k.b) if s not in centres]
            if missing:
                raise MeasurementError(
                    f"plate {self.name!r}: known distance {k.a}–{k.b} names socket(s) "
                    f"{missing} with no measured pose; measured: {sorted(centres)}"
                )
            d = centres[k.a] - centres[k.b]
            norm = float(np.linalg.norm(d))
            if norm < 1e-12:
                raise MeasurementError(f"sockets {k.a!r} and {k.b!r} coincide")
            r[i] = k.value - norm
            derivs.append((k.a, k.b, d / norm))
        return r, derivs


class _SocketFile(Protocol):
    """What the plates read of a socket file (:class:`pincal.measure.SocketData`)."""

    plate: SocketPlate
    socket: tuple[str, ...]
    ball: np.ndarray | None

    @property
    def sockets(self) -> tuple[str, ...]: ...

    def ball_centres(
        self, P: np.ndarray, Rs: np.ndarray, theta: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]: ...


class SocketPlates(SharedTerms):
    """Shared socket centres and known distances of the socket files of one problem.

    Args:
        datasets: the socket files (:class:`SocketData`), in the problem's order.

    Raises:
        MeasurementError: two files give different values for one known distance, or a
            known distance names a socket that no file measured.
    """

    def __init__(self, datasets: Sequence[Artefact]) -> None:
        super().__init__(datasets)
        data = cast("list[_SocketFile]", list(self.datasets))  # one kind per SharedTerms
        self.plates = _plates(data)
        for plate, sockets in self.plates.values():
            for k in plate.distances:
                missing = [s for s in (k.a, k.b) if s not in sockets]
                if missing:
                    raise MeasurementError(
                        f"plate {plate.name!r}: the known distance {k.a}–{k.b} names "
                        f"socket(s) {missing} with no pose in any file; measured: {sockets}"
                    )
        #: (plate, socket) → position of its x centre in :attr:`names`
        self.columns: dict[tuple[str, str], int] = {}
        for plate, sockets in self.plates.values():
            for s in sockets:
                self.columns[(plate.name, s)] = 3 * len(self.columns)
        self.names = tuple(f"{p}.{s}_{a}" for (p, s) in self.columns for a in "xyz")
        self.units = ("m",) * len(self.names)
        known = [k for p, _ in self.plates.values() for k in p.distances]
        self.sigma = np.array([[k.std] for k in known]) if known else None

    def start(
        self, poses: Sequence[tuple[np.ndarray, np.ndarray]], thetas: Sequence[np.ndarray]
    ) -> np.ndarray:
        """Each socket centre at the mean nominal ball centre of its poses (every file)."""
        sums: dict[tuple[str, str], list[np.ndarray]] = {}
        files = cast("list[_SocketFile]", list(self.datasets))
        for d, (P, Rs), t0 in zip(files, poses, thetas, strict=True):
            B, _ = d.ball_centres(P, Rs, t0 if d.ball is None else np.zeros(3))
            for s, b in zip(d.socket, B, strict=True):
                sums.setdefault((d.plate.name, s), []).append(b)
        phi = np.zeros(len(self.names))
        for key, col in self.columns.items():
            phi[col : col + 3] = np.mean(sums[key], axis=0)
        return phi

    def residuals(self, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``D − ‖c_a − c_b‖`` (d,) [m] per known distance and the derivatives (d, s)."""
        raws, rows = [], []
        for plate, _ in self.plates.values():
            centres = {s: phi[c : c + 3] for (p, s), c in self.columns.items() if p == plate.name}
            r, derivs = plate.distance_residuals(centres)
            raws.append(r)
            for a, b, u in derivs:
                row = np.zeros(len(self.names))
                ca, cb = self.columns[(plate.name, a)], self.columns[(plate.name, b)]
                row[ca : ca + 3] -= u
                row[cb : cb + 3] += u
                rows.append(row)
        return np.concatenate(raws), np.array(rows)

    def fixes_scale(self, alone: bool) -> bool:
        """False when only sockets without a known distance were measured.

        Socket residuals ``c − b`` scale with every length of the model: with no other
        dataset (a reading of a length, a measured position) and no known distance,
        nothing measured fixes the length scale.
        """
        return not alone or any(p.fixes_scale for p, _ in self.plates.values())

    def warnings(self, alone: bool) -> tuple[str, ...]:
        """:data:`pincal.measure.SCALE_MESSAGE` when :meth:`fixes_scale` is False."""
        return () if self.fixes_scale(alone) else (SCALE_MESSAGE,)

    def points(self, phi: np.ndarray) -> dict[str, np.ndarray]:
        """``"plate.socket"`` → (3,) socket centre [m]."""
        phi = np.asarray(phi, dtype=float)
        return {f"{p}.{s}": phi[c : c + 3].copy() for (p, s), c in self.columns.items()}


def _plates(data: list[_SocketFile]) -> dict[str, tuple[SocketPlate, list[str]]]:
    """Plate name → (the plate with the known distances of all its files, its sockets).

    Raises:
        MeasurementError: two files give different values for one known distance.
    """
    out: dict[str, tuple[SocketPlate, list[str]]] = {}
    for d in data:
        plate, sockets = out.get(d.plate.name, (d.plate, []))
        known = {(k.a, k.b): k for k in plate.distances}
        for k in d.plate.distances:
            same = known.get((k.a, k.b)) or known.get((k.b, k.a))
            if same is None:
                known[(k.a, k.b)] = k
            elif (same.value, same.std) != (k.value, k.std):
                raise MeasurementError(
                    f"plate {d.plate.name!r}: the known distance {k.a}–{k.b} is given as "
                    f"{same.value * 1e3:g} mm and {k.value * 1e3:g} mm by two files; give it once"
                )
        plate = SocketPlate(plate.name, plate.std, tuple(known.values()))
        out[d.plate.name] = (plate, sockets + [s for s in d.sockets if s not in sockets])
    return out
