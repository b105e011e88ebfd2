"""ISO 9283 pose accuracy (AP) and repeatability (RP) on the measured components.

Per test point j, with n attained poses (p_i, R_i) for the commanded pose (p_c, R_c),
over the components the machine measures (the others are neither commanded nor judged):

* ``AP_p = sqrt(Σ_k (x̄_k − x_ck)²)`` over the measured position axes k (barycentre vs
  command); ``RP_l = l̄ + 3 S_l`` with ``l_i = ‖p_i − p̄‖`` over the same axes and
  ``S_l = sqrt(Σ (l_i − l̄)² / (n − 1))``.
* Orientation, ISO 9283's convention (:data:`ORIENTATION_CONVENTION`): each orientation
  is given by the angles (a, b, c) about the base x, y, z axes, ``R = Rz(c)·Ry(b)·Rx(a)``
  (ISO 9787's roll, pitch, yaw); ``AP_a = ā − a_c``, ``AP_b = b̄ − b_c``, ``AP_c = c̄ − c_c``
  with each angle difference wrapped to (−π, π], and ``RP_a = ±3 S_a`` etc. (sample
  standard deviations). The angles are undefined at b = ±90° (gimbal lock); a test pose
  there is refused. Only the measured rotation components are reported; for a planar
  machine measuring rz, c is its rotation about z exactly.
* Rotation components are measured in the measured frame (the sidecar's ``rx ry rz``).
  When only some are, an attained orientation is first reduced to them: its rotation
  from the command ``log3(R_cᵀ R_i)`` keeps the measured components and the others are
  the command's (``R_i ← R_c · exp(masked)``), so an unmeasured turn about the tool
  axis of a tilted pose does not leak into a and b.

:func:`point_accuracy` computes one test point; ``pincal acceptance`` (through
:func:`pose_characteristics`) and ``pincal validate`` both use it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import MeasurementError
from pincal.model import COMPONENTS, Mechanism

__all__ = [
    "ORIENTATION_CONVENTION",
    "PointAccuracy",
    "PoseCharacteristics",
    "point_accuracy",
    "pose_characteristics",
    "simulate_cycles",
]

#: the orientation convention of AP_a/b/c and RP_a/b/c, as printed by acceptance/validate
ORIENTATION_CONVENTION = (
    "ISO 9283: a, b, c = angles about the base x, y, z axes, R = Rz(c)·Ry(b)·Rx(a); "
    "AP_a = ā − a_c (differences wrapped to ±π)"
)
#: |b| closer than this to 90° [rad]: the angles a and c are not defined
_GIMBAL_MARGIN = 1e-6


def iso_angles(R: np.ndarray) -> np.ndarray:
    """ISO 9283 orientation angles (a, b, c) [rad] of R = Rz(c)·Ry(b)·Rx(a), shape (3,).

    Raises:
        MeasurementError: b within 1e-6 rad of ±90° (gimbal lock: a and c undefined).
    """
    R = np.asarray(R, dtype=float)
    sb = -float(R[2, 0])
    if abs(abs(sb) - 1.0) < _GIMBAL_MARGIN**2 / 2:
        raise MeasurementError(
            "an orientation has b = ±90° (its x axis along the base z axis): ISO 9283's "
            "angles a and c are not defined there; choose test poses away from it"
        )
    a, c = np.arctan2(R[2, 1], R[2, 2]), np.arctan2(R[1, 0], R[0, 0])
    return np.array([a, np.arcsin(np.clip(sb, -1.0, 1.0)), c])


def simulate_cycles(
    actual: Mechanism,
    controller: Mechanism,
    poses: list[pin.SE3],
    cycles: int = 30,
    actuator_std: float = 2e-6,
    rng: np.random.Generator | int = 0,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Attained poses of ``actual`` commanded by ``controller``'s inverse kinematics.

    Each cycle visits every pose; the actuators reach the commanded values with an
    independent error N(0, actuator_std²) per cycle (the machine's repeatability).
    ``progress``: optional callback ``(cycles done, cycles)`` after each cycle.

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
        if progress is not None:
            progress(c + 1, cycles)
    return q_cmd, pos, rot


@dataclass(frozen=True)
class PointAccuracy:
    """AP and RP of one test point (NaN where a component is not measured / n < 2).

    Attributes:
        ap_xyz: (3,) x̄ − x_c, ȳ − y_c, z̄ − z_c [m]; ap_p: ‖·‖ over the measured axes [m].
        ap_abc: (3,) ā, b̄, c̄ [rad]; rp_l: l̄ + 3 S_l [m]; rp_abc: (3,) 3 S_a, 3 S_b, 3 S_c
            [rad]; n: attained poses.
    """

    ap_xyz: np.ndarray
    ap_p: float
    ap_abc: np.ndarray
    rp_l: float
    rp_abc: np.ndarray
    n: int


def _axes(components: tuple[str, ...] | list[str]) -> tuple[list[int], list[int]]:
    """Measured position axes and rotation axes (indices 0..2) of ``components``."""
    bad = [c for c in components if c not in COMPONENTS]
    if bad:
        raise MeasurementError(f"unknown components {bad}; valid: {' '.join(COMPONENTS)}")
    return (
        [k for k in range(3) if COMPONENTS[k] in components],
        [k for k in range(3) if COMPONENTS[3 + k] in components],
    )


def _measured_part(Rc: np.ndarray, rotations: np.ndarray, rot_k: list[int]) -> np.ndarray:
    """(n, 3, 3) attained rotations reduced to their measured local components (module doc).

    ``Rc`` (3, 3) the command; ``rot_k`` the measured rotation axes of the measured frame.
    """
    if len(rot_k) == 3:
        return rotations
    mask = np.isin(np.arange(3), rot_k)
    return np.array([Rc @ pin.exp3(mask * pin.log3(Rc.T @ R)) for R in rotations])


def point_accuracy(
    commanded: pin.SE3,
    positions: np.ndarray,
    rotations: np.ndarray | None,
    components: tuple[str, ...] | list[str] = COMPONENTS,
) -> PointAccuracy:
    """AP and RP (module doc) of n attained poses of one commanded pose.

    Args:
        commanded: the commanded pose (p_c, R_c).
        positions: (n, 3) attained positions [m].
        rotations: (n, 3, 3) attained orientations, or None when no rotation is measured.
        components: the measured components; the others are NaN in the result.

    Raises:
        MeasurementError: unknown components, or rotations missing for measured ones.
    """
    pos_k, rot_k = _axes(components)
    P = np.asarray(positions, dtype=float).reshape(-1, 3)
    n = len(P)
    nan3 = np.full(3, np.nan)
    bary = P.mean(axis=0)
    ap_xyz = np.where(np.isin(np.arange(3), pos_k), bary - commanded.translation, np.nan)
    ap_p = float(np.linalg.norm(ap_xyz[pos_k])) if pos_k else float("nan")
    rp_l = float("nan")
    if pos_k and n >= 2:
        l = np.linalg.norm(P[:, pos_k] - bary[pos_k], axis=1)  # noqa: E741
        rp_l = float(l.mean() + 3 * l.std(ddof=1))
    ap_abc, rp_abc = nan3.copy(), nan3.copy()
    if rot_k:
        if rotations is None:
            raise MeasurementError(
                f"components {' '.join(components)} include rotations but no orientation "
                "was given"
            )
        abc_c = iso_angles(commanded.rotation)
        attained = _measured_part(commanded.rotation, np.asarray(rotations, dtype=float), rot_k)
        ang = np.array([iso_angles(R) for R in attained]) - abc_c
        ang = (ang + np.pi) % (2 * np.pi) - np.pi  # each difference in [−π, π)
        ap_abc[rot_k] = ang.mean(axis=0)[rot_k]
        if n >= 2:
            rp_abc[rot_k] = 3 * ang.std(axis=0, ddof=1)[rot_k]
    return PointAccuracy(ap_xyz, ap_p, ap_abc, rp_l, rp_abc, n)


def _none(x: np.ndarray) -> list:
    """A JSON-ready list with None for NaN (unmeasured components)."""
    return [None if v != v else float(v) for v in np.asarray(x, dtype=float).ravel()]


def _nested(x: np.ndarray) -> list:
    return [_none(row) for row in np.asarray(x, dtype=float)]


@dataclass(frozen=True)
class PoseCharacteristics:
    """ISO 9283 pose accuracy (AP) and repeatability (RP) per test point.

    Attributes:
        ap_p: (P,) positional accuracy over the measured axes [m]; ap_xyz: (P, 3) [m].
        ap_abc: (P, 3) orientation accuracy ā, b̄, c̄ [rad] (module doc; NaN: not measured).
        rp_l: (P,) positional repeatability l̄ + 3 S_l [m].
        rp_abc: (P, 3) orientation repeatability 3 S_a, 3 S_b, 3 S_c [rad] (read ±).
        cycles: n; components: the measured components judged.
    """

    ap_p: np.ndarray
    ap_xyz: np.ndarray
    ap_abc: np.ndarray
    rp_l: np.ndarray
    rp_abc: np.ndarray
    cycles: int
    components: tuple[str, ...] = COMPONENTS

    def lines(self, title: str = "") -> list[str]:
        """A table in mm and mrad, one row per test point, then the worst case.

        Only the measured components get a column; the header names them and the
        orientation convention.
        """
        pos_k, rot_k = _axes(self.components)
        out = [title] if title else []
        axes = " ".join(COMPONENTS[k] for k in pos_k)
        out.append(f"  AP_p, RP_l over {axes}" + (
            f"; AP/RP_{'/'.join('abc'[k] for k in rot_k)}: {ORIENTATION_CONVENTION}"
            if rot_k else "; orientation not measured"))  # fmt: skip
        head = "  point   AP_p [mm]"
        head += "".join(f"   AP_{'abc'[k]} [mrad]" for k in rot_k)
        head += "   RP_l [mm]" + "".join(f"   RP_{'abc'[k]} [±mrad]" for k in rot_k)
        out.append(head)
        for j in range(len(self.ap_p)):
            a, r = self.ap_abc[j] * 1e3, self.rp_abc[j] * 1e3
            row = f"  P{j + 1}    {self.ap_p[j] * 1e3:9.4f}"
            row += "".join(f"   {a[k]:+12.4f}" for k in rot_k)
            row += f"   {self.rp_l[j] * 1e3:9.4f}" + "".join(f"   {r[k]:14.4f}" for k in rot_k)
            out.append(row)
        worst = (
            f"  worst   AP_p {self.ap_p.max() * 1e3:.4f} mm, "
            f"RP_l {self.rp_l.max() * 1e3:.4f} mm"
        )
        for k in rot_k:
            worst += f", |AP_{'abc'[k]}| {np.abs(self.ap_abc[:, k]).max() * 1e3:.4f} mrad"
        out.append(worst + f" ({self.cycles} cycles)")
        return out

    def to_dict(self) -> dict:
        """JSON-ready values [m, rad]; None for components not measured."""
        return {
            "cycles": self.cycles,
            "components": list(self.components),
            "orientation_convention": ORIENTATION_CONVENTION,
            "AP_p": self.ap_p.tolist(),
            "AP_xyz": _nested(self.ap_xyz),
            "AP_abc": _nested(self.ap_abc),
            "RP_l": self.rp_l.tolist(),
            "RP_abc": _nested(self.rp_abc),
        }


def pose_characteristics(
    commanded: list[pin.SE3],
    positions: np.ndarray,
    rotations: np.ndarray | None,
    components: tuple[str, ...] | list[str] = COMPONENTS,
) -> PoseCharacteristics:
    """AP and RP (see the module doc) of attained poses against the commands.

    Args:
        commanded: P commanded poses.
        positions: (P, n, 3) attained positions [m].
        rotations: (P, n, 3, 3) attained orientations, or None (no rotation measured).
        components: the measured components to judge (at least one position axis).

    Raises:
        MeasurementError: shapes that do not match, fewer than 2 cycles, no measured
            position axis.
    """
    pos = np.asarray(positions, dtype=float)
    if pos.ndim != 3 or pos.shape[0] != len(commanded) or pos.shape[2] != 3:
        raise MeasurementError(f"positions must be ({len(commanded)}, n, 3), got {pos.shape}")
    rot = None if rotations is None else np.asarray(rotations, dtype=float)
    if rot is not None and rot.shape != (*pos.shape[:2], 3, 3):
        raise MeasurementError(f"rotations must be {(*pos.shape[:2], 3, 3)}, got {rot.shape}")
    n = pos.shape[1]
    if n < 2:
        raise MeasurementError(f"repeatability needs at least 2 cycles, got {n}")
    if not _axes(components)[0]:
        raise MeasurementError(
            f"components {' '.join(components)} hold no position axis; AP_p needs x, y or z"
        )
    pts = [
        point_accuracy(T, pos[j], None if rot is None else rot[j], components)
        for j, T in enumerate(commanded)
    ]
    return PoseCharacteristics(
        np.array([p.ap_p for p in pts]), np.array([p.ap_xyz for p in pts]),
        np.array([p.ap_abc for p in pts]), np.array([p.rp_l for p in pts]),
        np.array([p.rp_abc for p in pts]), n, tuple(components),
    )  # fmt: skip
