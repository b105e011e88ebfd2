"""The columns of a base: an identifiable set chosen in the parameters' own order.

:func:`greedy_base` picks exactly ``rank`` columns of a column-scaled Jacobian, in order
while independent, then by pivoting (the best-conditioned completion) — the rule
:func:`pincal.sensitivity.analyse_jacobian` names the base parameters by.
"""

from __future__ import annotations

import numpy as np

__all__ = ["ORDER_COST", "greedy_base"]

ORDER_COST = 1e-2
"""How much conditioning the set's order may cost a base. A column is kept in order only
when its part outside the span of those kept before it is at least this fraction of
the ``rank``-th pivot of a column-pivoted QR of the same columns (the weakest part of
the best-conditioned greedy choice). A URDF that rounds π/2 to 1.5708 makes columns
3.7e-6 rad off being parallel: the xarm7's in-order base kept such pairs and was
conditioned at 1e-6 where a base of the same rank exists at 0.4 (its fit stalled at
1.1 mm); a machine whose every base is that weak keeps its in-order choice."""


def greedy_base(Js: np.ndarray, rank: int, threshold: float) -> list[int]:
    """Exactly ``rank`` column indices of Js: in order while independent, then pivoted.

    In order, a column is kept when its part outside the span of those kept exceeds
    ``threshold`` and :data:`ORDER_COST` of the best-conditioned choice's weakest part;
    the rest are the columns with the largest such part (column pivoting: the
    best-conditioned completion).
    """
    if rank:
        import scipy.linalg  # here: importing pincal must not load scipy

        pivots = np.abs(np.diag(scipy.linalg.qr(Js, mode="r", pivoting=True)[0]))
        threshold = max(threshold, ORDER_COST * float(pivots[rank - 1]))
    n = Js.shape[1]
    basis = np.zeros((Js.shape[0], 0))
    chosen: list[int] = []

    def outside(k: int) -> np.ndarray:
        """Column k's part outside the span of the kept columns (Gram–Schmidt, twice)."""
        v = Js[:, k] - basis @ (basis.T @ Js[:, k])
        return v - basis @ (basis.T @ v)

    for k in range(n):
        if len(chosen) == rank:
            break
        v = outside(k)
        norm = float(np.linalg.norm(v))
        if norm > threshold:
            basis = np.column_stack([basis, v / norm])
            chosen.append(k)
    while len(chosen) < rank:  # borderline spectrum: fill by pivoting
        rest = [k for k in range(n) if k not in set(chosen)]
        parts = [outside(k) for k in rest]
        norms = [float(np.linalg.norm(v)) for v in parts]
        i = int(np.argmax(norms))
        if norms[i] == 0.0:
            break
        basis = np.column_stack([basis, parts[i] / norms[i]])
        chosen.append(rest[i])
    return sorted(chosen)
