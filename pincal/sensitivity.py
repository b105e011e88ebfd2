"""Analytic identification Jacobian of closed-loop and serial mechanisms.

For a frame f downstream of the origin of URDF joint j, a displacement δ_k of the
origin along twist ξ_k moves f by the local twist ``Ad(oMf⁻¹ · A_j) ξ_k`` where
``A_j`` is the world placement of the (displaced) origin frame. Closures add the
passive-joint motion from the implicit-function theorem,
``dq_u/dp = −(∂c/∂q_u)⁺ ∂c/∂p`` (rank-revealing, so redundant closure rows of
over-constrained machines are harmless), and the measured quantity's sensitivity
is ``∂m/∂p + ∂m/∂q_u · dq_u/dp``. No finite differences.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.closures import COMPONENTS, measured_jacobian
from pincal.mechanism import Mechanism
from pincal.parameters import ParameterSet


@dataclass(frozen=True)
class PoseSensitivity:
    """Sensitivities at one closed configuration.

    Attributes:
        q: (nq,) closed configuration.
        position: (3,) world position of the measured frame [m].
        rotation: (3, 3) its orientation.
        jacobian: (6, n) derivative of ``[p_world; rotation (local)]`` w.r.t. parameters
            [m/m, m/rad, rad/m, rad/rad].
    """

    q: np.ndarray
    position: np.ndarray
    rotation: np.ndarray
    jacobian: np.ndarray


def _origin_placement(mech: Mechanism, joint: str) -> pin.SE3:
    """World placement of URDF joint ``joint``'s origin frame (before joint motion)."""
    uj = mech.tree.joints[joint]
    model, data = mech.model, mech.data
    if uj.type == "fixed":
        return data.oMf[mech.frame_id(joint)]
    jid = model.getJointId(joint)
    return data.oMi[model.parents[jid]] * model.jointPlacements[jid]


def _ancestor_sets(mech: Mechanism, frames: list[str]) -> dict[str, set[str]]:
    return {f: set(mech.tree.ancestors(f)) for f in frames}


def pose_sensitivity(
    mech: Mechanism, params: ParameterSet, q: np.ndarray, values: np.ndarray | None = None
) -> PoseSensitivity:
    """Sensitivity of the measured frame at a closed configuration ``q`` (nq,).

    ``mech`` must be the mechanism at parameter ``values`` (``params.apply(nominal,
    values)``); derivatives are with respect to those values (exact chain rule through
    ``exp6``).
    """
    values = params.check_values(values)
    twists = params.joint_twists(values)
    mech._update(q)
    n = len(params)
    fm = mech.measured_frame
    frames = [fm] + [f for c in mech.closures for f in (c.frame_a, c.frame_b)]
    ancestors = _ancestor_sets(mech, list(dict.fromkeys(frames)))
    origins = {j: _origin_placement(mech, j) for j in params.joints}
    cache: dict[str, np.ndarray] = {}

    def param_twist(frame: str) -> np.ndarray:
        if frame not in cache:
            P = np.zeros((6, n))
            oMf_inv = mech.data.oMf[mech.frame_id(frame)].inverse()
            for j in ancestors[frame].intersection(twists):
                cols, _, eff = twists[j]
                P[:, cols] = (oMf_inv * origins[j]).action @ eff
            cache[frame] = P
        return cache[frame]

    oMf = mech.data.oMf
    fid_m = mech.frame_id(fm)
    J = measured_jacobian(oMf[fid_m], param_twist(fm))
    if mech.closures:
        Jc = mech.closure_jacobian()
        free = mech._free_v
        Jc_p = np.vstack(
            [
                c.jacobian(oMf[a], oMf[b], param_twist(c.frame_a), param_twist(c.frame_b))
                for c, (a, b) in zip(mech.closures, mech._closure_fids, strict=True)
            ]
        )
        dqu_dp = -np.linalg.lstsq(Jc[:, free], Jc_p, rcond=mech.options.rcond)[0]
        Jm_u = measured_jacobian(oMf[fid_m], mech.frame_jacobian(fid_m))[:, free]
        J = J + Jm_u @ dqu_dp
    return PoseSensitivity(q.copy(), oMf[fid_m].translation.copy(), oMf[fid_m].rotation.copy(), J)


def identification_jacobian(
    mech: Mechanism,
    params: ParameterSet,
    q_act_rows: np.ndarray,
    values: np.ndarray | None = None,
    components: tuple[str, ...] | None = None,
) -> np.ndarray:
    """Stacked identification Jacobian (m·k, n) of the measured quantity.

    Args:
        mech: nominal mechanism (the one ``params`` was built for).
        params: parameter set (n parameters).
        q_act_rows: (m, n_act) actuator values [m, rad].
        values: (n,) parameter values at which to linearise (default zeros).
        components: measured components (default: the mechanism's), k of them; rows per
            pose are in the order ``x y z rx ry rz`` restricted to these.

    Returns:
        (m·k, n) array: position rows in metres (world frame) and rotation rows in
        radians (measured frame) per unit of each parameter.
    """
    values = params.check_values(values)
    at = mech if not np.any(values) else params.apply(mech, values)
    comps = components or mech.measured_components
    rows = [COMPONENTS.index(c) for c in comps]
    qs = at.configurations(q_act_rows)
    blocks = [pose_sensitivity(at, params, q, values).jacobian[rows] for q in qs]
    return np.vstack(blocks)
