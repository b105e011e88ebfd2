"""Candidate measurement poses and their identification-Jacobian blocks.

Pose design (:mod:`pincal.design._exchange`) chooses m poses out of N candidates. This
module produces the candidates from a mechanism, three ways:

- :func:`grid_candidates` — seed 000: n levels per actuator over a joint range,
  every combination (n^n_act rows) pushed through the forward kinematics; kept
  are the rows whose loops close, that are not singular, whose actuators are in
  their limits and whose measured-frame pose lies inside the sidecar's pose
  workspace (when one is given);
- :func:`random_candidates` — random feasible workspace poses
  (:func:`pincal.sample_actuators`);
- :func:`orthogonal_candidates` — seed 001: a strength-2 orthogonal array over
  the six workspace pose factors (x, y, z, rx, ry, rz) mapped onto the
  workspace ranges and solved by inverse kinematics.

The three generators live in :mod:`pincal.design._candidate_sources`; all of them
push actuator rows through :func:`evaluate_candidates` here. Each returns a
:class:`CandidateSet`: actuator rows (N, n_act), the nominal
measured-frame poses and the unscaled Jacobian blocks (N, k, n) of the measured
components (:func:`pincal.pose_sensitivity`), ready to be scaled
(:class:`pincal.design._scaling.DesignScaling`) and selected from.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from pincal.design._parallel import check_n_jobs, parallel_rows
from pincal.errors import (
    ConvergenceError,
    InputLimitError,
    PincalError,
    SingularConfigurationError,
)
from pincal.model import COMPONENTS, WORKSPACE_POSE_KEYS, Mechanism, ParameterSet, above_floor
from pincal.sensitivity import sensitivities_batch

__all__ = [
    "MAX_CANDIDATES",
    "MAX_CANDIDATE_BYTES",
    "CandidateCost",
    "CandidateSet",
    "candidate_cost",
    "evaluate_candidates",
]

#: default bound on the rows a candidate set tries (forward or inverse kinematics each)
MAX_CANDIDATES = 200_000
#: default bound on the estimated memory of a candidate set [bytes]
MAX_CANDIDATE_BYTES = 2 * 1024**3

_log = logging.getLogger(__name__)

Progress = Callable[[int, int], None]
"""Progress callback ``(done, total)``."""


@dataclass(frozen=True, eq=False)
class CandidateSet:
    """Feasible candidate poses with their identification-Jacobian blocks.

    Attributes:
        q_act: actuator values (N, n_act) [m, rad], columns in ``actuated`` order.
        positions: nominal measured-frame positions (N, 3), world [m].
        rotations: nominal measured-frame orientations (N, 3, 3).
        jacobians: unscaled Jacobian blocks (N, k, n): rows are the measured
            ``components`` (position [m], rotation [rad], measured frame) per unit
            of each parameter, at the nominal parameter values.
        components: the k measured components (from x y z rx ry rz).
        actuated: actuated joint names (n_act,).
        param_names: parameter names (n,).
        source: how the candidates were made, e.g. ``"grid:4"``.
        tried: number of rows tried before filtering.
        rejected: number of rejected rows per reason.
    """

    q_act: NDArray[np.float64]
    positions: NDArray[np.float64]
    rotations: NDArray[np.float64]
    jacobians: NDArray[np.float64]
    components: tuple[str, ...]
    actuated: tuple[str, ...]
    param_names: tuple[str, ...]
    source: str
    tried: int
    rejected: dict[str, int] = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.q_act.shape[0])

    def subset(self, indices: ArrayLike) -> CandidateSet:
        """The candidates at ``indices`` (any integer array), same source."""
        idx = np.asarray(indices, dtype=int).reshape(-1)
        return CandidateSet(
            self.q_act[idx],
            self.positions[idx],
            self.rotations[idx],
            self.jacobians[idx],
            self.components,
            self.actuated,
            self.param_names,
            self.source,
            self.tried,
            dict(self.rejected),
        )

    def joined(self, other: CandidateSet, source: str) -> CandidateSet:
        """These candidates followed by ``other``'s (same parameters), named ``source``."""
        rejected = dict(self.rejected)
        for reason, n in other.rejected.items():
            rejected[reason] = rejected.get(reason, 0) + n
        return CandidateSet(
            np.concatenate([self.q_act, other.q_act]),
            np.concatenate([self.positions, other.positions]),
            np.concatenate([self.rotations, other.rotations]),
            np.concatenate([self.jacobians, other.jacobians]),
            self.components,
            self.actuated,
            self.param_names,
            source,
            self.tried + other.tried,
            rejected,
        )

    def summary(self) -> str:
        """One line: how many candidates were kept and why others were rejected."""
        why = ", ".join(f"{n} {reason}" for reason, n in self.rejected.items() if n)
        return f"{len(self)} of {self.tried} candidates kept ({self.source})" + (
            f"; rejected: {why}" if why else ""
        )


