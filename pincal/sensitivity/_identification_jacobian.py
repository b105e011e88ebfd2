"""The identification Jacobian of a parameter set over many poses, and closure breaking.

Batched (:func:`pincal.sensitivity.sensitivities_batch`) at the rows' closed
configurations; rows are the measured components (or those given).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from pincal.model import COMPONENTS, Mechanism, ParameterSet
from pincal.sensitivity._jacobian import BatchSensitivity
from pincal.sensitivity.batch import sensitivities_batch

__all__ = ["closure_breaking", "identification_jacobian", "jacobian_and_closure_breaking"]


def _sensitivities(
    mech: Mechanism,
    params: ParameterSet,
    q_act_rows: np.ndarray,
    values: np.ndarray | None,
    conditions: Mapping[str, np.ndarray | None] | None = None,
) -> BatchSensitivity:
    """Batched sensitivities of the measured frame at the rows' closed configurations.

    ``conditions``: per-pose conditions of the rows some joint terms need (e.g.
    ``{"temperature": (m,) °C}``).
    """
    lin = params.linearise(values)
    at = mech if not np.any(lin.values) else params.apply(mech, lin)
    qs, bk = at.configurations_batch(q_act_rows)
    return sensitivities_batch(at, params, qs, bk, lin, conditions=conditions)


def _rows(mech: Mechanism, components: tuple[str, ...] | None) -> list[int]:
    return [COMPONENTS.index(c) for c in (components or mech.measured_components)]


def identification_jacobian(
    mech: Mechanism,
    params: ParameterSet,
    q_act_rows: np.ndarray,
    values: np.ndarray | None = None,
    components: tuple[str, ...] | None = None,
    conditions: Mapping[str, np.ndarray | None] | None = None,
) -> np.ndarray:
    """Stacked identification Jacobian (m·k, n) of the measured quantity.

    Args:
        mech: nominal mechanism (the one ``params`` was built for).
        params: parameter set (n parameters).
        q_act_rows: (m, n_act) actuator values [m, rad].
        values: (n,) parameter values at which to linearise (default zeros).
        components: measured components (default: the mechanism's), k of them; rows per
            pose are in the order ``x y z rx ry rz`` restricted to these.
        conditions: per-pose conditions joint terms need (``{"temperature": (m,) °C}``).

    Returns:
        (m·k, n) array: position rows in metres (world frame) and rotation rows in
        radians (measured frame) per unit of each parameter. Columns of parameters
        that break loop closure (:func:`closure_breaking`) are least-squares values
        without a physical meaning.
    """
    rows = _rows(mech, components)
    J = _sensitivities(mech, params, q_act_rows, values, conditions).jacobian[:, rows]
    return J.reshape(-1, len(params))


def closure_breaking(
    mech: Mechanism,
    params: ParameterSet,
    q_act_rows: np.ndarray,
    values: np.ndarray | None = None,
) -> np.ndarray:
    """Which parameters cannot change without breaking a loop closure.

    Parameter k keeps every loop closable when its closure-Jacobian column ∂c/∂p_k
    lies in the range of ∂c/∂q_u (passive joints) at every pose; otherwise (a ``6d``
    closure of a planar loop and an out-of-plane parameter, say) it breaks closure.

    Args:
        mech: nominal mechanism.
        params: the n parameters.
        q_act_rows: (m, n_act) actuator values [m, rad].
        values: (n,) parameter values (default zeros).

    Returns:
        (n,) boolean mask, True where the parameter breaks closure at any pose.
    """
    return jacobian_and_closure_breaking(mech, params, q_act_rows, values)[1]


def jacobian_and_closure_breaking(
    mech: Mechanism,
    params: ParameterSet,
    q_act_rows: np.ndarray,
    values: np.ndarray | None = None,
    components: tuple[str, ...] | None = None,
    conditions: Mapping[str, np.ndarray | None] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`identification_jacobian` and :func:`closure_breaking` from one pass."""
    rows = _rows(mech, components)
    sens = _sensitivities(mech, params, q_act_rows, values, conditions)
    return sens.jacobian[:, rows].reshape(-1, len(params)), sens.breaks_closure.copy()
