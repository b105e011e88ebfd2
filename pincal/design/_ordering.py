"""The order in which to measure designed poses: a short tour in joint space.

A laser-tracker campaign's time is mostly motion, and the machine moves its joints
together: going from pose a to pose b takes about ``d(a, b) = max_j |q_b,j − q_a,j| /
v_j`` (every joint at its speed ``v_j``; 1 rad/s revolute, 0.1 m/s prismatic by
default — only ratios matter). The tour starts at home and visits every pose once (an
open path): nearest neighbour from home, then 2-opt (reverse a stretch whenever that
shortens the path) until no reversal helps.
"""

from __future__ import annotations

import itertools

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["PoseOrder", "travel_order"]


class PoseOrder:
    """A visiting order and the path's length before and after [s at the speeds].

    Attributes:
        order: (m,) pose indices in visiting order.
        before: length of the path home → poses in their given order.
        after: length of the path in ``order``.
    """

    def __init__(self, order: NDArray[np.int_], before: float, after: float) -> None:
        self.order, self.before, self.after = order, before, after

    def summary(self) -> str:
        """One line, e.g. ``"measurement order: joint travel 41.2 → 18.3 (−56 %)"``."""
        gain = 100.0 * (self.after - self.before) / self.before if self.before else 0.0
        return (
            f"measurement order: joint travel {self.before:.4g} → {self.after:.4g} "
            f"({gain:+.0f} %, nearest neighbour + 2-opt from home)"
        )


def _path_length(D: NDArray[np.float64], path: list[int]) -> float:
    return float(sum(D[a, b] for a, b in itertools.pairwise(path)))


def travel_order(q_act: ArrayLike, home: ArrayLike, speeds: ArrayLike | None = None) -> PoseOrder:
    """A short open tour from ``home`` through every row of ``q_act``.

    Args:
        q_act: (m, n_act) actuator rows [m, rad].
        home: (n_act,) the start [m, rad].
        speeds: (n_act,) joint speeds (default 1 for every joint).

    Returns:
        The :class:`PoseOrder` (indices into ``q_act``).
    """
    Q = np.vstack([np.asarray(home, dtype=float)[None], np.atleast_2d(q_act)])
    v = np.ones(Q.shape[1]) if speeds is None else np.asarray(speeds, dtype=float)
    D = np.max(np.abs(Q[:, None, :] - Q[None, :, :]) / v, axis=2)  # node 0 = home
    m = len(Q) - 1
    given = list(range(m + 1))
    path, left = [0], set(range(1, m + 1))
    while left:
        nxt = min(left, key=lambda k: (D[path[-1], k], k))
        path.append(nxt)
        left.remove(nxt)
    improved = True
    while improved:
        improved = False
        for i in range(1, m):
            for j in range(i + 1, m + 1):
                a, b = path[i - 1], path[i]
                c = path[j]
                d = path[j + 1] if j < m else None
                old = D[a, b] + (D[c, d] if d is not None else 0.0)
                new = D[a, c] + (D[b, d] if d is not None else 0.0)
                if new < old - 1e-12:
                    path[i : j + 1] = path[i : j + 1][::-1]
                    improved = True
    order = np.array(path[1:], dtype=int) - 1
    return PoseOrder(order, _path_length(D, given), _path_length(D, path))
