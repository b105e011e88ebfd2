"""The socket-artefact terms of :class:`pincal.identification.InstrumentProblem`.

The files of one plate share its socket centres (three unknowns per socket, after
every file's own unknowns); each file may have its own unknown ball centre. Each pose
gives ``c_s − b`` (3 residuals, ``b = p + R t``), each known distance of a plate
``D − ‖c_a − c_b‖``. See :mod:`pincal.measure._sockets` for the model.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from pincal.errors import MeasurementError
from pincal.measure import SCALE_MESSAGE, SocketData, SocketPlate
from pincal.model import Mechanism

__all__ = ["SocketTerms"]


class SocketTerms:
    """Shared socket centres and known distances of the socket files of one problem.

    Args:
        datasets: every dataset of the problem (the socket ones are used).
        first_column: the column of the first socket centre (after all own unknowns).
        ball_columns: dataset index → column of its unknown ``ball_x``.

    Raises:
        MeasurementError: two files give different values for one known distance, or a
            known distance names a socket that no file measured.
    """

    def __init__(
        self, datasets: Sequence[Any], first_column: int, ball_columns: dict[int, int]
    ) -> None:
        self.datasets = list(datasets)
        self.ball_columns = dict(ball_columns)
        self.plates = _plates([d for d in self.datasets if isinstance(d, SocketData)])
        for plate, sockets in self.plates.values():
            for k in plate.distances:
                missing = [s for s in (k.a, k.b) if s not in sockets]
                if missing:
                    raise MeasurementError(
                        f"plate {plate.name!r}: the known distance {k.a}–{k.b} names "
                        f"socket(s) {missing} with no pose in any file; measured: {sockets}"
                    )
        self.columns: dict[tuple[str, str], int] = {}
        col = first_column
        for plate, sockets in self.plates.values():
            for s in sockets:
                self.columns[(plate.name, s)] = col
                col += 3
        self.names = tuple(f"{p}.{s}_{a}" for (p, s) in self.columns for a in "xyz")
        known = [k for p, _ in self.plates.values() for k in p.distances]
        #: (d, 1) 1σ of the known distances [m], or None without any
        self.sigma = np.array([[k.std] for k in known]) if known else None

    @property
    def fixes_scale(self) -> bool:
        """False when only sockets without a known distance were measured.

        Socket residuals ``c − b`` scale with every length of the model: with no other
        dataset (a reading of a length, a measured position) and no known distance,
        nothing measured fixes the length scale.
        """
        return (
            not self.plates
            or any(not isinstance(d, SocketData) for d in self.datasets)
            or any(p.fixes_scale for p, _ in self.plates.values())
        )

    @property
    def warnings(self) -> tuple[str, ...]:
        """:data:`pincal.measure.SCALE_MESSAGE` when :attr:`fixes_scale` is False."""
        return () if self.fixes_scale else (SCALE_MESSAGE,)

    def start(self, mech: Mechanism, qs: np.ndarray, x0: np.ndarray) -> None:
        """Write start values of unknown balls and socket centres into ``x0``.

        An unknown ball centre t starts at the linear least-squares solution of
        ``p_i + R_i t = c_s(i)`` over the file's nominal poses (its socket centres
        unknown too), not at 0, where the flange's rotation would not move the ball and
        the identifiable set decided there would hold it. Each socket centre starts at
        the mean nominal ball centre of its poses.
        """
        start = 0
        sums: dict[tuple[str, str], list[np.ndarray]] = {}
        for i, d in enumerate(self.datasets):
            m = len(d)
            if isinstance(d, SocketData):
                T = [mech.frame_placement(q) for q in qs[start : start + m]]
                P = np.array([t.translation for t in T])
                Rs = np.array([t.rotation for t in T])
                t0 = np.zeros(3)
                if d.ball is None:
                    t0 = _ball_start(d, P, Rs)
                    x0[self.ball_columns[i] : self.ball_columns[i] + 3] = t0
                B, _ = d.ball_centres(P, Rs, t0)
                for s, b in zip(d.socket, B, strict=True):
                    sums.setdefault((d.plate.name, s), []).append(b)
            start += m
        for key, col in self.columns.items():
            x0[col : col + 3] = np.mean(sums[key], axis=0)

    def centres(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """``"plate.socket"`` → (3,) socket centre at ``x`` [m]."""
        x = np.asarray(x, dtype=float)
        return {f"{p}.{s}": x[c : c + 3].copy() for (p, s), c in self.columns.items()}

    def block(self, d: SocketData, x: np.ndarray, col: int, n: int, P: np.ndarray,
              Rs: list[np.ndarray], sens: list[Any] | None):  # fmt: skip
        """Raw residuals ``c_s − b`` (m, 3) [m] and their Jacobian (m, 3, len(x)).

        Args:
            d: the socket file.
            x: all unknowns of the problem.
            col: the column of the file's own unknowns (its ball).
            n: the number of machine parameters (the first columns).
            P: (m, 3) flange positions [m].
            Rs: (m, 3, 3) flange orientations.
            sens: per pose :class:`pincal.sensitivity.PoseSensitivity` (None: no
                Jacobian, zeros returned).
        """
        m, k = len(d), len(d.parameter_names)
        R = np.asarray(Rs)
        B, _ = d.ball_centres(P, R, x[col : col + k])
        cols = np.array([self.columns[(d.plate.name, s)] for s in d.socket])
        C = x[cols[:, None] + np.arange(3)]
        J = np.zeros((m, 3, len(x)))
        if sens is not None:
            # b = p + R t; a local rotation δ of the flange moves b by −R [t]× δ
            t = d.ball if d.ball is not None else x[col : col + 3]
            tx = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])
            for i, s in enumerate(sens):
                J[i, :, :n] = -(s.jacobian[:3] - R[i] @ tx @ s.jacobian[3:6])
                J[i, :, cols[i] : cols[i] + 3] = np.eye(3)
                if k:
                    J[i, :, col : col + 3] = -R[i]
        return C - B, J

    def distance_block(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Raw residuals ``D − ‖c_a − c_b‖`` (d, 1) [m] and their Jacobian (d, 1, len(x))."""
        raws, rows = [], []
        for plate, _ in self.plates.values():
            centres = {s: x[c : c + 3] for (p, s), c in self.columns.items() if p == plate.name}
            r, derivs = plate.distance_residuals(centres)
            raws.append(r)
            for a, b, u in derivs:
                row = np.zeros(len(x))
                ca, cb = self.columns[(plate.name, a)], self.columns[(plate.name, b)]
                row[ca : ca + 3] -= u
                row[cb : cb + 3] += u
                rows.append(row)
        return np.concatenate(raws)[:, None], np.array(rows)[:, None, :]


def _ball_start(d: SocketData, P: np.ndarray, Rs: np.ndarray) -> np.ndarray:
    """Least-squares ball centre t (3,) [m] from ``R_i t − c_s(i) = −p_i`` (nominal poses)."""
    sockets = d.sockets
    A = np.zeros((3 * len(d), 3 + 3 * len(sockets)))
    for i, s in enumerate(d.socket):
        A[3 * i : 3 * i + 3, :3] = Rs[i]
        k = 3 + 3 * sockets.index(s)
        A[3 * i : 3 * i + 3, k : k + 3] = -np.eye(3)
    return np.linalg.lstsq(A, -P.reshape(-1), rcond=None)[0][:3]


def _plates(data: list[SocketData]) -> dict[str, tuple[SocketPlate, list[str]]]:
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