# ----------------------------------------------------------------------------- cost


@dataclass(frozen=True)
class CandidateCost:
    """Up-front estimate of a candidate set's size.

    Attributes:
        rows: actuator rows tried (each a forward or inverse kinematics solve).
        bytes: estimated peak memory [bytes] (Jacobian blocks, poses, tables).
    """

    rows: int
    bytes: int

    def describe(self) -> str:
        """E.g. ``"1.0e+12 candidate poses, ~1.6e+04 GB"``."""
        return f"{self.rows:.3g} candidate poses, ~{self.bytes / 1024**3:.3g} GB"

    def check(
        self,
        what: str,
        max_rows: int | None = MAX_CANDIDATES,
        max_bytes: int | None = MAX_CANDIDATE_BYTES,
    ) -> None:
        """Refuse a cost past the bounds (None: no bound).

        Raises:
            InputLimitError: naming ``what``, the estimate and the bound.
        """
        over_rows = max_rows is not None and self.rows > max_rows
        over_bytes = max_bytes is not None and self.bytes > max_bytes
        if over_rows or over_bytes:
            raise InputLimitError(
                f"{what} gives {self.describe()}; the bound is {max_rows} poses and "
                f"{(max_bytes or 0) / 1024**3:.3g} GB: use fewer levels or a smaller count "
                f"(grid:4, random:2000, oa:7 are typical), or pass --yes (library: "
                f"max_candidates=None) to go ahead"
            )


def candidate_cost(
    kind: str, value: int, n_act: int, n_components: int, n_params: int
) -> CandidateCost:
    """Estimate the rows and memory of candidates ``kind:value`` before making them.

    Args:
        kind: ``"grid"`` (value = levels per actuator), ``"random"`` (value = count) or
            ``"oa"`` (value = levels; the array has p² runs, p the next prime).
        value: the spec's number.
        n_act: number of actuators.
        n_components: measured components k (≤ 6).
        n_params: number of parameters n.

    Returns:
        The :class:`CandidateCost` (exact integers for the row counts).
    """
    per_row = 8 * (6 * n_params + n_components * n_params + 12 + 3 * n_act)
    table = 0
    if kind == "grid":
        rows = int(value) ** n_act
    elif kind == "oa":
        from pincal.design._arrays import is_prime

        p = max(int(value), len(WORKSPACE_POSE_KEYS) - 1, 2)
        while p < 10**6 and not is_prime(p):  # past that, p ≥ value is bound enough
            p += 1
        rows = p * p
        table = 8 * rows * (p + 1)  # the full Bose array before its first six columns
    else:
        rows = int(value)
    return CandidateCost(rows, rows * per_row + table)


# ----------------------------------------------------------------------------- helpers


def home_pose(mech: Mechanism) -> pin.SE3:
    """The measured frame's placement at home."""
    return mech.frame_placement(mech.q_home)


def _in_workspace(mech: Mechanism, home: pin.SE3, p: np.ndarray, R: np.ndarray) -> bool:
    """Whether a measured-frame pose lies in the sidecar pose workspace (missing keys: free)."""
    lim = mech.workspace.pose
    if not lim:
        return True
    r = pin.log3(home.rotation.T @ R)
    values = dict(zip(WORKSPACE_POSE_KEYS, (*p, *r), strict=True))
    tol = 1e-9
    return all(lo - tol <= values[k] <= hi + tol for k, (lo, hi) in lim.items())


