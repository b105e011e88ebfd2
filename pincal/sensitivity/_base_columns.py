"""The columns of a base: an identifiable set chosen in the parameters' own order.

:func:`greedy_base` picks exactly ``rank`` columns of a column-scaled Jacobian, in order
while independent, then by pivoting (the best-conditioned completion) — the rule
:func:`pincal.sensitivity.analyse_jacobian` names the base parameters by.
"""

from __future__ import annotations

import numpy as np

from pincal.sensitivity._rank import RANK_RTOL, numerical_rank

__all__ = ["greedy_base"]


def greedy_base(Js: np.ndarray, rank: int, threshold: float, whole: bool = False) -> list[int]:
    """Exactly ``rank`` column indices of Js: in order while independent, then pivoted.

    In order, a column is kept when its part outside the span of those kept exceeds
    ``threshold``; the rest are the columns with the largest such part (column
    pivoting: the best-conditioned completion). Parts outside the span one by one do
    not bound the whole set's smallest singular value: columns each 3e-6 off the span
    of the ones before can together be dependent to 1e-16 (the in-axis offsets of the
    xarm7, whose URDF rounds π/2 to 1.5708). With ``whole``, when the set so chosen is
    numerically rank-deficient (:data:`RANK_RTOL`), the choice is made again requiring
    the smallest singular value of the kept columns, not the new part alone, above
    ``threshold``.
    """
    chosen = _choose(Js, rank, threshold, whole=False)
    if whole and chosen:
        sv = np.linalg.svd(Js[:, chosen], compute_uv=False)
        if numerical_rank(sv, RANK_RTOL) < len(chosen):
            chosen = _choose(Js, rank, threshold, whole=True)
    return chosen


def _choose(Js: np.ndarray, rank: int, threshold: float, whole: bool) -> list[int]:
    """:func:`greedy_base`'s choice of columns.

    ``whole``: each extension is judged by the smallest singular value of the kept
    columns with it (from their R factor), else by its part outside their span
    (Gram–Schmidt, twice).
    """
    n = Js.shape[1]
    basis = np.zeros((Js.shape[0], 0))
    R = np.zeros((0, 0))
    chosen: list[int] = []

    def extended(k: int) -> tuple[float, np.ndarray, np.ndarray]:
        """(score of adding k, k's unit part outside the kept columns, the new R)."""
        c = basis.T @ Js[:, k]
        v = Js[:, k] - basis @ c
        c2 = basis.T @ v
        v, c = v - basis @ c2, c + c2
        norm = float(np.linalg.norm(v))
        R_new = np.block([[R, c[:, None]], [np.zeros((1, R.shape[1])), np.array([[norm]])]])
        score = float(np.linalg.svd(R_new, compute_uv=False)[-1]) if whole else norm
        return score, (v / norm if norm > 0 else v), R_new

    for k in range(n):
        if len(chosen) == rank:
            break
        score, v, R_new = extended(k)
        if score > threshold:
            basis, R = np.column_stack([basis, v]), R_new
            chosen.append(k)
    while len(chosen) < rank:  # borderline spectrum: fill by pivoting
        rest = [k for k in range(n) if k not in set(chosen)]
        tried = [extended(k) for k in rest]
        i = int(np.argmax([t[0] for t in tried]))
        if tried[i][0] == 0.0:
            break
        basis, R = np.column_stack([basis, tried[i][1]]), tried[i][2]
        chosen.append(rest[i])
    return sorted(chosen)
