"""Thermal expansion of named lengths, with a per-pose temperature (°C).

One coefficient ``α`` [1/K] per actuated joint ``<joint>.thermal``; at a pose measured
at temperature ``T`` [°C] the length grows by the factor ``1 + α (T − T0)``, with the
reference temperature ``T0 = 20 °C`` (the temperature of the nominal lengths):

* a prismatic joint: its stroke (a ball screw's or a linear scale's length from the
  joint's zero) — a joint-space term ``δq = α (T − T0) · q`` [m];
* a revolute joint: the link length into it, the translation of the joint's URDF
  origin ``t`` (in the parent link's frame; e.g. ``elbow_joint`` is a UR5's upper arm).
  That moves everything below the joint rigidly by ``δp = α (T − T0) · R_parent(q) t``
  in the world — a position change of the measured frame, not a joint change. Exact on
  a serial chain; on a closed loop the change is not a rigid move and the term refuses.

Like the other joint terms the basis is evaluated on the nominal mechanism at the
commanded joint values (the first-order model: its error is of order ``α ΔT δθ L``,
0.06 µm for α = 2e-5 /K, ΔT = 8 K, δθ = 1 mrad, L = 0.4 m), so ``δq`` and ``δp`` are
exactly linear in ``α``.

A coefficient is separable from the length itself only when the temperature varies
across the poses: with one temperature, ``α (T − T0) t`` is a constant length change
that the geometric parameters absorb (and ``α (T − T0) q`` a joint gain). Data whose
temperatures span less than :data:`MIN_SPREAD` are refused.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, ClassVar

import numpy as np
import pinocchio as pin

from pincal.errors import ConditionError, ParameterError
from pincal.model.params._joint_terms import JointTerm, register_term

if TYPE_CHECKING:
    from pincal.model._mechanism import Mechanism

__all__ = ["MIN_SPREAD", "REFERENCE_C", "Temperature"]

#: reference temperature of the nominal lengths [°C]
REFERENCE_C = 20.0
#: smallest temperature span across poses that identifies a coefficient [K]
MIN_SPREAD = 0.1
#: plausible machine temperatures [°C]
_RANGE_C = (-60.0, 200.0)


class Temperature(JointTerm):
    """Linear thermal expansion (1σ prior 2e-5 /K: steel 12e-6, aluminium 23e-6)."""

    kind: ClassVar[str] = "temperature"
    dofs: ClassVar[tuple[str, ...]] = ("thermal",)
    prior: ClassVar[float] = 2e-5
    needs: ClassVar[tuple[str, ...]] = ("temperature",)

    def unit(self, joint_type: str) -> str:
        return "1/K"

    def check(self, mech: Mechanism, joint: str) -> None:
        super().check(mech, joint)
        kind = mech.tree.joints[joint].type
        if kind != "prismatic" and mech.closures:
            raise ParameterError(
                f"thermal terms on a closed loop are for prismatic actuators (legs); "
                f"{joint!r} is {kind}: a link length inside a loop does not move the "
                f"platform rigidly"
            )

    def basis(self, mech: Mechanism, q_act: np.ndarray) -> np.ndarray:
        raise ConditionError(_MISSING)

    def basis_at(
        self, mech: Mechanism, q_act: np.ndarray, conditions: Mapping[str, np.ndarray | None]
    ) -> np.ndarray:
        q = np.atleast_2d(np.asarray(q_act, dtype=float))
        dT = _delta(conditions, q.shape[0])
        prismatic = np.array([mech.tree.joints[a].type == "prismatic" for a in mech.actuated])
        return (dT[:, None] * q * prismatic)[:, :, None]

    def shift(
        self, mech: Mechanism, q_act: np.ndarray, conditions: Mapping[str, np.ndarray | None]
    ) -> np.ndarray | None:
        q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
        if all(mech.tree.joints[a].type == "prismatic" for a in mech.actuated):
            return None  # only strokes: a joint-space term
        m, n_act = q_act.shape
        dT = _delta(conditions, m)
        out = np.zeros((m, n_act, 3, 1))
        model, data = mech.model, mech.model.createData()
        chain = set(model.supports[model.frames[mech.frame_id(mech.measured_frame)].parentJoint])
        moving = []  # (actuator index, parent link frame, origin translation [m])
        for a, name in enumerate(mech.actuated):
            uj = mech.tree.joints[name]
            if uj.type == "prismatic" or model.getJointId(name) not in chain:
                continue  # a stroke, or a link that does not carry the measured frame
            if not model.existFrame(uj.parent):
                raise ParameterError(
                    f"thermal term of {name!r}: its parent link {uj.parent!r} has no frame "
                    f"in the model, so the link's direction is unknown"
                )
            moving.append((a, model.getFrameId(uj.parent), uj.origin.translation))
        for k, row in enumerate(q_act if moving else ()):
            pin.framesForwardKinematics(model, data, mech.with_actuators(mech.q_home, row))
            for a, fid, t in moving:
                out[k, a, :, 0] = dT[k] * (data.oMf[fid].rotation @ t)
        return out

    def check_data(self, conditions: Mapping[str, np.ndarray | None]) -> None:
        T = conditions.get("temperature")
        if T is None:
            raise ConditionError(_MISSING)
        T = np.asarray(T, dtype=float)
        _delta(conditions, T.shape[0])
        spread = float(np.ptp(T)) if T.size else 0.0
        if spread < MIN_SPREAD:
            raise ConditionError(
                f"the temperature spans {spread:.3g} K over the poses (below {MIN_SPREAD} K): "
                f"a thermal coefficient is separable from the length itself only when the "
                f"temperature varies across poses; measure at several temperatures or drop "
                f"the temperature term"
            )


_MISSING = (
    "the temperature term needs a per-pose temperature: a 'temperature_C' column (°C) in "
    "the measurement file (or Measurements.temperature)"
)


def _delta(conditions: Mapping[str, np.ndarray | None], m: int) -> np.ndarray:
    """(m,) temperature minus the reference [K]; checked for shape, finiteness and range."""
    T = conditions.get("temperature")
    if T is None:
        raise ConditionError(_MISSING)
    T = np.broadcast_to(np.asarray(T, dtype=float), (m,)) if np.ndim(T) == 0 else np.asarray(T)
    if T.shape != (m,):
        raise ConditionError(f"temperature must have one value per pose ({m},), got {T.shape}")
    lo, hi = _RANGE_C
    bad = np.flatnonzero(~(np.isfinite(T) & (T >= lo) & (T <= hi)))
    if bad.size:
        raise ConditionError(
            f"temperature of pose {int(bad[0])} is {T[bad[0]]!r} °C; give finite values in °C "
            f"between {lo:g} and {hi:g}"
        )
    return T.astype(float) - REFERENCE_C


register_term(Temperature())
