"""Candidate generators: joint-space grids, random workspace poses, orthogonal arrays.

Joint-space grids (seed 000), random workspace poses and orthogonal arrays over the
workspace pose factors (seed 001); the spec strings that name them (and ``auto``) are
:mod:`pincal.design._candidate_specs`. Each pushes actuator rows through
:func:`pincal.design._candidates.evaluate_candidates`.
"""

from __future__ import annotations

import itertools

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from pincal.design._arrays import map_to_ranges, orthogonal_array
from pincal.design._candidates import (
    MAX_CANDIDATE_BYTES,
    MAX_CANDIDATES,
    CandidateCost,
    CandidateSet,
    Progress,
    candidate_cost,
    evaluate_candidates,
    home_pose,
)
from pincal.errors import (
    ConvergenceError,
    OptionValueError,
    PincalError,
)
from pincal.model import WORKSPACE_POSE_KEYS, Mechanism, ParameterSet, sample_actuators
from pincal.model.kernels import joint_ranges

__all__ = [
    "default_grid_ranges",
    "grid_candidates",
    "orthogonal_candidates",
    "random_candidates",
]


def default_grid_ranges(mech: Mechanism, joint_margin: float = 0.0) -> NDArray[np.float64]:
    """Actuator ranges (n_act, 2) for a joint-space grid [m, rad].

    With a pose workspace: the range of each actuator over the inverse kinematics of
    the home pose and the 2·d "star" poses that move one pose factor at a time to
    either end of its range, so the grid spans the joint motion of the workspace axes
    (grid corners that combine several extremes are then filtered by the pose
    workspace), within the sidecar's ``workspace.joints`` where given. A parallel
    machine's joint stroke is far wider than the joint motion of its pose workspace
    (a hexaslide's six carriages each over their whole rail: 4 levels leave one of
    4096 grid rows that assembles). Without a pose workspace: ``workspace.joints``,
    else the URDF limits. Always clipped to the actuator limits, less ``joint_margin``
    of each finite range at both ends (the joint-limit screen's margin: a grid over an
    arm's whole limits puts all but two of its levels where that screen removes them —
    a Panda's ``grid:4`` kept 128 of 16 384 rows).

    Raises:
        OptionValueError: ``joint_margin`` is not in [0, 0.5).
    """
    if not 0.0 <= joint_margin < 0.5:
        raise OptionValueError(
            f"joint margin {joint_margin!r} must be in [0, 0.5) (a share of each actuator "
            "range left out at both ends; the screens' default is 0.05)"
        )
    ranges = joint_ranges(mech)
    limits = np.asarray(mech.actuator_limits, dtype=float)
    pose = mech.workspace.pose
    if pose:
        home = home_pose(mech)
        seen = [mech.actuators_of(mech.q_home)]
        for key, ends in pose.items():
            for value in ends:
                p = home.translation.copy()
                r = np.zeros(3)
                i = WORKSPACE_POSE_KEYS.index(key)
                if i < 3:
                    p[i] = value
                else:
                    r[i - 3] = value
                T = pin.SE3(home.rotation @ pin.exp3(r), p)
                try:
                    seen.append(mech.inverse(T, check_limits=False))
                except ConvergenceError:
                    continue
        seen_arr = np.array(seen)
        star = np.stack([seen_arr.min(axis=0), seen_arr.max(axis=0)], axis=1)
        star = np.clip(star, ranges[:, :1], ranges[:, 1:])
        moved = star[:, 1] > star[:, 0]  # an actuator the pose workspace moves within its range
        ranges = np.where(moved[:, None], star, ranges)
    lower = np.where(np.isfinite(limits[:, 0]), limits[:, 0], -np.inf)
    upper = np.where(np.isfinite(limits[:, 1]), limits[:, 1], np.inf)
    if joint_margin:  # the screen's own expressions (limit ± pad): a level there passes it
        both = np.isfinite(limits).all(axis=1)
        pad = np.where(both, joint_margin * (limits[:, 1] - limits[:, 0]), 0.0)
        lower, upper = np.where(both, lower + pad, lower), np.where(both, upper - pad, upper)
    lo, hi = np.maximum(ranges[:, 0], lower), np.minimum(ranges[:, 1], upper)
    return np.stack([lo, hi], axis=1)


