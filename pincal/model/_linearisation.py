"""A parameter set linearised at given values: the exact derivatives of its origins.

Built by :meth:`~pincal.model.ParameterSet.linearise` once per evaluation point and
passed on (to :meth:`~pincal.model.ParameterSet.apply` and the sensitivity functions)
by whoever evaluates there, e.g. an identification problem: nothing is memoised in the
parameter set.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # the parameter set builds its linearisations
    from pincal.model._parameters import ParameterSet

__all__ = ["Linearisation"]


@dataclass(frozen=True, eq=False)
class Linearisation:
    """A parameter set linearised at given values (see :meth:`ParameterSet.linearise`).

    Attributes:
        params: the parameter set.
        values: (n,) the parameter values [SI] (read-only).
        joint_twists: per touched joint: (its parameter columns, its origin twist v_j
            (6,), the effective twists ``Jexp6(v_j)·Ξ_j`` (6, n_j)); the effective twists
            are the exact derivatives, in the displaced origin frame, of the origin with
            respect to the joint's parameters at ``values``.
    """

    params: ParameterSet
    values: np.ndarray
    joint_twists: Mapping[str, tuple[np.ndarray, np.ndarray, np.ndarray]]
