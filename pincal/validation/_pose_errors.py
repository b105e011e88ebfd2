"""Pose errors of a model against a reference machine on given commands."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.model import COMPONENTS, Mechanism

__all__ = ["PoseErrors", "pose_errors"]


@dataclass(frozen=True)
class PoseErrors:
    """Per-pose errors of a model's predicted measured-frame pose.

    Attributes:
        position: (m,) norms of the position error over the position components of
            ``components`` [m] (zeros when none is taken).
        orientation: (m,) norms of the rotation error log3(R_modelᵀ R_ref) over the
            orientation components of ``components`` [rad] (zeros when none is taken).
        components: the components the errors are taken over (default all six).
    """

    position: np.ndarray
    orientation: np.ndarray
    components: tuple[str, ...] = COMPONENTS

    def summary(self) -> dict[str, float | None]:
        """RMS and max of both, in mm and mrad (None for a block with no component)."""
        p, o = self.position * 1e3, self.orientation * 1e3
        has_p = any(c in COMPONENTS[:3] for c in self.components)
        has_o = any(c in COMPONENTS[3:] for c in self.components)
        return {
            "rms_position_mm": float(np.sqrt(np.mean(p**2))) if has_p else None,
            "max_position_mm": float(p.max()) if has_p else None,
            "rms_orientation_mrad": float(np.sqrt(np.mean(o**2))) if has_o else None,
            "max_orientation_mrad": float(o.max()) if has_o else None,
        }


def pose_errors(
    model: Mechanism,
    reference: Mechanism,
    q_act_rows: np.ndarray,
    components: tuple[str, ...] = COMPONENTS,
) -> PoseErrors:
    """Errors between the poses ``model`` predicts and those ``reference`` reaches.

    Args:
        model: the mechanism whose predictions are judged (nominal or calibrated).
        reference: the "actual" machine (simulation truth).
        q_act_rows: (m, n_act) actuator commands [m, rad].
        components: the components the errors are taken over (e.g. the measured ones,
            ``("x", "y", "rz")``); default the full pose.

    Returns:
        Position (m,) [m] and orientation (m,) [rad] errors per command row.

    Raises:
        ConvergenceError: a row whose closure cannot be solved by either mechanism.
    """
    comps = tuple(c for c in COMPONENTS if c in components)
    ip = [k for k in range(3) if COMPONENTS[k] in comps]
    ir = [k for k in range(3) if COMPONENTS[3 + k] in comps]
    qs_model = model.configurations(q_act_rows)
    qs_ref = reference.configurations(q_act_rows)
    pos, rot = [], []
    for qm, qr in zip(qs_model, qs_ref, strict=True):
        Tm = model.frame_placement(qm)
        Tr = reference.frame_placement(qr)
        pos.append(np.linalg.norm((Tm.translation - Tr.translation)[ip]))
        rot.append(np.linalg.norm(pin.log3(Tm.rotation.T @ Tr.rotation)[ir]))
    return PoseErrors(np.array(pos), np.array(rot), comps)