def grid_candidates(
    mech: Mechanism,
    params: ParameterSet,
    levels: int = 4,
    ranges: ArrayLike | None = None,
    *,
    in_workspace: bool = True,
    progress: Progress | None = None,
    max_candidates: int | None = MAX_CANDIDATES,
    max_bytes: int | None = MAX_CANDIDATE_BYTES,
    n_jobs: int = 1,
    scheduler: str | None = None,
    joint_margin: float = 0.0,
) -> CandidateSet:
    """Seed 000: a full joint-space grid pushed through the forward kinematics.

    Each actuator takes ``levels`` evenly spaced values over its range (both
    ends included), giving levels^n_act rows (4 levels, 6 legs: 4096), in
    lexicographic order (the last actuator varies fastest).

    Args:
        mech: nominal mechanism.
        params: parameter set for the Jacobian blocks.
        levels: values per actuator, ≥ 2.
        ranges: actuator ranges (n_act, 2) [m, rad]; default
            :func:`default_grid_ranges`.
        in_workspace: keep only poses inside the sidecar pose workspace.
        progress: callback ``(done, total)``.
        n_jobs: processes evaluating the rows (see :func:`evaluate_candidates`).
        scheduler: a Dask scheduler evaluating them instead, or None.
        max_candidates: refuse more rows than this (None: no bound).
        max_bytes: refuse a larger memory estimate [bytes] (None: no bound).
        joint_margin: share of each finite actuator range the default ranges leave out
            at both ends (:func:`default_grid_ranges`).

    Raises:
        OptionValueError: ``levels`` is not an integer ≥ 2.
        InputLimitError: the estimate passes a bound (:class:`CandidateCost`).
    """
    if not isinstance(levels, (int, np.integer)) or levels < 2:
        raise OptionValueError(f"a grid needs levels >= 2 per actuator; got {levels!r}")
    n_act = len(mech.actuated)
    _cost(mech, params, "grid", int(levels)).check(
        f"grid:{levels} ({n_act} actuators)", max_candidates, max_bytes
    )
    rng_arr = (
        default_grid_ranges(mech, joint_margin) if ranges is None else np.asarray(ranges, float)
    )
    if rng_arr.shape != (n_act, 2) or not np.all(np.isfinite(rng_arr)):
        raise PincalError(f"ranges must be finite (lower, upper) pairs, shape ({n_act}, 2)")
    axes = [np.linspace(lo, hi, int(levels)) for lo, hi in rng_arr]
    rows = np.array(list(itertools.product(*axes)))
    return evaluate_candidates(
        mech,
        params,
        rows,
        source=f"grid:{levels}",
        in_workspace=in_workspace,
        progress=progress,
        n_jobs=n_jobs,
        scheduler=scheduler,
    )


def random_candidates(
    mech: Mechanism,
    params: ParameterSet,
    count: int,
    rng: np.random.Generator | int | None = None,
    *,
    progress: Progress | None = None,
    max_candidates: int | None = MAX_CANDIDATES,
    max_bytes: int | None = MAX_CANDIDATE_BYTES,
    n_jobs: int = 1,
    scheduler: str | None = None,
) -> CandidateSet:
    """``count`` random feasible workspace poses (:func:`pincal.sample_actuators`).

    ``n_jobs``, ``scheduler``: processes or a Dask scheduler evaluating the rows (see
    :func:`evaluate_candidates`).

    Raises:
        OptionValueError: ``count`` is not an integer ≥ 1.
        InputLimitError: the estimate passes a bound (see :func:`grid_candidates`).
    """
    if not isinstance(count, (int, np.integer)) or count < 1:
        raise OptionValueError(f"count must be an integer >= 1; got {count!r}")
    _cost(mech, params, "random", int(count)).check(f"random:{count}", max_candidates, max_bytes)
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    rows = sample_actuators(mech, int(count), gen)
    return evaluate_candidates(
        mech,
        params,
        rows,
        source=f"random:{count}",
        in_workspace=False,
        progress=progress,
        n_jobs=n_jobs,
        scheduler=scheduler,
    )