def evaluate_candidates(
    mech: Mechanism,
    params: ParameterSet,
    q_act_rows: ArrayLike,
    *,
    source: str = "custom",
    in_workspace: bool = True,
    tried: int | None = None,
    rejected: dict[str, int] | None = None,
    progress: Progress | None = None,
    n_jobs: int = 1,
    scheduler: str | None = None,
) -> CandidateSet:
    """Forward kinematics and Jacobian blocks of actuator rows; infeasible rows dropped.

    A row is rejected when its loops do not close (``"no FK"``), the closed
    configuration is singular (``"singular"``), an actuator is outside its limits
    (``"outside limits"``), or, with ``in_workspace`` and a sidecar pose
    workspace, the measured-frame pose is outside it (``"outside workspace"``), or
    a moving link frame is below the sidecar's ``workspace.floor`` (``"below floor"``,
    open chains, see :func:`pincal.model.above_floor`).
    Rows are warm-started from the previous feasible row (the order of a grid
    keeps neighbours close), falling back to the home configuration.

    Args:
        mech: nominal mechanism.
        params: parameter set (n parameters) whose Jacobian blocks are computed.
        q_act_rows: actuator rows (N, n_act) [m, rad].
        source: label stored in the result.
        in_workspace: filter by the sidecar pose workspace.
        tried: total number of rows tried, counting an earlier stage (e.g. IK) that
            produced these rows (None = the number of rows given).
        rejected: rejection counts by reason (``"no FK"``, ``"singular"``, ...) from an
            earlier stage (e.g. failed IK), added to this stage's counts.
        progress: callback ``(done, N)`` after each row.
        n_jobs: processes for the batched forward kinematics and Jacobian blocks
            (joblib, one chunk of rows per worker; -1 = every CPU). Workers rebuild the
            mechanism (:mod:`pincal.design._parallel`); the result does not depend on
            ``n_jobs``. Pays off for thousands of rows (a worker's start-up costs
            about an import of pincal).
        scheduler: a Dask scheduler (``local:N``, ``tcp://host:port``) whose workers
            take the chunks instead (:class:`pincal.executor.Executor`), or None.

    Returns:
        The feasible candidates, in input order.

    Raises:
        PincalError: rows of the wrong shape, or ``n_jobs`` not a positive integer or -1.
    """
    rows = np.atleast_2d(np.asarray(q_act_rows, dtype=float))
    n_act = len(mech.actuated)
    if rows.ndim != 2 or rows.shape[1] != n_act:
        raise PincalError(
            f"q_act_rows must have shape (N, {n_act}) for actuated joints "
            f"{list(mech.actuated)}; got {np.shape(q_act_rows)}"
        )
    comps = tuple(mech.measured_components)
    comp_rows = [COMPONENTS.index(c) for c in comps]
    lo, hi = np.asarray(mech.actuator_limits, dtype=float).T
    home = home_pose(mech)
    counts = {"no FK": 0, "singular": 0, "outside limits": 0, "outside workspace": 0}
    for k, v in (rejected or {}).items():
        counts[k] = counts.get(k, 0) + v
    total = rows.shape[0]
    inside = np.all((rows >= lo - 1e-12) & (rows <= hi + 1e-12), axis=1)
    below = np.zeros(total, dtype=bool)  # a moving link frame below workspace.floor
    if in_workspace and mech.workspace.floor is not None:
        below = ~above_floor(mech, rows)
        counts["below floor"] = 0
    parallel = (check_n_jobs(n_jobs) != 1 or scheduler is not None) and total > 1
    if parallel:
        Q, solved, R_all, p_all = parallel_rows("fk", mech, rows, n_jobs, scheduler=scheduler)
    else:
        Q, solved, bk = mech.try_configurations_batch(rows)
        if bk is not None:
            R_all, p_all = mech.batch_model.frame_placement(bk, mech.frame_id(mech.measured_frame))
    keep: list[int] = []
    guess = mech.q_home
    for i, row in enumerate(rows):
        if progress is not None:
            progress(i + 1, total)
        if not inside[i]:
            counts["outside limits"] += 1
            continue
        if below[i]:
            counts["below floor"] += 1
            continue
        if solved[i]:
            q, p, R = Q[i], p_all[i], R_all[i]
        else:
            try:  # from the previous feasible row; configuration() also tries from home
                q = mech.configuration(row, guess, pose_index=i)
            except SingularConfigurationError:
                counts["singular"] += 1
                continue
            except ConvergenceError:
                counts["no FK"] += 1
                continue
            Q[i] = q
            oMf = mech.frame_placement(q)
            p, R = oMf.translation, oMf.rotation
        if in_workspace and not _in_workspace(mech, home, p, R):
            counts["outside workspace"] += 1
            continue
        guess = q
        keep.append(i)
    Q_keep = Q[keep].reshape(-1, mech.model.nq)
    if parallel and len(keep) > 1:
        keep_p, keep_R, J = parallel_rows("sensitivity", mech, Q_keep, n_jobs, params, scheduler)
    else:
        sens = sensitivities_batch(mech, params, Q_keep)
        keep_p, keep_R, J = sens.positions, sens.rotations, sens.jacobian
    keep_q, keep_J = rows[keep], J[:, comp_rows]
    n = len(params)
    result = CandidateSet(
        q_act=np.array(keep_q).reshape(-1, n_act),
        positions=np.array(keep_p).reshape(-1, 3),
        rotations=np.array(keep_R).reshape(-1, 3, 3),
        jacobians=np.array(keep_J).reshape(-1, len(comps), n),
        components=comps,
        actuated=tuple(mech.actuated),
        param_names=tuple(params.names),
        source=source,
        tried=int(tried if tried is not None else total),
        rejected=counts,
    )
    _log.info("%s", result.summary())
    return result
