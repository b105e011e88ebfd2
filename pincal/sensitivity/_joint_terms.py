"""Identification-Jacobian columns of joint terms (compliance, gain, harmonics).

A joint term changes the actuated joint values, ``q' = q + B(q) θ``; its column is the
pose's derivative with respect to the actuated joints — exactly the column of that
joint's ``offset`` parameter (the origin turned about the joint's own axis), closure
corrections included — times the basis: ``∂pose/∂θ_k = Σ_a J_offset[:, :, a] B[:, a, k]``.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pincal.model import Mechanism, ParameterSet, joint_term_basis, parameters
from pincal.sensitivity._jacobian import BatchSensitivity

__all__ = ["joint_term_sensitivities"]


def joint_term_sensitivities(
    geometric: Callable,
    mech: Mechanism,
    params: ParameterSet,
    qs: np.ndarray,
    bk,
    values: np.ndarray,
    basis: np.ndarray | None,
):
    """Sensitivities of a parameter set with joint terms.

    Args:
        geometric: the geometric sensitivity function (``sensitivities_batch`` on a set
            without joint terms).
        mech: the mechanism at ``values``.
        qs: (N, nq) closed configurations.
        bk: their batched kinematics, or None.
        values: (n,) parameter values [SI].
        params: a set whose ``joint_terms`` is not empty.
        basis: (N, n_act, n) basis of δq (:func:`pincal.model.joint_term_basis`) at
            the commanded joint values; None: evaluated on ``mech`` at the actuated
            values of ``qs``.

    Returns:
        A :class:`BatchSensitivity` with all n columns.
    """
    n = len(params)
    offsets = parameters(mech, [f"{a}.offset" for a in mech.actuated])
    s_off = geometric(mech, offsets, qs, bk, None)
    if basis is None:
        q_act = np.array([mech.actuators_of(q) for q in np.atleast_2d(qs)])
        basis = joint_term_basis(mech, params, q_act)
    J = np.einsum("nra,nak->nrk", s_off.jacobian, basis)
    breaks = np.zeros(n, dtype=bool)
    geo = np.setdiff1d(np.arange(n), params.joint_terms)
    if geo.size:
        s_geo = geometric(mech, params.subset(geo), qs, bk, values[geo])
        J[:, :, geo] = s_geo.jacobian
        breaks[geo] = s_geo.breaks_closure
    return BatchSensitivity(s_off.q, s_off.positions, s_off.rotations, J, breaks)
