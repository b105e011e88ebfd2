"""The actuator → measured-components Jacobian G of a (closed) configuration.

G = ∂(measured components)/∂q_act (k, n_act), in the components a measurement residual
uses (``p_meas − p_model`` in world axes, ``log3(R_modelᵀ R_meas)`` in the measured
frame): position rows are the measured frame's origin velocity in world axes, rotation
rows its angular velocity in the measured frame (J_m). A subset of components (a planar
[x, y, rz], a single x) therefore keeps its world meaning: the local axes of a rotating
frame would mix world x and y. On a closed chain the passive velocities
follow from the closure: J_c,free·v_free = −J_c,act·v_act (least squares: idle passive
joints take the minimum-norm share; they do not move the measured frame), so
G = J_m,act + J_m,free·(−J_c,free⁺ J_c,act).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from pincal.errors import ConvergenceError, MeasurementError
from pincal.model._mechanism import Mechanism
from pincal.model.files import COMPONENTS
from pincal.model.loops import six_by_nv

__all__ = ["actuator_jacobian", "actuator_jacobians"]


def actuator_jacobian(
    mech: Mechanism,
    q: NDArray[np.float64],
    components: Sequence[str] | None = None,
) -> NDArray[np.float64]:
    """G (k, n_act) at the closed configuration q (nq,) [m or rad per m or rad].

    Args:
        mech: the mechanism.
        q: (nq,) a configuration whose loops are closed.
        components: the k rows, names from x y z rx ry rz in any order (default the
            measured components), e.g. all six to ask which ones the actuators move.

    Raises:
        MeasurementError: an unknown component name.
    """
    model = mech.model
    comps = tuple(mech.measured_components) if components is None else tuple(components)
    bad = [c for c in comps if c not in COMPONENTS]
    if bad:
        raise MeasurementError(
            f"actuator_jacobian components {bad} unknown; choose names from {' '.join(COMPONENTS)}"
        )
    cols = [COMPONENTS.index(c) for c in comps]
    act = np.array([model.joints[mech.joint_id(j)].idx_v for j in mech.actuated])
    fid = mech.frame_id(mech.measured_frame)
    data = model.createData()
    J = six_by_nv(pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)).copy()
    J[:3] = six_by_nv(pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED))[:3]
    Jm = J[cols]
    G = Jm[:, act]
    free = mech.free_dofs
    if mech.n_closure_rows and free.size:
        Jc = mech.closure_jacobian(q)
        G = G + Jm[:, free] @ np.linalg.lstsq(Jc[:, free], -Jc[:, act], rcond=None)[0]
    return G


def actuator_jacobians(mech: Mechanism, q_act: NDArray[np.float64]) -> NDArray[np.float64]:
    """G per actuator row (N, k, n_act); rows whose loops do not close are NaN.

    Each row's loops are closed from the previous row's configuration (home first).
    """
    rows = np.atleast_2d(np.asarray(q_act, dtype=float))
    G = np.full((len(rows), len(mech.measured_components), len(mech.actuated)), np.nan)
    q = mech.q_home
    for i, row in enumerate(rows):
        try:
            q = mech.configuration(row, q)
        except ConvergenceError:
            q = mech.q_home
            continue
        G[i] = actuator_jacobian(mech, q)
    return G
