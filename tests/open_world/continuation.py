"""An independent forward kinematics: continuation from home along the command path.

Written for the tests, apart from pincal's loop solvers: each small step of the actuator
values is closed by minimum-norm Gauss–Newton on the passive joints from the previous
step's configuration, so the configuration stays on home's assembly branch as long as
the path avoids singularities.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.model import Mechanism


def continuation(mech: Mechanism, target: np.ndarray, steps: int = 200) -> np.ndarray:
    """Closed configuration (nq,) at actuator values ``target`` (n_act,) [m, rad], reached
    from home along the straight command path in ``steps`` steps."""
    q, a0, free = mech.q_home.copy(), mech.actuators_of(mech.q_home), mech.free_dofs
    for t in np.linspace(0.0, 1.0, steps + 1)[1:]:
        q = mech.with_actuators(q, a0 + t * (np.asarray(target) - a0))
        for _ in range(50):
            r = mech.closure_residual(q)
            if np.max(np.abs(r)) <= 1e-14:
                break
            J = mech.closure_jacobian(q)[:, free]
            v = np.zeros(mech.model.nv)
            v[free] = -np.linalg.lstsq(J, r, rcond=None)[0]
            q = pin.integrate(mech.model, q, v)
        assert np.max(np.abs(mech.closure_residual(q))) <= 1e-12, (t, target)
    return q
