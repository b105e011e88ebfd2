"""Random poses kept off the edge of the workspace (issue 36, item 5).

A random pose right at an actuator limit, or where the loops are about to stop closing
(the edge of the reachable set: a five-bar's arms stretched, a Stewart leg at full
stroke, a spherical wrist near its passive singularity), is one the actual or the
calibrated machine may not reach: forward kinematics from home along the command path
stops short of it ("stopped at 97 % of the path") and ``simulate`` or ``compensate``
refuse it. So random draws (:func:`pincal.model.sample_actuators`)

* keep :data:`SAMPLE_MARGIN` of every actuator and pose-factor range free at either end
  (:func:`shrunk`), and
* are kept (:func:`screen`) only when the continuation forward kinematics uses — the
  straight actuator path from home on home's assembly branch
  (:meth:`~pincal.model._branch.LoopSolver._continue`, batched as
  :meth:`~pincal.model._batch_fk.BatchLoopSolver._continue_batch`) — reaches them, and
  the passive closure Jacobian there keeps its smallest singular value (over the
  passive rank at home) at least :data:`MIN_SIGMA_RATIO` of home's. Mechanisms without
  loops have no such edge: only the margin applies.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pincal.errors import ConvergenceError
from pincal.model._batch_fk import _MIN_CONTINUATION_ROWS
from pincal.model._mechanism import Mechanism

__all__ = ["MIN_SIGMA_RATIO", "SAMPLE_MARGIN", "Rejections", "passive_sigma", "screen", "shrunk"]

SAMPLE_MARGIN = 0.05
"""Fraction of each sampling range [–] kept free at either end by random draws.

Actuator values (and pose-workspace factors) are drawn in
``[lo + f·(hi − lo), hi − f·(hi − lo)]``.
"""

MIN_SIGMA_RATIO = 0.2
"""Smallest singular value of the passive closure Jacobian a random pose keeps [–],
relative to home's (a closure conditioned at most 5× worse than home's).

On the 2-RSU ankle with 0/0 limits, of 232 closable draws (5 % margin), 6 do not close
on the same machine with a normal 2e-4 geometric error (one of 8 such errors): all at
0.074–0.11 of home's; 0.15 keeps none of them, 0.2 (a margin above that) keeps 199. The
spherical 3-RRR's draws all lie above 0.44.
"""


@dataclass
class Rejections:
    """Random draws rejected while sampling, per reason (counts).

    Attributes:
        infeasible: no closure on home's branch, no inverse kinematics, another
            assembly mode, or a link below the floor.
        unreached: closed, but not reached from home along the command path.
        near_edge: reached, but with a closure conditioned worse than
            :data:`MIN_SIGMA_RATIO` of home's (the edge of the workspace).
    """

    infeasible: int = 0
    unreached: int = 0
    near_edge: int = 0

    @property
    def total(self) -> int:
        """All rejected draws."""
        return self.infeasible + self.unreached + self.near_edge

    def as_dict(self) -> dict[str, int]:
        """Counts keyed by a short reason (for ``CandidateSet.rejected``)."""
        return {
            "infeasible": self.infeasible,
            "not reached from home along the command path": self.unreached,
            f"near the workspace edge (closure σ_min < {MIN_SIGMA_RATIO:g} × home's)": (
                self.near_edge
            ),
        }

    def describe(self) -> str:
        """E.g. ``"12 draws rejected: 3 infeasible, 9 near the workspace edge (…)"``."""
        why = ", ".join(f"{n} {reason}" for reason, n in self.as_dict().items() if n)
        return f"{self.total} random draws rejected" + (f": {why}" if why else "")


def shrunk(ranges: np.ndarray, margin: float = SAMPLE_MARGIN) -> np.ndarray:
    """(k, 2) ranges [m, rad] with ``margin`` of their width removed at either end."""
    ranges = np.asarray(ranges, dtype=float)
    width = ranges[:, 1] - ranges[:, 0]
    return ranges + margin * np.stack([width, -width], axis=1)


def passive_sigma(mech: Mechanism, q: np.ndarray) -> float:
    """Smallest passive closure singular value at configuration ``q`` [m/rad or 1].

    Over the passive rank at home; ``inf`` without loops.
    """
    r = mech.loop_solver.passive_rank
    if not mech.closures or r == 0:
        return float("inf")
    s = np.linalg.svd(mech.closure_jacobian(q)[:, mech.free_dofs], compute_uv=False)
    return float(s[r - 1])


def _reached_from_home(mech: Mechanism, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Configurations (n, nq) the continuation from home reaches, and the mask (n,)."""
    n = rows.shape[0]
    home = mech.q_home
    Q = np.tile(home, (n, 1))
    reached = np.zeros(n, dtype=bool)
    gave_up = np.zeros(n, dtype=bool)
    if mech.batch_solvable and n >= _MIN_CONTINUATION_ROWS:
        Qr, reached, gave_up = mech.batch_solver._continue_batch(rows, np.tile(home, (n, 1)))
        Q[reached] = Qr
    for j in np.nonzero(~reached & ~gave_up)[0]:
        try:
            Q[j] = mech.loop_solver._continue(home, rows[j]).q
            reached[j] = True
        except ConvergenceError:
            pass
    return Q, reached


def screen(mech: Mechanism, rows: np.ndarray) -> tuple[np.ndarray, int, int]:
    """Which closable actuator rows (n, n_act) [m, rad] are kept off the workspace edge.

    Returns the kept mask (n,), the number of rows not reached from home along the
    command path and the number reached but conditioned worse than
    :data:`MIN_SIGMA_RATIO` of home (see the module doc). Without loops all are kept.
    """
    rows = np.atleast_2d(np.asarray(rows, dtype=float))
    n = rows.shape[0]
    if not mech.closures or n == 0:
        return np.ones(n, dtype=bool), 0, 0
    Q, reached = _reached_from_home(mech, rows)
    floor = MIN_SIGMA_RATIO * passive_sigma(mech, mech.q_home)
    sigma = np.array([passive_sigma(mech, Q[j]) if reached[j] else 0.0 for j in range(n)])
    well = reached & (sigma >= floor)
    return well, int(n - reached.sum()), int((reached & ~well).sum())
