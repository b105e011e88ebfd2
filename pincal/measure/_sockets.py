"""Artefact instrument: a ball on the flange seated in the fixed sockets of a plate.

Every pose of one socket measures "the same point": the ball centre
``b = p + R·t`` (``p``, ``R`` the measured frame's world position [m] and orientation,
``t`` the ball centre in that frame [m]) sits at the socket centre ``c_s``, unknown.
Each pose gives three residuals ``c_s − b`` (1σ :attr:`SocketPlate.std` per axis);
each *known distance* between two sockets of the plate (a calibrated plate or bar)
gives one more, ``D − ‖c_a − c_b‖`` (its own 1σ). Socket centres belong to the plate
and are shared by every file of the same plate (several tool positions, several files).

Without a known distance nothing measured fixes the length scale: every residual
``c_s − b`` scales with the arm, so the fit may shrink it (the sockets come out too
close) and no residual warns. :data:`pincal.measure.SCALE_MESSAGE` says so in words.

:class:`SocketData` is the ``socket`` kind of :class:`pincal.measure.Artefact`
(registered like any kind); the plates' shared centres and known distances are its
:class:`pincal.measure._socket_plates.SocketPlates`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from pincal.errors import MeasurementError
from pincal.measure._artefact_kind import Artefact, SharedTerms
from pincal.measure._socket_plates import KnownDistance, SocketPlate, SocketPlates
from pincal.model import Mechanism

__all__ = [
    "KnownDistance",
    "SocketData",
    "SocketPlate",
    "simulate_sockets",
]

@dataclass(frozen=True, eq=False)
class SocketData(Artefact):
    """Poses of a ball seated in the sockets of one plate (one tool position).

    The ``socket`` artefact kind: three residuals ``c_s − b`` per pose; own unknowns the
    ball centre when unknown; shared unknowns the centres ``"plate.s_x"`` … of its
    sockets (shared by every file of the plate).

    Attributes:
        plate: the plate (its noise and known distances).
        q_act: (m, n_act) actuator values [m, rad].
        socket: (m,) socket name per pose.
        actuated: actuated joint names (columns of ``q_act``).
        frame: the measured frame (the flange).
        ball: (3,) ball centre in the measured frame [m], or None when unknown
            (identified, three unknowns of this file).

    Raises:
        MeasurementError: inconsistent shapes, non-finite values, empty socket names.
    """

    plate: SocketPlate
    q_act: np.ndarray
    socket: tuple[str, ...]
    actuated: tuple[str, ...]
    frame: str
    ball: np.ndarray | None = None

    kind: ClassVar[str] = "socket"
    description: ClassVar[str] = "a ball on the flange seated in the sockets of a plate"
    dim: ClassVar[int] = 3

    def __post_init__(self) -> None:
        q = np.atleast_2d(np.asarray(self.q_act, dtype=float))
        names = tuple(str(s) for s in self.socket)
        if q.shape != (len(names), len(self.actuated)):
            raise MeasurementError(
                f"q_act must be ({len(names)}, {len(self.actuated)}) for {len(names)} socket "
                f"poses, got {q.shape}"
            )
        if not np.all(np.isfinite(q)):
            raise MeasurementError("socket data contain NaN or inf")
        if any(not s.strip() for s in names):
            raise MeasurementError("every socket pose needs a socket name")
        object.__setattr__(self, "q_act", q)
        object.__setattr__(self, "socket", names)
        object.__setattr__(self, "actuated", tuple(self.actuated))
        if self.ball is not None:
            b = np.asarray(self.ball, dtype=float).reshape(-1)
            if b.size != 3 or not np.all(np.isfinite(b)):
                raise MeasurementError(f"ball centre must be 3 finite numbers [m], got {self.ball}")
            object.__setattr__(self, "ball", b)

    def __len__(self) -> int:
        return len(self.socket)

    @property
    def sockets(self) -> tuple[str, ...]:
        """The socket names, in order of first appearance."""
        return tuple(dict.fromkeys(self.socket))

    @property
    def sigma(self) -> np.ndarray:
        """(m, 3) the plate's seating 1σ per axis [m]."""
        return np.full((len(self), 3), self.plate.std)

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """This file's own unknowns: the ball centre when it is not given."""
        return ("ball_x", "ball_y", "ball_z") if self.ball is None else ()

    @property
    def shared_names(self) -> tuple[str, ...]:
        """The centres of its sockets, ``"plate.s_x"`` …, socket by socket."""
        return tuple(f"{self.plate.name}.{s}_{a}" for s in self.sockets for a in "xyz")

    def start(self, P: np.ndarray, Rs: np.ndarray) -> np.ndarray:
        """The least-squares ball centre of the nominal poses when unknown (not 0).

        At 0 the flange's rotation would not move the ball and the identifiable set
        decided there would hold it: ``R_i t − c_s(i) = −p_i``, the socket centres
        unknown too.
        """
        if self.ball is not None:
            return np.zeros(0)
        sockets = self.sockets
        A = np.zeros((3 * len(self), 3 + 3 * len(sockets)))
        for i, s in enumerate(self.socket):
            A[3 * i : 3 * i + 3, :3] = Rs[i]
            k = 3 + 3 * sockets.index(s)
            A[3 * i : 3 * i + 3, k : k + 3] = -np.eye(3)
        return np.linalg.lstsq(A, -np.asarray(P).reshape(-1), rcond=None)[0][:3]

    def residuals(
        self, P: np.ndarray, Rs: np.ndarray, theta: np.ndarray, phi: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``c_s − b`` (m, 3) [m], ``b = p + R t``, and its derivatives (see Artefact).

        ``b`` moves by ``δp − R [t]× ω`` for a move ``δp`` and a local rotation ``ω`` of
        the flange; ∂r/∂t = −R; ∂r/∂c_s = I.
        """
        m, R = len(self), np.asarray(Rs)
        B, _ = self.ball_centres(P, R, theta)
        k = np.array([self.sockets.index(s) for s in self.socket])
        phi = np.asarray(phi, dtype=float)
        C = phi[3 * k[:, None] + np.arange(3)]
        t = self.ball if self.ball is not None else np.asarray(theta, dtype=float)[:3]
        tx = np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])
        dp = np.tile(-np.eye(3), (m, 1, 1))
        dw = np.array([R[i] @ tx for i in range(m)]).reshape(m, 3, 3)
        dth = -R if self.ball is None else np.zeros((m, 3, 0))
        dphi = np.zeros((m, 3, phi.size))
        for i in range(m):
            dphi[i, :, 3 * k[i] : 3 * k[i] + 3] = np.eye(3)
        return C - B, dp, dw, dth, dphi

    @classmethod
    def shared_terms(cls, datasets: Sequence[Artefact]) -> SharedTerms:
        """The plates of the files: shared centres, known distances, the scale warning."""
        return SocketPlates(datasets)

    def ball_centres(
        self, P: np.ndarray, Rs: np.ndarray, theta: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Ball centres ``p + R t`` (m, 3) [m] and the offsets ``R t`` (m, 3).

        Args:
            P: (m, 3) flange positions [m].
            Rs: (m, 3, 3) flange orientations.
            theta: this file's own unknowns (the ball centre when unknown) [m].
        """
        t = self.ball if self.ball is not None else np.asarray(theta, dtype=float)[:3]
        off = np.einsum("mij,j->mi", np.asarray(Rs), t)
        return np.asarray(P) + off, off


def simulate_sockets(
    actual: Mechanism,
    plate: SocketPlate,
    centres: dict[str, np.ndarray],
    n_per_socket: int,
    rng: np.random.Generator,
    ball: np.ndarray | None = None,
    tilt: float = 0.6,
    noise: bool = True,
) -> SocketData:
    """Poses of the ``actual`` machine seating its ball in each socket.

    Each pose reaches the socket centre (plus N(0, std²) per axis when ``noise``) with
    the flange tilted up to ``tilt`` [rad] about a random axis from pointing down, by the
    inverse kinematics of ``actual`` from a random start; unreachable tries are skipped.

    Args:
        actual: the machine (simulation truth); it must impose the position.
        plate: the plate (its std is the seating noise).
        centres: socket name → (3,) true centre [m].
        n_per_socket: poses per socket.
        rng: generator of orientations, starts and noise.
        ball: true ball centre in the flange frame [m] (default its origin); the
            returned data declare it unknown when given.
        tilt: largest tilt of the flange from pointing down [rad].
        noise: add the seating noise.

    Returns:
        SocketData of the poses reached, socket by socket.

    Raises:
        MeasurementError: fewer than ``n_per_socket`` poses reached in 20× as many tries.
    """
    import pinocchio as pin

    from pincal.errors import ConvergenceError

    t = np.zeros(3) if ball is None else np.asarray(ball, dtype=float)
    if ball is not None and len(actual.measured_components) < 6:
        raise MeasurementError("a ball off the flange origin needs a machine whose measured "
                               "frame imposes its orientation")  # fmt: skip
    lo, hi = actual.actuator_limits.T
    rows, names = [], []
    for name, c in centres.items():
        got, tries = 0, 0
        while got < n_per_socket:
            tries += 1
            if tries > 20 * n_per_socket:
                raise MeasurementError(f"socket {name!r}: only {got} of {n_per_socket} poses "
                                       "reachable; move the socket into the workspace")  # fmt: skip
            axis = rng.normal(size=3)
            R = pin.exp3(tilt * rng.uniform() * axis / np.linalg.norm(axis)) @ np.diag(
                [1.0, -1.0, -1.0]
            )
            target = np.asarray(c, dtype=float) - R @ t
            if noise:
                target = target + rng.normal(0.0, plate.std, 3)
            guess = actual.q_home + rng.uniform(-0.8, 0.8, actual.model.nq)
            try:
                q_act = actual.inverse(pin.SE3(R, target), guess)
            except (ConvergenceError, ValueError):
                continue
            if np.any(q_act < lo) or np.any(q_act > hi):
                continue
            rows.append(q_act)
            names.append(name)
            got += 1
    known = np.zeros(3) if ball is None else None
    return SocketData(plate, np.array(rows), tuple(names), actual.actuated,
                      actual.measured_frame, known)  # fmt: skip
