"""Choosing measurement poses of a mechanism: candidates → scaling → index → selection.

Glue between :mod:`pincal.design._candidates` (feasible poses with Jacobian blocks),
:class:`pincal.design._scaling.DesignScaling` (the stated scaling) and
:mod:`pincal.design._exchange` (exchange / DETMAX / greedy). Writing the result to
files is :func:`pincal.io.write_pose_design` (design does not depend on io).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pincal.design._candidates import CandidateSet
from pincal.design._exchange import PoseSelection, detmax, exchange, greedy
from pincal.design._indices import ObservabilityIndices, observability
from pincal.design._scaling import DesignScaling
from pincal.errors import PincalError, UnknownNameError

__all__ = ["SELECTION_METHODS", "PoseDesign", "select_poses"]

_log = logging.getLogger(__name__)

SELECTION_METHODS: tuple[str, ...] = ("exchange", "detmax", "greedy")
"""Selection algorithms accepted by :func:`select_poses`."""


@dataclass(frozen=True, eq=False)
class PoseDesign:
    """Selected measurement poses.

    Attributes:
        candidates: the selected candidates (m poses; q_act, nominal poses, Jacobians).
        indices: their indices in the candidate set that was searched (m,).
        selection: the best :class:`pincal.design._exchange.PoseSelection` (index history etc.).
        indices_all: all observability indices of the selected design (same scaling).
        scaling: the scaling the index was computed on.
        n_candidates: size of the searched candidate set.
        restarts: number of random starts; the best was kept.
    """

    candidates: CandidateSet
    indices: NDArray[np.int_]
    selection: PoseSelection
    indices_all: ObservabilityIndices
    scaling: DesignScaling
    n_candidates: int
    restarts: int

    @property
    def q_act(self) -> NDArray[np.float64]:
        """Selected actuator rows (m, n_act) [m, rad]."""
        return self.candidates.q_act


def select_poses(
    candidates: CandidateSet,
    count: int,
    index: str = "O1",
    scaling: DesignScaling | None = None,
    method: str = "exchange",
    rng: np.random.Generator | int | None = None,
    *,
    restarts: int = 1,
    tabu: int = 0,
) -> PoseDesign:
    """Select ``count`` poses maximising an observability index on a stated scaling.

    Args:
        candidates: feasible candidates with unscaled Jacobian blocks (N, k, n).
        count: number of poses m (m·k ≥ n).
        index: "O1".."O5" or "A".
        scaling: row/column scaling (default: unscaled SI rows and columns).
        method: "exchange" (seed 000), "detmax" or "greedy".
        rng: generator or seed for the random starts.
        restarts: random starts of exchange/DETMAX; the best design is kept.
        tabu: tabu tenure for exchange (0: plain exchange).
    """
    if method not in SELECTION_METHODS:
        raise UnknownNameError("selection method", method, SELECTION_METHODS)
    if restarts < 1:
        raise PincalError(f"restarts must be >= 1; got {restarts}")
    scaling = scaling or DesignScaling(rows="none")
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    J = scaling.apply(candidates.jacobians, candidates.components).J
    best: PoseSelection | None = None
    for _ in range(1 if method == "greedy" else restarts):
        if method == "exchange":
            sel = exchange(J, count, index, rng=gen, tabu=tabu)
        elif method == "detmax":
            sel = detmax(J, count, index, rng=gen)
        else:
            sel = greedy(J, count, index)
        if best is None or sel.value > best.value:
            best = sel
    assert best is not None  # restarts >= 1
    idx = best.indices
    _log.info("selected %d of %d poses: %s = %.6g", count, len(candidates), index, best.value)
    return PoseDesign(
        candidates=candidates.subset(idx),
        indices=idx,
        selection=best,
        indices_all=observability(J[idx]),
        scaling=scaling,
        n_candidates=len(candidates),
        restarts=restarts,
    )
