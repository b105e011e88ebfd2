"""ISO 9283 pose accuracy and repeatability on the standard test cube.

The test cube is the largest axis-aligned cube, centred at the centre of the sampled
reachable workspace, whose 3×3×3 lattice of points (corners, edge and face centres,
centre) is reachable at the home orientation (bisection on the edge length). The five
test points lie in the cube's diagonal plane through the corners C1 = c + h(−1,−1,−1),
C2 = c + h(1,1,−1), C7 = c + h(1,1,1), C8 = c + h(−1,−1,1) (h = edge / 2): P1 at the
centre and P2–P5 on the plane's diagonals at ``inset`` (default 10 %, the standard's
(10 ± 2) %) of the diagonal length from the corners C7, C8, C1, C2.

Per test point j, with n attained poses (x_i, y_i, z_i, a_i, b_i, c_i) for the
commanded pose (x_c, …, c_c) (a, b, c: roll, pitch, yaw about the base x, y, z axes):

* ``AP_p = sqrt((x̄ − x_c)² + (ȳ − y_c)² + (z̄ − z_c)²)`` (barycentre vs command),
  ``AP_a = ā − a_c``, ``AP_b = b̄ − b_c``, ``AP_c = c̄ − c_c``;
* ``RP_l = l̄ + 3 S_l`` with ``l_i = ‖x_i − x̄‖`` and
  ``S_l = sqrt(Σ (l_i − l̄)² / (n − 1))``; ``RP_a = ±3 S_a`` (S_a the sample standard
  deviation of a_i), likewise b, c.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import ConvergenceError, MeasurementError, PincalError
from pincal.model._mechanism import Mechanism
from pincal.model._workspace import sample_actuators

__all__ = [
    "PoseCharacteristics",
    "TestCube",
    "iso_test_cube",
    "pose_characteristics",
    "simulate_cycles",
]


@dataclass(frozen=True)
class TestCube:
    """The ISO 9283 test cube and its five test poses.

    Attributes:
        centre: (3,) cube centre [m]; edge: edge length [m].
        rotation: (3, 3) commanded orientation of every test pose (home's).
        points: (5, 3) P1..P5 [m].
        inset: fraction of the plane diagonal between a corner and its test point.
    """

    __test__ = False  # not a pytest class

    centre: np.ndarray
    edge: float
    rotation: np.ndarray
    points: np.ndarray
    inset: float

    @property
    def poses(self) -> list[pin.SE3]:
        """The five commanded poses P1..P5."""
        return [pin.SE3(self.rotation, p) for p in self.points]


def _test_points(c: np.ndarray, edge: float, inset: float) -> np.ndarray:
    h = edge / 2
    C1, C2 = c + h * np.array([-1, -1, -1.0]), c + h * np.array([1, 1, -1.0])
    C7, C8 = c + h * np.array([1, 1, 1.0]), c + h * np.array([-1, -1, 1.0])
    corners = [C7, C8, C1, C2]
    opposite = [C1, C2, C7, C8]
    return np.array([c, *(a + inset * (b - a) for a, b in zip(corners, opposite, strict=True))])


def iso_test_cube(
    mech: Mechanism,
    n_samples: int = 300,
    rng: np.random.Generator | int = 0,
    inset: float = 0.1,
    tol: float = 1e-4,
) -> TestCube:
    """The largest reachable axis-aligned cube around the sampled workspace's centre.

    Args:
        mech: the (nominal) machine; its home orientation is commanded.
        n_samples: random reachable poses sampled for the centre and the initial size.
        rng: random generator or seed.
        inset: (0.08..0.12) fraction of the plane diagonal by which the test points
            P2..P5 are set in from the cube corners.
        tol: edge-length resolution of the bisection [m].

    Raises:
        PincalError: inset outside the standard's (10 ± 2) % or no reachable cube.
    """
    if not 0.08 <= inset <= 0.12:
        raise PincalError(f"inset must be within the standard's 0.08..0.12, got {inset}")
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    q = sample_actuators(mech, n_samples, gen)
    P = np.array([mech.frame_placement(x).translation for x in mech.configurations(q)])
    centre = P.mean(axis=0)
    R = mech.frame_placement(mech.q_home).rotation
    lattice = np.array([[i, j, k] for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)])

    def reachable(edge: float) -> bool:
        for d in lattice:
            try:
                mech.inverse(pin.SE3(R, centre + edge / 2 * d))
            except ConvergenceError:
                return False
        return True

    if not reachable(0.0):
        raise PincalError(
            f"the centre {centre} of the sampled workspace is not reachable at the home "
            "orientation; check the workspace limits of the sidecar"
        )
    lo, hi = 0.0, max(float(np.max(P.max(axis=0) - P.min(axis=0))), 8 * tol)
    for _ in range(20):  # grow until out of reach, then bisect
        if not reachable(hi):
            break
        lo, hi = hi, 2 * hi
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if reachable(mid) else (lo, mid)
    if lo <= 0:
        raise PincalError("no cube of positive size is reachable around the workspace centre")
    return TestCube(centre, lo, R, _test_points(centre, lo, inset), inset)


def simulate_cycles(
    actual: Mechanism,
    controller: Mechanism,
    poses: list[pin.SE3],
    cycles: int = 30,
    actuator_std: float = 2e-6,
    rng: np.random.Generator | int = 0,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Attained poses of ``actual`` commanded by ``controller``'s inverse kinematics.

    Each cycle visits every pose; the actuators reach the commanded values with an
    independent error N(0, actuator_std²) per cycle (the machine's repeatability).

    Returns:
        commanded actuator rows (P, n_act), attained positions (P, cycles, 3) [m] and
        rotations (P, cycles, 3, 3).

    Raises:
        UnreachablePoseError: the controller cannot reach a pose.
    """
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    q_cmd = np.array([controller.inverse(T) for T in poses])
    pos = np.empty((len(poses), cycles, 3))
    rot = np.empty((len(poses), cycles, 3, 3))
    for c in range(cycles):
        for j, q in enumerate(q_cmd):
            T = actual.forward(q + gen.normal(0.0, actuator_std, q.shape))
            pos[j, c], rot[j, c] = T.translation, T.rotation
    return q_cmd, pos, rot


@dataclass(frozen=True)
class PoseCharacteristics:
    """ISO 9283 pose accuracy (AP) and repeatability (RP) per test point.

    Attributes:
        ap_p: (P,) positional accuracy [m]; ap_xyz: (P, 3) x̄ − x_c etc. [m].
        ap_abc: (P, 3) orientation accuracy ā − a_c, b̄ − b_c, c̄ − c_c [rad].
        rp_l: (P,) positional repeatability l̄ + 3 S_l [m].
        rp_abc: (P, 3) orientation repeatability 3 S_a, 3 S_b, 3 S_c [rad] (read ±).
        cycles: n.
    """

    ap_p: np.ndarray
    ap_xyz: np.ndarray
    ap_abc: np.ndarray
    rp_l: np.ndarray
    rp_abc: np.ndarray
    cycles: int

    def lines(self, title: str = "") -> list[str]:
        """A table in mm and mrad, one row per test point, then the worst case."""
        out = [title] if title else []
        out.append(
            "  point   AP_p [mm]   AP_a      AP_b      AP_c [mrad]   RP_l [mm]   "
            "RP_a      RP_b      RP_c [±mrad]"
        )
        for j in range(len(self.ap_p)):
            a, r = self.ap_abc[j] * 1e3, self.rp_abc[j] * 1e3
            out.append(
                f"  P{j + 1}    {self.ap_p[j] * 1e3:9.4f}   {a[0]:+8.4f}  {a[1]:+8.4f}  "
                f"{a[2]:+8.4f}      {self.rp_l[j] * 1e3:9.4f}   {r[0]:7.4f}   {r[1]:7.4f}   "
                f"{r[2]:7.4f}"
            )
        out.append(
            f"  worst   AP_p {self.ap_p.max() * 1e3:.4f} mm, RP_l {self.rp_l.max() * 1e3:.4f} mm "
            f"({self.cycles} cycles)"
        )
        return out

    def to_dict(self) -> dict:
        """JSON-ready values [m, rad]."""
        return {
            "cycles": self.cycles,
            "AP_p": self.ap_p.tolist(),
            "AP_abc": self.ap_abc.tolist(),
            "RP_l": self.rp_l.tolist(),
            "RP_abc": self.rp_abc.tolist(),
        }


def _rpy(R: np.ndarray) -> np.ndarray:
    return np.asarray(pin.rpy.matrixToRpy(np.asarray(R, dtype=float)))


def pose_characteristics(
    commanded: list[pin.SE3], positions: np.ndarray, rotations: np.ndarray
) -> PoseCharacteristics:
    """AP and RP (see the module doc) of attained poses against the commands.

    Args:
        commanded: P commanded poses.
        positions: (P, n, 3) attained positions [m].
        rotations: (P, n, 3, 3) attained orientations (rotation matrices).

    Raises:
        MeasurementError: shapes that do not match, or fewer than 2 cycles.
    """
    pos = np.asarray(positions, dtype=float)
    rot = np.asarray(rotations, dtype=float)
    if pos.ndim != 3 or pos.shape[0] != len(commanded) or pos.shape[2] != 3:
        raise MeasurementError(f"positions must be ({len(commanded)}, n, 3), got {pos.shape}")
    if rot.shape != (*pos.shape[:2], 3, 3):
        raise MeasurementError(f"rotations must be {(*pos.shape[:2], 3, 3)}, got {rot.shape}")
    n = pos.shape[1]
    if n < 2:
        raise MeasurementError(f"repeatability needs at least 2 cycles, got {n}")
    ap_xyz, ap_abc, rp_l, rp_abc = [], [], [], []
    for j, T in enumerate(commanded):
        bary = pos[j].mean(axis=0)
        ap_xyz.append(bary - T.translation)
        l = np.linalg.norm(pos[j] - bary, axis=1)  # noqa: E741
        rp_l.append(l.mean() + 3 * l.std(ddof=1))
        cmd = _rpy(T.rotation)
        # angles relative to the command, wrapped to (−π, π]
        ang = np.array([_rpy(R) for R in rot[j]]) - cmd
        ang = (ang + np.pi) % (2 * np.pi) - np.pi
        ap_abc.append(ang.mean(axis=0))
        rp_abc.append(3 * ang.std(axis=0, ddof=1))
    ap_xyz_a = np.array(ap_xyz)
    return PoseCharacteristics(
        np.linalg.norm(ap_xyz_a, axis=1), ap_xyz_a, np.array(ap_abc), np.array(rp_l),
        np.array(rp_abc), n,
    )  # fmt: skip