def orthogonal_candidates(
    mech: Mechanism,
    params: ParameterSet,
    levels: int = 5,
    *,
    progress: Progress | None = None,
    max_candidates: int | None = MAX_CANDIDATES,
    max_bytes: int | None = MAX_CANDIDATE_BYTES,
    n_jobs: int = 1,
    scheduler: str | None = None,
) -> CandidateSet:
    """Seed 001: a strength-2 orthogonal array over the six workspace pose factors.

    The array (:func:`pincal.design._arrays.orthogonal_array`, e.g. L25(5⁶) for 5 levels,
    L49(7⁶) for 7) has one column per pose factor x, y, z, rx, ry, rz; levels are
    mapped evenly onto the sidecar's pose ranges (a factor without a range stays
    at its home value) and each run is solved by inverse kinematics. Unreachable
    runs are counted as ``"no IK"``. ``max_candidates`` and ``max_bytes`` bound the
    estimated cost as in :func:`grid_candidates`; ``n_jobs``, ``scheduler``: processes or
    a Dask scheduler evaluating the solved rows (see :func:`evaluate_candidates`).
    """
    if not isinstance(levels, (int, np.integer)) or levels < 2:
        raise OptionValueError(f"an orthogonal array needs levels >= 2; got {levels!r}")
    _cost(mech, params, "oa", int(levels)).check(f"oa:{levels}", max_candidates, max_bytes)
    pose = mech.workspace.pose
    if not pose:
        raise PincalError(
            f"{mech.name!r} has no pose workspace in its sidecar (workspace.pose); "
            "orthogonal-array candidates need pose ranges"
        )
    table = orthogonal_array(int(levels), len(WORKSPACE_POSE_KEYS))
    home = home_pose(mech)
    rvec_home = np.zeros(3)
    centre = np.concatenate([home.translation, rvec_home])
    lo = np.array(
        [pose.get(k, (centre[i], centre[i]))[0] for i, k in enumerate(WORKSPACE_POSE_KEYS)]
    )
    hi = np.array(
        [pose.get(k, (centre[i], centre[i]))[1] for i, k in enumerate(WORKSPACE_POSE_KEYS)]
    )
    factors = map_to_ranges(table, lo, hi)
    rows, failed = [], 0
    total = factors.shape[0]
    for i, f in enumerate(factors):
        if progress is not None:
            progress(i + 1, 2 * total)
        T = pin.SE3(home.rotation @ pin.exp3(f[3:]), f[:3])
        try:
            rows.append(mech.inverse(T, check_limits=False))
        except ConvergenceError:
            failed += 1
    p = table.max() + 1

    def second_half(done: int, n: int) -> None:
        if progress is not None:
            progress(total + round(done * total / max(n, 1)), 2 * total)

    return evaluate_candidates(
        mech,
        params,
        np.array(rows).reshape(-1, len(mech.actuated)),
        source=f"oa:L{p * p}({p}^6)",
        in_workspace=False,
        tried=total,
        rejected={"no IK": failed},
        progress=second_half,
        n_jobs=n_jobs,
        scheduler=scheduler,
    )


def _cost(mech: Mechanism, params: ParameterSet, kind: str, value: int) -> CandidateCost:
    """The cost (rows, memory) of ``kind:value`` candidates of ``mech`` for ``params``."""
    k = len(mech.measured_components)
    return candidate_cost(kind, value, len(mech.actuated), k, len(params))
