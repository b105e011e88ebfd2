"""A parameter set linearised at given values: the exact derivatives of its origins.

Built by :meth:`~pincal.model.ParameterSet.linearise` once per evaluation point and
passed on (to :meth:`~pincal.model.ParameterSet.apply` and the sensitivity functions)
by whoever evaluates there, e.g. an identification problem: nothing is memoised in the
parameter set.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

__all__ = ["Linearisation"]


@dataclass(frozen=True, eq=False)
class Linearisation:
    """A parameter set linearised at given values (see ``ParameterSet.linearise``).

    Attributes:
        names: the names of the set's parameters, in order (the set it belongs to).
        values: (n,) the parameter values [SI] (read-only).
        joint_twists: per touched joint: (its parameter columns, its origin twist v_j
            (6,), the effective twists ``Jexp6(v_j)·Ξ_j`` (6, n_j)); the effective twists
            are the exact derivatives, in the displaced origin frame, of the origin with
            respect to the joint's parameters at ``values``.
    """

    names: tuple[str, ...]
    values: np.ndarray
    joint_twists: Mapping[str, tuple[np.ndarray, np.ndarray, np.ndarray]]
