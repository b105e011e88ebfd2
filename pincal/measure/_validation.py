"""Pose errors of a model against a reference machine on given commands."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.model import Mechanism

__all__ = ["PoseErrors", "pose_errors"]


@dataclass(frozen=True)
class PoseErrors:
    """Per-pose errors of a model's predicted measured-frame pose.

    Attributes:
        position: (m,) position error norms [m].
        orientation: (m,) rotation angles of the orientation error [rad].
    """

    position: np.ndarray
    orientation: np.ndarray

    def summary(self) -> dict[str, float]:
        """RMS and max of both, in mm and mrad."""
        p, o = self.position * 1e3, self.orientation * 1e3
        return {
            "rms_position_mm": float(np.sqrt(np.mean(p**2))),
            "max_position_mm": float(p.max()),
            "rms_orientation_mrad": float(np.sqrt(np.mean(o**2))),
            "max_orientation_mrad": float(o.max()),
        }


def pose_errors(model: Mechanism, reference: Mechanism, q_act_rows: np.ndarray) -> PoseErrors:
    """Errors between the poses ``model`` predicts and those ``reference`` reaches.

    Args:
        model: the mechanism whose predictions are judged (nominal or calibrated).
        reference: the "actual" machine (simulation truth).
        q_act_rows: (m, n_act) actuator commands [m, rad].

    Returns:
        Position (m,) [m] and orientation (m,) [rad] errors per command row.

    Raises:
        ConvergenceError: a row whose closure cannot be solved by either mechanism.
    """
    qs_model = model.configurations(q_act_rows)
    qs_ref = reference.configurations(q_act_rows)
    pos, rot = [], []
    for qm, qr in zip(qs_model, qs_ref, strict=True):
        Tm = model.frame_placement(qm)
        Tr = reference.frame_placement(qr)
        pos.append(np.linalg.norm(Tm.translation - Tr.translation))
        rot.append(np.linalg.norm(pin.log3(Tm.rotation.T @ Tr.rotation)))
    return PoseErrors(np.array(pos), np.array(rot))
