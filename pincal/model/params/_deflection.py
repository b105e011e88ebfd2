"""Deflection under load on the identified machine: a fixed point and its Jacobian.

A load-dependent joint term (``JointTerm.loaded``: a joint's or a leg's compliance, a
strut's) yields under the forces of the machine as it is — its current geometry, at
the configuration it deflects to — not of the nominal machine at the command. With
``L(q; g) θ_L`` the loaded terms' joint change (m, n_act) at actual joint values ``q``
on geometry ``g``, and ``u = q_cmd + B₀ θ`` the command moved by the other terms
(encoder gain, harmonics, temperature: evaluated at the command, unchanged), the
actual joint values solve the fixed point

    q = u + L(q; g) θ_L

(iterated from ``u``; a contraction while the compliance times the load's stiffness
``∂(Lθ_L)/∂q`` stays below 1 — past it the machine buckles). Its Jacobian with respect
to the parameter values follows from the implicit-function theorem,

    dq/dθ = (I − T_q)⁻¹ [B₀ + L(q; g) (loaded columns) + T_g (geometric columns)],

``T_q = ∂(L θ_L)/∂q`` (n_act × n_act per pose) and ``T_g = ∂(L θ_L)/∂g`` (per geometric
parameter) by central differences of the statics (steps :data:`STEP` [m, rad]): the
forces have no analytic derivative in the geometry here. Both vanish when ``θ_L = 0``
(the start of a fit from nominal), and are skipped then.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from pincal.errors import ConvergenceError
from pincal.model._mechanism import Mechanism
from pincal.model.params._joint_term_set import joint_term_basis
from pincal.model.params._joint_terms import JointTerm, term_of_dof
from pincal.model.params._parameters import ParameterSet

__all__ = [
    "STEP",
    "actual_joint_values",
    "deflected_joints",
    "deflection_jacobian",
    "loaded_terms",
    "undeflected_commands",
]

#: central-difference step of the statics' derivatives [m, rad]
STEP = 1e-6
#: most fixed-point iterations before the deflection is declared divergent
MAX_ITERATIONS = 60


def loaded_terms(params: ParameterSet) -> np.ndarray:
    """Indices (k,) of the parameters of load-dependent joint terms (``JointTerm.loaded``)."""
    out = []
    for k in params.joint_terms:
        term = term_of_dof(params.parameters[k].dof)
        if term is not None and term.loaded:
            out.append(int(k))
    return np.array(out, dtype=int)


def _loaded(
    params: ParameterSet, values: np.ndarray
) -> tuple[np.ndarray, np.ndarray, JointTerm | None, tuple[str, ...]]:
    """The loaded terms of ``params``: (indices (k,), values θ_L (k,) [SI], kind, joints).

    The kind is the term when one kind holds them all (its own :meth:`JointTerm.deflected`
    may solve the deflection), None otherwise (the generic fixed point).
    """
    idx = loaded_terms(params)
    kinds = {term_of_dof(params.parameters[k].dof) for k in idx}
    kind = kinds.pop() if len(kinds) == 1 else None
    joints = tuple(params.parameters[k].joint for k in idx)
    return idx, np.asarray(values, dtype=float)[idx], kind, joints


def undeflected_commands(
    mech: Mechanism,
    params: ParameterSet,
    values: np.ndarray,
    q: np.ndarray,
    conditions: Mapping[str, np.ndarray | None] | None = None,
) -> np.ndarray:
    """The inverse of :func:`deflected_joints`: ``u`` (m, n_act) whose fixed point is ``q``.

    Args:
        mech: the machine at the current parameter values.
        params: the parameter set (n).
        values: (n,) its values [SI].
        q: (m, n_act) the joint values to reach [rad, m].
        conditions: per-pose conditions of the terms.
    """
    idx, theta, term, joints = _loaded(params, values)
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if not np.any(theta):
        return q.copy()
    out = None if term is None else term.commands(mech, joints, theta, q)
    if out is not None:
        return out
    return q - _loaded_change(mech, params.subset(idx), theta, q, conditions or {})


def _loaded_change(
    mech: Mechanism, sub: ParameterSet, theta: np.ndarray, q: np.ndarray, cond: Mapping
) -> np.ndarray:
    """(m, n_act) joint change of the loaded terms ``L(q; mech) θ_L`` [rad, m]."""
    return joint_term_basis(mech, sub, q, cond) @ theta


def deflected_joints(
    mech: Mechanism,
    params: ParameterSet,
    values: np.ndarray,
    u: np.ndarray,
    conditions: Mapping[str, np.ndarray | None] | None = None,
    tol: float = 1e-13,
) -> np.ndarray:
    """The actual joint values (m, n_act) [rad, m]: the fixed point ``q = u + L(q; mech) θ_L``.

    Args:
        mech: the machine at the current parameter values (its geometry bears the load).
        params: the parameter set (n).
        values: (n,) its values [SI].
        u: (m, n_act) the command moved by the terms that are not loaded.
        conditions: per-pose conditions of the terms.
        tol: convergence of the iteration, largest joint change [rad, m].

    Raises:
        ConvergenceError: the iteration does not settle (a compliance so large that the
            machine buckles under its load).
    """
    idx, theta, term, joints = _loaded(params, values)
    u = np.atleast_2d(np.asarray(u, dtype=float))
    if not np.any(theta):
        return u.copy()
    solved = None if term is None else term.deflected(mech, joints, theta, u)
    if solved is not None:
        return solved
    sub, cond = params.subset(idx), conditions or {}
    q = u.copy()
    step = np.inf
    for _ in range(MAX_ITERATIONS):
        new = u + _loaded_change(mech, sub, theta, q, cond)
        step = float(np.max(np.abs(new - q)))
        q = new
        if step <= tol:
            return q
    raise ConvergenceError(
        f"{mech.name!r}: the deflection under load does not settle after {MAX_ITERATIONS} "
        f"iterations (last change {step:.3g}): the compliance values "
        f"{np.array2string(theta, precision=3)} let the machine buckle under its load; "
        f"start from smaller compliances or check the payload and the model's masses",
        residual=step,
    )


def deflection_jacobian(
    mech: Mechanism,
    params: ParameterSet,
    values: np.ndarray,
    q: np.ndarray,
    basis0: np.ndarray,
    at: Callable[[np.ndarray], Mechanism],
    conditions: Mapping[str, np.ndarray | None] | None = None,
) -> np.ndarray:
    """``dq/dθ`` (m, n_act, n) of the deflected joint values at the fixed point ``q``.

    Args:
        mech: the machine at ``values``.
        params: the n parameters.
        values: (n,) their values [SI].
        q: (m, n_act) the fixed point (:func:`deflected_joints`).
        basis0: (m, n_act, n) basis of the terms that are not loaded (at the command;
            zero in the loaded and geometric columns).
        at: the machine at other parameter values (for the geometric derivative).
        conditions: per-pose conditions of the terms.

    Returns:
        The joint changes per parameter, geometric columns included (the load's
        change with the geometry), loaded and other terms' columns through
        ``(I − T_q)⁻¹``.
    """
    idx = loaded_terms(params)
    values = np.asarray(values, dtype=float)
    out = np.array(basis0, dtype=float, copy=True)
    if not idx.size:
        return out
    sub, cond = params.subset(idx), conditions or {}
    out[:, :, idx] = joint_term_basis(mech, sub, q, cond)
    theta = values[idx]
    if not np.any(theta):
        return out
    n_act = q.shape[1]
    Tq = np.empty((q.shape[0], n_act, n_act))
    for j in range(n_act):
        dq = np.zeros_like(q)
        dq[:, j] = STEP
        hi = _loaded_change(mech, sub, theta, q + dq, cond)
        Tq[:, :, j] = (hi - _loaded_change(mech, sub, theta, q - dq, cond)) / (2 * STEP)
    for k in np.setdiff1d(np.arange(len(params)), params.joint_terms):
        dv = np.zeros_like(values)
        dv[k] = STEP
        hi = _loaded_change(at(values + dv), sub, theta, q, cond)
        out[:, :, k] = (hi - _loaded_change(at(values - dv), sub, theta, q, cond)) / (2 * STEP)
    M = np.eye(n_act)[None] - Tq
    return np.linalg.solve(M, out)


def actual_joint_values(
    mech: Mechanism,
    params: ParameterSet,
    values: np.ndarray,
    q_act: np.ndarray,
    conditions: Mapping[str, np.ndarray | None] | None = None,
) -> np.ndarray:
    """The joint values the machine actually takes (m, n_act) [rad, m].

    ``values`` (n,) of ``params`` on the nominal ``mech``: the terms that are not loaded
    (gain, harmonics, temperature) move the commands ``q_act``; the loaded ones
    (compliances) deflect the machine of ``values``' geometry under its own loads, at the
    configuration it deflects to (:func:`deflected_joints`), as the fit models it. Used
    to simulate a machine with joint errors: measure ``params.apply(mech, values)`` at
    these values and record the commands (and add ``actual_shift`` to the positions).
    """
    q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
    if not params.joint_terms.size:
        return q_act.copy()
    values = params.check_values(values)
    basis = joint_term_basis(mech, params, q_act, conditions)
    loaded = loaded_terms(params)
    if not loaded.size or not np.any(values[loaded]):
        return q_act + basis @ values
    basis[:, :, loaded] = 0.0
    actual = params.apply(mech, params.linearise(values))
    return deflected_joints(actual, params, values, q_act + basis @ values, conditions)
