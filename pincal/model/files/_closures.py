"""Loop closures and measured quantities: residuals and their Jacobians.

Both a loop closure (frame b must coincide with frame a in some components) and a
measurement (the measured frame's pose in some components) are functions of frame
placements. Their derivatives with respect to anything (joint velocities,
parameters) follow from the *local twists* of the frames involved, so the same
code serves forward/inverse kinematics and the identification Jacobian.

Component conventions (see models/README.md):

* closure ``a → b``: ``[x, y, z]`` = ``R_aᵀ (p_b − p_a)`` and ``[rx, ry, rz]`` =
  ``log3(R_aᵀ R_b)``, both in frame a [m, rad]; a pure point closure (``3d``) uses
  ``p_b − p_a`` in world axes instead (same zero set, cheaper);
* measured quantity of frame f: ``[x, y, z]`` = world position ``p_f`` [m] and
  ``[rx, ry, rz]`` = rotation in the local frame of f [rad].
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import ModelFileError

__all__ = ["COMPONENTS", "Closure", "parse_components"]

COMPONENTS: tuple[str, ...] = ("x", "y", "z", "rx", "ry", "rz")
_KIND_COMPONENTS = {
    "3d": ("x", "y", "z"),
    "6d": COMPONENTS,
    "pose": COMPONENTS,
    "position": ("x", "y", "z"),
    "orientation": ("rx", "ry", "rz"),
}


def parse_components(spec: str | Sequence[str], what: str) -> tuple[int, ...]:
    """Turn ``"3d"``, ``"6d"``, ``"pose"``, ``"position"`` or a component list into indices.

    Args:
        spec: a kind name or a list of component names from ``x y z rx ry rz``.
        what: a description used in error messages (e.g. "closure 2 type").

    Returns:
        Sorted indices into ``COMPONENTS``.
    """
    if isinstance(spec, str):
        key = spec.strip().lower()
        if key in _KIND_COMPONENTS:
            names: Sequence[str] = _KIND_COMPONENTS[key]
        else:
            names = key.replace(",", " ").split()
    else:
        names = [str(s).strip().lower() for s in spec]
    bad = [n for n in names if n not in COMPONENTS]
    if bad or not names:
        valid = ", ".join(list(_KIND_COMPONENTS) + list(COMPONENTS))
        raise ModelFileError(f"{what}: invalid components {spec!r}; use one of {valid}")
    idx = sorted({COMPONENTS.index(n) for n in names})
    return tuple(idx)


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


@dataclass(frozen=True)
class Closure:
    """A cut joint: frame ``frame_b`` must match ``frame_a`` in ``components``.

    Attributes:
        frame_a, frame_b: URDF link names.
        components: indices into ``COMPONENTS`` that are constrained.
        label: the kind as written in the sidecar (``3d``, ``6d``, or a list).
    """

    frame_a: str
    frame_b: str
    components: tuple[int, ...]
    label: str

    @property
    def size(self) -> int:
        """Number of constrained components of this closure."""
        return len(self.components)

    @property
    def is_point(self) -> bool:
        """A point coincidence (``3d``): residual ``p_b − p_a`` in world axes."""
        return self.components == (0, 1, 2)

    def residual(self, oMa: pin.SE3, oMb: pin.SE3) -> np.ndarray:
        """Residual (size,) [m, rad]; a point closure uses world axes (same zero set)."""
        if self.is_point:
            return oMb.translation - oMa.translation
        return relative_residual(oMa, oMb, self.components)

    def jacobian(
        self, oMa: pin.SE3, oMb: pin.SE3, twist_a: np.ndarray, twist_b: np.ndarray
    ) -> np.ndarray:
        """(size, N) derivative of :meth:`residual` given local twists (6, N) of a and b."""
        if self.is_point:
            return oMb.rotation @ twist_b[:3] - oMa.rotation @ twist_a[:3]
        return relative_jacobian(oMa, oMb, twist_a, twist_b, self.components)


def relative_residual(
    oMa: pin.SE3, oMb: pin.SE3, components: tuple[int, ...] = (0, 1, 2, 3, 4, 5)
) -> np.ndarray:
    """Selected components of ``[R_aᵀ(p_b − p_a); log3(R_aᵀ R_b)]`` [m, rad]."""
    Ra = oMa.rotation
    full = np.empty(6)
    if components[0] < 3:
        full[:3] = Ra.T @ (oMb.translation - oMa.translation)
    if components[-1] >= 3:
        full[3:] = pin.log3(Ra.T @ oMb.rotation)
    return full[list(components)]


def relative_jacobian(
    oMa: pin.SE3,
    oMb: pin.SE3,
    twist_a: np.ndarray,
    twist_b: np.ndarray,
    components: tuple[int, ...] = (0, 1, 2, 3, 4, 5),
) -> np.ndarray:
    """Derivative of :func:`relative_residual` given the local twists of both frames.

    Args:
        oMa: world placement of frame a (the frame the residual is expressed in).
        oMb: world placement of frame b.
        twist_a: (6, N) local twists ``[v; ω]`` of frame a per unit of each of N
            variables (LOCAL frame Jacobian, or parameter sensitivities) [m, rad].
        twist_b: (6, N) local twists ``[v; ω]`` of frame b per unit of the same N
            variables, in the same form as ``twist_a``.
        components: which residual components to return (indices into ``COMPONENTS``).

    Returns:
        (len(components), N) derivative of the selected residual components.
    """
    Ra = oMa.rotation
    R_ab = Ra.T @ oMb.rotation
    blocks = []
    if components[0] < 3:
        t = Ra.T @ (oMb.translation - oMa.translation)
        dt = _skew(t) @ twist_a[3:] + R_ab @ twist_b[:3] - twist_a[:3]
        blocks.append(dt)
    if components[-1] >= 3:
        dphi = pin.Jlog3(R_ab) @ (twist_b[3:] - R_ab.T @ twist_a[3:])
        blocks.append(dphi)
    full = blocks[0] if len(blocks) == 1 else np.vstack(blocks)
    first = 0 if components[0] < 3 else 3
    if len(components) == full.shape[0]:
        return full
    return full[[c - first for c in components]]


def measured_quantity(oMf: pin.SE3) -> tuple[np.ndarray, np.ndarray]:
    """Position [m] (3,) and rotation matrix (3, 3) of the measured frame."""
    return oMf.translation.copy(), oMf.rotation.copy()


def measured_jacobian(oMf: pin.SE3, twist_f: np.ndarray) -> np.ndarray:
    """(6, N) derivative of the measured quantity ``[p_world; rotation (local)]``.

    Position rows are world-frame velocities ``R v``; rotation rows are the local
    angular part ``ω`` (first-order rotation of the frame, in the frame).
    """
    return np.vstack([oMf.rotation @ twist_f[:3], twist_f[3:]])


def measurement_residual(
    position_model: np.ndarray,
    rotation_model: np.ndarray,
    position_meas: np.ndarray,
    rotation_meas: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    """Residual ``measured − model`` and the factor that maps model sensitivities to it.

    Returns:
        r: (6,) ``[p_meas − p_model; log3(R_modelᵀ R_meas)]`` (rotation part zero when
            ``rotation_meas`` is None);
        D: (6, 6) such that ``dr = −D @ d(model quantity)`` exactly (block diagonal:
            identity for position, ``Jlog3(E) Eᵀ`` for rotation, E = R_modelᵀ R_meas).
    """
    r = np.zeros(6)
    D = np.eye(6)
    r[:3] = position_meas - position_model
    if rotation_meas is not None:
        E = rotation_model.T @ rotation_meas
        r[3:] = pin.log3(E)
        D[3:, 3:] = pin.Jlog3(E) @ E.T
    return r, D
