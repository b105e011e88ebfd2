"""Identification-Jacobian columns of joint terms (compliance, gain, harmonics).

A joint term changes the actuated joint values, ``q' = q + B(q) θ``; its column is the
pose's derivative with respect to the actuated joints — exactly the column of that
joint's ``offset`` parameter (the origin turned about the joint's own axis), closure
corrections included — times the basis: ``∂pose/∂θ_k = Σ_a J_offset[:, :, a] B[:, a, k]``.
A term moving the measured frame directly (a link's thermal expansion) adds its world
position change ``S[:, :, k]`` to the position rows when the basis is evaluated here.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from pincal.model import (
    BatchKinematics,
    Mechanism,
    ParameterSet,
    joint_term_basis,
    joint_term_shift,
    parameters,
)
from pincal.sensitivity._jacobian import BatchSensitivity

__all__ = ["joint_term_sensitivities"]

#: ``geometric(mech, params, qs, bk, values)``: the sensitivities of a set without joint
#: terms (``sensitivities_batch``)
GeometricSensitivity = Callable[
    [Mechanism, ParameterSet, np.ndarray, BatchKinematics | None, np.ndarray | None],
    BatchSensitivity,
]


def joint_term_sensitivities(
    geometric: GeometricSensitivity,
    mech: Mechanism,
    params: ParameterSet,
    qs: np.ndarray,
    bk: BatchKinematics | None,
    values: np.ndarray,
    basis: np.ndarray | None,
    conditions: Mapping[str, np.ndarray | None] | None = None,
) -> BatchSensitivity:
    """Sensitivities of a parameter set with joint terms.

    Args:
        geometric: the geometric sensitivity function (``sensitivities_batch`` on a set
            without joint terms).
        mech: the mechanism at ``values``.
        qs: (N, nq) closed configurations.
        bk: their batched kinematics, or None.
        values: (n,) parameter values [SI].
        params: a set whose ``joint_terms`` is not empty.
        basis: (N, n_act, n) joint changes per parameter (:func:`pincal.model.joint_term_basis`
            at the commanded joint values; with loaded terms
            :func:`pincal.model.deflection_jacobian`, whose geometric columns — the
            load's change with the geometry — add to the geometric sensitivities);
            None: evaluated on ``mech`` at the actuated values of ``qs`` with
            ``conditions`` (the frame-moving terms included).
        conditions: per-pose conditions the terms need (e.g. ``{"temperature": T}``).

    Returns:
        A :class:`BatchSensitivity` with all n columns.
    """
    n = len(params)
    offsets = parameters(mech, [f"{a}.offset" for a in mech.actuated])
    s_off = geometric(mech, offsets, qs, bk, None)
    shift = None
    if basis is None:
        q_act = np.array([mech.actuators_of(q) for q in np.atleast_2d(qs)])
        basis = joint_term_basis(mech, params, q_act, conditions)
        shift = joint_term_shift(mech, params, q_act, conditions)
    J = np.einsum("nra,nak->nrk", s_off.jacobian, basis)
    if shift is not None:
        J[:, :3] += shift
    breaks = np.zeros(n, dtype=bool)
    geo = np.setdiff1d(np.arange(n), params.joint_terms)
    if geo.size:
        s_geo = geometric(mech, params.subset(geo), qs, bk, values[geo])
        J[:, :, geo] += s_geo.jacobian  # basis columns of a geometric parameter: a load's change
        breaks[geo] = s_geo.breaks_closure
    return BatchSensitivity(s_off.q, s_off.positions, s_off.rotations, J, breaks)
